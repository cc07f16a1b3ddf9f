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
