//! The search that set the press variability's two free parameters (docs/calibration.md): for
//! each pair of (junction potential moved by a press, the hand's force wobble) on a grid, the
//! six published cases of docs/method.md §9 (plain QDA on raw frames, next day), and the pair
//! whose largest difference from the reference is smallest. Everything else is the default
//! `Plan` and front end (the noise layers are calibrated on their own, by
//! `cargo run --release -p et-sim --example calibrate`).
//!
//! Run: `cargo run --release -p et-learn --example calibration_search [-- --scans 20
//! --junction-uv 0,25,50 --wobble 0,0.4,0.8 --threads 2]` (about 3 minutes of one core per
//! grid point at full size, S_num 20; the points run on `--threads` cores).

use std::sync::Mutex;
use std::time::Instant;

use et_learn::collect::Plan;
use et_learn::reference::{CASES, measure};
use et_sim::frontend::FrontendSpec;
use et_sim::touch::Piezo;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    let i = args.iter().position(|a| a == name)?;
    args.get(i + 1).cloned()
}

fn list(name: &str, default: &[f64]) -> Result<Vec<f64>, String> {
    match arg(name) {
        None => Ok(default.to_vec()),
        Some(s) => s
            .split(',')
            .map(|v| {
                v.trim()
                    .parse::<f64>()
                    .map_err(|e| format!("{name}: '{v}': {e}"))
            })
            .collect(),
    }
}

/// One grid point's outcome: next-day accuracy per case, in `CASES` order.
struct Point {
    junction_uv: f64,
    wobble: f64,
    next_day: Vec<f64>,
    worst: f64,
    rms: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scans = arg("--scans").map_or(Ok(20), |s| s.parse::<usize>())?;
    let threads = arg("--threads")
        .map_or(Ok(2), |s| s.parse::<usize>())?
        .max(1);
    let junctions = list("--junction-uv", &[0.0, 25.0, 50.0])?;
    let wobbles = list("--wobble", &[0.0, 0.4, 0.8])?;
    let grid: Vec<(f64, f64)> = junctions
        .iter()
        .flat_map(|&j| wobbles.iter().map(move |&w| (j, w)))
        .collect();
    println!(
        "S_num {scans}; {} grid points on {threads} threads",
        grid.len()
    );
    let started = Instant::now();
    let next = Mutex::new(0usize);
    let points = Mutex::new(Vec::new());
    let failure = Mutex::new(None);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let i = {
                        let Ok(mut n) = next.lock() else { return };
                        *n += 1;
                        *n - 1
                    };
                    let Some(&(junction_uv, wobble)) = grid.get(i) else {
                        return;
                    };
                    let plan = Plan {
                        scans,
                        press_junction: junction_uv * 1e-6,
                        wobble,
                        ..Plan::default()
                    };
                    let mut next_day = Vec::new();
                    for case in CASES {
                        match measure(&case, FrontendSpec::default(), Piezo::default(), &plan, 3) {
                            Ok(o) => next_day.push(o.next_day),
                            Err(e) => {
                                if let Ok(mut f) = failure.lock() {
                                    *f = Some(e.to_string());
                                }
                                return;
                            }
                        }
                    }
                    let diffs: Vec<f64> = CASES
                        .iter()
                        .zip(&next_day)
                        .map(|(c, a)| 100.0 * (a - c.reference))
                        .collect();
                    let worst = diffs.iter().map(|d| d.abs()).fold(0.0, f64::max);
                    let rms =
                        (diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64).sqrt();
                    eprintln!(
                        "  junction {junction_uv} uV, wobble {wobble}: largest difference \
                         {worst:.1} points ({:.0} s)",
                        started.elapsed().as_secs_f64()
                    );
                    if let Ok(mut p) = points.lock() {
                        p.push(Point {
                            junction_uv,
                            wobble,
                            next_day,
                            worst,
                            rms,
                        });
                    }
                }
            });
        }
    });
    if let Some(e) = failure.into_inner().ok().flatten() {
        return Err(e.into());
    }
    let mut points = points
        .into_inner()
        .map_err(|_| "a search thread panicked")?;
    points.sort_by(|a, b| {
        (a.junction_uv, a.wobble)
            .partial_cmp(&(b.junction_uv, b.wobble))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    print_table(&points);
    if let Some(best) = points.iter().min_by(|a, b| a.worst.total_cmp(&b.worst)) {
        println!(
            "best: press junction {} uV, wobble {} (largest difference {:.1} points); {:.0} s",
            best.junction_uv,
            best.wobble,
            best.worst,
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// The grid's results as a Markdown table, the reference row first.
fn print_table(points: &[Point]) {
    let names: Vec<String> = CASES.iter().map(|c| c.name()).collect();
    println!(
        "| press junction (uV) | wobble | {} | largest difference | rms difference |",
        names.join(" | ")
    );
    println!("|---|---|{}---|---|", "---|".repeat(CASES.len()));
    let reference: Vec<String> = CASES
        .iter()
        .map(|c| format!("{:.1}", 100.0 * c.reference))
        .collect();
    println!("| reference | | {} | | |", reference.join(" | "));
    for p in points {
        let cells: Vec<String> = p
            .next_day
            .iter()
            .map(|a| format!("{:.1}", 100.0 * a))
            .collect();
        println!(
            "| {} | {} | {} | {:.1} | {:.1} |",
            p.junction_uv,
            p.wobble,
            cells.join(" | "),
            p.worst,
            p.rms
        );
    }
}
