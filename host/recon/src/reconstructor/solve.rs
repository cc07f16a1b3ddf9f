//! One frame's solve by each method: GREIT's matrix, Gauss-Newton's one-step matrix or its
//! iterated fit, giving [`Reconstructor::image_dv`] the pixels, their noise and the alpha.

use std::time::Instant;

use super::spec::{AlphaRule, FrameTimings, Iterations};
use super::{ImagingError, Matrix, Reconstructor};
use crate::gauss_newton::{Data, GaussNewton, gauss_newton};
use crate::gcv::{Criterion, default_alphas};
use crate::greit::{Greit, Regularisation};
use crate::onestep::{ReconError, floor_variance};
use crate::pixels::PixelGrid;

impl Reconstructor {
    /// The least model error a frame's alpha choice allows for, per channel (V^2): the
    /// imaging variance `var` when the background was fitted, else [`floor_variance`].
    pub(super) fn floor(&self, var_dv: &[f64], dv: &[f64], var: &[f64]) -> Vec<f64> {
        match (&self.mismatch, self.mismatch_factor) {
            (Some(_), Some(_)) => var.to_vec(),
            _ => floor_variance(var_dv, dv),
        }
    }

    /// GREIT's image of `dv`, its matrix made at the first frame's alpha when the spec left
    /// alpha to the noise figure.
    pub(super) fn solve_greit(
        &mut self,
        radius: Option<f64>,
        dv: &[f64],
        var_dv: &[f64],
        var: &[f64],
    ) -> Result<Solved, ImagingError> {
        let mut timings = FrameTimings::default();
        let clock = Instant::now();
        let greit = match &self.greit {
            Some(g) => g,
            None => {
                let floor = self.floor(var_dv, dv, var);
                let alpha = Greit::choose_alpha(&self.imager, &self.jac, dv, &floor)?;
                let made = self.greit_with(radius, Regularisation::Alpha(alpha))?;
                timings.matrix = Some(clock.elapsed().as_secs_f64());
                &*self.greit_chosen.insert(made)
            }
        };
        let clock = Instant::now();
        let pixels = greit.image(dv)?;
        timings.frame = clock.elapsed().as_secs_f64();
        Ok(Solved {
            alpha: greit.alpha,
            pixels,
            noise_sd: greit.noise_sd(var)?,
            mesh_values: None,
            iterations: None,
            greit: Some((greit.noise_figure, greit.radius)),
            timings,
        })
    }

    /// Gauss-Newton's image of `dv` with the NOSER exponent `s`: one step through the
    /// one-step matrix (made again when alpha changes), or `n` iterations of the full fit.
    pub(super) fn solve_gauss_newton(
        &mut self,
        s: f64,
        n: usize,
        dv: &[f64],
        var_dv: &[f64],
        var: &[f64],
    ) -> Result<Solved, ImagingError> {
        let mut timings = FrameTimings::default();
        let clock = Instant::now();
        let alpha = self.gauss_newton_alpha(dv, var_dv, var)?;
        if n <= 1 {
            if self.matrix_at(alpha)? {
                timings.matrix = Some(clock.elapsed().as_secs_f64());
            }
            let grid = &self.imager.grid;
            let Some(matrix) = self.one_step.as_mut() else {
                return Err(ReconError::Singular.into());
            };
            matrix.frames += 1;
            let clock = Instant::now();
            if !self.mesh_values && matrix.frames > 1 {
                // The pixels alone, through the f32 operator onto them.
                let pixels = matrix.pixels_of(grid, dv)?;
                timings.frame = clock.elapsed().as_secs_f64();
                return Ok(Solved {
                    alpha,
                    pixels,
                    noise_sd: grid.noise_sd(&matrix.recon, var)?,
                    mesh_values: None,
                    iterations: None,
                    greit: None,
                    timings,
                });
            }
            // From the f64 factors: exact, the same image every call, and cheaper for one
            // frame than making the f32 operator (which the warm frames' figure,
            // `frame_median`, and the live pipeline's pixels use).
            let values = matrix.recon.reconstruct(dv)?;
            timings.frame = clock.elapsed().as_secs_f64();
            let noise_sd = grid.noise_sd(&matrix.recon, var)?;
            return Ok(Solved::on_mesh(
                alpha, grid, values, noise_sd, None, timings,
            ));
        }
        let clock = Instant::now();
        let sigma0 = self.imager.background();
        let fit = gauss_newton(
            &self.imager.forward,
            &self.schedule,
            &sigma0,
            Data::Difference(dv),
            GaussNewton {
                alpha,
                s,
                iterations: n,
            },
            var,
        )?;
        timings.frame = clock.elapsed().as_secs_f64();
        let last = fit.iterates.last().ok_or(ReconError::Singular)?;
        let d: Vec<f64> = last.sigma.iter().zip(&sigma0).map(|(a, b)| a - b).collect();
        let iterations = Iterations {
            completed: fit.iterates.len(),
            residual: last.residual,
            steps: fit.iterates.iter().map(|i| i.step).collect(),
            stop: fit.stop,
        };
        let grid = &self.imager.grid;
        let noise_sd = grid.image(&last.noise_sd);
        Ok(Solved::on_mesh(
            alpha,
            grid,
            d,
            noise_sd,
            Some(iterations),
            timings,
        ))
    }

    /// Gauss-Newton's alpha for `dv` by the spec's rule (the frames' noise `var_dv` and the
    /// imaging variance `var` set the floor of the rules that choose).
    pub(super) fn gauss_newton_alpha(
        &self,
        dv: &[f64],
        var_dv: &[f64],
        var: &[f64],
    ) -> Result<f64, ImagingError> {
        let space = self.space.as_ref().ok_or(ReconError::Singular)?;
        Ok(match self.alpha {
            AlphaRule::Fixed(a) => a,
            // The corner's floor is the least model error any frame has, not the fitted
            // background's.
            AlphaRule::Chosen(c @ Criterion::CornerAboveFloor) => {
                space.alpha_by(c, dv, &floor_variance(var_dv, dv), &default_alphas())?
            }
            AlphaRule::Chosen(c) => {
                let floor = self.floor(var_dv, dv, var);
                space.alpha_by(c, dv, &floor, &default_alphas())?
            }
            AlphaRule::Gcv | AlphaRule::NoiseFigure(_) => {
                let floor = self.floor(var_dv, dv, var);
                space.choose_alpha(dv, &floor, &default_alphas())?
            }
        })
    }

    /// Makes the one-step matrix at `alpha` the current one: the current, one kept from
    /// before, or made (then true).
    pub(super) fn matrix_at(&mut self, alpha: f64) -> Result<bool, ImagingError> {
        if self.one_step.as_ref().is_some_and(|m| m.alpha == alpha) {
            return Ok(false);
        }
        let (matrix, made) = match self.earlier.iter().position(|m| m.alpha == alpha) {
            Some(i) => (self.earlier.remove(i), false),
            None => {
                let space = self.space.as_ref().ok_or(ReconError::Singular)?;
                (Matrix::new(alpha, space.one_step(alpha)?), true)
            }
        };
        if let Some(last) = self.one_step.replace(matrix) {
            self.earlier.insert(0, last);
            self.earlier.truncate(super::MATRICES_KEPT);
        }
        Ok(made)
    }
}

/// What one method's solve gives [`Reconstructor::image_dv`]: [`Image`]'s fields of the same
/// names.
pub(super) struct Solved {
    pub(super) alpha: f64,
    pub(super) pixels: Vec<Option<f64>>,
    pub(super) noise_sd: Vec<Option<f64>>,
    pub(super) mesh_values: Option<Vec<f64>>,
    pub(super) iterations: Option<Iterations>,
    pub(super) greit: Option<(f64, f64)>,
    pub(super) timings: FrameTimings,
}

impl Solved {
    /// A Gauss-Newton solve's result: the change of each element's conductivity `values`
    /// drawn on `grid`, with the pixels' noise.
    fn on_mesh(
        alpha: f64,
        grid: &PixelGrid,
        values: Vec<f64>,
        noise_sd: Vec<Option<f64>>,
        iterations: Option<Iterations>,
        timings: FrameTimings,
    ) -> Self {
        Self {
            alpha,
            pixels: grid.image(&values),
            noise_sd,
            mesh_values: Some(values),
            iterations,
            greit: None,
            timings,
        }
    }
}
