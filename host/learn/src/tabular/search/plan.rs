//! A training's plan: how its rows are cross-validated, every candidate searched, the best
//! that fits on every row, and what is said of the choice.

use super::*;

/// The most groups (sessions) a training leaves out one at a time: each candidate is fitted
/// once per group (every row its own group took over five minutes, without a word).
pub const MAX_GROUPS: usize = 100;

/// How a training's rows are cross-validated: leaving each group out when the rows name two
/// groups or more, else `opts.folds` folds by `opts.scheme`.
pub(super) struct Cv {
    /// Folds (groups when grouped).
    pub(super) k: usize,
    pub(super) scheme: CvScheme,
    pub(super) grouped: bool,
    /// Each row's group and the groups' names, when the rows have groups.
    pub(super) groups: Option<(Vec<usize>, Vec<String>)>,
}

impl Cv {
    /// The cross-validation of `table`'s rows under `opts`.
    pub(super) fn plan(table: &Table, opts: &TrainOptions) -> Result<Self, TabularError> {
        let n = table.rows();
        let groups = table.group_index();
        let grouped = groups.as_ref().is_some_and(|(_, names)| names.len() >= 2);
        let k = if grouped {
            groups.as_ref().map_or(0, |(_, names)| names.len())
        } else {
            opts.folds
        };
        // Leaving each group out fits every candidate once per group: sessions, not rows.
        if grouped && k > MAX_GROUPS {
            return Err(usage(Misuse::TooManyGroups { groups: k, rows: n }));
        }
        // Two rows in two folds fit each fold on one row: every method's error came out
        // undefined, said as "no candidate could be fitted".
        if !grouped && n < 3 {
            return Err(usage(Misuse::TooFewRows(n)));
        }
        if !grouped && (opts.folds < 2 || opts.folds > n) {
            return Err(usage(Misuse::Folds {
                folds: opts.folds,
                rows: n,
            }));
        }
        let scheme = if grouped {
            CvScheme::Groups
        } else if opts.scheme == CvScheme::Groups {
            return Err(usage(Misuse::NoGroups));
        } else {
            opts.scheme
        };
        Ok(Self {
            k,
            scheme,
            grouped,
            groups,
        })
    }

    /// Each of the `n` rows' fold: its group when grouped, else by the scheme (stratified by
    /// `labels` when given).
    pub(super) fn folds(&self, n: usize, labels: Option<&[u16]>, seed: u64) -> Vec<usize> {
        match &self.groups {
            Some((index, _)) if self.grouped => index.clone(),
            _ => folds(n, self.k, self.scheme, labels, seed),
        }
    }
}

/// Every candidate of `choice`'s methods, cross-validated by `cv`: the classifiers on the
/// class labels, the regressors on the positions (`targets`).
pub(super) fn search_all(
    table: &Table,
    choice: Choice,
    opts: &TrainOptions,
    cv: &Cv,
    (targets, classes): (Option<&[Target3]>, Option<&(Labels, ClassInfo)>),
    progress: Progress<'_>,
) -> Result<Vec<Candidate>, TabularError> {
    let methods: Vec<Kind> = match choice {
        Choice::One(m) => vec![m],
        Choice::Auto if targets.is_some() && opts.grid.is_none() => {
            vec![
                Kind::Ridge,
                Kind::Knn,
                Kind::KernelRidge,
                Kind::Mlp,
                Kind::Gp,
            ]
        }
        Choice::Auto => vec![Kind::Lda, Kind::Qda],
    };
    let n = table.rows();
    // A discriminant's covariance tables, refused before any fit where they would not fit in
    // the memory free (20 000 features were killed by the system at 24 GB, without a word).
    if let Some((labels, _)) = classes {
        for &method in methods.iter().filter(|m| m.is_classifier()) {
            discriminant_fits(method, table.x.ncols(), labels.names.len())?;
        }
    }
    // The regressors' folds, and the time of those that estimate theirs, refused past the
    // budget before any fit.
    let regressor_fold = cv.folds(n, None, opts.seed);
    let k = regressor_fold.iter().max().map_or(0, |m| m + 1);
    let estimates: Vec<Option<f64>> = methods
        .iter()
        .map(|&m| match classes {
            Some((labels, _)) if m.is_classifier() => {
                let shape = (n, table.x.ncols(), labels.names.len());
                Some(discriminant_seconds(m, shape, cv.k))
            }
            _ => {
                let regressor = !m.is_classifier() && targets.is_some();
                regressor
                    .then(|| estimate_seconds(m, &table.x, k))
                    .flatten()
            }
        })
        .collect();
    let total: f64 = estimates.iter().flatten().sum();
    if total > opts.budget_s {
        let what = methods
            .iter()
            .zip(&estimates)
            .filter(|(_, e)| e.is_some())
            .map(|(m, _)| m.name())
            .collect::<Vec<_>>()
            .join(" and ");
        return Err(usage(Misuse::OverBudget {
            what: format!(
                "training {what} on {} rows x {} features",
                n,
                table.x.ncols()
            ),
            estimate_s: total,
            budget_s: opts.budget_s,
        }));
    }
    let mut search: Vec<Candidate> = Vec::new();
    for (&method, &estimate_s) in methods.iter().zip(&estimates) {
        let found = if method.is_classifier() {
            let (labels, _) = classes.ok_or_else(|| usage(Misuse::NeedsLabels(method)))?;
            let fold = cv.folds(n, Some(&labels.index), opts.seed);
            search_classifier(table, method, labels, &fold, estimate_s, progress)?
        } else {
            let t = targets.ok_or_else(|| usage(Misuse::NeedsXy(method)))?;
            let fold = (regressor_fold.as_slice(), cv.grouped);
            search_regressor(&table.x, t, method, fold, estimate_s, progress)?
        };
        search.extend(found);
    }
    Ok(search)
}

/// Bytes a discriminant holds while it is fitted and cross-validated on `features` features
/// and `classes` classes: about 6 + 10 per class tables of features x features in double
/// precision (measured: 2 classes of 2 000 and 4 000 features held 24 of them, 4 classes 43;
/// `/usr/bin/time -v et train --kind qda` on 40 rows of random features).
#[must_use]
pub fn discriminant_bytes(features: usize, classes: usize) -> u64 {
    let table = 8 * (features as u128).pow(2);
    u64::try_from(table * (6 + 10 * classes as u128)).unwrap_or(u64::MAX)
}

/// Seconds QDA or LDA (`method`) takes to cross-validate its shrinkages over `k` folds of
/// `n` rows of `p` features in `classes` classes and then fit on every row, counted in
/// multiply-adds at the rate of a Cholesky factor timed on min(p, 2000) features (nalgebra's
/// factor runs a quarter faster on 1 000 than on 2 000 or 3 000): per shrinkage, the folds' factors (one per
/// class and fold for QDA, one per fold for LDA, p^3 / 3 each, the folds shared between the
/// threads), the sufficient statistics (n p^2) and the held-out rows' forward substitutions
/// (p^2 / 2 for each of up to 8 classes looked at; LDA's weights p per class); the final fit's
/// factors after. 2 000 features of 400 rows in 4 classes took 36 s of QDA and 12 s of LDA
/// without a word.
fn discriminant_seconds(method: Kind, (n, p, classes): (usize, usize, usize), k: usize) -> f64 {
    let (n, p, c, k) = (n as f64, p as f64, classes as f64, k.max(1) as f64);
    let threads = crate::pipeline::cost::threads();
    let factors = if method == Kind::Qda { c } else { 1.0 };
    let looked_at = if method == Kind::Qda {
        c.min(8.0) * p / 2.0
    } else {
        c
    };
    let factor = p.powi(3) / 3.0;
    let per_shrinkage = k * factors * factor / threads.min(k) + n * p * p + n * looked_at * p;
    let madds = SHRINKAGES.len() as f64 * per_shrinkage + factors * factor + n * p * p;
    madds / crate::pipeline::cost::cholesky_rate(p as usize)
}

/// Refuses `method` (QDA or LDA) on `features` features and `classes` classes where
/// [`discriminant_bytes`] pass the memory free now.
fn discriminant_fits(method: Kind, features: usize, classes: usize) -> Result<(), TabularError> {
    let need_bytes = discriminant_bytes(features, classes);
    match et_core::text::available_memory_bytes() {
        Some(free_bytes) if need_bytes > free_bytes => Err(usage(Misuse::TooWide {
            method,
            features,
            classes,
            need_bytes,
            free_bytes,
        })),
        _ => Ok(()),
    }
}

/// `auto`'s average of the best regressors ([`average_of_best`]) as a training keeps it: the
/// average, its note said in `notes`, and its members; none when no average cross-validates
/// better than the best single method.
pub(super) fn averaged(
    ranked: &[&Candidate],
    t: &[Target3],
    fold: &[usize],
    grouped: bool,
    notes: &mut Vec<String>,
) -> (Option<Candidate>, Vec<Candidate>) {
    let by_drift = !grouped;
    match average_of_best(ranked, t, fold, grouped, by_drift) {
        Some((average, members)) => {
            notes.push(average_note(&average, &members, by_drift));
            (Some(average), members)
        }
        None => (None, Vec::new()),
    }
}

/// What the training says when it chose the average `avg` of `members`.
pub(super) fn average_note(avg: &Candidate, members: &[Candidate], by_drift: bool) -> String {
    format!(
        "the mean of {}'s predictions cross-validated at {:.2} mm{} against {:.2} for {} \
         alone: chose their average",
        members
            .iter()
            .map(|c| c.method.name())
            .collect::<Vec<_>>()
            .join(", "),
        avg.choice_loss(by_drift),
        if by_drift {
            format!(
                " ({} of the plain and the drifted error)",
                drift_weighting()
            )
        } else {
            String::new()
        },
        members
            .first()
            .map_or(f64::NAN, |c| c.choice_loss(by_drift)),
        members.first().map_or("", |c| c.method.name())
    )
}

/// The first of the `ranked` candidates whose fit on every row succeeds ([`fit_final`]): the
/// candidate (a QDA at shrinkage 1 saved as the LDA it is), its tables and standardisation,
/// and whether it was so turned into an LDA.
#[allow(clippy::type_complexity)]
pub(super) fn fit_first(
    ranked: &[&Candidate],
    table: &Table,
    (targets, classes): (Option<&[Target3]>, Option<&(Labels, ClassInfo)>),
    (members, fold_rows): (&[Candidate], usize),
    (seed, progress): (u64, Progress<'_>),
) -> Result<(Candidate, (Tables, Vec<f64>, Vec<f64>), bool), TabularError> {
    let mut last_error = None;
    for &candidate in ranked {
        // QDA shrunk fully toward the pooled covariance is LDA, saved as one; where the pooled
        // covariance is singular (a constant feature, more features than rows to pool) LDA
        // cannot be fitted and the QDA, shrunk toward a target made usable, is kept.
        let labels = classes.map(|(l, _)| l);
        let lda = as_lda_if_equal(candidate, table.x.ncols(), labels, fold_rows);
        for (best, is_lda) in lda.iter().map(|l| (l, true)).chain([(candidate, false)]) {
            progress(&format!("fitting {}", best.method.name()), 0, 1);
            let fit = (classes, fold_rows);
            match fit_final(table, best, targets, fit, members, (seed, progress)) {
                Ok(f) => {
                    progress(&format!("fitting {}", best.method.name()), 1, 1);
                    return Ok((best.clone(), f, is_lda));
                }
                Err(e) => last_error = Some(e),
            }
        }
    }
    Err(
        last_error.unwrap_or(TabularError::Fit(FitError::NoCandidates(
            "no candidate could be fitted in cross-validation",
        ))),
    )
}

/// The hyperparameters a fit learns beside those searched: a Gaussian process's signal and
/// noise variances and its length scales' median.
pub(super) fn fitted_hyperparameters(tables: &Tables) -> Vec<(String, f64)> {
    let Tables::Gp {
        length_scales,
        signal_variance,
        noise_variance,
        ..
    } = tables
    else {
        return Vec::new();
    };
    let mut sorted = length_scales.clone();
    sorted.sort_by(f64::total_cmp);
    vec![
        ("signal_variance".to_string(), *signal_variance),
        ("noise_variance".to_string(), *noise_variance),
        (
            "length_scale_median".to_string(),
            sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN),
        ),
    ]
}
