//! The one entry point from frames to an image: a [`Reconstructor`] is set up once for a
//! sheet, a [`Schedule`] (the protocol: who drives, who measures, with what current; a
//! built-in protocol's or any system's from a CSV file), a mesh, an electrode model (the
//! sheet's), a method and an alpha rule,
//! then images every frame against a [`Reference`] (docs/method.md §5-6). The command line,
//! the demo, the live pipeline, the viewer, the examples and the benchmarks all image through
//! it; none chains mesh -> forward model -> Jacobian -> matrix -> image itself.
//!
//! ```text
//! Spec --set_up()--> Reconstructor { mesh, forward model, Jacobian J, A = J P^-1 J^T or GREIT }
//! frame V, Reference { V_0, var(dV) } --image()--> Image { pixels, noise, regions, touches }
//! ```
//!
//! A 22 cm disc with 16 electrodes, adjacent drive, 1 mA; V_0 from untouched frames:
//!
//! ```no_run
//! use et_core::protocol::{Protocol, ProtocolKind};
//! use et_core::sheet::Sheet;
//! use et_recon::{ImagingError, Reference, Spec};
//!
//! /// The touches in `frame` against the `untouched` frames (volts, K = 208 values each).
//! fn touches(untouched: &[Vec<f32>], frame: &[f32]) -> Result<Vec<[f64; 2]>, ImagingError> {
//!     let sheet = Sheet::disc(0.11, 16);
//!     let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("16 electrodes");
//!     let mut recon = Spec::new(sheet, protocol.schedule(1e-3)?).set_up()?;
//!     let image = recon.image(frame, &Reference::from_frames(untouched)?)?;
//!     Ok(image.touches.iter().map(|t| t.centroid).collect())
//! }
//! ```

use std::time::Instant;

use et_core::schedule::Schedule;
use et_core::sheet::Sheet;

use crate::background::{BackgroundError, BackgroundFit};
use crate::fem::{FemError, TransferJacobian};
use crate::gauss_newton::Stop;
use crate::greit::{Greit, GreitOptions, Regularisation};
use crate::imager::Imager;
use crate::mesh::{Mesh, MeshError, Refinement};
use crate::onestep::{DataSpace, OneStep, ReconError, imaging_variance};
use crate::operator::FrameOperator;
use crate::pixels::PixelGrid;
use crate::redundancy::{Redundancy, RedundancyNoise};
use crate::touches::{
    OBJECT_FRACTION, Object, Region, TOUCH_Z, default_threshold, objects, regions, touch_rule,
};

/// Why a reconstruction could not be set up or a frame imaged.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum ImagingError {
    /// The sheet could not be meshed.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The forward model could not be built or solved.
    #[error("forward model: {0}")]
    Fem(#[from] FemError),
    /// A parameter, a frame or a reference is unusable, or a matrix is singular.
    #[error(transparent)]
    Recon(#[from] ReconError),
    /// The schedule (protocol, currents) is not usable.
    #[error("protocol: {0}")]
    Schedule(#[from] et_core::schedule::ScheduleError),
    /// The background could not be fitted to the reference frame.
    #[error(transparent)]
    Background(#[from] BackgroundError),
    /// A frame to image against the reference set, and none was set.
    #[error(
        "no reference set: set the untouched frame(s) first (set_reference), or give them with \
         the frame"
    )]
    NoReference,
    /// The reference is one value throughout (all zero, a constant): not measured voltages.
    #[error("the reference V_0 {}", crate::background::not_measured_said(*.0))]
    ReferenceNotMeasured(f64),
    /// The reference is not the signed voltages the model gives
    /// ([`crate::background::not_signed`]: magnitudes, or an offset).
    #[error("the reference V_0 {0}")]
    ReferenceNotSigned(crate::background::NotSigned),
    /// The reference runs against the model's frame of the untouched sheet.
    #[error(
        "the reference V_0 {0}: are the protocol's positive and negative electrodes, or \
         source and sink, swapped, or the electrodes placed or numbered the other way \
         (first_deg and direction; placement=\"pyeit\" for pyEIT's frames)?{one_sign}",
        one_sign = if *.1 { crate::background::ONE_SIGN } else { "" }
    )]
    ReferenceAgainstModel(String, bool),
    /// The set-up was stopped by its caller between two of its stages
    /// ([`Spec::set_up_until`]).
    #[error("the set-up was stopped before its end")]
    Stopped,
    /// One frame of many failed ([`Reconstructor::image_frames`]).
    #[error("frame {index} (0-based, of those given): {source}")]
    Frame {
        /// Its place among the frames given.
        index: usize,
        /// Why.
        source: Box<ImagingError>,
    },
}

/// A reconstruction set up for one sheet, protocol, mesh, method and alpha rule (see the
/// module docs).
pub struct Reconstructor {
    /// The sheet imaged (its R_s and contact the background's, fitted or the scene's).
    sheet: Sheet,
    /// Pixels across the image.
    pixels: usize,
    schedule: Schedule,
    method: Method,
    alpha: AlphaRule,
    /// The ROI threshold asked for (None: the protocol's default).
    threshold: Option<f64>,
    imager: Imager,
    jac: TransferJacobian,
    /// Gauss-Newton's data space, shared by GCV and every alpha's matrix.
    space: Option<DataSpace>,
    /// GREIT's matrix, when one serves every frame.
    greit: Option<Greit>,
    /// The last one-step matrix used, with how its frames are applied.
    one_step: Option<Matrix>,
    /// The matrices used before it at other alphas, the latest first (at most
    /// [`MATRICES_KEPT`]): a recording's frames choose among a few neighbouring alphas of
    /// the candidates, and each matrix is made once.
    earlier: Vec<Matrix>,
    /// GREIT's matrix chosen for the last frame (alpha by GCV).
    greit_chosen: Option<Greit>,
    /// The protocol's redundancy (the noise of a frame without repeated reference frames),
    /// made on first use.
    redundancy: std::sync::OnceLock<Option<Redundancy>>,
    /// What the set-up took.
    pub set_up_timings: SetUpTimings,
    /// Each value's share of the reference the fitted background leaves unexplained, by kind
    /// of value (on a drive electrode or off), after [`Reconstructor::fit_background`].
    mismatch: Option<Vec<f64>>,
    /// Imaging counts `mismatch_factor` x that share of each value's change as the model's
    /// error ([`MISMATCH_FACTOR`] unless set; None: the constant shares of a model not
    /// fitted, [`imaging_variance`] and [`floor_variance`]).
    mismatch_factor: Option<f64>,
    /// How the values are weighted in the fit.
    weighting: Weighting,
    /// The untouched frame(s) set once for the frames after ([`Reconstructor::set_reference`]).
    reference: Option<Reference>,
    /// Whether one-step images keep their values on the mesh ([`Image::mesh_values`]).
    mesh_values: bool,
    /// Each value's weight under `weighting` (None: alike).
    weights: Option<Vec<f64>>,
}

impl std::fmt::Debug for Reconstructor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Reconstructor")
            .field("imager", &self.imager)
            .field("method", &self.method)
            .field("alpha", &self.alpha)
            .field("threshold", &self.threshold)
            .finish_non_exhaustive()
    }
}

/// [`ImagingError::Stopped`] when `stop` says so.
fn stopped(stop: &dyn Fn() -> bool) -> Result<(), ImagingError> {
    if stop() {
        Err(ImagingError::Stopped)
    } else {
        Ok(())
    }
}

impl Reconstructor {
    /// The whole set-up, asking `stop` between its stages (the mesh, the forward model, the
    /// Jacobian, the method's matrix) whether to end there.
    fn new(spec: Spec, stop: &dyn Fn() -> bool) -> Result<Self, ImagingError> {
        let mut r = Self::unprepared(spec, true, stop)?;
        stopped(stop)?;
        r.prepare()?;
        Ok(r)
    }

    /// The mesh and the forward model, and the Jacobian at the spec's background when
    /// `jacobian` (else an empty one: a background fit makes it, about the fitted sheet);
    /// nothing prepared for the frames ([`Reconstructor::prepare`]). `stop` is asked between
    /// the stages.
    fn unprepared(
        spec: Spec,
        jacobian: bool,
        stop: &dyn Fn() -> bool,
    ) -> Result<Self, ImagingError> {
        let clock = Instant::now();
        let mesh = spec.mesh.mesh(&spec.sheet)?;
        let mesh_s = clock.elapsed().as_secs_f64();
        stopped(stop)?;
        let clock = Instant::now();
        let imager = Imager::new(&spec.sheet, mesh, spec.pixels)?;
        stopped(stop)?;
        let jac = if jacobian {
            imager.transfer_jacobian(&spec.schedule)?
        } else {
            TransferJacobian {
                frame: Vec::new(),
                combination: Vec::new(),
                g: nalgebra::DMatrix::zeros(0, 0),
            }
        };
        let forward_jacobian = clock.elapsed().as_secs_f64();
        Ok(Self {
            sheet: spec.sheet,
            pixels: spec.pixels,
            threshold: spec.threshold,
            schedule: spec.schedule,
            method: spec.method,
            alpha: spec.alpha,
            imager,
            jac,
            space: None,
            greit: None,
            one_step: None,
            earlier: Vec::new(),
            greit_chosen: None,
            redundancy: std::sync::OnceLock::new(),
            mismatch: None,
            mismatch_factor: Some(MISMATCH_FACTOR),
            weighting: Weighting::Alike,
            weights: None,
            reference: None,
            mesh_values: true,
            set_up_timings: SetUpTimings {
                mesh: mesh_s,
                forward_jacobian,
                matrix: 0.0,
            },
        })
    }

    /// What the method keeps for every frame: Gauss-Newton's data space (and the matrix at a
    /// fixed alpha), or GREIT's matrix under a fixed rule.
    fn prepare(&mut self) -> Result<(), ImagingError> {
        let clock = Instant::now();
        self.space = None;
        self.greit = None;
        self.one_step = None;
        self.earlier.clear();
        self.greit_chosen = None;
        match (self.method, self.alpha) {
            (Method::GaussNewton { .. }, AlphaRule::NoiseFigure(_)) => {
                return Err(ReconError::Unsupported(
                    "a noise figure sets GREIT's lambda; Gauss-Newton takes a fixed alpha or GCV",
                )
                .into());
            }
            (Method::GaussNewton { s, iterations }, rule) => {
                let space = match &self.weights {
                    Some(w) => DataSpace::factored_weighted(&self.jac, s, w)?,
                    None => DataSpace::factored(&self.jac, s)?,
                };
                if let (AlphaRule::Fixed(alpha), 0 | 1) = (rule, iterations) {
                    self.one_step = Some(Matrix::new(alpha, space.one_step(alpha)?));
                }
                self.space = Some(space);
            }
            (Method::Greit { radius }, AlphaRule::Fixed(a)) => {
                self.greit = Some(self.greit_with(radius, Regularisation::Alpha(a))?);
            }
            (Method::Greit { radius }, AlphaRule::NoiseFigure(nf)) => {
                self.greit = Some(self.greit_with(radius, Regularisation::NoiseFigure(nf))?);
            }
            (Method::Greit { .. }, AlphaRule::Gcv | AlphaRule::Chosen(_)) => {}
        }
        self.set_up_timings.matrix = clock.elapsed().as_secs_f64();
        Ok(())
    }

    fn greit_with(
        &self,
        radius: Option<f64>,
        regularisation: Regularisation,
    ) -> Result<Greit, ReconError> {
        Greit::new(
            &self.imager,
            &self.jac,
            &GreitOptions {
                radius,
                regularisation,
            },
        )
    }

    /// Another schedule (protocol and currents) on the same mesh: a new Jacobian and matrix.
    ///
    /// # Errors
    /// As [`Spec::set_up`].
    pub fn set_schedule(&mut self, schedule: Schedule) -> Result<(), ImagingError> {
        self.jac = self.imager.transfer_jacobian(&schedule)?;
        self.schedule = schedule;
        self.redundancy = std::sync::OnceLock::new();
        self.prepare()
    }

    /// The sheet imaged: the spec's, or with the fitted background
    /// ([`Reconstructor::fit_background`]).
    #[must_use]
    pub fn sheet(&self) -> &Sheet {
        &self.sheet
    }

    /// How the values are weighted in the fit ([`Weighting`]): the weights are made from the
    /// reference by the next [`Reconstructor::fit_background`] (alike without one).
    pub fn set_weighting(&mut self, weighting: Weighting) {
        self.weighting = weighting;
    }

    /// How many times the share of V_0 the fitted background leaves unexplained imaging counts
    /// of each value's change as the model's error ([`MISMATCH_FACTOR`] by default; a
    /// negative or non-finite factor is taken as 0); None: the constant shares a model not
    /// fitted to the reference is given ([`imaging_variance`], [`floor_variance`]), as before
    /// any fit.
    pub fn set_mismatch_factor(&mut self, factor: Option<f64>) {
        self.mismatch_factor = factor.map(|f| if f.is_finite() { f.max(0.0) } else { 0.0 });
    }

    /// Another method or alpha rule on the same mesh and Jacobian.
    ///
    /// # Errors
    /// As [`Spec::set_up`].
    pub fn set_method(&mut self, method: Method, alpha: AlphaRule) -> Result<(), ImagingError> {
        spec::check_method(&method, &alpha)?;
        self.method = method;
        self.alpha = alpha;
        self.prepare()
    }

    /// Another ROI threshold f (None: the protocol's default).
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] for f outside [0, 1] (the threshold kept).
    pub fn set_threshold(&mut self, threshold: Option<f64>) -> Result<(), ReconError> {
        spec::check_threshold(threshold)?;
        self.threshold = threshold;
        Ok(())
    }

    /// The forward model and the pixel grid (for pictures and for tests).
    #[must_use]
    pub fn imager(&self) -> &Imager {
        &self.imager
    }

    /// The pixel grid images are drawn on.
    #[must_use]
    pub fn grid(&self) -> &PixelGrid {
        &self.imager.grid
    }

    /// The Jacobian at the background, factored.
    #[must_use]
    pub fn jacobian(&self) -> &TransferJacobian {
        &self.jac
    }

    /// The measurements imaged: electrodes, protocol and currents.
    #[must_use]
    pub fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> Method {
        self.method
    }

    /// The alpha rule.
    #[must_use]
    pub fn alpha_rule(&self) -> AlphaRule {
        self.alpha
    }

    /// The ROI threshold f.
    #[must_use]
    pub fn threshold(&self) -> f64 {
        self.threshold
            .unwrap_or_else(|| self.schedule.kind().map_or(0.10, default_threshold))
    }

    /// GREIT's matrix when one serves every frame (a fixed rule).
    #[must_use]
    pub fn greit(&self) -> Option<&Greit> {
        self.greit.as_ref()
    }

    /// The reconstruction onto the pixels inside the sheet as thin f32 factors, for a rule
    /// that makes one matrix for every frame (a fixed alpha, or GREIT's noise figure): the
    /// live pipeline applies it to each frame.
    ///
    /// # Errors
    /// [`ReconError::Unsupported`] under [`AlphaRule::Gcv`] or for iterative Gauss-Newton,
    /// which have no one matrix.
    pub fn pixel_operator(&self) -> Result<FrameOperator, ImagingError> {
        if let Some(g) = &self.greit {
            return Ok(g.projection());
        }
        match &self.one_step {
            Some(m) => Ok(self.imager.grid.project(&m.recon)),
            None => Err(ReconError::Unsupported(
                "no single matrix: alpha is chosen per frame, or the fit is iterative",
            )
            .into()),
        }
    }

    /// The image of `frame` (V, K values) against `reference`: dV = V - V_0, alpha by the
    /// rule, the conductivity change on the pixels with its noise (from the reference's
    /// noise and what the model cannot explain, [`imaging_variance`]), the regions above
    /// f max and the touches above [`TOUCH_Z`] times their noise.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a frame or reference not of K values,
    /// [`ReconError::NonFinite`] for NaN or infinity in them; a reference of one value or
    /// one running against the model's frame of the untouched sheet (as
    /// [`Reconstructor::set_reference`] refuses); a failed solve.
    pub fn image(&mut self, frame: &[f32], reference: &Reference) -> Result<Image, ImagingError> {
        let dv = self.difference(frame, reference)?;
        self.runs_with_the_model(&reference.v0)?;
        self.image_dv(dv, &reference.var_dv)
    }

    /// dV = `frame` - V_0 (K values, V), frame and reference checked.
    fn difference(&self, frame: &[f32], reference: &Reference) -> Result<Vec<f64>, ImagingError> {
        let k = self.schedule.frame_len();
        for (what, n) in [
            ("frame", frame.len()),
            ("reference V_0", reference.v0.len()),
            ("reference noise", reference.var_dv.len()),
        ] {
            if n != k {
                return Err(ReconError::FrameLength { what, got: n, k }.into());
            }
        }
        let dv: Vec<f64> = frame
            .iter()
            .zip(&reference.v0)
            .map(|(a, b)| f64::from(*a) - b)
            .collect();
        if dv.iter().chain(&reference.var_dv).any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite.into());
        }
        Ok(dv)
    }

    /// Each channel's variance of `dv` (K values, V) as the images see it, V^2: the frames'
    /// noise `var_dv` and the model's error (the fitted background's misfit, else
    /// [`imaging_variance`]'s share of dV). The live pipeline's pixel noise comes from here too.
    #[must_use]
    pub fn imaging_variance(&self, var_dv: &[f64], dv: &[f64]) -> Vec<f64> {
        match (&self.mismatch, self.mismatch_factor) {
            (Some(share), Some(factor)) => (var_dv.iter().zip(dv).zip(share))
                .map(|((v, d), e)| v.max(0.0) + (factor * e * d).powi(2))
                .collect(),
            _ => imaging_variance(var_dv, dv),
        }
    }

    /// The noise of `dv` (K values, V) seen in the protocol's redundancy (the part of dV no
    /// conductivity change can make, [`Redundancy`]); None when the protocol has too little
    /// redundancy.
    #[must_use]
    pub fn redundancy_noise(&self, dv: &[f64]) -> Option<RedundancyNoise> {
        self.redundancy
            .get_or_init(|| Redundancy::of(&self.jac))
            .as_ref()
            .and_then(|r| r.noise(dv))
    }

    /// The noise of `dv` from the protocol's redundancy when the frames' own, `var_dv`, is
    /// unknown (all zeros: one reference frame).
    fn estimated_noise(&self, dv: &[f64], var_dv: &[f64]) -> Option<RedundancyNoise> {
        if var_dv.iter().all(|v| *v <= 0.0) {
            self.redundancy_noise(dv)
        } else {
            None
        }
    }

    /// The noise variance of `dv`'s channels (V^2) the frame is imaged with: `var_dv`, or
    /// when that is unknown (all zeros: one reference frame) the estimate from dV itself
    /// ([`Reconstructor::redundancy_noise`]); and the frame's noise as reported.
    fn frame_noise(&self, dv: &[f64], var_dv: &[f64]) -> (Vec<f64>, FrameNoise) {
        let estimated = self.estimated_noise(dv, var_dv);
        let var_dv = match estimated {
            Some(n) => vec![n.variance; dv.len()],
            None => var_dv.to_vec(),
        };
        let ms = var_dv.iter().map(|v| v.max(0.0)).sum::<f64>() / var_dv.len().max(1) as f64;
        let noise = FrameNoise {
            rms_v: ms.sqrt(),
            source: match estimated {
                Some(n) => NoiseSource::Redundancy { dof: n.dof },
                None if ms > 0.0 => NoiseSource::ReferenceFrames,
                None => NoiseSource::Unknown,
            },
        };
        (var_dv, noise)
    }

    /// As [`Reconstructor::image`], from dV = V - V_0 (V) and its noise variance per channel
    /// (V^2). When the noise is unknown (all zeros: one reference frame), it is estimated from
    /// dV itself ([`Reconstructor::redundancy_noise`]).
    ///
    /// # Errors
    /// As [`Reconstructor::image`].
    pub fn image_dv(&mut self, dv: Vec<f64>, var_dv: &[f64]) -> Result<Image, ImagingError> {
        let (var_dv, noise) = self.frame_noise(&dv, var_dv);
        let var_dv = &var_dv[..];
        let var = self.imaging_variance(var_dv, &dv);
        let solved = match self.method {
            Method::Greit { radius } => self.solve_greit(radius, &dv, var_dv, &var)?,
            Method::GaussNewton { s, iterations } => {
                self.solve_gauss_newton(s, iterations, &dv, var_dv, &var)?
            }
        };
        let f = self.threshold();
        let grid = &self.imager.grid;
        Ok(Image {
            regions: regions(grid, &solved.pixels, f),
            touches: touch_rule(grid, &solved.pixels, f, TOUCH_Z, |p| {
                solved.noise_sd.get(p).copied().flatten()
            }),
            pixels: solved.pixels,
            noise_sd: solved.noise_sd,
            mesh_values: solved.mesh_values,
            dv,
            noise,
            alpha: solved.alpha,
            greit: solved.greit,
            threshold: f,
            iterations: solved.iterations,
            timings: solved.timings,
        })
    }
}

/// One-step matrices kept at other alphas than the last frame's.
const MATRICES_KEPT: usize = 2;

/// A one-step matrix and how its frames are applied.
#[derive(Debug)]
struct Matrix {
    /// The alpha it was made at.
    alpha: f64,
    /// Its f64 factors.
    recon: OneStep,
    /// The f32 operator onto the triangles (packed, [`FrameOperator`]) whose warm frames
    /// [`Reconstructor::frame_median`] times, made when first asked for: images are made from
    /// the f64 factors, and the operator costs more to make than a frame from them (0.7 to 1 s
    /// for 32 electrodes at 8 000 triangles). The live pipeline, which images onto the pixels
    /// through `pixel_operator`, never needs it.
    operator: std::sync::OnceLock<FrameOperator>,
    /// The f32 operator onto the pixels inside the sheet (through the triangles under them),
    /// made at the second frame imaged with this matrix by [`Reconstructor::frame_pixels`],
    /// or by any image when the values on the mesh are not kept
    /// ([`Reconstructor::keep_mesh_values`]).
    pixels: std::sync::OnceLock<crate::pixels::PixelOperator>,
    /// Frames imaged with it.
    frames: usize,
}

impl Matrix {
    fn new(alpha: f64, recon: OneStep) -> Self {
        Self {
            alpha,
            recon,
            operator: std::sync::OnceLock::new(),
            pixels: std::sync::OnceLock::new(),
            frames: 0,
        }
    }

    /// The operator, made on first use.
    fn operator(&self) -> &FrameOperator {
        self.operator.get_or_init(|| FrameOperator::of(&self.recon))
    }
}

mod batch;
mod fitted;
mod frame;
mod model_error;
mod solve;
mod stream;
pub use batch::{Found, FrameObjects};
pub use frame::*;
use model_error::mismatch_and_weights;
pub use model_error::{MISMATCH_FACTOR, Weighting};
pub use stream::{FramePixels, ReferenceChanges};
mod spec;
pub use spec::*;
