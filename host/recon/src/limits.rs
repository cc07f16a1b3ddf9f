//! The domain of every number a reconstruction is set up with, in one place: the command
//! line's flags parse against these and [`crate::Spec::check`] (run by every set-up) holds the
//! Python module and every other caller to them, naming the value and what it must be.

use std::ops::RangeInclusive;

use crate::ReconError;

/// About how many triangles a sheet is meshed with (`--triangles`, `triangles=`): fewer
/// cannot place a touch; more take minutes and gigabytes to set up.
pub const TRIANGLES: RangeInclusive<usize> = 20..=500_000;

/// Gauss-Newton iterations (`--iterations`, `iterations=`): 1 is the one-step
/// reconstruction.
pub const ITERATIONS: RangeInclusive<usize> = 1..=100;

/// Pixels across an image (`--pixels`, `pixels=`).
pub const PIXELS: RangeInclusive<usize> = 4..=crate::imager::MAX_PIXELS;

/// GREIT's noise figure (`--noise-figure`, `noise_figure=`): above 0, at most this.
pub const MAX_NOISE_FIGURE: f64 = 100.0;

/// GREIT's desired image radius, m (`--radius-mm`, `radius_m=`): above 0, at most this (and
/// at most half the sheet, checked with the sheet).
pub const MAX_RADIUS_M: f64 = 1.0;

/// A fixed alpha (`--alpha`, `alpha=`): above 0, at most this (alpha is dimensionless,
/// lambda = alpha^2 tr(A) / K; the automatic rules try 1e-4 to 10).
pub const MAX_ALPHA: f64 = 1e6;

/// The most values a frame may have (K, the protocol's rows): the reconstruction keeps
/// A = J P^-1 J^T, K x K, 2.1 GB at this K (a 100 000-row protocol would ask for 80 GB).
pub const MAX_FRAME_LEN: usize = 16_384;

/// Timed repeats of one frame ([`crate::Reconstructor::frame_median`], `repeats=`).
pub const REPEATS: RangeInclusive<usize> = 1..=100_000;

/// `value` named `name` within `range`, else [`ReconError::CountOutOfRange`] saying so.
///
/// # Errors
/// [`ReconError::CountOutOfRange`].
pub fn count(
    name: &'static str,
    value: usize,
    range: &RangeInclusive<usize>,
) -> Result<(), ReconError> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(ReconError::CountOutOfRange {
            name,
            value,
            lo: *range.start(),
            hi: *range.end(),
        })
    }
}

/// `value` named `name` finite, above `lo` (or from it when `from`), at most `hi`.
///
/// # Errors
/// [`ReconError::OutOfRange`] naming the range.
pub fn real(
    name: &'static str,
    value: f64,
    lo: f64,
    from: bool,
    hi: f64,
    range: &'static str,
) -> Result<(), ReconError> {
    let low = if from { value >= lo } else { value > lo };
    if value.is_finite() && low && value <= hi {
        Ok(())
    } else {
        Err(ReconError::OutOfRange { name, value, range })
    }
}
