//! Evaluation (docs/method.md §9): stratified k-fold cross-validation, the confusion matrix, accuracy,
//! the average Euclidean error AEE [5.9-5.11] and the plain mean position error.

use nalgebra::DMatrix;

use super::fit::{FitError, FitOptions, Fitted};

/// Counts of (true class, predicted class).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Confusion {
    /// Class count C.
    pub classes: usize,
    /// `counts[t * C + p]`: observations of true class t predicted as p.
    pub counts: Vec<u32>,
}

impl Confusion {
    /// An empty C x C matrix.
    #[must_use]
    pub fn new(classes: usize) -> Self {
        Self {
            classes,
            counts: vec![0; classes * classes],
        }
    }

    /// Counts one prediction.
    pub fn add(&mut self, truth: u16, predicted: u16) {
        self.counts[usize::from(truth) * self.classes + usize::from(predicted)] += 1;
    }

    /// Adds another matrix's counts (same class count).
    ///
    /// # Panics
    /// If the class counts differ.
    pub fn merge(&mut self, other: &Confusion) {
        assert_eq!(
            self.classes, other.classes,
            "confusion matrices of different sizes"
        );
        for (a, b) in self.counts.iter_mut().zip(&other.counts) {
            *a += b;
        }
    }

    /// Observations counted.
    #[must_use]
    pub fn total(&self) -> u32 {
        self.counts.iter().sum()
    }

    /// Fraction predicted right.
    #[must_use]
    pub fn accuracy(&self) -> f64 {
        let right: u32 = (0..self.classes)
            .map(|c| self.counts[c * self.classes + c])
            .sum();
        f64::from(right) / f64::from(self.total().max(1))
    }

    /// Observations of each true class.
    #[must_use]
    pub fn class_counts(&self) -> Vec<usize> {
        (self.counts.chunks(self.classes.max(1)))
            .map(|row| row.iter().map(|&c| c as usize).sum())
            .collect()
    }

    /// Whether the accuracy is no better than always guessing the commonest class
    /// ([`crate::guess::classes`]).
    #[must_use]
    pub fn no_better_than_guessing(&self) -> Option<crate::guess::NoBetter> {
        crate::guess::classes(self.accuracy(), &self.class_counts())
    }

    /// AEE [5.10-5.11]: for each true class tr, EE_tr = sum over predicted c != tr of
    /// d(tr, c) n_pred(c); AEE = sum_tr EE_tr / C. Units of `positions` (mm).
    #[must_use]
    pub fn aee(&self, positions: &[[f64; 2]]) -> f64 {
        let c_n = self.classes;
        let ee: f64 = (0..c_n)
            .map(|tr| {
                (0..c_n)
                    .filter(|&c| c != tr)
                    .map(|c| {
                        dist(positions[tr], positions[c]) * f64::from(self.counts[tr * c_n + c])
                    })
                    .sum::<f64>()
            })
            .sum();
        ee / c_n as f64
    }

    /// Mean distance between the true and the predicted class centre per prediction (units of
    /// `positions`).
    #[must_use]
    pub fn mean_position_error(&self, positions: &[[f64; 2]]) -> f64 {
        let c_n = self.classes;
        let sum: f64 = (0..c_n)
            .flat_map(|t| (0..c_n).map(move |p| (t, p)))
            .map(|(t, p)| dist(positions[t], positions[p]) * f64::from(self.counts[t * c_n + p]))
            .sum();
        sum / f64::from(self.total().max(1))
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Predicts every observation (row of `x`) with `model` and counts it against its label.
///
/// # Errors
/// [`FitError::FeatureCount`] if `x` does not have the model's feature count, [`FitError::Counts`] or [`FitError::Label`] if rows and labels differ
/// in number, or a label is not one of the model's classes.
pub fn evaluate(model: &Fitted, x: &DMatrix<f64>, y: &[u16]) -> Result<Confusion, FitError> {
    confusion_of(model.classes.len(), y, &predict_rows(model, x)?)
}

/// The model's class for every observation (row of `x`).
///
/// # Errors
/// [`FitError::FeatureCount`] if `x` does not have the model's feature count,
/// [`FitError::Discriminants`] for a row whose discriminants are not all finite.
pub fn predict_rows(model: &Fitted, x: &DMatrix<f64>) -> Result<Vec<u16>, FitError> {
    if x.ncols() != model.features() {
        return Err(FitError::FeatureCount {
            got: x.ncols(),
            expected: model.features(),
        });
    }
    let mut row = vec![0.0; x.ncols()];
    (0..x.nrows())
        .map(|r| {
            for (j, v) in row.iter_mut().enumerate() {
                *v = x[(r, j)];
            }
            model
                .predict_finite(&row)
                .ok_or(FitError::Discriminants { row: r })
        })
        .collect()
}

/// Counts `predicted` against the labels `y` (one each, labels in 0..classes).
///
/// # Errors
/// [`FitError::Counts`] if they differ in number, [`FitError::Label`] if a label is not one of the classes.
pub fn confusion_of(classes: usize, y: &[u16], predicted: &[u16]) -> Result<Confusion, FitError> {
    if predicted.len() != y.len() {
        return Err(FitError::Counts {
            what: "labels",
            got: y.len(),
            expected: predicted.len(),
            of: "observations",
        });
    }
    let mut confusion = Confusion::new(classes);
    for (r, (&label, &p)) in y.iter().zip(predicted).enumerate() {
        if usize::from(label) >= classes {
            return Err(FitError::Label {
                row: r,
                label: usize::from(label),
                classes,
            });
        }
        confusion.add(label, p);
    }
    Ok(confusion)
}

/// Stratified fold of every observation: within each class, observations are dealt to folds
/// 0..k in a shuffled (seeded) order, so every fold holds about 1/k of every class.
#[must_use]
pub fn folds(y: &[u16], k: usize, seed: u64) -> Vec<usize> {
    let mut rng = et_core::rng::Rng::new(seed);
    let classes = y.iter().map(|&c| usize::from(c) + 1).max().unwrap_or(0);
    let mut fold = vec![0; y.len()];
    for c in 0..classes {
        let mut rows: Vec<usize> = (0..y.len()).filter(|&r| usize::from(y[r]) == c).collect();
        for i in (1..rows.len()).rev() {
            let j = (rng.next_u64() % (i as u64 + 1)) as usize;
            rows.swap(i, j);
        }
        for (i, r) in rows.into_iter().enumerate() {
            fold[r] = i % k.max(1);
        }
    }
    fold
}

/// Cross-validation over given folds: for each fold f, fits on the other folds and predicts
/// fold f. With `fold` = the visit of each observation this is leave-one-visit-out, which
/// measures what a new session (electrodes moved) will see.
///
/// # Errors
/// The first [`FitError`].
pub fn cross_validate_folds(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
    opts: &FitOptions,
    fold: &[usize],
) -> Result<Confusion, FitError> {
    let k = fold_count(fold, y.len())?;
    let mut confusion = Confusion::new(classes);
    for f in 0..k {
        let train: Vec<usize> = (0..y.len()).filter(|&r| fold[r] != f).collect();
        let test: Vec<usize> = (0..y.len()).filter(|&r| fold[r] == f).collect();
        if test.is_empty() {
            continue;
        }
        let xt = DMatrix::from_fn(train.len(), x.ncols(), |i, j| x[(train[i], j)]);
        let yt: Vec<u16> = train.iter().map(|&r| y[r]).collect();
        let model = Fitted::fit(&xt, &yt, classes, opts)?;
        let mut row = vec![0.0; x.ncols()];
        for &r in &test {
            for (j, v) in row.iter_mut().enumerate() {
                *v = x[(r, j)];
            }
            confusion.add(y[r], model.predict(&row));
        }
    }
    Ok(confusion)
}

/// The number of folds in `fold` (one entry per observation, values 0..k).
///
/// # Errors
/// [`FitError::Counts`] if `fold` is not one entry per observation, [`FitError::TooFewFolds`] if it holds fewer than 2 folds.
pub(crate) fn fold_count(fold: &[usize], n: usize) -> Result<usize, FitError> {
    if fold.len() != n {
        return Err(FitError::Counts {
            what: "fold assignments",
            got: fold.len(),
            expected: n,
            of: "observations",
        });
    }
    let k = fold.iter().max().map_or(0, |m| m + 1);
    if k < 2 {
        return Err(FitError::TooFewFolds(k));
    }
    Ok(k)
}

/// The shrinkage chosen, and every candidate's (shrinkage, cross-validated accuracy): None
/// where the candidate's fit is not positive definite in some fold.
pub type ShrinkageChoice = (f64, Vec<(f64, Option<f64>)>);

/// The shrinkage among `candidates` with the best cross-validated accuracy over `fold`
/// (ties: the first), with every candidate's accuracy: None for a candidate whose fit is not
/// positive definite in some fold (when none fits, the first is returned, and its fit says
/// why).
///
/// # Errors
/// [`FitError::NoCandidates`] for no candidates, [`FitError::Counts`] or [`FitError::TooFewFolds`] for bad folds.
pub fn choose_shrinkage(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
    base: &FitOptions,
    candidates: &[f64],
    fold: &[usize],
) -> Result<ShrinkageChoice, FitError> {
    choose_shrinkage_with(
        candidates,
        |o| cross_validate_folds(x, y, classes, o, fold),
        base,
    )
}

/// [`choose_shrinkage`] with any cross-validation (e.g. [`super::fastcv::cross_validate_fast`]).
///
/// # Errors
/// [`FitError::NoCandidates`] for no candidates; the first error other than a singular fit.
pub fn choose_shrinkage_with(
    candidates: &[f64],
    mut validate: impl FnMut(&FitOptions) -> Result<Confusion, FitError>,
    base: &FitOptions,
) -> Result<ShrinkageChoice, FitError> {
    let mut scores = Vec::new();
    for &lambda in candidates {
        let opts = FitOptions {
            shrinkage: lambda,
            ..*base
        };
        let acc = match validate(&opts) {
            Ok(c) => Some(c.accuracy()),
            Err(FitError::NotPositiveDefinite { .. }) => None,
            Err(e) => return Err(e),
        };
        scores.push((lambda, acc));
    }
    let first = candidates
        .first()
        .copied()
        .ok_or(FitError::NoCandidates("no shrinkage candidates"))?;
    let best = scores
        .iter()
        .filter_map(|&(lambda, acc)| Some((lambda, acc?)))
        .fold(None, |best: Option<(f64, f64)>, s| match best {
            Some(b) if b.1 >= s.1 => Some(b),
            _ => Some(s),
        })
        .map_or(first, |b| b.0);
    Ok((best, scores))
}

/// k-fold stratified cross-validation: fits on k-1 folds, predicts the held-out one, k times.
///
/// # Errors
/// The first fold's [`FitError`] (e.g. a class with no observation outside the held-out fold).
pub fn cross_validate(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
    opts: &FitOptions,
    k: usize,
    seed: u64,
) -> Result<Confusion, FitError> {
    if k < 2 {
        return Err(FitError::TooFewFolds(k));
    }
    cross_validate_folds(x, y, classes, opts, &folds(y, k, seed))
}
