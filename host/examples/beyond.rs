//! Beyond classes (docs/method.md §11) on the simulated 13 x 13 cm, 16-electrode sheet: continuous
//! position and pressure by regression, and telling one touch from two.
//!
//! Training: T = 6 visits (each a measurement set of its own), 400 presses per visit
//! anywhere on the sheet (the calibrated 7.5 mm fingertip and press variability, 5 to 60 kPa,
//! PGIA gain 8), 5 sub-section observations each.
//! Test: a "next day" visit (another set) of 400 new presses, one observation each.
//! Features are referenced (frame minus the visit's untouched frame). The class-based method
//! uses a 10 x 10 grid collected the docs/method.md §9 way.
//!
//! Run: `cargo run --release -p et-host --example beyond [-- --quick] [--plots DIR]`
//! (`--plots DIR`: also the error distributions as DIR/position-error-cdf.png.)

use et_core::ScanConfig;
use et_core::model::ModelKind;
use et_host::plot::{self, Labels, Series};
use et_learn::collect::{Plan, collect, collect_presses, grid, random_presses, training_config};
use et_learn::cv::evaluate;
use et_learn::dataset::Dataset;
use et_learn::fit::{FitOptions, Fitted, Target};
use et_learn::regress::{
    IntensityByClass, KernelRidge, Ridge, Target3, choose_temperature, posterior_centre,
    sorted_position_errors, summarise,
};
use et_sim::frontend::FrontendSpec;
use et_sim::sheet::SheetSpec;
use nalgebra::DMatrix;

fn targets(d: &Dataset) -> Vec<Target3> {
    d.positions
        .iter()
        .zip(&d.pressure)
        .map(|(p, kpa)| [p[0], p[1], kpa * 1e-3])
        .collect()
}

/// (error mm, % of presses at or below it), the empirical CDF of the position error up to
/// 40 mm.
fn cdf(pred: &[Target3], truth: &[Target3]) -> Vec<(f64, f64)> {
    let e = sorted_position_errors(pred, truth);
    let n = e.len() as f64;
    e.iter()
        .enumerate()
        .filter(|(i, _)| i % 4 == 0 || *i + 1 == e.len())
        .map(|(i, v)| (*v, 100.0 * (i + 1) as f64 / n))
        .filter(|(v, _)| *v <= 40.0) // the plot's axis ends at 40 mm
        .collect()
}

fn rows(x: &DMatrix<f64>) -> Vec<Vec<f64>> {
    x.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// The sheet, its front end and scan, and the collection plans every part of the example
/// draws from.
struct Setup {
    spec: SheetSpec,
    fe: FrontendSpec,
    config: ScanConfig,
    /// The training visits.
    plan: Plan,
    /// The "next day" test visit.
    next_day: Plan,
    /// Training presses per visit.
    presses: usize,
}

impl Setup {
    fn new(quick: bool) -> Self {
        let spec = SheetSpec::rectangle(0.13, 0.13, 16);
        // The calibrated simulator's operating point (docs/calibration.md): PGIA gain 8, the
        // collection's calibrated press variability and its 7.5 mm fingertip.
        let config = training_config(ScanConfig {
            gain: et_sim::frontend::CALIBRATION_GAIN,
            ..ScanConfig::REFERENCE
        });
        let plan = Plan {
            visits: 6,
            scans: if quick { 5 } else { 20 },
            subsections: 5,
            pressure_pa: (5e3, 60e3),
            ..Plan::default()
        };
        let next_day = Plan {
            visits: 1,
            subsections: 1,
            seed: 77,
            ..plan.clone()
        };
        Self {
            spec,
            fe: FrontendSpec::default(),
            config,
            plan,
            next_day,
            presses: if quick { 150 } else { 400 },
        }
    }

    /// `n` random presses of `touches` touches each, collected under `plan`.
    fn presses(&self, plan: &Plan, n: usize, touches: usize) -> Dataset {
        collect_presses(
            &self.spec,
            self.fe,
            self.config,
            &[],
            plan,
            random_presses(&self.spec, &self.plan, n, touches),
        )
        .expect("collect")
    }

    /// `n` one-touch presses under `plan`, then `n` two-touch presses under it with `seed`.
    fn one_and_two(&self, plan: &Plan, n: usize, seed: u64) -> Dataset {
        let mut one = self.presses(plan, n, 1);
        let two = self.presses(
            &Plan {
                seed,
                ..plan.clone()
            },
            n,
            2,
        );
        one.append(two).expect("append");
        one
    }
}

/// Each method's name and its position errors' empirical CDF, for the plot.
type Cdfs = Vec<(String, Vec<(f64, f64)>)>;

/// The regression table's row for one method.
fn regression_row(name: &str, pred: &[Target3], truth: &[Target3], macs: usize) {
    let s = summarise(pred, truth, true);
    println!(
        "{name:<40} {:7.2}  {:9.2}  {:6.2}  {:16.1}  {:10.3}  {macs:10}",
        s.mean_mm, s.median_mm, s.p90_mm, s.pressure_mae_kpa, s.pressure_r,
    );
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let setup = Setup::new(quick);
    let started = std::time::Instant::now();
    let train = setup.presses(&setup.plan, setup.presses, 1);
    let test = setup.presses(&setup.next_day, 400, 1);
    eprintln!("collected in {:.1} s", started.elapsed().as_secs_f64());
    let (x, xt) = (train.features(true).unwrap(), test.features(true).unwrap());
    let (t, tt) = (targets(&train), targets(&test));
    println!(
        "Regression, next-day test of {} presses ({} training observations):",
        tt.len(),
        t.len()
    );
    println!(
        "method                                   mean_mm  median_mm  p90_mm  pressure_MAE_kPa  pressure_r  MACs/frame"
    );
    let mut cdfs = regression(&x, &t, &xt, &tt);
    let qda = class_based(&setup, &x, &t, &xt, &tt, &mut cdfs);
    one_touch_or_two(&setup, &qda);
    let args: Vec<String> = std::env::args().collect();
    if let Some(dir) = args
        .iter()
        .position(|a| a == "--plots")
        .and_then(|i| args.get(i + 1))
    {
        plot_cdfs(std::path::Path::new(dir), cdfs);
    }
    eprintln!("total {:.1} s", started.elapsed().as_secs_f64());
}

/// Linear ridge, then kernel ridge on direction and raw features: the table's rows and their
/// CDFs.
fn regression(x: &DMatrix<f64>, t: &[Target3], xt: &DMatrix<f64>, tt: &[Target3]) -> Cdfs {
    let test_rows = rows(xt);
    let mut cdfs: Cdfs = Vec::new();
    let ridge = Ridge::fit(x, t, 1e-4).expect("ridge");
    let pred: Vec<Target3> = test_rows.iter().map(|r| ridge.predict(r)).collect();
    cdfs.push(("linear ridge".to_string(), cdf(&pred, tt)));
    regression_row("linear ridge", &pred, tt, ridge.cost());
    // Direction features: the touch's signature divided by its size (which pressure sets),
    // plus the log of the size as one more feature.
    let direction = |x: &DMatrix<f64>| {
        DMatrix::from_fn(x.nrows(), x.ncols() + 1, |r, j| {
            let n = x.row(r).norm().max(1e-12);
            if j < x.ncols() { x[(r, j)] / n } else { n.ln() }
        })
    };
    let (xd, xtd) = (direction(x), direction(xt));
    let test_dir = rows(&xtd);
    for (features, train_x, test_x, settings) in [
        (
            "direction",
            &xd,
            &test_dir,
            [
                (1000, 1.0, 1e-3),
                (2000, 1.0, 1e-3),
                (2000, 2.0, 1e-3),
                (3000, 4.0, 1e-3),
            ],
        ),
        (
            "raw",
            x,
            &test_rows,
            [
                (1000, 1.0, 1e-3),
                (2000, 1.0, 1e-3),
                (2000, 2.0, 1e-4),
                (3000, 2.0, 1e-4),
            ],
        ),
    ] {
        for (m, width, lambda) in settings {
            if m > t.len() {
                continue;
            }
            let krr = KernelRidge::fit(train_x, t, m, width, lambda).expect("krr");
            let pred: Vec<Target3> = test_x.iter().map(|r| krr.predict(r)).collect();
            if features == "direction" {
                cdfs.push((
                    format!("kernel ridge, direction, m = {m}, w = {width}"),
                    cdf(&pred, tt),
                ));
            }
            let name = format!("kernel ridge, {features}, m={m} w={width} l={lambda}");
            regression_row(&name, &pred, tt, krr.cost());
        }
    }
    cdfs
}

/// Class-based: QDA on a 10 x 10 grid (docs/method.md §9 collection), referenced; its class
/// centres, then its posterior-weighted centres at a temperature chosen on the training
/// presses. Returns the QDA model.
fn class_based(
    setup: &Setup,
    x: &DMatrix<f64>,
    t: &[Target3],
    xt: &DMatrix<f64>,
    tt: &[Target3],
    cdfs: &mut Cdfs,
) -> Fitted {
    let test_rows = rows(xt);
    let centres = grid(&setup.spec, 10, 10, 0.0);
    let grid_train = collect(
        &setup.spec,
        setup.fe,
        setup.config,
        &centres,
        &Plan {
            subsections: 20,
            // docs/method.md §9's 10 mm targets for 100 classes.
            target_radius: 0.005,
            ..setup.plan.clone()
        },
    )
    .expect("collect");
    let qda = Fitted::fit(
        &grid_train.features(true).unwrap(),
        &grid_train.y,
        centres.len(),
        &FitOptions {
            kind: ModelKind::Qda,
            shrinkage: 0.1,
            target: Target::Pooled,
        },
    )
    .expect("qda");
    let nearest: Vec<Target3> = test_rows
        .iter()
        .map(|r| {
            let c = centres[usize::from(qda.predict(r))];
            [c[0], c[1], 0.0]
        })
        .collect();
    let qda_macs = centres.len() * (96 * 97 / 2 + 96);
    let s = summarise(&nearest, tt, false);
    cdfs.push(("QDA class centre".to_string(), cdf(&nearest, tt)));
    println!(
        "{:<40} {:7.2}  {:9.2}  {:6.2}  {:>16}  {:>10}  {qda_macs:10}",
        "QDA class centre (10 x 10)", s.mean_mm, s.median_mm, s.p90_mm, "-", "-"
    );
    // The temperature is chosen on the training presses, never on the test.
    let truth: Vec<[f64; 2]> = t.iter().map(|v| [v[0], v[1]]).collect();
    let temps = [1.0, 2.0, 5.0, 10.0, 20.0, 50.0];
    let temperature = choose_temperature(&qda, x, &truth, &centres, &temps);
    let grid_x = grid_train.features(true).unwrap();
    let kpa: Vec<f64> = grid_train.pressure.iter().map(|p| p * 1e-3).collect();
    let intensity =
        IntensityByClass::fit(&grid_x, &grid_train.y, &kpa, centres.len()).expect("intensity");
    let post: Vec<Target3> = test_rows
        .iter()
        .map(|r| {
            let p = posterior_centre(&qda, r, &centres, temperature);
            [p[0], p[1], intensity.predict(r, qda.predict(r))]
        })
        .collect();
    let name = format!("QDA posterior centres, T = {temperature}");
    cdfs.push((name.clone(), cdf(&post, tt)));
    regression_row(&name, &post, tt, qda_macs + 3 * 96);
    for &tp in &temps {
        let post: Vec<Target3> = test_rows
            .iter()
            .map(|r| {
                let p = posterior_centre(&qda, r, &centres, tp);
                [p[0], p[1], 0.0]
            })
            .collect();
        eprintln!(
            "  (T = {tp}: test mean error {:.2} mm)",
            summarise(&post, tt, false).mean_mm
        );
    }
    qda
}

/// One touch or two: LDA and QDA trained on the count, and the 10 x 10 single-touch `qda`'s
/// best discriminant as an outlier test.
fn one_touch_or_two(setup: &Setup, qda: &Fitted) {
    let two_train = setup.one_and_two(&setup.plan, setup.presses / 2, 2);
    let two_test = setup.one_and_two(&setup.next_day, 200, 78);
    let labels = |d: &Dataset| d.y.iter().map(|&n| n - 1).collect::<Vec<u16>>();
    println!("\nOne touch or two (next day: 200 presses of each):");
    println!("model            accuracy  two_missed  false_two");
    for (name, kind, lambda) in [
        ("LDA", ModelKind::Lda, 0.0),
        ("QDA l=0.1", ModelKind::Qda, 0.1),
        ("QDA", ModelKind::Qda, 0.0),
    ] {
        let m = Fitted::fit(
            &two_train.features(true).unwrap(),
            &labels(&two_train),
            2,
            &FitOptions {
                kind,
                shrinkage: lambda,
                target: Target::Pooled,
            },
        )
        .expect("fit");
        let c = evaluate(&m, &two_test.features(true).unwrap(), &labels(&two_test)).expect("eval");
        let (ones, twos) = (c.counts[0] + c.counts[1], c.counts[2] + c.counts[3]);
        println!(
            "{name:<16} {:7.1} %  {:8.1} %  {:8.1} %",
            100.0 * c.accuracy(),
            100.0 * f64::from(c.counts[2]) / f64::from(twos.max(1)),
            100.0 * f64::from(c.counts[1]) / f64::from(ones.max(1)),
        );
    }
    // Outlier test: a two-touch frame fits no single-touch class, so the best QDA
    // discriminant of the 10 x 10 single-touch model is low. Threshold chosen on the training
    // presses.
    let best = |d: &Dataset| -> Vec<f64> {
        let x = d.features(true).unwrap();
        rows(&x)
            .iter()
            .map(|r| {
                qda.discriminants(r)
                    .into_iter()
                    .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect()
    };
    let (s_train, s_test) = (best(&two_train), best(&two_test));
    let (l_train, l_test) = (labels(&two_train), labels(&two_test));
    let accuracy = |s: &[f64], l: &[u16], th: f64| {
        s.iter()
            .zip(l)
            .filter(|(v, l)| (**v < th) == (**l == 1))
            .count() as f64
            / s.len() as f64
    };
    let mut cands = s_train.clone();
    cands.sort_by(f64::total_cmp);
    let th = cands
        .iter()
        .copied()
        .max_by(|a, b| {
            accuracy(&s_train, &l_train, *a).total_cmp(&accuracy(&s_train, &l_train, *b))
        })
        .unwrap_or(0.0);
    let missed = s_test
        .iter()
        .zip(&l_test)
        .filter(|(v, l)| **l == 1 && **v >= th)
        .count();
    let false_two = s_test
        .iter()
        .zip(&l_test)
        .filter(|(v, l)| **l == 0 && **v < th)
        .count();
    println!(
        "{:<16} {:7.1} %  {:8.1} %  {:8.1} %",
        "QDA outlier",
        100.0 * accuracy(&s_test, &l_test, th),
        100.0 * missed as f64 / 200.0,
        100.0 * false_two as f64 / 200.0
    );
}

/// The CDFs drawn as DIR/position-error-cdf.png.
fn plot_cdfs(dir: &std::path::Path, cdfs: Cdfs) {
    std::fs::create_dir_all(dir).expect("plot directory");
    let series: Vec<Series> = cdfs
        .into_iter()
        .map(|(label, points)| Series {
            label,
            points,
            scatter: false,
        })
        .collect();
    plot::chart(
        &dir.join("position-error-cdf.png"),
        Labels {
            title: "continuous position, next day: cumulative distribution of the error",
            x: "position error (mm)",
            y: "share of presses with a smaller error (%)",
            legend: plot::Legend::LowerRight,
        },
        &series,
    )
    .expect("plot");
}
