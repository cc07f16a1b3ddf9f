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
//! regularisation is as large as the average data-space eigenvalue).
//!
//! The Jacobian is used factored, J = M G over the r = L (L - 1) / 2 transfer impedances
//! ([`crate::fem::TransferJacobian`]): the frame's K values are combinations of r numbers, so
//! every large product costs r instead of K (16 electrodes: r = 120, K = 208 adjacent; 32
//! electrodes PP-PP: r = 496, K = 1 824). The reconstruction R (T x K) = (G P^-1)^T X^T is
//! built once as its two factors; each frame then costs two matrix-vector products onto the
//! mesh, about the time of reading the factors once, or one product onto a pixel grid
//! ([`crate::pixels::PixelGrid`]). Speeds: `cargo bench -p et-recon --bench imaging`,
//! docs/measurements.md.

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::solvers::{Llt, SolveCore};
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use nalgebra::DMatrix;

mod candidates;
mod error;
pub(crate) use candidates::Weights;
pub use error::ReconError;

/// The data-space quantities of one (Jacobian, NOSER exponent s), computed once and shared by
/// alpha's automatic choice ([`DataSpace::gcv`]) and the reconstruction matrix
/// ([`DataSpace::one_step`]). The Jacobian is kept factored, J = M G (K x r sparse times
/// r x T: [`crate::fem::TransferJacobian`]; a dense J is M = I, G = J), so the products cost r,
/// the transfer impedances, not K, the frame length: G P^-1 (r x T), H = G P^-1 G^T (r x r, a
/// symmetric rank-T update of its lower triangle: faer's BLAS-3 kernel) and A = M H M^T =
/// J P^-1 J^T (K x K).
/// What a data space keeps from one call for the next (a frame's projections, the
/// candidates' weights): made on use, replaced by the next; a clone starts empty.
#[derive(Debug)]
pub(crate) struct Kept<T>(pub(crate) std::sync::Mutex<Option<T>>);

impl<T> Default for Kept<T> {
    fn default() -> Self {
        Self(std::sync::Mutex::new(None))
    }
}

impl<T> Clone for Kept<T> {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// A frame dV, its projections c onto A's eigenvectors and the rest's squared norm.
type Projected = (Vec<f64>, Vec<f64>, f64);

#[derive(Clone, Debug)]
pub struct DataSpace {
    /// M: K rows of (column of G, coefficient), each row scaled by its value's weight's root
    /// sqrt(w_k) (the data space of the whitened frame sqrt(w) dV).
    combination: Vec<Vec<(usize, f64)>>,
    /// sqrt(w_k) per frame value: a frame's values are whitened by it before they meet M
    /// (None: every weight 1).
    root_weights: Option<Vec<f64>>,
    /// G P^-1, r x T: one copy, shared with every one-step matrix made from this space (r
    /// x T is 33 MB in f64 for 32 electrodes and 8 000 triangles).
    gp: std::sync::Arc<Mat<f64>>,
    /// A = J P^-1 J^T, K x K (full).
    a: Mat<f64>,
    /// tr(A), V^2 per (S/sq)^2 (the scale of lambda).
    trace: f64,
    /// The NOSER exponent s.
    s: f64,
    /// The prior's diagonal P = diag(J^T J)^s (T values).
    p: Vec<f64>,
    /// H = G P^-1 G^T, r x r.
    h: Mat<f64>,
    /// A's spectrum, made on first use (GCV).
    eigen: std::sync::OnceLock<Option<Spectrum>>,
    /// N = M^T M's root and B^T H B, made on first use (the one-step matrix).
    root: std::sync::OnceLock<Option<NormalRoot>>,
    /// The last frame's projections onto A's eigenvectors (the alpha rules read them
    /// several times a frame).
    pub(crate) last_seen: Kept<Projected>,
    /// The alpha rules' weights for the last candidate list asked.
    pub(crate) weights: Kept<std::sync::Arc<Weights>>,
}

/// `m`^T `v` for `m` (n x q) and `v` (n values): q values.
pub(crate) fn transposed_times(m: &faer::Mat<f64>, v: &[f64]) -> Vec<f64> {
    let v = faer::MatRef::from_column_major_slice(v, v.len(), 1);
    let mut out = vec![0.0; m.ncols()];
    faer::linalg::matmul::matmul(
        faer::MatMut::from_column_major_slice_mut(&mut out, m.ncols(), 1),
        faer::Accum::Replace,
        m.transpose(),
        v,
        1.0,
        faer::Par::Seq,
    );
    out
}

/// N = M^T M (r x r) for the K rows of M (`combination`, over r columns).
pub(crate) fn normal(combination: &[Vec<(usize, f64)>], r: usize) -> Mat<f64> {
    let mut n = Mat::<f64>::zeros(r, r);
    for row in combination {
        for &(p, a) in row {
            for &(q, b) in row {
                n[(p, q)] += a * b;
            }
        }
    }
    n
}

/// N = M^T M's eigenpairs with eigenvalues above 1e-10 of the largest, for the K rows of M
/// (`combination`, over r columns): (Q, r x q orthonormal; n, q values). Its range is M^T's.
pub(crate) fn normal_range(
    combination: &[Vec<(usize, f64)>],
    r: usize,
) -> Option<(Mat<f64>, Vec<f64>)> {
    let evd = normal(combination, r)
        .self_adjoint_eigen(Side::Lower)
        .ok()?;
    let e: Vec<f64> = evd.S().column_vector().iter().copied().collect();
    let top = e.iter().copied().fold(0.0f64, f64::max);
    let keep: Vec<usize> = (0..r).filter(|&i| e[i] > 1e-10 * top).collect();
    let u = evd.U();
    Some((
        Mat::from_fn(r, keep.len(), |i, j| u[(i, keep[j])]),
        keep.iter().map(|&i| e[i]).collect(),
    ))
}

/// N = M^T M on its range: N = B B^T with B = Q diag(n)^1/2 over N's eigenpairs (Q, n) above
/// 1e-10 of the largest (r x q), B^+ = diag(n)^-1/2 Q^T (q x r), and B^T H B (q x q).
#[derive(Clone, Debug)]
struct NormalRoot {
    b: Mat<f64>,
    b_pinv: Mat<f64>,
    bhb: Mat<f64>,
}

impl NormalRoot {
    fn new(combination: &[Vec<(usize, f64)>], h: &Mat<f64>) -> Option<Self> {
        let r = h.nrows();
        let (q, n) = normal_range(combination, r)?;
        let b = Mat::from_fn(r, n.len(), |i, j| q[(i, j)] * n[j].sqrt());
        let b_pinv = Mat::from_fn(n.len(), r, |i, j| q[(j, i)] / n[i].sqrt());
        let hb = product(h.as_ref(), b.as_ref());
        let bhb = product(b.transpose(), hb.as_ref());
        Some(Self { b, b_pinv, bhb })
    }
}

/// A's nonzero eigenvalues e_i and how to get c = U^T dv for their eigenvectors U.
#[derive(Clone, Debug)]
pub(crate) enum Spectrum {
    /// From the r x r problem: with H = C C^T and F = M C (so A = F F^T), the eigenpairs
    /// (V, E) of F^T F = C^T M^T M C give A's nonzero eigenvalues E and c = W^T (M^T dv) with
    /// W = C V E^-1/2 (r x q); A's other K - q eigenvalues are 0.
    Compact { e: Vec<f64>, w: Mat<f64> },
    /// All K eigenpairs of A (when H cannot be factorised): c = U^T dv.
    Full { e: Vec<f64>, u: Mat<f64> },
}

impl DataSpace {
    /// The data space of the dense Jacobian `jac` (K x T) and NOSER exponent `s`.
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] for s outside [0, 1]; [`ReconError::Singular`] for a
    /// Jacobian with non-finite values or all zero.
    pub fn new(jac: &DMatrix<f64>, s: f64) -> Result<Self, ReconError> {
        check_s(s)?;
        if jac.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let p_inv = noser_inverse(jac, s).ok_or(ReconError::Singular)?;
        Ok(Self::with_prior(jac, s, &p_inv))
    }

    /// The data space of a factored Jacobian (the fast way: [`crate::Imager::transfer_jacobian`]).
    ///
    /// # Errors
    /// As [`DataSpace::new`].
    pub fn factored(jac: &crate::fem::TransferJacobian, s: f64) -> Result<Self, ReconError> {
        check_s(s)?;
        let g = &jac.g;
        if g.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let diag = jtj_diagonal(&jac.combination, g);
        let p_inv = noser_weights(&diag, s).ok_or(ReconError::Singular)?;
        let g = MatRef::from_column_major_slice(g.as_slice(), g.nrows(), g.ncols());
        Ok(Self::build(jac.combination.clone(), g, s, &p_inv))
    }

    /// The data space of a factored Jacobian with the prior's inverse P^-1 given (`p_inv`, T
    /// positive values; GREIT's covariance of the conductivity, [`crate::greit`]). Its `s` is 0.
    ///
    /// # Errors
    /// [`ReconError::Singular`] for a Jacobian with non-finite values;
    /// [`ReconError::Size`] for `p_inv` not of T values, [`ReconError::NotPositive`] for one not positive and finite.
    pub(crate) fn factored_with_prior(
        jac: &crate::fem::TransferJacobian,
        p_inv: &[f64],
    ) -> Result<Self, ReconError> {
        let g = &jac.g;
        if g.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        if p_inv.len() != g.ncols() {
            return Err(ReconError::Size {
                what: "the prior's values (one per triangle)",
                got: p_inv.len(),
                expected: g.ncols(),
            });
        }
        not_positive("prior value", p_inv)?;
        let g = MatRef::from_column_major_slice(g.as_slice(), g.nrows(), g.ncols());
        Ok(Self::build(jac.combination.clone(), g, 0.0, p_inv))
    }

    /// As [`DataSpace::new`] with the prior's inverse P^-1 given (`p_inv`, T positive values):
    /// iterative Gauss-Newton keeps the background's prior at every iterate.
    pub(crate) fn with_prior(jac: &DMatrix<f64>, s: f64, p_inv: &[f64]) -> Self {
        let (k, t) = jac.shape();
        let identity = (0..k).map(|i| vec![(i, 1.0)]).collect();
        Self::build(
            identity,
            MatRef::from_column_major_slice(jac.as_slice(), k, t),
            s,
            p_inv,
        )
    }

    fn build(
        combination: Vec<Vec<(usize, f64)>>,
        g: MatRef<'_, f64>,
        s: f64,
        p_inv: &[f64],
    ) -> Self {
        let (r, t) = g.shape();
        let k = combination.len();
        // B = G P^-1/2, so H = B B^T (symmetric rank-T update), then G P^-1 = B P^-1/2.
        let root: Vec<f64> = p_inv.iter().map(|w| w.sqrt()).collect();
        let mut gp = Mat::<f64>::zeros(r, t);
        for (c, w) in root.iter().enumerate() {
            gp.col_mut(c)
                .iter_mut()
                .zip(g.col(c).iter())
                .for_each(|(d, v)| *d = v * w);
        }
        let mut h = Mat::<f64>::zeros(r, r);
        triangular::matmul(
            h.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            gp.as_ref(),
            BlockStructure::Rectangular,
            gp.transpose(),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        for i in 0..r {
            for j in i + 1..r {
                h[(i, j)] = h[(j, i)];
            }
        }
        for (c, w) in root.iter().enumerate() {
            gp.col_mut(c).iter_mut().for_each(|v| *v *= w);
        }
        // A = M H M^T: MH (K x r), then A[i, j] = sum over row j of M of MH[i, p] c.
        let mh = Mat::from_fn(k, r, |i, col| {
            combination[i]
                .iter()
                .map(|&(p, c)| c * h[(p, col)])
                .sum::<f64>()
        });
        let a = Mat::from_fn(k, k, |i, j| {
            combination[j]
                .iter()
                .map(|&(p, c)| c * mh[(i, p)])
                .sum::<f64>()
        });
        let trace = (0..k).map(|i| a[(i, i)]).sum();
        Self {
            combination,
            root_weights: None,
            gp: std::sync::Arc::new(gp),
            a,
            trace,
            s,
            p: p_inv.iter().map(|w| 1.0 / w).collect(),
            h,
            eigen: std::sync::OnceLock::new(),
            root: std::sync::OnceLock::new(),
            last_seen: Kept::default(),
            weights: Kept::default(),
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

    /// The one-step reconstruction R = P^-1 J^T (A + lambda I)^-1 at `alpha`, factored.
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] for alpha not in (0, inf); [`ReconError::Singular`] when
    /// A + lambda I cannot be factorised.
    pub fn one_step(&self, alpha: f64) -> Result<OneStep, ReconError> {
        check_alpha(alpha)?;
        self.at_lambda(self.lambda(alpha), alpha)
    }

    /// R = P^-1 J^T (A + lambda I)^-1 = (G P^-1)^T X^T at an absolute `lambda`, with X^T =
    /// M^T (M H M^T + lambda I)^-1 = (N H + lambda I)^-1 M^T (N = M^T M; the push-through
    /// identity, since (N H + lambda I) M^T = M^T (M H M^T + lambda I)): an r x r problem
    /// instead of a K x K Cholesky, so a protocol of many values (a tank's 1 264, 32
    /// electrodes' 2 304) costs what its r transfer impedances cost. M^T's columns lie in N's
    /// range, where N = B B^T ([`NormalRoot`]) and (N H + lambda I)^-1 = B (B^T H B + lambda
    /// I)^-1 B^+: a symmetric positive definite q x q Cholesky whose condition is A + lambda
    /// I's (B^T H B has A's nonzero eigenvalues).
    pub(crate) fn at_lambda(&self, lambda: f64, alpha: f64) -> Result<OneStep, ReconError> {
        let k = self.frame_len();
        let root = self.normal_root()?;
        let q = root.b.ncols();
        let mut s = root.bhb.clone();
        for i in 0..q {
            s[(i, i)] += lambda;
        }
        let llt = s.llt(Side::Lower).map_err(|_| ReconError::Singular)?;
        let mut z = root.b_pinv.clone();
        llt.solve_in_place_with_conj(faer::Conj::No, z.as_mut());
        // (N H + lambda I)^-1 on N's range (r x r), then combined by M^T's sparse columns.
        let inverse = product(root.b.as_ref(), z.as_ref());
        // Applied to the frame as measured: M's row k times sqrt(w_k) once more.
        let combination: Vec<Vec<(usize, f64)>> = match &self.root_weights {
            Some(w) => (self.combination.iter().zip(w))
                .map(|(row, w)| row.iter().map(|&(p, c)| (p, c * w)).collect())
                .collect(),
            None => self.combination.clone(),
        };
        let mut xt = Mat::<f64>::zeros(self.gp.nrows(), k);
        for (col, row) in combination.iter().enumerate() {
            for &(p, c) in row {
                xt.col_mut(col)
                    .iter_mut()
                    .zip(inverse.col(p).iter())
                    .for_each(|(x, v)| *x += c * v);
            }
        }
        if xt.col_iter().any(|c| c.iter().any(|v| !v.is_finite())) {
            return Err(ReconError::Singular);
        }
        Ok(OneStep {
            gp: std::sync::Arc::clone(&self.gp),
            xt,
            inverse,
            combination,
            alpha,
            s: self.s,
            squared: NoiseRows::default(),
        })
    }

    /// [`NormalRoot`], made on first use and kept.
    fn normal_root(&self) -> Result<&NormalRoot, ReconError> {
        self.root
            .get_or_init(|| NormalRoot::new(&self.combination, &self.h))
            .as_ref()
            .ok_or(ReconError::Singular)
    }

    /// (A + lambda I)^-1 `rhs` at an absolute `lambda` for one vector of K values (iterative
    /// Gauss-Newton's step).
    pub(crate) fn solve(&self, lambda: f64, rhs: &[f64]) -> Result<Vec<f64>, ReconError> {
        let llt = self.regularised(lambda)?;
        let mut x = Mat::from_fn(rhs.len(), 1, |r, _| rhs[r]);
        llt.solve_in_place_with_conj(faer::Conj::No, x.as_mut());
        Ok((0..rhs.len()).map(|r| x[(r, 0)]).collect())
    }

    /// P^-1 J^T `y` (T values) for K values `y`: (G P^-1)^T (M^T y).
    pub(crate) fn back_project(&self, y: &[f64]) -> Vec<f64> {
        let w = self.m_transpose(y);
        (0..self.gp.ncols())
            .map(|t| self.gp.col(t).iter().zip(&w).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// G P^-1 (r x T).
    pub(crate) fn gp(&self) -> MatRef<'_, f64> {
        Mat::as_ref(&self.gp)
    }

    /// tr(A) / K, lambda's scale (V^2 per (S/sq)^2).
    pub(crate) fn lambda_scale(&self) -> f64 {
        self.trace / self.frame_len() as f64
    }

    /// M^T `y` (r values) for K values `y`.
    pub(crate) fn m_transpose(&self, y: &[f64]) -> Vec<f64> {
        let mut w = vec![0.0; self.gp.nrows()];
        for (row, yk) in self.combination.iter().zip(y) {
            for &(p, c) in row {
                w[p] += c * yk;
            }
        }
        w
    }

    /// A's spectrum, made on first use and kept.
    pub(crate) fn eigen(&self) -> Result<&Spectrum, ReconError> {
        self.eigen
            .get_or_init(|| self.compact_spectrum().or_else(|| self.full_spectrum()))
            .as_ref()
            .ok_or(ReconError::Singular)
    }

    /// A's eigenpairs with eigenvalues above 1e-12 of the largest: (e, U), U K x q with
    /// orthonormal columns (from the r x r problem when H factorises, as GCV's spectrum).
    ///
    /// # Errors
    /// [`ReconError::Singular`] when A has no eigendecomposition.
    pub(crate) fn eigenpairs(&self) -> Result<(Vec<f64>, Mat<f64>), ReconError> {
        let spectrum = self.eigen()?;
        let k = self.frame_len();
        Ok(match spectrum {
            Spectrum::Compact { e, w } => {
                let u = Mat::from_fn(k, e.len(), |i, j| {
                    self.combination[i]
                        .iter()
                        .map(|&(p, c)| c * w[(p, j)])
                        .sum::<f64>()
                });
                (e.clone(), u)
            }
            Spectrum::Full { e, u } => {
                let top = e.iter().copied().fold(0.0f64, f64::max);
                let keep: Vec<usize> = (0..e.len()).filter(|&i| e[i] > 1e-12 * top).collect();
                (
                    keep.iter().map(|&i| e[i]).collect(),
                    Mat::from_fn(k, keep.len(), |i, j| u[(i, keep[j])]),
                )
            }
        })
    }

    /// [`Spectrum::Compact`] (None if an eigendecomposition fails). H is semidefinite and
    /// often nearly singular (transfer impedances whose sensitivities nearly coincide), so
    /// its square root is taken from its own eigendecomposition, C = Q Lambda^1/2 over its
    /// eigenvalues above 1e-13 of the largest, not from a Cholesky factor.
    fn compact_spectrum(&self) -> Option<Spectrum> {
        let r = self.h.nrows();
        let hevd = self.h.self_adjoint_eigen(Side::Lower).ok()?;
        let lambda: Vec<f64> = hevd.S().column_vector().iter().copied().collect();
        let top = lambda.iter().copied().fold(0.0f64, f64::max);
        let kept: Vec<usize> = (0..r).filter(|&i| lambda[i] > 1e-13 * top).collect();
        let q = hevd.U();
        let c = Mat::from_fn(r, kept.len(), |i, j| {
            q[(i, kept[j])] * lambda[kept[j]].sqrt()
        });
        let n = normal(&self.combination, r);
        let m = c.ncols();
        let nc = product(n.as_ref(), c.as_ref());
        let small = product(c.transpose(), nc.as_ref());
        let evd = small.self_adjoint_eigen(Side::Lower).ok()?;
        let all: Vec<f64> = evd.S().column_vector().iter().copied().collect();
        let top = all.iter().copied().fold(0.0f64, f64::max);
        let keep: Vec<usize> = (0..m).filter(|&i| all[i] > 1e-12 * top).collect();
        let v = evd.U();
        let vq = Mat::from_fn(m, keep.len(), |i, j| v[(i, keep[j])] / all[keep[j]].sqrt());
        let w = product(c.as_ref(), vq.as_ref());
        Some(Spectrum::Compact {
            e: keep.iter().map(|&i| all[i]).collect(),
            w,
        })
    }

    /// [`Spectrum::Full`]: every eigenpair of A (K x K).
    fn full_spectrum(&self) -> Option<Spectrum> {
        let evd = self.a.self_adjoint_eigen(Side::Lower).ok()?;
        Some(Spectrum::Full {
            e: evd.S().column_vector().iter().copied().collect(),
            u: evd.U().to_owned(),
        })
    }
}

/// `gp` (r x T) times the sparse D^T (T x N; D's rows are (column of gp, weight)): r x N.
pub(crate) fn map_columns(gp: MatRef<'_, f64>, d: &[Vec<(usize, f64)>]) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(gp.nrows(), d.len());
    for (row, entries) in d.iter().enumerate() {
        for &(t, w) in entries {
            out.col_mut(row)
                .iter_mut()
                .zip(gp.col(t).iter())
                .for_each(|(a, b)| *a += w * b);
        }
    }
    out
}

/// a b, one core (faer's blocked kernel).
pub(crate) fn product(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(a.nrows(), b.ncols());
    matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

/// [`ReconError::NotPositive`] for the first of `values` that is not positive and finite.
pub(crate) fn not_positive(what: &'static str, values: &[f64]) -> Result<(), ReconError> {
    match crate::fem::first_not_positive(values) {
        Some((index, value)) => Err(ReconError::NotPositive { what, index, value }),
        None => Ok(()),
    }
}

pub(crate) fn check_s(s: f64) -> Result<(), ReconError> {
    if (0.0..=1.0).contains(&s) {
        Ok(())
    } else {
        Err(ReconError::OutOfRange {
            name: "s",
            value: s,
            range: "in [0, 1]",
        })
    }
}

pub(crate) fn check_alpha(alpha: f64) -> Result<(), ReconError> {
    if alpha.is_finite() && alpha > 0.0 {
        Ok(())
    } else {
        Err(ReconError::OutOfRange {
            name: "alpha",
            value: alpha,
            range: "finite and > 0",
        })
    }
}

mod matrix;
mod prior;
mod weights;
pub use matrix::*;
pub use prior::jtj_diagonal;
pub(crate) use prior::noser_inverse;
use prior::noser_weights;
