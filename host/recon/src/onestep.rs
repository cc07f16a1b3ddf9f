//! One-step linearised Gauss-Newton difference imaging with the NOSER prior
//! (docs/method.md §6).
//!
//! With J the Jacobian at the background sigma_0 (K x T, [`crate::fem::Forward::jacobian`]) and
//! the NOSER prior P = diag(J^T J)^s (6.3), the Tikhonov solution (6.2)
//!
//! ```text
//! d_sigma = (J^T J + lambda P)^-1 J^T dV = P^-1 J^T (J P^-1 J^T + lambda I)^-1 dV
//! ```
//!
//! is computed in its data-space form on the right (P is diagonal, so only a K x K system is
//! factorised). **Normalisation of alpha:** lambda = alpha^2 tr(J P^-1 J^T) / K, so alpha is
//! dimensionless and means the same for any mesh, current or protocol (alpha = 1: the
//! regularisation is as large as the average data-space eigenvalue). The reconstruction matrix
//! R (T x K) is built once; each frame then costs one matrix-vector product, onto the mesh or
//! (cheaper) onto a pixel grid ([`crate::pixels::PixelGrid`]).

use nalgebra::{DMatrix, DVector};

/// Why a reconstruction could not be set up or run.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum ReconError {
    /// A parameter out of range (alpha not finite or <= 0, s outside [0, 1], wrong lengths).
    Parameter(String),
    /// The data-space system is not positive definite (a Jacobian with NaN, or all zero).
    Singular,
    /// A frame holds NaN or infinite values.
    NonFinite,
}

impl std::fmt::Display for ReconError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReconError::Parameter(why) => write!(f, "reconstruction: {why}"),
            ReconError::Singular => write!(f, "reconstruction: the regularised system is singular"),
            ReconError::NonFinite => write!(f, "reconstruction: a frame value is NaN or infinite"),
        }
    }
}

impl std::error::Error for ReconError {}

/// The one-step Gauss-Newton reconstruction matrix of one (mesh, protocol, alpha, s).
#[derive(Clone, Debug)]
pub struct OneStep {
    /// T x K: d_sigma = R dV.
    pub matrix: DMatrix<f64>,
    /// The alpha it was built with.
    pub alpha: f64,
    /// The NOSER exponent s.
    pub s: f64,
}

impl OneStep {
    /// Builds R from the Jacobian `jac` (K x T).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for alpha not in (0, inf) or s not in [0, 1];
    /// [`ReconError::Singular`] when the system cannot be factorised.
    pub fn new(jac: &DMatrix<f64>, alpha: f64, s: f64) -> Result<Self, ReconError> {
        if !(alpha.is_finite() && alpha > 0.0) {
            return Err(ReconError::Parameter(format!(
                "alpha = {alpha}: must be finite and > 0"
            )));
        }
        if !(0.0..=1.0).contains(&s) {
            return Err(ReconError::Parameter(format!("s = {s}: must be in [0, 1]")));
        }
        if jac.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let (jp, a) = data_space(jac, s)?;
        let chol = regularised(a, alpha)?;
        // R = P^-1 J^T (A + lambda I)^-1 = ((A + lambda I)^-1 J P^-1)^T.
        let x = chol.solve(&jp);
        let matrix = x.transpose();
        if matrix.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        Ok(Self { matrix, alpha, s })
    }

    /// d_sigma on the mesh's triangles for the frame difference `dv` = V_1 - V_0 (K values).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
    pub fn reconstruct(&self, dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if dv.len() != self.matrix.ncols() {
            return Err(ReconError::Parameter(format!(
                "{} values, the protocol has K = {}",
                dv.len(),
                self.matrix.ncols()
            )));
        }
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        Ok((&self.matrix * DVector::from_column_slice(dv))
            .as_slice()
            .to_vec())
    }

    /// The standard deviation of each triangle's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2): [`noise_sd`] of the matrix. Same units as an image.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for a wrong length.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if var_dv.len() != self.matrix.ncols() {
            return Err(ReconError::Parameter(format!(
                "{} variances, the protocol has K = {}",
                var_dv.len(),
                self.matrix.ncols()
            )));
        }
        Ok(noise_sd(&self.matrix, var_dv))
    }
}

/// The noise each row of a reconstruction matrix `r` (rows x K: triangles, or pixels of a
/// projection) carries when dV has independent noise of variance `var_dv` per channel (V^2,
/// [`et_core::stats::dv_variance`]): sqrt(sum_k R_tk^2 var_k), in the image's units. Extra
/// channels on either side are ignored; negative variances count as 0.
#[must_use]
pub fn noise_sd<T: nalgebra::Scalar + Copy + Into<f64>>(
    r: &DMatrix<T>,
    var_dv: &[f64],
) -> Vec<f64> {
    r.row_iter()
        .map(|row| {
            row.iter()
                .zip(var_dv)
                .map(|(&p, v)| {
                    let p: f64 = p.into();
                    p * p * v.max(0.0)
                })
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// J P^-1 (K x T) and A = J P^-1 J^T (K x K) for the NOSER prior of exponent `s`.
pub(crate) fn data_space(
    jac: &DMatrix<f64>,
    s: f64,
) -> Result<(DMatrix<f64>, DMatrix<f64>), ReconError> {
    let p_inv = noser_inverse(jac, s).ok_or(ReconError::Singular)?;
    let jp = DMatrix::from_fn(jac.nrows(), jac.ncols(), |r, c| jac[(r, c)] * p_inv[c]);
    let a = &jp * jac.transpose();
    Ok((jp, a))
}

/// The Cholesky factor of A + lambda I, lambda = alpha^2 tr(A) / K (the module's
/// normalisation).
pub(crate) fn regularised(
    mut a: DMatrix<f64>,
    alpha: f64,
) -> Result<nalgebra::Cholesky<f64, nalgebra::Dyn>, ReconError> {
    let k = a.nrows();
    let lambda = alpha * alpha * a.trace() / k as f64;
    for i in 0..k {
        a[(i, i)] += lambda;
    }
    a.cholesky().ok_or(ReconError::Singular)
}

/// The NOSER weights P^-1 = diag(J^T J)^-s (a column that sees nothing gets the smallest
/// positive weight's), or None when every column is zero.
fn noser_inverse(jac: &DMatrix<f64>, s: f64) -> Option<Vec<f64>> {
    let diag: Vec<f64> = (0..jac.ncols())
        .map(|c| jac.column(c).norm_squared())
        .collect();
    let floor = diag
        .iter()
        .copied()
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    floor
        .is_finite()
        .then(|| diag.iter().map(|d| d.max(floor).powf(-s)).collect())
}

#[cfg(test)]
mod tests;
