//! Frames against a reference set, their pixels alone: what a stream of frames needs of each
//! before anyone asks for its noise, regions or objects.

use super::{ImagingError, Reconstructor};
use crate::onestep::ReconError;
use crate::pixels::PixelGrid;
use crate::reconstructor::spec::Method;

/// One frame's pixels against the reference set ([`Reconstructor::frame_pixels`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FramePixels {
    /// dV = V - V_0, V (K values).
    pub dv: Vec<f64>,
    /// The alpha the frame was imaged at.
    pub alpha: f64,
    /// Delta sigma, S per square, on each pixel (the bottom row first, None outside the
    /// sheet), as [`super::Image::pixels`].
    pub pixels: Vec<Option<f64>>,
}

impl Reconstructor {
    /// The pixels of `frame` (V, K values) against the reference set
    /// ([`Reconstructor::set_reference`]), and no more: [`Reconstructor::image_frame`] makes
    /// the whole image (the pixels' noise, regions, touches) of the same frame. One-step
    /// Gauss-Newton applies its matrix's f64 factors to the first frame at an alpha and from
    /// the second on the f32 operator onto the pixels (made then, kept with the matrix), as
    /// the live pipeline does: the two agree to f32's precision. GREIT and the iterative fit
    /// make the whole image.
    ///
    /// # Errors
    /// [`ImagingError::NoReference`] when none was set; as [`Reconstructor::image`].
    pub fn frame_pixels(&mut self, frame: &[f32]) -> Result<FramePixels, ImagingError> {
        let Method::GaussNewton {
            iterations: 0 | 1, ..
        } = self.method
        else {
            let image = self.image_frame(frame)?;
            return Ok(FramePixels {
                dv: image.dv,
                alpha: image.alpha,
                pixels: image.pixels,
            });
        };
        let reference = self.reference.as_ref().ok_or(ImagingError::NoReference)?;
        let dv = self.difference(frame, reference)?;
        let alpha = match self.alpha {
            super::AlphaRule::Fixed(a) => a,
            _ => {
                let var_dv = &reference.var_dv;
                let var_dv = match self.estimated_noise(&dv, var_dv) {
                    Some(n) => &vec![n.variance; dv.len()][..],
                    None => var_dv,
                };
                let var = self.imaging_variance(var_dv, &dv);
                self.gauss_newton_alpha(&dv, var_dv, &var)?
            }
        };
        self.matrix_at(alpha)?;
        let grid = &self.imager.grid;
        let matrix = self.one_step.as_mut().ok_or(ReconError::Singular)?;
        matrix.frames += 1;
        let pixels = if matrix.frames == 1 {
            grid.image(&matrix.recon.reconstruct(&dv)?)
        } else {
            matrix.pixels_of(grid, &dv)?
        };
        Ok(FramePixels { dv, alpha, pixels })
    }
}

impl super::Matrix {
    /// The pixels of `dv` through the f32 operator onto the pixels (made at the first call).
    pub(super) fn pixels_of(
        &self,
        grid: &PixelGrid,
        dv: &[f64],
    ) -> Result<Vec<Option<f64>>, ReconError> {
        let inside = self
            .pixels
            .get_or_init(|| grid.project(&self.recon))
            .image(dv)?;
        let mut values = inside.into_iter();
        Ok(grid
            .triangle
            .iter()
            .map(|t| t.and_then(|_| values.next().map(f64::from)))
            .collect())
    }
}
