//! The one entry point from frames to an image: a [`Reconstructor`] is set up once for a
//! sheet, a protocol, a mesh, an electrode model (the sheet's), a method and an alpha rule,
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
//! use et_recon::{Reference, Spec};
//!
//! # fn frames() -> (Vec<Vec<f32>>, Vec<f32>) { unimplemented!() }
//! let sheet = Sheet::disc(0.11, 16);
//! let protocol = Protocol::new(ProtocolKind::Adjacent, 16)?;
//! let mut recon = Spec::new(sheet, protocol, 1e-3).set_up()?;
//! let (untouched, frame) = frames(); // volts, K = 208 values each
//! let image = recon.image(&frame, &Reference::from_frames(&untouched)?)?;
//! for touch in &image.touches {
//!     println!("({:.1}, {:.1}) mm", touch.centroid[0] * 1e3, touch.centroid[1] * 1e3);
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::time::Instant;

use et_core::protocol::Protocol;
use et_core::sheet::Sheet;

use crate::fem::{FemError, TransferJacobian};
use crate::gauss_newton::{Data, GaussNewton, Stop, gauss_newton};
use crate::gcv::default_alphas;
use crate::greit::{Greit, GreitOptions, Regularisation};
use crate::imager::Imager;
use crate::mesh::{Mesh, MeshError, Refinement};
use crate::onestep::{DataSpace, OneStep, ReconError, imaging_variance};
use crate::pixels::{PixelGrid, PixelOperator};
use crate::touches::{PROMINENCE, Region, TOUCH_Z, above_noise, default_threshold, regions};

/// Why a reconstruction could not be set up or a frame imaged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ImagingError {
    /// The sheet could not be meshed.
    #[error("mesh: {0}")]
    Mesh(#[from] MeshError),
    /// The forward model could not be built or solved.
    #[error("forward model: {0}")]
    Fem(#[from] FemError),
    /// A parameter, a frame or a reference is unusable, or a matrix is singular.
    #[error("{0}")]
    Recon(#[from] ReconError),
}

/// Where the mesh comes from.
#[derive(Clone, Debug)]
pub enum MeshPlan {
    /// The sheet meshed to about this many triangles, finer inside these regions (the
    /// budget stays the same).
    About {
        /// About this many triangles.
        triangles: usize,
        /// Regions meshed finer.
        refine: Vec<Refinement>,
    },
    /// A mesh made elsewhere (`mesh::import`); its electrodes must be the sheet's.
    Given(Mesh),
}

/// The reconstruction (docs/method.md §6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Gauss-Newton with the NOSER prior diag(J^T J)^s: one step (the linear reconstruction,
    /// one matrix) or several iterations refitting the data.
    GaussNewton {
        /// NOSER exponent in [0, 1].
        s: f64,
        /// 1: one step; more: iterative.
        iterations: usize,
    },
    /// GREIT, the consensus linear reconstruction onto the pixels.
    Greit {
        /// The desired image's radius of a small target, m (None: 5 % of the longer side).
        radius: Option<f64>,
    },
}

impl MeshPlan {
    /// The mesh of `sheet` by this plan; a given mesh must have the sheet's electrode count.
    ///
    /// # Errors
    /// [`ImagingError::Mesh`] when the sheet cannot be meshed; [`ReconError::Parameter`] for
    /// a given mesh with another electrode count.
    pub fn mesh(self, sheet: &Sheet) -> Result<Mesh, ImagingError> {
        let mesh = match self {
            MeshPlan::About { triangles, refine } => {
                Mesh::with_about_refined(sheet, triangles, &refine)?
            }
            MeshPlan::Given(mesh) => mesh,
        };
        if mesh.electrodes.len() != usize::from(sheet.electrodes.count) {
            return Err(ReconError::Parameter(format!(
                "the mesh has {} electrodes, the sheet {}",
                mesh.electrodes.len(),
                sheet.electrodes.count
            ))
            .into());
        }
        Ok(mesh)
    }
}

impl Default for Method {
    /// One-step Gauss-Newton with s = 0.5.
    fn default() -> Self {
        Method::GaussNewton {
            s: 0.5,
            iterations: 1,
        }
    }
}

/// How alpha (dimensionless: lambda = alpha^2 tr(A) / K) is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaRule {
    /// This alpha for every frame: one matrix, made at set-up.
    Fixed(f64),
    /// Generalised cross-validation on each frame, never fitting closer than its noise
    /// ([`DataSpace::choose_alpha`]; for GREIT, [`Greit::choose_alpha`]): a matrix per frame.
    Gcv,
    /// GREIT only: lambda set by this noise figure (one matrix for every frame, the
    /// consensus rule; 0.5 is the consensus value).
    NoiseFigure(f64),
}

/// Everything a [`Reconstructor`] is made from.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The sheet: outline, sheet resistance, electrodes and their model.
    pub sheet: Sheet,
    /// The scan's injections and measurements.
    pub protocol: Protocol,
    /// Injected current, A.
    pub amps: f64,
    /// The mesh.
    pub mesh: MeshPlan,
    /// The reconstruction.
    pub method: Method,
    /// How alpha is chosen.
    pub alpha: AlphaRule,
    /// Pixels across the image (4 to [`crate::imager::MAX_PIXELS`]).
    pub pixels: usize,
    /// ROI threshold f (keep pixels >= f max); None: the protocol's default
    /// ([`default_threshold`]).
    pub threshold: Option<f64>,
}

impl Spec {
    /// `sheet` scanned with `protocol` at `amps`: one-step Gauss-Newton (s = 0.5), alpha by
    /// GCV per frame, about 8 000 triangles, 64 pixels across, the protocol's threshold.
    #[must_use]
    pub fn new(sheet: Sheet, protocol: Protocol, amps: f64) -> Self {
        Self {
            sheet,
            protocol,
            amps,
            mesh: MeshPlan::About {
                triangles: 8_000,
                refine: Vec::new(),
            },
            method: Method::default(),
            alpha: AlphaRule::Gcv,
            pixels: 64,
            threshold: None,
        }
    }

    /// Builds the mesh, the forward model at the background, the Jacobian and what the
    /// method keeps for every frame.
    ///
    /// # Errors
    /// [`ImagingError`] when the sheet cannot be meshed or modelled, the mesh's electrodes are
    /// not the sheet's, or a parameter is out of range.
    pub fn set_up(self) -> Result<Reconstructor, ImagingError> {
        Reconstructor::new(self)
    }
}

/// The untouched sheet's frame V_0 and the noise of dV per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    /// V_0, V (K values).
    pub v0: Vec<f64>,
    /// Each channel's noise variance of dV = V - V_0, V^2 (zeros when unknown).
    pub var_dv: Vec<f64>,
}

impl Reference {
    /// V_0 as the mean of untouched `frames` (V) and the noise of dV from their spread
    /// ([`et_core::stats::dv_variance`]; zero from one frame).
    ///
    /// # Errors
    /// [`ReconError::Parameter`] for no frames or frames of different lengths.
    pub fn from_frames<F: AsRef<[f32]>>(frames: &[F]) -> Result<Self, ReconError> {
        let k = frames.first().map_or(0, |f| f.as_ref().len());
        let (mut v0, mut var_dv) = (vec![0.0; k], vec![0.0; k]);
        let bad = |e: et_core::stats::StatsError| ReconError::Parameter(format!("reference: {e}"));
        et_core::stats::reference(frames, &mut v0).map_err(bad)?;
        et_core::stats::dv_variance(frames, &mut var_dv).map_err(bad)?;
        Ok(Self { v0, var_dv })
    }
}

/// What one frame's image took, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimings {
    /// The matrix made for this frame (GCV's choice of alpha and the matrix at it); None
    /// when the matrix was made at set-up or the fit is iterative.
    pub matrix: Option<f64>,
    /// Imaging: the matrix applied to dV and drawn on the pixels (the whole fit when
    /// iterative).
    pub frame: f64,
}

/// What the set-up took, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SetUpTimings {
    /// Meshing the sheet (nothing for a given mesh).
    pub mesh: f64,
    /// The forward model, its factorisation, the frame and the Jacobian at the background.
    pub forward_jacobian: f64,
    /// What the method keeps for every frame (A = J P^-1 J^T, or GREIT's matrix).
    pub matrix: f64,
}

/// How an iterative fit went.
#[derive(Clone, Debug, PartialEq)]
pub struct Iterations {
    /// Steps completed.
    pub completed: usize,
    /// The last iterate's residual |V - F(sigma)|, V.
    pub residual: f64,
    /// Each step's length along its Gauss-Newton direction.
    pub steps: Vec<f64>,
    /// Why it stopped.
    pub stop: Stop,
}

/// One frame imaged.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Conductivity change per pixel (None outside the sheet), S per square.
    pub pixels: Vec<Option<f64>>,
    /// Each pixel's noise through the reconstruction, S per square.
    pub noise_sd: Vec<Option<f64>>,
    /// dV = V - V_0, V.
    pub dv: Vec<f64>,
    /// The alpha used.
    pub alpha: f64,
    /// GREIT's noise figure and desired-image radius (m) of the matrix used; None for
    /// Gauss-Newton.
    pub greit: Option<(f64, f64)>,
    /// The ROI threshold f used.
    pub threshold: f64,
    /// Every region above f max, largest peak first.
    pub regions: Vec<Region>,
    /// The touches: regions split at their saddles, at least [`TOUCH_Z`] times their noise.
    pub touches: Vec<Region>,
    /// The iterative fit's report (None for a one-step or GREIT image).
    pub iterations: Option<Iterations>,
    /// What this frame took.
    pub timings: FrameTimings,
}

/// A reconstruction set up for one sheet, protocol, mesh, method and alpha rule (see the
/// module docs).
pub struct Reconstructor {
    protocol: Protocol,
    amps: f64,
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
    /// The last one-step matrix made, with its alpha.
    one_step: Option<(f64, OneStep)>,
    /// What the set-up took.
    pub set_up_timings: SetUpTimings,
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

impl Reconstructor {
    fn new(spec: Spec) -> Result<Self, ImagingError> {
        let clock = Instant::now();
        let mesh = spec.mesh.mesh(&spec.sheet)?;
        let mesh_s = clock.elapsed().as_secs_f64();
        let clock = Instant::now();
        let imager = Imager::new(&spec.sheet, mesh, spec.pixels)?;
        let jac = imager.transfer_jacobian(&spec.protocol, spec.amps)?;
        let forward_jacobian = clock.elapsed().as_secs_f64();
        let mut r = Self {
            threshold: spec.threshold,
            protocol: spec.protocol,
            amps: spec.amps,
            method: spec.method,
            alpha: spec.alpha,
            imager,
            jac,
            space: None,
            greit: None,
            one_step: None,
            set_up_timings: SetUpTimings {
                mesh: mesh_s,
                forward_jacobian,
                matrix: 0.0,
            },
        };
        r.prepare()?;
        Ok(r)
    }

    /// What the method keeps for every frame: Gauss-Newton's data space (and the matrix at a
    /// fixed alpha), or GREIT's matrix under a fixed rule.
    fn prepare(&mut self) -> Result<(), ImagingError> {
        let clock = Instant::now();
        self.space = None;
        self.greit = None;
        self.one_step = None;
        match (self.method, self.alpha) {
            (Method::GaussNewton { .. }, AlphaRule::NoiseFigure(_)) => {
                return Err(ReconError::Parameter(
                    "a noise figure sets GREIT's lambda; Gauss-Newton takes a fixed alpha or GCV"
                        .into(),
                )
                .into());
            }
            (Method::GaussNewton { s, iterations }, rule) => {
                let space = DataSpace::factored(&self.jac, s)?;
                if let (AlphaRule::Fixed(alpha), 0 | 1) = (rule, iterations) {
                    self.one_step = Some((alpha, space.one_step(alpha)?));
                }
                self.space = Some(space);
            }
            (Method::Greit { radius }, AlphaRule::Fixed(a)) => {
                self.greit = Some(self.greit_with(radius, Regularisation::Alpha(a))?);
            }
            (Method::Greit { radius }, AlphaRule::NoiseFigure(nf)) => {
                self.greit = Some(self.greit_with(radius, Regularisation::NoiseFigure(nf))?);
            }
            (Method::Greit { .. }, AlphaRule::Gcv) => {}
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

    /// Another protocol (and current) on the same mesh: a new Jacobian and matrix.
    ///
    /// # Errors
    /// As [`Spec::set_up`].
    pub fn set_protocol(&mut self, protocol: Protocol, amps: f64) -> Result<(), ImagingError> {
        self.jac = self.imager.transfer_jacobian(&protocol, amps)?;
        self.protocol = protocol;
        self.amps = amps;
        self.prepare()
    }

    /// Another method or alpha rule on the same mesh and Jacobian.
    ///
    /// # Errors
    /// As [`Spec::set_up`].
    pub fn set_method(&mut self, method: Method, alpha: AlphaRule) -> Result<(), ImagingError> {
        self.method = method;
        self.alpha = alpha;
        self.prepare()
    }

    /// Another ROI threshold f (None: the protocol's default).
    pub fn set_threshold(&mut self, threshold: Option<f64>) {
        self.threshold = threshold;
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

    /// The protocol imaged.
    #[must_use]
    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// The injected current, A.
    #[must_use]
    pub fn amps(&self) -> f64 {
        self.amps
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
            .unwrap_or_else(|| default_threshold(self.protocol.kind()))
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
    /// [`ReconError::Parameter`] under [`AlphaRule::Gcv`] or for iterative Gauss-Newton,
    /// which have no one matrix.
    pub fn pixel_operator(&self) -> Result<PixelOperator, ImagingError> {
        if let Some(g) = &self.greit {
            return Ok(g.projection());
        }
        match &self.one_step {
            Some((_, r)) => Ok(self.imager.grid.project(r)),
            None => Err(ReconError::Parameter(
                "no single matrix: alpha is chosen per frame, or the fit is iterative".into(),
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
    /// [`ReconError::Parameter`] for a frame or reference not of K values,
    /// [`ReconError::NonFinite`] for NaN or infinity in them; a failed solve.
    pub fn image(&mut self, frame: &[f32], reference: &Reference) -> Result<Image, ImagingError> {
        let k = self.protocol.frame_len();
        for (what, n) in [
            ("frame", frame.len()),
            ("reference V_0", reference.v0.len()),
            ("reference noise", reference.var_dv.len()),
        ] {
            if n != k {
                return Err(
                    ReconError::Parameter(format!("{what}: {n} values for K = {k}")).into(),
                );
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
        self.image_dv(dv, &reference.var_dv)
    }

    /// As [`Reconstructor::image`], from dV = V - V_0 (V) and its noise variance per channel
    /// (V^2).
    ///
    /// # Errors
    /// As [`Reconstructor::image`].
    pub fn image_dv(&mut self, dv: Vec<f64>, var_dv: &[f64]) -> Result<Image, ImagingError> {
        // What imaging cannot explain: the frames' noise and the model's own error.
        let var = imaging_variance(var_dv, &dv);
        let grid = &self.imager.grid;
        let mut timings = FrameTimings::default();
        let mut greit_made = None;
        let mut iterations = None;
        let (alpha, pixels, noise_sd) = match self.method {
            Method::Greit { radius } => {
                let clock = Instant::now();
                let made;
                let greit = match &self.greit {
                    Some(g) => g,
                    None => {
                        let alpha = Greit::choose_alpha(&self.imager, &self.jac, &dv, &var)?;
                        made = self.greit_with(radius, Regularisation::Alpha(alpha))?;
                        timings.matrix = Some(clock.elapsed().as_secs_f64());
                        &made
                    }
                };
                greit_made = Some((greit.noise_figure, greit.radius));
                let clock = Instant::now();
                let image = greit.image(&dv)?;
                timings.frame = clock.elapsed().as_secs_f64();
                (greit.alpha, image, greit.noise_sd(&var)?)
            }
            Method::GaussNewton { s, iterations: n } => {
                let clock = Instant::now();
                let space = self.space.as_ref().ok_or(ReconError::Singular)?;
                let alpha = match self.alpha {
                    AlphaRule::Fixed(a) => a,
                    _ => space.choose_alpha(&dv, &var, &default_alphas())?,
                };
                if n <= 1 {
                    if self.one_step.as_ref().is_none_or(|(a, _)| *a != alpha) {
                        self.one_step = Some((alpha, space.one_step(alpha)?));
                        timings.matrix = Some(clock.elapsed().as_secs_f64());
                    }
                    let Some((_, recon)) = &self.one_step else {
                        return Err(ReconError::Singular.into());
                    };
                    let clock = Instant::now();
                    let image = grid.image(&recon.reconstruct(&dv)?);
                    timings.frame = clock.elapsed().as_secs_f64();
                    (alpha, image, grid.image(&recon.noise_sd(&var)?))
                } else {
                    let clock = Instant::now();
                    let sigma0 = self.imager.background();
                    let fit = gauss_newton(
                        &self.imager.forward,
                        &self.protocol,
                        self.amps,
                        &sigma0,
                        Data::Difference(&dv),
                        GaussNewton {
                            alpha,
                            s,
                            iterations: n,
                        },
                        &var,
                    )?;
                    timings.frame = clock.elapsed().as_secs_f64();
                    let last = fit.iterates.last().ok_or(ReconError::Singular)?;
                    let d: Vec<f64> = last.sigma.iter().zip(&sigma0).map(|(a, b)| a - b).collect();
                    iterations = Some(Iterations {
                        completed: fit.iterates.len(),
                        residual: last.residual,
                        steps: fit.iterates.iter().map(|i| i.step).collect(),
                        stop: fit.stop,
                    });
                    (alpha, grid.image(&d), grid.image(&last.noise_sd))
                }
            }
        };
        let f = self.threshold();
        let grid = &self.imager.grid;
        Ok(Image {
            regions: regions(grid, &pixels, f),
            touches: above_noise(
                &crate::touches::touches(grid, &pixels, &noise_sd, f, PROMINENCE),
                TOUCH_Z,
            ),
            pixels,
            noise_sd,
            dv,
            alpha,
            greit: greit_made,
            threshold: f,
            iterations,
            timings,
        })
    }
}
