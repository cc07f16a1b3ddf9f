//! An f32 matrix packed for matrix-vector products at memory speed.
//!
//! A frame's image is a matrix-vector product y = A x whose matrix (tens of thousands of rows,
//! a hundred or two columns) is read from cache or memory once per frame, so its speed is the
//! speed of reading A. [`Panels`] stores A in panels of W rows (W = 8 vector registers of f32
//! lanes: 64 with AVX2), each panel's columns one after another, so the product streams the
//! matrix in one sequential pass: for every column j, eight vector fused multiply-adds of the
//! panel's W values by x_j into eight accumulators held in registers. The instruction set is
//! chosen when the program runs (pulp's dispatch: AVX2 and FMA where the processor has them,
//! else SSE2 or plain arithmetic), never fixed at build time.

use pulp::{Arch, Simd, WithSimd};

/// Vector registers a panel fills: enough independent accumulators to hide the latency of a
/// fused multiply-add (4 cycles, 2 a cycle on current x86 cores).
const REGISTERS: usize = 8;

/// The widest panel any instruction set here packs: 8 registers of 16 f32 lanes.
const MAX_WIDTH: usize = REGISTERS * 16;

/// An f32 matrix (rows x cols) in panels of `width` rows; the last panel is padded with zeros.
#[derive(Clone, Debug, PartialEq)]
pub struct Panels {
    rows: usize,
    cols: usize,
    /// Rows per panel, REGISTERS x the f32 lanes of this processor's vectors.
    width: usize,
    /// Panel p, column j, row i of the panel at `p * width * cols + j * width + i`.
    data: Vec<f32>,
}

/// This processor's f32 lanes per vector register.
struct Lanes;

impl WithSimd for Lanes {
    type Output = usize;
    #[inline(always)]
    fn with_simd<S: Simd>(self, _simd: S) -> usize {
        S::F32_LANES
    }
}

impl Panels {
    /// The `rows` x `cols` matrix whose entry (i, j) is `entry(i, j)`.
    pub fn from_fn(rows: usize, cols: usize, mut entry: impl FnMut(usize, usize) -> f32) -> Self {
        let width = (REGISTERS * Arch::new().dispatch(Lanes)).min(MAX_WIDTH);
        let panels = rows.div_ceil(width);
        let mut data = vec![0.0f32; panels * width * cols];
        for (p, panel) in data.chunks_exact_mut((width * cols).max(1)).enumerate() {
            for (j, column) in panel.chunks_exact_mut(width).enumerate() {
                for (i, v) in column.iter_mut().enumerate() {
                    let row = p * width + i;
                    if row < rows {
                        *v = entry(row, j);
                    }
                }
            }
        }
        Self {
            rows,
            cols,
            width,
            data,
        }
    }

    /// Rows.
    #[must_use]
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Columns.
    #[must_use]
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Entry (i, j).
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> f32 {
        let (p, r) = (i / self.width, i % self.width);
        self.data[p * self.width * self.cols + j * self.width + r]
    }

    /// Bytes the product reads (the padded matrix).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.data.len() * size_of::<f32>()
    }

    /// `out` = A `x`: `x` of `cols` values, `out` of `rows`.
    ///
    /// # Panics
    /// When the lengths do not match (the callers check them against their own sizes first).
    pub fn apply(&self, x: &[f32], out: &mut [f32]) {
        assert!(x.len() == self.cols && out.len() == self.rows);
        Arch::new().dispatch(Product { a: self, x, out });
    }
}

/// One product A x into `out`, run with the processor's vectors.
struct Product<'a> {
    a: &'a Panels,
    x: &'a [f32],
    out: &'a mut [f32],
}

impl WithSimd for Product<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, simd: S) {
        let Product { a, x, out } = self;
        let w = a.width;
        if a.cols == 0 {
            out.fill(0.0);
            return;
        }
        for (panel, out) in a.data.chunks_exact(w * a.cols).zip(out.chunks_mut(w)) {
            let mut sum = [0.0f32; MAX_WIDTH];
            if w == REGISTERS * S::F32_LANES {
                let mut acc = [simd.splat_f32s(0.0); REGISTERS];
                for (column, &xj) in panel.chunks_exact(w).zip(x) {
                    let (v, _) = S::as_simd_f32s(column);
                    let Ok(v) = <&[S::f32s; REGISTERS]>::try_from(v) else {
                        unreachable!("a panel column is REGISTERS vectors")
                    };
                    let xj = simd.splat_f32s(xj);
                    for (acc, v) in acc.iter_mut().zip(v) {
                        *acc = simd.mul_add_f32s(*v, xj, *acc);
                    }
                }
                let (lanes, _) = S::as_mut_simd_f32s(&mut sum[..w]);
                lanes.copy_from_slice(&acc);
            } else {
                // Packed on a processor with other vectors (not expected within one process).
                for (column, &xj) in panel.chunks_exact(w).zip(x) {
                    for (s, v) in sum.iter_mut().zip(column) {
                        *s = v.mul_add(xj, *s);
                    }
                }
            }
            out.copy_from_slice(&sum[..out.len()]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The product against a plain f64 sum of the same f32 entries, for shapes around the
    /// panel width (empty, one row, a partial last panel, several panels).
    #[test]
    fn the_packed_product_is_the_matrix_vector_product() {
        for (rows, cols) in [
            (0, 3),
            (1, 1),
            (5, 0),
            (7, 3),
            (64, 5),
            (65, 17),
            (300, 120),
        ] {
            let entry = |i: usize, j: usize| ((i * 31 + j * 17) % 23) as f32 / 7.0 - 1.5;
            let a = Panels::from_fn(rows, cols, entry);
            assert_eq!((a.rows(), a.cols()), (rows, cols));
            let x: Vec<f32> = (0..cols).map(|j| (j as f32 * 0.37).sin()).collect();
            let mut out = vec![f32::NAN; rows];
            a.apply(&x, &mut out);
            for i in 0..rows {
                if cols > 0 {
                    assert_eq!(a.get(i, cols - 1), entry(i, cols - 1));
                }
                let exact: f64 = (0..cols)
                    .map(|j| f64::from(entry(i, j)) * f64::from(x[j]))
                    .sum();
                let scale: f64 = (0..cols)
                    .map(|j| (f64::from(entry(i, j)) * f64::from(x[j])).abs())
                    .sum::<f64>()
                    .max(1.0);
                assert!(
                    (f64::from(out[i]) - exact).abs() <= 1e-6 * scale,
                    "{rows} x {cols}, row {i}: {} against {exact}",
                    out[i]
                );
            }
        }
    }
}
