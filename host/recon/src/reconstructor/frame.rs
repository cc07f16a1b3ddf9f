//! A frame's cost as the live pipeline pays it, and what a reconstructor gives beside the
//! image: its one-step matrix and the objects of both signs.

use super::*;
use crate::segment::{Class, SEGMENT_LEVEL, segment};

/// The median time of `repeats` calls of `f` (at least one), s; None as soon as `f` gives
/// None. The live frame's figure everywhere it is reported ([`Reconstructor::frame_median`],
/// `et demo`'s sweep).
pub fn median_seconds<T>(repeats: usize, mut f: impl FnMut() -> Option<T>) -> Option<f64> {
    // Within crate::limits::REPEATS (a larger count is taken as its most).
    let repeats = repeats.clamp(
        *crate::limits::REPEATS.start(),
        *crate::limits::REPEATS.end(),
    );
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let clock = Instant::now();
        std::hint::black_box(f()?);
        times.push(clock.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Some(times[times.len() / 2])
}

/// A frame imaged as a live frame is: dV (K values, V) in f32 through the operator onto the
/// mesh's triangles, drawn on the grid's pixels (None outside the sheet).
///
/// # Errors
/// [`ReconError::FrameLength`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
pub fn onto_triangles(
    grid: &PixelGrid,
    operator: &FrameOperator,
    dv: &[f64],
) -> Result<Vec<Option<f64>>, ReconError> {
    Ok(on_pixels(grid, &operator.image(dv)?))
}

/// Values on the mesh's triangles drawn on the grid's pixels (None outside the sheet).
fn on_pixels(grid: &PixelGrid, triangles: &[f32]) -> Vec<Option<f64>> {
    grid.triangle
        .iter()
        .map(|t| t.map(|t| f64::from(triangles[t])))
        .collect()
}

impl Reconstructor {
    /// The one-step matrix of the last frame imaged (or made at set-up for a fixed alpha),
    /// factored; [`OneStep::matrix`] multiplies it out (triangles x K). None for GREIT and
    /// iterative Gauss-Newton.
    #[must_use]
    pub fn one_step(&self) -> Option<&OneStep> {
        self.one_step.as_ref().map(|m| &m.recon)
    }

    /// Makes the f32 operator onto the triangles whose warm frames
    /// [`Reconstructor::frame_median`] times (images are made from the matrix's f64 factors,
    /// which is cheaper for a few frames than making it); the seconds it took, 0 when there is
    /// nothing to make (made already, GREIT, iterative Gauss-Newton, or alpha chosen per frame
    /// and no frame imaged yet).
    pub fn prepare_frames(&self) -> f64 {
        let clock = Instant::now();
        match (self.method, &self.one_step) {
            (Method::GaussNewton { .. }, Some(m)) if m.operator.get().is_none() => {
                m.operator();
                clock.elapsed().as_secs_f64()
            }
            _ => 0.0,
        }
    }

    /// What a live frame costs, s: the median time of `repeats` applications of the last
    /// imaged frame's linear reconstruction to `dv` (K values, V) as a stream applies it (in
    /// f32 through the packed operator onto the triangles and drawn on the pixels for one-step
    /// Gauss-Newton, onto the pixels for GREIT), with the matrix warm in cache.
    /// This is the figure `et reconstruct` reports as the frame's time; `et demo` and `cargo
    /// bench -p et-recon --bench imaging` report the same. With `repeats` 1, one application
    /// as the caches find it. [`Reconstructor::image`] applies the one-step matrix's f64
    /// factors instead (exact, and for one frame cheaper than making the operator:
    /// [`FrameTimings::frame`]); the operator is made first when not yet made
    /// ([`Reconstructor::prepare_frames`]), outside the time. None for iterative Gauss-Newton (each frame is a fit),
    /// before any matrix (alpha chosen per frame), or for `dv` of another length.
    #[must_use]
    pub fn frame_median(&self, dv: &[f64], repeats: usize) -> Option<f64> {
        let greit = self.greit.as_ref().or(self.greit_chosen.as_ref());
        // The operator made before the clock starts.
        self.prepare_frames();
        let apply = || -> Option<Vec<Option<f64>>> {
            match (self.method, greit, &self.one_step) {
                (Method::Greit { .. }, Some(g), _) => g.image(dv).ok(),
                (
                    Method::GaussNewton {
                        iterations: 0 | 1, ..
                    },
                    _,
                    Some(m),
                ) => onto_triangles(&self.imager.grid, m.operator(), dv).ok(),
                _ => None,
            }
        };
        median_seconds(repeats, apply)
    }

    /// The objects of both signs in `image` (conductive and resistive, strongest first,
    /// [`crate::touches::objects`]): asked for by who images tanks, not made for every live
    /// frame, where touches are positive.
    #[must_use]
    pub fn objects(&self, image: &Image) -> Vec<Object> {
        objects(
            &self.imager.grid,
            &image.pixels,
            &image.noise_sd,
            OBJECT_FRACTION,
            TOUCH_Z,
        )
    }

    /// The three-class picture of `image` (background, resistive, conductive; None outside
    /// the sheet), from its [`objects`](Self::objects) at [`SEGMENT_LEVEL`] of each one's
    /// peak ([`crate::segment`]).
    #[must_use]
    pub fn segment(&self, image: &Image) -> Vec<Option<Class>> {
        segment(&image.pixels, &self.objects(image), SEGMENT_LEVEL)
    }

    /// How far the linearisation is off at `image`: the nonlinear model's change at the
    /// image's conductivity against the linear prediction, as a share of the measured change,
    /// |F(sigma_0 + d sigma) - F(sigma_0) - J d sigma| / |dV| (dimensionless; conductivities
    /// kept above a thousandth of the background's). Two forward solves: a measure of the
    /// model error the frame itself shows, where the reference's fitted misfit measures only
    /// the static one. None for an image without values on the triangles (GREIT).
    ///
    /// # Errors
    /// [`ImagingError::Fem`] when a forward solve fails.
    pub fn linearisation_misfit(&self, image: &Image) -> Result<Option<f64>, ImagingError> {
        let Some(d) = &image.mesh_values else {
            return Ok(None);
        };
        let sigma0 = self.imager.background();
        let sigma: Vec<f64> = sigma0
            .iter()
            .zip(d)
            .map(|(s, x)| (s + x).max(1e-3 * s))
            .collect();
        let f0 = self.imager.forward.frame(&sigma0, &self.schedule)?;
        let f1 = self.imager.forward.frame(&sigma, &self.schedule)?;
        let y = &self.jac.g * nalgebra::DVector::from_column_slice(d);
        let (mut misfit, mut norm) = (0.0, 0.0);
        for (k, row) in self.jac.combination.iter().enumerate() {
            let linear: f64 = row.iter().map(|&(p, c)| c * y[p]).sum();
            misfit += (f1[k] - f0[k] - linear).powi(2);
            norm += image.dv[k].powi(2);
        }
        Ok((norm > 0.0).then(|| (misfit / norm).sqrt()))
    }
}
