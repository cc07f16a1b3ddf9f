//! The NOSER prior's weights P^-1 = diag(J^T J)^-s, from a Jacobian whole or factored.

use nalgebra::DMatrix;

/// The NOSER weights P^-1 = diag(J^T J)^-s (a column that sees nothing gets the smallest
/// positive weight's), or None when every column is zero.
pub(crate) fn noser_inverse(jac: &DMatrix<f64>, s: f64) -> Option<Vec<f64>> {
    let diag: Vec<f64> = (0..jac.ncols())
        .map(|c| jac.column(c).norm_squared())
        .collect();
    noser_weights(&diag, s)
}

/// P^-1 = diag^-s from diag(J^T J) (`diag`, T values), as [`noser_inverse`].
pub(super) fn noser_weights(diag: &[f64], s: f64) -> Option<Vec<f64>> {
    let floor = diag
        .iter()
        .copied()
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    floor
        .is_finite()
        .then(|| diag.iter().map(|d| d.max(floor).powf(-s)).collect())
}

/// diag(J^T J) for J = M G (M's K rows `combination` over G's r rows; G r x T): |M g_t|^2
/// for each of G's columns g_t. Sixteen columns at a time, laid out side by side, so that each
/// row of M combines them in one vectorised pass.
#[must_use]
pub fn jtj_diagonal(combination: &[Vec<(usize, f64)>], g: &DMatrix<f64>) -> Vec<f64> {
    const B: usize = 16;
    let (r, t) = g.shape();
    let mut diag = vec![0.0; t];
    // tile[p][j] = G[p, t0 + j].
    let mut tile = vec![[0.0f64; B]; r];
    for t0 in (0..t).step_by(B) {
        let w = B.min(t - t0);
        for (p, lane) in tile.iter_mut().enumerate() {
            for (j, v) in lane.iter_mut().enumerate() {
                *v = if j < w { g[(p, t0 + j)] } else { 0.0 };
            }
        }
        let mut sum = [0.0f64; B];
        for row in combination {
            let mut acc = [0.0f64; B];
            for &(p, c) in row {
                for (a, v) in acc.iter_mut().zip(&tile[p]) {
                    *a += c * v;
                }
            }
            for (s, a) in sum.iter_mut().zip(&acc) {
                *s += a * a;
            }
        }
        diag[t0..t0 + w].copy_from_slice(&sum[..w]);
    }
    diag
}
