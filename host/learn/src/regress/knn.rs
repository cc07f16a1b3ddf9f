//! k nearest neighbours: the mean position of the k closest training rows in z-space.

use super::*;

/// How the k nearest neighbours' targets are averaged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Weighting {
    /// Each neighbour counts the same.
    Uniform,
    /// Each neighbour counts 1 / its distance (an exact match takes all the weight).
    Distance,
}

/// The most memory the distances of one block of rows take in [`Knn::neighbours`], bytes.
const DISTANCE_BLOCK_BYTES: usize = 64 << 20;

/// k-nearest-neighbour regression in z-space: the mean (or inverse-distance weighted mean) of
/// the targets of the k training observations nearest to a frame.
#[derive(Clone, Debug)]
pub struct Knn {
    pub(crate) mean: Vec<f64>,
    pub(crate) scale: Vec<f64>,
    /// m x p training observations in z-space.
    pub(crate) support: Mat<f64>,
    /// Their targets.
    pub(crate) targets: Vec<Target3>,
    pub(crate) k: usize,
    pub(crate) weighting: Weighting,
}

impl Knn {
    /// Keeps the (standardised) observations.
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data, or k = 0.
    pub fn fit(
        x: &DMatrix<f64>,
        t: &[Target3],
        k: usize,
        weighting: Weighting,
    ) -> Result<Self, FitError> {
        check(x, t)?;
        if k == 0 {
            return Err(FitError::NoNeighbours);
        }
        let (mean, scale) = standardisation(x);
        let support = z_space(x, &mean, &scale);
        Ok(Self {
            mean,
            scale,
            support,
            targets: t.to_vec(),
            k: k.min(x.nrows()),
            weighting,
        })
    }

    /// For every row of `x` (n x p, volts), its `k_max` nearest training observations as
    /// (squared distance, index), nearest first: the distances as matrix products, a block of
    /// rows at a time (one m x n matrix of them took 19 GB for 50 000 rows of 16 features).
    #[must_use]
    pub fn neighbours(&self, x: &DMatrix<f64>, k_max: usize) -> Vec<Vec<(f64, usize)>> {
        // Rows per block: their distances (an f32 product and its f64 result, 12 bytes each)
        // within DISTANCE_BLOCK_BYTES.
        let block = DISTANCE_BLOCK_BYTES / (12 * self.support.nrows().max(1));
        self.neighbours_in_blocks(x, k_max, block)
    }

    /// [`neighbours`](Self::neighbours) with the distances of `block` rows at a time.
    #[must_use]
    pub fn neighbours_in_blocks(
        &self,
        x: &DMatrix<f64>,
        k_max: usize,
        block: usize,
    ) -> Vec<Vec<(f64, usize)>> {
        let z = z_space(x, &self.mean, &self.scale);
        let m = self.support.nrows();
        let k = k_max.clamp(1, m);
        let block = block.max(1);
        let mut all: Vec<(f64, usize)> = Vec::with_capacity(m);
        let mut out = Vec::with_capacity(z.nrows());
        for start in (0..z.nrows()).step_by(block) {
            let rows = block.min(z.nrows() - start);
            let part = z.as_ref().subrows(start, rows).to_owned();
            // m x rows: each row's distances to the support are a contiguous column.
            let d2 = squared_distances_f32(&self.support, &part);
            out.extend((0..d2.ncols()).map(|r| {
                all.clear();
                all.extend(d2.col(r).iter().copied().zip(0..));
                all.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
                let mut near = all.get(..k).unwrap_or(&all).to_vec();
                near.sort_by(|a, b| a.0.total_cmp(&b.0));
                near
            }));
        }
        out
    }

    /// The prediction from `near` (a row of [`neighbours`](Self::neighbours)) with `k`
    /// neighbours and `weighting`.
    #[must_use]
    pub fn combine(&self, near: &[(f64, usize)], k: usize, weighting: Weighting) -> Target3 {
        let near = near.get(..k.min(near.len())).unwrap_or(near);
        let weights: Vec<f64> = match weighting {
            Weighting::Uniform => vec![1.0; near.len()],
            Weighting::Distance => {
                if let Some(&(_, i)) = near.iter().find(|(d, _)| *d <= 1e-24) {
                    return self.targets[i];
                }
                near.iter().map(|(d, _)| 1.0 / d.sqrt()).collect()
            }
        };
        let total: f64 = weights.iter().sum();
        let mut out = [0.0; 3];
        for (w, &(_, i)) in weights.iter().zip(near) {
            for c in 0..3 {
                out[c] += w / total * self.targets[i][c];
            }
        }
        out
    }

    /// Predicts every row of `x` (n x p, volts).
    #[must_use]
    pub fn predict_many(&self, x: &DMatrix<f64>) -> Vec<Target3> {
        self.neighbours(x, self.k)
            .iter()
            .map(|near| self.combine(near, self.k, self.weighting))
            .collect()
    }

    /// Seconds finding the `k_max` nearest neighbours of `queries` rows among `support` rows
    /// like `x`'s takes, timed on a piece: up to 256 of `x`'s rows against the support
    /// (the time grows as queries x support; knn's cross-validation of 50 000 rows took
    /// 137 s and said nothing beforehand).
    #[must_use]
    pub fn estimate_seconds(x: &DMatrix<f64>, support: usize, queries: usize, k_max: usize) -> f64 {
        let support = support.clamp(2, x.nrows().max(2));
        let rows = |n: usize| DMatrix::from_fn(n, x.ncols(), |r, c| x[(r % x.nrows().max(1), c)]);
        let stored = rows(support);
        let targets = vec![[0.0; 3]; support];
        let Ok(model) = Knn::fit(&stored, &targets, 1, Weighting::Uniform) else {
            return 0.0;
        };
        let probe = rows(queries.clamp(1, 256));
        let started = std::time::Instant::now();
        let _ = model.neighbours(&probe, k_max);
        started.elapsed().as_secs_f64() * queries as f64 / probe.nrows() as f64
    }

    /// Multiply-adds per prediction (distances to every stored observation).
    #[must_use]
    pub fn cost(&self) -> usize {
        self.support.nrows() * self.support.ncols()
    }
}
