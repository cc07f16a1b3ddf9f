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

use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::solvers::{Llt, SolveCore};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
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
    /// Iterative Gauss-Newton found no step that lowers its objective at this iteration
    /// (the linearisation does not describe the data: a smaller alpha than the data bear, or
    /// a model far from the sheet).
    NoDescent {
        /// The iteration (0-based).
        iteration: usize,
    },
}

impl std::fmt::Display for ReconError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReconError::Parameter(why) => write!(f, "reconstruction: {why}"),
            ReconError::Singular => write!(f, "reconstruction: the regularised system is singular"),
            ReconError::NonFinite => write!(f, "reconstruction: a frame value is NaN or infinite"),
            ReconError::NoDescent { iteration } => write!(
                f,
                "iterative Gauss-Newton: no step lowers the misfit at iteration {iteration}; \
                 try a larger alpha"
            ),
        }
    }
}

impl std::error::Error for ReconError {}

/// The data-space quantities of one (Jacobian, NOSER exponent s), computed once and shared by
/// alpha's automatic choice ([`DataSpace::gcv`]) and the reconstruction matrix
/// ([`DataSpace::one_step`]): J P^-1 (K x T) and A = J P^-1 J^T (K x K). Built with BLAS-3
/// kernels (faer): A as a symmetric rank-T update of its lower triangle, R by a Cholesky
/// factorisation of A + lambda I and a blocked triangular solve on J P^-1; no inverse is formed.
#[derive(Clone, Debug)]
pub struct DataSpace {
    /// J P^-1, K x T (V per S/sq, divided by the prior).
    jp: Mat<f64>,
    /// A = J P^-1 J^T, K x K (lower triangle filled; upper mirrored).
    a: Mat<f64>,
    /// tr(A), V^2 per (S/sq)^2 (the scale of lambda).
    trace: f64,
    /// The NOSER exponent s.
    s: f64,
    /// The prior's diagonal P = diag(J^T J)^s (T values).
    p: Vec<f64>,
    /// Eigenvalues and eigenvectors of A, made on first use (GCV).
    eigen: std::sync::OnceLock<Option<(Vec<f64>, Mat<f64>)>>,
}

impl DataSpace {
    /// J P^-1 and A for the Jacobian `jac` (K x T) and NOSER exponent `s`.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for s outside [0, 1]; [`ReconError::Singular`] for a
    /// Jacobian with non-finite values or all zero.
    pub fn new(jac: &DMatrix<f64>, s: f64) -> Result<Self, ReconError> {
        if !(0.0..=1.0).contains(&s) {
            return Err(ReconError::Parameter(format!("s = {s}: must be in [0, 1]")));
        }
        if jac.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let p_inv = noser_inverse(jac, s).ok_or(ReconError::Singular)?;
        Ok(Self::with_prior(jac, s, &p_inv))
    }

    /// As [`DataSpace::new`] with the prior's inverse P^-1 given (`p_inv`, T positive values):
    /// iterative Gauss-Newton keeps the background's prior at every iterate.
    pub(crate) fn with_prior(jac: &DMatrix<f64>, s: f64, p_inv: &[f64]) -> Self {
        let (k, t) = jac.shape();
        let j = MatRef::from_column_major_slice(jac.as_slice(), k, t);
        // B = J P^-1/2, so A = B B^T (symmetric rank-T update), then J P^-1 = B P^-1/2.
        let mut jp = Mat::from_fn(k, t, |r, c| j[(r, c)] * p_inv[c].sqrt());
        let mut a = Mat::<f64>::zeros(k, k);
        triangular::matmul(
            a.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            jp.as_ref(),
            BlockStructure::Rectangular,
            jp.transpose(),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        for r in 0..k {
            for c in r + 1..k {
                a[(r, c)] = a[(c, r)];
            }
        }
        for (c, w) in p_inv.iter().enumerate() {
            let w = w.sqrt();
            jp.col_mut(c).iter_mut().for_each(|v| *v *= w);
        }
        let trace = (0..k).map(|i| a[(i, i)]).sum();
        Self {
            jp,
            a,
            trace,
            s,
            p: p_inv.iter().map(|w| 1.0 / w).collect(),
            eigen: std::sync::OnceLock::new(),
        }
    }

    /// The prior's diagonal P (T values, one per triangle).
    #[must_use]
    pub fn prior(&self) -> &[f64] {
        &self.p
    }

    /// K, the frame length.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.a.nrows()
    }

    /// lambda = alpha^2 tr(A) / K, the module's normalisation.
    #[must_use]
    pub fn lambda(&self, alpha: f64) -> f64 {
        alpha * alpha * self.trace / self.frame_len() as f64
    }

    /// The Cholesky factor of A + lambda I.
    fn regularised(&self, lambda: f64) -> Result<Llt<f64>, ReconError> {
        let mut m = self.a.clone();
        for i in 0..m.nrows() {
            m[(i, i)] += lambda;
        }
        m.llt(Side::Lower).map_err(|_| ReconError::Singular)
    }

    /// The one-step reconstruction matrix R = P^-1 J^T (A + lambda I)^-1 at `alpha`.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for alpha not in (0, inf); [`ReconError::Singular`] when
    /// A + lambda I cannot be factorised.
    pub fn one_step(&self, alpha: f64) -> Result<OneStep, ReconError> {
        check_alpha(alpha)?;
        Ok(OneStep {
            matrix: self.matrix(self.lambda(alpha))?,
            alpha,
            s: self.s,
        })
    }

    /// R = P^-1 J^T (A + lambda I)^-1 (T x K) at an absolute `lambda`.
    pub(crate) fn matrix(&self, lambda: f64) -> Result<DMatrix<f64>, ReconError> {
        let llt = self.regularised(lambda)?;
        let (k, t) = self.jp.shape();
        // R^T = (A + lambda I)^-1 J P^-1 (K x T), solved in place in R's own storage (T x K,
        // column-major: R^T is its row-major view).
        let mut matrix = DMatrix::<f64>::zeros(t, k);
        {
            let mut rt = MatMut::from_column_major_slice_mut(matrix.as_mut_slice(), t, k);
            let mut rt = rt.as_mut().transpose_mut();
            rt.copy_from(&self.jp);
            llt.solve_in_place_with_conj(faer::Conj::No, rt);
        }
        if matrix.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        Ok(matrix)
    }

    /// (A + lambda I)^-1 `rhs` at an absolute `lambda` for one vector of K values (iterative Gauss-Newton's step).
    pub(crate) fn solve(&self, lambda: f64, rhs: &[f64]) -> Result<Vec<f64>, ReconError> {
        let llt = self.regularised(lambda)?;
        let mut x = Mat::from_fn(rhs.len(), 1, |r, _| rhs[r]);
        llt.solve_in_place_with_conj(faer::Conj::No, x.as_mut());
        Ok((0..rhs.len()).map(|r| x[(r, 0)]).collect())
    }

    /// P^-1 J^T `y` (T values) for K values `y`.
    pub(crate) fn back_project(&self, y: &[f64]) -> Vec<f64> {
        (0..self.jp.ncols())
            .map(|c| self.jp.col(c).iter().zip(y).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// A's eigenvalues e and the coefficients c = U^T dv (the eigendecomposition made once).
    fn spectrum(&self, dv: &[f64]) -> Result<(&[f64], Vec<f64>), ReconError> {
        let (e, u) = self
            .eigen
            .get_or_init(|| {
                let evd = self.a.self_adjoint_eigen(Side::Lower).ok()?;
                let e: Vec<f64> = evd.S().column_vector().iter().copied().collect();
                Some((e, evd.U().to_owned()))
            })
            .as_ref()
            .ok_or(ReconError::Singular)?;
        let c = (0..e.len())
            .map(|i| u.col(i).iter().zip(dv).map(|(a, b)| a * b).sum())
            .collect();
        Ok((e, c))
    }

    /// Generalised cross-validation of alpha for the frame difference `dv` (docs/method.md
    /// (6.1)): with A = U diag(e) U^T and c = U^T dv, GCV(lambda) = K sum_i (lambda c_i /
    /// (e_i + lambda))^2 / (sum_i lambda / (e_i + lambda))^2. Returns the candidate with the
    /// smallest GCV and every (alpha, GCV). A's eigendecomposition is made once and kept.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for a frame of the wrong length or no candidates;
    /// [`ReconError::NonFinite`] for a frame with NaN/inf; [`ReconError::Singular`] when A
    /// has no eigendecomposition or no candidate scores finitely.
    pub fn gcv(
        &self,
        dv: &[f64],
        candidates: &[f64],
    ) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
        let k = self.frame_len();
        if dv.len() != k || candidates.is_empty() {
            return Err(ReconError::Parameter(format!(
                "{} frame values for K = {k}, and at least one candidate alpha",
                dv.len()
            )));
        }
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        let (e, c) = self.spectrum(dv)?;
        let scores: Vec<(f64, f64)> = candidates
            .iter()
            .map(|&alpha| {
                let lambda = self.lambda(alpha);
                let (mut num, mut den) = (0.0, 0.0);
                for (e, ci) in e.iter().zip(&c) {
                    let w = lambda / (e.max(0.0) + lambda);
                    num += (w * ci).powi(2);
                    den += w;
                }
                (alpha, k as f64 * num / (den * den).max(f64::MIN_POSITIVE))
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
}

impl DataSpace {
    /// |dv - J R dv|^2 at each candidate alpha, V^2 (the residual of the one-step image),
    /// from A's eigendecomposition.
    fn residuals(&self, dv: &[f64], candidates: &[f64]) -> Result<Vec<f64>, ReconError> {
        let (e, c) = self.spectrum(dv)?;
        Ok(candidates
            .iter()
            .map(|&alpha| {
                let lambda = self.lambda(alpha);
                e.iter()
                    .zip(&c)
                    .map(|(e, ci)| (lambda * ci / (e.max(0.0) + lambda)).powi(2))
                    .sum()
            })
            .collect())
    }

    /// alpha for the frame difference `dv` whose per-channel noise variance is `var_dv`
    /// (V^2): the GCV minimum ([`DataSpace::gcv`]) among the candidates that do not fit the
    /// data closer than its noise, |dv - J R dv|^2 >= sum_k var_k (the discrepancy principle as
    /// a floor). GCV alone assumes the misfit is noise; on frames with little or no noise it
    /// runs to the smallest alpha, where the image rings and what remains (the ADC's
    /// rounding, the model's mismatch) is amplified into spurious peaks. When every candidate
    /// fits closer than the noise (dv within the noise), the largest is taken.
    ///
    /// # Errors
    /// As [`DataSpace::gcv`]; [`ReconError::Parameter`] for `var_dv` not of K values.
    pub fn choose_alpha(
        &self,
        dv: &[f64],
        var_dv: &[f64],
        candidates: &[f64],
    ) -> Result<f64, ReconError> {
        let (best, scores) = self.gcv(dv, candidates)?;
        if var_dv.len() != dv.len() {
            return Err(ReconError::Parameter(format!(
                "{} noise variances for K = {}",
                var_dv.len(),
                dv.len()
            )));
        }
        let noise: f64 = var_dv.iter().map(|v| v.max(0.0)).sum();
        let residuals = self.residuals(dv, candidates)?;
        let admissible = scores
            .iter()
            .zip(&residuals)
            .filter(|(s, r)| s.1.is_finite() && **r >= noise)
            .min_by(|a, b| a.0.1.total_cmp(&b.0.1));
        Ok(match admissible {
            Some((s, _)) => s.0,
            None => candidates.iter().copied().fold(best, f64::max),
        })
    }
}

fn check_alpha(alpha: f64) -> Result<(), ReconError> {
    if alpha.is_finite() && alpha > 0.0 {
        Ok(())
    } else {
        Err(ReconError::Parameter(format!(
            "alpha = {alpha}: must be finite and > 0"
        )))
    }
}

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
    /// Builds R from the Jacobian `jac` (K x T): [`DataSpace::new`] then
    /// [`DataSpace::one_step`] (use those to choose alpha by GCV on the same data space).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for alpha not in (0, inf) or s not in [0, 1];
    /// [`ReconError::Singular`] when the system cannot be factorised.
    pub fn new(jac: &DMatrix<f64>, alpha: f64, s: f64) -> Result<Self, ReconError> {
        check_alpha(alpha)?;
        DataSpace::new(jac, s)?.one_step(alpha)
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

/// The forward model's relative error against a real sheet, as a share of each channel's
/// change: the finite elements and the simulator's resistor network (two independent models
/// of one sheet) agree within 3.7 % on the 22 cm disc and 2.7 % on the 13 cm square
/// (`finite_elements_and_the_simulators_resistor_network_agree`); a real fabric is no closer.
pub const MODEL_ERROR: f64 = 0.03;

/// Each channel's variance of dV as imaging sees it, V^2: the frames' noise `var_dv` plus the
/// model's error (`MODEL_ERROR` x dV_k)^2. The model's error is not noise (it repeats from
/// frame to frame), but to an image it is the same: a misfit that no alpha should chase and
/// that images into peaks where there is no touch. Without it, frames with little noise let
/// GCV choose the smallest alpha and every ripple of the mismatch counts as a touch.
#[must_use]
pub fn imaging_variance(var_dv: &[f64], dv: &[f64]) -> Vec<f64> {
    var_dv
        .iter()
        .zip(dv)
        .map(|(v, d)| v.max(0.0) + (MODEL_ERROR * d).powi(2))
        .collect()
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

/// The NOSER weights P^-1 = diag(J^T J)^-s (a column that sees nothing gets the smallest
/// positive weight's), or None when every column is zero.
pub(crate) fn noser_inverse(jac: &DMatrix<f64>, s: f64) -> Option<Vec<f64>> {
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
