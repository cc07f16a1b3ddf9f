//! Evaluating a frame (docs/method.md §9): the used voltages standardised, then each class's
//! discriminant from the blob's tables.

// Reads an untrusted blob: no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

impl<'a> Model<'a> {
    /// Picks and standardises the features of `v_m` (minus `v_0` for a referenced model) into
    /// `z` (len p).
    pub(super) fn standardise(
        &self,
        v_m: &[f32],
        v_0: &[f32],
        z: &mut [f32],
    ) -> Result<(), EvalError> {
        for (j, zj) in z.iter_mut().enumerate() {
            let i = usize::from(self.feature_index(j));
            // In range for a blob that passed `parse` (indices < K = the frame's length).
            let (Some(&m), Some(&o)) = (v_m.get(i), v_0.get(i)) else {
                return Err(EvalError::FrameLength {
                    expected: i + 1,
                    got: v_m.len().min(v_0.len()),
                });
            };
            let x = if self.referenced { m - o } else { m };
            if !x.is_finite() {
                return Err(EvalError::NonFinite);
            }
            *zj = (x - self.mean(j)) / self.scale(j);
        }
        Ok(())
    }

    pub(super) fn discriminant(&self, c: usize, z: &[f32], work: &mut [f32]) -> f32 {
        let p = self.features;
        let quad_or_lin = match self.kind {
            ModelKind::Qda => {
                // Forward substitution L_c y = z - mu_c; the quadratic form is |y|^2.
                // z and work hold p values each (checked by the caller).
                let base = c * packed_len(p);
                let mut q = 0.0f32;
                for (r, zr) in z.iter().enumerate().take(p) {
                    let row = base + packed_len(r);
                    let mut acc = zr - self.vector(c, r);
                    for (k, yk) in work.iter().take(r).enumerate() {
                        acc -= self.stored(self.layout.factors, row + k) * yk;
                    }
                    let y = acc / self.stored(self.layout.factors, row + r);
                    if let Some(w) = work.get_mut(r) {
                        *w = y;
                    }
                    q += y * y;
                }
                -0.5 * q
            }
            ModelKind::Lda => z
                .iter()
                .take(p)
                .enumerate()
                .map(|(j, zj)| zj * self.vector(c, j))
                .sum(),
        };
        quad_or_lin + self.constant(c) + self.log_prior(c)
    }

    /// Every class's discriminant delta_c for frame `v_m`, into `out[..C]`.
    ///
    /// # Errors
    /// [`EvalError`] for a frame of the wrong length, short scratch or `out`, a non-finite
    /// voltage or discriminant, or a referenced model ([`EvalError::Untouched`]).
    pub fn discriminants(
        &self,
        v_m: &[f32],
        scratch: &mut [f32],
        out: &mut [f32],
    ) -> Result<(), EvalError> {
        self.discriminants_referenced(v_m, None, scratch, out)
    }

    /// As [`discriminants`](Self::discriminants), with the untouched frame `v_0` (K values)
    /// that a referenced model subtracts; an unreferenced model ignores it.
    ///
    /// # Errors
    /// As [`discriminants`](Self::discriminants); [`EvalError::Untouched`] when a referenced
    /// model gets no `v_0` or one of the wrong length.
    pub fn discriminants_referenced(
        &self,
        v_m: &[f32],
        v_0: Option<&[f32]>,
        scratch: &mut [f32],
        out: &mut [f32],
    ) -> Result<(), EvalError> {
        if out.len() < self.classes {
            return Err(EvalError::Scratch {
                needed: self.classes,
                given: out.len(),
            });
        }
        self.each_discriminant(v_m, v_0, scratch, |c, d| {
            if let Some(o) = out.get_mut(c) {
                *o = d;
            }
        })
    }

    pub(super) fn each_discriminant(
        &self,
        v_m: &[f32],
        v_0: Option<&[f32]>,
        scratch: &mut [f32],
        mut visit: impl FnMut(usize, f32),
    ) -> Result<(), EvalError> {
        if v_m.len() != self.frame_len {
            return Err(EvalError::FrameLength {
                expected: self.frame_len,
                got: v_m.len(),
            });
        }
        let v_0 = match v_0 {
            _ if !self.referenced => v_m,
            Some(v_0) if v_0.len() == self.frame_len => v_0,
            _ => return Err(EvalError::Untouched),
        };
        let p = self.features;
        if scratch.len() < 2 * p {
            return Err(EvalError::Scratch {
                needed: 2 * p,
                given: scratch.len(),
            });
        }
        let (z, work) = scratch.split_at_mut(p);
        self.standardise(v_m, v_0, z)?;
        for c in 0..self.classes {
            let d = self.discriminant(c, z, work);
            if !d.is_finite() {
                return Err(EvalError::NonFinite);
            }
            visit(c, d);
        }
        Ok(())
    }

    /// Classifies frame `v_m` (K values): argmax_c delta_c and its margin to the runner-up.
    /// `scratch` needs [`scratch_len`](Self::scratch_len) values.
    ///
    /// # Errors
    /// As [`discriminants`](Self::discriminants).
    pub fn evaluate(&self, v_m: &[f32], scratch: &mut [f32]) -> Result<Decision, EvalError> {
        self.evaluate_referenced(v_m, None, scratch)
    }

    /// As [`evaluate`](Self::evaluate), with the untouched frame `v_0` (K values) that a
    /// referenced model subtracts from `v_m`; an unreferenced model ignores it.
    ///
    /// # Errors
    /// As [`discriminants_referenced`](Self::discriminants_referenced).
    pub fn evaluate_referenced(
        &self,
        v_m: &[f32],
        v_0: Option<&[f32]>,
        scratch: &mut [f32],
    ) -> Result<Decision, EvalError> {
        let (mut best, mut best_d, mut second_d) = (0usize, f32::NEG_INFINITY, f32::NEG_INFINITY);
        self.each_discriminant(v_m, v_0, scratch, |c, d| {
            if d > best_d {
                second_d = best_d;
                best_d = d;
                best = c;
            } else if d > second_d {
                second_d = d;
            }
        })?;
        Ok(Decision {
            class: best as u16,
            discriminant: best_d,
            margin: best_d - second_d,
        })
    }
}
