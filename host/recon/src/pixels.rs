//! Pixel grids over a mesh: images drawn on pixels cost two thin products per frame.

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use nalgebra::DMatrix;

use crate::mesh::Mesh;
use crate::onestep::{OneStep, ReconError, product};

/// A pixel grid over a mesh: which triangle each pixel centre lies in.
#[derive(Clone, Debug)]
pub struct PixelGrid {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// Lower-left corner and pixel size, m: pixel (i, j) (column i, row j from the bottom)
    /// is centred at (x0 + (i + 1/2) size, y0 + (j + 1/2) size).
    pub origin: [f64; 2],
    /// Pixel size, m.
    pub size: f64,
    /// Triangle under each pixel (row-major from the bottom row), None outside the sheet.
    pub triangle: Vec<Option<usize>>,
}

impl PixelGrid {
    /// A grid `pixels` across the mesh's longer side.
    #[must_use]
    pub fn new(mesh: &Mesh, pixels: usize) -> Self {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in &mesh.nodes {
            for d in 0..2 {
                lo[d] = lo[d].min(p[d]);
                hi[d] = hi[d].max(p[d]);
            }
        }
        let size = (hi[0] - lo[0]).max(hi[1] - lo[1]) / pixels.max(1) as f64;
        let width = ((hi[0] - lo[0]) / size).round().max(1.0) as usize;
        let height = ((hi[1] - lo[1]) / size).round().max(1.0) as usize;
        let mut triangle = vec![None; width * height];
        // Each triangle claims the pixel centres inside it (barycentric test on its box).
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let p = tri.map(|i| mesh.nodes[i]);
            let bx = |d: usize, f: fn(f64, f64) -> f64| f(f(p[0][d], p[1][d]), p[2][d]);
            let i0 = (((bx(0, f64::min) - lo[0]) / size - 0.5).ceil().max(0.0)) as usize;
            let i1 = (((bx(0, f64::max) - lo[0]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let j0 = (((bx(1, f64::min) - lo[1]) / size - 0.5).ceil().max(0.0)) as usize;
            let j1 = (((bx(1, f64::max) - lo[1]) / size - 0.5).floor().max(-1.0) + 1.0) as usize;
            let area2 = mesh.double_area(t);
            for j in j0..j1.min(height) {
                for i in i0..i1.min(width) {
                    let c = [
                        lo[0] + (i as f64 + 0.5) * size,
                        lo[1] + (j as f64 + 0.5) * size,
                    ];
                    let w = |a: [f64; 2], b: [f64; 2]| {
                        ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])) / area2
                    };
                    let eps = -1e-12;
                    if w(p[0], p[1]) >= eps && w(p[1], p[2]) >= eps && w(p[2], p[0]) >= eps {
                        triangle[j * width + i].get_or_insert(t);
                    }
                }
            }
        }
        Self {
            width,
            height,
            origin: lo,
            size,
            triangle,
        }
    }

    /// Centre of pixel `index`, m.
    #[must_use]
    pub fn centre(&self, index: usize) -> [f64; 2] {
        let (i, j) = (index % self.width, index / self.width);
        [
            self.origin[0] + (i as f64 + 0.5) * self.size,
            self.origin[1] + (j as f64 + 0.5) * self.size,
        ]
    }

    /// The 4 neighbours of pixel `index` (left, right, below, above; None off the grid).
    #[must_use]
    pub fn neighbours(&self, index: usize) -> [Option<usize>; 4] {
        let (i, j) = (index % self.width, index / self.width);
        [
            (i > 0).then(|| index - 1),
            (i + 1 < self.width).then(|| index + 1),
            (j > 0).then(|| index - self.width),
            (j + 1 < self.height).then(|| index + self.width),
        ]
    }

    /// The outline of the pixels `member` marks (one flag per pixel): each edge between a
    /// member and a non-member (or the grid's edge), as its two ends, m. Drawn as line
    /// segments it outlines a region of interest.
    #[must_use]
    pub fn outline(&self, member: &[bool]) -> Vec<[[f64; 2]; 2]> {
        let is = |p: Option<usize>| p.is_some_and(|p| member.get(p).copied().unwrap_or(false));
        let corner = |i: usize, j: usize| {
            [
                self.origin[0] + i as f64 * self.size,
                self.origin[1] + j as f64 * self.size,
            ]
        };
        let mut edges = Vec::new();
        for p in (0..self.width * self.height).filter(|&p| is(Some(p))) {
            let (i, j) = (p % self.width, p / self.width);
            let [left, right, below, above] = self.neighbours(p);
            for (next, a, b) in [
                (left, corner(i, j), corner(i, j + 1)),
                (right, corner(i + 1, j), corner(i + 1, j + 1)),
                (below, corner(i, j), corner(i + 1, j)),
                (above, corner(i, j + 1), corner(i + 1, j + 1)),
            ] {
                if !is(next) {
                    edges.push([a, b]);
                }
            }
        }
        edges
    }

    /// Mean of the centres of `pixels`, m ([0, 0] for none).
    #[must_use]
    pub fn centroid(&self, pixels: &[usize]) -> [f64; 2] {
        let n = pixels.len().max(1) as f64;
        pixels.iter().fold([0.0; 2], |c, &p| {
            let x = self.centre(p);
            [c[0] + x[0] / n, c[1] + x[1] / n]
        })
    }

    /// The reconstruction matrix onto the pixels (one row per pixel inside the sheet, in
    /// pixel order), as a [`PixelOperator`].
    #[must_use]
    pub fn project(&self, r: &OneStep) -> PixelOperator {
        let inside: Vec<usize> = self.triangle.iter().filter_map(|t| *t).collect();
        PixelOperator::of_rows(r, &inside)
    }

    /// Spreads per-triangle values onto the grid (None outside the sheet).
    #[must_use]
    pub fn image(&self, per_triangle: &[f64]) -> Vec<Option<f64>> {
        self.triangle
            .iter()
            .map(|t| t.map(|t| per_triangle[t]))
            .collect()
    }
}

/// A reconstruction matrix onto pixels, P (pixels inside the sheet x K), kept as two thin
/// factors in f32, P = L C with L (pixels x q) and C (q x K), q the numerical rank of P: a
/// frame reads q (pixels + K) numbers instead of pixels K. One-step Gauss-Newton and GREIT
/// both reach the pixels through the r transfer impedances (r = L (L - 1) / 2 for L
/// electrodes: 120 for 16), so q <= r, and fewer when the protocol has fewer independent
/// values (104 for 16 electrodes adjacent): a 64 x 64 frame on a disc reads 0.36 M numbers
/// instead of 0.67 M. The factors come from a QR factor of the pixels' side and a singular
/// value decomposition of the r x K core; only singular values below 1e-7 of the largest
/// (what f32 cannot resolve) are dropped.
#[derive(Clone, Debug)]
pub struct PixelOperator {
    /// L, pixels x q.
    left: Mat<f32>,
    /// C, q x K.
    core: Mat<f32>,
}

impl PixelOperator {
    /// The rows of R for `rows` (each one of R's rows: a triangle, or a pixel of GREIT's
    /// matrix) from R's factors R = (G P^-1)^T X^T.
    #[must_use]
    pub fn of_rows(r: &OneStep, rows: &[usize]) -> Self {
        let g = Mat::from_fn(rows.len(), r.gp.nrows(), |i, j| r.gp[(j, rows[i])]);
        Self::from_factors(g.as_ref(), r.xt.as_ref())
    }

    /// P = `a` `b` from `a` (pixels x r) and `b` (r x K).
    pub(crate) fn from_factors(a: MatRef<'_, f64>, b: MatRef<'_, f64>) -> Self {
        let qr = a.qr();
        let (q, r) = (qr.compute_thin_Q(), qr.thin_R());
        let core = product(r, b);
        let (left, core) = match core.thin_svd() {
            Ok(svd) => {
                let s = svd.S().column_vector();
                let top = s.iter().copied().fold(0.0f64, f64::max);
                let rank = s.iter().filter(|&&x| x > 1e-7 * top).count();
                let left = product(q.as_ref(), svd.U().subcols(0, rank));
                let v = svd.V();
                let core = Mat::from_fn(rank, b.ncols(), |i, k| s[i] * v[(k, i)]);
                (left, core)
            }
            // Not expected for finite input; the untruncated factors are as exact.
            Err(_) => (q, core),
        };
        let f32_of = |m: &Mat<f64>| Mat::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)] as f32);
        Self {
            left: f32_of(&left),
            core: f32_of(&core),
        }
    }

    /// Pixels (rows of P).
    #[must_use]
    pub fn pixels(&self) -> usize {
        self.left.nrows()
    }

    /// K, the frame length (columns of P).
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.core.ncols()
    }

    /// q, the rank the factors keep.
    #[must_use]
    pub fn rank(&self) -> usize {
        self.core.nrows()
    }

    /// A live frame onto the pixels: P `dv` (K values, V) into `out` (one value per pixel
    /// inside), as C dv (q values) then L times that, faer's f32 kernels on one core.
    ///
    /// # Errors
    /// [`ReconError::Parameter`] when `dv` does not hold K values or `out` not one per pixel.
    pub fn apply(&self, dv: &[f32], out: &mut [f32]) -> Result<(), ReconError> {
        let (p, k) = (self.pixels(), self.frame_len());
        if dv.len() != k || out.len() != p {
            return Err(ReconError::Parameter(format!(
                "{} values into {} pixels for a projection of {p} x {k}",
                dv.len(),
                out.len()
            )));
        }
        let mut y = Mat::<f32>::zeros(self.rank(), 1);
        let dv = MatRef::from_column_major_slice(dv, k, 1);
        matmul(
            y.as_mut(),
            Accum::Replace,
            self.core.as_ref(),
            dv,
            1.0,
            Par::Seq,
        );
        let out = MatMut::from_column_major_slice_mut(out, p, 1);
        matmul(
            out,
            Accum::Replace,
            self.left.as_ref(),
            y.as_ref(),
            1.0,
            Par::Seq,
        );
        Ok(())
    }

    /// P multiplied out (pixels x K).
    #[must_use]
    pub fn dense(&self) -> DMatrix<f32> {
        let m = product_f32(self.left.as_ref(), self.core.as_ref());
        DMatrix::from_fn(self.pixels(), self.frame_len(), |i, k| m[(i, k)])
    }

    /// The standard deviation of each pixel's value when dV carries independent noise of
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
            f64::from(self.core[(i, k)]) * var_dv[k].max(0.0).sqrt()
        });
        let gram = product(w.as_ref(), w.transpose());
        let left = Mat::from_fn(self.pixels(), self.rank(), |p, i| {
            f64::from(self.left[(p, i)])
        });
        let lg = product(left.as_ref(), gram.as_ref());
        Ok((0..self.pixels())
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

/// a b in f32, one core.
fn product_f32(a: MatRef<'_, f32>, b: MatRef<'_, f32>) -> Mat<f32> {
    let mut out = Mat::<f32>::zeros(a.nrows(), b.ncols());
    matmul(out.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(width: usize, height: usize) -> PixelGrid {
        PixelGrid {
            width,
            height,
            origin: [-0.01, 0.02],
            size: 0.005,
            triangle: vec![Some(0); width * height],
        }
    }

    /// Total length of an outline, m.
    fn length(edges: &[[[f64; 2]; 2]]) -> f64 {
        edges
            .iter()
            .map(|[a, b]| (a[0] - b[0]).hypot(a[1] - b[1]))
            .sum()
    }

    #[test]
    fn outlines_are_the_perimeter_of_the_marked_pixels() {
        let g = grid(4, 3);
        let mut member = vec![false; 12];
        assert!(g.outline(&member).is_empty());
        // One pixel inside: its four sides, around its own centre.
        member[5] = true;
        let one = g.outline(&member);
        assert_eq!(one.len(), 4);
        assert!((length(&one) - 4.0 * g.size).abs() < 1e-15);
        let c = g.centre(5);
        for [a, b] in &one {
            let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            let d = (mid[0] - c[0]).abs().max((mid[1] - c[1]).abs());
            assert!((d - g.size / 2.0).abs() < 1e-15, "{mid:?} around {c:?}");
        }
        // Its right-hand neighbour joins it: the shared side is gone (a 2 x 1 rectangle).
        member[6] = true;
        let two = g.outline(&member);
        assert_eq!(two.len(), 6);
        assert!((length(&two) - 6.0 * g.size).abs() < 1e-15);
        // The whole grid: its border, whatever the grid's edge (no neighbour) is.
        let all = g.outline(&[true; 12]);
        assert_eq!(all.len(), 2 * (4 + 3));
        // Flags beyond the grid are ignored; a short list marks only what it covers.
        assert_eq!(g.outline(&[true]).len(), 4);
    }
}
