//! The reconstruction as the operator a live frame meets: rows (triangles or pixels) x K, in
//! two thin factors packed for matrix-vector products at memory speed ([`Panels`]).

use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::triangular_solve::solve_upper_triangular_in_place;
use faer::{Accum, Mat, MatMut, MatRef, Par, Side};
use nalgebra::DMatrix;

use crate::onestep::{OneStep, ReconError, product};

mod panels;
mod squared;
pub use panels::{Panels, Stored};
pub use squared::SquaredRows;

/// A reconstruction matrix onto rows (triangles of the mesh, or pixels inside the sheet), P
/// (rows x K), kept as two thin factors, P = L C with L (rows x q) and C (q x K), q the
/// numerical rank of P: a frame reads q (rows + K) numbers instead of rows x K. One-step
/// Gauss-Newton and GREIT both reach their rows through the r transfer impedances (for L
/// electrodes r = L (L - 1) / 2, 120 for 16), so q <= r, and fewer when the protocol has
/// fewer independent values (104 for 16 electrodes adjacent). When a frame holds more values
/// than twice the transfer impedances (K > 2 r: 1 824 against 496 for 32 electrodes PP-PP), C
/// is kept as C' M^T with C' (q x r) and M (K x r) the sparse combination of transfer
/// impedances each value is: z = M^T dV is a sum of a few values for each of the r, and C'
/// reads q r numbers instead of q K. That step runs in f64: C' z cancels where M is poorly
/// conditioned (f32 there cost 4e-5 of the image's peak for 32 electrodes PP-PP), and C' in
/// f64 is still about half the bytes of C in f32.
///
/// The factors come from a QR factor of the rows' side and a singular value decomposition of
/// the r x K core; only singular values below 1e-7 of the largest (what f32 cannot resolve)
/// are dropped. L's columns are orthonormal, so rounding does not grow through cancellation:
/// L, the large factor, is stored in 16-bit fixed point per row (half the bytes of f32), C
/// in f32, and an image is within 1e-4 of its largest value of the f64 matrix's
/// (`frames_are_the_f64_images_within_1e_4_of_their_peak`: 2e-5 to 5e-5 measured).
#[derive(Clone, Debug)]
pub struct FrameOperator {
    /// L, rows x q.
    left: Panels<i16>,
    /// C, or C' and M^T.
    core: Core,
    /// K.
    frame_len: usize,
}

/// The operator's side of the frame: dV (K values) to the q values L multiplies.
#[derive(Clone, Debug)]
enum Core {
    /// C (q x K).
    Full(Panels),
    /// C' (q x r, f64) and M^T (r x K), when 2 r < K.
    Gathered { core: Mat<f64>, gather: Gather },
}

/// A sparse r x K matrix by rows (compressed sparse rows): row p's entries are
/// `(column[e], value[e])` for e in `start[p]..start[p + 1]`.
#[derive(Clone, Debug)]
struct Gather {
    start: Vec<usize>,
    column: Vec<u32>,
    value: Vec<f64>,
}

impl Gather {
    /// M^T from M's rows (`combination[k]`: the (p, c) of frame value k), over r columns.
    fn transpose_of(combination: &[Vec<(usize, f64)>], r: usize) -> Option<Self> {
        let mut rows = vec![Vec::new(); r];
        for (k, row) in combination.iter().enumerate() {
            for &(p, c) in row {
                rows.get_mut(p)?.push((u32::try_from(k).ok()?, c));
            }
        }
        let mut start = vec![0];
        let (mut column, mut value) = (Vec::new(), Vec::new());
        for row in rows {
            for (k, c) in row {
                column.push(k);
                value.push(c);
            }
            start.push(column.len());
        }
        Some(Self {
            start,
            column,
            value,
        })
    }

    /// Bytes a frame reads of it.
    fn bytes(&self) -> usize {
        size_of_val(&self.start[..]) + size_of_val(&self.column[..]) + size_of_val(&self.value[..])
    }

    /// `z` = M^T `dv`.
    fn apply(&self, dv: &[f32], z: &mut [f64]) {
        for (z, ends) in z.iter_mut().zip(self.start.windows(2)) {
            let (columns, values) = (
                &self.column[ends[0]..ends[1]],
                &self.value[ends[0]..ends[1]],
            );
            *z = columns
                .iter()
                .zip(values)
                .map(|(&k, &c)| c * f64::from(dv[k as usize]))
                .sum();
        }
    }

    /// C' M^T (q x K) for C' (q x r).
    fn times(&self, core: &Mat<f64>, k: usize) -> Mat<f64> {
        let mut out = Mat::<f64>::zeros(core.nrows(), k);
        for (p, ends) in self.start.windows(2).enumerate() {
            for e in ends[0]..ends[1] {
                let (col, c) = (self.column[e] as usize, self.value[e]);
                for i in 0..core.nrows() {
                    out[(i, col)] += core[(i, p)] * c;
                }
            }
        }
        out
    }
}

impl FrameOperator {
    /// The rows of R for `rows` (each one of R's rows: a triangle, or a pixel of GREIT's
    /// matrix) from R's factors R = (G P^-1)^T X^T.
    #[must_use]
    pub fn of_rows(r: &OneStep, rows: &[usize]) -> Self {
        let g = Mat::from_fn(rows.len(), r.gp.nrows(), |i, j| r.gp[(j, rows[i])]);
        Self::of_left(g.as_ref(), r)
    }

    /// All of R's rows (a frame onto every triangle).
    #[must_use]
    pub fn of(r: &OneStep) -> Self {
        Self::of_left(r.gp.transpose(), r)
    }

    /// P = `a` X^T for `a` (rows x r), through M^T when that reads fewer bytes (2 r < K).
    fn of_left(a: MatRef<'_, f64>, r: &OneStep) -> Self {
        // C' in f64 (8 r bytes a row) against C in f32 (4 K bytes a row).
        let short = (2 * r.inverse.nrows() < r.frame_len())
            .then(|| Gather::transpose_of(&r.combination, r.inverse.nrows()))
            .flatten()
            .map(|gather| (r.inverse.as_ref(), gather));
        Self::from_factors(a, r.xt.as_ref(), short)
    }

    /// P = `a` `b` from `a` (rows x r) and `b` (r x K). With a = Q R (R from the Cholesky
    /// factor of the r x r Gram matrix a^T a, Householder's QR when that is not positive
    /// definite; Q never formed) and R b = U S V^T (SVD, the q singular values above 1e-7 of
    /// the largest kept): L = Q U = a (R^-1 U), one product of the tall `a` by an r x q
    /// matrix, and C = S V^T. Any invertible R gives L C = a b; an accurate one makes L's
    /// columns orthonormal, so rounding L costs no accuracy through cancellation. With
    /// `short` = (b', M^T) where b = b' M^T (b' r x r), C is kept as C' = U^T R b' (q x r)
    /// and M^T: the same C = U^T R b = S V^T, at the same rank (cut on R b's singular values,
    /// as without it).
    fn from_factors(
        a: MatRef<'_, f64>,
        b: MatRef<'_, f64>,
        short: Option<(MatRef<'_, f64>, Gather)>,
    ) -> Self {
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
                let core = match &short {
                    Some((b_short, _)) => {
                        product(u.transpose(), product(r.as_ref(), *b_short).as_ref())
                    }
                    None => {
                        let v = svd.V();
                        Mat::from_fn(rank, b.ncols(), |i, k| s[i] * v[(k, i)])
                    }
                };
                (left, core)
            }
            // Not expected for finite input; the unfactored product is as exact.
            Err(_) => (
                a.to_owned(),
                short.as_ref().map_or(b, |(b_short, _)| *b_short).to_owned(),
            ),
        };
        Self {
            left: Panels::from_fn(left.nrows(), left.ncols(), |i, j| left[(i, j)]),
            core: match short {
                Some((_, gather)) => Core::Gathered { core, gather },
                None => Core::Full(Panels::from_fn(core.nrows(), core.ncols(), |i, j| {
                    core[(i, j)]
                })),
            },
            frame_len: b.ncols(),
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
        self.frame_len
    }

    /// q, the rank the factors keep.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.left.cols()
    }

    /// Bytes a frame reads: both factors as packed, and M^T when kept.
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.left.bytes()
            + match &self.core {
                Core::Full(core) => core.bytes(),
                Core::Gathered { core, gather } => {
                    core.nrows() * core.ncols() * size_of::<f64>() + gather.bytes()
                }
            }
    }

    /// A live frame: P `dv` (K values, V) into `out` (one value per row), as y = C dv (q
    /// values; C' (M^T dv) when M^T is kept) then L y, each one pass over its packed factor on
    /// one core.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] when `dv` does not hold K values, [`ReconError::Size`] when `out` is not one per row.
    pub fn apply(&self, dv: &[f32], out: &mut [f32]) -> Result<(), ReconError> {
        let (p, k) = (self.rows(), self.frame_len());
        if dv.len() != k {
            return Err(ReconError::FrameLength {
                what: "frame",
                got: dv.len(),
                k,
            });
        }
        if out.len() != p {
            return Err(ReconError::Size {
                what: "the output's rows",
                got: out.len(),
                expected: p,
            });
        }
        let (mut stack, mut heap) = ([0.0f32; 512], Vec::new());
        let y = if self.rank() <= stack.len() {
            &mut stack[..self.rank()]
        } else {
            heap.resize(self.rank(), 0.0);
            &mut heap[..]
        };
        match &self.core {
            Core::Full(core) => core.apply(dv, y),
            Core::Gathered { core, gather } => {
                // z (r values) and C' z (q values) in f64, on the stack for up to 32 electrodes.
                let (r, q) = (core.ncols(), core.nrows());
                let (mut stack, mut heap) = ([0.0f64; 1024], Vec::new());
                let scratch = if r + q <= stack.len() {
                    &mut stack[..r + q]
                } else {
                    heap.resize(r + q, 0.0);
                    &mut heap[..]
                };
                let (z, cz) = scratch.split_at_mut(r);
                gather.apply(dv, z);
                matmul(
                    MatMut::from_column_major_slice_mut(cz, q, 1),
                    Accum::Replace,
                    core.as_ref(),
                    MatRef::from_column_major_slice(z, r, 1),
                    1.0,
                    Par::Seq,
                );
                for (y, v) in y.iter_mut().zip(cz.iter()) {
                    *y = *v as f32;
                }
            }
        }
        self.left.apply(y, out);
        Ok(())
    }

    /// A frame as every imaging path applies it: dV (K values, V, as f64) rounded to f32, then
    /// [`FrameOperator::apply`]; one value per row.
    ///
    /// # Errors
    /// [`ReconError::NonFinite`] for a value that is NaN or infinite in f32,
    /// [`ReconError::FrameLength`] for a wrong length.
    pub fn image(&self, dv: &[f64]) -> Result<Vec<f32>, ReconError> {
        let dv: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        let mut out = vec![0.0f32; self.rows()];
        self.apply(&dv, &mut out)?;
        Ok(out)
    }

    /// P multiplied out (rows x K), from the stored factors.
    #[must_use]
    pub fn dense(&self) -> DMatrix<f32> {
        let core = self.core_dense();
        let left = Mat::from_fn(self.rows(), self.rank(), |i, j| {
            f64::from(self.left.get(i, j))
        });
        // One matrix product (faer's, blocked on the vector unit: rows x rank x K
        // multiply-adds, 3 300 x 496 x 2 356 for 32 electrodes onto the pixels).
        let p = crate::onestep::product(left.as_ref(), core.as_ref());
        DMatrix::from_fn(self.rows(), self.frame_len(), |i, k| p[(i, k)] as f32)
    }

    /// C (q x K) as stored: C' M^T when M^T is kept.
    fn core_dense(&self) -> Mat<f64> {
        match &self.core {
            Core::Full(core) => {
                Mat::from_fn(core.rows(), core.cols(), |i, j| f64::from(core.get(i, j)))
            }
            Core::Gathered { core, gather } => gather.times(core, self.frame_len),
        }
    }

    /// The standard deviation of each row's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2): sqrt(sum_k P_pk^2 var_k) = |L_p W| with W = C
    /// diag(sqrt var) (q x K), computed through the q x q Gram matrix W W^T. Negative
    /// variances count as 0.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] when `var_dv` does not hold K values.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        if var_dv.len() != self.frame_len() {
            return Err(ReconError::FrameLength {
                what: "variances",
                got: var_dv.len(),
                k: self.frame_len(),
            });
        }
        let core = self.core_dense();
        let w = Mat::from_fn(self.rank(), self.frame_len(), |i, k| {
            core[(i, k)] * var_dv[k].max(0.0).sqrt()
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
