//! Touch classification accuracy on the simulated sheet, the SPEC §9 way: a class grid on the
//! 13 x 13 cm, 16-electrode sheet, T = 6 visits x S_num = 20 scans x S_sub = 20 sub-sections
//! (2 400 observations per class) with the electrodes moving between visits and the pressure
//! varied by hand (5 to 60 kPa), the opposite protocol's 96 features; then a "next day" test
//! set (20 observations per class, electrodes moved again, unknown pressure).
//!
//! Run: `cargo run --release -p et-host --example accuracy [-- --quick]`
//! (`--quick`: S_num = 5, for a fast look.)

use std::time::Instant;

use et_core::ScanConfig;
use et_core::model::ModelKind;
use et_core::protocol::ProtocolKind;
use et_host::learn::collect::{Plan, collect, grid};
use et_host::learn::cv::Confusion;
use et_host::learn::fit::{FitOptions, Fitted, Target};
use et_sim::frontend::FrontendSpec;
use et_sim::shape::Shape;
use et_sim::sheet::{ElectrodeSpec, SheetSpec};
use et_sim::touch::Piezo;

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let config = ScanConfig {
        protocol: ProtocolKind::Opposite,
        samples_per_step: 200,
        settle_samples: 40,
        sample_rate_hz: 10_000,
        ..ScanConfig::REFERENCE
    };
    println!(
        "case                      classes  train_obs  fit_s  next_day_acc  mean_err_mm  AEE_mm"
    );
    for (side, l, n, radius) in [
        (0.13, 16u8, 7usize, 0.0075),
        (0.13, 16, 10, 0.005),
        (0.13, 8, 7, 0.0075),
        (0.17, 16, 7, 0.0075),
    ] {
        let spec = SheetSpec {
            shape: Shape::Rectangle {
                width: side,
                height: side,
            },
            sheet_resistance: 30e3,
            electrodes: ElectrodeSpec {
                count: l,
                ..ElectrodeSpec::default()
            },
            resolution: None,
            piezo: Piezo::default(),
            bend: None,
        };
        let config = ScanConfig {
            electrodes: l,
            ..config
        };
        let centres = grid(&spec, n, n, 0.0);
        let plan = Plan {
            visits: 6,
            scans: if quick { 5 } else { 20 },
            subsections: 20,
            pressure_pa: (5e3, 60e3),
            radius,
            placement: radius / 4.0,
            electrode_movement: 0.0005,
            seed: 1,
        };
        let started = Instant::now();
        let train =
            collect(&spec, FrontendSpec::default(), config, &centres, &plan).expect("collect");
        let test = collect(
            &spec,
            FrontendSpec::default(),
            config,
            &centres,
            &Plan {
                visits: 1,
                scans: 1,
                seed: 77,
                ..plan.clone()
            },
        )
        .expect("collect");
        let collected = started.elapsed();
        let mm: Vec<[f64; 2]> = centres.iter().map(|c| [c[0] * 1e3, c[1] * 1e3]).collect();
        for (name, opts) in [
            (
                "QDA",
                FitOptions {
                    kind: ModelKind::Qda,
                    shrinkage: 0.0,
                    target: Target::Diagonal,
                },
            ),
            (
                "QDA shrunk 0.05",
                FitOptions {
                    kind: ModelKind::Qda,
                    shrinkage: 0.05,
                    target: Target::Pooled,
                },
            ),
            (
                "LDA",
                FitOptions {
                    kind: ModelKind::Lda,
                    shrinkage: 0.0,
                    target: Target::Diagonal,
                },
            ),
        ] {
            let t = Instant::now();
            let model = match Fitted::fit(&train.x, &train.y, centres.len(), &opts) {
                Ok(m) => m,
                Err(e) => {
                    println!("{name}: {e}");
                    continue;
                }
            };
            let fit_s = t.elapsed().as_secs_f64();
            let mut conf = Confusion::new(centres.len());
            for r in 0..test.x.nrows() {
                let row: Vec<f64> = test.x.row(r).iter().copied().collect();
                conf.add(test.y[r], model.predict(&row));
            }
            println!(
                "{:>4.0} cm L={l:<2} {name:<15} {:7}  {:9}  {:5.2}  {:12.3}  {:11.2}  {:6.1}",
                side * 100.0,
                centres.len(),
                train.x.nrows(),
                fit_s,
                conf.accuracy(),
                conf.mean_position_error(&mm),
                conf.aee(&mm)
            );
        }
        eprintln!("  (collected in {:.1} s)", collected.as_secs_f64());
    }
}
