//! A matrix packed for matrix-vector products at memory speed.
//!
//! A frame's image is a matrix-vector product y = A x whose matrix (tens of thousands of rows,
//! a hundred or two columns) is read from cache or memory once per frame, so its speed is the
//! speed of reading A. [`Panels`] stores A in f32, or in 16-bit fixed point with each row
//! scaled by its own factor (A_ij = s_i n_ij, n_ij an i16, the row's largest entry at 32 767):
//! half the bytes of f32, each entry within 1.5e-5 of its row's largest (f16 would keep 11
//! bits: 4.9e-4). The rows come in panels of W = 64 (8 vector registers of 8 f32 lanes), each
//! panel's columns one after another, so the product streams the matrix in one sequential
//! pass: for every column j, the panel's 64 entries (widened to f32) multiplied by x_j into
//! eight accumulators held in registers, the row scales applied once at the end. With AVX2
//! (found when the program runs, through pulp's safe wrappers: no `unsafe` here) a column of
//! i16 is eight sign extensions, eight conversions and eight fused multiply-adds; other
//! processors run the same sums in plain arithmetic.

#[cfg(target_arch = "x86_64")]
use pulp::{Simd, WithSimd, x86::V3};

/// Vector registers a panel fills: enough independent accumulators to hide the latency of a
/// fused multiply-add (4 cycles, 2 a cycle on current x86 cores).
const REGISTERS: usize = 8;

/// f32 lanes of one AVX2 register.
const LANES: usize = 8;

/// Rows per panel.
const WIDTH: usize = REGISTERS * LANES;

/// What a panel stores per entry: f32 itself, or i16 in fixed point per row.
pub trait Stored: Copy + Default + pulp::bytemuck::Pod + std::fmt::Debug {
    /// s_i for a row whose largest magnitude is `largest` (NaN for a row that is not finite).
    fn scale(largest: f64) -> f32;
    /// The stored value of `v` in a row of scale `s`.
    fn round(v: f64, s: f32) -> Self;
    /// The stored value as f32 (before the row's scale).
    fn widen(self) -> f32;
    /// Eight stored values as f32 lanes (before the row's scale).
    #[cfg(target_arch = "x86_64")]
    fn widen8(v3: V3, n: [Self; LANES]) -> pulp::f32x8;
}

impl Stored for f32 {
    fn scale(_: f64) -> f32 {
        1.0
    }
    fn round(v: f64, _: f32) -> Self {
        v as f32
    }
    #[inline(always)]
    fn widen(self) -> f32 {
        self
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn widen8(_: V3, n: [Self; LANES]) -> pulp::f32x8 {
        pulp::cast(n)
    }
}

/// The largest integer a row's entries are scaled to.
const FULL_SCALE: f64 = i16::MAX as f64;

impl Stored for i16 {
    fn scale(largest: f64) -> f32 {
        (largest / FULL_SCALE) as f32
    }
    fn round(v: f64, s: f32) -> Self {
        // |v / s| <= 32 767 up to s's rounding to f32: clamped, never wrapped.
        let n = (v / f64::from(s)).round().clamp(-FULL_SCALE, FULL_SCALE);
        if n.is_finite() { n as i16 } else { 0 }
    }
    #[inline(always)]
    fn widen(self) -> f32 {
        f32::from(self)
    }
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    fn widen8(v3: V3, n: [Self; LANES]) -> pulp::f32x8 {
        v3.convert_i32x8_to_f32x8(v3.convert_i16x8_to_i32x8(pulp::cast(n)))
    }
}

/// A matrix (rows x cols) of entries stored as `T` with a scale per row, in panels of
/// [`WIDTH`] rows; the last panel is padded with zero rows.
#[derive(Clone, Debug)]
pub struct Panels<T: Stored = f32> {
    rows: usize,
    cols: usize,
    /// Panel p, column j, row i of the panel at `p * WIDTH * cols + j * WIDTH + i`.
    data: Vec<T>,
    /// s_i, one per row (padded to whole panels with zeros): A_ij = s_i n_ij.
    scale: Vec<f32>,
    /// AVX2 and FMA, when this processor has them.
    #[cfg(target_arch = "x86_64")]
    v3: Option<V3>,
}

impl<T: Stored> Panels<T> {
    /// The `rows` x `cols` matrix whose entry (i, j) is `entry(i, j)`, rounded to each row's
    /// fixed point. A row holding a value that is not finite gets a NaN scale (its products
    /// are NaN, as in floating point).
    pub fn from_fn(rows: usize, cols: usize, mut entry: impl FnMut(usize, usize) -> f64) -> Self {
        let panels = rows.div_ceil(WIDTH);
        let mut data = vec![T::default(); panels * WIDTH * cols];
        let mut scale = vec![0.0f32; panels * WIDTH];
        let mut row = vec![0.0f64; cols];
        for i in 0..rows {
            for (j, v) in row.iter_mut().enumerate() {
                *v = entry(i, j);
            }
            let largest = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let finite = row.iter().all(|v| v.is_finite());
            let s = if finite { T::scale(largest) } else { f32::NAN };
            scale[i] = s;
            if s == 0.0 {
                continue;
            }
            let (p, r) = (i / WIDTH, i % WIDTH);
            for (j, v) in row.iter().enumerate() {
                data[p * WIDTH * cols + j * WIDTH + r] = T::round(*v, s);
            }
        }
        Self {
            rows,
            cols,
            data,
            scale,
            #[cfg(target_arch = "x86_64")]
            v3: V3::try_new(),
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

    /// Entry (i, j) as stored: s_i n_ij.
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> f32 {
        let (p, r) = (i / WIDTH, i % WIDTH);
        self.scale[i] * self.data[p * WIDTH * self.cols + j * WIDTH + r].widen()
    }

    /// Bytes the product reads (the padded matrix and its row scales).
    #[must_use]
    pub fn bytes(&self) -> usize {
        self.data.len() * size_of::<T>() + self.scale.len() * size_of::<f32>()
    }

    /// `out` = A `x`: `x` of `cols` values, `out` of `rows`.
    ///
    /// # Panics
    /// When the lengths do not match (the callers check them against their own sizes first).
    pub fn apply(&self, x: &[f32], out: &mut [f32]) {
        assert!(x.len() == self.cols && out.len() == self.rows);
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = self.v3 {
            return Simd::vectorize(
                v3,
                Product {
                    v3,
                    a: self,
                    x,
                    out,
                },
            );
        }
        self.apply_plain(x, out);
    }

    /// The same product in plain arithmetic (processors without AVX2, and the tests).
    pub fn apply_plain(&self, x: &[f32], out: &mut [f32]) {
        if self.cols == 0 {
            out.fill(0.0);
            return;
        }
        let panels = self.data.chunks_exact(WIDTH * self.cols);
        for ((panel, out), scale) in panels
            .zip(out.chunks_mut(WIDTH))
            .zip(self.scale.chunks(WIDTH))
        {
            let mut sum = [0.0f32; WIDTH];
            for (column, &xj) in panel.chunks_exact(WIDTH).zip(x) {
                for (s, &n) in sum.iter_mut().zip(column) {
                    *s = n.widen().mul_add(xj, *s);
                }
            }
            for ((o, s), scale) in out.iter_mut().zip(sum).zip(scale) {
                *o = s * scale;
            }
        }
    }
}

/// One product A x into `out` with AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
struct Product<'a, T: Stored> {
    v3: V3,
    a: &'a Panels<T>,
    x: &'a [f32],
    out: &'a mut [f32],
}

#[cfg(target_arch = "x86_64")]
impl<T: Stored> WithSimd for Product<'_, T> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: Simd>(self, _: S) {
        let Product { v3, a, x, out } = self;
        if a.cols == 0 {
            out.fill(0.0);
            return;
        }
        let panels = a.data.chunks_exact(WIDTH * a.cols);
        for ((panel, out), scale) in panels.zip(out.chunks_mut(WIDTH)).zip(a.scale.chunks(WIDTH)) {
            let mut acc = [v3.splat_f32x8(0.0); REGISTERS];
            for (column, &xj) in panel.chunks_exact(WIDTH).zip(x) {
                let (n, _) = pulp::as_arrays::<LANES, T>(column);
                let xj = v3.splat_f32x8(xj);
                for (acc, n) in acc.iter_mut().zip(n) {
                    *acc = v3.mul_add_f32x8(T::widen8(v3, *n), xj, *acc);
                }
            }
            let (scale, _) = pulp::as_arrays::<LANES, f32>(scale);
            let mut sum = [0.0f32; WIDTH];
            let (lanes, _) = pulp::as_arrays_mut::<LANES, f32>(&mut sum);
            for ((lane, acc), scale) in lanes.iter_mut().zip(acc).zip(scale) {
                *lane = pulp::cast(v3.mul_f32x8(acc, pulp::cast(*scale)));
            }
            out.copy_from_slice(&sum[..out.len()]);
        }
    }
}
