//! Which rows a model was trained on, by a sample of their fingerprints: rows evaluated that
//! are training rows score the training's error, lower than a new session's, without a word.

use super::*;

/// Training rows whose fingerprints a model keeps, evenly spaced: enough to tell the share of
/// training rows among evaluated ones to a few per cent, in 19 kB of the model file.
pub const SEEN_SAMPLE: usize = 1000;

/// The share of evaluated rows past which they are said to be training rows.
pub const SEEN_SAID: f64 = 0.1;

/// A row's fingerprint: FNV-1a over its values' bits (the same file read twice gives the same
/// values, and so the same fingerprint).
fn fingerprint(row: impl Iterator<Item = f64>) -> u64 {
    row.flat_map(f64::to_le_bytes)
        .fold(0xcbf2_9ce4_8422_2325, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
        })
}

/// The fingerprints (16 hex digits each) of up to [`SEEN_SAMPLE`] rows of `x` (n x p, the
/// features as the model reads them), evenly spaced.
#[must_use]
pub fn seen_sample(x: &DMatrix<f64>) -> Vec<String> {
    let n = x.nrows();
    let step = n.div_ceil(SEEN_SAMPLE).max(1);
    (0..n)
        .step_by(step)
        .map(|r| format!("{:016x}", fingerprint(x.row(r).iter().copied())))
        .collect()
}

/// The share of `seen` (fingerprints from [`seen_sample`]) found among the rows of `x`
/// (n x p, the features as the model reads them): about the share of the training rows
/// these rows hold. None when `seen` is empty (files written before it was kept) or `x` has
/// no rows.
#[must_use]
pub fn seen_share(seen: &[String], x: &DMatrix<f64>) -> Option<f64> {
    if seen.is_empty() || x.nrows() == 0 {
        return None;
    }
    // Every row, not a sample: the evaluated rows may hold the training's anywhere.
    let rows: std::collections::HashSet<u64> = (0..x.nrows())
        .map(|r| fingerprint(x.row(r).iter().copied()))
        .collect();
    let found = (seen.iter())
        .filter(|h| u64::from_str_radix(h, 16).is_ok_and(|h| rows.contains(&h)))
        .count();
    Some(found as f64 / seen.len() as f64)
}

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
                 it has not seen; evaluate on rows it has not seen (--rows on the command line) or another session's",
                100.0 * share,
                self.trained_rows[0],
                self.trained_rows[1]
            )
        })
    }
}
