//! et's defaults on two real saline tanks measured by other labs' instruments, through the
//! front door as a user meets it: every case with known targets imaged by `et reconstruct
//! --scene S --frames F --reference 1 --frame N --json` and nothing else chosen, scored
//! against the targets (the strongest object's distance to the nearest target, its sign, the
//! object count) with the bar et's defaults must hold on both: median distance at most 5 mm,
//! the sign right in all but one case, the count within one in at least 80 % of cases; and its
//! three-class picture (`--segment`) scored as the Kuopio Tomography Challenge 2023 scores one,
//! at least 14 of 21 on average.
//!
//! The data (`../shared/data/tanks/`, beside the project, not part of the repository): the
//! "Open 2D Electrical Impedance Tomography data archive", Hauptmann, Kolehmainen, Mach,
//! Savolainen, Seppanen, Siltanen (2017), arXiv:1704.01178 (KIT4, 16 electrodes); the Kuopio
//! Tomography Challenge 2023's training data (Finnish Inverse Problems Society and the
//! University of Eastern Finland, Zenodo record 8252370; 32 electrodes). Without the folder
//! the test says so and passes (a clone alone does not have it; CI has it beside the clone).

mod support;

use std::process::Command;

use support::tanks::{self, CaseScore, Found};

/// The challenge's score per case the default segmentation (`--segment`) must reach on
/// average: 14 of 21, the Kuopio Tomography Challenge 2023 bar the held-out cases are asked.
const SEGMENT_BAR: f64 = 14.0 / 21.0;

#[test]
fn defaults_hold_on_the_16_electrode_tank() {
    defaults_hold_on(0);
}

#[test]
fn defaults_hold_on_the_32_electrode_tank() {
    defaults_hold_on(1);
}

/// Every case of tank `which` ([`tanks::both`]'s order) through `et reconstruct`'s defaults:
/// the objects against the targets, the segmentation by the challenge's score against the
/// truth (the challenge's own images for the 32-electrode tank, the targets' discs for the
/// 16-electrode one).
fn defaults_hold_on(which: usize) {
    let Some(all) = tanks::both() else {
        eprintln!("skipped: no ../shared/data/tanks beside the project");
        return;
    };
    let tank = &all[which];
    let work = std::env::temp_dir().join(format!("et-tanks-test-{}-{which}", std::process::id()));
    let (scene, frames) = tank.write(&work);
    let mut scores = Vec::new();
    let mut segment_score = 0.0;
    // Each case is its own `et reconstruct`, as a user runs it; as many at a time as there are
    // cores (the set-up is most of each run).
    let classes_path = |id: &str| work.join(format!("{id}-classes.npy"));
    let command = |case: &tanks::Case| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_et"));
        command
            .args(["reconstruct", "--scene"])
            .arg(&scene)
            .arg("--frames")
            .arg(&frames)
            .args([
                "--reference",
                "1",
                "--frame",
                &case.frame.to_string(),
                "--json",
            ])
            .args(["--force", "--out"])
            .arg(work.join(format!("{}.png", case.id)))
            .arg("--segment")
            .arg(classes_path(&case.id));
        command
    };
    let at_once = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let mut outputs = Vec::new();
    for cases in tank.cases.chunks(at_once) {
        let running: Vec<_> = cases
            .iter()
            .map(|case| {
                command(case)
                    .stdout(std::process::Stdio::piped())
                    .stderr(std::process::Stdio::piped())
                    .spawn()
                    .expect("run et")
            })
            .collect();
        outputs.extend(
            running
                .into_iter()
                .map(|c| c.wait_with_output().expect("run et")),
        );
    }
    for (case, out) in tank.cases.iter().zip(outputs) {
        let classes_path = classes_path(&case.id);
        assert!(
            out.status.success(),
            "{} {}: {}",
            tank.name,
            case.id,
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
        let objects: Vec<Found> = json["objects"]
            .as_array()
            .expect("objects")
            .iter()
            .map(|o| Found {
                centre: [o["x_m"].as_f64().unwrap(), o["y_m"].as_f64().unwrap()],
                sign: i8::try_from(o["sign"].as_i64().unwrap()).unwrap(),
            })
            .collect();
        let score = CaseScore::of(case, &objects);
        let classes = tanks::read_pixels(tank, &classes_path, &json["segment"]);
        let seg: Vec<u8> = classes.iter().map(|c| c.map_or(0, |c| c as u8)).collect();
        let challenge = tanks::challenge_score(&tanks::truth_mask(tank, case), &seg);
        segment_score += challenge;
        eprintln!(
            "{} {}: alpha {:.3e}, strongest object {:.1} mm from a target, sign {}, {} objects of {} targets, segmentation's score {challenge:.2}",
            tank.name,
            case.id,
            json["alpha"].as_f64().unwrap_or(f64::NAN),
            1e3 * score.miss.unwrap_or(f64::NAN),
            if score.sign_right { "right" } else { "wrong" },
            score.found,
            score.targets
        );
        scores.push(score);
    }
    std::fs::remove_dir_all(&work).ok();
    let summary = tanks::summary(&scores);
    let n = tank.cases.len() as f64;
    eprintln!(
        "{}: {summary}, segmentation's score {segment_score:.2} of {n}",
        tank.name
    );
    assert!(
        summary.meets_the_bar(),
        "{}: {summary}, below the bar (median <= 5 mm, sign right in all but one, count within one in 80 %)",
        tank.name
    );
    assert!(
        segment_score >= SEGMENT_BAR * n,
        "{}: the segmentation scores {segment_score:.2} of {n}, below {:.2}",
        tank.name,
        SEGMENT_BAR * n
    );
}

/// A detached electrode, as other labs' instruments show one, on both real tanks: electrode 7
/// (as the protocol files count, from 1) reads noise (a floating input, 0.5 V rms) and drives no current
/// (its injections' values a few microvolts of noise). `et reconstruct` names it, on neither
/// tank as measured, and `--skip-electrodes 7` images each case as the tank as measured does
/// (the strongest object within 5 mm, its sign the same); without it the first case's image
/// has no object or another. Detached after the reference, it is named in the frames.
#[test]
fn a_detached_electrode_is_named_and_left_out() {
    let Some(all) = tanks::both() else {
        eprintln!("skipped: no ../shared/data/tanks beside the project");
        return;
    };
    for (which, tank) in all.iter().enumerate() {
        let work =
            std::env::temp_dir().join(format!("et-tanks-detached-{}-{which}", std::process::id()));
        let (scene, frames) = tank.write(&work);
        let broken = work.join("broken.csv");
        std::fs::write(&broken, detached(&tank.protocol_csv, &frames, 7, 0)).expect("frames");
        // Detached after the reference was taken (every frame but the first).
        let later = work.join("later.csv");
        std::fs::write(&later, detached(&tank.protocol_csv, &frames, 7, 1)).expect("frames");
        let run = |frames: &std::path::Path, case: &tanks::Case, skip: bool| {
            let mut command = Command::new(env!("CARGO_BIN_EXE_et"));
            command
                .args(["reconstruct", "--scene"])
                .arg(&scene)
                .arg("--frames")
                .arg(frames)
                .args(["--reference", "1", "--frame", &case.frame.to_string()])
                .args(["--json", "--force", "--out"])
                .arg(work.join("x.png"));
            if skip {
                command.args(["--skip-electrodes", "7"]);
            }
            let out = command.output().expect("run et");
            let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
            assert!(out.status.success(), "{}: {stderr}", tank.name);
            let json: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
            let strongest = json["objects"]
                .as_array()
                .expect("objects")
                .first()
                .map(|o| {
                    let at = [o["x_m"].as_f64().unwrap(), o["y_m"].as_f64().unwrap()];
                    (at, o["sign"].as_i64().unwrap())
                });
            (strongest, stderr)
        };
        for (k, case) in tank.cases.iter().take(2).enumerate() {
            let (measured, said) = run(&frames, case, false);
            assert!(
                !said.contains("warning: electrode"),
                "{}: {said}",
                tank.name
            );
            let (left_out, said) = run(&broken, case, true);
            assert!(
                said.contains("284 of the frame's 1264")
                    || said.contains("326 of the frame's 2356"),
                "{said}"
            );
            let ((a, sign_a), (b, sign_b)) = (measured.unwrap(), left_out.unwrap());
            let apart = (a[0] - b[0]).hypot(a[1] - b[1]);
            assert!(
                apart < 5e-3 && sign_a == sign_b,
                "{} {}: {apart} m apart, signs {sign_a} {sign_b}",
                tank.name,
                case.id
            );
            if k == 0 {
                let (broken_image, said) = run(&broken, case, false);
                assert!(
                    said.contains("warning: electrode 7's")
                        && said.contains("--skip-electrodes 7 leaves its values out"),
                    "{}: {said}",
                    tank.name
                );
                assert!(
                    broken_image.is_none_or(|(c, s)| (c[0] - a[0]).hypot(c[1] - a[1]) > 5e-3
                        || s != sign_a),
                    "{}: the detached electrode did not change the image",
                    tank.name
                );
                let (_, said) = run(&later, case, false);
                let from = format!(
                    "warning: electrode 7's values stand out in 1 of the 1 frames to image, from \
                     frame {}",
                    case.frame
                );
                assert!(
                    said.contains(&from) && !said.contains("warning: electrode 7's 2"),
                    "{}: {said}",
                    tank.name
                );
            }
        }
        std::fs::remove_dir_all(&work).ok();
    }
}

/// The frames of `frames_csv` (one per line, V) with `electrode` (counted from 1, as
/// `protocol_csv` counts) detached: every value it measures noise of 0.5 V rms, every value
/// under its injections noise of 10 uV rms; from the frame `from` on (0-based, the earlier
/// ones as they are).
fn detached(
    protocol_csv: &str,
    frames_csv: &std::path::Path,
    electrode: u16,
    from: usize,
) -> String {
    let rows: Vec<[u16; 4]> = protocol_csv
        .lines()
        .skip(1)
        .map(|l| {
            let c: Vec<u16> = l.split(',').take(4).map(|c| c.parse().unwrap()).collect();
            [c[0], c[1], c[2], c[3]]
        })
        .collect();
    // A fixed-seed generator of about normal noise (the sum of 12 uniforms less 6).
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut normal = move || {
        (0..12)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1);
                (state >> 11) as f64 / (1u64 << 53) as f64
            })
            .sum::<f64>()
            - 6.0
    };
    let text = std::fs::read_to_string(frames_csv).expect("frames");
    let mut out = String::new();
    for (index, line) in text.lines().enumerate() {
        if index < from {
            out.push_str(line);
            out.push('\n');
            continue;
        }
        let values: Vec<String> = (line.split(',').zip(&rows))
            .map(|(v, [source, sink, positive, negative])| {
                if [source, sink].contains(&&electrode) {
                    format!("{:e}", 1e-5 * normal())
                } else if [positive, negative].contains(&&electrode) {
                    format!("{:e}", 0.5 * normal())
                } else {
                    v.to_string()
                }
            })
            .collect();
        out.push_str(&values.join(","));
        out.push('\n');
    }
    out
}

/// `et protocol --injections --measurements` on each tank's own two lists of pairs (counted
/// from 1, their currents in mA) writes the protocol file this test's support crosses from
/// the data set's description, row for row, and says how a scene reads it.
#[test]
fn the_tanks_pair_lists_cross_into_their_protocol_files() {
    let Some(all) = tanks::both() else {
        eprintln!("skipped: no ../shared/data/tanks beside the project");
        return;
    };
    let parse = |text: &str| -> Vec<(Vec<u16>, f64)> {
        (text.lines().skip(1))
            .map(|line| {
                let cells: Vec<&str> = line.split(',').collect();
                let electrodes = cells[..4].iter().map(|c| c.parse().expect("an electrode"));
                (electrodes.collect(), cells[4].parse().expect("a current"))
            })
            .collect()
    };
    for tank in &all {
        let out = Command::new(env!("CARGO_BIN_EXE_et"))
            .args(["protocol", "--current-unit", "mA", "--injections"])
            .arg(tank.dir.join("injection_pairs.csv"))
            .arg("--measurements")
            .arg(tank.dir.join("measurement_pairs.csv"))
            .output()
            .expect("et runs");
        let said = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{}: {said}", tank.name);
        let (made, expected) = (
            parse(&String::from_utf8_lossy(&out.stdout)),
            parse(&tank.protocol_csv),
        );
        assert_eq!(made.len(), expected.len(), "{}", tank.name);
        for (k, ((e, c), (e0, c0))) in made.iter().zip(&expected).enumerate() {
            assert_eq!(e, e0, "{}: value {k}", tank.name);
            assert!(
                (c - c0).abs() <= 1e-12 * c0,
                "{}: value {k}: {c} A, not {c0}",
                tank.name
            );
        }
        assert!(
            said.contains("base = 1") && said.contains(&format!("K = {}", expected.len())),
            "{said}"
        );
    }
}
