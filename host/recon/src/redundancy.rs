//! The noise of one frame difference from the protocol's redundancy: a frame's K values are
//! combinations of the r = L (L - 1) / 2 transfer impedances (J = M G,
//! [`TransferJacobian`]), so whatever part of dV lies outside M's range no change of
//! conductivity, contact or gain can make. With one reference frame and no repeated frames
//! that part is the only measure of the noise there is (reciprocal pairs are its simplest
//! case: a pair's two values must agree).

use faer::Mat;

use crate::fem::TransferJacobian;

/// The fewest redundant directions an estimate is made from (fewer: no estimate).
pub const MIN_REDUNDANCY: usize = 8;

/// The noise of dV seen in the protocol's redundancy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RedundancyNoise {
    /// |dV - P_M dV|^2 / (K - rank M), V^2: each value's noise variance, taken as alike.
    pub variance: f64,
    /// K - rank(M): how many independent directions the estimate rests on.
    pub dof: usize,
}

/// M's range (K x r, sparse) as a basis in the r-space: with N = M^T M = V diag(n) V^T over
/// the eigenvalues n above 1e-10 of the largest, |P_M dV|^2 = sum_i (v_i^T M^T dV)^2 / n_i.
#[derive(Clone, Debug)]
pub struct Redundancy {
    /// M's K rows: (pair, coefficient) over the r pairs.
    pub combination: Vec<Vec<(usize, f64)>>,
    /// V diag(n)^-1/2, r x rank(M).
    pub basis: Mat<f64>,
}

impl Redundancy {
    /// The redundancy of `jac`'s protocol; None when N has no eigendecomposition.
    #[must_use]
    pub fn of(jac: &TransferJacobian) -> Option<Self> {
        let r = jac.pairs();
        let (v, n) = crate::onestep::normal_range(&jac.combination, r)?;
        Some(Self {
            combination: jac.combination.clone(),
            basis: Mat::from_fn(r, n.len(), |i, j| v[(i, j)] / n[j].sqrt()),
        })
    }

    /// K - rank(M): the protocol's redundant values.
    #[must_use]
    pub fn dof(&self) -> usize {
        self.combination.len().saturating_sub(self.basis.ncols())
    }

    /// The noise of `dv` (K values, V) from the protocol's redundancy (see the module docs);
    /// None when the protocol has fewer than [`MIN_REDUNDANCY`] redundant values or `dv` is not
    /// of K finite values.
    #[must_use]
    pub fn noise(&self, dv: &[f64]) -> Option<RedundancyNoise> {
        let dof = self.dof();
        if dv.len() != self.combination.len() || dof < MIN_REDUNDANCY {
            return None;
        }
        if dv.iter().any(|v| !v.is_finite()) {
            return None;
        }
        let mut mtdv = vec![0.0; self.basis.nrows()];
        for (row, v) in self.combination.iter().zip(dv) {
            for &(p, c) in row {
                mtdv[p] += c * v;
            }
        }
        let seen: f64 = (crate::onestep::transposed_times(&self.basis, &mtdv).iter())
            .map(|p| p * p)
            .sum();
        let total: f64 = dv.iter().map(|v| v * v).sum();
        Some(RedundancyNoise {
            variance: (total - seen).max(0.0) / dof as f64,
            dof,
        })
    }
}
