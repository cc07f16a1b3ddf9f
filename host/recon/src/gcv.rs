//! The regularisation alpha by generalised cross-validation
//! (docs/method.md §6.3).

use nalgebra::DMatrix;

use crate::onestep::{DataSpace, ReconError};

/// The alphas automatic selection tries: 26 steps from 1e-4 to 10, five per decade (alpha is
/// dimensionless, normalised as in [`crate::onestep`]).
#[must_use]
pub fn default_alphas() -> Vec<f64> {
    (0..=25)
        .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
        .collect()
}

/// Generalised cross-validation of alpha for the frame difference `dv`: [`DataSpace::gcv`] on
/// a data space made for this call (keep a [`DataSpace`] to also build the matrix from it).
///
/// # Errors
/// [`ReconError`] for bad parameters, a zero Jacobian or a non-finite frame.
pub fn gcv_alpha(
    jac: &DMatrix<f64>,
    s: f64,
    dv: &[f64],
    candidates: &[f64],
) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
    if dv.len() != jac.nrows() {
        return Err(ReconError::Parameter(format!(
            "{} frame values for K = {}",
            dv.len(),
            jac.nrows()
        )));
    }
    DataSpace::new(jac, s)?.gcv(dv, candidates)
}
