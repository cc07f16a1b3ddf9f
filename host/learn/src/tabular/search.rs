//! Training: every candidate method and hyperparameter scored by cross-validation inside the
//! training rows, the best fitted on all of them.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

mod plan;

use crate::pipeline::cost::about;
use plan::{Cv, averaged, fit_first, fitted_hyperparameters, search_all};

/// Shrinkage candidates for QDA and LDA.
pub(super) const SHRINKAGES: [f64; 6] = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0];
/// Ridge's lambda candidates (times n on the z-space Gram matrix).
pub(super) const RIDGE_LAMBDAS: [f64; 9] = [1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0];
/// Kernel ridge: widths (gamma = width / median squared distance) and lambdas.
pub(super) const KRR_WIDTHS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];
pub(super) const KRR_LAMBDAS: [f64; 4] = [1e-4, 1e-3, 1e-2, 1e-1];
/// Kernel ridge keeps at most this many support rows (spread evenly over the training rows).
pub const KRR_SUPPORT: usize = 3_000;
/// ... and searches on at most this many per fold.
pub(super) const KRR_SEARCH_SUPPORT: usize = 1_200;
/// k-nearest-neighbour candidates.
pub(super) const KNN_KS: [usize; 8] = [1, 2, 3, 5, 8, 12, 20, 30];
/// The Gaussian process's learning rows, iterations and support.
pub(super) const GP: GpOptions = GpOptions::DEFAULT;
/// ... and in each fold of its search: half the learning rows (a third of the time each), so
/// the search fits the 30 s budget on 2 000 x 192. The folds' score is then a little
/// pessimistic for the final fit, never flattering.
pub(super) const GP_SEARCH: GpOptions = GpOptions {
    learn_rows: GP.learn_rows / 2,
    ..GP
};

/// The held-out rows are also predicted as a later session might measure them: each
/// channel's gain changed by this standard deviation (10 %: contacts and amplifier paths) ...
pub const DRIFT_GAIN: f64 = 0.1;
/// ... and its level shifted by this share of the channel's spread (half: the sheet settled,
/// a reference frame gone stale), which scores how a candidate would take a new session's
/// drift ([`Candidate::cv_drifted_error_mm`]).
pub const DRIFT_OFFSET: f64 = 0.5;
/// Each fold's held-out rows are drifted this many times, each draw its own gains and
/// levels, and the drifted error is their mean: one draw's error depends on which channels
/// it happened to move most, and ties between candidates were broken by that luck.
pub const DRIFT_DRAWS: usize = 4;
/// Without groups, `auto` ranks a regressor by its plain cross-validated error P and its
/// drifted error D together, P^(1 - w) D^w with this w ([`Candidate::choice_loss`]). By D
/// alone (w = 1) the robust but coarse won same-session splits; by P alone the accurate but
/// fragile lost several times the best error on the next session. Chosen over thirteen
/// splits (same-session and new-session stand-ins, milder and harsher drift, scikit-learn's
/// bundled sets; `host/learn/benches/choice_study.py`, docs/measurements.md): on the skins
/// the worst `auto` came to 1.60, 1.27, 1.27, 1.28 and 1.59 times the best kind alone at
/// w = 0.5, 0.65, 0.75, 0.85 and 1; of the two best, 0.75 does better than 0.65 on the four
/// splits where they differ that drift (0.87 to 0.96 times the best kind against 0.97 to
/// 1.23) and worse on friedman1 (1.57 against 1.23).
pub const DRIFT_WEIGHT: f64 = 0.75;

/// The choice's weighting as the reports write it: "P^0.25 D^0.75".
#[must_use]
pub fn drift_weighting() -> String {
    format!("P^{:.2} D^{:.2}", 1.0 - DRIFT_WEIGHT, DRIFT_WEIGHT)
}

/// `x` as a drifted session measures it: each column `j` times 1 + `gain` N(0, 1), plus
/// `offset` `spread[j]` N(0, 1), drawn from `seed`; `spread` is each column's standard
/// deviation (in the learning rows, so the held-out rows' own spread is not peeked at).
#[must_use]
pub fn drifted(
    x: &DMatrix<f64>,
    spread: &[f64],
    gain: f64,
    offset: f64,
    seed: u64,
) -> DMatrix<f64> {
    let mut rng = et_core::rng::Rng::new(seed);
    let shift: Vec<(f64, f64)> = (0..x.ncols())
        .map(|j| {
            let g = 1.0 + gain * rng.normal();
            let o = offset * spread.get(j).copied().unwrap_or(0.0) * rng.normal();
            (g, o)
        })
        .collect();
    DMatrix::from_fn(x.nrows(), x.ncols(), |r, j| {
        let (g, o) = shift.get(j).copied().unwrap_or((1.0, 0.0));
        x[(r, j)] * g + o
    })
}

/// The perceptron's candidates: hidden layers 300, 50, 20 (what won on measured skins) with
/// relu or tanh, and L2 penalties.
pub(super) const MLP_L2S: [f64; 2] = [0.1, 1.0];
pub(super) const MLP_ACTIVATIONS: [Activation; 2] = [Activation::Relu, Activation::Tanh];
pub(super) const MLP_HIDDEN: [usize; 3] = [300, 50, 20];
/// Random starts in the search's folds and in the final fit.
pub(super) const MLP_SEARCH_STARTS: usize = 1;
pub(super) const MLP_FINAL_STARTS: usize = 3;

/// The perceptron a candidate's hyperparameters describe.
pub(super) fn mlp_options(h: &BTreeMap<String, f64>) -> MlpOptions {
    let get = |k: &str| h.get(k).copied();
    let hidden: Vec<usize> = (1..=4)
        .map_while(|i| get(&format!("hidden_{i}")))
        .map(|w| w.max(1.0) as usize)
        .collect();
    MlpOptions {
        hidden: if hidden.is_empty() {
            MLP_HIDDEN.to_vec()
        } else {
            hidden
        },
        activation: if get("tanh").unwrap_or(0.0) > 0.5 {
            Activation::Tanh
        } else {
            Activation::Relu
        },
        l2: get("l2").unwrap_or(0.1),
        starts: MLP_SEARCH_STARTS,
        ..MlpOptions::default()
    }
}

/// Trains `choice` on `table` (all its rows: select the training rows first), hyperparameters
/// by `opts.folds`-fold cross-validation inside them.
///
/// # Errors
/// [`TabularError::Usage`] when the targets do not suit the method (a regressor without
/// positions, a classifier without labels or a grid, a single class, too few rows for the
/// folds), [`TabularError::Fit`] when no candidate could be fitted.
pub fn train(
    table: &Table,
    choice: Choice,
    opts: &TrainOptions,
    progress: Progress<'_>,
) -> Result<TableModel, TabularError> {
    let started = std::time::Instant::now();
    finite_features(&table.x)?;
    let constant = constant_said(table);
    // The rows as given (before any standardisation per group), as evaluation reads them.
    let seen = seen_sample(&table.x);
    let standardised;
    let table = if opts.per_group {
        standardised = table.standardised_per_group()?;
        &standardised
    } else {
        table
    };
    let n = table.rows();
    let cv = Cv::plan(table, opts)?;
    let targets = table.targets();
    let classes = class_targets(table, opts.grid)?;
    let mut search = search_all(
        table,
        choice,
        opts,
        &cv,
        (targets.as_deref(), classes.as_ref()),
        progress,
    )?;
    let by_drift = !cv.grouped;
    let (mut ranked, mut notes) = rank(&search, choice, cv.grouped);
    notes.extend(constant.clone());
    notes.extend(table.positions_scale_note());
    let (average, members) = match (&targets, choice) {
        (Some(t), Choice::Auto) if opts.grid.is_none() => averaged(
            &ranked,
            t,
            &cv.folds(n, None, opts.seed),
            cv.grouped,
            &mut notes,
        ),
        _ => (None, Vec::new()),
    };
    if let Some(avg) = &average {
        ranked.insert(0, avg);
    }
    if ranked.is_empty()
        && let Some(e) = nothing_fitted(&search)
    {
        return Err(e);
    }
    // The smallest cross-validation training set, which chose QDA's shrinkage target.
    let fold_rows = classes.as_ref().map_or(n, |(l, _)| {
        classify::fold_rows(&cv.folds(n, Some(&l.index), opts.seed))
    });
    let (best, (tables, mean, scale), qda_is_lda) = fit_first(
        &ranked,
        table,
        (targets.as_deref(), classes.as_ref()),
        (&members, fold_rows),
        (opts.seed, progress),
    )
    .map_err(|e| match constant {
        Some(constant) => TabularError::Constant {
            source: Box::new(e),
            constant,
        },
        None => e,
    })?;
    notes.extend(guessing_note(
        &best,
        targets.as_deref(),
        classes.as_ref().map(|(l, _)| l),
        || cv.folds(n, None, opts.seed),
    ));
    search.extend(average.clone());
    for c in &mut search {
        c.out_of_fold = None;
    }
    if qda_is_lda {
        // Its cross-validation is the QDA's: the same classifier in every fold.
        search.push(best.clone());
        // Said as a dataset's training says it.
        let classes = classes.as_ref().map_or(0, |(l, _)| l.names.len());
        notes.push(crate::pipeline::Fallback::QdaIsLda { classes }.to_string());
    }
    let mut hyperparameters = best.hyperparameters.clone();
    hyperparameters.extend(fitted_hyperparameters(&tables));
    Ok(TableModel {
        format: "et-table-model".into(),
        version: TABLE_MODEL_VERSION,
        method: best.method,
        feature_names: table.feature_names.clone(),
        feature_mean: mean,
        feature_scale: scale,
        unit: table.unit,
        third: table.third.as_ref().map(|(n, _)| n.clone()),
        classes: if best.method.is_classifier() {
            classes.map(|(_, info)| info)
        } else {
            None
        },
        hyperparameters,
        search,
        cv_folds: cv.k,
        cv_scheme: cv.scheme,
        trained_rows: [table.first_row, table.first_row + n],
        source: table.description.clone(),
        fit_seconds: started.elapsed().as_secs_f64(),
        chosen_by_drift: by_drift && !best.method.is_classifier(),
        note: (!notes.is_empty()).then(|| notes.join("; ")),
        tables,
        per_group: opts.per_group,
        reference: None,
        seen,
    })
}

/// QDA at shrinkage 1 toward the pooled covariance gives every class the pooled covariance,
/// in every fold as on all rows: that is LDA at shrinkage 0, as that LDA candidate (scored
/// as the QDA was), C times smaller. `None` for any other candidate, and when the folds'
/// `fold_rows` made the target the diagonal.
#[must_use]
pub fn as_lda_if_equal(
    c: &Candidate,
    p: usize,
    labels: Option<&Labels>,
    fold_rows: usize,
) -> Option<Candidate> {
    let full = c
        .hyperparameters
        .get("shrinkage")
        .is_some_and(|&s| s >= 1.0);
    let pooled = shrink_target(p, labels?, fold_rows) == Target::Pooled;
    (c.method == Kind::Qda && full && pooled).then(|| Candidate {
        method: Kind::Lda,
        hyperparameters: params(&[("shrinkage", 0.0)]),
        ..c.clone()
    })
}

/// Fold of each row: contiguous blocks, or shuffled (stratified by `labels` when given).
#[must_use]
pub fn folds(
    n: usize,
    k: usize,
    scheme: CvScheme,
    labels: Option<&[u16]>,
    seed: u64,
) -> Vec<usize> {
    let k = k.max(1);
    match (scheme, labels) {
        // Without the groups themselves, contiguous blocks are the nearest thing.
        (CvScheme::Blocks | CvScheme::Groups, _) => (0..n).map(|r| r * k / n.max(1)).collect(),
        (CvScheme::Shuffled, Some(y)) => cv::folds(y, k, seed),
        (CvScheme::Shuffled, None) => cv::folds(&vec![0; n], k, seed),
    }
}

/// Rows of `x` as a matrix.
pub(super) fn rows_of(x: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), x.ncols(), |i, j| {
        rows.get(i).map_or(0.0, |&r| x[(r, j)])
    })
}

pub(super) fn params(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
    pairs.iter().map(|&(k, v)| (k.to_string(), v)).collect()
}

/// Mean position error (x, y; mm) of predictions against truth (m).
pub(super) fn mean_error(pred: &[Target3], truth: &[Target3]) -> f64 {
    summarise(pred, truth, false).mean_mm
}

/// Mean position error (mm) of the drifted predictions (draw d's of row r at d n + r, `t`'s
/// n rows in m) over every draw.
pub(super) fn drifted_error(pred: &[Target3], t: &[Target3]) -> f64 {
    let truth: Vec<Target3> = t.iter().copied().cycle().take(pred.len()).collect();
    mean_error(pred, &truth)
}

/// Seconds `method`'s cross-validation over `k` folds and its final fit on rows like `x` are
/// estimated to take, for the methods whose time grows fastest with the table (the Gaussian
/// process, the perceptron, k nearest neighbours, kernel ridge: each times a piece of its
/// work on rows of `x`'s shape); None for the others.
pub(super) fn estimate_seconds(method: Kind, x: &DMatrix<f64>, k: usize) -> Option<f64> {
    match method {
        Kind::Gp => Some(Gp::estimate_seconds(x, &GP_SEARCH, k) + Gp::estimate_seconds(x, &GP, 1)),
        Kind::Mlp => {
            let grid = regressor_grid(Kind::Mlp, x.nrows()).ok()?;
            let search = mlp_options(grid.first()?);
            let last = MlpOptions {
                starts: MLP_FINAL_STARTS,
                ..search.clone()
            };
            Some(
                Mlp::estimate_seconds(x, &search, k * grid.len())
                    + Mlp::estimate_seconds(x, &last, 1),
            )
        }
        Kind::KernelRidge => Some(KernelRidge::estimate_seconds(
            x,
            (k, KRR_WIDTHS.len() * KRR_LAMBDAS.len(), DRIFT_DRAWS),
            (KRR_SEARCH_SUPPORT, KRR_SUPPORT),
        )),
        Kind::Knn => {
            // Each fold: its held-out rows and their drifted copies against the others.
            let n = x.nrows();
            let k_max = KNN_KS.iter().copied().max().unwrap_or(1);
            let held_out = n.div_ceil(k.max(1));
            let fold = Knn::estimate_seconds(x, n - held_out, held_out * (1 + DRIFT_DRAWS), k_max);
            Some(fold * k as f64)
        }
        _ => None,
    }
}

/// Every hyperparameter candidate of a regressor, scored by cross-validation; `estimate_s`
/// its time when estimated ([`estimate_seconds`]), said beforehand.
pub(super) fn search_regressor(
    x: &DMatrix<f64>,
    t: &[Target3],
    method: Kind,
    (fold, grouped): (&[usize], bool),
    estimate_s: Option<f64>,
    progress: Progress<'_>,
) -> Result<Vec<Candidate>, TabularError> {
    let n = x.nrows();
    let k = fold.iter().max().map_or(0, |m| m + 1);
    let grid = regressor_grid(method, n)?;
    // Out-of-fold predictions of every candidate.
    let mut pred: Vec<Vec<Option<Target3>>> = vec![vec![None; n]; grid.len()];
    // Row r's prediction under draw d at d n + r.
    let mut pred_drifted: Vec<Vec<Option<Target3>>> = vec![vec![None; n * DRIFT_DRAWS]; grid.len()];
    let seed_of = |f: usize| 0x6a1e_d41f ^ (f as u64);
    // Progress steps per fold: the Gaussian process reports each of its iterations, and says
    // beforehand how long its folds and final fit will take.
    let steps = match method {
        Kind::Gp => GP.iterations,
        Kind::Mlp => grid.len(),
        _ => 1,
    };
    let (name, candidates) = (method.name(), grid.len());
    let what = match estimate_s.map(about) {
        Some(t) if method == Kind::Mlp => format!(
            "cross-validating mlp ({candidates} candidates, {k} folds, then the final fit: {t}, \
             within a factor of 3: early stopping decides)"
        ),
        Some(t) => format!("cross-validating {name} ({k} folds, then the final fit: {t})"),
        None => format!("cross-validating {name} ({candidates} candidates)"),
    };
    let total = k * steps;
    for f in 0..k {
        progress(&what, f * steps, total);
        let train: Vec<usize> = (0..n).filter(|&r| fold.get(r) != Some(&f)).collect();
        let test: Vec<usize> = (0..n).filter(|&r| fold.get(r) == Some(&f)).collect();
        if test.is_empty() || train.len() < 2 {
            continue;
        }
        let (xt, xv) = (rows_of(x, &train), rows_of(x, &test));
        let tt: Vec<Target3> = train.iter().filter_map(|&r| t.get(r).copied()).collect();
        // The held-out rows as measured, and as a session later might measure them: each
        // channel's gain and level changed (drawn per fold).
        let spread: Vec<f64> = (0..xt.ncols())
            .map(|j| xt.column(j).variance().sqrt())
            .collect();
        // The drawn sessions stacked: draw d's rows at d m .. (d + 1) m.
        let m = xv.nrows();
        let draws: Vec<DMatrix<f64>> = (0..DRIFT_DRAWS as u64)
            .map(|d| {
                drifted(
                    &xv,
                    &spread,
                    DRIFT_GAIN,
                    DRIFT_OFFSET,
                    seed_of(f) ^ (d << 32),
                )
            })
            .collect();
        let sets = [
            xv.clone(),
            DMatrix::from_fn(m * DRIFT_DRAWS, xv.ncols(), |r, j| {
                draws.get(r / m).map_or(0.0, |x| x[(r % m, j)])
            }),
        ];
        let mut tick = |done: usize| progress(&what, f * steps + done, total);
        let fold_pred = fold_predictions(method, &grid, (&xt, &tt), &sets, &mut tick)?;
        for (c, p) in fold_pred.into_iter().enumerate() {
            let (Some([p, q]), Some(slot), Some(drifted)) =
                (p, pred.get_mut(c), pred_drifted.get_mut(c))
            else {
                continue;
            };
            for (&r, v) in test.iter().zip(p) {
                if let Some(s) = slot.get_mut(r) {
                    *s = Some(v);
                }
            }
            for (i, w) in q.into_iter().enumerate() {
                let (d, row) = (i / m.max(1), i % m.max(1));
                if let Some(slot) = test.get(row).and_then(|&r| drifted.get_mut(d * n + r)) {
                    *slot = Some(w);
                }
            }
        }
    }
    progress(&what, total, total);
    Ok(grid
        .into_iter()
        .zip(pred.into_iter().zip(pred_drifted))
        .map(|(hyperparameters, (p, q))| {
            // A candidate that failed in any fold scores nothing.
            let p_all: Option<Vec<Target3>> = p.into_iter().collect();
            let q_all: Option<Vec<Target3>> = q.into_iter().collect();
            Candidate {
                method,
                hyperparameters,
                cv_mean_error_mm: p_all
                    .as_ref()
                    .map(|p| mean_error(p, t))
                    .filter(|e| e.is_finite()),
                cv_block_errors_mm: block_errors(&p_all, t, fold, grouped),
                cv_drifted_error_mm: q_all
                    .as_ref()
                    .map(|p| drifted_error(p, t))
                    .filter(|e| e.is_finite()),
                cv_accuracy: None,
                out_of_fold: p_all.zip(q_all).map(|(p, q)| [p, q]),
                failure: None,
            }
        })
        .collect())
}

/// The hyperparameter candidates a regressor's search tries on `n` rows.
fn regressor_grid(method: Kind, n: usize) -> Result<Vec<BTreeMap<String, f64>>, TabularError> {
    Ok(match method {
        Kind::Ridge => RIDGE_LAMBDAS
            .iter()
            .map(|&l| params(&[("lambda", l)]))
            .collect(),
        Kind::KernelRidge => KRR_WIDTHS
            .iter()
            .flat_map(|&w| {
                KRR_LAMBDAS
                    .iter()
                    .map(move |&l| params(&[("width", w), ("lambda", l)]))
            })
            .collect(),
        Kind::Knn => KNN_KS
            .iter()
            .flat_map(|&k| [0.0, 1.0].map(|d| params(&[("k", k as f64), ("distance_weighted", d)])))
            .collect(),
        Kind::Gp => vec![params(&[
            ("learn_rows", GP.learn_rows.min(n) as f64),
            ("search_learn_rows", GP_SEARCH.learn_rows.min(n) as f64),
            ("iterations", GP.iterations as f64),
        ])],
        Kind::Mlp => MLP_ACTIVATIONS
            .iter()
            .flat_map(|&a| {
                MLP_L2S.iter().map(move |&l2| {
                    let mut h = params(&[
                        ("l2", l2),
                        ("tanh", f64::from(u8::from(a == Activation::Tanh))),
                    ]);
                    for (i, w) in MLP_HIDDEN.iter().enumerate() {
                        h.insert(format!("hidden_{}", i + 1), *w as f64);
                    }
                    h
                })
            })
            .collect(),
        Kind::Qda | Kind::Lda | Kind::Average => return Err(usage(Misuse::NotARegressor)),
    })
}

/// One fold's predictions by every candidate of `grid`, fitted on the fold's training rows
/// (`xt`, `tt`), of each of the held-out `sets` (as measured, drifted); None for a candidate
/// whose fit failed. `tick(done)` reports the steps of a long fold (the Gaussian process's
/// iterations, the perceptron's candidates).
#[allow(clippy::type_complexity)]
fn fold_predictions(
    method: Kind,
    grid: &[BTreeMap<String, f64>],
    (xt, tt): (&DMatrix<f64>, &[Target3]),
    sets: &[DMatrix<f64>; 2],
    tick: &mut dyn FnMut(usize),
) -> Result<Vec<Option<[Vec<Target3>; 2]>>, TabularError> {
    Ok(match method {
        Kind::Ridge => Ridge::fit_path(xt, tt, &RIDGE_LAMBDAS)?
            .into_iter()
            .map(|m| m.map(|m| sets.each_ref().map(|x| m.predict_many(x))))
            .collect(),
        Kind::KernelRidge => {
            let fits =
                KernelRidge::fit_grid(xt, tt, KRR_SEARCH_SUPPORT, &KRR_WIDTHS, &KRR_LAMBDAS)?;
            // Every fit of the grid shares the support: the held-out rows' distances once per
            // block of rows (memory bounded: all at once took 19 kB a table row), each fit's
            // predictions from them.
            let mut pred: Vec<Option<[Vec<Target3>; 2]>> = (fits.iter())
                .map(|m| m.as_ref().map(|_| [Vec::new(), Vec::new()]))
                .collect();
            if let Some(first) = fits.iter().flatten().next() {
                for (s, x) in sets.iter().enumerate() {
                    for (start, rows) in crate::regress::row_blocks(x.nrows(), first.support_rows())
                    {
                        let d2 = first.distances(&x.rows(start, rows).into_owned());
                        for (m, p) in fits.iter().zip(&mut pred) {
                            if let (Some(m), Some(into)) =
                                (m, p.as_mut().and_then(|p| p.get_mut(s)))
                            {
                                into.extend(m.predict_from_distances(&d2));
                            }
                        }
                    }
                }
            }
            pred
        }
        Kind::Knn => {
            let model = Knn::fit(xt, tt, 1, Weighting::Uniform)?;
            let k_max = KNN_KS.iter().copied().max().unwrap_or(1);
            let near = sets.each_ref().map(|x| model.neighbours(x, k_max));
            grid.iter()
                .map(|h| {
                    let k = h.get("k").copied().unwrap_or(1.0) as usize;
                    let w = if h.get("distance_weighted").copied().unwrap_or(0.0) > 0.5 {
                        Weighting::Distance
                    } else {
                        Weighting::Uniform
                    };
                    Some(
                        near.each_ref()
                            .map(|near| near.iter().map(|nr| model.combine(nr, k, w)).collect()),
                    )
                })
                .collect()
        }
        Kind::Gp => {
            let mut step = |done: usize, _: usize| tick(done);
            vec![
                Gp::fit(xt, tt, &GP_SEARCH, &mut step)
                    .ok()
                    .map(|m| sets.each_ref().map(|x| m.predict_many(x))),
            ]
        }
        Kind::Mlp => grid
            .iter()
            .enumerate()
            .map(|(c, h)| {
                tick(c);
                Mlp::fit(xt, tt, &mlp_options(h))
                    .ok()
                    .map(|m| sets.each_ref().map(|x| m.predict_many(x)))
            })
            .collect(),
        Kind::Qda | Kind::Lda | Kind::Average => Vec::new(),
    })
}
