//! A data space of a weighted frame: each value k weighs w_k (the inverse of its error
//! variance), so the fit is that of the whitened frame sqrt(w) dV while every method still
//! takes the frame as measured.

use super::*;

impl DataSpace {
    /// As [`DataSpace::factored`], for a frame whose value k weighs `weights[k]` (K positive
    /// values: the inverse of each value's error variance, to any common scale): the data
    /// space of the whitened frame sqrt(w) dV, with NOSER's prior diag(J^T W J)^s. Every
    /// method still takes the frame as measured; the weights are applied inside.
    ///
    /// # Errors
    /// As [`DataSpace::factored`]; [`ReconError::FrameLength`] or [`ReconError::NotPositive`] for weights not of K positive
    /// finite values.
    pub fn factored_weighted(
        jac: &crate::fem::TransferJacobian,
        s: f64,
        weights: &[f64],
    ) -> Result<Self, ReconError> {
        if weights.len() != jac.combination.len() {
            return Err(ReconError::FrameLength {
                what: "weights",
                got: weights.len(),
                k: jac.combination.len(),
            });
        }
        super::not_positive("weight", weights)?;
        let root: Vec<f64> = weights.iter().map(|w| w.sqrt()).collect();
        let whitened = crate::fem::TransferJacobian {
            frame: jac.frame.iter().zip(&root).map(|(v, w)| v * w).collect(),
            combination: (jac.combination.iter().zip(&root))
                .map(|(row, w)| row.iter().map(|&(p, c)| (p, c * w)).collect())
                .collect(),
            g: jac.g.clone(),
        };
        let mut space = Self::factored(&whitened, s)?;
        space.root_weights = Some(root);
        Ok(space)
    }

    /// `dv` whitened: sqrt(w_k) dv_k (itself without weights).
    pub(crate) fn whiten<'a>(&self, dv: &'a [f64]) -> std::borrow::Cow<'a, [f64]> {
        match &self.root_weights {
            Some(w) => dv.iter().zip(w).map(|(v, w)| v * w).collect(),
            None => std::borrow::Cow::Borrowed(dv),
        }
    }

    /// `var` (V^2 per value) whitened: w_k var_k.
    pub(crate) fn whiten_variance<'a>(&self, var: &'a [f64]) -> std::borrow::Cow<'a, [f64]> {
        match &self.root_weights {
            Some(w) => var.iter().zip(w).map(|(v, w)| v * w * w).collect(),
            None => std::borrow::Cow::Borrowed(var),
        }
    }
}
