//! A frame's cost as the live pipeline pays it, and what a reconstructor gives beside the
//! image: its one-step matrix and the objects of both signs.

use super::*;
use crate::segment::{Class, SEGMENT_LEVEL, segment};

/// The median time of `repeats` calls of `f` (at least one), s; None as soon as `f` gives
/// None. The live frame's figure everywhere it is reported ([`Reconstructor::frame_median`],
/// `et demo`'s sweep).
pub fn median_seconds<T>(repeats: usize, mut f: impl FnMut() -> Option<T>) -> Option<f64> {
    let mut times = Vec::with_capacity(repeats.max(1));
    for _ in 0..repeats.max(1) {
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
/// [`ReconError::Parameter`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
pub fn onto_triangles(
    grid: &PixelGrid,
    operator: &FrameOperator,
    dv: &[f64],
) -> Result<Vec<Option<f64>>, ReconError> {
    Ok(on_pixels(grid, &operator.image(dv)?))
}

/// Values on the mesh's triangles drawn on the grid's pixels (None outside the sheet).
pub(super) fn on_pixels(grid: &PixelGrid, triangles: &[f32]) -> Vec<Option<f64>> {
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
        self.one_step.as_ref().map(|(_, r, _)| r)
    }

    /// What a live frame costs, s: the median time of `repeats` applications of the last
    /// imaged frame's linear reconstruction to `dv` (K values, V), each as
    /// [`Reconstructor::image`] applies it (in f32 onto the triangles and drawn on the pixels
    /// for one-step Gauss-Newton, onto the pixels for GREIT), with the matrix warm in cache.
    /// This is the figure `et reconstruct` reports as the frame's time (its first application
    /// is [`FrameTimings::frame`]); `et demo` and `cargo bench -p et-recon --bench imaging`
    /// report the same. With `repeats` 1, one application as the caches find it. None for
    /// iterative Gauss-Newton (each frame is a fit), before any frame, or for `dv` of another
    /// length.
    #[must_use]
    pub fn frame_median(&self, dv: &[f64], repeats: usize) -> Option<f64> {
        let greit = self.greit.as_ref().or(self.greit_chosen.as_ref());
        let apply = || -> Option<Vec<Option<f64>>> {
            match (self.method, greit, &self.one_step) {
                (Method::Greit { .. }, Some(g), _) => g.image(dv).ok(),
                (
                    Method::GaussNewton {
                        iterations: 0 | 1, ..
                    },
                    _,
                    Some((_, _, op)),
                ) => onto_triangles(&self.imager.grid, op.get()?, dv).ok(),
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
}
