//! Frames in, images and touch events out: V_0 and the noise from untouched frames, the one-step
//! image on pixels, touches above their noise, and a trained model's class and position.

use super::*;

mod imaging;

use imaging::Imaging;

/// What a touch looks like to a downstream program (`et stream --json` prints these).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TouchEvent {
    /// Device time of the frame, us.
    pub t_us: u32,
    /// Frame sequence number.
    pub seq: u32,
    /// The class (a trained model's, or the board's), when there is a model.
    pub class: Option<u16>,
    /// Position on the sheet, mm: the model's posterior-weighted class centre, else the
    /// strongest image region's centroid. Printed to 0.1 mm (a pixel is several mm).
    #[serde(serialize_with = "tenths")]
    pub position_mm: [f64; 2],
    /// The image's strongest pixel over that pixel's noise on the untouched sheet (a z-score:
    /// noise alone stays below about 3.5 on the simulator; a 20 kPa press reaches tens).
    /// Printed to 0.1.
    #[serde(serialize_with = "tenth")]
    pub intensity: f64,
    /// The model's posterior of its class (0 to 1), when there is a model. Printed to 0.001.
    #[serde(serialize_with = "thousandth")]
    pub confidence: Option<f64>,
    /// Touches in the image: its regions split at their saddles (`recon::touches`), above
    /// the touch factor times their noise, with half the strongest peak and a quarter
    /// fingertip's area (`et_recon::select::significant`).
    pub regions: usize,
}

/// `x` rounded to `digits` decimals for printing (JSON has no NaN: non-finite stays as serde
/// writes it, null).
fn rounded(x: f64, digits: i32) -> f64 {
    let scale = 10f64.powi(digits);
    if x.is_finite() {
        (x * scale).round() / scale
    } else {
        x
    }
}

fn tenths<S: serde::Serializer>(p: &[f64; 2], s: S) -> Result<S::Ok, S::Error> {
    [rounded(p[0], 1), rounded(p[1], 1)].serialize(s)
}

fn tenth<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    rounded(*x, 1).serialize(s)
}

fn thousandth<S: serde::Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    x.map(|c| rounded(c, 3)).serialize(s)
}

/// Reference frames collected so far of those needed before images start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Referencing {
    /// Untouched frames averaged so far.
    pub frames: usize,
    /// Frames V_0 needs ([`Settings::reference_frames`]).
    pub needed: usize,
}

/// The pixel projection of the reconstruction matrix for one configuration, method and
/// alpha.
struct Projection {
    config: ScanConfig,
    method: Method,
    alpha: f64,
    /// Pixels inside the sheet x K, in thin factors.
    matrix: FrameOperator,
    /// Its entries squared: a pixel's noise under a touched frame's channel variances,
    /// made for its regions' pixels alone.
    squares: SquaredRows,
}

impl Projection {
    /// The projection in `slot` if it is for `config` and `(method, alpha)`, else a new one put
    /// there, from `recon` moved to the configuration (`at`: the one it is set up for) and the
    /// method.
    fn current<'p>(
        slot: &'p mut Option<Projection>,
        recon: &mut Reconstructor,
        at: &mut ScanConfig,
        config: &ScanConfig,
        (method, alpha): (Method, f64),
    ) -> Result<&'p Projection, LiveError> {
        let kept = slot
            .take()
            .filter(|p| p.config == *config && p.method == method && p.alpha == alpha);
        let projection = match kept {
            Some(p) => p,
            None => {
                if *at != *config {
                    recon.set_schedule(config.schedule()?)?;
                    *at = *config;
                }
                let (method_of, rule) = live_reconstruction(method, alpha);
                recon.set_method(method_of, rule)?;
                let matrix = recon.pixel_operator()?;
                let squares = SquaredRows::of(&matrix);
                Projection {
                    config: *config,
                    method,
                    alpha,
                    matrix,
                    squares,
                }
            }
        };
        Ok(slot.insert(projection))
    }
}

/// The reconstruction and alpha rule the live pipeline images with: one step of
/// Gauss-Newton (with `method`'s s) at the fixed `alpha`, or GREIT at the consensus noise
/// figure.
fn live_reconstruction(method: Method, alpha: f64) -> (Method, AlphaRule) {
    match method {
        Method::GaussNewton { s, .. } => (
            Method::GaussNewton { s, iterations: 1 },
            AlphaRule::Fixed(alpha),
        ),
        Method::Greit { radius } => (
            Method::Greit { radius },
            AlphaRule::NoiseFigure(et_recon::greit::NOISE_FIGURE),
        ),
    }
}

/// Settings of the live pipeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// The reconstruction (Gauss-Newton with its NOSER exponent s, one step a frame whatever
    /// its iterations; or GREIT).
    pub method: Method,
    /// Tikhonov alpha of Gauss-Newton (dimensionless, as `recon::OneStep`).
    pub alpha: f64,
    /// ROI threshold f; None: docs/method.md §6's value for the protocol.
    pub threshold: Option<f64>,
    /// A frame is a touch when one of the image's touches (`et_recon::touch_rule`) reaches
    /// this many times its pixels' noise (the noise `et reconstruct` gives its images: the
    /// untouched frames' and the model's own error); `et reconstruct`'s is
    /// [`et_recon::TOUCH_Z`], the default.
    pub touch_factor: f64,
    /// Untouched frames averaged into V_0 after a start, a configuration change or a tare.
    pub reference_frames: usize,
    /// Triangles of the imaging mesh.
    pub triangles: usize,
    /// Pixels across the image.
    pub pixels: usize,
}

impl Default for Settings {
    /// One-step Gauss-Newton, alpha 0.3 (about what GCV picks on the simulator's noisy
    /// frames), s = 0.5, 5 x the noise for a touch, 20 reference frames, 3 000 triangles, 32
    /// pixels across.
    fn default() -> Self {
        Self {
            method: Method::default(),
            alpha: 0.3,
            threshold: None,
            touch_factor: TOUCH_Z,
            reference_frames: 20,
            triangles: 3_000,
            pixels: 32,
        }
    }
}

/// Scan configurations whose V_0 a [`Processor`] keeps at once: the built-in protocols.
pub const REFERENCES_KEPT: usize = 4;

/// V_0 and the noise of the untouched frames.
#[derive(Clone, Debug)]
pub(super) struct Reference {
    pub(super) config: ScanConfig,
    /// The untouched frames so far, V.
    pub(super) frames: Vec<Vec<f32>>,
    /// What the complete reference gives, made once (and again when the method or alpha
    /// change).
    pub(super) noise: Option<Noise>,
}

/// V_0, the noise of dV per channel, and each pixel's noise through the projection built
/// with (method, alpha).
#[derive(Clone, Debug)]
pub(super) struct Noise {
    pub(super) method: Method,
    pub(super) alpha: f64,
    pub(super) v0: Vec<f64>,
    pub(super) var_dv: Vec<f64>,
    /// 1 / each pixel's noise (0 where the noise is 0), for the frames' z-scores.
    pub(super) inverse_sd: Vec<f32>,
    /// A reference of one frame carries no noise: `var_dv` is then 0 and `inverse_sd` is for
    /// a variance of 1 V^2 on every channel, and each frame's noise is estimated from its own
    /// dV ([`Noise::of_frame`]), as `et reconstruct` images such frames.
    pub(super) per_frame: bool,
}

/// One frame processed.
#[derive(Clone, Debug)]
pub struct Output {
    /// The frame.
    pub frame: LiveFrame,
    /// Reference frames collected so far and needed; the image waits until they are in.
    pub referencing: Option<Referencing>,
    /// Conductivity change per pixel (None outside the sheet), S per square.
    pub image: Vec<Option<f64>>,
    /// The touches in the image (only when touched): regions above the threshold split at
    /// their saddles, each above the touch factor times its noise; strongest first.
    pub regions: Vec<Region>,
    /// Of `regions`, those counted as touches (`TouchEvent::regions`): with half the strongest
    /// peak and a quarter fingertip's area (`et_recon::select::significant`); strongest first.
    pub touches: Vec<Region>,
    /// BVC = |V_m - V_0|, V.
    pub bvc: f64,
    /// The expected |V_m - V_0| of an untouched frame (from the reference frames), V.
    pub noise: f64,
    /// The touch, when the frame is one.
    pub event: Option<TouchEvent>,
    /// ROI threshold used.
    pub threshold: f64,
}

/// The live pipeline for one sheet (see the module docs).
pub struct Processor {
    /// The sheet's reconstruction, set up for `at`.
    recon: Reconstructor,
    at: ScanConfig,
    /// Settings; change `alpha` or `s` through [`Processor::set_settings`].
    settings: Settings,
    projection: Option<Projection>,
    /// The grid's pixels inside the sheet, in the projection's row order.
    inside: Vec<usize>,
    /// Each grid pixel's row in the projection (None outside the sheet).
    inside_index: Vec<Option<usize>>,
    /// V_0 of each scan configuration met since the last [`Processor::tare`] (at most
    /// [`REFERENCES_KEPT`], the oldest let go first): a scan switched back to finds its own
    /// untouched frames, not frames taken while the touch that made the switch was held.
    references: Vec<Reference>,
    /// The configuration of the latest frame: whose reference [`Processor::v0`] gives.
    current: Option<ScanConfig>,
    /// The board model evaluated on each touched frame (set through
    /// [`Processor::set_classifier`], which checks it is of this sheet).
    pub classifier: Option<Board>,
}

impl std::fmt::Debug for Processor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Processor")
            .field("recon", &self.recon)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl Processor {
    /// Classifies each touched frame with `board` from now on, once its classes are found
    /// to be places on this sheet ([`Board::same_sheet`]: a model of another sheet names its
    /// own sheet's places).
    ///
    /// # Errors
    /// [`UseError`] when the model was trained on another sheet.
    pub fn set_classifier(&mut self, board: Board) -> Result<(), et_learn::model::UseError> {
        let sheet = self.recon.sheet();
        board.same_sheet(&sheet.electrodes.centres(&sheet.shape))?;
        self.classifier = Some(board);
        Ok(())
    }

    /// The pipeline for `sheet`, set up for its electrodes scanned as the reference scan
    /// (adjacent; another configuration is set up when its first frame comes).
    ///
    /// # Errors
    /// [`LiveError::Imaging`] if the sheet cannot be meshed or modelled.
    pub fn new(sheet: &Sheet, settings: Settings) -> Result<Self, LiveError> {
        let at = ScanConfig {
            electrodes: sheet.electrodes.count,
            ..ScanConfig::REFERENCE
        };
        let (method, alpha) = live_reconstruction(settings.method, settings.alpha);
        let recon = et_recon::Spec {
            mesh: MeshPlan::About {
                triangles: settings.triangles,
                refine: Vec::new(),
            },
            method,
            alpha,
            pixels: settings.pixels,
            threshold: settings.threshold,
            ..et_recon::Spec::new(sheet.clone(), at.schedule()?)
        }
        .set_up()?;
        let inside: Vec<usize> = recon
            .grid()
            .triangle
            .iter()
            .enumerate()
            .filter_map(|(p, t)| t.map(|_| p))
            .collect();
        let mut inside_index = vec![None; recon.grid().triangle.len()];
        for (i, &p) in inside.iter().enumerate() {
            inside_index[p] = Some(i);
        }
        Ok(Self {
            recon,
            at,
            settings,
            projection: None,
            inside,
            inside_index,
            references: Vec::new(),
            current: None,
            classifier: None,
        })
    }

    /// The pixel grid images are on.
    #[must_use]
    pub fn grid(&self) -> &PixelGrid {
        self.recon.grid()
    }

    /// The imager (mesh, forward model, grid), for writing pictures.
    #[must_use]
    pub fn imager(&self) -> &Imager {
        self.recon.imager()
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// New settings; the reconstruction matrix is rebuilt on the next frame if the method,
    /// alpha or s changed. Mesh and pixel changes need a new `Processor`.
    pub fn set_settings(&mut self, settings: Settings) {
        self.settings = settings;
    }

    /// Forgets V_0 (of every configuration): the next `reference_frames` frames of each (the
    /// sheet untouched) make a new one.
    pub fn tare(&mut self) {
        self.references.clear();
    }

    /// The complete reference of the latest frame's configuration.
    fn reference(&self) -> Option<&Reference> {
        let r = (self.references.iter()).find(|r| Some(r.config) == self.current)?;
        (r.frames.len() >= self.settings.reference_frames.max(1)).then_some(r)
    }

    /// V_0 of the latest frame's configuration, when complete.
    #[must_use]
    pub fn v0(&self) -> Option<Vec<f64>> {
        let r = self.reference()?;
        let mut v0 = vec![0.0; r.frames.first().map_or(0, Vec::len)];
        stats::reference(&r.frames, &mut v0).ok()?;
        Some(v0)
    }

    /// The share of V_0 ([`Processor::v0`]) that the model of the untouched sheet, at its
    /// best scale, leaves unexplained ([`Reconstructor::unexplained`]); None until the
    /// reference is complete. Past [`et_recon::background::POOR_FIT`] the frames are likely of
    /// another protocol, numbering or sheet than the scene's.
    #[must_use]
    pub fn v0_unexplained(&self) -> Option<f64> {
        self.v0().map(|v0| self.recon.unexplained(&v0))
    }

    /// What is said of the electrodes whose values in V_0 stand out from the model as a
    /// detached or broken electrode's ([`Reconstructor::detached_electrodes`]), numbered from 0
    /// as the board counts; None until the reference is complete, or when none stands out.
    #[must_use]
    pub fn v0_electrode_said(&self) -> Option<String> {
        let detached = self.recon.detached_electrodes(&self.v0()?);
        let (said, _) = et_recon::background::detached_said(&detached, 0)?;
        let check = if detached.len() == 1 {
            "its clip and wire"
        } else {
            "their clips and wires"
        };
        Some(format!("{said} Check {check}"))
    }

    /// Of the untouched reference frames, the one that differs most from their mean as a
    /// change of conductivity does, and by how much ([`Reconstructor::reference_changes`]);
    /// None until the reference is complete.
    #[must_use]
    pub fn reference_changes(&self) -> Option<(usize, f64)> {
        let r = self.reference()?;
        self.recon.reference_changes(&r.frames)
    }

    /// Builds the reconstruction for frames of `config` now (the one-step or GREIT matrix on
    /// the pixels), so that the first such frame does not wait for it: a replay or a board
    /// whose configuration is known before its first frame.
    ///
    /// # Errors
    /// [`LiveError`] when the configuration is not valid for the sheet or cannot be imaged.
    pub fn prepare(&mut self, config: &ScanConfig) -> Result<(), LiveError> {
        config.validate()?;
        let Settings { method, alpha, .. } = self.settings;
        Projection::current(
            &mut self.projection,
            &mut self.recon,
            &mut self.at,
            config,
            (method, alpha),
        )?;
        Ok(())
    }

    /// Processes one frame.
    ///
    /// # Errors
    /// [`LiveError`] for a frame of the wrong length or with non-finite values, or when the
    /// reconstruction cannot be built.
    pub fn process(&mut self, frame: LiveFrame) -> Result<Output, LiveError> {
        let k = frame.voltages.len();
        let protocol = frame.config.validate()?;
        if k != protocol.frame_len() {
            return Err(LiveError::FrameLength {
                seq: frame.seq,
                got: k,
                expected: protocol.frame_len(),
            });
        }
        if frame.voltages.iter().any(|v| !v.is_finite()) {
            return Err(LiveError::NonFinite { seq: frame.seq });
        }
        let threshold = self
            .settings
            .threshold
            .unwrap_or_else(|| default_threshold(frame.config.protocol));
        let needed = self.settings.reference_frames.max(1);
        self.current = Some(frame.config);
        let at = match self
            .references
            .iter()
            .position(|r| r.config == frame.config)
        {
            Some(at) => at,
            None => {
                if self.references.len() >= REFERENCES_KEPT {
                    self.references.remove(0);
                }
                self.references.push(Reference {
                    config: frame.config,
                    frames: Vec::with_capacity(needed),
                    noise: None,
                });
                self.references.len() - 1
            }
        };
        let reference = &mut self.references[at];
        if reference.frames.len() < needed {
            reference.frames.push(frame.voltages.clone());
            return Ok(Output {
                referencing: Some(Referencing {
                    frames: reference.frames.len(),
                    needed,
                }),
                image: vec![None; self.recon.grid().triangle.len()],
                regions: Vec::new(),
                touches: Vec::new(),
                bvc: 0.0,
                noise: 0.0,
                event: None,
                threshold,
                frame,
            });
        }
        let key = (self.settings.method, self.settings.alpha);
        let projection = Projection::current(
            &mut self.projection,
            &mut self.recon,
            &mut self.at,
            &frame.config,
            key,
        )?;
        let noise = Noise::current(
            &mut reference.noise,
            &reference.frames,
            (&self.recon, projection),
            key,
        )?;
        let estimated = noise.of_frame(&self.recon, &frame)?;
        let noise = estimated.as_ref().unwrap_or(noise);
        Imaging {
            recon: &self.recon,
            inside: &self.inside,
            inside_index: &self.inside_index,
            touch_factor: self.settings.touch_factor,
            projection,
            noise,
            classifier: self.classifier.as_ref(),
        }
        .frame(frame, threshold)
    }
}

impl Noise {
    /// The noise in `slot` if it was made for `(method, alpha)`, else one made from the
    /// reference `frames` (each K values, V) through `projection` and put there, their V_0
    /// checked against `recon`'s model of the untouched sheet as a reconstruction's reference
    /// is (negated or unsigned frames imaged every touch in the wrong place).
    fn current<'n>(
        slot: &'n mut Option<Noise>,
        frames: &[Vec<f32>],
        (recon, projection): (&Reconstructor, &Projection),
        (method, alpha): (Method, f64),
    ) -> Result<&'n Noise, LiveError> {
        if let Some(kept) = slot
            .take()
            .filter(|n| n.method == method && n.alpha == alpha)
        {
            return Ok(slot.insert(kept));
        }
        // V_0 and the channel variances of an untouched frame's dV.
        let k = frames.first().map_or(0, Vec::len);
        let (mut v0, mut var_dv) = (vec![0.0; k], vec![0.0; k]);
        stats::reference(frames, &mut v0)?;
        recon.runs_with_the_model(&v0)?;
        stats::dv_variance(frames, &mut var_dv)?;
        let per_frame = frames.len() < 2;
        // The image's own noise level, E|P n|^2 = sum_p sum_k P_pk^2 var_k: the image filters
        // the noise the data carry, so a touch stands out better here than in |dV|.
        let pixel_sd = if per_frame {
            projection.matrix.noise_sd(&vec![1.0; k])?
        } else {
            projection.matrix.noise_sd(&var_dv)?
        };
        let inverse_sd = pixel_sd
            .iter()
            .map(|&sd| if sd > 0.0 { (1.0 / sd) as f32 } else { 0.0 })
            .collect();
        Ok(slot.insert(Noise {
            method,
            alpha,
            v0,
            var_dv,
            inverse_sd,
            per_frame,
        }))
    }

    /// For a reference of one frame ([`Noise::per_frame`]): this noise with each channel's
    /// variance estimated from the frame's own dV (the part no conductivity change can make,
    /// [`Reconstructor::redundancy_noise`]); None for a reference of two or more frames,
    /// whose noise is measured.
    ///
    /// # Errors
    /// [`LiveError::UnknownNoise`] when the protocol has too little redundancy to tell noise
    /// from a change.
    fn of_frame(
        &self,
        recon: &Reconstructor,
        frame: &LiveFrame,
    ) -> Result<Option<Noise>, LiveError> {
        if !self.per_frame {
            return Ok(None);
        }
        let dv: Vec<f64> = (frame.voltages.iter().zip(&self.v0))
            .map(|(a, b)| f64::from(*a) - b)
            .collect();
        let variance = recon
            .redundancy_noise(&dv)
            .map(|n| n.variance)
            .ok_or(LiveError::UnknownNoise { seq: frame.seq })?;
        // A frame equal to V_0 has no noise to see and nothing to image: no touch.
        let scale = if variance > 0.0 {
            (1.0 / variance.sqrt()) as f32
        } else {
            0.0
        };
        Ok(Some(Noise {
            method: self.method,
            alpha: self.alpha,
            v0: self.v0.clone(),
            var_dv: vec![variance; dv.len()],
            inverse_sd: self.inverse_sd.iter().map(|i| i * scale).collect(),
            per_frame: false,
        }))
    }
}
