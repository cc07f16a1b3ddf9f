//! Which rows a model was trained on, by a sample of their fingerprints: rows evaluated that
//! are training rows score the training's error, lower than a new session's, without a word.
//! Table models and board models keep them (`seen` in their files); this module depends on
//! nothing else of the crate's, so both files' checks can use it.

use nalgebra::DMatrix;

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

/// A fingerprint a model file keeps that is not one et writes (16 hex digits, at most
/// [`SEEN_SAMPLE`] of them): an edited one was skipped, and silenced the note it makes.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "seen[{index}]: '{value}' is not a training row's fingerprint (16 hex digits, at most \
     {SEEN_SAMPLE} of them)"
)]
pub struct SeenError {
    /// Its index.
    pub index: usize,
    /// What it holds (its first 40 characters).
    pub value: String,
}

/// Checks `seen` as [`seen_sample`] writes it.
///
/// # Errors
/// [`SeenError`] at the first that is not.
pub fn check_seen(seen: &[String]) -> Result<(), SeenError> {
    let fingerprint = |h: &String| h.len() == 16 && u64::from_str_radix(h, 16).is_ok();
    match (seen.iter().enumerate()).find(|&(i, h)| i >= SEEN_SAMPLE || !fingerprint(h)) {
        Some((index, value)) => Err(SeenError {
            index,
            value: value.chars().take(40).collect(),
        }),
        None => Ok(()),
    }
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
