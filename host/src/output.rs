//! Where et writes: never onto a command's own input, never over an existing file unless the
//! user said so (`--force`), and a file appears only when it is complete: it is written under a
//! temporary name beside its target and renamed over it at the end, so a crash or Ctrl-C leaves
//! the old file or none, never half of one.

use std::path::{Path, PathBuf};

/// Why an output was refused or could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// The output is one of the command's inputs.
    #[error("{}: this is the input {}; refusing to overwrite it (write elsewhere)", .out.display(), .input.display())]
    Input {
        /// The output path as given.
        out: PathBuf,
        /// The input it names.
        input: PathBuf,
    },
    /// The output exists and replacing was not asked for.
    #[error("{} already exists; refusing to overwrite it (--force replaces it)", .out.display())]
    Exists {
        /// The output.
        out: PathBuf,
    },
    /// Writing or renaming failed.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
}

/// Whether `a` and `b` name the same existing file, however spelled (`./a`, a symlink, ...).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    }
}

/// Checks `out` before a command writes it: not one of `inputs` (even with `force`), and not
/// an existing file or non-empty folder unless `force`.
///
/// # Errors
/// [`OutputError::Input`] or [`OutputError::Exists`].
pub fn check(out: &Path, inputs: &[&Path], force: bool) -> Result<(), OutputError> {
    if let Some(input) = inputs.iter().find(|i| same_file(out, i)) {
        return Err(OutputError::Input {
            out: out.into(),
            input: input.to_path_buf(),
        });
    }
    let occupied = match std::fs::metadata(out) {
        Ok(m) if m.is_dir() => std::fs::read_dir(out).map_or(true, |mut d| d.next().is_some()),
        Ok(_) => true,
        Err(_) => false,
    };
    if occupied && !force {
        return Err(OutputError::Exists { out: out.into() });
    }
    Ok(())
}

/// The temporary name `out` is written under: hidden, beside it (so the rename stays on one
/// file system), with the same extension (writers that pick a format by it still do).
#[must_use]
pub fn partial_path(out: &Path) -> PathBuf {
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let name = match out.extension() {
        Some(ext) => format!(
            ".{stem}.partial-{}.{}",
            std::process::id(),
            ext.to_string_lossy()
        ),
        None => format!(".{stem}.partial-{}", std::process::id()),
    };
    out.with_file_name(name)
}

/// Writes `out` with `save` (which writes the path it is given) under [`partial_path`], then
/// renames it over `out`. The partial file is removed when `save` fails.
///
/// # Errors
/// `save`'s error, or an [`OutputError::Io`] converted into it.
pub fn write<T, E: From<OutputError>>(
    out: &Path,
    save: impl FnOnce(&Path) -> Result<T, E>,
) -> Result<T, E> {
    let partial = partial_path(out);
    match save(&partial) {
        Ok(value) => {
            std::fs::rename(&partial, out).map_err(|source| {
                let _ = std::fs::remove_file(&partial);
                OutputError::Io {
                    path: out.into(),
                    source,
                }
            })?;
            Ok(value)
        }
        Err(e) => {
            let _ = std::fs::remove_file(&partial);
            Err(e)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        // A folder: empty is fine, one with files is not (unless forced).
        let empty = d.join("empty");
        std::fs::create_dir(&empty).unwrap();
        check(&empty, &[], false).unwrap();
        assert!(check(&d, &[], false).is_err());
        check(&d, &[], true).unwrap();
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
}
