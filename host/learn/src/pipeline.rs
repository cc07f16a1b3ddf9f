//! A board model's training as `et train`, the viewer's wizard and `et demo` do it, in one
//! place: features from a dataset (referenced or raw, optionally the best p by Fisher ratio),
//! the shrinkage chosen by cross-validation (leave-one-visit-out when there are several
//! visits), the fit and its cross-validated accuracy. Its use (prediction, a test on another
//! session's data, the chip's check) is [`crate::model::Board`]'s.

pub mod cost;

use et_core::model::ModelKind;

use super::analysis;
use super::cv::{self, Confusion};
use super::dataset::{DataError, Dataset};
use super::fastcv::{Partition, Prepared};
use super::fit::{self, FitError, FitOptions, Fitted, Target};

use et_core::board::MODEL_SLOT_BYTES;

/// The most features (at most `max`) a `kind` model of `classes` classes can keep and still
/// fit one model slot of the board in f16 (0 when not even one feature fits).
#[must_use]
pub fn features_that_fit(kind: ModelKind, classes: usize, max: usize) -> usize {
    (1..=max)
        .rev()
        .find(|&p| {
            et_core::model::model_len(kind, et_core::model::Precision::F16, classes, p)
                <= MODEL_SLOT_BYTES
        })
        .unwrap_or(0)
}

/// The shrinkage candidates tried when it is chosen by cross-validation.
pub const SHRINKAGE_CANDIDATES: [f64; 6] = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0];

/// Replaces `data.x` by the features a model is trained on: each frame minus its session's
/// untouched frame when `referenced`, then (with `keep`) only the `keep` features of largest
/// Fisher ratio, in frame order (a smaller model for the chip). `data.feature_index` follows.
///
/// # Errors
/// [`DataError`] when referencing is impossible (no untouched frames) or `keep` is 0 or too
/// large.
pub fn prepare(data: &mut Dataset, referenced: bool, keep: Option<usize>) -> Result<(), DataError> {
    data.x = data.features(referenced)?;
    if let Some(keep) = keep {
        if keep == 0 || keep > data.x.ncols() {
            return Err(DataError::Keep {
                keep,
                available: data.x.ncols(),
            });
        }
        let mut kept = fit::fisher_ranking(&data.x, &data.y, data.centres.len());
        kept.truncate(keep);
        kept.sort_unstable();
        data.x = analysis::select_columns(&data.x, &kept);
        data.feature_index = kept.iter().map(|&j| data.feature_index[j]).collect();
    }
    Ok(())
}

/// How to train.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainOptions {
    /// QDA or LDA.
    pub kind: ModelKind,
    /// A fixed shrinkage in [0, 1], or None to choose among [`SHRINKAGE_CANDIDATES`].
    pub shrinkage: Option<f64>,
    /// k of the stratified k-fold cross-validation that is reported (docs/method.md §9: 10).
    pub folds: usize,
    /// The seed of the stratified folds' shuffle (the folds by visit have none).
    pub seed: u64,
}

/// A trained model and how well it cross-validates.
#[derive(Clone, Debug)]
pub struct Training {
    /// The fit on every observation.
    pub model: Fitted,
    /// Its options (shrinkage included).
    pub options: FitOptions,
    /// (candidate, cross-validated accuracy) when the shrinkage was chosen: None where the
    /// candidate's fit is not positive definite in some fold.
    pub shrinkage_scores: Vec<(f64, Option<f64>)>,
    /// k of the stratified k-fold cross-validation [`Training::cv`] reports.
    pub folds: usize,
    /// Stratified k-fold confusion.
    pub cv: Confusion,
    /// Leave-one-visit-out accuracy, when there are at least two visits.
    pub leave_one_visit_out: Option<f64>,
    /// The folds the shrinkage was chosen on (by visit, or stratified): learning curves reuse
    /// them.
    pub selection_folds: Vec<usize>,
    /// How the shrinkage was chosen.
    pub chosen_by: ChosenBy,
    /// Where the recipe changed because the data are too few (empty normally).
    pub fallbacks: Vec<Fallback>,
}

impl Training {
    /// What a training says beside its scores, as `et train`, the viewer's wizard and Python
    /// say it: each change of recipe ([`Training::fallbacks`]), then an accuracy no better than
    /// guessing ([`Confusion::no_better_than_guessing`]).
    #[must_use]
    pub fn notes(&self) -> Vec<String> {
        (self.fallbacks.iter().map(ToString::to_string))
            .chain(self.cv.no_better_than_guessing().map(|g| g.to_string()))
            .collect()
    }
}

/// How [`train`] chose the shrinkage.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ChosenBy {
    /// It was given.
    Given,
    /// Leave-one-visit-out cross-validation.
    LeaveOneVisitOut,
    /// Stratified k-fold cross-validation, with k folds (one visit, or leave-one-visit-out
    /// could not choose).
    KFold(usize),
}

impl std::fmt::Display for ChosenBy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ChosenBy::Given => write!(f, "given"),
            ChosenBy::LeaveOneVisitOut => write!(f, "chosen by leave-one-visit-out"),
            ChosenBy::KFold(k) => write!(f, "chosen by stratified {k}-fold"),
        }
    }
}

/// What [`train`] did differently from the usual recipe because the data are too few, said
/// aloud by `et train` and the report.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
#[serde(tag = "fallback", rename_all = "snake_case")]
pub enum Fallback {
    /// QDA shrinks toward the diagonal instead of the pooled covariance: some cross-validation
    /// fold trains on `rows` observations, too few for a pooled covariance of full rank
    /// (needs more than `features` + `classes`).
    DiagonalTarget {
        /// Fewest observations any fold trains on.
        rows: usize,
        /// p.
        features: usize,
        /// C.
        classes: usize,
    },
    /// The shrinkage was chosen by stratified k-fold instead of leave-one-visit-out, because no
    /// candidate fits on every visit's complement (`reason`).
    KFoldSelection {
        /// Why leave-one-visit-out could not choose (its text in JSON).
        #[serde(serialize_with = "as_text")]
        reason: VisitFault,
    },
    /// Leave-one-visit-out accuracy is not reported (`reason`).
    NoLeaveOneVisitOut {
        /// Why (its text in JSON).
        #[serde(serialize_with = "as_text")]
        reason: VisitFault,
    },
    /// QDA's chosen shrinkage was 1 toward the pooled covariance: every class has the pooled
    /// covariance, which is LDA (the same decisions); the LDA is what was fitted, C times
    /// smaller.
    QdaIsLda {
        /// C.
        classes: usize,
    },
}

/// Why leave-one-visit-out could not choose the shrinkage, or score the model.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum VisitFault {
    /// A fit on some visit's complement failed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// Every candidate failed on some visit's complement.
    #[error("no shrinkage candidate fits on one visit's complement")]
    NoCandidateFits,
}

fn as_text<S: serde::Serializer>(value: &impl std::fmt::Display, to: S) -> Result<S::Ok, S::Error> {
    to.collect_str(value)
}

impl std::fmt::Display for Fallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Fallback::DiagonalTarget {
                rows,
                features,
                classes,
            } => write!(
                f,
                "shrinking toward the diagonal, not the pooled covariance: a cross-validation fold \
                 trains on only {rows} observations, and a pooled covariance of {features} \
                 features over {classes} classes needs more than {}",
                features + classes
            ),
            Fallback::KFoldSelection { reason } => write!(
                f,
                "shrinkage chosen by stratified k-fold, not leave-one-visit-out ({reason}); \
                 k-fold mixes visits, so expect a new session to score lower than it says"
            ),
            Fallback::NoLeaveOneVisitOut { reason } => {
                write!(f, "no leave-one-visit-out accuracy ({reason})")
            }
            Fallback::QdaIsLda { classes } => write!(
                f,
                "qda's best shrinkage is 1 toward the pooled covariance: every class then has \
                 the pooled covariance, which is lda (the same decisions); saved the lda, one \
                 covariance instead of {classes}"
            ),
        }
    }
}

/// Fewest rows any fold of `fold` trains on (all of them outside the fold); `n` for no folds.
fn fewest_training_rows(fold: &[usize]) -> usize {
    let n = fold.len();
    let k = fold.iter().max().map_or(0, |&f| f + 1);
    let mut held = vec![0usize; k];
    for &f in fold {
        held[f] += 1;
    }
    held.iter().map(|&h| n - h).min().unwrap_or(n)
}

/// Fits a model on `data` (features already [`prepare`]d). QDA shrinks toward the pooled
/// covariance when that has full rank (n - C > p) in every fold it is cross-validated on, else
/// toward the diagonal, since a rank-deficient target cannot make a class covariance definite;
/// LDA toward the diagonal. The shrinkage is chosen by leave-one-visit-out when there are
/// several visits and some candidate fits on every visit's complement, else by stratified
/// k-fold; each such fallback is listed in [`Training::fallbacks`].
///
/// # Errors
/// [`FitError`] from fitting or cross-validation.
pub fn train(data: &Dataset, options: &TrainOptions) -> Result<Training, FitError> {
    train_reporting(data, options, |_| {})
}

/// A stage of [`train`], as it starts (for a progress display).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stage {
    /// Centring the data and each fold partition's sufficient statistics.
    Statistics,
    /// Cross-validating shrinkage candidate `index` (0-based) of `of`, by leave-one-visit-out
    /// or by k-fold when `by_visit` is false.
    Candidate {
        index: usize,
        of: usize,
        shrinkage: f64,
        by_visit: bool,
    },
    /// The final fit beside its k-fold and leave-one-visit-out cross-validations.
    Final,
}

impl Stage {
    /// The stage in words, for a progress display; `folds` the k of the k-fold
    /// cross-validation.
    #[must_use]
    pub fn said(self, folds: usize) -> String {
        match self {
            Self::Statistics => "each fold's statistics".to_string(),
            Self::Candidate {
                index,
                of,
                shrinkage,
                by_visit,
            } => format!(
                "choosing the shrinkage: {shrinkage} ({} of {of}), {}",
                index + 1,
                if by_visit {
                    "leave-one-visit-out".to_string()
                } else {
                    format!("{folds}-fold")
                }
            ),
            Self::Final => format!(
                "fitting the model beside its {folds}-fold and leave-one-visit-out \
                 cross-validations"
            ),
        }
    }
}

/// [`train`], calling `report` as each [`Stage`] starts.
///
/// # Errors
/// As [`train`].
pub fn train_reporting(
    data: &Dataset,
    options: &TrainOptions,
    mut report: impl FnMut(Stage),
) -> Result<Training, FitError> {
    let classes = data.centres.len();
    let (x, y) = (&data.x, &data.y);
    let p = x.ncols();
    let by_visit: Vec<usize> = data.visit.iter().map(|&v| usize::from(v)).collect();
    let several_visits = data.visits() >= 2;
    let strat = cv::folds(y, options.folds.max(2), options.seed);
    let mut fallbacks = Vec::new();
    let mut rows = fewest_training_rows(&strat);
    if several_visits {
        rows = rows.min(fewest_training_rows(&by_visit));
    }
    let target = shrinkage_target(options.kind, rows, x.nrows(), p, classes, &mut fallbacks);
    let base = FitOptions {
        kind: options.kind,
        shrinkage: 0.0,
        target,
    };
    // Centred once; each fold partition's sufficient statistics once, for every candidate
    // and for the final cross-validations.
    report(Stage::Statistics);
    let prepared = Prepared::new(x, y, classes)?;
    let strat_part = prepared.partition(&strat)?;
    let visit_part = several_visits.then(|| prepared.partition(&by_visit));
    let mut choose = |part: &Partition, by_visit: bool| match options.shrinkage {
        Some(l) => Ok((l, Vec::new())),
        None => {
            let mut index = 0;
            cv::choose_shrinkage_with(
                &SHRINKAGE_CANDIDATES,
                |o| {
                    report(Stage::Candidate {
                        index,
                        of: SHRINKAGE_CANDIDATES.len(),
                        shrinkage: o.shrinkage,
                        by_visit,
                    });
                    index += 1;
                    prepared.cross_validate(part, o)
                },
                &base,
            )
        }
    };
    // Leave-one-visit-out chooses when some candidate fits on every visit's complement (a
    // failing candidate scores None); otherwise stratified k-fold does.
    // None: one visit, nothing to choose by.
    let by_visit_choice = visit_part.as_ref().map(|part| {
        match part {
            Ok(part) => choose(part, true).map_err(VisitFault::from),
            Err(e) => Err(VisitFault::from(e.clone())),
        }
        .and_then(|(l, scores)| {
            if !scores.is_empty() && scores.iter().all(|&(_, a)| a.is_none()) {
                Err(VisitFault::NoCandidateFits)
            } else {
                Ok((l, scores))
            }
        })
    });
    let ((shrinkage, shrinkage_scores), selection_folds, chosen_by) = match by_visit_choice {
        Some(Ok(choice)) => (choice, by_visit.clone(), ChosenBy::LeaveOneVisitOut),
        failed => {
            if let Some(Err(reason)) = failed
                && options.shrinkage.is_none()
            {
                fallbacks.push(Fallback::KFoldSelection { reason });
            }
            let k = options.folds.max(2);
            (
                choose(&strat_part, false)?,
                strat.clone(),
                ChosenBy::KFold(k),
            )
        }
    };
    let chosen_by = if options.shrinkage.is_some() {
        ChosenBy::Given
    } else {
        chosen_by
    };
    let opts = if options.kind == ModelKind::Qda && target == Target::Pooled && shrinkage >= 1.0 {
        fallbacks.push(Fallback::QdaIsLda { classes });
        FitOptions {
            kind: ModelKind::Lda,
            shrinkage: 0.0,
            target: Target::Diagonal,
        }
    } else {
        FitOptions { shrinkage, ..base }
    };
    report(Stage::Final);
    let (model, cv, leave_one_visit_out) =
        fit_beside_scores(&prepared, data, &opts, &strat_part, visit_part.as_ref());
    let (model, cv) = (model?, cv?);
    let leave_one_visit_out = match leave_one_visit_out {
        Some(Ok(c)) => Some(c.accuracy()),
        Some(Err(e)) => {
            fallbacks.push(Fallback::NoLeaveOneVisitOut { reason: e.into() });
            None
        }
        None => None,
    };
    Ok(Training {
        model,
        options: opts,
        shrinkage_scores,
        folds: options.folds.max(2),
        cv,
        leave_one_visit_out,
        selection_folds,
        chosen_by,
        fallbacks,
    })
}

/// The covariance the class covariances shrink toward: QDA's pooled covariance when it has
/// full rank (more than `p` + `classes` rows) in the fold with the fewest training `rows`,
/// else the diagonal (noted in `fallbacks` when all `n` rows would have had full rank); LDA's
/// always the diagonal.
fn shrinkage_target(
    kind: ModelKind,
    rows: usize,
    n: usize,
    p: usize,
    classes: usize,
    fallbacks: &mut Vec<Fallback>,
) -> Target {
    if kind != ModelKind::Qda {
        Target::Diagonal
    } else if rows.saturating_sub(classes) > p {
        Target::Pooled
    } else {
        if n.saturating_sub(classes) > p {
            fallbacks.push(Fallback::DiagonalTarget {
                rows,
                features: p,
                classes,
            });
        }
        Target::Diagonal
    }
}

/// A fit and its cross-validations as [`train`] returns them: the model on every observation,
/// the stratified k-fold confusion, and the leave-one-visit-out confusion when there are visits.
type FitAndScores = (
    Result<Fitted, FitError>,
    Result<Confusion, FitError>,
    Option<Result<Confusion, FitError>>,
);

/// The final fit at `opts` on one thread while its k-fold (`strat`) and leave-one-visit-out
/// (`by_visit`) cross-validations use the others.
fn fit_beside_scores(
    prepared: &Prepared,
    data: &Dataset,
    opts: &FitOptions,
    strat: &Partition,
    by_visit: Option<&Result<Partition, FitError>>,
) -> FitAndScores {
    std::thread::scope(|scope| {
        let model = scope.spawn(|| Fitted::fit(&data.x, &data.y, data.centres.len(), opts));
        let cv = prepared.cross_validate(strat, opts);
        let lovo = by_visit.map(|part| match part {
            Ok(part) => prepared.cross_validate(part, opts),
            Err(e) => Err(e.clone()),
        });
        let model = model.join().unwrap_or(Err(FitError::Panicked));
        (model, cv, lovo)
    })
}
