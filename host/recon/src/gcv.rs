//! The regularisation alpha by generalised cross-validation (docs/method.md §6.3): the GCV
//! score of every candidate from A's spectrum, and the choice with the discrepancy principle
//! as a floor. A = J P^-1 J^T is [`DataSpace`]'s; its spectrum is made once and kept there.

use nalgebra::DMatrix;

use crate::onestep::{DataSpace, ReconError, Spectrum, Weights, transposed_times};

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

/// A's spectrum seen by a frame: c = U^T dv for the nonzero eigenvalues, and the part of dv
/// in A's null space (|dv_0|^2, V^2).
struct Seen {
    c: Vec<f64>,
    null_norm2: f64,
}

/// The alpha rules' curves for one frame over the candidates (in the order given).
struct Curves<'w> {
    weights: &'w Weights,
    /// c_i^2 (n values).
    c2: Vec<f64>,
    /// |dv - J R dv|^2 (V^2) per candidate.
    residual: Vec<f64>,
    /// |x_alpha|_P^2 per candidate.
    norm: Vec<f64>,
    /// K, the frame length.
    k: f64,
}

impl Curves<'_> {
    /// GCV(lambda) = K |dv - J R dv|^2 / (K - tr H)^2 per candidate.
    fn gcv(&self) -> Vec<(f64, f64)> {
        (self
            .weights
            .alphas
            .iter()
            .zip(&self.residual)
            .zip(&self.weights.dof))
        .map(|((&a, r), d)| (a, self.k * r / (d * d).max(f64::MIN_POSITIVE)))
        .collect()
    }

    /// GCV's smallest finite score and every (alpha, score).
    fn gcv_best(&self) -> Result<(f64, Vec<(f64, f64)>), ReconError> {
        let scores = self.gcv();
        let best = scores
            .iter()
            .copied()
            .filter(|s| s.1.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .ok_or(ReconError::Singular)?;
        Ok((best.0, scores))
    }

    /// Whether each candidate's residual reaches the noise's: r >= noise (K - tr H) / K.
    fn above(&self, noise: f64) -> Vec<bool> {
        (self.residual.iter().zip(&self.weights.dof))
            .map(|(r, d)| *r >= noise * d / self.k)
            .collect()
    }

    /// |x_alpha_j - x_alpha_j+1|_P^2 between consecutive candidates (the last repeats the one
    /// before).
    fn steps(&self) -> Vec<f64> {
        let (w, n) = (self.weights, self.weights.n);
        let mut steps: Vec<f64> = (1..w.alphas.len())
            .map(|j| {
                let (s0, s1) = (&w.s[(j - 1) * n..j * n], &w.s[j * n..(j + 1) * n]);
                (self.c2.iter().zip(s0).zip(s1))
                    .map(|((c2, a), b)| c2 * (a - b) * (a - b))
                    .sum()
            })
            .collect();
        if let Some(&last) = steps.last() {
            steps.push(last);
        }
        steps
    }
}

/// The candidates in increasing order, with their indices in the list given.
fn sorted(candidates: &[f64]) -> (Vec<usize>, Vec<f64>) {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by(|&a, &b| candidates[a].total_cmp(&candidates[b]));
    let alphas = order.iter().map(|&i| candidates[i]).collect();
    (order, alphas)
}

impl DataSpace {
    /// A's spectrum (made once: from the r x r problem, cheap when K is large) as seen by
    /// `dv`.
    fn spectrum(&self, dv: &[f64]) -> Result<Seen, ReconError> {
        let spectrum = self.eigen()?;
        // The same frame again (a frame's image asks after its alpha): its projections.
        if let Ok(last) = self.last_seen.0.lock()
            && let Some((seen_dv, c, null_norm2)) = last.as_ref()
            && seen_dv.as_slice() == dv
        {
            return Ok(Seen {
                c: c.clone(),
                null_norm2: *null_norm2,
            });
        }
        let key = dv.to_vec();
        let dv = &*self.whiten(dv);
        let c = match spectrum {
            // One matrix-vector product each (faer's, on the vector unit).
            Spectrum::Compact { w, .. } => transposed_times(w, &self.m_transpose(dv)),
            Spectrum::Full { u, .. } => transposed_times(u, dv),
        };
        let total: f64 = dv.iter().map(|v| v * v).sum();
        let seen: f64 = c.iter().map(|v| v * v).sum();
        let null_norm2 = (total - seen).max(0.0);
        if let Ok(mut last) = self.last_seen.0.lock() {
            *last = Some((key, c.clone(), null_norm2));
        }
        Ok(Seen { c, null_norm2 })
    }

    /// The frame `dv` checked (length, finite) and the alpha rules' curves over `candidates`.
    fn curves<'w>(
        &self,
        dv: &[f64],
        candidates: &[f64],
        weights: &'w Weights,
    ) -> Result<Curves<'w>, ReconError> {
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
        let c2: Vec<f64> = seen.c.iter().map(|c| c * c).collect();
        // Two matrix-vector products (faer's, on the vector unit).
        let mut residual = transposed_times(&weights.w2, &c2);
        let norm = transposed_times(&weights.g, &c2);
        residual.iter_mut().for_each(|r| *r += seen.null_norm2);
        Ok(Curves {
            weights,
            c2,
            residual,
            norm,
            k: k as f64,
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
        let weights = self.weights(candidates)?;
        self.curves(dv, candidates, &weights)?.gcv_best()
    }

    /// The noise's residual sum_k var_k (whitened, V^2) for per-value variances `var_dv`.
    fn noise_sum(&self, dv: &[f64], var_dv: &[f64]) -> Result<f64, ReconError> {
        if var_dv.len() != dv.len() {
            return Err(ReconError::FrameLength {
                what: "noise variances",
                got: var_dv.len(),
                k: dv.len(),
            });
        }
        Ok((self.whiten_variance(var_dv).iter())
            .map(|v| v.max(0.0))
            .sum())
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
        let weights = self.weights(candidates)?;
        let curves = self.curves(dv, candidates, &weights)?;
        Ok(curves.above(self.noise_sum(dv, var_dv)?))
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
        // The curves over the candidates in increasing order (the rules walk alpha upwards).
        let (_, alphas) = sorted(candidates);
        let weights = self.weights(&alphas)?;
        let curves = self.curves(dv, &alphas, &weights)?;
        curves.gcv_best()?;
        match criterion {
            Criterion::Gcv => self.choose_by(&curves, dv, var_dv),
            Criterion::Discrepancy => {
                // The smallest alpha whose residual reaches the noise's (residuals grow with
                // alpha); the largest when none does.
                let above = curves.above(self.noise_sum(dv, var_dv)?);
                Ok(above
                    .iter()
                    .position(|&a| a)
                    .map_or(alphas[alphas.len() - 1], |i| alphas[i]))
            }
            Criterion::LCurve => Ok(corner(&curves)),
            Criterion::CornerAboveFloor => {
                Ok(corner(&curves).max(self.choose_by(&curves, dv, var_dv)?))
            }
            Criterion::QuasiOptimality => Ok((curves.steps().iter().zip(&alphas))
                .filter(|(s, _)| s.is_finite())
                .min_by(|a, b| a.0.total_cmp(b.0))
                .map_or(alphas[0], |(_, a)| *a)),
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
        let weights = self.weights(candidates)?;
        let curves = self.curves(dv, candidates, &weights)?;
        self.choose_by(&curves, dv, var_dv)
    }

    /// [`DataSpace::choose_alpha`] on a frame's curves.
    fn choose_by(&self, curves: &Curves, dv: &[f64], var_dv: &[f64]) -> Result<f64, ReconError> {
        let (best, scores) = curves.gcv_best()?;
        let admissible = curves.above(self.noise_sum(dv, var_dv)?);
        let chosen = scores
            .iter()
            .zip(&admissible)
            .filter(|(s, a)| s.1.is_finite() && **a)
            .map(|(s, _)| s)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        Ok(match chosen {
            Some(s) => s.0,
            None => curves.weights.alphas.iter().copied().fold(best, f64::max),
        })
    }
}

/// The L-curve's corner over curves whose candidates increase: the largest curvature of
/// (log residual, log image norm) against log alpha, by central differences (the middle
/// candidate when no curvature is finite).
fn corner(curves: &Curves) -> f64 {
    let alphas = &curves.weights.alphas;
    let tiny = f64::MIN_POSITIVE;
    let x: Vec<f64> = curves
        .residual
        .iter()
        .map(|r| 0.5 * r.max(tiny).ln())
        .collect();
    let y: Vec<f64> = curves.norm.iter().map(|n| 0.5 * n.max(tiny).ln()).collect();
    let t: Vec<f64> = alphas.iter().map(|a| a.ln()).collect();
    let mut best = (f64::NEG_INFINITY, alphas[alphas.len() / 2]);
    for i in 1..alphas.len().saturating_sub(1) {
        let (h0, h1) = (t[i] - t[i - 1], t[i + 1] - t[i]);
        let d1 = |v: &[f64]| (v[i + 1] - v[i - 1]) / (h0 + h1);
        let d2 = |v: &[f64]| 2.0 * ((v[i + 1] - v[i]) / h1 - (v[i] - v[i - 1]) / h0) / (h0 + h1);
        let (dx, dy, ddx, ddy) = (d1(&x), d1(&y), d2(&x), d2(&y));
        let kappa = (dx * ddy - ddx * dy) / (dx * dx + dy * dy).powf(1.5).max(tiny);
        if kappa.is_finite() && kappa > best.0 {
            best = (kappa, alphas[i]);
        }
    }
    best.1
}
