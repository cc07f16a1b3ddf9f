//! A frame operator's entries squared, row by row: each row's noise under channel variances
//! that change from frame to frame, one row at a time.

use super::FrameOperator;

/// P's entries squared, P_ik^2 (rows x K, row-major: a row is contiguous). A row's noise
/// variance under channel variances var_k is sum_k P_ik^2 var_k: the live pipeline makes it
/// for a touched frame's region pixels alone.
#[derive(Clone, Debug)]
pub struct SquaredRows {
    /// K, the values of a frame.
    k: usize,
    squares: Vec<f32>,
    /// The instruction set the dot products run with, found once.
    arch: pulp::Arch,
}

impl SquaredRows {
    /// The squared rows of `op` (from [`FrameOperator::dense`]).
    #[must_use]
    pub fn of(op: &FrameOperator) -> Self {
        let dense = op.dense();
        Self {
            k: dense.ncols(),
            squares: (0..dense.nrows())
                .flat_map(|i| dense.row(i).iter().map(|p| p * p).collect::<Vec<_>>())
                .collect(),
            arch: pulp::Arch::new(),
        }
    }

    /// Row `i`'s noise standard deviation under the channels' variances `var` (K values,
    /// V^2): sqrt(sum_k P_ik^2 var_k). None for a row out of range or `var` not of K values.
    #[must_use]
    pub fn sd(&self, i: usize, var: &[f32]) -> Option<f64> {
        if var.len() != self.k {
            return None;
        }
        let row = self.squares.get(i * self.k..(i + 1) * self.k)?;
        // Dispatched to the widest vector instructions the machine has (AVX2 and FMA on
        // x86-64), where the compiler vectorises the eight running sums.
        let sum = self.arch.dispatch(
            #[inline(always)]
            || dot(row, var),
        );
        Some(f64::from(sum).sqrt())
    }
}

/// sum_k a_k b_k over equal lengths, in eight running sums (one vector register).
#[inline(always)]
fn dot(a: &[f32], b: &[f32]) -> f32 {
    let mut sums = [0.0f32; 8];
    let (a8, a_rest) = a.as_chunks::<8>();
    let (b8, b_rest) = b.as_chunks::<8>();
    for (x, y) in a8.iter().zip(b8) {
        for j in 0..8 {
            sums[j] += x[j] * y[j];
        }
    }
    let rest: f32 = a_rest.iter().zip(b_rest).map(|(x, y)| x * y).sum();
    sums.iter().sum::<f32>() + rest
}
