//! et's defaults on two real saline tanks measured by other labs' instruments, through the
//! front door as a user meets it: every case with known targets imaged by `et reconstruct
//! --scene S --frames F --reference 1 --frame N --json` and nothing else chosen, scored
//! against the targets (the strongest object's distance to the nearest target, its sign, the
//! object count) with the bar et's defaults must hold on both: median distance at most 5 mm,
//! the sign right in all but one case, the count within one in at least 80 % of cases.
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

#[test]
fn defaults_hold_on_two_real_tanks() {
    let Some(all) = tanks::both() else {
        eprintln!("skipped: no ../shared/data/tanks beside the project");
        return;
    };
    let work = std::env::temp_dir().join(format!("et-tanks-test-{}", std::process::id()));
    let mut failures = Vec::new();
    for tank in &all {
        let dir = work.join(tank.name.split(' ').next().unwrap_or("tank"));
        let (scene, frames) = tank.write(&dir);
        let mut scores = Vec::new();
        for case in &tank.cases {
            let out = Command::new(env!("CARGO_BIN_EXE_et"))
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
                .arg(dir.join(format!("{}.png", case.id)))
                .output()
                .expect("run et");
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
            eprintln!(
                "{} {}: alpha {:.3e}, strongest object {:.1} mm from a target, sign {}, {} objects of {} targets",
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
        let summary = tanks::summary(&scores);
        eprintln!("{}: {summary}", tank.name);
        if !summary.meets_the_bar() {
            failures.push(format!("{}: {summary}", tank.name));
        }
    }
    std::fs::remove_dir_all(&work).ok();
    assert!(
        failures.is_empty(),
        "below the bar (median <= 5 mm, sign right in all but one, count within one in 80 %): {failures:?}"
    );
}
