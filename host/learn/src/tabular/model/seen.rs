//! A table model's note of the rows it was trained on, by their fingerprints
//! ([`crate::fingerprint`]).

use super::*;
use crate::fingerprint::{SEEN_SAID, seen_share};

impl TableModel {
    /// About what share of `x`'s rows (n x p, in the model's column order) are rows it was
    /// trained on: the share of its kept fingerprints found among `x`'s rows, times its
    /// training rows over `x`'s. None when the file keeps no fingerprints (files written
    /// before it did) or `x` has no rows.
    #[must_use]
    pub fn trained_share(&self, x: &DMatrix<f64>) -> Option<f64> {
        let trained = self.trained_rows[1].saturating_sub(self.trained_rows[0]) as f64;
        let share = seen_share(&self.seen, x)? * trained / x.nrows() as f64;
        Some(share.min(1.0))
    }

    /// What to say when more than [`SEEN_SAID`] of `x`'s rows are rows the model was trained
    /// on ([`trained_share`](Self::trained_share)); None otherwise.
    #[must_use]
    pub fn trained_note(&self, x: &DMatrix<f64>) -> Option<String> {
        let share = self.trained_share(x)?;
        (share > SEEN_SAID).then(|| {
            format!(
                "about {:.0} % of these rows are rows the model was trained on (rows {}..{} \
                 of its training files): their errors are the training's, lower than on rows \
                 it has not seen; evaluate on others (--rows on the command line) or another \
                 session's",
                100.0 * share,
                self.trained_rows[0],
                self.trained_rows[1]
            )
        })
    }
}
