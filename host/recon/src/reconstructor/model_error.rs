//! The model's error a fitted background shows in the reference frame, by kind of value (on a
//! drive electrode or off), and how a frame's values are weighted in the fit.

use et_core::schedule::Row;

use crate::onestep::ReconError;

/// How much of a frame's change the model's mismatch with a real sheet may explain, as a
/// multiple of the share of the reference frame V_0 the fitted background leaves unexplained
/// (per kind of value: on a drive electrode, off one). A difference image meets the model's
/// error twice (the frame's and the reference's), and the linearisation adds to it; on two
/// real tanks 1.5 and 2 are equally good, 1 and 3 each lose a count on one of them
/// (docs/measurements.md, "Defaults on real tanks").
pub const MISMATCH_FACTOR: f64 = 2.0;

/// How the values of a frame are weighted in the fit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Weighting {
    /// Alike (the default: the measured best on real tanks, docs/measurements.md).
    #[default]
    Alike,
    /// By the inverse of the mean square the fitted background leaves of their kind's values
    /// in the reference (on a drive electrode or off).
    PerKind,
    /// By 1 / V_0^2: the normalised difference dV / V_0 (as EIDORS offers it).
    Normalised,
}

impl Weighting {
    /// The weighting a user's text names: "alike", "kind" or "normalised".
    ///
    /// # Errors
    /// [`ReconError::UnknownName`] for other text.
    pub fn from_text(text: &str) -> Result<Self, ReconError> {
        match text {
            "alike" => Ok(Self::Alike),
            "kind" => Ok(Self::PerKind),
            "normalised" | "normalized" => Ok(Self::Normalised),
            other => Err(ReconError::UnknownName {
                what: "weights",
                given: other.to_string(),
                choices: "alike, kind or normalised",
            }),
        }
    }
}

/// What the fitted background leaves of the reference, by kind of value.
pub(super) struct Mismatch {
    /// Each value's kind's share of V_0 left unexplained.
    pub(super) shares: Vec<f64>,
    /// |V_0 - V(fit)| / |V_0| over the values on drive electrodes (None: there are none).
    pub(super) on_drive: Option<f64>,
    /// The same over the values off them.
    pub(super) off_drive: Option<f64>,
}

/// The model's mismatch with the reference `v0` (K values, V) by kind of value (on a drive
/// electrode or off), the fitted background's frame being `model`; and each value's weight
/// under `weighting`.
pub(super) fn mismatch_and_weights(
    rows: &[Row],
    v0: &[f64],
    model: &[f64],
    weighting: Weighting,
) -> (Mismatch, Option<Vec<f64>>) {
    // (sum of squared misfits, sum of squares of V_0, values) per kind.
    let mut kinds = [(0.0, 0.0, 0usize); 2];
    for ((row, v), m) in rows.iter().zip(v0).zip(model) {
        let kind = &mut kinds[usize::from(row.on_drive().is_some())];
        kind.0 += (v - m).powi(2);
        kind.1 += v * v;
        kind.2 += 1;
    }
    let share = |(r2, v2, n): (f64, f64, usize)| (n > 0 && v2 > 0.0).then(|| (r2 / v2).sqrt());
    let (off, on) = (share(kinds[0]), share(kinds[1]));
    let shares = rows
        .iter()
        .map(|row| {
            let kind = if row.on_drive().is_some() { on } else { off };
            kind.unwrap_or(0.0)
        })
        .collect();
    let mean_square = |(r2, _, n): (f64, f64, usize)| r2 / n.max(1) as f64;
    let weights = match weighting {
        Weighting::Alike => None,
        Weighting::PerKind => {
            let ms = [mean_square(kinds[0]), mean_square(kinds[1])];
            (ms.iter().all(|m| *m > 0.0)).then(|| {
                rows.iter()
                    .map(|row| 1.0 / ms[usize::from(row.on_drive().is_some())])
                    .collect()
            })
        }
        Weighting::Normalised => {
            (v0.iter().all(|v| *v != 0.0)).then(|| v0.iter().map(|v| 1.0 / (v * v)).collect())
        }
    };
    (
        Mismatch {
            shares,
            on_drive: on,
            off_drive: off,
        },
        weights,
    )
}
