//! Touch classification accuracy on the simulated sheet, the SPEC §9 way: a class grid,
//! T = 6 visits x S_num = 20 scans x S_sub = 20 sub-sections (2 400 observations per class)
//! with the electrodes moving between visits and the pressure varied by hand (5 to 60 kPa),
//! the opposite protocol's reciprocity-halved features; then three "next day" sessions (20
//! observations per class each, electrodes moved again, unknown pressure).
//!
//! Models: plain QDA and LDA as SPEC §9, and both with the shrinkage chosen by
//! leave-one-visit-out cross-validation (which measures what a moved electrode costs).
//!
//! Run: `cargo run --release -p et-host --example accuracy [-- --quick]`
//! (`--quick`: S_num = 5, for a fast look.)

use std::time::Instant;

use et_core::ScanConfig;
use et_core::model::ModelKind;
use et_host::learn::collect::{Plan, collect, grid, training_config};
use et_host::learn::cv::{Confusion, choose_shrinkage_with, evaluate};
use et_host::learn::fastcv::cross_validate_fast;
use et_host::learn::fit::{FitOptions, Fitted, Target};
use et_sim::frontend::FrontendSpec;
use et_sim::sheet::SheetSpec;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let base = ScanConfig::REFERENCE;
    println!(
        "sheet         classes  model                 lambda  next_day_acc (min-max)  mean_err_mm  AEE_mm"
    );
    for (side, l, n, radius) in [
        (0.13, 16u8, 7usize, 0.0075),
        (0.13, 16, 10, 0.005),
        (0.13, 8, 7, 0.0075),
        (0.17, 16, 7, 0.0075),
    ] {
        let spec = SheetSpec::rectangle(side, side, l);
        // SPEC §9's training scans for this electrode count (3 200 / L samples per step).
        let config = training_config(ScanConfig {
            electrodes: l,
            ..base
        });
        let centres = grid(&spec, n, n, 0.0);
        let classes = centres.len();
        let plan = Plan {
            visits: 6,
            scans: if quick { 5 } else { 20 },
            subsections: 20,
            pressure_pa: (5e3, 60e3),
            radius,
            placement: radius / 4.0,
            electrode_movement: 0.0005,
            poses: 1,
            press_movement: 0.0,
            seed: 1,
        };
        let started = Instant::now();
        let train =
            collect(&spec, FrontendSpec::default(), config, &centres, &plan).expect("collect");
        let days: Vec<_> = (0..3)
            .map(|d| {
                collect(
                    &spec,
                    FrontendSpec::default(),
                    config,
                    &centres,
                    &Plan {
                        visits: 1,
                        scans: 1,
                        seed: 77 + d,
                        ..plan.clone()
                    },
                )
                .expect("collect")
            })
            .collect();
        eprintln!(
            "  {:.0} cm L={l}: collected in {:.1} s",
            side * 100.0,
            started.elapsed().as_secs_f64()
        );
        let by_visit: Vec<usize> = train.visit.iter().map(|&v| usize::from(v)).collect();
        let mm: Vec<[f64; 2]> = centres.iter().map(|c| [c[0] * 1e3, c[1] * 1e3]).collect();
        for (name, kind, target, grid_l) in [
            ("QDA", ModelKind::Qda, Target::Pooled, vec![0.0]),
            (
                "QDA, lambda by LOVO",
                ModelKind::Qda,
                Target::Pooled,
                vec![0.01, 0.03, 0.1, 0.3, 1.0],
            ),
            ("LDA", ModelKind::Lda, Target::Diagonal, vec![0.0]),
            (
                "LDA, lambda by LOVO",
                ModelKind::Lda,
                Target::Diagonal,
                vec![0.0, 0.01, 0.03, 0.1, 0.3],
            ),
        ] {
            let opts = FitOptions {
                kind,
                shrinkage: 0.0,
                target,
            };
            let lambda = if grid_l.len() == 1 {
                grid_l[0]
            } else {
                choose_shrinkage_with(
                    &grid_l,
                    |o| cross_validate_fast(&train.x, &train.y, classes, o, &by_visit),
                    &opts,
                )
                .expect("choose")
                .0
            };
            let opts = FitOptions {
                shrinkage: lambda,
                ..opts
            };
            let model = match Fitted::fit(&train.x, &train.y, classes, &opts) {
                Ok(m) => m,
                Err(e) => {
                    println!(
                        "{:>4.0} cm L={l:<2} {classes:7}  {name:<20}  {e}",
                        side * 100.0
                    );
                    continue;
                }
            };
            let mut all = Confusion::new(classes);
            let mut accs = Vec::new();
            for day in &days {
                let conf = evaluate(&model, &day.x, &day.y).expect("evaluate");
                all.merge(&conf);
                accs.push(conf.accuracy());
            }
            let (lo, hi) = accs
                .iter()
                .fold((1.0f64, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            println!(
                "{:>4.0} cm L={l:<2} {classes:7}  {name:<20}  {lambda:6.2}  {:6.1} % ({:4.1}-{:4.1})       {:11.2}  {:6.1}",
                side * 100.0,
                100.0 * all.accuracy(),
                100.0 * lo,
                100.0 * hi,
                all.mean_position_error(&mm),
                all.aee(&mm) / days.len() as f64
            );
        }
    }
}
