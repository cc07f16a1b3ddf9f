//! The simulator against the reference's touch-classification figures (docs/calibration.md):
//! docs/method.md §9's procedure with plain QDA on raw frames, for the six published cases
//! (13 / 17 cm, L = 16 / 8, 49 / 100 classes), printed beside the reference with the training
//! accuracy (10-fold cross-validation).
//!
//! Run: `cargo run --release -p et-learn --example calibration_table [-- --scans 20]`
//! (`--scans`: S_num per class and visit, 20 as the reference; fewer is a quicker proxy:
//! 5 gives 600 observations per class. `--creep`, `--drift`, `--radius-spread`,
//! `--movement-mm`, `--poses`, `--press-movement-mm`, `--press-junction-uv` override the
//! collection's defaults; `--junction-uv` and `--conductance` the front end's spread between
//! sets, as `cargo run --release -p et-sim --example calibrate -- --movement-mm M` fits it.)

use std::time::Instant;

use et_learn::collect::Plan;
use et_learn::reference::{CASES, measure};
use et_sim::frontend::{FrontendSpec, SetSpread};
use et_sim::touch::Piezo;

fn arg(name: &str) -> Option<f64> {
    let args: Vec<String> = std::env::args().collect();
    let i = args.iter().position(|a| a == name)?;
    args.get(i + 1)?.parse().ok()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let d = Plan::default();
    let plan = Plan {
        scans: arg("--scans").map_or(20, |s| s as usize),
        creep: arg("--creep").unwrap_or(d.creep),
        drift: arg("--drift").unwrap_or(d.drift),
        radius_spread: arg("--radius-spread").unwrap_or(d.radius_spread),
        electrode_movement: arg("--movement-mm").map_or(d.electrode_movement, |m| m * 1e-3),
        poses: arg("--poses").map_or(d.poses, |p| p as usize),
        press_movement: arg("--press-movement-mm").map_or(d.press_movement, |m| m * 1e-3),
        press_junction: arg("--press-junction-uv").map_or(d.press_junction, |v| v * 1e-6),
        unevenness: arg("--unevenness").unwrap_or(d.unevenness),
        wobble: arg("--wobble").unwrap_or(d.wobble),
        wobble_s: arg("--wobble-s").unwrap_or(d.wobble_s),
        elongation: arg("--elongation").unwrap_or(d.elongation),
        ..d
    };
    println!(
        "S_num {}, creep {}, drift {}, radius spread {}, re-placement {} mm, {} poses {} mm, press junction {} uV, unevenness {}, hand wobble {} over {} s, elongation up to {}",
        plan.scans,
        plan.creep,
        plan.drift,
        plan.radius_spread,
        plan.electrode_movement * 1e3,
        plan.poses,
        plan.press_movement * 1e3,
        plan.press_junction * 1e6,
        plan.unevenness,
        plan.wobble,
        plan.wobble_s,
        plan.elongation
    );
    let f = FrontendSpec::default();
    let frontend = FrontendSpec {
        sets: SetSpread {
            contact_potential_v: arg("--junction-uv")
                .map_or(f.sets.contact_potential_v, |v| v * 1e-6),
            conductance: arg("--conductance").unwrap_or(f.sets.conductance),
        },
        ..f
    };
    println!(
        "between sets: junction potential {} uV, conductance {}",
        frontend.sets.contact_potential_v * 1e6,
        frontend.sets.conductance
    );
    let piezo = Piezo {
        gain: arg("--piezo-gain").unwrap_or(Piezo::default().gain),
        ..Piezo::default()
    };
    println!(
        "fabric: conductance x{:.2} at 5 kPa, x{:.2} at 20 kPa, x{:.2} at 60 kPa",
        piezo.multiplier(5e3),
        piezo.multiplier(20e3),
        piezo.multiplier(60e3)
    );
    println!("| case | reference | simulator, next day | difference | training (10-fold) |");
    println!("| --- | --- | --- | --- | --- |");
    let started = Instant::now();
    let mut worst: f64 = 0.0;
    for case in CASES {
        let t = Instant::now();
        let o = measure(&case, frontend, piezo, &plan, 3)?;
        let diff = 100.0 * (o.next_day - case.reference);
        worst = worst.max(diff.abs());
        println!(
            "| {} | {:.1} % | {:.1} % | {diff:+.1} | {:.1} % |",
            case.name(),
            100.0 * case.reference,
            100.0 * o.next_day,
            100.0 * o.training
        );
        eprintln!("  ({:.0} s)", t.elapsed().as_secs_f64());
    }
    println!(
        "largest difference {worst:.1} points; {:.0} s",
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
