//! The regularisation alpha by generalised cross-validation (docs/method.md §6.3): the GCV
//! score of every candidate from A's spectrum, and the choice with the discrepancy principle
//! as a floor. A = J P^-1 J^T is [`DataSpace`]'s; its spectrum is made once and kept there.

use nalgebra::DMatrix;

use crate::onestep::{DataSpace, ReconError, Spectrum};

/// How alpha is chosen from a frame, all from A's spectrum (cheap once it is made).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Criterion {
    /// Generalised cross-validation's minimum, never fitting closer than the noise
    /// ([`DataSpace::choose_alpha`]).
    Gcv,
    /// The generalised discrepancy principle: the smallest alpha whose residual reaches what
    /// the noise alone leaves.
    Discrepancy,
    /// The L-curve's corner: the largest curvature of (log residual, log image norm).
    LCurve,
    /// Quasi-optimality: where the image changes least from one candidate to the next.
    QuasiOptimality,
    /// The L-curve's corner, never below GCV's choice above the floor given
    /// ([`DataSpace::choose_alpha`]): the corner finds the error the frame itself shows (noise
    /// and the model's mismatch), the floor keeps noise-free frames, which have no corner,
    /// from running to the smallest alpha.
    CornerAboveFloor,
}

/// The alphas automatic selection tries: 26 steps from 1e-4 to 10, five per decade (alpha is
/// dimensionless, normalised as in [`crate::onestep`]).
#[must_use]
pub fn default_alphas() -> Vec<f64> {
    (0..=25)
        .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
        .collect()
}

/// Generalised cross-validation of alpha for the frame difference `dv`: [`DataSpace::gcv`] on
/// a data space made for this call (keep a [`DataSpace`] to also build the matrix from it).
///
/// # Errors
/// [`ReconError`] for bad parameters, a zero Jacobian or a non-finite frame.
pub fn gcv_alpha(
    jac: &DMatrix<f64>,
    s: f64,
    dv: &[f64],
    candidates: &[f64],
) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
    if dv.len() != jac.nrows() {
        return Err(ReconError::FrameLength {
            what: "frame",
            got: dv.len(),
            k: jac.nrows(),
        });
    }
    DataSpace::new(jac, s)?.gcv(dv, candidates)
}

/// A's spectrum seen by a frame: the nonzero eigenvalues, c = U^T dv for them, and the part
/// of dv in A's null space (|dv_0|^2, V^2, and the null space's dimension).
struct Seen<'a> {
    e: &'a [f64],
    c: Vec<f64>,
    null_norm2: f64,
    null_dim: usize,
}

/// `m`^T `v` for `m` (n x q) and `v` (n values): q values.
fn transposed_times(m: &faer::Mat<f64>, v: &[f64]) -> Vec<f64> {
    let v = faer::MatRef::from_column_major_slice(v, v.len(), 1);
    let mut out = vec![0.0; m.ncols()];
    faer::linalg::matmul::matmul(
        faer::MatMut::from_column_major_slice_mut(&mut out, m.ncols(), 1),
        faer::Accum::Replace,
        m.transpose(),
        v,
        1.0,
        faer::Par::Seq,
    );
    out
}

impl DataSpace {
    /// A's spectrum (made once: from the r x r problem, cheap when K is large) as seen by
    /// `dv`.
    fn spectrum(&self, dv: &[f64]) -> Result<Seen<'_>, ReconError> {
        let spectrum = self.eigen()?;
        let k = self.frame_len();
        let (Spectrum::Compact { e, .. } | Spectrum::Full { e, .. }) = spectrum;
        // The same frame again (the alpha rules read it several times): its projections.
        if let Ok(last) = self.last_seen.0.lock()
            && let Some((seen_dv, c, null_norm2)) = last.as_ref()
            && seen_dv.as_slice() == dv
        {
            return Ok(Seen {
                e,
                c: c.clone(),
                null_norm2: *null_norm2,
                null_dim: k.saturating_sub(e.len()),
            });
        }
        let key = dv.to_vec();
        let dv = &*self.whiten(dv);
        let (e, c) = match spectrum {
            // One matrix-vector product each (faer's, on the vector unit: every frame's alpha
            // reads the spectrum several times).
            Spectrum::Compact { e, w } => (e, transposed_times(w, &self.m_transpose(dv))),
            Spectrum::Full { e, u } => (e, transposed_times(u, dv)),
        };
        let total: f64 = dv.iter().map(|v| v * v).sum();
        let seen: f64 = c.iter().map(|v| v * v).sum();
        let null_norm2 = (total - seen).max(0.0);
        if let Ok(mut last) = self.last_seen.0.lock() {
            *last = Some((key, c.clone(), null_norm2));
        }
        Ok(Seen {
            e,
            null_norm2,
            null_dim: k.saturating_sub(e.len()),
            c,
        })
    }

    /// Generalised cross-validation of alpha for the frame difference `dv` (docs/method.md
    /// (6.1)): with A = U diag(e) U^T and c = U^T dv, GCV(lambda) = K sum_i (lambda c_i /
    /// (e_i + lambda))^2 / (sum_i lambda / (e_i + lambda))^2. Returns the candidate with the
    /// smallest GCV and every (alpha, GCV). A's spectrum is made once and kept, from the r x r
    /// problem of the factored Jacobian (its K - q zero eigenvalues in closed form).
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a frame of the wrong length, [`ReconError::NoCandidates`];
    /// [`ReconError::NonFinite`] for a frame with NaN/inf; [`ReconError::Singular`] when A
    /// has no eigendecomposition or no candidate scores finitely.
    pub fn gcv(
        &self,
        dv: &[f64],
        candidates: &[f64],
    ) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
        let k = self.frame_len();
        if dv.len() != k {
            return Err(ReconError::FrameLength {
                what: "frame",
                got: dv.len(),
                k,
            });
        }
        if candidates.is_empty() {
            return Err(ReconError::NoCandidates);
        }
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        let seen = self.spectrum(dv)?;
        let scores: Vec<(f64, f64)> = candidates
            .iter()
            .map(|&alpha| {
                let lambda = self.lambda(alpha);
                // Null-space components are left whole (weight 1).
                let (mut num, mut den) = (seen.null_norm2, seen.null_dim as f64);
                for (e, ci) in seen.e.iter().zip(&seen.c) {
                    let w = lambda / (e.max(0.0) + lambda);
                    num += (w * ci).powi(2);
                    den += w;
                }
                (alpha, k as f64 * num / (den * den).max(f64::MIN_POSITIVE))
            })
            .collect();
        let best = scores
            .iter()
            .copied()
            .filter(|s| s.1.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or(ReconError::Singular)?;
        Ok((best.0, scores))
    }

    /// |dv - J R dv|^2 at each candidate alpha, V^2 (the residual of the one-step image),
    /// from A's eigendecomposition.
    fn residuals(&self, dv: &[f64], candidates: &[f64]) -> Result<Vec<f64>, ReconError> {
        let seen = self.spectrum(dv)?;
        Ok(candidates
            .iter()
            .map(|&alpha| {
                let lambda = self.lambda(alpha);
                seen.null_norm2
                    + seen
                        .e
                        .iter()
                        .zip(&seen.c)
                        .map(|(e, ci)| (lambda * ci / (e.max(0.0) + lambda)).powi(2))
                        .sum::<f64>()
            })
            .collect())
    }

    /// K - tr(H_lambda) at each candidate, where H_lambda = A (A + lambda I)^-1 maps dv to the
    /// fitted J R dv: the degrees of freedom left to the residual (pure noise of variance s^2
    /// per value leaves a residual of s^2 (K - tr H) on average).
    fn residual_dof(&self, candidates: &[f64]) -> Result<Vec<f64>, ReconError> {
        // A's eigenvalues alone: no frame's projections needed.
        let (Spectrum::Compact { e, .. } | Spectrum::Full { e, .. }) = self.eigen()?;
        let null_dim = self.frame_len().saturating_sub(e.len());
        Ok(candidates
            .iter()
            .map(|&alpha| {
                let lambda = self.lambda(alpha);
                null_dim as f64
                    + e.iter()
                        .map(|e| lambda / (e.max(0.0) + lambda))
                        .sum::<f64>()
            })
            .collect())
    }

    /// |x_alpha|_P^2 = x^T P x of the one-step image x = P^-1 J^T (A + lambda I)^-1 dv at each
    /// candidate (= sum_i e_i c_i^2 / (e_i + lambda)^2), and |x_alpha_j - x_alpha_j+1|_P^2
    /// between consecutive candidates (the last repeats the one before).
    fn image_norms(
        &self,
        dv: &[f64],
        candidates: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), ReconError> {
        let seen = self.spectrum(dv)?;
        let lambdas: Vec<f64> = candidates.iter().map(|&a| self.lambda(a)).collect();
        let norm = |l: f64| -> f64 {
            seen.e
                .iter()
                .zip(&seen.c)
                .map(|(e, c)| e.max(0.0) * c * c / (e.max(0.0) + l).powi(2))
                .sum()
        };
        let step = |l1: f64, l2: f64| -> f64 {
            seen.e
                .iter()
                .zip(&seen.c)
                .map(|(e, c)| {
                    let e = e.max(0.0);
                    e * c * c * (1.0 / (e + l1) - 1.0 / (e + l2)).powi(2)
                })
                .sum()
        };
        let norms = lambdas.iter().map(|&l| norm(l)).collect();
        let mut steps: Vec<f64> = lambdas.windows(2).map(|w| step(w[0], w[1])).collect();
        if let Some(&last) = steps.last() {
            steps.push(last);
        }
        Ok((norms, steps))
    }

    /// Whether each candidate's residual reaches what noise of variance `var_dv` per value
    /// (V^2) alone leaves, |dv - J R dv|^2 >= (K - tr H_lambda) sum_k var_k / K (the
    /// generalised discrepancy principle; weights applied).
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for `var_dv` not of K values; as [`DataSpace::gcv`].
    pub fn above_noise(
        &self,
        dv: &[f64],
        var_dv: &[f64],
        candidates: &[f64],
    ) -> Result<Vec<bool>, ReconError> {
        if var_dv.len() != dv.len() {
            return Err(ReconError::FrameLength {
                what: "noise variances",
                got: var_dv.len(),
                k: dv.len(),
            });
        }
        let noise: f64 = (self.whiten_variance(var_dv).iter())
            .map(|v| v.max(0.0))
            .sum();
        let residuals = self.residuals(dv, candidates)?;
        let dof = self.residual_dof(candidates)?;
        let k = dv.len() as f64;
        Ok(residuals
            .iter()
            .zip(&dof)
            .map(|(r, d)| *r >= noise * d / k)
            .collect())
    }

    /// alpha for the frame difference `dv` by `criterion` (see [`Criterion`]), with the noise
    /// variance per value `var_dv` (V^2) where the criterion uses it.
    ///
    /// # Errors
    /// As [`DataSpace::choose_alpha`].
    pub fn alpha_by(
        &self,
        criterion: Criterion,
        dv: &[f64],
        var_dv: &[f64],
        candidates: &[f64],
    ) -> Result<f64, ReconError> {
        if candidates.is_empty() {
            return Err(ReconError::NoCandidates);
        }
        match criterion {
            Criterion::Gcv => self.choose_alpha(dv, var_dv, candidates),
            Criterion::Discrepancy => {
                self.gcv(dv, candidates)?;
                if var_dv.len() != dv.len() {
                    return Err(ReconError::FrameLength {
                        what: "noise variances",
                        got: var_dv.len(),
                        k: dv.len(),
                    });
                }
                let noise: f64 = self
                    .whiten_variance(var_dv)
                    .iter()
                    .map(|v| v.max(0.0))
                    .sum();
                let residuals = self.residuals(dv, candidates)?;
                let dof = self.residual_dof(candidates)?;
                let k = dv.len() as f64;
                // The smallest alpha whose residual reaches the noise's (residuals grow with
                // alpha); the largest when none does.
                let mut order: Vec<usize> = (0..candidates.len()).collect();
                order.sort_by(|&a, &b| candidates[a].total_cmp(&candidates[b]));
                Ok(order
                    .iter()
                    .find(|&&i| residuals[i] >= noise * dof[i] / k)
                    .or(order.last())
                    .map(|&i| candidates[i])
                    .unwrap_or(candidates[0]))
            }
            Criterion::LCurve => {
                self.gcv(dv, candidates)?;
                let mut order: Vec<usize> = (0..candidates.len()).collect();
                order.sort_by(|&a, &b| candidates[a].total_cmp(&candidates[b]));
                let sorted: Vec<f64> = order.iter().map(|&i| candidates[i]).collect();
                let residuals = self.residuals(dv, &sorted)?;
                let (norms, _) = self.image_norms(dv, &sorted)?;
                let tiny = f64::MIN_POSITIVE;
                let x: Vec<f64> = residuals.iter().map(|r| 0.5 * r.max(tiny).ln()).collect();
                let y: Vec<f64> = norms.iter().map(|n| 0.5 * n.max(tiny).ln()).collect();
                // The corner: the largest curvature of (log residual, log image norm) against
                // log alpha, by central differences.
                let t: Vec<f64> = sorted.iter().map(|a| a.ln()).collect();
                let mut best = (f64::NEG_INFINITY, sorted[sorted.len() / 2]);
                for i in 1..sorted.len().saturating_sub(1) {
                    let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
                    let d1 = |v: &[f64]| (v[i + 1] - v[i - 1]) / (h0 + h1);
                    let d2 = |v: &[f64]| {
                        2.0 * ((v[i + 1] - v[i]) / h1 - (v[i] - v[i - 1]) / h0) / (h0 + h1)
                    };
                    let (dx, dy, ddx, ddy) = (d1(&x), d1(&y), d2(&x), d2(&y));
                    let kappa = (dx * ddy - ddx * dy) / (dx * dx + dy * dy).powf(1.5).max(tiny);
                    if kappa.is_finite() && kappa > best.0 {
                        best = (kappa, sorted[i]);
                    }
                }
                Ok(best.1)
            }
            Criterion::CornerAboveFloor => {
                let corner = self.alpha_by(Criterion::LCurve, dv, var_dv, candidates)?;
                Ok(corner.max(self.choose_alpha(dv, var_dv, candidates)?))
            }
            Criterion::QuasiOptimality => {
                self.gcv(dv, candidates)?;
                let mut order: Vec<usize> = (0..candidates.len()).collect();
                order.sort_by(|&a, &b| candidates[a].total_cmp(&candidates[b]));
                let sorted: Vec<f64> = order.iter().map(|&i| candidates[i]).collect();
                let (_, steps) = self.image_norms(dv, &sorted)?;
                Ok(steps
                    .iter()
                    .zip(&sorted)
                    .filter(|(s, _)| s.is_finite())
                    .min_by(|a, b| a.0.total_cmp(b.0))
                    .map_or(sorted[0], |(_, a)| *a))
            }
        }
    }

    /// alpha for the frame difference `dv` whose per-channel noise variance is `var_dv`
    /// (V^2): the GCV minimum ([`DataSpace::gcv`]) among the candidates that do not fit the
    /// data closer than its noise, |dv - J R dv|^2 >= (K - tr H_lambda) sum_k var_k / K (the
    /// generalised discrepancy principle as a floor: noise alone of that variance leaves that
    /// residual on average, the fit taking tr H_lambda of its K degrees of freedom). GCV alone assumes the misfit is noise; on frames with little or no noise it
    /// runs to the smallest alpha, where the image rings and what remains (the ADC's
    /// rounding, the model's mismatch) is amplified into spurious peaks. When every candidate
    /// fits closer than the noise (dv within the noise), the largest is taken.
    ///
    /// # Errors
    /// As [`DataSpace::gcv`]; [`ReconError::FrameLength`] for `var_dv` not of K values.
    pub fn choose_alpha(
        &self,
        dv: &[f64],
        var_dv: &[f64],
        candidates: &[f64],
    ) -> Result<f64, ReconError> {
        let (best, scores) = self.gcv(dv, candidates)?;
        let admissible = self.above_noise(dv, var_dv, candidates)?;
        let chosen = scores
            .iter()
            .zip(&admissible)
            .filter(|(s, a)| s.1.is_finite() && **a)
            .map(|(s, _)| s)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        Ok(match chosen {
            Some(s) => s.0,
            None => candidates.iter().copied().fold(best, f64::max),
        })
    }
}
