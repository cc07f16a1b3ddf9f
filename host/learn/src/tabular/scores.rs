//! What a table model's cross-validation said, as `et train --json` prints it and Python's
//! `Model.scores` gives it.

use super::*;

/// A table model's cross-validated scores (errors mm, accuracies fractions).
#[derive(Clone, Debug, Serialize)]
pub struct TableScores<'a> {
    /// The method chosen.
    pub method: Kind,
    /// Its hyperparameters.
    pub hyperparameters: &'a BTreeMap<String, f64>,
    /// Folds of the cross-validation (groups: one per group).
    pub cv_folds: usize,
    /// Shuffled or contiguous blocks.
    pub cv_scheme: CvScheme,
    /// The chosen candidate's cross-validated mean position error, mm (positions).
    pub cv_mean_error_mm: Option<f64>,
    /// Its cross-validated accuracy (classes).
    pub cv_accuracy: Option<f64>,
    /// Its cross-validated error with the held-out rows' channels drifted, mm (regressors).
    pub cv_drifted_error_mm: Option<f64>,
    /// Whether positions were chosen by the error and the drifted error together.
    pub chosen_by_drift: bool,
    /// Every candidate tried, with its scores.
    pub candidates: &'a [Candidate],
    /// The training rows (0-based, half open, in the files).
    pub rows: [usize; 2],
    /// Features each row has.
    pub features: usize,
    /// Classes (a classifier).
    pub classes: Option<usize>,
    /// What the training changed from the request or found in the data.
    pub note: Option<&'a str>,
}

impl TableModel {
    /// What cross-validation said of this model and of every candidate it was chosen from.
    #[must_use]
    pub fn scores(&self) -> TableScores<'_> {
        let best = self.chosen();
        TableScores {
            method: self.method,
            hyperparameters: &self.hyperparameters,
            cv_folds: self.cv_folds,
            cv_scheme: self.cv_scheme,
            cv_mean_error_mm: best.and_then(|b| b.cv_mean_error_mm),
            cv_accuracy: best.and_then(|b| b.cv_accuracy),
            cv_drifted_error_mm: best.and_then(|b| b.cv_drifted_error_mm),
            chosen_by_drift: self.chosen_by_drift,
            candidates: &self.search,
            rows: self.trained_rows,
            features: self.features(),
            classes: self.classes.as_ref().map(|c| c.names.len()),
            note: self.note.as_deref(),
        }
    }
}
