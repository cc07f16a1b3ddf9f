//! Scene files: the shipped ones load and run; bad ones say which file and which field.

use super::*;
use std::path::PathBuf;

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

const SMALL: &str = r#"
seed = 9
[sheet]
shape = { kind = "rectangle", width = 0.13, height = 0.13 }
electrodes = { count = 16 }
resolution = 0.005
[[touch]]
position = [0.0, 0.0]
radius = 0.0075
pressure = 20e3
"#;

#[test]
fn every_shipped_scene_loads_and_runs() {
    let mut names = Vec::new();
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{e}"));
            assert!(
                !scene.description.is_empty(),
                "{} has a description",
                path.display()
            );
            let mut run = Run::new(&scene).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            for _ in 0..3 {
                let (frame, _) = run.next_frame(Detail::Frames).unwrap();
                assert!(frame.voltages.iter().all(|v| v.is_finite()));
                assert_eq!(
                    frame.voltages.len(),
                    run.config().validate().unwrap().frame_len()
                );
            }
            names.push(path.file_name().unwrap().to_string_lossy().to_string());
        }
    }
    for geometry in [
        "disc-22cm-16",
        "square-13cm-16",
        "square-13cm-8",
        "square-17cm-16",
        "strip-22x10-16",
        "l-shape-16",
    ] {
        assert!(
            names.iter().any(|n| n.starts_with(geometry)),
            "{geometry} ships"
        );
    }
    for reference in [
        "disc-ref-x075",
        "disc-ref-x050",
        "disc-ref-x025",
        "disc-ref-x000",
        "disc-ref-two",
    ] {
        assert!(
            names.iter().any(|n| n.starts_with(reference)),
            "{reference} ships"
        );
    }
}

#[test]
fn bad_scenes_name_the_file_and_the_field() {
    let err = |text: &str| Scene::parse(text, "bad.toml").unwrap_err().to_string();
    let typo = err(&SMALL.replace("radius = 0.0075", "radus = 0.0075"));
    assert!(
        typo.starts_with("bad.toml") && typo.contains("radus"),
        "{typo}"
    );
    let count = err(&SMALL.replace("count = 16", "count = 7"));
    assert!(
        count.contains("sheet.electrodes.count") && count.contains("even"),
        "{count}"
    );
    let off = err(&SMALL.replace("position = [0.0, 0.0]", "position = [0.5, 0.0]"));
    assert!(
        off.contains("touch[0].position") && off.contains("not on the sheet"),
        "{off}"
    );
    // A touch larger than the sheet used to hang; a steep pressure law gave NaN that blamed
    // a triangle.
    let huge = err(&SMALL.replace("radius = 0.0075", "radius = 1e308"));
    assert!(
        huge.contains("touch[0].radius") && huge.contains("sheet's size"),
        "{huge}"
    );
    let flat = err(&SMALL.replace(
        "radius = 0.0075",
        "radius = 0.0075\nfootprint = { elongation = 0.5, angle = 0.0 }",
    ));
    assert!(
        flat.contains("touch[0].footprint") && flat.contains("elongation"),
        "{flat}"
    );
    let piezo = err(&SMALL.replace("[[touch]]", "[sheet.piezo]\ngain = 1e15\n\n[[touch]]"));
    assert!(
        piezo.contains("sheet.piezo") && piezo.contains("gain"),
        "{piezo}"
    );
    let protocol = err(&format!("{SMALL}\n[scan]\nprotocol = \"spiral\"\n"));
    assert!(protocol.contains("scan.protocol"), "{protocol}");
    // A damaged file table is told by its field (an untagged enum said no variant matched).
    for (table, says) in [
        ("{ fle = \"p.csv\" }", "fle"),
        ("{ base = 1 }", "file"),
        ("{ file = \"p.csv\", base = -1 }", "base"),
        ("3", "a built-in protocol's name"),
    ] {
        let e = err(&format!("{SMALL}\n[scan]\nprotocol = {table}\n"));
        assert!(
            e.contains("protocol") && e.contains(says) && !e.contains("untagged"),
            "{table}: {e}"
        );
    }
    let settle = err(&format!("{SMALL}\n[scan]\nsettle_samples = 60\n"));
    assert!(settle.contains("settle_samples"), "{settle}");
    let shape = err(&SMALL.replace("width = 0.13, height", "width = -0.13, height"));
    assert!(shape.contains("width"), "{shape}");
    // Too fine a grid for memory is refused by name, not by an allocation abort, where the
    // simulator would build it; a scene that only images measured frames never does (a 1 m
    // sheet with 5 mm electrodes was refused for a grid nothing would make).
    let fine = Scene::parse(
        &SMALL.replace("resolution = 0.005", "resolution = 0.0005"),
        "fine.toml",
    )
    .unwrap();
    let fine = crate::sheet::SimulatedSheet::new(&fine.sheet, &[])
        .unwrap_err()
        .to_string();
    assert!(
        fine.contains("sheet.resolution") && fine.contains("at most 12000"),
        "{fine}"
    );
    // A touch under 1e-4 of the sheet's size changes no frame that single precision holds
    // (1e-20 m hung the mesher); one under half the grid spacing is kept for imaging (the
    // truth beside measured frames) and refused where the scene is simulated.
    let tiny = err(&SMALL.replace("radius = 0.0075", "radius = 1e-20"));
    assert!(
        tiny.contains("touch[0].radius: 1e-20 m is outside 1.3e-5 to 1.3e-1"),
        "{tiny}"
    );
    let small = Scene::parse(
        &SMALL.replace("radius = 0.0075", "radius = 0.001"),
        "s.toml",
    )
    .unwrap();
    let e = crate::still::simulated_sheet(&small)
        .unwrap_err()
        .to_string();
    assert!(e.contains("touch[0].radius: 0.001 m is under half"), "{e}");
    // A current is said in the field's own unit (0.0004 uA was "scan: current_na = 0").
    for (ua, says) in [
        ("0.0004", "4e-4 uA is outside 1e-3 to 5e4"),
        ("1e9", "1e9 uA is outside"),
    ] {
        let e = err(&format!("{SMALL}\n[scan]\ncurrent_ua = {ua}\n"));
        assert!(e.contains("scan.current_ua: ") && e.contains(says), "{e}");
    }
    // A pressure or a fabric's time constant past anything physical (a press of 1e30 Pa
    // loaded without a word; a load time of 1e300 s was a press that never arrives).
    for (edit, says) in [
        (
            "pressure = 1e30",
            "touch[0].pressure: 1e30 Pa is outside 0 to 1e9",
        ),
        (
            "pressure = 20e3\n[dynamics]\nload_s = 1e300",
            "dynamics.load_s: 1e300 s is outside 0 to 8.64e4",
        ),
        (
            "pressure = 20e3\n[dynamics]\nunload_s = -1",
            "dynamics.unload_s: -1 s is outside",
        ),
        (
            "pressure = 20e3\n[dynamics]\nhysteresis = 1.5",
            "dynamics.hysteresis: 1.5 must be in [0, 1)",
        ),
    ] {
        let e = err(&SMALL.replace("pressure = 20e3", edit));
        assert!(e.contains(says), "{edit}: {e}");
    }
    // An outline whose edges cross is refused before the sheet is built.
    let outline = |vertices: &str| {
        err(&SMALL.replace(
            r#"shape = { kind = "rectangle", width = 0.13, height = 0.13 }"#,
            &format!(r#"shape = {{ kind = "polygon", vertices = {vertices} }}"#),
        ))
    };
    let bow_tie = outline("[[0.0, 0.0], [0.1, 0.1], [0.1, 0.0], [0.0, 0.12]]");
    assert!(
        bow_tie.contains("sheet.shape") && bow_tie.contains("simple"),
        "{bow_tie}"
    );
    // A clockwise outline placed and numbered its electrodes the other way round (a
    // mirrored image) without a word: refused with the fix.
    let clockwise = outline("[[0.0, 0.0], [0.0, 0.1], [0.1, 0.1], [0.1, 0.0]]");
    assert!(
        clockwise.contains("sheet.shape") && clockwise.contains("vertices clockwise"),
        "{clockwise}"
    );
    let not_toml = err("[sheet\nshape = 3");
    assert!(not_toml.starts_with("bad.toml"), "{not_toml}");
    let missing = Scene::load(Path::new("/nonexistent/scene.toml"))
        .unwrap_err()
        .to_string();
    assert!(missing.contains("/nonexistent/scene.toml"), "{missing}");
}

/// A file that is not a scene (a frames CSV given as one) is said as such, and its line is
/// cut in the parser's snippet (a line of 5 000 characters was echoed whole, twice).
#[test]
fn a_file_that_is_no_scene_is_said_shortly() {
    let csv: String = (0..300).map(|i| format!("{i}.5e-02,")).collect();
    let e = Scene::parse(&csv, "frames.csv").unwrap_err().to_string();
    assert!(e.contains("is it a scene?"), "{e}");
    assert!(e.lines().all(|l| l.chars().count() <= 130), "{e}");
    assert_eq!(e.matches("TOML parse error").count(), 1, "{e}");
    // A scene's own mistake past its first line says the line, without the question.
    let e = Scene::parse(
        "[sheet]\nshape = { kind = \"disc\", radius = 0.1\n",
        "s.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("line 2") && !e.contains("is it a scene?"), "{e}");
    // A scene's field in the wrong table on its first line is said by the fields, not asked
    // whether the file is a scene.
    let e = Scene::parse(&format!("protocol = \"adjacent\"\n{SMALL}"), "s.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unknown field `protocol`") && !e.contains("is it a scene?"),
        "{e}"
    );
}

/// Another of et's files given as a scene is said as what it is (the parser's "invalid
/// key-value pair, expected key" was all it said of a recording), and an empty one as empty.
#[test]
fn another_of_ets_files_given_as_a_scene_is_named() {
    for (text, said) in [
        (
            "{\"format\":\"et-recording\",\"version\":1}\n",
            "r: an et recording (et sim, et record), not a scene",
        ),
        (
            "# et-dataset 2\n",
            "r: an et dataset (et collect), not a scene",
        ),
        (
            "source,sink,positive,negative\n0,1,2,3\n",
            "r: a protocol file (et protocol --csv), not a scene (a TOML file of [sheet], [scan] \
             and [[touch]] tables, as in sim/scenes/): a scene names it as [scan] protocol = { \
             file = \"FILE\" }",
        ),
        // An empty file, or one of comments alone ("missing field `sheet`" at line 1).
        ("", "r: an empty scene (no table or key in it)"),
        ("\u{feff}# a scene\n\n  # to write\n", "r: an empty scene"),
    ] {
        let e = Scene::parse(text, "r").unwrap_err().to_string();
        assert!(e.contains(said), "{e}");
    }
}

/// A field left out is said with what it is, in its unit, and a value to start from (serde's
/// "missing field `pressure`" left the unit to guess); a field of no such help as serde says it.
#[test]
fn a_field_left_out_is_said_with_its_unit() {
    let disc = "[sheet]\nshape = { kind = \"disc\", radius = 0.11 }\n";
    for (text, said) in [
        (
            format!("{disc}[[touch]]\nposition = [0.02, 0.0]\nradius = 0.008\n"),
            "missing field `pressure`: the touch's pressure while on, Pa",
        ),
        (
            format!("{disc}[[touch]]\nradius = 0.008\npressure = 2e4\n"),
            "missing field `position`: the touch's centre, [x, y] in m",
        ),
        (
            "[sheet]\nshape = { kind = \"rectangle\", width = 0.1 }\n".into(),
            "missing field `height`: the rectangle's extent",
        ),
        (
            "seed = 3\n".into(),
            "missing field `sheet`: the sheet's table",
        ),
        (
            "[sheet]\nshape = { radius = 0.1 }\n".into(),
            "missing field `kind`: what it is: an outline's \"disc\"",
        ),
        // A help past the snippet's 120 characters is said whole.
        (
            "[sheet]\nsheet_resistance = 200.0\n".into(),
            "missing field `shape`: the sheet's outline, m: shape = { kind = \"disc\", radius = \
             0.11 }, { kind = \"rectangle\", width = 0.13, height = 0.13 } or { kind = \
             \"polygon\", vertices = [[x, y], ...] }",
        ),
    ] {
        let e = Scene::parse(&text, "s.toml").unwrap_err().to_string();
        assert!(e.contains(said), "{e}");
    }
}

/// An unclosed inline table repeated (`b = {` after a table header, 3 000 times: 30 kB)
/// overflowed the TOML parser's stack and aborted the process (found by the parser fuzzer).
/// It is refused by line; brackets inside strings and comments do not count.
#[test]
fn runaway_nesting_is_refused_not_a_stack_overflow() {
    let deep = format!("seed = 1\n{}", "[a]\nb = {\n".repeat(3000));
    // On a small stack, as a test thread or a viewer thread has.
    let e = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || Scene::parse(&deep, "deep.toml").unwrap_err().to_string())
        .unwrap()
        .join()
        .unwrap();
    assert!(
        e.contains("deep.toml: line 66") && e.contains("nest deeper than 32"),
        "{e}"
    );
    // A wrong closer does not close: `{ ... ]` stays open for the parser too.
    let crossed = format!("seed = 1\n{}", "[a]\nb = { c = ]\n".repeat(3000));
    let e = Scene::parse(&crossed, "crossed.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("nest deeper than 32"), "{e}");
    // The parser's lexer, not a hand-written one, decides what is a string: after `shape"`
    // the quote belongs to the key's atom, so the `{` is real (found by the fuzzer).
    let quoted = format!(
        "seed = 1\n{}",
        "[sheet]\nshape\"= { kind touch, return)\"\nseed = 7\n\n".repeat(3000)
    );
    let e = Scene::parse(&quoted, "quoted.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("nest deeper than 32"), "{e}");
    // Size is capped before parsing.
    let huge = format!("{SMALL}{}", "# padding\n".repeat(MAX_SCENE_BYTES / 10));
    let e = Scene::parse(&huge, "huge.toml").unwrap_err().to_string();
    assert!(e.contains("a scene is at most 1048576 bytes"), "{e}");
    // Brackets in strings, multi-line strings and comments are not nesting.
    let noise = "{[".repeat(100);
    for description in [
        format!(r#""{noise}\"{noise}""#),
        format!("'{noise}'"),
        format!(
            r#""""
{noise}\"{noise}""""#
        ),
        format!("'''\n{noise}\n'{noise}'''"),
    ] {
        let text = format!("# {noise}\ndescription = {description}\n{SMALL}");
        Scene::parse(&text, "noisy.toml").unwrap_or_else(|e| panic!("{text}: {e}"));
    }
}

#[test]
fn runs_are_deterministic_from_the_seed() {
    let scene = Scene::parse(SMALL, "small").unwrap();
    let frames = |scene: &Scene| {
        let mut run = Run::new(scene).unwrap();
        (0..3)
            .map(|_| run.next_frame(Detail::Frames).unwrap().0)
            .collect::<Vec<_>>()
    };
    assert_eq!(frames(&scene), frames(&scene));
    let other = Scene {
        seed: 10,
        ..scene.clone()
    };
    assert_ne!(frames(&scene), frames(&other));
}

#[test]
fn electrode_movement_moves_the_frame() {
    let still = Scene::parse(SMALL, "small").unwrap();
    let moving = Scene {
        movement: Movement { rms: 0.002 },
        ..still.clone()
    };
    let quiet = |s: &Scene| {
        let mut s = s.clone();
        s.frontend = s.frontend.without_noise();
        Run::new(&s).unwrap().next_frame(Detail::Frames).unwrap().0
    };
    let (a, b) = (quiet(&still), quiet(&moving));
    let diff: f32 = a
        .voltages
        .iter()
        .zip(&b.voltages)
        .map(|(x, y)| (x - y).abs())
        .sum();
    assert!(diff > 1e-3, "moved electrodes change the frame ({diff} V)");
    // A still scene's sheet (et sim to another system's file, et reconstruct's simulated
    // frames) is the recording's: its electrodes moved as the seed draws them (they stayed
    // at their nominal places there).
    let z = |sheet: &crate::sheet::SimulatedSheet| sheet.transfer(&[]).unwrap().z;
    let still_sheet = z(&crate::still::simulated_sheet(&moving).unwrap());
    let recorded = crate::sheet::SimulatedSheet::new(&moving.sheet, &moving.electrode_offsets());
    assert_eq!(still_sheet, z(&recorded.unwrap()));
    assert_ne!(
        still_sheet,
        z(&crate::still::simulated_sheet(&still).unwrap())
    );
}

/// Electrodes moved so far (a movement of 1 m rms on a 13 cm sheet) that their order along
/// the outline changes, or so that neighbours overlap, are refused with the two electrodes:
/// the offsets were added without a look, and the frames were of scrambled electrodes.
#[test]
fn electrodes_moved_past_each_other_are_refused() {
    let still = Scene::parse(SMALL, "small").unwrap();
    let spacing = still.sheet.physical.shape.perimeter() / 16.0;
    for rms in [1.0, 0.5 * spacing] {
        let moving = Scene {
            movement: Movement { rms },
            ..still.clone()
        };
        let e = crate::still::simulated_sheet(&moving)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("movement: electrodes")
                && (e.contains("pass each other") || e.contains("overlap")),
            "{rms}: {e}"
        );
        let e = Run::new(&moving).unwrap_err().to_string();
        assert!(e.contains("movement: electrodes"), "{rms}: {e}");
    }
}

#[test]
fn touches_move_press_quickly_and_relax_slowly() {
    let text = SMALL.replace(
        "pressure = 20e3",
        "pressure = 40e3\nstart = 0.1\nend = 0.6\nto = [0.04, 0.0]",
    );
    let scene = Scene::parse(&text, "swipe").unwrap();
    let mut run = Run::new(&scene).unwrap();
    let period = run.frame_period();
    let mut history = Vec::new();
    while (history.len() as f64) * period < 2.0 {
        let (_, truth) = run.next_frame(Detail::Frames).unwrap();
        history.push(truth);
    }
    let at = |t: f64| &history[(t / period) as usize];
    assert!(
        at(0.05).touches.is_empty(),
        "nothing before the touch lands"
    );
    // 40 ms after landing (two load time constants) it presses at > 80 % of 40 kPa.
    let landed = &at(0.14).touches[0];
    assert!(landed.pressure > 0.8 * 40e3, "{}", landed.pressure);
    // Half-way through it is half-way along.
    let mid = &at(0.35).touches[0];
    assert!((mid.position[0] - 0.02).abs() < 0.002, "{:?}", mid.position);
    // After lifting at 0.6 s the effect fades slowly: still felt 100 ms later, more than a
    // pure unloading decay would leave (hysteresis), and all but gone 1.4 s (4.7 tau) later.
    let after = &at(0.7).touches;
    assert!(
        !after.is_empty() && after[0].pressure > 40e3 * (-0.1f64 / 0.3).exp() * 0.9,
        "{after:?}"
    );
    assert!(
        at(0.7).touches[0].position == at(0.59).touches[0].position,
        "it lifts where it was"
    );
    let last = &history.last().unwrap().touches;
    assert!(
        last.is_empty() || last[0].pressure < 0.05 * 40e3,
        "{last:?}"
    );
}

fn quiet(text: &str) -> Scene {
    let mut s = Scene::parse(text, "quiet").unwrap();
    s.frontend = s.frontend.without_noise();
    s
}

#[test]
fn faults_show_in_the_frames_not_averaged_in() {
    let text = format!(
        "{SMALL}\n[[fault]]\nelectrode = 5\nkind = \"disconnected\"\n\n[[fault]]\nelectrode = 2\nkind = \"shorted\"\nwith = 3\n"
    );
    let scene = quiet(&text);
    let mut run = Run::new(&scene).unwrap();
    let protocol = run.config().validate().unwrap();
    let (frame, _) = run.next_frame(Detail::Samples).unwrap();
    assert!(frame.flags & et_core::wire::FLAG_RAIL != 0);
    for step in protocol.steps() {
        let k = usize::from(step.k);
        let (inj, m) = (step.injection, step.measurement);
        let probes_5 = m.positive.0 == 5 || m.negative.0 == 5;
        let drives_5 = inj.source.0 == 5 || inj.sink.0 == 5;
        let v = frame.voltages[k];
        if probes_5 {
            assert!(v > 4.9, "step {k} reads a floating electrode: {v} V");
        } else if drives_5 {
            assert!(
                v.abs() < 1e-3,
                "no current through a disconnected electrode: step {k} {v} V"
            );
        } else if (m.positive.0, m.negative.0) == (2, 3) {
            assert!(
                v.abs() < 1e-3,
                "a shorted pair reads nothing: step {k} {v} V"
            );
        }
    }
    // Intermittent: some frames flag the electrode, some do not.
    let text =
        format!("{SMALL}\n[[fault]]\nelectrode = 9\nkind = \"intermittent\"\nprobability = 0.02\n");
    let mut run = Run::new(&quiet(&text)).unwrap();
    let flagged = (0..20)
        .filter(|_| {
            run.next_frame(Detail::Frames)
                .unwrap()
                .0
                .voltages
                .iter()
                .any(|&v| v > 4.9)
        })
        .count();
    assert!(flagged > 0 && flagged < 20, "{flagged} of 20 frames");
    let bad = Scene::parse(
        &format!("{SMALL}\n[[fault]]\nelectrode = 3\nkind = \"shorted\"\n"),
        "bad.toml",
    );
    assert!(bad.unwrap_err().to_string().contains("fault[0].with"));
}

#[test]
fn timestamps_keep_advancing_past_the_counters_wrap() {
    // The 32-bit microsecond counter wraps after 2^32 us = 71.6 minutes; frames beyond it
    // keep their spacing (it used to stop at the top).
    let mut run = Run::new(&quiet(SMALL)).unwrap();
    let period = run.frame_period();
    run.seq = (4_294.0 / period) as u32;
    let times: Vec<et_core::time::Micros> = (0..(4.0 / period) as usize)
        .map(|_| run.next_frame(Detail::Frames).unwrap().0.timestamp)
        .collect();
    assert!(
        times.windows(2).any(|w| w[1].0 < w[0].0),
        "the counter wrapped"
    );
    for w in times.windows(2) {
        let step = f64::from(w[1].since(w[0])) * 1e-6;
        assert!(
            (step - period).abs() < 2e-6,
            "{step} s between frames, not {period}"
        );
    }
}

#[test]
fn drift_scales_the_frame_over_time() {
    // +10 % conductance per kelvin, 60 K per minute: after 1 s the sheet conducts 10 % more.
    // No touch, so that only the drift changes the frame.
    let untouched = &SMALL[..SMALL.find("[[touch]]").unwrap()];
    let scene = quiet(&format!(
        "{untouched}\n[drift]\nper_kelvin = 0.1\nkelvin_per_minute = 60.0\n"
    ));
    let mut run = Run::new(&scene).unwrap();
    let (first, _) = run.next_frame(Detail::Frames).unwrap();
    let n = (1.0 / run.frame_period()).round() as usize;
    let mut last = first.clone();
    let mut t = 0.0;
    for _ in 0..n {
        let (f, truth) = run.next_frame(Detail::Frames).unwrap();
        last = f;
        t = truth.time;
    }
    let want = 1.0 / (1.0 + 0.1 * t);
    let lsb = 10.0 / 65_536.0;
    for (a, b) in last.voltages.iter().zip(&first.voltages) {
        assert!(
            (f64::from(*a) - want * f64::from(*b)).abs() <= lsb,
            "{a} vs {want} x {b}"
        );
    }
}

/// A value of the wrong kind is said as what the file holds and what belongs there (the
/// parser said "expected f64", "expected struct ElectrodeSpec", "expected internally tagged
/// enum Shape": the types the scene is read into), under the parser's line and snippet.
#[test]
fn a_value_of_the_wrong_kind_is_said_in_the_files_words() {
    let disc = "shape = { kind = \"disc\", radius = 0.1 }";
    for (sheet, said) in [
        (
            format!("{disc}\nelectrodes = {{ count = 16 }}\nsheet_resistance = \"30e3\""),
            "\"30e3\" is text, where a number belongs (write it without quotes)",
        ),
        (
            format!("{disc}\nelectrodes = 16"),
            "16 is a whole number, where a table of fields belongs",
        ),
        (
            "shape = \"disc\"\nelectrodes = { count = 16 }".to_string(),
            "\"disc\" is text, where a table of fields belongs",
        ),
    ] {
        let e = Scene::parse(&format!("[sheet]\n{sheet}\n"), "s.toml")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("TOML parse error at line") && e.contains(said),
            "{e}"
        );
        for internal in ["f64", "struct", "enum", "Spec", "expected"] {
            assert!(!e.contains(internal), "{e}");
        }
    }
}
