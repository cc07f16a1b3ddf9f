//! What a kernel ridge search will take, timed on pieces of its work before it starts.

use nalgebra::DMatrix;

use super::KernelRidge;

impl KernelRidge {
    /// Seconds a cross-validation of `candidates` (width, lambda) pairs over `k` folds of
    /// rows like `x`'s (n x p) takes, each fold fitted on `search_support` of its rows and
    /// predicting its held-out rows `1 + draws` times (as measured and drifted), then the
    /// final fit on `final_support` rows. Timed on pieces of the same shapes: one fit on the
    /// search's support (the distances and a Cholesky factor of m x m, one per candidate)
    /// and a block of up to 512 rows predicted against it (the distances once, the kernel
    /// and its product per candidate); the final fit scaled from the first as m^3. Kernel
    /// ridge's time grows with the rows predicted (50 000 rows took 85 s and said nothing
    /// beforehand).
    #[must_use]
    pub fn estimate_seconds(
        x: &DMatrix<f64>,
        (k, candidates, draws): (usize, usize, usize),
        (search_support, final_support): (usize, usize),
    ) -> f64 {
        let (n, k) = (x.nrows(), k.max(1));
        if n < 2 || x.ncols() == 0 {
            return 0.0;
        }
        let held_out = n.div_ceil(k);
        let m = search_support.clamp(2, n.saturating_sub(held_out).max(2));
        // Rows of x's shape, varied so that the kernel is well conditioned.
        let rows = |count: usize| {
            DMatrix::from_fn(count, x.ncols(), |r, c| {
                x[(r % n, c)] + 1e-3 * ((r * 31 + c * 17) % 97) as f64
            })
        };
        let support = rows(m);
        let targets = vec![[0.0; 3]; m];
        let started = std::time::Instant::now();
        let Ok(model) = Self::fit(&support, &targets, m, 1.0, 1e-2) else {
            return 0.0;
        };
        let fit_s = started.elapsed().as_secs_f64();
        let queries = held_out * (1 + draws);
        let probe = rows(queries.clamp(1, 512));
        let started = std::time::Instant::now();
        let d2 = model.distances(&probe);
        let distances_s = started.elapsed().as_secs_f64();
        let started = std::time::Instant::now();
        let _ = model.predict_from_distances(&d2);
        let predict_s = started.elapsed().as_secs_f64();
        let per_row = (distances_s + predict_s * candidates as f64) / probe.nrows() as f64;
        let fold_s = fit_s * candidates as f64 + per_row * queries as f64;
        let last = final_support.clamp(2, n) as f64 / m as f64;
        fold_s * k as f64 + fit_s * last.powi(3)
    }
}
