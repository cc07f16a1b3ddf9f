use et_host::output::*;
use std::path::{Path, PathBuf};

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("et-output-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn inputs_are_never_overwritten_and_existing_files_only_with_force() {
    let d = dir("check");
    let input = d.join("d.csv");
    std::fs::write(&input, "x").unwrap();
    // The same file spelled differently is still the input, even with force.
    let other_spelling = d.join(".").join("d.csv");
    for force in [false, true] {
        let e = check(&other_spelling, &[&input], force).unwrap_err();
        assert!(matches!(e, OutputError::Input { .. }), "{e}");
        assert!(e.to_string().contains("refusing to overwrite"), "{e}");
    }
    let old = d.join("model.json");
    std::fs::write(&old, "old").unwrap();
    assert!(matches!(
        check(&old, &[&input], false),
        Err(OutputError::Exists { .. })
    ));
    check(&old, &[&input], true).unwrap();
    check(&d.join("new.json"), &[&input], false).unwrap();
    // A report folder: empty is fine, one with files is not (unless forced), a file never.
    let empty = d.join("empty");
    std::fs::create_dir(&empty).unwrap();
    check_folder(&empty, false).unwrap();
    assert!(check_folder(&d, false).is_err());
    check_folder(&d, true).unwrap();
    let e = check_folder(&old, true).unwrap_err();
    assert!(matches!(e, OutputError::NotAFolder { .. }), "{e}");
    // A file's output is never a folder, even with force (it said "--force replaces it", and
    // forced, failed on the rename as "Device or resource busy").
    for (folder, force) in [(&empty, false), (&d, true)] {
        let e = check(folder, &[], force).unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_failed_write_leaves_the_old_file_and_no_partial_one() {
    let d = dir("write");
    let out = d.join("model.json");
    std::fs::write(&out, "old").unwrap();
    let r: Result<(), OutputError> = write(&out, |p| {
        assert_eq!(p.extension().unwrap(), "json");
        std::fs::write(p, "half").unwrap();
        Err(OutputError::Exists { out: p.into() })
    });
    assert!(r.is_err());
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        1,
        "no partial file left"
    );
    write::<_, OutputError>(&out, |p| {
        std::fs::write(p, "new").map_err(|source| OutputError::Io {
            path: p.into(),
            source,
        })
    })
    .unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "new");
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn only_regular_files_are_replaced_and_streams_are_written_through() {
    let d = dir("kinds");
    let target = d.join("target.json");
    std::fs::write(&target, "keep").unwrap();
    let link = d.join("link.json");
    std::os::unix::fs::symlink(&target, &link).unwrap();
    let fifo = d.join("fifo.json");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    for (path, what) in [
        (link.as_path(), "a symbolic link"),
        (fifo.as_path(), "a FIFO"),
        (Path::new("/dev/zero"), "a device"),
    ] {
        for force in [false, true] {
            let e = check(path, &[], force).unwrap_err();
            assert!(
                matches!(e, OutputError::NotAFile { what: w, .. } if w == what),
                "{e}"
            );
            assert!(e.to_string().contains(&path.display().to_string()), "{e}");
        }
    }
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "keep");
    // A file's path spelt as a folder's (`m.json/`), there or not, with --force or not: said
    // before the work (the rename failed after it, or "appeared while et was writing it").
    for force in [false, true] {
        for out in [d.join("new.json/"), d.join("target.json/")] {
            let e = check(&out, &[], force).unwrap_err();
            assert!(matches!(e, OutputError::FolderSpelling { .. }), "{e}");
            assert!(e.to_string().contains("names a folder"), "{e}");
        }
    }
    // The null device and standard output: allowed without --force, written straight
    // through (no temporary file beside /dev/null).
    for stream in ["/dev/null", "/dev/stdout"] {
        check(Path::new(stream), &[], false).unwrap();
    }
    // The null device as an input too harms nothing (it was refused as overwriting it).
    let null = Path::new("/dev/null");
    check(null, &[null], false).unwrap();
    let mut given = None;
    write::<_, OutputError>(Path::new("/dev/null"), |p| {
        given = Some(p.to_path_buf());
        std::fs::write(p, "x").map_err(|source| OutputError::Io {
            path: p.into(),
            source,
        })
    })
    .unwrap();
    assert_eq!(given.as_deref(), Some(Path::new("/dev/null")));
    // A folder that does not exist.
    let e = check(&d.join("nodir").join("v.png"), &[], true).unwrap_err();
    assert!(matches!(e, OutputError::NoFolder { .. }), "{e}");
    assert!(e.to_string().ends_with("(create it first)"), "{e}");
    // `~` in quotes, which the shell left as it is: said as the shell's word.
    let e = check(Path::new("~/v.png"), &[], true).unwrap_err();
    assert!(e.to_string().contains("'~' is the shell's word"), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn outputs_may_not_collide_with_inputs_or_each_other_however_spelled() {
    let d = dir("collide");
    let mesh = d.join("tri.csv");
    std::fs::write(&mesh, "x").unwrap();
    let out = d.join("out.json");
    let same_out = d.join(".").join("out.json");
    // Two outputs at one new path.
    let e = check_all(&[&out, &same_out], &[], &[], false).unwrap_err();
    assert!(matches!(e, OutputError::Collision { .. }), "{e}");
    // An output at an input named anywhere among the inputs, with --force too.
    let e = check_all(
        &[
            &out,
            &d.join("..").join(d.file_name().unwrap()).join("tri.csv"),
        ],
        &[],
        &[&mesh],
        true,
    )
    .unwrap_err();
    assert!(matches!(e, OutputError::Input { .. }), "{e}");
    // A file the command puts in a folder it creates, and another output at the same name.
    let plots = d.join("plots");
    let map = plots.join("error-map.png");
    let e = check_all(
        &[&map, &plots.join("./error-map.png")],
        &[&plots],
        &[],
        false,
    )
    .unwrap_err();
    assert!(matches!(e, OutputError::Collision { .. }), "{e}");
    check_all(&[&map, &out], &[&plots], &[&mesh], false).unwrap();
    // A file where the folder of plots goes, said before the work (it failed on creating
    // the folder, after it, as "File exists (os error 17)"), with --force too.
    std::fs::write(&plots, "x").unwrap();
    let e = check_all(&[&map], &[&plots], &[], true).unwrap_err();
    assert!(matches!(e, OutputError::NotAFolder { .. }), "{e}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn a_new_output_is_created_exclusively_and_long_names_fit_or_are_refused() {
    let d = dir("race");
    let out = d.join("model.json");
    // Another run creates the same new file while this one writes: this one fails and
    // leaves the other's file alone.
    let r = write::<(), OutputError>(&out, |p| {
        std::fs::write(p, "mine").unwrap();
        std::fs::write(&out, "theirs").unwrap();
        Ok(())
    });
    assert!(matches!(r, Err(OutputError::Raced { .. })), "{r:?}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "theirs");
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1, "no partial left");
    // A 250-byte name (multi-byte characters too): the temporary name stays within 255.
    for stem in ["a".repeat(245), "é".repeat(122)] {
        let long = d.join(format!("{stem}.json"));
        assert!(partial_path(&long).file_name().unwrap().len() <= NAME_MAX);
        write::<(), OutputError>(&long, |p| {
            std::fs::write(p, "x").map_err(|source| OutputError::Io {
                path: p.into(),
                source,
            })
        })
        .unwrap();
        assert_eq!(std::fs::read_to_string(&long).unwrap(), "x");
    }
    // A name of 255 bytes is taken; one past it is refused before the work (its partial file
    // fitted, so the check passed, and the finished file could not be given its name: the
    // work lost, "writing N: N: File name too long").
    let most = d.join(format!("{}.json", "b".repeat(NAME_MAX - 5)));
    check(&most, &[], false).unwrap();
    let past = d.join(format!("{}.json", "b".repeat(NAME_MAX - 4)));
    let e = check(&past, &[], false).unwrap_err();
    assert!(
        matches!(e, OutputError::NameTooLong { bytes: 256, .. }),
        "{e}"
    );
    std::fs::remove_dir_all(&d).unwrap();
}

/// An output that did not exist when the command checked it, and that another writer
/// creates while et works, is left as it is, with or without --force (which sanctions
/// replacing what existed at the check, nothing that appeared after it); a file that existed
/// at the check is replaced under --force as before.
#[test]
fn a_file_that_appears_during_the_work_is_never_replaced() {
    let d = dir("appears");
    let out = d.join("model.json");
    for force in [false, true] {
        let _ = std::fs::remove_file(&out);
        check(&out, &[], force).unwrap();
        // Another run writes it while this one trains.
        std::fs::write(&out, "theirs").unwrap();
        let e = write(&out, |p: &Path| {
            std::fs::write(p, "ours").map_err(|source| OutputError::Io {
                path: p.into(),
                source,
            })
        })
        .unwrap_err();
        assert!(matches!(e, OutputError::Raced { .. }), "{e}");
        assert!(
            e.to_string().contains("appeared while et was writing it"),
            "{e}"
        );
        assert_eq!(std::fs::read_to_string(&out).unwrap(), "theirs");
        let partials = std::fs::read_dir(&d).unwrap().count();
        assert_eq!(partials, 1, "no partial file left");
    }
    // Existing at the check, replaced with --force.
    let old = d.join("old.json");
    std::fs::write(&old, "old").unwrap();
    check(&old, &[], true).unwrap();
    write(&old, |p: &Path| {
        std::fs::write(p, "new").map_err(|source| OutputError::Io {
            path: p.into(),
            source,
        })
    })
    .unwrap();
    assert_eq!(std::fs::read_to_string(&old).unwrap(), "new");
    std::fs::remove_dir_all(&d).unwrap();
}

/// An output's extension must be one of the formats written there (any case); a name without
/// one, and a stream, are taken.
#[test]
fn an_output_named_for_another_format_is_refused() {
    let png: &[&str] = &["png"];
    for ok in [
        "r.png",
        "R.PNG",
        "r",
        "/dev/stdout",
        "/dev/null",
        "dir.v2/r",
    ] {
        check_format(Path::new(ok), "the image (PNG)", png).unwrap();
    }
    let e = check_format(Path::new("r.jpg"), "the image (PNG)", png).unwrap_err();
    assert!(matches!(e, OutputError::Format { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "r.jpg: the image (PNG) is written as .png: name the file so (or with no extension)"
    );
}
