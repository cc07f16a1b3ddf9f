//! Frames in, images and touch events out: V_0 and the noise from untouched frames, the one-step
//! image on pixels, touches above their noise, and a trained model's class and position.

use super::*;

mod electrodes;
mod event;
mod imaging;
mod noise;

pub use event::TouchEvent;
use imaging::Imaging;
use noise::Noise;

/// Reference frames collected so far of those needed before images start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Referencing {
    /// Untouched frames averaged so far.
    pub frames: usize,
    /// Frames V_0 needs ([`Settings::reference_frames`]).
    pub needed: usize,
}

/// What the reconstruction is set up for: a scan configuration, less the electrodes left out
/// (a detached or broken electrode's values, [`Processor::set_left_out`]).
#[derive(Clone, Debug, PartialEq)]
struct At {
    config: ScanConfig,
    /// Electrodes left out, 0-based, ascending.
    left_out: Vec<u16>,
    /// The index in the configuration's frame of each value imaged; None: all of them.
    kept: Option<Vec<usize>>,
}

impl At {
    /// `config` less `left_out`'s values, whose reconstruction schedule this is.
    ///
    /// # Errors
    /// [`LiveError::Config`] for a configuration that is not valid, [`LiveError::LeftOut`]
    /// when the electrodes cannot be left out of its protocol.
    fn new(
        config: ScanConfig,
        left_out: &[u16],
    ) -> Result<(Self, et_core::schedule::Schedule), LiveError> {
        let schedule = config.schedule()?;
        let (schedule, kept) = if left_out.is_empty() {
            (schedule, None)
        } else {
            let (without, kept) = schedule.without(left_out)?;
            (without, Some(kept))
        };
        let at = Self {
            config,
            left_out: left_out.to_vec(),
            kept,
        };
        Ok((at, schedule))
    }

    /// Of `v` (a frame's K values of this configuration), the values imaged.
    fn keep<T: Copy>(&self, v: &[T]) -> Vec<T> {
        match &self.kept {
            Some(kept) => kept.iter().filter_map(|&k| v.get(k).copied()).collect(),
            None => v.to_vec(),
        }
    }
}

/// The pixel projection of the reconstruction matrix for one configuration (its electrodes
/// left out), method and alpha.
struct Projection {
    at: At,
    method: Method,
    alpha: f64,
    /// Pixels inside the sheet x K (the values kept), in thin factors.
    matrix: FrameOperator,
    /// Its entries squared: a pixel's noise under a touched frame's channel variances,
    /// made for its regions' pixels alone.
    squares: SquaredRows,
}

impl Projection {
    /// The projection in `slot` if it is for `config` less `left_out` and `(method, alpha)`,
    /// else a new one put there, from `recon` moved to them (`at`: what it is set up for) and
    /// the method.
    fn current<'p>(
        slot: &'p mut Option<Projection>,
        (recon, at): (&mut Reconstructor, &mut At),
        (config, left_out): (&ScanConfig, &[u16]),
        (method, alpha): (Method, f64),
    ) -> Result<&'p Projection, LiveError> {
        let kept = slot.take().filter(|p| {
            p.at.config == *config
                && p.at.left_out == left_out
                && p.method == method
                && p.alpha == alpha
        });
        let projection = match kept {
            Some(p) => p,
            None => {
                if at.config != *config || at.left_out != left_out {
                    let (new, schedule) = At::new(*config, left_out)?;
                    recon.set_schedule(schedule)?;
                    *at = new;
                }
                let (method_of, rule) = live_reconstruction(method, alpha);
                recon.set_method(method_of, rule)?;
                let matrix = recon.pixel_operator()?;
                let squares = SquaredRows::of(&matrix);
                Projection {
                    at: at.clone(),
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
struct Reference {
    config: ScanConfig,
    /// The untouched frames so far, V.
    frames: Vec<Vec<f32>>,
    /// What the complete reference gives, made once (and again when the method, alpha or
    /// the electrodes left out change).
    noise: Option<Noise>,
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
    /// The electrode whose values in this frame stand out from the model as a detached or
    /// broken electrode's (0-based; of the values imaged, so never one left out): a clip come
    /// off since V_0 was taken, or one V_0 named and still imaged.
    pub electrode_off: Option<ElectrodeMisfit>,
}

/// The live pipeline for one sheet (see the module docs).
pub struct Processor {
    /// The sheet's reconstruction, set up for `at`.
    recon: Reconstructor,
    at: At,
    /// Electrodes whose values are left out of the images, 0-based, ascending
    /// ([`Processor::set_left_out`]).
    left_out: Vec<u16>,
    /// Settings; change `alpha` or `s` through [`Processor::set_settings`].
    settings: Settings,
    /// The number of the first electrode in what is said of electrodes (the source's,
    /// [`crate::live::Source::electrode_base`]); 0-based everywhere else.
    electrode_base: u16,
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
        let (at, schedule) = At::new(
            ScanConfig {
                electrodes: sheet.electrodes.count,
                ..ScanConfig::REFERENCE
            },
            &[],
        )?;
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
            ..et_recon::Spec::new(sheet.clone(), schedule)
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
            left_out: Vec::new(),
            settings,
            electrode_base: 0,
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
        self.v0()
            .map(|v0| self.recon.unexplained(&self.at.keep(&v0)))
    }

    /// Of the untouched reference frames, the one that differs most from their mean as a
    /// change of conductivity does, and by how much ([`Reconstructor::reference_changes`]);
    /// None until the reference is complete.
    #[must_use]
    pub fn reference_changes(&self) -> Option<et_recon::ReferenceChanges> {
        let r = self.reference()?;
        let frames: Vec<Vec<f32>> = r.frames.iter().map(|f| self.at.keep(f)).collect();
        self.recon.reference_changes(&frames)
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
            (&mut self.recon, &mut self.at),
            (config, &self.left_out),
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
                electrode_off: None,
                frame,
            });
        }
        let key = (self.settings.method, self.settings.alpha);
        let projection = Projection::current(
            &mut self.projection,
            (&mut self.recon, &mut self.at),
            (&frame.config, &self.left_out),
            key,
        )?;
        let noise = Noise::current(
            &mut reference.noise,
            &reference.frames,
            (&self.recon, projection),
            key,
        )?;
        let estimated = noise.of_frame((&self.recon, &projection.at), &frame)?;
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
