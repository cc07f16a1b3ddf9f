//! A board model's test as `et eval --json` reports it, and the Python module too.

use super::board::Tested;
use crate::analysis::Band;

/// What a board model scored on a dataset (`et eval --data ... --json`). Field names are
/// fixed: scripts rely on them.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TestSummary<'a> {
    /// Observations tested.
    pub observations: u32,
    /// Share classified right.
    pub accuracy: f64,
    /// From the true press position to the predicted class's centre, mm (None when the
    /// dataset has no positions): the figure to compare with a regressor's.
    pub mean_error_mm: Option<f64>,
    /// Median of the same, mm.
    pub median_error_mm: Option<f64>,
    /// 90th percentile of the same, mm.
    pub p90_error_mm: Option<f64>,
    /// From the true class's centre to the predicted one's (0 when right), mm.
    pub mean_cell_error_mm: f64,
    /// The average euclidean error over the classes, mm.
    pub aee_mm: f64,
    /// Mean error per 10 mm band of distance from the electrodes.
    pub by_distance_from_electrodes: &'a [Band],
    /// Rows: true class; columns: predicted class.
    pub confusion: Vec<&'a [u32]>,
    /// What to say when the observations hold many the model was trained on.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub trained_note: Option<&'a str>,
    /// What to say when the observations are another scale than the training's (mV for V).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub scale_note: Option<&'a str>,
}

impl Tested {
    /// The summary of this test.
    #[must_use]
    pub fn summary(&self) -> TestSummary<'_> {
        let centres_mm = &self.centres_mm;
        let conf = &self.confusion;
        let mut from_truth = self.errors_from_truth_mm.clone();
        from_truth.sort_by(f64::total_cmp);
        let [mean, median, p90] = crate::regress::mean_median_p90(&from_truth);
        let known = !from_truth.is_empty();
        TestSummary {
            observations: conf.total(),
            accuracy: conf.accuracy(),
            mean_error_mm: known.then_some(mean),
            median_error_mm: known.then_some(median),
            p90_error_mm: known.then_some(p90),
            mean_cell_error_mm: conf.mean_position_error(centres_mm),
            aee_mm: conf.aee(centres_mm),
            by_distance_from_electrodes: &self.bands,
            confusion: conf.counts.chunks(conf.classes.max(1)).collect(),
            trained_note: self.trained_note.as_deref(),
            scale_note: self.scale_note.as_deref(),
        }
    }
}
