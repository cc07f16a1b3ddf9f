//! The regularisation alpha by generalised cross-validation
//! (docs/method.md §6.3).

use nalgebra::{DMatrix, DVector};

use crate::onestep::{ReconError, data_space};

/// The alphas automatic selection tries: 26 steps from 1e-4 to 10, five per decade (alpha is
/// dimensionless, normalised as in [`crate::onestep`]).
#[must_use]
pub fn default_alphas() -> Vec<f64> {
    (0..=25)
        .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
        .collect()
}

/// Generalised cross-validation of alpha for the frame difference `dv` (docs/method.md (6.1)):
/// with A = J P^-1 J^T = U diag(e) U^T and c = U^T dv, GCV(lambda) = K sum_i (lambda c_i /
/// (e_i + lambda))^2 / (sum_i lambda / (e_i + lambda))^2, lambda = alpha^2 tr(A) / K (the
/// normalisation of [`crate::onestep`]). Returns the candidate with the smallest GCV and
/// every (alpha, GCV).
///
/// # Errors
/// [`ReconError`] for bad parameters, a zero Jacobian or a non-finite frame.
pub fn gcv_alpha(
    jac: &DMatrix<f64>,
    s: f64,
    dv: &[f64],
    candidates: &[f64],
) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
    if !(0.0..=1.0).contains(&s) || dv.len() != jac.nrows() || candidates.is_empty() {
        return Err(ReconError::Parameter(
            "s in [0, 1], K frame values, candidates".into(),
        ));
    }
    if dv.iter().any(|v| !v.is_finite()) {
        return Err(ReconError::NonFinite);
    }
    let (_, a) = data_space(jac, s)?;
    let k = a.nrows() as f64;
    let trace = a.trace();
    let eig = a.symmetric_eigen();
    let c = eig.eigenvectors.transpose() * DVector::from_column_slice(dv);
    let scores: Vec<(f64, f64)> = candidates
        .iter()
        .map(|&alpha| {
            let lambda = alpha * alpha * trace / k;
            let (mut num, mut den) = (0.0, 0.0);
            for (e, ci) in eig.eigenvalues.iter().zip(c.iter()) {
                let w = lambda / (e.max(0.0) + lambda);
                num += (w * ci).powi(2);
                den += w;
            }
            (alpha, k * num / (den * den).max(f64::MIN_POSITIVE))
        })
        .collect();
    let best = scores
        .iter()
        .copied()
        .filter(|s| s.1.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or(ReconError::Singular)?;
    Ok((best.0, scores))
}
