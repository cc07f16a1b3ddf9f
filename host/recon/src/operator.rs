//! The reconstruction as the operator a live frame meets: rows (triangles or pixels) x K, in
//! two thin f32 factors packed for matrix-vector products at memory speed ([`Panels`]).

use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Accum, Mat, MatRef, Par, Side};
use nalgebra::DMatrix;

use crate::onestep::{OneStep, ReconError, product};

mod panels;
pub use panels::Panels;

/// A reconstruction matrix onto rows (triangles of the mesh, or pixels inside the sheet), P
/// (rows x K), kept as two thin factors in f32, P = L C with L (rows x q) and C (q x K), q the
/// numerical rank of P: a frame reads q (rows + K) numbers instead of rows x K. One-step
/// Gauss-Newton and GREIT both reach their rows through the r transfer impedances (for L
/// electrodes r = L (L - 1) / 2, 120 for 16), so q <= r, and fewer when the protocol has
/// fewer independent values (104 for 16 electrodes adjacent): a 64 x 64 frame on a disc reads
/// 0.36 M numbers instead of 0.67 M, a frame onto 8 000 triangles 0.85 M instead of 1.7 M.
/// The factors come from a QR factor of the rows' side and a singular value decomposition of
/// the r x K core; only singular values below 1e-7 of the largest (what f32 cannot resolve)
/// are dropped. L's columns are orthonormal, so rounding to f32 does not grow through
/// cancellation: an image is within 1e-5 of its largest value of the f64 matrix's
/// (`f32_frames_are_the_f64_images_within_1e_5_of_their_peak`).
#[derive(Clone, Debug)]
pub struct FrameOperator {
    /// L, rows x q.
    left: Panels,
    /// C, q x K.
    core: Panels,
}

impl FrameOperator {
    /// The rows of R for `rows` (each one of R's rows: a triangle, or a pixel of GREIT's
    /// matrix) from R's factors R = (G P^-1)^T X^T.
    #[must_use]
    pub fn of_rows(r: &OneStep, rows: &[usize]) -> Self {
        let g = Mat::from_fn(rows.len(), r.gp.nrows(), |i, j| r.gp[(j, rows[i])]);
        Self::from_factors(g.as_ref(), r.xt.as_ref())
    }

    /// All of R's rows (a frame onto every triangle).
    #[must_use]
    pub fn of(r: &OneStep) -> Self {
        Self::from_factors(r.gp.transpose(), r.xt.as_ref())
    }

    /// P = `a` `b` from `a` (rows x r) and `b` (r x K). With a = Q R (R from the Cholesky
    /// factor of the r x r Gram matrix a^T a, Householder's QR when that is not positive
    /// definite; Q never formed) and R b = U S V^T (SVD, the q singular values above 1e-7 of
    /// the largest kept): L = Q U = a (R^-1 U), one product of the tall `a` by an r x q
    /// matrix, and C = S V^T. Any invertible R gives L C = a b; an accurate one makes L's
    /// columns orthonormal, so rounding L to f32 costs no accuracy through cancellation.
    pub(crate) fn from_factors(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Self {
        // Q explicitly when a's conditioning would cost R^-1 its accuracy.
        let (q, r) = match upper_factor(a) {
            Some(r) => (None, r),
            None => {
                let qr = a.qr();
                (Some(qr.compute_thin_Q()), qr.thin_R().to_owned())
            }
        };
        let core = product(r.as_ref(), b);
        let (left, core) = match core.thin_svd() {
            Ok(svd) => {
                let s = svd.S().column_vector();
                let top = s.iter().copied().fold(0.0f64, f64::max);
                let rank = s.iter().filter(|&&x| x > 1e-7 * top).count();
                let u = svd.U().subcols(0, rank);
                let left = match &q {
                    Some(q) => product(q.as_ref(), u),
                    None => {
                        let mut m = u.to_owned();
                        solve_upper_triangular_in_place(r.as_ref(), m.as_mut(), Par::Seq);
                        product(a, m.as_ref())
                    }
                };
                let v = svd.V();
                let core = Mat::from_fn(rank, b.ncols(), |i, k| s[i] * v[(k, i)]);
                (left, core)
            }
            // Not expected for finite input; the unfactored product is as exact.
            Err(_) => (a.to_owned(), b.to_owned()),
        };
        let packed = |m: &Mat<f64>| Panels::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)] as f32);
        Self {
            left: packed(&left),
            core: packed(&core),
        }
    }

    /// Rows of P (pixels inside the sheet, or triangles).
    #[must_use]
    pub fn rows(&self) -> usize {
        self.left.rows()
    }

    /// K, the frame length (columns of P).
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.core.cols()
    }

    /// q, the rank the factors keep.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.core.rows()
    }

    /// Bytes a frame reads: both factors, as packed.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.left.bytes() + self.core.bytes()
    }

    /// A live frame: P `dv` (K values, V) into `out` (one value per row), as y = C dv (q
    /// values) then L y, each one pass over its packed factor on one core.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] when `dv` does not hold K values or `out` not one per row.
    pub fn apply(&self, dv: &[f32], out: &mut [f32]) -> Result<(), ReconError> {
        let (p, k) = (self.rows(), self.frame_len());
        if dv.len() != k || out.len() != p {
            return Err(ReconError::Parameter(format!(
                "{} values into {} rows for a reconstruction of {p} x {k}",
                dv.len(),
                out.len()
            )));
        }
        let (mut stack, mut heap) = ([0.0f32; 512], Vec::new());
        let y = if self.rank() <= stack.len() {
            &mut stack[..self.rank()]
        } else {
            heap.resize(self.rank(), 0.0);
            &mut heap[..]
        };
        self.core.apply(dv, y);
        self.left.apply(y, out);
        Ok(())
    }

    /// A frame as every imaging path applies it: dV (K values, V, as f64) rounded to f32, then
    /// [`FrameOperator::apply`]; one value per row.
    ///
    /// # Errors
    /// [`ReconError::NonFinite`] for a value that is NaN or infinite in f32,
    /// [`ReconError::Parameter`] for a wrong length.
    pub fn image(&self, dv: &[f64]) -> Result<Vec<f32>, ReconError> {
        let dv: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        let mut out = vec![0.0f32; self.rows()];
        self.apply(&dv, &mut out)?;
        Ok(out)
    }

    /// P multiplied out (rows x K), from the f32 factors.
    #[must_use]
    pub fn dense(&self) -> DMatrix<f32> {
        DMatrix::from_fn(self.rows(), self.frame_len(), |i, k| {
            (0..self.rank())
                .map(|j| self.left.get(i, j) * self.core.get(j, k))
                .sum()
        })
    }

    /// The standard deviation of each row's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2): sqrt(sum_k P_pk^2 var_k) = |L_p W| with W = C
    /// diag(sqrt var) (q x K), computed through the q x q Gram matrix W W^T. Negative
    /// variances count as 0.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] when `var_dv` does not hold K values.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if var_dv.len() != self.frame_len() {
            return Err(ReconError::Parameter(format!(
                "{} variances for K = {}",
                var_dv.len(),
                self.frame_len()
            )));
        }
        let w = Mat::from_fn(self.rank(), self.frame_len(), |i, k| {
            f64::from(self.core.get(i, k)) * var_dv[k].max(0.0).sqrt()
        });
        let gram = product(w.as_ref(), w.transpose());
        let left = Mat::from_fn(self.rows(), self.rank(), |p, i| {
            f64::from(self.left.get(p, i))
        });
        let lg = product(left.as_ref(), gram.as_ref());
        Ok((0..self.rows())
            .map(|p| {
                (0..self.rank())
                    .map(|i| lg[(p, i)] * left[(p, i)])
                    .sum::<f64>()
                    .max(0.0)
                    .sqrt()
            })
            .collect())
    }
}

/// R (r x r, upper triangular) with a = Q R for the tall `a` (n x r): the transposed Cholesky
/// factor of a^T a (a symmetric rank-n update: half the work of Householder's QR, and no Q).
/// None when a^T a is not positive definite or a is too ill-conditioned for it (its
/// diagonal's ratio, a lower bound of a's condition number, above 1e5: Q = a R^-1 would
/// lose orthogonality as the condition's square times f64's 1e-16).
fn upper_factor(a: MatRef<'_, f64>) -> Option<Mat<f64>> {
    let r = a.ncols();
    let mut gram = Mat::<f64>::zeros(r, r);
    triangular::matmul(
        gram.as_mut(),
        BlockStructure::TriangularLower,
        Accum::Replace,
        a.transpose(),
        BlockStructure::Rectangular,
        a,
        BlockStructure::Rectangular,
        1.0,
        Par::Seq,
    );
    let l = gram.llt(Side::Lower).ok()?.L().to_owned();
    let diag: Vec<f64> = (0..r).map(|i| l[(i, i)].abs()).collect();
    let (lo, hi) = diag.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), d| {
        (lo.min(*d), hi.max(*d))
    });
    (hi.is_finite() && lo > 1e-5 * hi).then(|| l.transpose().to_owned())
}
