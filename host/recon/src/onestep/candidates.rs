//! The alpha rules' weights on A's spectrum, per candidate list ([`crate::gcv`] reads them).

use super::{DataSpace, ReconError, Spectrum};

/// The candidates' weights on A's nonzero eigenvalues e_i, made once per data space and
/// candidate list (they depend on no frame): a frame's alpha rules are then sums of products,
/// no division. Column j (candidate j, lambda_j) of each n x q table holds n values, one per
/// e_i.
#[derive(Debug)]
pub(crate) struct Weights {
    /// The candidates (alpha), in the order given.
    pub(crate) alphas: Vec<f64>,
    /// n, the nonzero eigenvalues' count.
    pub(crate) n: usize,
    /// (lambda / (e + lambda))^2: the share of c_i^2 left in the residual.
    pub(crate) w2: faer::Mat<f64>,
    /// e / (e + lambda)^2: c_i^2's share of the image's P-norm.
    pub(crate) g: faer::Mat<f64>,
    /// sqrt(e) / (e + lambda): the image's P-norm's root per c_i (quasi-optimality's steps).
    pub(crate) s: Vec<f64>,
    /// K - tr H_lambda = (K - n) + sum_i lambda / (e_i + lambda): the residual's degrees of
    /// freedom.
    pub(crate) dof: Vec<f64>,
}

impl DataSpace {
    /// The candidates' [`Weights`], made on the first ask for this list and kept.
    pub(crate) fn weights(
        &self,
        candidates: &[f64],
    ) -> Result<std::sync::Arc<Weights>, ReconError> {
        if let Ok(kept) = self.weights.0.lock()
            && let Some(w) = kept.as_ref()
            && w.alphas == candidates
        {
            return Ok(w.clone());
        }
        let (Spectrum::Compact { e, .. } | Spectrum::Full { e, .. }) = self.eigen()?;
        let (n, q) = (e.len(), candidates.len());
        let null_dim = self.frame_len().saturating_sub(n) as f64;
        let (mut w2, mut g, mut s) = (
            Vec::with_capacity(n * q),
            Vec::with_capacity(n * q),
            Vec::with_capacity(n * q),
        );
        let mut dof = Vec::with_capacity(q);
        for &alpha in candidates {
            let lambda = self.lambda(alpha);
            let mut free = null_dim;
            for e in e.iter().map(|e| e.max(0.0)) {
                let inv = 1.0 / (e + lambda);
                let w = lambda * inv;
                free += w;
                w2.push(w * w);
                g.push(e * inv * inv);
                s.push(e.sqrt() * inv);
            }
            dof.push(free);
        }
        let w = std::sync::Arc::new(Weights {
            alphas: candidates.to_vec(),
            n,
            w2: faer::Mat::from_fn(n, q, |i, j| w2[j * n + i]),
            g: faer::Mat::from_fn(n, q, |i, j| g[j * n + i]),
            s,
            dof,
        });
        if let Ok(mut kept) = self.weights.0.lock() {
            *kept = Some(w.clone());
        }
        Ok(w)
    }
}
