//! The `et` binary from the outside: what a user or a script sees.

use std::process::Command;

fn et(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_et"))
        .args(args)
        .output()
        .expect("run et")
}

/// `et ARGS`, which must succeed (its standard error shown if not).
fn et_ok(args: &[&str]) -> std::process::Output {
    let out = et(args);
    assert!(
        out.status.success(),
        "et {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// What a Python script of the repository prints for one file (it must succeed).
fn python_script(script: &std::path::Path, file: &std::path::Path) -> String {
    let py = Command::new("python3")
        .arg(script)
        .arg(file)
        .output()
        .expect("python3 is needed for this test");
    assert!(
        py.status.success(),
        "{}: {}",
        script.display(),
        String::from_utf8_lossy(&py.stderr)
    );
    String::from_utf8_lossy(&py.stdout).into_owned()
}

#[test]
fn protocol_json_reports_k_and_p_for_every_l() {
    for l in (4..=32).step_by(2) {
        for name in ["adjacent", "pseudo-polar", "pp-pp", "opposite"] {
            let out = et(&[
                "protocol",
                "--electrodes",
                &l.to_string(),
                "--protocol",
                name,
                "--json",
            ]);
            if name == "opposite" && l == 4 {
                // K = L (L - 4) = 0: refused with a reason, not an empty table.
                assert!(!out.status.success());
                assert!(String::from_utf8_lossy(&out.stderr).contains("no usable measurement"));
                continue;
            }
            assert!(
                out.status.success(),
                "{name} L={l}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
            let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("valid JSON");
            let k = v["K"].as_u64().unwrap() as usize;
            let rows = v["injections"].as_array().unwrap();
            assert_eq!(rows.len(), l);
            let measured: usize = rows
                .iter()
                .map(|r| r["measurements"].as_array().unwrap().len())
                .sum();
            assert_eq!(measured, k, "{name} L={l}");
            // No measurement touches the row's current-carrying electrodes.
            for r in rows {
                let (src, sink) = (r["source"].as_u64().unwrap(), r["sink"].as_u64().unwrap());
                for m in r["measurements"].as_array().unwrap() {
                    let (a, b) = (m[0].as_u64().unwrap(), m[1].as_u64().unwrap());
                    assert!(![src, sink].contains(&a) && ![src, sink].contains(&b));
                }
            }
            if name == "opposite" {
                assert_eq!(v["p_halved"].as_u64().unwrap() as usize, l * (l - 4) / 2);
            }
        }
    }
}

#[test]
fn protocol_text_and_errors_teach() {
    let out = et(&["protocol", "-l", "16", "-p", "ad"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("K = 208"), "{text}");
    let bad = et(&["protocol", "-l", "7"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("even number from 4 to 32"));
    // Past the range, or written as a decimal: the bound, not "300 is not in 0..=255" or
    // "invalid digit found in string".
    for (l, said) in [
        ("300", "300 is above 32, the most it takes"),
        ("2", "2 is below 4, the least it takes"),
        ("16.0", "'16.0' is not a whole number as written: write 16"),
    ] {
        let bad = et(&["protocol", "-l", l]);
        let err = String::from_utf8_lossy(&bad.stderr);
        assert!(!bad.status.success() && err.contains(said), "{err}");
    }
    let unknown = et(&["protocol", "-p", "spiral"]);
    assert!(
        String::from_utf8_lossy(&unknown.stderr)
            .contains("possible values: adjacent, pseudo-polar, pp-pp, opposite")
    );
    let general = et(&[
        "protocol",
        "-l",
        "16",
        "--drive-skip",
        "6",
        "--measure-skip",
        "0",
        "--measure-skip",
        "6",
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&general.stdout).unwrap();
    assert_eq!(v["K"], 400, "the general form with PP-PP's skips is PP-PP");
    // A named protocol beside the general form is refused (it was ignored without a word).
    let both = et(&[
        "protocol",
        "-p",
        "opposite",
        "--drive-skip",
        "3",
        "--measure-skip",
        "0",
    ]);
    assert!(!both.status.success());
    assert!(String::from_utf8_lossy(&both.stderr).contains("cannot be used with"));
    let help = et(&["protocol", "--help"]);
    assert!(String::from_utf8_lossy(&help.stdout).contains("Examples:"));
}

#[test]
fn sim_writes_a_recording_that_python_reads() {
    let dir = std::env::temp_dir().join(format!("et-cli-sim-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("touch.jsonl");
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let run = et(&[
        "sim",
        "--scene",
        scene.to_str().unwrap(),
        "--frames",
        "30",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(String::from_utf8_lossy(&run.stderr).contains("wrote 30 frames of 208 values"));
    // Read back in Rust...
    let rec = et_host::recording::read(&out).unwrap();
    assert_eq!(rec.records.len(), 30);
    // ...and with the documented Python reader (standard library only).
    let text = python_script(&root.join("python/et_recording.py"), &out);
    assert!(
        text.contains("frames 30")
            && text.contains("K 208")
            && text.contains("protocol adjacent L 16"),
        "{text}"
    );
    // The touch lands at 0.05 s (frame 4 at 78 Hz): later frames carry it.
    let touched: usize = text
        .lines()
        .find_map(|l| l.strip_prefix("touched "))
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(
        touched,
        rec.records
            .iter()
            .filter(|r| r.touches.as_ref().is_some_and(|t| !t.is_empty()))
            .count()
    );
    assert!(touched >= 25);
    // A swipe's touches streamed for another program (the finger lands after the 20 frames
    // that make V_0): positions to 0.1 mm, not 15 decimals.
    let swipe = dir.join("swipe.jsonl");
    let run = et(&[
        "sim",
        "--scene",
        root.join("sim/scenes/square-13cm-16-swipe.toml")
            .to_str()
            .unwrap(),
        "--frames",
        "50",
        "--out",
        swipe.to_str().unwrap(),
    ]);
    assert!(run.status.success());
    let stream = et(&["stream", "--json", "--replay", swipe.to_str().unwrap()]);
    assert!(
        stream.status.success(),
        "{}",
        String::from_utf8_lossy(&stream.stderr)
    );
    let events: Vec<serde_json::Value> = String::from_utf8_lossy(&stream.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON object a line"))
        .collect();
    assert!(!events.is_empty(), "the replayed touch is streamed");
    for e in &events {
        for v in e["position_mm"].as_array().unwrap() {
            let text = v.to_string();
            let decimals = text.split_once('.').map_or(0, |(_, d)| d.len());
            assert!(decimals <= 1, "{text} in {e}");
        }
    }
    another_systems_frames_play_as_the_recording(&root, &dir, &swipe, &stream.stdout);
    // A bad scene names the file and the field.
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "[sheet]\nshape = { kind = \"disc\", radius = 0.1 }\nelectrodes = { count = 7 }\n",
    )
    .unwrap();
    let err = et(&[
        "sim",
        "--scene",
        bad.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--force",
    ]);
    assert!(!err.status.success());
    let msg = String::from_utf8_lossy(&err.stderr);
    assert!(
        msg.contains("bad.toml") && msg.contains("sheet.electrodes.count"),
        "{msg}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The swipe recording's frames written as another system's CSV (volts, one frame per row)
/// play the touches `et stream` found in the recording (`streamed`, its stdout), the scene
/// giving the protocol; shorter files, one reference frame, a protocol file and a current
/// above the board's are played or refused as said.
fn another_systems_frames_play_as_the_recording(
    root: &std::path::Path,
    dir: &std::path::Path,
    swipe: &std::path::Path,
    streamed: &[u8],
) {
    let recorded = et_host::recording::read(swipe).unwrap();
    // The frames times `gain` (a system's other current, or polarity), one a row.
    let frames_csv = |gain: f64| -> String {
        (recorded.records.iter())
            .map(|r| {
                let row: Vec<String> = (r.voltages.iter())
                    .map(|v| format!("{:e}", f64::from(*v) * gain))
                    .collect();
                row.join(",") + "\n"
            })
            .collect()
    };
    let csv = frames_csv(1.0);
    let swipe_csv = dir.join("swipe.csv");
    std::fs::write(&swipe_csv, &csv).unwrap();
    let scene = root.join("sim/scenes/square-13cm-16-swipe.toml");
    // `et stream` replaying another system's frames of the swipe's scene.
    let replay = |file: &std::path::Path, extra: &[&str]| {
        let args = [
            "stream",
            "--json",
            "--replay",
            file.to_str().unwrap(),
            "--scene",
            scene.to_str().unwrap(),
        ];
        et(&[&args[..], extra].concat())
    };
    let from_csv = replay(&swipe_csv, &[]);
    assert!(
        from_csv.status.success(),
        "{}",
        String::from_utf8_lossy(&from_csv.stderr)
    );
    let positions = |out: &[u8]| -> Vec<serde_json::Value> {
        String::from_utf8_lossy(out)
            .lines()
            .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["position_mm"].clone())
            .collect()
    };
    assert_eq!(positions(&from_csv.stdout), positions(streamed));
    let fits = String::from_utf8_lossy(&from_csv.stderr);
    // Its events' t_us, 0 without a board's clock, said as that.
    assert!(
        fits.contains("no board clock in the file: every event's t_us is 0"),
        "{fits}"
    );
    assert!(
        !fits.contains("unexplained") && !fits.contains("was the sheet touched"),
        "{fits}"
    );
    // The swipe from its 40th frame on, then its start: the untouched reference is then 20
    // frames of the finger moving, said once the reference is complete (its touches were
    // streamed against it without a word).
    let touched_first = dir.join("touched-first.csv");
    let lines: Vec<&str> = csv.lines().collect();
    let moved: String = (lines[40..].iter().chain(&lines[..40]))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&touched_first, moved).unwrap();
    let touched = replay(&touched_first, &[]);
    let said = String::from_utf8_lossy(&touched.stderr);
    assert!(
        said.matches("was the sheet touched, or drifting").count() == 1,
        "{said}"
    );
    // `et reconstruct` of the same frames, V_0 from their first 20, says it too, and of the
    // swipe's own frames with them as --reference-file.
    let picture = dir.join("touched-first.png");
    let reconstruct = |args: &[&str]| {
        let common = ["reconstruct", "--scene", scene.to_str().unwrap()];
        let out = ["--out", picture.to_str().unwrap(), "--force"];
        et(&[&common[..], args, &out[..]].concat())
    };
    let touched_first = touched_first.to_str().unwrap();
    for asked in [
        [
            "--frames",
            touched_first,
            "--reference",
            "20",
            "--frame",
            "30",
        ],
        [
            "--frames",
            swipe_csv.to_str().unwrap(),
            "--reference-file",
            touched_first,
            "--frame",
            "45",
        ],
    ] {
        let imaged = reconstruct(&asked);
        let said = String::from_utf8_lossy(&imaged.stderr);
        assert!(
            imaged.status.success() && said.contains("was the sheet touched, or drifting"),
            "{asked:?}: {said}"
        );
    }
    // Frames of the other sign (sense wires swapped) are refused at their reference, once,
    // as `et reconstruct` refuses them (they streamed touches in the wrong places).
    let negated_csv = dir.join("negated.csv");
    std::fs::write(&negated_csv, frames_csv(-1.0)).unwrap();
    let e = replay(&negated_csv, &[]);
    let said = String::from_utf8_lossy(&e.stderr);
    assert!(
        !e.status.success()
            && said.contains("runs against the model")
            && !said.contains("skipped")
            && e.stdout.is_empty(),
        "{said}"
    );
    // Without --scene they are refused: et's default sheet is not the one they were
    // measured on (they were imaged on it, touches in the wrong places, without a word).
    let bare = et(&["stream", "--json", "--replay", swipe_csv.to_str().unwrap()]);
    let said = String::from_utf8_lossy(&bare.stderr);
    assert!(
        !bare.status.success() && said.contains("give a scene with --scene"),
        "{said}"
    );
    // A recording shorter than the untouched reference gives no image: said, not silence.
    let short = dir.join("short.csv");
    let first: String = csv.lines().take(3).map(|l| format!("{l}\n")).collect();
    std::fs::write(&short, first).unwrap();
    // And --frames ending it before the reference is said as that (it said the file ended,
    // and the reference's length as 0 frames).
    for (extra, said) in [
        (
            &[][..],
            "it ended after 3 frames before the untouched reference (20 frames)",
        ),
        (
            &["--frames", "2"],
            "--frames 2 stopped it before the untouched reference (20 frames)",
        ),
        // Its three frames all the reference: said as that (it said the reference was not
        // complete).
        (
            &["--reference", "3"],
            "it ended after 3 frames, and every frame went into the untouched reference \
             (--reference 3): no frame was imaged; if fewer of its first frames are untouched, \
             give their count (--reference 1 to 2)",
        ),
    ] {
        let e = replay(&short, extra);
        let message = String::from_utf8_lossy(&e.stderr);
        assert!(!e.status.success() && message.contains(said), "{message}");
        // No pace of frames "each referenced, imaged, searched for touches" is said.
        assert!(!message.contains("frames/s"), "{message}");
    }
    // Another system's file with one untouched frame at its start (as many tanks' are): with
    // --reference 1 each frame's noise is estimated from the frame itself, and the swipe
    // streams as it does against 20 untouched frames: the same frames touched, the same
    // places within 2 mm (no untouched frame called a touch, none of the swipe's missed).
    let one = dir.join("one.csv");
    let kept: String = (csv.lines().enumerate())
        .filter(|(i, _)| *i == 0 || *i >= 20)
        .map(|(_, l)| format!("{l}\n"))
        .collect();
    std::fs::write(&one, kept).unwrap();
    let from_one = replay(&one, &["--reference", "1"]);
    let (a, b) = (positions(&from_csv.stdout), positions(&from_one.stdout));
    assert_eq!(
        a.len(),
        b.len(),
        "{}",
        String::from_utf8_lossy(&from_one.stderr)
    );
    for (a, b) in a.iter().zip(&b) {
        let d = |i: usize| a[i].as_f64().unwrap() - b[i].as_f64().unwrap();
        assert!(d(0).hypot(d(1)) < 2.0, "{a} and {b}");
    }
    // A scene whose protocol is a file is for `et reconstruct`, and says so.
    std::fs::write(dir.join("p.csv"), "0,1,2,3\n").unwrap();
    let file_scene = dir.join("file-protocol.toml");
    std::fs::write(
        &file_scene,
        "[sheet]\nshape = { kind = \"disc\", radius = 0.1 }\n\n[scan]\nprotocol = { file = \"p.csv\" }\n",
    )
    .unwrap();
    let e = et(&[
        "stream",
        "--json",
        "--replay",
        swipe_csv.to_str().unwrap(),
        "--scene",
        file_scene.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&e.stderr).into_owned();
    // (It named the frames' file as the one holding `scan.protocol`.)
    assert!(
        e.contains("file-protocol.toml: scan.protocol: a protocol file")
            && e.contains("et reconstruct --scene")
            && e.contains("--frames"),
        "{e}"
    );
    // Another system driving more than the board's 1 mA (a tank at 2 mA, its frames 62.5
    // times the swipe's 32 uA ones) plays as the board's 1 mA, said: the same touches at the
    // same places. (It was refused as more than "the simulated board drives".)
    let text = std::fs::read_to_string(&scene).unwrap();
    let tank = dir.join("tank-2ma.toml");
    std::fs::write(
        &tank,
        text.replace("[scan]\n", "[scan]\ncurrent_ua = 2000\n"),
    )
    .unwrap();
    let tank_csv = dir.join("tank-2ma.csv");
    std::fs::write(&tank_csv, frames_csv(62.5)).unwrap();
    let played = et(&[
        "stream",
        "--json",
        "--replay",
        tank_csv.to_str().unwrap(),
        "--scene",
        tank.to_str().unwrap(),
    ]);
    let said = String::from_utf8_lossy(&played.stderr);
    assert!(
        played.status.success()
            && said.contains("driven at 2000 uA, played as the board's 1000 uA"),
        "{said}"
    );
    let (a, b) = (positions(&from_csv.stdout), positions(&played.stdout));
    assert_eq!(a.len(), b.len(), "{said}");
    for (a, b) in a.iter().zip(&b) {
        let d = |i: usize| a[i].as_f64().unwrap() - b[i].as_f64().unwrap();
        assert!(d(0).hypot(d(1)) < 0.2, "{a} and {b}");
    }
}

/// The dataset as Python users read it: `python/et_dataset.py` (standard library), and the
/// numpy recipe its docstring gives, run as written (with the file's path) where numpy is
/// installed.
fn python_reads_the_dataset(root: &std::path::Path, csv: &std::path::Path) {
    let reader = root.join("python/et_dataset.py");
    let text = python_script(&reader, csv);
    assert!(
        text.contains("observations 80")
            && text.contains("features 96")
            && text.contains("classes 4"),
        "{text}"
    );
    let has_numpy = Command::new("python3")
        .args(["-c", "import numpy"])
        .status()
        .is_ok_and(|s| s.success());
    if !has_numpy {
        eprintln!("numpy not installed: the docstring's numpy recipe is not run");
        return;
    }
    let doc = std::fs::read_to_string(&reader).unwrap();
    let recipe: String = doc
        .lines()
        .skip_while(|l| !l.starts_with("With numpy"))
        .skip(1)
        .skip_while(|l| l.trim().is_empty())
        .take_while(|l| !l.trim().is_empty())
        .map(|l| format!("{}\n", l.strip_prefix("    ").unwrap_or(l)))
        .collect::<String>()
        .replace("\"train.csv\"", &format!("{:?}", csv.to_str().unwrap()));
    assert!(recipe.contains("numpy.loadtxt"), "{recipe}");
    let run = Command::new("python3")
        .args([
            "-c",
            &format!("{recipe}print(x.shape, sorted(int(v) for v in set(label)))"),
        ])
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{recipe}: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let shape = String::from_utf8_lossy(&run.stdout);
    assert!(shape.contains("(80, 96) [0, 1, 2, 3]"), "{shape}");
}

/// One touch rule: the live pipeline (`et stream --replay`) and `et reconstruct` of the same
/// recording, with the live pipeline's settings (its 20 untouched frames as V_0, one-step
/// Gauss-Newton at alpha 0.3 and s 0.5, 3 000 triangles, 32 x 32 pixels, the scene's
/// background), find a touch on the same frames and put it in the same place.
#[test]
fn stream_and_reconstruct_find_the_same_touches() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = std::env::temp_dir().join(format!("et-cli-one-rule-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = root.join("sim/scenes/square-13cm-16-swipe.toml");
    let scene = scene.to_str().unwrap();
    let swipe = dir.join("swipe.jsonl");
    let swipe = swipe.to_str().unwrap();
    let run = et(&["sim", "--scene", scene, "--frames", "60", "--out", swipe]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stream = et(&["stream", "--json", "--replay", swipe]);
    assert!(
        stream.status.success(),
        "{}",
        String::from_utf8_lossy(&stream.stderr)
    );
    let events: Vec<serde_json::Value> = String::from_utf8_lossy(&stream.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let recording = et_host::recording::read(std::path::Path::new(swipe)).unwrap();
    let (mut touched, mut untouched) = (0, 0);
    // Every third frame after the reference: the untouched ones before the finger lands, then
    // the swipe.
    for frame in (20..60).step_by(3) {
        let seq = recording.records[frame].seq;
        let event = events.iter().find(|e| e["seq"] == seq);
        let out = dir.join(format!("frame-{frame}.png"));
        let image = et(&[
            "reconstruct",
            "--scene",
            scene,
            "--frames",
            swipe,
            "--frame",
            &frame.to_string(),
            "--reference",
            "20",
            "--alpha",
            "0.3",
            "--triangles",
            "3000",
            "--pixels",
            "32",
            "--background",
            "scene",
            "--out",
            out.to_str().unwrap(),
            "--json",
        ]);
        assert!(
            image.status.success(),
            "{}",
            String::from_utf8_lossy(&image.stderr)
        );
        let summary: serde_json::Value = serde_json::from_slice(&image.stdout).unwrap();
        let found = summary["found_touches"].as_array().unwrap();
        match (event, found.first()) {
            (None, None) => untouched += 1,
            (Some(e), Some(first)) => {
                touched += 1;
                for axis in 0..2 {
                    let (live, offline) = (
                        e["position_mm"][axis].as_f64().unwrap(),
                        first["centroid_mm"][axis].as_f64().unwrap(),
                    );
                    // The stream prints tenths of a millimetre; its image is the same matrix in
                    // f32.
                    assert!(
                        (live - offline).abs() <= 0.1,
                        "frame {frame}: stream {live} mm, reconstruct {offline} mm"
                    );
                }
            }
            (e, f) => panic!("frame {frame}: stream {e:?}, reconstruct {f:?}"),
        }
    }
    assert!(
        touched >= 5 && untouched >= 1,
        "{touched} touched, {untouched} not"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn collect_train_eval_export_chain() {
    let dir = std::env::temp_dir().join(format!("et-cli-learn-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let (train, test, model) = (
        dir.join("train.csv"),
        dir.join("test.csv"),
        dir.join("model.json"),
    );
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let ok = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    };
    let json = |text: String| -> serde_json::Value { serde_json::from_str(text.trim()).unwrap() };
    let base = [
        "collect",
        "--scene",
        &s(&scene),
        "--grid",
        "2x2",
        "--scans",
        "2",
        "--subsections",
        "5",
    ];
    let collected = et(&[&base[..], &["--visits", "2", "--out", &s(&train), "--json"]].concat());
    // The scene's adjacent is not what is collected: said (it was replaced without a word).
    let said = String::from_utf8_lossy(&collected.stderr).into_owned();
    assert!(
        said.contains("et collect scans the opposite protocol, the method's training scan")
            && said.contains("the scene's adjacent is not used here"),
        "{said}"
    );
    let c = json(ok(collected));
    assert_eq!(
        (
            c["observations"].as_u64(),
            c["features"].as_u64(),
            c["classes"].as_u64()
        ),
        (Some(80), Some(96), Some(4))
    );
    python_reads_the_dataset(&root, &train);
    ok(et(&[
        &base[..],
        &["--visits", "1", "--seed", "9", "--out", &s(&test)],
    ]
    .concat()));
    let t = json(ok(et(&[
        "train",
        "--data",
        &s(&train),
        "--shrinkage",
        "0.3",
        "--folds",
        "4",
        "--out",
        &s(&model),
        "--curve",
        &s(&dir.join("curve.png")),
        "--json",
    ])));
    assert_eq!(t["classes"], 4);
    assert_eq!(
        t["referenced"], true,
        "untouched frames were collected: {t}"
    );
    // Learning curve: n_c up to the 20 observations per class there are, as a PNG.
    let curve = t["learning_curve"].as_array().unwrap();
    assert_eq!(curve.last().unwrap()["n_c"], 20);
    assert!(
        std::fs::read(dir.join("curve.png"))
            .unwrap()
            .starts_with(b"\x89PNG")
    );
    assert!(t["cv_accuracy"].as_f64().unwrap() > 0.9, "{t}");
    assert!(t["leave_one_visit_out_accuracy"].as_f64().is_some());
    let e = json(ok(et(&[
        "eval",
        "--model",
        &s(&model),
        "--data",
        &s(&test),
        "--plots",
        &s(&dir.join("plots")),
        "--json",
    ])));
    for png in ["confusion.png", "error-vs-distance.png"] {
        let bytes = std::fs::read(dir.join("plots").join(png)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG"), "{png}");
    }
    // The same test set as NumPy arrays (same seed): the same evaluation.
    let npz = dir.join("test.npz");
    ok(et(&[
        &base[..],
        &["--visits", "1", "--seed", "9", "--out", &s(&npz)],
    ]
    .concat()));
    assert!(
        std::fs::read(&npz).unwrap().starts_with(b"PK\x03\x04"),
        "a zip"
    );
    let en = json(ok(et(&[
        "eval",
        "--model",
        &s(&model),
        "--data",
        &s(&npz),
        "--json",
    ])));
    assert_eq!(
        (&en["accuracy"], &en["confusion"]),
        (&e["accuracy"], &e["confusion"])
    );
    let (a, b) = (en["mean_error_mm"].as_f64(), e["mean_error_mm"].as_f64());
    assert!((a.unwrap() - b.unwrap()).abs() < 1e-9, "{a:?} {b:?}");
    // The error from where the finger really was (the dataset keeps it), beside the
    // centre-to-centre one.
    let from_truth = ["mean_error_mm", "median_error_mm", "p90_error_mm"]
        .map(|k| e[k].as_f64().unwrap_or_else(|| panic!("{k} missing: {e}")));
    assert!(from_truth.iter().all(|v| v.is_finite() && *v >= 0.0), "{e}");
    assert!(from_truth[2] >= from_truth[1], "p90 below the median: {e}");
    assert!(e["mean_cell_error_mm"].as_f64().is_some(), "{e}");
    let bands = e["by_distance_from_electrodes"].as_array().unwrap();
    let counted: u64 = bands.iter().map(|b| b["count"].as_u64().unwrap()).sum();
    assert_eq!(counted, 40, "every observation is in a distance band");
    assert_eq!(
        e["observations"], 40,
        "4 classes x 2 scans x 5 sub-sections"
    );
    let confusion: u64 = e["confusion"]
        .as_array()
        .unwrap()
        .iter()
        .flat_map(|r| r.as_array().unwrap())
        .map(|v| v.as_u64().unwrap())
        .sum();
    assert_eq!(confusion, 40);
    for (precision, name) in [("f32", "m32.etm"), ("f16", "m16.etm")] {
        let x = json(ok(et(&[
            "export",
            "--model",
            &s(&model),
            "--precision",
            precision,
            "--out",
            &s(&dir.join(name)),
            "--json",
        ])));
        let bytes = std::fs::read(dir.join(name)).unwrap();
        assert_eq!(x["bytes"].as_u64(), Some(bytes.len() as u64));
        let blob =
            et_core::model::Model::parse(&bytes).expect("the exported blob loads in et-core");
        assert_eq!((blob.classes(), blob.features()), (4, 96));
        assert!(blob.referenced());
    }
    // A feature-reduced model: trained on 20 of the 96, evaluated on the full test set, exported.
    let small = dir.join("small.json");
    let t = json(ok(et(&[
        "train",
        "--data",
        &s(&train),
        "--shrinkage",
        "0.3",
        "--keep",
        "20",
        "--out",
        &s(&small),
        "--json",
    ])));
    assert_eq!(t["features"], 20);
    let e = json(ok(et(&[
        "eval",
        "--model",
        &s(&small),
        "--data",
        &s(&test),
        "--json",
    ])));
    assert_eq!(e["observations"], 40);
    ok(et(&[
        "export",
        "--model",
        &s(&small),
        "--out",
        &s(&dir.join("small.etm")),
    ]));
    let bytes = std::fs::read(dir.join("small.etm")).unwrap();
    assert_eq!(et_core::model::Model::parse(&bytes).unwrap().features(), 20);
    // Mistakes are explained.
    let bad = et(&[
        "train",
        "--data",
        &s(&train),
        "--kind",
        "svm",
        "--out",
        &s(&model),
    ]);
    assert!(
        String::from_utf8_lossy(&bad.stderr)
            .contains("[possible values: qda, lda, ridge, kernel-ridge, knn, gp, mlp, auto]")
    );
    let bad = et(&[
        "collect",
        "--scene",
        &s(&scene),
        "--grid",
        "7",
        "--out",
        &s(&train),
        "--force",
    ]);
    assert!(String::from_utf8_lossy(&bad.stderr).contains("ROWSxCOLS"));
    let bad = et(&["eval", "--model", &s(&train), "--data", &s(&test)]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("train.csv"));
    // A model trained on frames as measured takes no V_0: --tare is refused before the
    // upload (it took a V_0 the model never reads).
    let (raw, raw_blob) = (dir.join("raw.json"), dir.join("raw.etm"));
    ok(et(&[
        "train",
        "--data",
        &s(&train),
        "--raw",
        "--shrinkage",
        "0.3",
        "--out",
        &s(&raw),
    ]));
    ok(et(&["export", "--model", &s(&raw), "--out", &s(&raw_blob)]));
    let tare = et(&[
        "upload",
        "--port",
        "/dev/null",
        "--blob",
        &s(&raw_blob),
        "--tare",
    ]);
    let said = String::from_utf8_lossy(&tare.stderr);
    assert!(
        !tare.status.success() && said.contains("takes no V_0: drop --tare"),
        "{said}"
    );
    // The model classifies the live frames of its sheet, each touch with a class; on another
    // sheet its classes would name its own sheet's places (a 17 cm sheet's model put a touch
    // 57 mm off at a posterior of 1.0): refused, naming the model.
    let stream = |scene: &str| {
        let scene = s(&root.join("sim/scenes").join(scene));
        et(&[
            "stream",
            "--json",
            "--fast",
            "--frames",
            "50",
            "--scene",
            &scene,
            "--model",
            &s(&model),
        ])
    };
    let events = ok(stream("square-13cm-16.toml"));
    let last: serde_json::Value = serde_json::from_str(events.lines().last().unwrap()).unwrap();
    assert!(last["class"].as_u64().is_some_and(|c| c < 4), "{events}");
    let other = stream("square-17cm-16.toml");
    let said = String::from_utf8_lossy(&other.stderr);
    assert!(
        !other.status.success()
            && said.contains("model.json: the model was trained on another sheet: its electrode 1"),
        "{said}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn reconstruct_writes_an_image_and_finds_the_touch() {
    let dir = std::env::temp_dir().join(format!("et-cli-recon-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let png = dir.join("x075.png");
    let out = et(&[
        "reconstruct",
        "--scene",
        root.join("sim/scenes/disc-ref-x075.toml").to_str().unwrap(),
        "--triangles",
        "3000",
        "--out",
        png.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(std::fs::read(&png).unwrap().starts_with(b"\x89PNG"));
    // The strongest region lies on the touch (82.5, 0) mm, radius 13.3 mm.
    let c = &j["regions"][0]["centroid_mm"];
    let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
    assert!((x - 82.5).hypot(y) < 13.3, "{j}");
    assert!(j["alpha"].as_f64().unwrap() > 0.0);
    // Stage times: set-up is the first three, every one a non-negative number.
    let t = &j["timings_s"];
    let stage = |k: &str| t[k].as_f64().unwrap_or(-1.0);
    for k in ["mesh", "forward_jacobian", "one_step", "setup", "frame"] {
        assert!(stage(k) >= 0.0, "{k}: {t}");
    }
    let sum = stage("mesh") + stage("forward_jacobian") + stage("one_step");
    assert!((stage("setup") - sum).abs() < 1e-9, "{t}");
    assert_eq!(j["protocol"], "adjacent");
    assert_eq!(j["touch_matches"].as_array().map(Vec::len), Some(1), "{j}");
    assert_eq!(j["out"], png.to_str().unwrap());
    // The summary alone: no picture drawn (`out` null), the same regions; without --json (or
    // another output) the picture is asked for.
    let scene = root.join("sim/scenes/disc-ref-x075.toml");
    let args = [
        "reconstruct",
        "--scene",
        scene.to_str().unwrap(),
        "--triangles",
        "3000",
    ];
    let alone = et(&[&args[..], &["--json"]].concat());
    let k: serde_json::Value = serde_json::from_slice(&alone.stdout).unwrap();
    assert!(k["out"].is_null() && k["regions"] == j["regions"], "{k}");
    let refused = et(&args);
    let e = String::from_utf8_lossy(&refused.stderr);
    assert!(!refused.status.success() && e.contains("--out"), "{e}");
    // Without --json the touch is said; on the untouched sheet, that there is none (it listed
    // the noise's regions and said nothing of touches).
    let words = |scene: &str| {
        let untouched = dir.join("untouched.toml");
        std::fs::write(&untouched, scene).unwrap();
        let out = et(&[
            "reconstruct",
            "--scene",
            untouched.to_str().unwrap(),
            "--triangles",
            "3000",
            "--out",
            png.to_str().unwrap(),
            "--force",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let x075 = std::fs::read_to_string(root.join("sim/scenes/disc-ref-x075.toml")).unwrap();
    let touched = words(&x075);
    assert!(
        touched.contains("touch 0: at (") && !touched.contains("no touch"),
        "{touched}"
    );
    let untouched = words(x075.split("[[touch]]").next().unwrap());
    assert!(
        untouched.contains("no touch: no region reaches 5 times its pixels' noise")
            && !untouched.contains("touch 0: at"),
        "{untouched}"
    );
    let bad = et(&[
        "reconstruct",
        "--scene",
        "no-such.toml",
        "--out",
        png.to_str().unwrap(),
        "--force",
    ]);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("no-such.toml"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--method greit` images the touch where it is, at the noise figure asked for, and is one
/// matrix (no --iterations).
#[test]
fn reconstruct_with_greit() {
    let dir = std::env::temp_dir().join(format!("et-cli-greit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let png = dir.join("greit.png");
    let scene = root.join("sim/scenes/disc-ref-x050.toml");
    let args = |extra: &[&str]| {
        let mut a = vec![
            "reconstruct",
            "--scene",
            scene.to_str().unwrap(),
            "--triangles",
            "3000",
            "--method",
            "greit",
            "--out",
            png.to_str().unwrap(),
            "--force",
            "--json",
        ];
        a.extend_from_slice(extra);
        et(&a)
    };
    let out = args(&["--noise-figure", "0.4"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["method"], "greit");
    assert!(
        (j["noise_figure"].as_f64().unwrap() - 0.4).abs() < 1e-3,
        "{j}"
    );
    assert!(j["timings_s"]["one_step"].as_f64().unwrap() >= 0.0, "{j}");
    // The touch (55, 0) mm, radius 13.3 mm.
    let m = &j["touch_matches"][0];
    assert_eq!(m["found"], 0, "{j}");
    let c = &j["found_touches"][0]["centroid_mm"];
    let (x, y) = (c[0].as_f64().unwrap(), c[1].as_f64().unwrap());
    assert!((x - 55.0).hypot(y) < 13.3, "{j}");
    // A fixed alpha is used as given.
    let j: serde_json::Value = serde_json::from_slice(&args(&["--alpha", "0.2"]).stdout).unwrap();
    assert!((j["alpha"].as_f64().unwrap() - 0.2).abs() < 1e-12, "{j}");
    let bad = args(&["--iterations", "3"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--method gn"));
    // The central touch, which adjacent drive sees least: at the calibrated noise both the
    // noise figure's lambda and the one chosen by the frame (--alpha gcv) find it.
    let centre = root.join("sim/scenes/disc-ref-x000.toml");
    let run = |alpha: &str| -> serde_json::Value {
        let out = et(&[
            "reconstruct",
            "--scene",
            centre.to_str().unwrap(),
            "--triangles",
            "3000",
            "--method",
            "greit",
            "--alpha",
            alpha,
            "--out",
            png.to_str().unwrap(),
            "--force",
            "--json",
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    for j in [run("auto"), run("gcv")] {
        let m = &j["touch_matches"][0];
        assert_eq!(m["found"], 0, "{j}");
        assert!(m["pe"].as_f64().unwrap() < 0.1, "{j}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn reconstruct_images_recorded_frames() {
    let dir = std::env::temp_dir().join(format!("et-cli-recon-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16-swipe.toml");
    let rec = dir.join("swipe.jsonl");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    et_ok(&[
        "sim",
        "--scene",
        &s(&scene),
        "--frames",
        "60",
        "--out",
        &s(&rec),
    ]);
    let png = dir.join("f50.png");
    let args = |frame: &str| {
        vec![
            "reconstruct".to_string(),
            "--scene".into(),
            s(&scene),
            "--frames".into(),
            s(&rec),
            "--reference".into(),
            "5".into(),
            "--frame".into(),
            frame.into(),
            "--triangles".into(),
            "3000".into(),
            "--out".into(),
            s(&png),
            "--json".into(),
        ]
    };
    let run = |a: &[String]| et(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let ok = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out
    };
    let out = ok(run(&args("50")));
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    // The strongest region lies on the recorded touch (7 mm finger).
    let t = &j["touches_mm"][0];
    let c = &j["regions"][0]["centroid_mm"];
    let d = (c[0].as_f64().unwrap() - t[0].as_f64().unwrap())
        .hypot(c[1].as_f64().unwrap() - t[1].as_f64().unwrap());
    assert!(d < 10.0, "{j}");
    // A frame inside the reference is refused with a reason.
    let mut a = args("3");
    a.push("--force".into());
    let bad = run(&a);
    assert!(!bad.status.success() && String::from_utf8_lossy(&bad.stderr).contains("reference"));
    // The untouched frames from another recording, --reference-file (it was ignored beside a
    // recording, and refused as a CSV when it was the reference): the recording's first five
    // frames as their own file image frame 50 as --reference 5 does.
    let text = std::fs::read_to_string(&rec).unwrap();
    let untouched = dir.join("untouched.jsonl");
    let lines: Vec<&str> = text.lines().take(6).collect();
    std::fs::write(&untouched, lines.join("\n") + "\n").unwrap();
    let mut a = args("50");
    let at = a.iter().position(|x| x == "--reference").unwrap();
    a.splice(at..at + 2, ["--reference-file".to_string(), s(&untouched)]);
    a.push("--force".into());
    let out = ok(run(&a));
    let k: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(k["regions"], j["regions"]);
    assert_eq!(k["alpha"], j["alpha"]);
    assert!(!String::from_utf8_lossy(&out.stderr).contains("warning"));
    // A reference in mV against frames in V was imaged as a press everywhere, without a word.
    let volts: Vec<serde_json::Value> = lines[1..]
        .iter()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap()["voltages"].clone())
        .collect();
    let mv: String = volts
        .iter()
        .map(|v| {
            let row: Vec<String> = (v.as_array().unwrap().iter())
                .map(|x| format!("{}", x.as_f64().unwrap() * 1e3))
                .collect();
            row.join(",") + "\n"
        })
        .collect();
    let in_mv = dir.join("untouched-mv.csv");
    std::fs::write(&in_mv, mv).unwrap();
    let at = a.iter().position(|x| x == "--reference-file").unwrap();
    a[at + 1] = s(&in_mv);
    let out = run(&a);
    let e = String::from_utf8_lossy(&out.stderr);
    // (About a thousandth: the press in frame 50 moves its values' ratios a little.)
    let scale: Option<f64> =
        (e.split("warning: frame 50 is ").nth(1)).and_then(|r| r.split(' ').next()?.parse().ok());
    assert!(
        scale.is_some_and(|s| (s / 1e-3 - 1.0).abs() < 0.02)
            && e.contains("times the reference V_0")
            && e.contains("in the same units"),
        "{e}"
    );
    // A reference of the other sign (another session's wires the other way round): said as
    // that, not asked for its units.
    let negated: String = (volts.iter())
        .map(|v| {
            let row: Vec<String> = (v.as_array().unwrap().iter())
                .map(|x| format!("{}", -x.as_f64().unwrap()))
                .collect();
            row.join(",") + "\n"
        })
        .collect();
    std::fs::write(&in_mv, negated).unwrap();
    let e = String::from_utf8_lossy(&run(&a).stderr).to_string();
    assert!(
        e.contains("times the reference V_0") && e.contains("the other sign: were the frames'"),
        "{e}"
    );
    // The frames imaged on another sheet of as many electrodes (a 22 cm disc) were imaged
    // without a word on the sheet's outline: said, naming the scene they were made on.
    let mut a = args("50");
    let at = a.iter().position(|x| x == "--scene").unwrap();
    a[at + 1] = s(&root.join("sim/scenes/disc-22cm-16.toml"));
    a.push("--force".into());
    let e = String::from_utf8_lossy(&run(&a).stderr).to_string();
    assert!(
        e.contains("its frames were simulated on")
            && e.contains("a 130 x 130 mm rectangle")
            && e.contains(&format!("image them with --scene {}", s(&scene))),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A structured 13 x 13 cm mesh (16 x 16 cells, each split in two) with 16 one-edge
/// electrodes around the boundary, as Gmsh 2.2 text.
fn square_msh() -> String {
    square_msh_scaled(1.0)
}

/// [`square_msh`] with its coordinates times `scale` (1 000: the same mesh in mm).
fn square_msh_scaled(scale: f64) -> String {
    use std::fmt::Write as _;
    let (n, h) = (16usize, 0.13 / 16.0);
    let id = |i: usize, j: usize| j * (n + 1) + i + 1;
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    let _ = writeln!(s, "{}", (n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let _ = writeln!(
                s,
                "{} {} {} 0",
                id(i, j),
                scale * (-0.065 + i as f64 * h),
                scale * (-0.065 + j as f64 * h)
            );
        }
    }
    // Boundary walk, counter-clockwise from the lower-left corner: 64 edges.
    let mut walk = Vec::new();
    walk.extend((0..n).map(|i| (id(i, 0), id(i + 1, 0))));
    walk.extend((0..n).map(|j| (id(n, j), id(n, j + 1))));
    walk.extend((0..n).map(|i| (id(n - i, n), id(n - i - 1, n))));
    walk.extend((0..n).map(|j| (id(0, n - j), id(0, n - j - 1))));
    let electrodes: Vec<(usize, usize)> = (0..16).map(|e| walk[4 * e + 2]).collect();
    let _ = writeln!(s, "$EndNodes\n$Elements\n{}", 16 + 2 * n * n);
    let mut k = 1;
    for (e, (a, b)) in electrodes.iter().enumerate() {
        let _ = writeln!(s, "{k} 1 2 {} 1 {a} {b}", e + 1);
        k += 1;
    }
    for j in 0..n {
        for i in 0..n {
            let _ = writeln!(
                s,
                "{k} 2 2 1 1 {} {} {}",
                id(i, j),
                id(i + 1, j),
                id(i + 1, j + 1)
            );
            let _ = writeln!(
                s,
                "{} 2 2 1 1 {} {} {}",
                k + 1,
                id(i, j),
                id(i + 1, j + 1),
                id(i, j + 1)
            );
            k += 2;
        }
    }
    s.push_str("$EndElements\n");
    s
}

#[test]
fn forward_and_reconstruct_take_an_imported_mesh() {
    let dir = std::env::temp_dir().join(format!("et-cli-mesh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let msh = dir.join("square.msh");
    std::fs::write(&msh, square_msh()).unwrap();
    let (sc, m) = (scene.to_str().unwrap(), msh.to_str().unwrap());
    let out = et(&["forward", "--scene", sc, "--mesh", m, "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let j: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(j["triangles"], 512);
    let v0 = j["v0"].as_array().unwrap();
    assert_eq!(v0.len(), 208);
    assert!(v0.iter().all(|v| v.as_f64().is_some_and(f64::is_finite)));
    let png = dir.join("r.png");
    let out = et(&[
        "reconstruct",
        "--scene",
        sc,
        "--mesh",
        m,
        "--iterations",
        "2",
        "--alpha",
        "0.3",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Mistakes are explained: wrong electrode count, a list that is not three files.
    let disc = root.join("sim/scenes/square-13cm-8.toml");
    let bad = et(&["forward", "--scene", disc.to_str().unwrap(), "--mesh", m]);
    assert!(String::from_utf8_lossy(&bad.stderr).contains("16 electrodes"));
    // A mesh that is not the scene's sheet: the same mesh in mm, a square mesh for a disc.
    let mm = dir.join("square-mm.msh");
    std::fs::write(&mm, square_msh_scaled(1e3)).unwrap();
    let bad = et(&["forward", "--scene", sc, "--mesh", mm.to_str().unwrap()]);
    let e = String::from_utf8_lossy(&bad.stderr);
    assert!(!bad.status.success() && e.contains("in metres"), "{e}");
    let disc = root.join("sim/scenes/disc-22cm-16.toml");
    let png = dir.join("d.png");
    let bad = et(&[
        "reconstruct",
        "--scene",
        disc.to_str().unwrap(),
        "--mesh",
        m,
        "--out",
        png.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&bad.stderr);
    assert!(
        !bad.status.success() && e.contains("not the sheet's"),
        "{e}"
    );
    let bad = et(&["forward", "--scene", sc, "--mesh", "a.csv,b.csv"]);
    assert!(
        String::from_utf8_lossy(&bad.stderr).contains("nodes.csv,triangles.csv,electrodes.csv")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Outputs never overwrite a command's own input (even with --force), and never an existing
/// file unless --force; a refused command leaves every file as it was.
#[test]
fn outputs_refuse_inputs_and_existing_files_without_force() {
    let dir = std::env::temp_dir().join(format!("et-cli-overwrite-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    std::fs::copy(root.join("sim/scenes/square-13cm-16.toml"), p("s.toml")).unwrap();
    let refused = |args: &[&str], what: &str, file: &str| {
        let before = std::fs::read(file).unwrap();
        let out = et(args);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(
            !out.status.success() && err.contains(what),
            "{args:?}: {err}"
        );
        assert_eq!(std::fs::read(file).unwrap(), before, "{file} untouched");
    };
    let input = "this is the input";
    let exists = "already exists; refusing to overwrite it (--force replaces it)";
    // et sim onto its scene; then onto an earlier recording.
    let sim = ["sim", "--scene", &p("s.toml"), "--frames", "2", "--out"];
    refused(&[&sim[..], &[&p("s.toml")]].concat(), input, &p("s.toml"));
    refused(
        &[&sim[..], &[&p("s.toml"), "--force"]].concat(),
        input,
        &p("s.toml"),
    );
    assert!(et(&[&sim[..], &[&p("r.jsonl")]].concat()).status.success());
    refused(
        &[&sim[..], &[&p("r.jsonl")]].concat(),
        exists,
        &p("r.jsonl"),
    );
    assert!(
        et(&[&sim[..], &[&p("r.jsonl"), "--force"]].concat())
            .status
            .success()
    );
    // '-' (a file named '-' was written, where many tools write standard output), and a
    // folder that takes no new file (said before the work, not when its result is lost:
    // a training's model was lost after the training).
    let dash = et(&[
        "sim",
        "--scene",
        &p("s.toml"),
        "--frames",
        "2",
        "--out",
        "-",
    ]);
    let e = String::from_utf8_lossy(&dash.stderr);
    assert!(
        !dash.status.success() && e.contains("give /dev/stdout"),
        "{e}"
    );
    #[cfg(target_os = "linux")]
    {
        let proc = et(&[
            "sim",
            "--scene",
            &p("s.toml"),
            "--out",
            "/proc/et-out.jsonl",
        ]);
        let e = String::from_utf8_lossy(&proc.stderr);
        assert!(
            !proc.status.success() && e.contains("et cannot create a file in /proc"),
            "{e}"
        );
        // A report folder likewise (it said "/proc/et-report/: No such file or directory").
        let report = et(&["demo", "--out", "/proc/et-report"]);
        let e = String::from_utf8_lossy(&report.stderr);
        assert!(
            !report.status.success() && e.contains("et cannot create a folder in /proc"),
            "{e}"
        );
    }
    // A name whose extension is neither a recording's nor a table's (a recording was
    // written as x.png), and a folder, even forced (it said "--force replaces it").
    let out = et(&[&sim[..], &[&p("x.png")]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains(".jsonl") && err.contains(".npy"),
        "{err}"
    );
    assert!(!dir.join("x.png").exists());
    std::fs::create_dir(dir.join("d.jsonl")).unwrap();
    for force in [&[][..], &["--force"]] {
        let out = et(&[&sim[..], &[&p("d.jsonl")], force].concat());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains("is a folder"),
            "{err}"
        );
    }
    std::fs::remove_dir(dir.join("d.jsonl")).unwrap();
    // A dataset, a model, a blob: none onto its input.
    let collect = [
        "collect",
        "--scene",
        &p("s.toml"),
        "--grid",
        "2x2",
        "--visits",
        "2",
        "--scans",
        "2",
        "--subsections",
        "10",
        "--out",
        &p("d.csv"),
    ];
    let c = et(&collect);
    assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    refused(&collect, exists, &p("d.csv"));
    refused(
        &["train", "--data", &p("d.csv"), "--out", &p("d.csv")],
        input,
        &p("d.csv"),
    );
    let t = et(&["train", "--data", &p("d.csv"), "--out", &p("m.json")]);
    assert!(t.status.success(), "{}", String::from_utf8_lossy(&t.stderr));
    refused(
        &["train", "--data", &p("d.csv"), "--out", &p("m.json")],
        exists,
        &p("m.json"),
    );
    refused(
        &["export", "--model", &p("m.json"), "--out", &p("m.json")],
        input,
        &p("m.json"),
    );
    // No partial files are left beside the outputs.
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.contains("partial")), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Outputs as a class: a command's outputs are checked together against every input named in
/// any flag and against each other; only regular files are replaced; the null device and
/// standard output are written through; Ctrl-C or SIGTERM leaves no hidden partial file; a
/// full device is an error.
#[test]
fn outputs_are_checked_together_and_never_lost_silently() {
    use std::process::Stdio;
    let dir = std::env::temp_dir().join(format!("et-cli-outputs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    std::fs::copy(root.join("sim/scenes/square-13cm-16.toml"), p("s.toml")).unwrap();
    let fails = |args: &[&str], what: &str| {
        let out = et(args);
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(
            !out.status.success() && err.contains(what),
            "{args:?}: {err}"
        );
    };
    // A recording to image, and a mesh given as three files.
    let sim = et(&[
        "sim",
        "--scene",
        &p("s.toml"),
        "--frames",
        "5",
        "--out",
        &p("r.jsonl"),
    ]);
    assert!(
        sim.status.success(),
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );
    for name in ["nodes.csv", "tri.csv", "el.csv"] {
        std::fs::write(p(name), "x").unwrap();
    }
    let mesh = format!("{},{},{}", p("nodes.csv"), p("tri.csv"), p("el.csv"));
    let recon = [
        "reconstruct",
        "--scene",
        &p("s.toml"),
        "--frames",
        &p("r.jsonl"),
        "--reference",
        "2",
        "--frame",
        "4",
    ];
    // An output onto a file named inside --mesh, even with --force: the mesh is untouched.
    fails(
        &[
            &recon[..],
            &["--mesh", &mesh, "--out", &p("tri.csv"), "--force"],
        ]
        .concat(),
        "this is the input",
    );
    assert_eq!(std::fs::read_to_string(p("tri.csv")).unwrap(), "x");
    // Two outputs at one path, spelled differently.
    let same = dir.join(".").join("i.json");
    fails(
        &[
            &recon[..],
            &["--out", &p("i.json"), "--image-out", same.to_str().unwrap()],
        ]
        .concat(),
        "are the same file",
    );
    // Not a regular file: refused by name even with --force; the null device is written.
    std::fs::write(p("other.json"), "keep").unwrap();
    std::os::unix::fs::symlink(p("other.json"), p("link.json")).unwrap();
    fails(
        &[&recon[..], &["--out", &p("link.json"), "--force"]].concat(),
        "is a symbolic link",
    );
    let null = et(&[
        "sim",
        "--scene",
        &p("s.toml"),
        "--frames",
        "2",
        "--out",
        "/dev/null",
    ]);
    assert!(
        null.status.success(),
        "{}",
        String::from_utf8_lossy(&null.stderr)
    );
    fails(
        &[&recon[..], &["--out", &p("nodir/i.json")]].concat(),
        "does not exist",
    );
    // Flags that would have no effect are refused, not ignored.
    let (scene, recording, table) = (p("s.toml"), p("i.jsonl"), p("i.csv"));
    for (out, flag, said) in [
        (
            &recording,
            &["--instrument", "ideal"][..],
            "--instrument ideal sets another system's noise",
        ),
        (
            &table,
            &["--samples"][..],
            "--samples simulates the board's ADC",
        ),
    ] {
        let mut args = vec!["sim", "--scene", &scene, "--frames", "2", "--out", out];
        args.extend(flag);
        let run = et(&args);
        assert!(!run.status.success(), "{args:?}");
        let text = String::from_utf8_lossy(&run.stderr);
        assert!(text.contains(said), "{args:?}: {text}");
    }
    // SIGTERM, or SIGUSR1 (any signal that ends et), in the middle of a long write: no hidden
    // partial file left.
    for (signal, number) in [("TERM", 15), ("USR1", 10)] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_et"))
            .args([
                "sim",
                "--scene",
                &p("s.toml"),
                "--frames",
                "10000000",
                "--out",
                &p("big.jsonl"),
            ])
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let partial_appeared = (0..200).any(|_| {
            std::thread::sleep(std::time::Duration::from_millis(50));
            std::fs::read_dir(&dir)
                .unwrap()
                .any(|e| e.unwrap().file_name().to_string_lossy().contains("partial"))
        });
        assert!(partial_appeared, "et sim writes under a partial name");
        let kill = Command::new("kill")
            .args([format!("-{signal}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(kill.success());
        let status = child.wait().unwrap();
        assert_eq!(status.code(), Some(128 + number), "{signal}: {status:?}");
        let names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(
            !names
                .iter()
                .any(|n| n.contains("partial") || n == "big.jsonl"),
            "{signal}: {names:?}"
        );
    }
    // So does a report folder made part way (`et demo`): it was left, and the next run
    // refused it without --force ("rep already exists").
    let mut child = Command::new(env!("CARGO_BIN_EXE_et"))
        .args(["demo", "--quick", "--out", &p("rep")])
        .stderr(Stdio::null())
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let names = || -> Vec<String> {
        (std::fs::read_dir(&dir).unwrap())
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect()
    };
    let made_aside = (0..200).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(20));
        names().iter().any(|n| n.starts_with(".rep.partial"))
    });
    assert!(made_aside, "et demo makes its report aside: {:?}", names());
    assert!(
        Command::new("kill")
            .args(["-TERM", &child.id().to_string()])
            .status()
            .unwrap()
            .success()
    );
    assert_eq!(child.wait().unwrap().code(), Some(128 + 15));
    let left = names();
    assert!(!left.iter().any(|n| n.contains("rep")), "{left:?}");
    // A closed standard output takes nothing (Rust puts the null device in its place: the
    // result vanished without a word): said, once; one a shell sent to the null device asks
    // for that, unsaid.
    let closed = |args: &str| {
        Command::new("sh")
            .arg("-c")
            .arg(format!("exec \"$0\" {args}"))
            .arg(env!("CARGO_BIN_EXE_et"))
            .output()
            .unwrap()
    };
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../sim/scenes/square-13cm-16.toml")
        .display()
        .to_string();
    // (Told from /proc: Linux only.)
    let on_linux = if cfg!(target_os = "linux") { 2 } else { 0 };
    for args in [
        "protocol --json >&-".to_string(),
        format!("sim --scene {scene} --frames 2 --out /dev/stdout >&-"),
    ]
    .into_iter()
    .take(on_linux)
    {
        let o = closed(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{args}: {e}");
        assert_eq!(
            e.matches("standard output is closed").count(),
            1,
            "{args}: {e}"
        );
    }
    let jsonl = dir.join("closed.jsonl");
    let o = closed(&format!(
        "sim --scene {scene} --frames 2 --out {} >&- 2>&-",
        jsonl.display()
    ));
    assert!(o.status.success(), "{o:?}");
    let text = std::fs::read_to_string(&jsonl).unwrap();
    assert!(
        text.lines().all(|l| l.starts_with('{')),
        "only the recording: {text}"
    );
    let o = closed("protocol --json > /dev/null");
    assert!(o.status.success() && o.stderr.is_empty(), "{o:?}");
    // A full device takes nothing: not a success.
    for args in [&["--help"][..], &["protocol", "--json"][..]] {
        let out = Command::new(env!("CARGO_BIN_EXE_et"))
            .args(args)
            .stdout(std::fs::File::create("/dev/full").unwrap())
            .output()
            .unwrap();
        assert!(!out.status.success(), "{args:?} onto /dev/full");
        assert!(
            String::from_utf8_lossy(&out.stderr).contains("No space left"),
            "{args:?}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every numeric flag has a domain, refused before any work with what the flag takes; an
/// endless input stops at the reader's limit.
#[test]
fn flags_outside_their_domain_and_endless_inputs_are_refused() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let scene = scene.to_str().unwrap();
    let out = std::env::temp_dir().join(format!("et-cli-domains-{}.png", std::process::id()));
    let out = out.to_str().unwrap();
    let recon = ["reconstruct", "--scene", scene, "--out", out];
    let dataset = out.replace(".png", ".csv");
    let collect = ["collect", "--scene", scene, "--out", &dataset];
    let record = ["record", "--port", "/dev/null", "--out", out];
    let cases: Vec<(Vec<&str>, &str)> = vec![
        ([&record[..], &["--seconds=-1"]].concat(), "--seconds"),
        // A negative number written as people write it reaches the flag's domain (clap alone
        // reads "-0.1" as short flags: "unexpected argument '-0'"), and a value is said as
        // given, not as 300 digits.
        (
            [&record[..], &["--seconds", "-1"]].concat(),
            "-1 is not above 0 and at most",
        ),
        (
            [&record[..], &["--seconds", "1e300"]].concat(),
            "'1e300' for '--seconds <SECONDS>': 1e300 is not above 0",
        ),
        (
            [&collect[..], &["--drift", "-0.1"]].concat(),
            "-0.1 is outside 0 to 1",
        ),
        // And in an exponent's form, as currents are written (it was "unexpected argument
        // '-1' found").
        (
            vec!["protocol", "-l", "16", "--csv", "--current-a", "-1.4e-3"],
            "'-1.4e-3' for '--current-a <CURRENT_A>': -1.4e-3 is outside 1e-9 to 0.05",
        ),
        // Below a board's least current, said at the flag (it was "row 0: current 1e-12 A is
        // below 1 nA"), its bounds as written (not 0.000000001).
        (
            vec!["protocol", "--csv", "--current-a", "1e-12"],
            "1e-12 is outside 1e-9 to 0.05",
        ),
        // A row range from the end, as Python indexes: said as et counts rows (it was
        // "unexpected argument '-5' found").
        (
            vec!["train", "--features", out, "--out", out, "--rows", "-5..10"],
            "'-5': rows count from 0 at the first row (not from the end)",
        ),
        (
            [&record[..], &["--seconds", "nan"]].concat(),
            "not a finite number",
        ),
        (
            [&record[..], &["--seconds", "inf"]].concat(),
            "not a finite number",
        ),
        (
            vec!["train", "--features", out, "--out", out, "--folds", "1"],
            "1 is below 2, the least it takes",
        ),
        // Another system's frames: streamed files bounded on disk, a .mat in memory, said
        // before any work with what to write instead.
        (
            vec![
                "sim",
                "--scene",
                scene,
                "--frames",
                "4294967295",
                "--out",
                "/tmp/f.npy",
            ],
            "at most 4807692",
        ),
        (
            vec![
                "sim",
                "--scene",
                scene,
                "--frames",
                "300000",
                "--out",
                "/tmp/f.mat",
            ],
            "a .npy or .csv",
        ),
        (
            vec![
                "train",
                "--features",
                out,
                "--out",
                out,
                "--folds",
                "1000000",
            ],
            "1000000 is above",
        ),
        // A whole-number flag of any width says the value and the bound, not a parser's
        // words ("invalid digit found in string", "-3 is not in 1..=4294967295").
        (
            vec!["sim", "--scene", scene, "--out", out, "--frames", "-3"],
            "-3 is below 1, the least it takes",
        ),
        (
            vec!["sim", "--scene", scene, "--out", out, "--frames", "1e3"],
            "'1e3' is not a whole number as written: write 1000",
        ),
        (
            [&record[..], &["--frames", "99999999999999999999"]].concat(),
            "99999999999999999999 is above 18446744073709551615",
        ),
        // Python's last frame: said as not counted from the end.
        (
            [&recon[..], &["--frames", "f.csv", "--frame", "-1"]].concat(),
            "-1 is below 0, the least it takes (frames are counted from 0 at the file's first, \
             not from its end: without --frame the last is imaged)",
        ),
        ([&recon[..], &["--threshold", "2"]].concat(), "--threshold"),
        (
            [&recon[..], &["--threshold", "nan"]].concat(),
            "--threshold",
        ),
        ([&recon[..], &["--triangles", "0"]].concat(), "--triangles"),
        (
            [&recon[..], &["--triangles", "1000000000"]].concat(),
            "--triangles",
        ),
        (
            [&recon[..], &["--iterations", "0"]].concat(),
            "--iterations",
        ),
        ([&recon[..], &["--reference", "0"]].concat(), "--reference"),
        (
            [&recon[..], &["--radius-mm", "1e9"]].concat(),
            "--radius-mm",
        ),
        (
            [&collect[..], &["--radius-mm", "0"]].concat(),
            "--radius-mm",
        ),
        ([&collect[..], &["--max-kpa", "inf"]].concat(), "--max-kpa"),
        ([&collect[..], &["--poses", "0"]].concat(), "--poses"),
        ([&collect[..], &["--poses", "1000000"]].concat(), "--poses"),
        (
            [&collect[..], &["--press-movement-mm", "nan"]].concat(),
            "--press-movement-mm",
        ),
        (
            [&collect[..], &["--grid", "100000x100000"]].concat(),
            "at most 100 rows",
        ),
        // One class: a dataset no classifier can be trained on (also written as people
        // write grids: the same error, not "write ROWSxCOLS").
        ([&collect[..], &["--grid", "1x1"]].concat(), "one class"),
        ([&collect[..], &["--grid", " 1 X 1"]].concat(), "one class"),
        // No row: said as that (it was "write ROWSxCOLS", as if written wrongly).
        (
            [&collect[..], &["--grid", "0x3"]].concat(),
            "--grid '0x3': a grid of no cells; at least 1 row and 1 column",
        ),
        (
            vec!["reconstruct", "--scene", "/dev/zero", "--out", out],
            "a character device, which never ends",
        ),
    ];
    for (args, what) in cases {
        let o = et(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(what), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
    }
    assert!(!std::path::Path::new(out).exists());
    assert!(!std::path::Path::new(&dataset).exists());

    // Flags that do not apply to the mode, a model used on another scan, two columns of one
    // name: refused, not ignored.
    let dir = std::env::temp_dir().join(format!("et-cli-modes-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let small = [
        "--grid",
        "2x2",
        "--visits",
        "2",
        "--scans",
        "2",
        "--subsections",
        "10",
    ];
    let eight = root.join("sim/scenes/square-13cm-8.toml");
    for (s, d) in [(scene, "d.csv"), (eight.to_str().unwrap(), "d8.csv")] {
        let c = et(&[&["collect", "--scene", s, "--out", &p(d)][..], &small[..]].concat());
        assert!(c.status.success(), "{}", String::from_utf8_lossy(&c.stderr));
    }
    let t = et(&["train", "--data", &p("d.csv"), "--out", &p("m.json")]);
    assert!(t.status.success(), "{}", String::from_utf8_lossy(&t.stderr));
    std::fs::write(p("F.csv"), "x,a,X\n1,2,3\n4,5,6\n7,8,9\n").unwrap();
    // pandas' `to_csv` with its row index: an unnamed first column.
    std::fs::write(p("I.csv"), ",a,b,label\n0,1,2,0\n1,4,5,1\n2,7,8,0\n").unwrap();
    // One method's flags beside the other method (the GREIT flags under Gauss-Newton, the
    // NOSER exponent under GREIT, a noise figure beside an alpha that overrides it).
    let image = |extra: &[&str]| -> Vec<String> {
        let base = [
            "reconstruct",
            "--scene",
            scene,
            "--triangles",
            "300",
            "--out",
        ];
        base.iter()
            .map(|a| (*a).to_string())
            .chain([p("m.png")])
            .chain(extra.iter().map(|a| (*a).to_string()))
            .collect()
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        (image(&["--noise-figure", "0.3"]), "are GREIT's"),
        (image(&["--radius-mm", "5"]), "are GREIT's"),
        (
            image(&["--method", "greit", "--s", "0.2"]),
            "GREIT has no prior",
        ),
        (
            image(&[
                "--method",
                "greit",
                "--alpha",
                "0.1",
                "--noise-figure",
                "0.3",
            ]),
            "under --alpha auto",
        ),
        (
            vec![
                "train".into(),
                "--data".into(),
                p("d.csv"),
                "--rows".into(),
                "0..10".into(),
                "--out".into(),
                p("n.json"),
            ],
            "--rows applies to any sensor's table",
        ),
        (
            vec![
                "train".into(),
                "--data".into(),
                p("d.csv"),
                "--per-group".into(),
                "--out".into(),
                p("n.json"),
            ],
            "--per-group apply to any sensor's table",
        ),
        // A dataset's training is estimated and held to the budget as a table's is (a 100 x
        // 100 grid trained for minutes without a word).
        (
            vec![
                "train".into(),
                "--data".into(),
                p("d.csv"),
                "--max-minutes".into(),
                "1e-6".into(),
                "--out".into(),
                p("n.json"),
            ],
            "past the budget of 6.0e-5 s: fewer classes (et collect --grid)",
        ),
        (
            vec![
                "eval".into(),
                "--model".into(),
                p("m.json"),
                "--data".into(),
                p("d.csv"),
                "--unit".into(),
                "m".into(),
            ],
            "--unit applies",
        ),
        (
            vec![
                "eval".into(),
                "--model".into(),
                p("m.json"),
                "--data".into(),
                p("d.csv"),
                "--predictions".into(),
                p("p.csv"),
            ],
            "--predictions writes",
        ),
        (
            vec![
                "eval".into(),
                "--model".into(),
                p("m.json"),
                "--data".into(),
                p("d8.csv"),
            ],
            "trained on a scan of L = 16",
        ),
        (
            vec![
                "train".into(),
                "--features".into(),
                p("F.csv"),
                "--out".into(),
                p("n.json"),
            ],
            "both named",
        ),
        (
            vec![
                "train".into(),
                "--features".into(),
                p("I.csv"),
                "--out".into(),
                p("n.json"),
            ],
            "I.csv:1: column 1 of the header has no name (pandas' row index or R's row names?",
        ),
        (
            vec![
                "reconstruct".into(),
                "--scene".into(),
                scene.into(),
                "--frame".into(),
                "3".into(),
                "--out".into(),
                p("i.png"),
            ],
            "--frames",
        ),
    ];
    for (args, what) in cases {
        let o = et(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(what), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Rust's debug text in a message (`ImageError(IoError(Os { code: 2, .. }))`,
/// `NonPositivePivot { index: 1161 }`, `Some(..)`): a CamelCase name, or a name right before a
/// bracket or brace.
fn debug_text(message: &str) -> Option<String> {
    // Paths are the user's (a fresh clone's random folder may read as CamelCase): not words.
    let unpathed: Vec<&str> = message
        .split_whitespace()
        .filter(|w| !w.contains('/'))
        .collect();
    let unpathed = unpathed.join(" ");
    let words = unpathed.split(|c: char| !c.is_ascii_alphanumeric() && c != '_');
    let camel = |w: &&str| {
        let mut chars = w.chars();
        chars.next().is_some_and(|c| c.is_ascii_uppercase())
            && w.chars().any(|c| c.is_ascii_lowercase())
            && w.chars().skip(1).any(|c| c.is_ascii_uppercase())
    };
    if let Some(w) = words.clone().find(camel) {
        return Some(w.to_string());
    }
    [
        "Os {", "Some(", "None)", "Err(", "Ok(", "\\\"", " { ", "(\"",
    ]
    .iter()
    .find(|p| message.contains(**p))
    .map(|p| (*p).to_string())
}

/// Messages in words, for the causes that used to reach users as Rust's debug text or with
/// advice that did not fit (each case fails in its own way; none may print debug text, and
/// each says what is wrong in the user's terms). And a plot written to a stream (it used to
/// fail: the image format came from the file name).
#[test]
fn messages_say_the_cause_in_words() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let scene = scene.to_str().unwrap();
    let dir = std::env::temp_dir().join(format!("et-cli-words-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    // A dataset whose header reads one frame value twice.
    let dataset = "# et-dataset 1
# config: {\"electrodes\":8,\"protocol\":\"Adjacent\",\"samples_per_step\":200,\"settle_samples\":40,\"current_na\":32000,\"sample_rate_hz\":10000,\"gain\":1}
# feature_index: 0 3 3
# centres_mm: 0 0; 10 10
# untouched: 0.1 0.2 0.3
label,x_mm,y_mm,visit,v0,v3,v3b
0,0.5,-0.2,0,0.11,0.2,0.3
1,9.5,10.2,0,0.1,0.22,0.3
0,0.1,0.3,0,0.12,0.2,0.29
1,10.1,9.9,0,0.1,0.21,0.33
";
    std::fs::write(p("twice.csv"), dataset).unwrap();
    std::fs::write(p("f-units.csv"), "a,b\n1,2\n3,4\n5,6\n7,8\n").unwrap();
    std::fs::write(p("t-units.csv"), "x_mm,y_mm\n1,2\n3,4\n5,6\n7,8\n").unwrap();
    let ridge = root.join("host/learn/tests/data/table-model-v1/ridge.json");
    let refine = |r: &str| -> Vec<String> {
        ["reconstruct", "--scene", scene, "--refine", r, "--out"]
            .map(String::from)
            .into_iter()
            .chain([p("r.png")])
            .collect()
    };
    let cases: Vec<(Vec<String>, &str)> = vec![
        // New rows without targets, given to eval: what it is for and where they are
        // predicted (it asked only to "add a 'label' column").
        (
            ["eval", "--model", ridge.to_str().unwrap(), "--features"]
                .map(String::from)
                .into_iter()
                .chain([p("f-units.csv")])
                .collect(),
            "no target: add a 'label' column or 'x' and 'y' columns (et eval scores a model \
             against the rows' own targets; rows without them are predicted by Python's \
             model.predict, or live by et stream)",
        ),
        // --unit beside columns that name theirs (x_mm) would be two readings of one value.
        (
            [
                "train",
                "--features",
                &p("f-units.csv"),
                "--targets",
                &p("t-units.csv"),
            ]
            .into_iter()
            .chain(["--unit", "m", "--out", &p("m.json")])
            .map(String::from)
            .collect(),
            "--unit m: the position columns name their unit, mm (x_mm): drop --unit",
        ),
        (
            vec![
                "train".into(),
                "--data".into(),
                p("twice.csv"),
                "--out".into(),
                p("m.json"),
            ],
            "each frame value once",
        ),
        (refine("500,500,10"), "does not meet the sheet"),
        // Edges no finer than the mesh's own refine nothing (it was taken without a word).
        (refine("0,0,1000"), "it refines nothing"),
        // A radius of 0 in the flag's mm (it was said in m, "radius 0 m, edge 0 m").
        (
            refine("0,0,0"),
            "--refine '0,0,0': a finite centre X,Y and a radius R above 0, in mm",
        ),
        (
            [
                "reconstruct",
                "--scene",
                scene,
                "--method",
                "greit",
                "--radius-mm",
                "90",
                "--out",
            ]
            .map(String::from)
            .into_iter()
            .chain([p("g.png")])
            .collect(),
            "at most half",
        ),
        (
            ["collect", "--scene", scene, "--radius-mm", "60", "--out"]
                .map(String::from)
                .into_iter()
                .chain([p("c.csv")])
                .collect(),
            "sheet 130.0 mm across",
        ),
        (
            ["collect", "--scene", scene, "--radius-mm", "1", "--out"]
                .map(String::from)
                .into_iter()
                .chain([p("c.csv")])
                .collect(),
            "under half the simulated sheet's grid spacing (2.5 mm)",
        ),
    ];
    for (args, what) in cases {
        let o = et(&args.iter().map(String::as_str).collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(what), "{args:?}: {err}");
        assert_eq!(debug_text(&err), None, "{args:?}: {err}");
        assert!(!err.contains("mesh: mesh:"), "{args:?}: {err}");
    }
    // The checker itself finds what it is for.
    for debug in [
        "ImageError(IoError(Os { code: 2 }))",
        "Numeric(NonPositivePivot { index: 1161 })",
        "x: Some(3)",
    ] {
        assert!(debug_text(debug).is_some(), "{debug}");
    }
    // ... and not a path's folder: a fresh clone's random /tmp/fresh-ci.GiUHsn failed it.
    assert_eq!(
        debug_text("error: /tmp/fresh-ci.GiUHsn/s.toml: no such file"),
        None
    );
    // An image to a stream: PNG bytes, whatever the name.
    let o = et(&["reconstruct", "--scene", scene, "--out", "/dev/stdout"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(o.stdout.starts_with(b"\x89PNG"), "{} bytes", o.stdout.len());
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reader that stops early (`et protocol --json | head`) ends et quietly: it used to panic
/// ("failed printing to stdout: Broken pipe"). So does an output file given as `/dev/stdout`
/// (`et sim --out /dev/stdout | head`, a model, an image): it ended "error: writing
/// /dev/stdout: Broken pipe", exit 1.
#[test]
fn a_closed_pipe_ends_et_quietly() {
    use std::process::Stdio;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let scene = root.join("sim/scenes/square-13cm-16.toml");
    let scene = scene.to_str().unwrap();
    let dir = std::env::temp_dir().join(format!("et-cli-pipe-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (f, t) = (dir.join("F.csv"), dir.join("T.csv"));
    et_learn::standin::make(60, 3, 5)
        .unwrap()
        .write_all(&f, &t, None)
        .unwrap();
    let (f, t) = (f.to_str().unwrap(), t.to_str().unwrap());
    let stdout = "/dev/stdout";
    // et run with its standard output's reader gone from the start.
    let reader_gone = |args: &[&str]| {
        let mut child = Command::new(env!("CARGO_BIN_EXE_et"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        drop(child.stdout.take());
        child.wait_with_output().unwrap()
    };
    for args in [
        // 105 kB of JSON: more than a pipe holds, so et is still writing when the reader goes.
        &["protocol", "-l", "32", "-p", "pp-pp", "--json"][..],
        &["sim", "--scene", scene, "--frames", "50", "--out", stdout],
        &["reconstruct", "--scene", scene, "--out", stdout],
        &[
            "collect", "--scene", scene, "--grid", "3x3", "--out", stdout,
        ],
        &[
            "train",
            "--features",
            f,
            "--targets",
            t,
            "--kind",
            "ridge",
            "--out",
            stdout,
        ],
    ] {
        let out = reader_gone(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            out.status.success() && !err.contains("panicked") && !err.contains("error:"),
            "{args:?}: {err}"
        );
    }
    // A command with files still to write goes on without its reader and writes them, said
    // (`et reconstruct --all ... | head -1` ended at its first line, exit 0, without them).
    let name = |file: &str| dir.join(file).to_str().unwrap().to_string();
    let (frames, last, stack) = (name("frames.csv"), name("last.png"), name("stack.npy"));
    let made = et(&["sim", "--scene", scene, "--frames", "12", "--out", &frames]);
    assert!(made.status.success());
    let out = reader_gone(&[
        "reconstruct",
        "--scene",
        scene,
        "--frames",
        &frames,
        "--reference",
        "2",
        "--all",
        "--out",
        &last,
        "--image-out",
        &stack,
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    assert!(err.contains("standard output's reader went away"), "{err}");
    let written = |p: &str| std::path::Path::new(p).is_file();
    assert!(written(&last) && written(&stack), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Another lab's e-skin data through the whole CLI path: the stand-in written as that lab
/// writes it (byte-order mark, no header, CRLF, targets x, y, z in metres in a second file),
/// trained on the first rows and evaluated on the later ones with every kind, and its
/// mistakes explained.
#[test]
fn any_sensors_table_trains_and_evaluates_through_the_cli() {
    let dir = std::env::temp_dir().join(format!("et-cli-table-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (f, t) = (dir.join("F.csv"), dir.join("T.csv"));
    let sessions = dir.join("sessions.csv");
    let (pressed, before) = (dir.join("pressed.csv"), dir.join("before.csv"));
    let standin = et_learn::standin::make(300, 3, 5).unwrap();
    standin.write_all(&f, &t, Some(&sessions)).unwrap();
    standin.write_frames(&pressed, &before).unwrap();
    let ok = |o: std::process::Output| {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    let json = |o: std::process::Output| -> serde_json::Value {
        serde_json::from_slice(&o.stdout).expect("JSON on stdout")
    };
    let table = [
        "--features".to_string(),
        s(&f),
        "--targets".into(),
        s(&t),
        "--unit".into(),
        "m".into(),
    ];
    let train = |extra: &[&str], out: &str| {
        let mut a: Vec<String> = vec!["train".into()];
        a.extend(table.iter().cloned());
        a.extend(["--rows", "0..240", "--folds", "3", "--json", "--out", out].map(String::from));
        a.extend(extra.iter().map(|x| x.to_string()));
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        et(&refs)
    };
    let eval = |model: &str, extra: &[&str]| {
        let mut a: Vec<String> = vec!["eval".into(), "--model".into(), model.into()];
        a.extend(table.iter().cloned());
        a.extend(["--rows", "240..300", "--json"].map(String::from));
        a.extend(extra.iter().map(|x| x.to_string()));
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        et(&refs)
    };
    // Auto: tries the regressors, says which won, and the model evaluates on later rows.
    let auto = s(&dir.join("auto.json"));
    let tr = json(ok(train(&["--kind", "auto"], &auto)));
    let method = tr["method"].as_str().unwrap().to_string();
    assert!(
        ["ridge", "knn", "kernel-ridge", "gp", "mlp", "average"].contains(&method.as_str()),
        "{tr}"
    );
    assert_eq!(tr["rows"], serde_json::json!([0, 240]));
    assert_eq!(tr["features"], 192);
    assert!(tr["cv_mean_error_mm"].as_f64().unwrap() > 0.0);
    assert!(!tr["hyperparameters"].as_object().unwrap().is_empty());
    // Printed to 4 significant digits (the model file keeps them all).
    for (k, v) in tr["hyperparameters"].as_object().unwrap() {
        let digits: String = format!("{:e}", v.as_f64().unwrap())
            .split('e')
            .next()
            .unwrap()
            .chars()
            .filter(char::is_ascii_digit)
            .collect();
        assert!(digits.len() <= 4, "{k} = {v}");
    }
    let plots = dir.join("plots");
    let ev = json(ok(eval(&auto, &["--plots", &s(&plots)])));
    for key in [
        "mean_error_mm",
        "median_error_mm",
        "p90_error_mm",
        "fit_seconds",
        "predict_seconds",
    ] {
        assert!(ev[key].as_f64().is_some(), "{key}: {ev}");
    }
    assert_eq!(ev["observations"], 60);
    assert!(
        ev["mean_error_mm"].as_f64().unwrap() < ev["mean_predictor_error_mm"].as_f64().unwrap()
    );
    for png in ["error-map.png", "predicted-vs-true.png"] {
        assert!(
            std::fs::metadata(plots.join(png)).unwrap().len() > 1000,
            "{png}"
        );
    }
    // Every row's prediction as CSV: the error recomputed from it and the targets file (BOM,
    // no header, metres) is the one reported.
    let pred = dir.join("pred.csv");
    let ev = json(ok(eval(&auto, &["--predictions", &s(&pred)])));
    let text = std::fs::read_to_string(&pred).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("row,x_mm,y_mm,z_mm"), "{text}");
    let truth: Vec<Vec<f64>> = std::fs::read_to_string(&t)
        .unwrap()
        .trim_start_matches('\u{feff}')
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split(',').map(|v| v.trim().parse().unwrap()).collect())
        .collect();
    let mut sum = 0.0;
    for (i, line) in lines.enumerate() {
        let v: Vec<f64> = line.split(',').map(|v| v.parse().unwrap()).collect();
        assert_eq!(v[0] as usize, 240 + i, "rows numbered as in the file");
        let r = &truth[240 + i];
        sum += (v[1] - 1e3 * r[0]).hypot(v[2] - 1e3 * r[1]);
    }
    let mean = sum / 60.0;
    let reported = ev["mean_error_mm"].as_f64().unwrap();
    assert!((mean - reported).abs() < 1e-3, "{mean} vs {reported}");
    // Standard error onto a full device: its messages are dropped, the work and the model
    // are not (a panic on the first message lost the model).
    let quiet = dir.join("quiet.json");
    let mut a: Vec<String> = vec!["train".into()];
    a.extend(table.iter().cloned());
    a.extend(["--rows", "0..240", "--kind", "ridge", "--out", &s(&quiet)].map(String::from));
    let full = Command::new(env!("CARGO_BIN_EXE_et"))
        .args(&a)
        .stderr(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert!(full.status.success(), "{:?}", full.status);
    assert!(quiet.is_file(), "the model written");
    // Every kind.
    for (kind, extra) in [
        ("ridge", vec![]),
        ("knn", vec![]),
        ("kernel-ridge", vec![]),
        ("gp", vec![]),
        ("mlp", vec![]),
        ("lda", vec!["--grid", "3x3"]),
        ("qda", vec!["--grid", "3x3", "--cv", "blocks"]),
    ] {
        let out = s(&dir.join(format!("{kind}.json")));
        let mut args = vec!["--kind", kind];
        args.extend(extra);
        let tr = json(ok(train(&args, &out)));
        assert_eq!(tr["method"], kind, "{tr}");
        let ev = json(ok(eval(&out, &[])));
        assert!(ev["mean_error_mm"].as_f64().is_some(), "{kind}: {ev}");
        if kind == "lda" || kind == "qda" {
            assert_eq!(tr["classes"], 9);
            assert!(ev["accuracy"].as_f64().is_some(), "{ev}");
            ok(eval(&out, &["--predictions", &s(&pred), "--force"]));
            let text = std::fs::read_to_string(&pred).unwrap();
            assert!(
                text.starts_with("row,class,x_mm,y_mm,z_mm\n240,r"),
                "{text}"
            );
        }
    }
    // Sessions: with --groups cross-validation leaves each session out in turn, and the
    // evaluation scores each session of its rows.
    let grouped = s(&dir.join("grouped.json"));
    let tr = json(ok(train(
        &["--kind", "knn", "--groups", &s(&sessions)],
        &grouped,
    )));
    assert_eq!(tr["cv_scheme"], "groups", "{tr}");
    let train_sessions = std::fs::read_to_string(&sessions)
        .unwrap()
        .lines()
        .take(240)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    assert_eq!(tr["cv_folds"], train_sessions, "{tr}");
    let ev = json(ok(eval(&grouped, &["--groups", &s(&sessions)])));
    let per_group = ev["per_group"].as_array().unwrap();
    let counted: u64 = per_group
        .iter()
        .map(|g| g["observations"].as_u64().unwrap())
        .sum();
    assert_eq!(counted, 60, "{ev}");
    assert!(
        per_group
            .iter()
            .all(|g| g["group"].as_str().unwrap().starts_with("session-"))
    );
    // Each session standardised by its own statistics: remembered, and done again to the
    // evaluated rows.
    let own = s(&dir.join("own.json"));
    ok(train(
        &["--kind", "ridge", "--groups", &s(&sessions), "--per-group"],
        &own,
    ));
    let model: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&own).unwrap()).unwrap();
    assert_eq!(model["per_group"], true);
    assert!(json(ok(eval(&own, &["--groups", &s(&sessions)])))["mean_error_mm"].is_number());
    // Pressed frames referenced to the frame before each press: pressed - before is the
    // features file itself, so the difference trains the same model.
    let with_reference = |extra: &[&str], out: &str| {
        let mut a: Vec<String> = ["train", "--features", &s(&pressed), "--targets", &s(&t)]
            .map(String::from)
            .to_vec();
        a.extend(
            [
                "--unit",
                "m",
                "--rows",
                "0..240",
                "--folds",
                "3",
                "--kind",
                "ridge",
                "--json",
                "--out",
                out,
                "--reference-features",
                &s(&before),
            ]
            .map(String::from),
        );
        a.extend(extra.iter().map(|x| x.to_string()));
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        et(&refs)
    };
    let plain = json(ok(train(&["--kind", "ridge"], &s(&dir.join("plain.json")))));
    let differenced = s(&dir.join("difference.json"));
    let diff = json(ok(with_reference(
        &["--reference-as", "difference"],
        &differenced,
    )));
    let (a, b) = (
        plain["cv_mean_error_mm"].as_f64().unwrap(),
        diff["cv_mean_error_mm"].as_f64().unwrap(),
    );
    assert!((a - b).abs() < 1e-3 * a, "{a} against {b}");
    ok(with_reference(&[], &s(&dir.join("ratio.json"))));
    // The evaluation needs the same references, and says so.
    let mut a: Vec<String> = ["eval", "--model", &differenced, "--features", &s(&pressed)]
        .map(String::from)
        .to_vec();
    a.extend(["--targets", &s(&t), "--unit", "m", "--rows", "240..300"].map(String::from));
    let refs: Vec<&str> = a.iter().map(String::as_str).collect();
    let o = et(&refs);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--reference-features"), "{e}");
    // Groups and a chosen fold scheme contradict each other.
    let e = train(&["--groups", &s(&sessions), "--cv", "blocks"], &grouped);
    assert!(!e.status.success());
    // Mistakes are explained.
    let err = |o: std::process::Output| {
        assert!(!o.status.success());
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    let e = err(et(&[
        "train",
        "--groups",
        "no-such-column",
        "--features",
        &s(&f),
        "--targets",
        &s(&t),
        "--out",
        &s(&dir.join("x.json")),
    ]));
    assert!(
        e.contains("no-such-column") && e.contains("no header row"),
        "{e}"
    );
    let e = err(et(&[
        "train",
        "--features",
        "87",
        "--out",
        &s(&dir.join("x.json")),
    ]));
    assert!(e.contains("--keep"), "{e}");
    std::fs::write(dir.join("short.csv"), "0.1,0.2\n").unwrap();
    let e = err(et(&[
        "train",
        "--features",
        &s(&f),
        "--targets",
        &s(&dir.join("short.csv")),
        "--out",
        &s(&dir.join("x.json")),
    ]));
    assert!(e.contains("short.csv") && e.contains("1 rows"), "{e}");
    let e = err(train(&["--kind", "qda"], &s(&dir.join("x.json"))));
    assert!(e.contains("--grid"), "{e}");
    let e = err(et(&["eval", "--model", &auto, "--data", &s(&f)]));
    assert!(e.contains("--features"), "{e}");
    let text = std::fs::read_to_string(&f).unwrap();
    let mut lines: Vec<String> = text.split("\r\n").map(String::from).collect();
    let mut cells: Vec<String> = lines[0].split(',').map(String::from).collect();
    cells[3] = "NaN".into();
    lines[0] = cells.join(",");
    std::fs::write(dir.join("nan.csv"), lines.join("\r\n")).unwrap();
    let e = err(et(&[
        "train",
        "--features",
        &s(&dir.join("nan.csv")),
        "--targets",
        &s(&t),
        "--out",
        &s(&dir.join("x.json")),
    ]));
    assert!(
        e.contains("nan.csv:1, column 4") && e.contains("finite"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--force` (replace outputs that exist) is refused by the commands that write no file, as
/// other flags that change nothing are, rather than accepted and ignored; the commands that
/// write take it.
#[test]
fn force_is_refused_where_nothing_is_written() {
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes/disc-ref-x050.toml");
    let scene = scene.to_str().unwrap();
    assert!(et(&["forward", "--scene", scene]).status.success());
    for args in [
        &["protocol", "--force"][..],
        &["forward", "--scene", scene, "--force"],
        &["ports", "--force"],
    ] {
        let out = et(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(
            err.contains(&format!("--force: et {} writes no file", args[0])),
            "{args:?}: {err}"
        );
    }
    let out = et(&["protocol"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A rate without a port, and the simulator's pace beside a recording or a board, change
    // nothing: refused (`--baud 9600 --replay r.jsonl` streamed as if unsaid), and no rate of 0.
    for (args, said) in [
        (&["stream", "--json", "--baud", "9600"][..], "--port"),
        (
            &["stream", "--json", "--fast", "--replay", "r.jsonl"],
            "--replay",
        ),
        (
            &["stream", "--json", "--fast", "--port", "/dev/null"],
            "--port",
        ),
        (
            &["stream", "--json", "--port", "/dev/null", "--baud", "0"],
            "0",
        ),
    ] {
        let out = et(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(said),
            "{args:?}: {err}"
        );
    }
}

/// A file of another kind where et reads one of its own is said as what it is, with the fix
/// for that reader: a scene given as a .npy is not told to write a table with numpy.savetxt,
/// frames given as the board's blob are not said as Latin-1 text, and the model file given to
/// `et upload` is told to be exported first.
#[test]
fn a_file_of_another_kind_is_said_as_what_it_is() {
    let dir = std::env::temp_dir().join(format!("et-cli-kinds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let npy = dir.join("a.npy");
    std::fs::write(&npy, b"\x93NUMPY\x01\x00v\x00{'descr': '<f8'}").unwrap();
    let blob = dir.join("m.etm");
    std::fs::write(&blob, b"ETDA\x01\x00\x00\x00\x09\x00\x60\x00\xc0\x00").unwrap();
    let json = dir.join("m.json");
    std::fs::write(&json, "{\"format\": \"et-model\"}").unwrap();
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes/disc-ref-x050.toml");
    let out = dir.join("n.json");
    let [npy, blob, json, scene, out] =
        [&npy, &blob, &json, &scene, &out].map(|p| p.to_str().unwrap());
    for (args, said) in [
        (
            &["forward", "--scene", npy][..],
            "a NumPy .npy array, not text: a file of another kind given?",
        ),
        (
            &[
                "reconstruct",
                "--scene",
                scene,
                "--frames",
                blob,
                "--reference",
                "1",
                "--out",
                "/dev/null",
            ],
            "a model blob for the board",
        ),
        (
            &["upload", "--port", "/dev/null", "--blob", json],
            "et export --model",
        ),
        (
            &["train", "--data", npy, "--out", out],
            "a NumPy .npy array, not text: a file of another kind given?",
        ),
    ] {
        let out = et(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(said) && !err.contains("savetxt"),
            "{args:?}: {err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A board that never answers is said with the port and the rate it was asked at, and a rate
/// other than the firmware's is named as the likely cause.
#[test]
fn a_board_that_never_answers_is_said_with_its_rate() {
    use serialport::{SerialPort as _, TTYPort};
    let (_master, slave) = TTYPort::pair().unwrap();
    let port = slave.name().unwrap();
    let out = std::env::temp_dir().join(format!("et-cli-silent-{}.jsonl", std::process::id()));
    let out = out.to_str().unwrap();
    let o = et(&[
        "record", "--port", &port, "--baud", "9600", "--frames", "1", "--out", out,
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{o:?}");
    assert!(
        stderr.contains(&format!("no answer from the board on {port} at 9600 baud"))
            && stderr.contains(&format!(
                "et's firmware talks at {} baud: leave out --baud",
                et_core::board::BAUD
            )),
        "{stderr}"
    );
    assert!(
        !std::path::Path::new(out).exists(),
        "no recording of nothing"
    );
    // At the firmware's rate, what else to check; `et stream` says it as `et record` does.
    let o = et(&["stream", "--json", "--port", &port]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{o:?}");
    assert!(
        stderr.contains(&format!(
            "no answer from the board on {port} at {} baud",
            et_core::board::BAUD
        )) && stderr.contains("is this its port?"),
        "{stderr}"
    );
}

/// An electrode whose contact opens now and then (the simulator's intermittent fault, open
/// one step in 20) under a press: `et stream` names it once V_0 is taken and says how to
/// leave it out; its values moved the press's events (most touched frames gave none, the rest
/// tens of mm off) until `--skip-electrodes 3` leaves them out of the images, when each
/// touched frame gives its press within 5 mm. Electrodes past the sheet, or more than half of
/// them, are refused by the flag's name. An electrode that comes off after V_0 is named once,
/// in the first frame it is off in; put back, it is said back once it fits the model 10 frames
/// in a row, and off again when it comes off again; one off while V_0 was taken is said back
/// with V_0 to take again.
#[test]
fn an_electrode_left_out_live_streams_the_presses_it_hid() {
    let dir = std::env::temp_dir().join(format!("et-cli-live-skip-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sound = std::fs::read_to_string(root.join("sim/scenes/square-13cm-16.toml")).unwrap();
    // The press from 0.5 s (frame 40 of 12.8 ms each), after the 20 reference frames.
    let text = sound.replace("start = 0.05", "start = 0.5")
        + "\n[[fault]]\nelectrode = 3\nkind = \"intermittent\"\nprobability = 0.05\n";
    let (scene, rec) = (dir.join("scene.toml"), dir.join("r.jsonl"));
    std::fs::write(&scene, text).unwrap();
    let (scene, rec) = (scene.to_str().unwrap(), rec.to_str().unwrap());
    et_ok(&["sim", "--scene", scene, "--frames", "80", "--out", rec]);
    // Each touched frame's press, by sequence number (m).
    let pressed: std::collections::HashMap<u64, [f64; 2]> = std::fs::read_to_string(rec)
        .unwrap()
        .lines()
        .skip(1)
        .filter_map(|l| {
            let v: serde_json::Value = serde_json::from_str(l).unwrap();
            let p = v["touches"].get(0)?;
            Some((v["seq"].as_u64()?, [p["x"].as_f64()?, p["y"].as_f64()?]))
        })
        .collect();
    assert!(pressed.len() >= 30, "{}", pressed.len());
    let stream = |extra: &[&str]| {
        let mut args = vec!["stream", "--json", "--replay", rec, "--scene", scene];
        args.extend(extra);
        let out = et(&args);
        let said = String::from_utf8_lossy(&out.stderr).into_owned();
        assert!(out.status.success(), "{said}");
        // Touched frames whose event places the press within 5 mm.
        let placed = String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter(|l| {
                let e: serde_json::Value = serde_json::from_str(l).unwrap();
                let at = &e["position_mm"];
                pressed.get(&e["seq"].as_u64().unwrap()).is_some_and(|p| {
                    (at[0].as_f64().unwrap() - 1e3 * p[0])
                        .hypot(at[1].as_f64().unwrap() - 1e3 * p[1])
                        < 5.0
                })
            })
            .count();
        (said, placed)
    };
    let (said, placed) = stream(&[]);
    // (Named in V_0, or in the first frame it is open in.)
    assert!(said.contains("electrode 3's 52 values"), "{said}");
    assert!(
        said.contains("--skip-electrodes 3 leaves its values out"),
        "{said}"
    );
    assert!(2 * placed < pressed.len(), "{placed} of {}", pressed.len());
    // The board's flags (the contact open in a step rails its probe and puts the source in
    // compliance) said once each, and counted at the end.
    for kind in ["samples on an ADC rail", "the current source in compliance"] {
        assert_eq!(said.matches(kind).count(), 1, "{kind}: {said}");
    }
    assert!(said.contains("flagged by the board) in"), "{said}");
    // (Written with a space, as people list them.)
    let (said, placed) = stream(&["--skip-electrodes", "3, 3"]);
    assert!(
        said.contains("note: --skip-electrodes 3: 52 of adjacent's 208 values left out"),
        "{said}"
    );
    assert!(!said.contains("warning: electrode"), "{said}");
    assert!(
        10 * placed >= 9 * pressed.len(),
        "{placed} of {}",
        pressed.len()
    );
    for (skip, refused) in [
        (
            "16",
            "--skip-electrodes: electrode 16: the sheet's electrodes are 0 to 15",
        ),
        (
            "0,1,2,3,4,5,6,7,8",
            "--skip-electrodes: 9 of the 16 electrodes to leave out",
        ),
        // A list with a gap or a word: its place named, not a parser's words.
        ("3,,7", "an empty place in the list"),
        ("3,x", "'x' is not an electrode's number"),
    ] {
        let out = et(&[
            "stream",
            "--replay",
            rec,
            "--scene",
            scene,
            "--skip-electrodes",
            skip,
        ]);
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success() && said.contains(refused), "{said}");
    }
    // Sound while V_0 is taken, electrode 3 off from frame 30 on (the sound sheet's first 30
    // frames, the disconnected one's after them: one seed, one press): named once, at frame 30.
    let recorded = |name: &str, fault: &str| {
        let (scene, rec) = (
            dir.join(format!("{name}.toml")),
            dir.join(format!("{name}.jsonl")),
        );
        let text = sound.replace("start = 0.05", "start = 0.5") + fault;
        std::fs::write(&scene, text).unwrap();
        let (s, r) = (scene.to_str().unwrap(), rec.to_str().unwrap());
        et_ok(&["sim", "--scene", s, "--frames", "80", "--out", r]);
        (scene, std::fs::read_to_string(rec).unwrap())
    };
    let (scene, before) = recorded("sound", "");
    let (_, after) = recorded(
        "off",
        "\n[[fault]]\nelectrode = 3\nkind = \"disconnected\"\n",
    );
    // The sound recording's header, then `runs` of (frames, off or sound) in turn, each from
    // its recording's frames of those numbers; what `et stream` says of them.
    let splice = |name: &str, runs: &[(usize, bool)]| {
        let (sound, off): (Vec<&str>, Vec<&str>) =
            (before.lines().collect(), after.lines().collect());
        let mut lines = vec![sound[0]];
        for &(n, is_off) in runs {
            let from = lines.len();
            lines.extend_from_slice(&(if is_off { &off } else { &sound })[from..from + n]);
        }
        let rec = dir.join(name);
        std::fs::write(&rec, lines.join("\n") + "\n").unwrap();
        let (rec, scene) = (rec.to_str().unwrap(), scene.to_str().unwrap());
        let out = et_ok(&["stream", "--json", "--replay", rec, "--scene", scene]);
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let said = splice("off-later.jsonl", &[(30, false), (50, true)]);
    assert_eq!(said.matches("electrode 3").count(), 1, "{said}");
    assert!(
        said.contains("warning: frame 30: electrode 3's 52 values"),
        "{said}"
    );
    assert!(said.contains("Not in V_0"), "{said}");
    // Put back at frame 50: said back once it fits 10 frames in a row; off again at 65.
    let runs = [(30, false), (20, true), (15, false), (15, true)];
    let said = splice("off-and-back.jsonl", &runs);
    assert!(
        said.contains(
            "note: frame 59: electrode 3's values fit the model again from frame 50 (off since \
             frame 30): it is back"
        ),
        "{said}"
    );
    assert!(
        said.contains(
            "warning: frame 65: electrode 3 is off again (the 2nd time, back at frame 59;"
        ),
        "{said}"
    );
    assert_eq!(said.matches("electrode 3").count(), 3, "{said}");
    // Off while V_0 was taken, back at frame 30: V_0 is to be taken again.
    let said = splice("off-in-v0.jsonl", &[(30, true), (50, false)]);
    assert!(
        said.contains(
            "frame 39: electrode 3's values fit the model again from frame 30, but V_0 was taken \
             while it was off"
        ),
        "{said}"
    );
    let scene = scene.to_str().unwrap();
    // The sound sheet's frames flagged none.
    let sound = dir.join("sound.jsonl");
    let sound = sound.to_str().unwrap();
    let out = et_ok(&["stream", "--json", "--replay", sound, "--scene", scene]);
    let said = String::from_utf8_lossy(&out.stderr);
    assert!(!said.contains("flagged"), "{said}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A recording of the simulated board with electrode 3 disconnected (the simulator's fault:
/// its measurements float to a rail, its injections drive nothing): `et reconstruct` names
/// electrode 3, `--skip-electrodes 3` leaves its 52 values out and is not warned, an electrode
/// the sheet lacks is refused in the scene's numbering. The same board sound names none.
/// A built-in protocol without an electrode keeps its family's threshold.
#[test]
fn a_disconnected_electrode_is_named_and_left_out() {
    let dir = std::env::temp_dir().join(format!("et-cli-disconnected-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let sound = std::fs::read_to_string(root.join("sim/scenes/square-13cm-16.toml")).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    for faulty in [false, true] {
        let mut text = sound.clone();
        if faulty {
            text.push_str("\n[[fault]]\nelectrode = 3\nkind = \"disconnected\"\n");
        }
        let (scene, rec) = (dir.join("scene.toml"), dir.join("r.jsonl"));
        std::fs::write(&scene, text).unwrap();
        et_ok(&[
            "sim",
            "--scene",
            &s(&scene),
            "--frames",
            "8",
            "--force",
            "--out",
            &s(&rec),
        ]);
        let reconstruct = |extra: &[&str]| {
            let (scene, rec, png) = (s(&scene), s(&rec), s(&dir.join("x.png")));
            let mut args = vec!["reconstruct", "--scene", &scene, "--frames", &rec];
            args.extend([
                "--reference",
                "4",
                "--triangles",
                "2000",
                "--force",
                "--out",
                &png,
            ]);
            args.extend(extra);
            let out = et(&args);
            (
                out.status.success(),
                String::from_utf8_lossy(&out.stderr).into_owned(),
            )
        };
        let (ok, said) = reconstruct(&[]);
        assert!(ok, "{said}");
        assert_eq!(
            said.contains("warning: electrode 3's 52 values"),
            faulty,
            "{said}"
        );
        assert_eq!(
            said.contains("--skip-electrodes 3 leaves its values out"),
            faulty,
            "{said}"
        );
        // The board's own flags on the frames used (its open probe floats to a rail, its
        // injections in compliance), said with which frames: every one of them here.
        assert_eq!(
            said.contains(
                "r.jsonl: the board flagged readings with samples on an ADC rail (clipped"
            ),
            faulty,
            "{said}"
        );
        assert_eq!(
            said.contains("in 4 of the 4 reference frames and 1 of the 1 imaged"),
            faulty,
            "{said}"
        );
        if faulty {
            // Its frames as another's untouched reference: said of the reference file.
            let (scene, rec, png) = (s(&scene), s(&rec), s(&dir.join("y.png")));
            let out = et(&[
                "reconstruct",
                "--scene",
                &scene,
                "--frames",
                &rec,
                "--reference-file",
                &rec,
                "--triangles",
                "2000",
                "--force",
                "--out",
                &png,
            ]);
            let said = String::from_utf8_lossy(&out.stderr);
            assert!(
                said.contains("in 8 of the 8 reference frames")
                    && said.contains("(another --reference-file)"),
                "{said}"
            );
            let (ok, said) = reconstruct(&["--skip-electrodes", "3"]);
            assert!(ok, "{said}");
            assert!(
                said.contains("--skip-electrodes 3: 52 of the frame's 208 values left out"),
                "{said}"
            );
            assert!(!said.contains("warning: electrode"), "{said}");
            let (ok, said) = reconstruct(&["--skip-electrodes", "0,1,2,3,4,5,6,7,8"]);
            assert!(
                !ok && said.contains("9 of the 16 electrodes to leave out: at most half (8)"),
                "{said}"
            );
            let (ok, said) = reconstruct(&["--skip-electrodes", "3,16"]);
            assert!(
                !ok && said.contains("--skip-electrodes 16: the scene's electrodes are 0 to 15"),
                "{said}"
            );
        }
    }
    // Pseudo-polar without electrode 3 keeps pseudo-polar's threshold (0.08; a protocol
    // of no family takes 0.10).
    let (scene, rec, png) = (
        dir.join("pp.toml"),
        dir.join("pp.jsonl"),
        dir.join("pp.png"),
    );
    std::fs::write(
        &scene,
        sound.replace("protocol = \"adjacent\"", "protocol = \"pseudo-polar\""),
    )
    .unwrap();
    et_ok(&[
        "sim",
        "--scene",
        &s(&scene),
        "--frames",
        "6",
        "--out",
        &s(&rec),
    ]);
    let out = et_ok(&[
        "reconstruct",
        "--scene",
        &s(&scene),
        "--frames",
        &s(&rec),
        "--reference",
        "3",
        "--triangles",
        "2000",
        "--skip-electrodes",
        "3",
        "--json",
        "--out",
        &s(&png),
    ]);
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(json["threshold"], 0.08, "{json}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A table of class labels alone, trained without --groups: the note says what holds for
/// classes (it spoke of positions chosen on two figures, which labels do not have).
#[test]
fn a_table_of_labels_alone_is_not_told_of_positions() {
    let dir = std::env::temp_dir().join(format!("et-cli-labels-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let rows: String = (0..40)
        .map(|i| {
            format!(
                "{},{}\n",
                f64::from(i % 2) * 3.0 + f64::from(i % 7) * 0.1,
                i % 5
            )
        })
        .collect();
    std::fs::write(p("F.csv"), format!("a,b\n{rows}")).unwrap();
    let labels: String = (0..40).map(|i| format!("{}\n", i % 2)).collect();
    std::fs::write(p("T.csv"), format!("label\n{labels}")).unwrap();
    let t = et(&[
        "train",
        "--features",
        &p("F.csv"),
        "--targets",
        &p("T.csv"),
        "--kind",
        "lda",
        "--out",
        &p("m.json"),
    ]);
    let said = String::from_utf8_lossy(&t.stderr);
    assert!(
        t.status.success()
            && said.contains("note: no --groups: every row is taken as one session")
            && !said.contains("positions"),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
