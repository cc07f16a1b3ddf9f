//! What a reconstructor is made from ([`Spec`], [`MeshPlan`], [`Method`], [`AlphaRule`]) and
//! what it gives ([`Reference`], [`Image`] and their timings).

use super::*;

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
    /// [`ImagingError::Mesh`] when the sheet cannot be meshed; [`ReconError::MeshElectrodes`] for
    /// a given mesh with another electrode count.
    pub fn mesh(self, sheet: &Sheet) -> Result<Mesh, ImagingError> {
        let mesh = match self {
            MeshPlan::About { triangles, refine } => {
                Mesh::with_about_refined(sheet, triangles, &refine)?
            }
            MeshPlan::Given(mesh) => {
                fits(&mesh, sheet)?;
                mesh
            }
        };
        if mesh.electrodes.len() != usize::from(sheet.electrodes.count) {
            return Err(ReconError::MeshElectrodes {
                mesh: mesh.electrodes.len(),
                sheet: usize::from(sheet.electrodes.count),
            }
            .into());
        }
        Ok(mesh)
    }
}

/// Whether a mesh made elsewhere is the sheet's: every node on the sheet and the mesh's extent
/// the sheet's, each within 5 % of the sheet's size (a mesh in mm, or a square mesh for a
/// disc, would image another sheet).
fn fits(mesh: &Mesh, sheet: &Sheet) -> Result<(), ImagingError> {
    let [x0, y0, x1, y1] = sheet.shape.bounds();
    let tol = 0.05 * (x1 - x0).max(y1 - y0);
    if let Some((i, p)) = (mesh.nodes.iter().enumerate())
        .find(|(_, p)| !(p.iter().all(|v| v.is_finite()) && sheet.shape.contains(**p, tol)))
    {
        return Err(ReconError::MeshNodeOffSheet {
            node: i,
            at: *p,
            sheet: [x1 - x0, y1 - y0],
        }
        .into());
    }
    let [m0, n0, m1, n1] = mesh.nodes.iter().fold(
        [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ],
        |[a, b, c, d], p| [a.min(p[0]), b.min(p[1]), c.max(p[0]), d.max(p[1])],
    );
    if [m0 - x0, n0 - y0, x1 - m1, y1 - n1]
        .iter()
        .any(|gap| *gap > tol)
    {
        return Err(ReconError::MeshExtent {
            mesh: [m0, n0, m1, n1],
            sheet: [x0, y0, x1, y1],
        }
        .into());
    }
    Ok(())
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

impl Method {
    /// The methods by name at their default parameters: what `--method` (and Python's
    /// `method=`) choose from.
    pub const NAMED: [Method; 2] = [
        Method::GaussNewton {
            s: 0.5,
            iterations: 1,
        },
        Method::Greit { radius: None },
    ];

    /// Its name on the command line and in Python: `gn` or `greit`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::GaussNewton { .. } => "gn",
            Method::Greit { .. } => "greit",
        }
    }

    /// The method named `name` at its default parameters ([`Method::NAMED`]).
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::NAMED.into_iter().find(|m| m.name() == name)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::GaussNewton { iterations, .. } if *iterations > 1 => "iterative Gauss-Newton",
            Method::GaussNewton { .. } => "one-step Gauss-Newton",
            Method::Greit { .. } => "GREIT",
        })
    }
}

/// The methods as command-line values (`--method gn|greit`), by their names, at their
/// default parameters (the command's other flags set s, the iterations and GREIT's radius).
#[cfg(feature = "clap")]
impl clap::ValueEnum for Method {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::NAMED
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let help = match self {
            Method::GaussNewton { .. } => {
                "Gauss-Newton with the NOSER prior: one step (one matrix), or iterated"
            }
            Method::Greit { .. } => {
                "GREIT, the consensus linear reconstruction (lambda by the noise figure)"
            }
        };
        Some(clap::builder::PossibleValue::new(self.name()).help(help))
    }
}

/// How alpha (dimensionless: lambda = alpha^2 tr(A) / K) is chosen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AlphaRule {
    /// This alpha for every frame: one matrix, made at set-up.
    Fixed(f64),
    /// Generalised cross-validation on each frame, never fitting closer than its noise and
    /// the model's error ([`DataSpace::choose_alpha`]; for GREIT, [`Greit::choose_alpha`]): a
    /// matrix per frame. GREIT's per-frame rule; for Gauss-Newton the default before the
    /// L-curve's corner, which holds where this over-smooths (a tank whose background misfit
    /// does not carry into dV, docs/measurements.md "Defaults on real tanks").
    Gcv,
    /// Gauss-Newton only: chosen on each frame by this criterion (a matrix per frame). The
    /// default is [`crate::gcv::Criterion::CornerAboveFloor`]: on two real tanks and the
    /// simulated ones, mismatched or not, its worst case is the best of the rules measured.
    Chosen(crate::gcv::Criterion),
    /// GREIT only: lambda set by this noise figure (one matrix for every frame, the
    /// consensus rule; 0.5 is the consensus value).
    NoiseFigure(f64),
}

impl AlphaRule {
    /// The rule a user's text asks for with `method`: a number (a fixed alpha), "gcv"
    /// (generalised cross-validation on each frame, no closer than the noise), "corner",
    /// "discrepancy", "lcurve" or "quasi-optimality" (those criteria on each frame,
    /// [`crate::gcv::Criterion`]), or "auto": the corner for Gauss-Newton, and for GREIT the
    /// lambda of `noise_figure` (one matrix for every frame, the consensus rule).
    ///
    /// # Errors
    /// [`ReconError::UnknownName`] for other text.
    pub fn from_text(text: &str, method: &Method, noise_figure: f64) -> Result<Self, ReconError> {
        use crate::gcv::Criterion;
        let rule =
            match text {
                "gcv" => AlphaRule::Gcv,
                "corner" => AlphaRule::Chosen(Criterion::CornerAboveFloor),
                "discrepancy" => AlphaRule::Chosen(Criterion::Discrepancy),
                "lcurve" | "l-curve" => AlphaRule::Chosen(Criterion::LCurve),
                "quasi-optimality" => AlphaRule::Chosen(Criterion::QuasiOptimality),
                "auto" => match method {
                    Method::Greit { .. } => AlphaRule::NoiseFigure(noise_figure),
                    Method::GaussNewton { .. } => AlphaRule::Chosen(Criterion::CornerAboveFloor),
                },
                v => AlphaRule::Fixed(v.trim().parse::<f64>().map_err(|_| {
                    ReconError::UnknownName {
                        what: "alpha",
                        given: v.to_string(),
                        choices: "a number, auto, corner, gcv, discrepancy, lcurve or \
                              quasi-optimality",
                    }
                })?),
            };
        Ok(rule)
    }
}

/// Everything a [`Reconstructor`] is made from.
#[derive(Clone, Debug)]
pub struct Spec {
    /// The sheet: outline, sheet resistance, electrodes and their model.
    pub sheet: Sheet,
    /// The frame's measurements: who drives, who measures, with what current.
    pub schedule: Schedule,
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
    /// `sheet` measured by `schedule`: one-step Gauss-Newton (s = 0.5), alpha by the L-curve's
    /// corner above GCV's floor per frame, about 8 000 triangles, 64 pixels across, the protocol's threshold.
    #[must_use]
    pub fn new(sheet: Sheet, schedule: Schedule) -> Self {
        Self {
            sheet,
            schedule,
            mesh: MeshPlan::About {
                triangles: 8_000,
                refine: Vec::new(),
            },
            method: Method::default(),
            alpha: AlphaRule::Chosen(crate::gcv::Criterion::CornerAboveFloor),
            pixels: 64,
            threshold: None,
        }
    }

    /// Every number of the spec within its domain ([`crate::limits`]): the triangles asked
    /// for, the frame's length, the iterations and s, GREIT's radius, a fixed alpha or noise figure, the pixels
    /// and the threshold. [`Spec::set_up`] and [`Spec::set_up_fitted`] run it first.
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] or [`ReconError::CountOutOfRange`] naming the first value
    /// outside and what it must be.
    pub fn check(&self) -> Result<(), ReconError> {
        use crate::limits;
        if let MeshPlan::About { triangles, .. } = &self.mesh {
            limits::count("triangles", *triangles, &limits::TRIANGLES)?;
        }
        let k = self.schedule.frame_len();
        limits::count(
            "values a frame (the protocol's rows)",
            k,
            &(1..=limits::MAX_FRAME_LEN),
        )?;
        check_method(&self.method, &self.alpha)?;
        limits::count("pixels", self.pixels, &limits::PIXELS)?;
        check_threshold(self.threshold)
    }

    /// Builds the mesh, the forward model at the background, the Jacobian and what the
    /// method keeps for every frame.
    ///
    /// # Errors
    /// [`ImagingError`] when the sheet cannot be meshed or modelled, the mesh's electrodes are
    /// not the sheet's, or a parameter is out of range.
    pub fn set_up(self) -> Result<Reconstructor, ImagingError> {
        self.set_up_until(&|| false)
    }

    /// [`Spec::set_up`], asking `stop` between its stages (the mesh, the forward model, the
    /// Jacobian, the method's matrix) whether to end there: a caller that no longer wants the
    /// result (Python's Ctrl-C) ends the work at the next stage, not at its end.
    ///
    /// # Errors
    /// As [`Spec::set_up`]; [`ImagingError::Stopped`] when `stop` said so.
    pub fn set_up_until(self, stop: &dyn Fn() -> bool) -> Result<Reconstructor, ImagingError> {
        self.check()?;
        Reconstructor::new(self, stop)
    }

    /// The sheet meshed by this spec's plan, with its forward model (the sheet's electrodes,
    /// its background conductivity) and pixel grid: where [`Spec::set_up`] starts, without
    /// the Jacobian. What `et forward` simulates frames with.
    ///
    /// # Errors
    /// As [`Spec::check`]; [`ImagingError::Mesh`] when the sheet cannot be meshed,
    /// [`ImagingError::Fem`] for a forward model that cannot be built.
    pub fn imager(self) -> Result<Imager, ImagingError> {
        self.check()?;
        let mesh = self.mesh.mesh(&self.sheet)?;
        Ok(Imager::new(&self.sheet, mesh, self.pixels)?)
    }

    /// As [`Spec::set_up`] followed by [`Reconstructor::fit_background`] to the reference
    /// `v0` (K values, V) with the values weighted by `weighting`, without first making the
    /// Jacobian and matrix about the spec's background (which the fit replaces): the set-up a
    /// recording with its own reference frame needs, in about half the time.
    ///
    /// # Errors
    /// As [`Spec::set_up`] and [`Reconstructor::fit_background`].
    pub fn set_up_fitted(
        self,
        v0: &[f64],
        weighting: Weighting,
    ) -> Result<(Reconstructor, BackgroundFit), ImagingError> {
        self.check()?;
        let mut r = Reconstructor::unprepared(self, false, &|| false)?;
        r.set_weighting(weighting);
        let fit = r.fit_background(v0)?;
        Ok((r, fit))
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

/// How far a frame may be from its reference V_0, a factor either way ([`Reference::scale_of`]),
/// before it is said as another unit or current: a press changes a frame by a few per cent,
/// the real tanks' targets (two labs' saline tanks, 26 cases) by at most 8 %.
pub const FRAME_SCALE_SAID: f64 = 2.0;

impl Reference {
    /// How many times V_0 `frame` (V, K values) is: the median of its values' ratios to
    /// V_0's, over the values at least a thousandth of V_0's largest (smaller ones' ratios
    /// are noise). About 1 for frames of the same sheet, units and current, and while fewer
    /// than half of a frame's values are off (a detached electrode's railed values, a
    /// quarter of a 16-electrode frame 900 % off, moved the least-squares scale to 0.29, and
    /// the frame was said as another unit); past [`FRAME_SCALE_SAID`] either way, the frame
    /// and its reference are not alike (one in mV, the other in V; another current), and dV
    /// is not the touch's. None when V_0 is zero or the lengths differ.
    #[must_use]
    pub fn scale_of(&self, frame: &[f32]) -> Option<f64> {
        if frame.len() != self.v0.len() {
            return None;
        }
        let largest = self.v0.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut ratios: Vec<f64> = (frame.iter().zip(&self.v0))
            .filter(|(_, v)| largest > 0.0 && v.abs() >= 1e-3 * largest)
            .map(|(f, v)| f64::from(*f) / v)
            .filter(|r| r.is_finite())
            .collect();
        if ratios.is_empty() {
            return None;
        }
        let half = ratios.len() / 2;
        let (_, median, _) = ratios.select_nth_unstable_by(half, f64::total_cmp);
        Some(*median)
    }

    /// V_0 as the mean of untouched `frames` (V) and the noise of dV from their spread
    /// ([`et_core::stats::dv_variance`]; zero from one frame).
    ///
    /// # Errors
    /// [`ReconError::Reference`] for no frames or frames of different lengths.
    pub fn from_frames<F: AsRef<[f32]>>(frames: &[F]) -> Result<Self, ReconError> {
        let k = frames.first().map_or(0, |f| f.as_ref().len());
        let (mut v0, mut var_dv) = (vec![0.0; k], vec![0.0; k]);
        et_core::stats::reference(frames, &mut v0).map_err(ReconError::Reference)?;
        et_core::stats::dv_variance(frames, &mut var_dv).map_err(ReconError::Reference)?;
        Ok(Self { v0, var_dv })
    }
}

/// What one frame's image took, s.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrameTimings {
    /// The matrix made for this frame (the choice of alpha and the matrix at it);
    /// None when all of it was made before or the fit is iterative.
    pub matrix: Option<f64>,
    /// Imaging: the matrix applied to dV (the one-step matrix's f64 factors) and drawn on the
    /// pixels (the whole fit when iterative).
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

/// Where an image's noise of dV came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseSource {
    /// The reference frames' spread ([`Reference::from_frames`]).
    ReferenceFrames,
    /// The part of dV no conductivity change makes, with one reference frame
    /// ([`crate::redundancy`]), from `dof` redundant values.
    Redundancy {
        /// How many redundant values the estimate rests on.
        dof: usize,
    },
    /// Neither: one reference frame and a protocol without redundancy (zero noise assumed).
    Unknown,
}

/// The noise of dV an image was made against.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameNoise {
    /// rms over the channels of dV's noise, V.
    pub rms_v: f64,
    /// Where it came from.
    pub source: NoiseSource,
}

impl serde::Serialize for FrameNoise {
    /// As `et reconstruct --json` writes it: `rms_v`; `source`, "reference frames" (their
    /// spread), "redundancy" (the part of dV no conductivity change makes, with one reference
    /// frame) or "unknown"; `dof`, with "redundancy", how many redundant values it rests on.
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let (source, dof) = match self.source {
            NoiseSource::ReferenceFrames => ("reference frames", None),
            NoiseSource::Redundancy { dof } => ("redundancy", Some(dof)),
            NoiseSource::Unknown => ("unknown", None),
        };
        let mut s = serializer.serialize_struct("FrameNoise", 3)?;
        s.serialize_field("rms_v", &self.rms_v)?;
        s.serialize_field("source", source)?;
        s.serialize_field("dof", &dof)?;
        s.end()
    }
}

/// One frame imaged.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Conductivity change per pixel (None outside the sheet), S per square.
    pub pixels: Vec<Option<f64>>,
    /// Each pixel's noise through the reconstruction, S per square.
    pub noise_sd: Vec<Option<f64>>,
    /// Conductivity change per triangle of the mesh, S per square: Gauss-Newton's image
    /// before it is drawn on the pixels; None for GREIT, which images onto the pixels.
    pub mesh_values: Option<Vec<f64>>,
    /// dV = V - V_0, V.
    pub dv: Vec<f64>,
    /// The noise of dV the image was made against, and where it came from.
    pub noise: FrameNoise,
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

/// `method` and `alpha`'s numbers within their domains ([`crate::limits`]).
pub(crate) fn check_method(method: &Method, alpha: &AlphaRule) -> Result<(), ReconError> {
    use crate::limits;
    match *method {
        Method::GaussNewton { s, iterations } => {
            limits::count("iterations", iterations, &limits::ITERATIONS)?;
            limits::real("s", s, 0.0, true, 1.0, "from 0 to 1")?;
        }
        Method::Greit { radius } => {
            if let Some(r) = radius {
                limits::real(
                    "radius, m",
                    r,
                    0.0,
                    false,
                    limits::MAX_RADIUS_M,
                    "above 0 and at most 1 m",
                )?;
            }
        }
    }
    match *alpha {
        AlphaRule::Fixed(a) => limits::real(
            "alpha",
            a,
            0.0,
            false,
            limits::MAX_ALPHA,
            "above 0 and at most 1e6",
        ),
        AlphaRule::NoiseFigure(f) => limits::real(
            "noise figure",
            f,
            0.0,
            false,
            limits::MAX_NOISE_FIGURE,
            "above 0 and at most 100",
        ),
        _ => Ok(()),
    }
}

/// A ROI threshold f (None: the protocol's) within [0, 1].
pub(crate) fn check_threshold(threshold: Option<f64>) -> Result<(), ReconError> {
    match threshold {
        Some(f) => crate::limits::real("threshold", f, 0.0, true, 1.0, "from 0 to 1"),
        None => Ok(()),
    }
}
