//! Touch classification accuracy on the simulated sheet, the docs/method.md §9 way: a class grid,
//! T = 6 visits x S_num = 20 scans x S_sub = 20 sub-sections (2 400 observations per class)
//! on the calibrated simulator (docs/calibration.md: each visit a measurement set, presses
//! varying as a hand's, one 7.5 mm fingertip aiming at 15 mm targets for 49 classes and 10 mm
//! for 100, PGIA gain 8); then three "next day" sessions (20 observations per class each, a
//! new set again, unknown pressure).
//!
//! Models: QDA exactly as docs/method.md §9 on the raw frames; the best shrinkage on raw frames; and
//! QDA / LDA on *referenced* frames (each frame minus its session's untouched frame), the
//! shrinkage chosen by leave-one-visit-out cross-validation on the training set only. Then
//! the reduced variants that fit the STM32F405, evaluated by et-core on the exported blobs.
//!
//! Run: `cargo run --release -p et-learn --example accuracy [-- --quick]`
//! (`--quick`: S_num = 5, for a fast look.)

use std::time::Instant;

use et_core::ScanConfig;
use et_core::model::{Model, ModelKind, Precision};
use et_learn::collect::{Plan, collect, grid, training_config};
use et_learn::cv::{Confusion, choose_shrinkage_with, evaluate};
use et_learn::dataset::Dataset;
use et_learn::fastcv::cross_validate_fast;
use et_learn::fit::{FitOptions, Fitted, Target, fisher_ranking};
use et_sim::frontend::{CALIBRATION_GAIN, FrontendSpec};
use et_sim::sheet::SheetSpec;
use nalgebra::DMatrix;

use et_core::board::MODEL_SLOT_BYTES as SLOT;

struct Case {
    name: String,
    classes: usize,
    train: Dataset,
    days: Vec<Dataset>,
    mm: Vec<[f64; 2]>,
}

fn collect_case(
    side: f64,
    l: u8,
    n: usize,
    target: f64,
    scans: usize,
    poses: usize,
    press: f64,
) -> Case {
    let spec = SheetSpec::rectangle(side, side, l);
    // docs/method.md §9's training scans for this electrode count (3 200 / L samples per step).
    let config = training_config(ScanConfig {
        electrodes: l,
        gain: CALIBRATION_GAIN,
        ..ScanConfig::REFERENCE
    });
    let centres = grid(&spec, n, n, 0.0);
    let plan = Plan {
        visits: 6,
        scans,
        subsections: 20,
        pressure_pa: (5e3, 60e3),
        target_radius: target,
        poses,
        press_movement: press,
        ..Plan::default()
    };
    let started = Instant::now();
    let fe = FrontendSpec::default();
    let train = collect(&spec, fe, config, &centres, &plan).expect("collect");
    let days = (0..3)
        .map(|d| {
            let day = Plan {
                visits: 1,
                scans: 1,
                seed: 77 + d,
                ..plan.clone()
            };
            collect(&spec, fe, config, &centres, &day).expect("collect")
        })
        .collect();
    let name = format!(
        "{:.0} cm, L = {l}{}",
        side * 100.0,
        if poses > 1 {
            ", electrodes moving within visits"
        } else {
            ""
        }
    );
    eprintln!(
        "  {name}, {} classes: collected in {:.1} s",
        centres.len(),
        started.elapsed().as_secs_f64()
    );
    Case {
        name,
        classes: centres.len(),
        mm: centres.iter().map(|c| [c[0] * 1e3, c[1] * 1e3]).collect(),
        train,
        days,
    }
}

/// A model's shrinkage and its next-day confusion (all days merged) and per-day accuracy.
struct Scored {
    lambda: f64,
    all: Confusion,
    days: Vec<f64>,
}

fn fit_and_score(
    case: &Case,
    kind: ModelKind,
    referenced: bool,
    lambdas: &[f64],
) -> Option<Scored> {
    let x = case.train.features(referenced).expect("features");
    // Shrink QDA toward the pooled covariance; LDA toward the diagonal.
    let target = if kind == ModelKind::Qda {
        Target::Pooled
    } else {
        Target::Diagonal
    };
    let opts = FitOptions {
        kind,
        shrinkage: 0.0,
        target,
    };
    let by_visit: Vec<usize> = case.train.visit.iter().map(|&v| usize::from(v)).collect();
    let lambda = if lambdas.len() == 1 {
        lambdas[0]
    } else {
        choose_shrinkage_with(
            lambdas,
            |o| cross_validate_fast(&x, &case.train.y, case.classes, o, &by_visit),
            &opts,
        )
        .ok()?
        .0
    };
    let model = Fitted::fit(
        &x,
        &case.train.y,
        case.classes,
        &FitOptions {
            shrinkage: lambda,
            ..opts
        },
    )
    .ok()?;
    let mut all = Confusion::new(case.classes);
    let mut days = Vec::new();
    for day in &case.days {
        let c = evaluate(&model, &day.features(referenced).expect("features"), &day.y)
            .expect("evaluate");
        all.merge(&c);
        days.push(c.accuracy());
    }
    Some(Scored { lambda, all, days })
}

fn row(case: &Case, method: &str, s: Option<&Scored>) {
    match s {
        Some(s) => {
            let lo = s.days.iter().copied().fold(1.0, f64::min);
            let hi = s.days.iter().copied().fold(0.0, f64::max);
            println!(
                "| {} | {} | {method} | {:.2} | {:.1} % ({:.1} to {:.1}) | {:.2} | {:.1} |",
                case.name,
                case.classes,
                s.lambda,
                100.0 * s.all.accuracy(),
                100.0 * lo,
                100.0 * hi,
                s.all.mean_position_error(&case.mm),
                s.all.aee(&case.mm) / s.days.len() as f64
            );
        }
        None => println!(
            "| {} | {} | {method} | - | cannot be fitted | - | - |",
            case.name, case.classes
        ),
    }
}

fn frame(x: &DMatrix<f64>, r: usize, index: &[u16], k: usize) -> Vec<f32> {
    let mut v = vec![0.0f32; k];
    for (j, &i) in index.iter().enumerate() {
        v[usize::from(i)] = x[(r, j)] as f32;
    }
    v
}

/// Exports `keep` features of a referenced model at `precision`, then classifies every
/// next-day frame on et-core (V_m and V_0 as the chip would see them, f32).
fn on_chip(
    case: &Case,
    kind: ModelKind,
    lambda: f64,
    keep: &[usize],
    precision: Precision,
) -> String {
    let x = case.train.features(true).expect("features");
    let xs = et_learn::analysis::select_columns(&x, keep);
    let target = if kind == ModelKind::Qda {
        Target::Pooled
    } else {
        Target::Diagonal
    };
    let Ok(model) = Fitted::fit(
        &xs,
        &case.train.y,
        case.classes,
        &FitOptions {
            kind,
            shrinkage: lambda,
            target,
        },
    ) else {
        return "cannot be fitted".into();
    };
    let index: Vec<u16> = keep.iter().map(|&j| case.train.feature_index[j]).collect();
    let positions: Vec<[f32; 2]> = case.mm.iter().map(|p| [p[0] as f32, p[1] as f32]).collect();
    let l = case.train.config.electrodes;
    let blob = match model.to_blob(
        l,
        case.train.config.protocol,
        &index,
        &positions,
        precision,
        true,
    ) {
        Ok(b) => b,
        Err(e) => return format!("export refused: {e}"),
    };
    let chip = Model::parse(&blob).expect("a written blob parses");
    let k = chip.frame_len();
    let mut scratch = vec![0.0f32; chip.scratch_len()];
    let (mut right, mut total, mut disagree) = (0usize, 0usize, 0usize);
    for day in &case.days {
        let v_0 = frame(&day.baselines, 0, &day.feature_index, k);
        let xr = day.features(true).expect("features");
        for r in 0..day.x.nrows() {
            let v_m = frame(&day.x, r, &day.feature_index, k);
            let d = chip
                .evaluate_referenced(&v_m, Some(&v_0), &mut scratch)
                .expect("finite");
            let host: Vec<f64> = keep.iter().map(|&j| xr[(r, j)]).collect();
            disagree += usize::from(d.class != model.predict(&host));
            right += usize::from(d.class == day.y[r]);
            total += 1;
        }
    }
    let macs = match kind {
        ModelKind::Qda => case.classes * (keep.len() * (keep.len() + 1) / 2 + keep.len()),
        ModelKind::Lda => case.classes * keep.len(),
    };
    format!(
        "{} | {} | {macs} | {:.1} % | {disagree} of {total}",
        blob.len(),
        if blob.len() <= SLOT { "yes" } else { "no" },
        100.0 * right as f64 / total as f64
    )
}

fn main() {
    let quick = std::env::args().any(|a| a == "--quick");
    let scans = if quick { 5 } else { 20 };
    let started = Instant::now();
    let lovo_qda = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0];
    let lovo_lda = [0.0, 0.01, 0.03, 0.1, 0.3];
    println!(
        "| sheet | classes | method | lambda | next-day accuracy (3 sessions' range) | mean error mm | AEE mm |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    let mut reduced = Vec::new();
    for (side, l, n, target, poses, press) in [
        (0.13, 16u8, 7usize, 0.0075, 1, 0.0),
        (0.13, 16, 10, 0.005, 1, 0.0),
        (0.13, 8, 7, 0.0075, 1, 0.0),
        (0.13, 8, 10, 0.005, 1, 0.0),
        (0.17, 16, 7, 0.0075, 1, 0.0),
        (0.17, 16, 10, 0.005, 1, 0.0),
        (0.13, 16, 10, 0.005, 6, 0.0003),
    ] {
        let case = collect_case(side, l, n, target, scans, poses, press);
        row(
            &case,
            "raw, QDA (docs/method.md §9)",
            fit_and_score(&case, ModelKind::Qda, false, &[0.0]).as_ref(),
        );
        row(
            &case,
            "raw, QDA, lambda by LOVO",
            fit_and_score(&case, ModelKind::Qda, false, &lovo_qda).as_ref(),
        );
        let qda = fit_and_score(&case, ModelKind::Qda, true, &lovo_qda);
        row(&case, "referenced, QDA, lambda by LOVO", qda.as_ref());
        let lda = fit_and_score(&case, ModelKind::Lda, true, &lovo_lda);
        row(&case, "referenced, LDA, lambda by LOVO", lda.as_ref());
        if side == 0.13 && l == 16 && poses == 1 {
            reduced.push((
                case,
                qda.map_or(0.1, |s| s.lambda),
                lda.map_or(0.0, |s| s.lambda),
            ));
        }
    }
    println!(
        "\nReduced variants on the chip (referenced; et-core evaluates the exported blob on every next-day frame):\n"
    );
    println!(
        "| classes | variant | blob bytes | fits beside a 128 KiB firmware | multiply-adds per frame | next-day accuracy on et-core | decisions differing from the host |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for (case, lq, ll) in &reduced {
        let all: Vec<usize> = (0..case.train.x.ncols()).collect();
        let ranked = fisher_ranking(
            &case.train.features(true).expect("features"),
            &case.train.y,
            case.classes,
        );
        // The best `n`, in frame order (a blob lists its features so).
        let best = |n: usize| {
            let mut kept = ranked[..n].to_vec();
            kept.sort_unstable();
            kept
        };
        for (variant, kind, lambda, keep, precision) in [
            ("QDA, f32", ModelKind::Qda, *lq, all.clone(), Precision::F32),
            ("QDA, f16", ModelKind::Qda, *lq, all.clone(), Precision::F16),
            (
                "QDA, 64 features, f16",
                ModelKind::Qda,
                *lq,
                best(64),
                Precision::F16,
            ),
            (
                "QDA, 48 features, f16",
                ModelKind::Qda,
                *lq,
                best(48),
                Precision::F16,
            ),
            ("LDA, f32", ModelKind::Lda, *ll, all.clone(), Precision::F32),
            ("LDA, f16", ModelKind::Lda, *ll, all.clone(), Precision::F16),
        ] {
            println!(
                "| {} | {variant} (lambda {lambda}) | {} |",
                case.classes,
                on_chip(case, kind, lambda, &keep, precision)
            );
        }
    }
    eprintln!("total {:.0} s", started.elapsed().as_secs_f64());
}
