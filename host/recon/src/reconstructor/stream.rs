//! Frames against a reference set once: the whole image of each, or its pixels alone (what a
//! stream of frames needs of each before anyone asks for its noise, regions or objects).

use super::{Image, ImagingError, Reconstructor, Reference};
use crate::onestep::ReconError;
use crate::pixels::PixelGrid;
use crate::reconstructor::spec::Method;

/// How untouched reference frames differ as a change of the sheet does
/// ([`Reconstructor::reference_changes`]); each share is a difference's mean square over its
/// part no conductivity change can make (about 1 for noise alone).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceChanges {
    /// The frame (from 0) that differs most from the frames' mean.
    pub frame: usize,
    /// How far it differs.
    pub ratio: f64,
    /// The first frame (from 0) that differs from the mean of those before it past
    /// [`crate::background::REFERENCE_CHANGE_SAID`], and how far: where a touch or a drift
    /// began. None when none does.
    pub first_unlike: Option<(usize, f64)>,
}

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
    /// Sets the untouched reference (V_0 and the noise of dV) that [`Reconstructor::image_frame`]
    /// images every later frame against, checked once here. The matrices made for the
    /// frames (one per alpha chosen, a few kept) and each frame's noise image's squared rows
    /// are kept from frame to frame, so a recording's frames cost the frame, not the set-up.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] when V_0 or the noise is not of K values,
    /// [`ReconError::NonFinite`] for NaN or infinity in them.
    pub fn set_reference(&mut self, reference: Reference) -> Result<(), ImagingError> {
        let k = self.schedule.frame_len();
        for (what, n) in [
            ("reference V_0", reference.v0.len()),
            ("reference noise", reference.var_dv.len()),
        ] {
            if n != k {
                return Err(ReconError::FrameLength { what, got: n, k }.into());
            }
        }
        if reference
            .v0
            .iter()
            .chain(&reference.var_dv)
            .any(|v| !v.is_finite())
        {
            return Err(ReconError::NonFinite.into());
        }
        self.runs_with_the_model(&reference.v0)?;
        self.reference = Some(reference);
        Ok(())
    }

    /// Whether `v0` (K values, V) runs with the model's frame of the untouched sheet: their
    /// correlation sum_k v0_k m_k / (|v0| |m|) positive. Frames of the other sign (a polarity
    /// or a drive swapped) image every touch as its opposite; one of a single value (all zero,
    /// a constant) is no measurement. The model's frame is the one the Jacobian was made at:
    /// K products, no solve.
    ///
    /// Magnitudes without their sign, and the model's frame plus a common level (ADC counts
    /// about a mid-scale), are refused too ([`crate::background::not_signed`]).
    ///
    /// # Errors
    /// [`ImagingError::ReferenceNotMeasured`]; [`ImagingError::ReferenceNotSigned`];
    /// [`ImagingError::ReferenceAgainstModel`] naming the correlation.
    pub fn runs_with_the_model(&self, v0: &[f64]) -> Result<(), ImagingError> {
        if let Some(value) = crate::background::one_value(v0) {
            return Err(ImagingError::ReferenceNotMeasured(value));
        }
        if let Some(not) = crate::background::not_signed(v0, &self.jac.frame) {
            return Err(ImagingError::ReferenceNotSigned(not));
        }
        let r = self.correlation(v0);
        if r <= 0.0 {
            return Err(ImagingError::ReferenceAgainstModel(
                format!(
                    "runs against the model's frame of the untouched sheet (their correlation \
                     is {r:.2}, where a reference that fits has about +1)"
                ),
                crate::background::one_sign(v0),
            ));
        }
        Ok(())
    }

    /// The correlation sum_k v0_k m_k / (|v0| |m|) of `v0` (K values, V) with the model's
    /// frame of the untouched sheet, m (the one the Jacobian was made at).
    fn correlation(&self, v0: &[f64]) -> f64 {
        let model = &self.jac.frame;
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let (a, b) = (norm(v0), norm(model));
        v0.iter().zip(model).map(|(x, y)| x * y).sum::<f64>() / (a * b).max(f64::MIN_POSITIVE)
    }

    /// The share of `v0` (K values, V) that the model's frame of the untouched sheet, m, at
    /// its best scale leaves unexplained: min_s |v0 - s m| / |v0| (sqrt(1 - r^2), r their
    /// [correlation](Self::correlation)). The background fit's residual when the model was
    /// fitted to `v0`; frames of another protocol, or of electrodes numbered otherwise, leave
    /// far more ([`crate::background::POOR_FIT`]).
    #[must_use]
    pub fn unexplained(&self, v0: &[f64]) -> f64 {
        crate::background::best_scale(&self.jac.frame, v0).1
    }

    /// The electrode whose values (those it drives or measures) in `v0` (K values, V) the
    /// model's frame of the untouched sheet explains worst beside the rest, and how far off
    /// each is ([`crate::background::electrode_misfit`]); a detached or broken electrode
    /// [stands out](crate::background::ElectrodeMisfit::stands_out).
    #[must_use]
    pub fn electrode_misfit(&self, v0: &[f64]) -> Option<crate::background::ElectrodeMisfit> {
        let schedule = self.schedule();
        let electrodes = u16::try_from(schedule.electrodes()).ok()?;
        crate::background::electrode_misfit(schedule.rows(), electrodes, v0, &self.jac.frame)
    }

    /// Electrode `electrode`'s misfit in `v` (K values, V) beside the model's frame of the
    /// untouched sheet, leaving out the values `without` drive or measure
    /// ([`crate::background::misfit_of`]); None for an electrode the schedule leaves out.
    #[must_use]
    pub fn misfit_of(
        &self,
        v: &[f64],
        electrode: u16,
        without: &[u16],
    ) -> Option<crate::background::ElectrodeMisfit> {
        let schedule = self.schedule();
        let electrodes = u16::try_from(schedule.electrodes()).ok()?;
        let rows = schedule.rows();
        crate::background::misfit_of(rows, electrodes, (v, &self.jac.frame), electrode, without)
    }

    /// Of `frames` to image (each numbered, K values, V), the electrode whose values stand out
    /// as a detached or broken electrode's ([`Reconstructor::electrode_misfit`]) in most of
    /// them, none of `in_reference` (0-based: V_0 named them already): one that came off
    /// during the recording. None when none does.
    #[must_use]
    pub fn came_off<F: AsRef<[f32]>>(
        &self,
        frames: &[(usize, F)],
        in_reference: &[u16],
    ) -> Option<crate::background::CameOff> {
        use crate::background::CameOff;
        let mut seen: std::collections::BTreeMap<u16, CameOff> = Default::default();
        for (index, frame) in frames {
            let v: Vec<f64> = frame.as_ref().iter().map(|x| f64::from(*x)).collect();
            if let Some(m) = (self.electrode_misfit(&v))
                .filter(|m| m.stands_out() && !in_reference.contains(&m.electrode))
            {
                seen.entry(m.electrode)
                    .or_insert(CameOff {
                        misfit: m,
                        count: 0,
                        first: *index,
                        frames: frames.len(),
                    })
                    .count += 1;
            }
        }
        seen.into_values().max_by_key(|c| c.count)
    }

    /// Every electrode whose values in `v0` (K values, V) stand out from the model's frame of
    /// the untouched sheet as a detached or broken electrode's, each weighed without the
    /// others' ([`crate::background::detached_electrodes`]).
    #[must_use]
    pub fn detached_electrodes(&self, v0: &[f64]) -> Vec<crate::background::ElectrodeMisfit> {
        let schedule = self.schedule();
        let Ok(electrodes) = u16::try_from(schedule.electrodes()) else {
            return Vec::new();
        };
        crate::background::detached_electrodes(schedule.rows(), electrodes, v0, &self.jac.frame)
    }

    /// How untouched reference `frames` (each K values, V) differ as a change of
    /// conductivity does: the one that differs most from their mean, and the first that
    /// differs from those before it. A difference's share is its mean square over the mean
    /// square of its part no conductivity change can make (the protocol's redundancy,
    /// [`Reconstructor::redundancy_noise`]). Noise alone has both alike (about 1); a touch or
    /// a drift while the reference was taken lies in the changes a sheet can make, far
    /// above. None for fewer than two frames or a protocol without redundancy.
    #[must_use]
    pub fn reference_changes<F: AsRef<[f32]>>(&self, frames: &[F]) -> Option<ReferenceChanges> {
        let k = frames.first()?.as_ref().len();
        let mut mean = vec![0.0; k];
        if frames.len() < 2 || et_core::stats::reference(frames, &mut mean).is_err() {
            return None;
        }
        let mut most: Option<(usize, f64)> = None;
        for (i, f) in frames.iter().enumerate() {
            let ratio = self.change_ratio(f.as_ref(), &mean)?;
            if most.is_none_or(|(_, r)| ratio > r) {
                most = Some((i, ratio));
            }
        }
        let (frame, ratio) = most?;
        // The mean of the frames before each, kept as it grows.
        let mut before = vec![0.0; k];
        let mut first_unlike = None;
        for (i, f) in frames.iter().enumerate() {
            let f = f.as_ref();
            if i > 0 {
                let r = self.change_ratio(f, &before)?;
                if r > crate::background::REFERENCE_CHANGE_SAID {
                    first_unlike = Some((i, r));
                    break;
                }
            }
            for (b, v) in before.iter_mut().zip(f) {
                *b += (f64::from(*v) - *b) / (i + 1) as f64;
            }
        }
        Some(ReferenceChanges {
            frame,
            ratio,
            first_unlike,
        })
    }

    /// The share of `frame - mean` (K values, V) that lies in the changes a sheet can make:
    /// its mean square over its redundancy noise's variance ([`Reconstructor::reference_changes`]).
    fn change_ratio(&self, frame: &[f32], mean: &[f64]) -> Option<f64> {
        let dv: Vec<f64> = (frame.iter().zip(mean))
            .map(|(v, m)| f64::from(*v) - m)
            .collect();
        let noise = self.redundancy_noise(&dv)?.variance;
        Some(
            dv.iter().map(|d| d * d).sum::<f64>()
                / dv.len().max(1) as f64
                / noise.max(f64::MIN_POSITIVE),
        )
    }

    /// Whether one-step Gauss-Newton's images keep their values on the mesh's triangles
    /// ([`Image::mesh_values`]; the default). Without them, a matrix's second frame on is
    /// imaged onto the pixels alone through its f32 operator, as
    /// [`Reconstructor::frame_pixels`] does: what a stream of frames whose objects are read
    /// needs (a 32-electrode protocol's factors onto 8 000 triangles are 32 MB a frame).
    pub fn keep_mesh_values(&mut self, keep: bool) {
        self.mesh_values = keep;
    }

    /// The reference set by [`Reconstructor::set_reference`].
    #[must_use]
    pub fn reference(&self) -> Option<&Reference> {
        self.reference.as_ref()
    }

    /// [`Reconstructor::image`] of `frame` (V, K values) against the reference set.
    ///
    /// # Errors
    /// [`ImagingError::NoReference`] when none was set; as [`Reconstructor::image`].
    pub fn image_frame(&mut self, frame: &[f32]) -> Result<Image, ImagingError> {
        let reference = self.reference.take().ok_or(ImagingError::NoReference)?;
        let image = self.image(frame, &reference);
        self.reference = Some(reference);
        image
    }

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
        let (dv, alpha) = self.frame_matrix(frame)?;
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

    /// [`Reconstructor::frame_pixels`] drawn as a picture is read ([`PixelGrid::top_first`]:
    /// rows from the top, each value times `scale`, NaN outside) over `out` (height x width
    /// values), straight from the f32 operator's rows where the frame goes through it; dV
    /// (K values, V) and alpha returned.
    ///
    /// # Errors
    /// As [`Reconstructor::frame_pixels`].
    pub fn frame_picture(
        &mut self,
        frame: &[f32],
        scale: f64,
        out: &mut [f64],
    ) -> Result<(Vec<f64>, f64), ImagingError> {
        let Method::GaussNewton {
            iterations: 0 | 1, ..
        } = self.method
        else {
            let made = self.frame_pixels(frame)?;
            self.imager.grid.top_first_onto(&made.pixels, scale, out);
            return Ok((made.dv, made.alpha));
        };
        let (dv, alpha) = self.frame_matrix(frame)?;
        let grid = &self.imager.grid;
        let matrix = self.one_step.as_mut().ok_or(ReconError::Singular)?;
        matrix.frames += 1;
        if matrix.frames == 1 {
            grid.top_first_onto(&grid.image(&matrix.recon.reconstruct(&dv)?), scale, out);
        } else {
            matrix.pixel_operator(grid).picture(grid, &dv, scale, out)?;
        }
        Ok((dv, alpha))
    }

    /// One-step Gauss-Newton's dV of `frame` against the reference set and its alpha, the
    /// matrix at that alpha made the current one.
    fn frame_matrix(&mut self, frame: &[f32]) -> Result<(Vec<f64>, f64), ImagingError> {
        let reference = self.reference.as_ref().ok_or(ImagingError::NoReference)?;
        let dv = self.difference(frame, reference)?;
        let alpha = match self.alpha {
            super::AlphaRule::Fixed(a) => a,
            _ => {
                let (var_dv, _) = self.frame_noise(&dv, &reference.var_dv);
                let var = self.imaging_variance(&var_dv, &dv);
                self.gauss_newton_alpha(&dv, &var_dv, &var)?
            }
        };
        self.matrix_at(alpha)?;
        Ok((dv, alpha))
    }
}

impl super::Matrix {
    /// The pixels of `dv` through the f32 operator onto the pixels (made at the first call).
    pub(super) fn pixels_of(
        &self,
        grid: &PixelGrid,
        dv: &[f64],
    ) -> Result<Vec<Option<f64>>, ReconError> {
        self.pixel_operator(grid).image(dv)
    }

    /// The f32 operator onto `grid`'s pixels, made at the first call.
    pub(super) fn pixel_operator(&self, grid: &PixelGrid) -> &crate::pixels::PixelOperator {
        self.pixels.get_or_init(|| grid.project_under(&self.recon))
    }
}
