//! Live touch sensing from any source: frames in, images and touch events out. The viewer
//! (`et view`) and `et stream` are both thin shells over this module.
//!
//! - [`Source`]: where frames come from, a simulated scene (which a pointer can press), a
//!   recording (replay with pause and seek) or a board on a serial port.
//! - [`Processor`]: V_0 from the first untouched frames, then per frame dV = V_m - V_0, the
//!   one-step image onto a pixel grid (SPEC §6), its touches (regions split at their saddles),
//!   and a [`TouchEvent`] when a touch stands out of the image's noise; with a trained model also the class,
//!   its posterior and the posterior-weighted position (SPEC §9, §11).
//! - [`Monitor`]: frame rate, per-channel SNR and BVC over time, and lost frames.

use std::collections::VecDeque;
use std::path::Path;
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::protocol::ProtocolKind;
use et_core::wire::{Command, Event, Uplink};
use et_sim::scene::{Detail, Run, Scene};
use et_sim::sheet::SheetSpec;
use et_sim::touch::Touch;
use nalgebra::DMatrix;
use serde::Serialize;

use crate::imaging::Imager;
use crate::learn::fit::Fitted;
use crate::learn::model_file::ModelFile;
use crate::learn::regress::posterior_centre;
use crate::link::{Counters, Link};
use crate::mesh::Mesh;
use crate::recon::{
    OneStep, PROMINENCE, PixelGrid, Region, above_noise, default_threshold, touches,
};
use crate::recording::{self, Recording};

/// One frame as the live pipeline sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveFrame {
    /// Sequence number (gaps: frames lost).
    pub seq: u32,
    /// Device time of the scan, us.
    pub t_us: u32,
    /// What produced it.
    pub config: ScanConfig,
    /// V_m, V (K values).
    pub voltages: Vec<f32>,
    /// The true touches, when the source knows them (simulated or recorded from the sim).
    pub truth: Option<Vec<Touch>>,
    /// The board's own class for this frame (`Event::Touch`) and its margin.
    pub chip_class: Option<(u16, f32)>,
}

/// The default sheet of the simulator and of boards whose sheet is not given: 13 x 13 cm, 16
/// electrodes (SPEC §1).
///
/// # Errors
/// Never for the compiled-in scene (a message otherwise).
pub fn default_scene() -> Result<Scene, String> {
    let (name, text) = crate::demo::DEFAULT_SCENE;
    Scene::parse(text, name).map_err(|e| e.to_string())
}

/// A simulated scene, running in real time, that a pointer can press.
#[derive(Debug)]
pub struct SimSource {
    /// The scene's name.
    pub name: String,
    run: Run,
    started: Instant,
    produced: u64,
}

impl SimSource {
    /// Frames the sheet lies untouched before the scene's own touches start, so that the
    /// reference V_0 is taken on an untouched sheet (as a user puts a sheet down): twice
    /// the default reference.
    pub const LEAD_FRAMES: u64 = 40;

    /// Starts `scene`, its touches held back for [`Self::LEAD_FRAMES`] frames.
    ///
    /// # Errors
    /// A message if the sheet cannot be built.
    pub fn new(scene: &Scene, name: impl Into<String>) -> Result<Self, String> {
        let mut run = Run::new(scene).map_err(|e| e.to_string())?;
        run.hold_scene(true);
        Ok(Self {
            name: name.into(),
            run,
            started: Instant::now(),
            produced: 0,
        })
    }

    /// Presses the sheet with `touches` (in addition to the scene's own) from the next frame.
    pub fn press(&mut self, touches: Vec<Touch>) {
        self.run.set_extra_touches(touches);
    }

    /// The next frame, whatever the clock says.
    ///
    /// # Errors
    /// A message if the simulation fails.
    pub fn next_frame(&mut self) -> Result<LiveFrame, String> {
        if self.produced == Self::LEAD_FRAMES {
            self.run.hold_scene(false);
        }
        let (frame, truth) = self
            .run
            .next_frame(Detail::Frames)
            .map_err(|e| e.to_string())?;
        self.produced += 1;
        Ok(LiveFrame {
            seq: frame.seq,
            t_us: frame.timestamp.0,
            config: frame.config,
            voltages: frame.voltages.to_vec(),
            truth: Some(truth.touches),
            chip_class: None,
        })
    }
}

/// A recording played back, with pause and seek.
#[derive(Debug)]
pub struct ReplaySource {
    /// The file.
    pub name: String,
    /// Its frames.
    pub recording: Recording,
    /// The sheet it was recorded on (for imaging).
    pub sheet: SheetSpec,
    /// Index of the next frame to play.
    pub position: usize,
    /// Paused: no frames come.
    pub paused: bool,
    /// Start again at the end.
    pub looping: bool,
}

impl ReplaySource {
    /// Reads `path`; `sheet` is the sheet it was recorded on.
    ///
    /// # Errors
    /// The recording's error, naming the file.
    pub fn open(path: &Path, sheet: SheetSpec) -> Result<Self, String> {
        let recording = recording::read(path).map_err(|e| e.to_string())?;
        if recording.header.electrodes != sheet.electrodes.count {
            return Err(format!(
                "{}: frames of {} electrodes, the sheet has {}",
                path.display(),
                recording.header.electrodes,
                sheet.electrodes.count
            ));
        }
        Ok(Self {
            name: path.display().to_string(),
            recording,
            sheet,
            position: 0,
            paused: false,
            looping: true,
        })
    }

    /// Frames in the recording.
    #[must_use]
    pub fn len(&self) -> usize {
        self.recording.records.len()
    }

    /// Whether the recording has no frames.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.recording.records.is_empty()
    }

    /// Plays from frame `index` next (clamped to the recording).
    pub fn seek(&mut self, index: usize) {
        self.position = index.min(self.len().saturating_sub(1));
    }

    /// The frame at the play position, advancing it (None when paused or at the end).
    pub fn next_frame(&mut self) -> Option<LiveFrame> {
        if self.paused {
            return None;
        }
        if self.position >= self.len() {
            if !self.looping || self.is_empty() {
                return None;
            }
            self.position = 0;
        }
        let r = &self.recording.records[self.position];
        self.position += 1;
        Some(LiveFrame {
            seq: r.seq,
            t_us: r.t_us,
            config: self.recording.header.config,
            voltages: r.voltages.clone(),
            truth: r.touches.as_ref().map(|ts| {
                ts.iter()
                    .map(|t| Touch {
                        position: [t.x, t.y],
                        radius: t.radius,
                        pressure: t.pressure,
                    })
                    .collect()
            }),
            chip_class: None,
        })
    }
}

/// A board on a serial port.
#[derive(Debug)]
pub struct PortSource {
    /// The port's path.
    pub path: String,
    /// The link.
    pub link: Link,
    /// The board's latest status report.
    pub status: Option<et_core::wire::Status>,
    /// The board's latest refusal or fault, for people.
    pub last_problem: Option<String>,
    /// Frames waiting for their on-chip class.
    pending: VecDeque<LiveFrame>,
}

impl PortSource {
    /// Opens `path` and starts the scan.
    ///
    /// # Errors
    /// A message if the port cannot be opened or the board does not answer.
    pub fn open(path: &str, baud: u32) -> Result<Self, String> {
        let mut link = Link::open(path, baud).map_err(|e| e.to_string())?;
        link.request(&Command::Start, Duration::from_secs(2))
            .map_err(|e| format!("{path}: {e}"))?;
        Ok(Self {
            path: path.to_string(),
            link,
            status: None,
            last_problem: None,
            pending: VecDeque::new(),
        })
    }

    /// Puts a model on the board: uploads `blob` (the board verifies it before it replaces
    /// its model; erasing a slot takes seconds) and, for a referenced model, has the board
    /// take V_0 from its next frames, so the sheet must be untouched. Returns what happened,
    /// for people.
    ///
    /// # Errors
    /// A message when the blob is not a model, or the board refuses or does not answer
    /// (it then keeps its old model).
    pub fn install_model(&mut self, blob: &[u8]) -> Result<String, String> {
        let model = et_core::model::Model::parse(blob)
            .map_err(|e| format!("not a valid model blob: {e:?}"))?;
        self.link
            .upload_model(blob, Duration::from_secs(2), Duration::from_secs(15))
            .map_err(|e| format!("upload failed: {e}"))?;
        let loaded = format!(
            "the board verified and loaded the model ({} bytes, {} classes)",
            blob.len(),
            model.classes()
        );
        if !model.referenced() {
            return Ok(loaded);
        }
        self.link
            .request(&Command::Tare, Duration::from_secs(2))
            .map_err(|e| format!("{loaded}, but taking V_0 failed: {e}"))?;
        Ok(format!("{loaded} and took V_0: it classifies every frame"))
    }

    /// Everything that arrived, without waiting: frames (each with its on-chip class when
    /// the board sent one), and status and problems kept for [`Source::health`].
    fn drain(&mut self) -> Vec<LiveFrame> {
        while let Ok(m) = self.link.next(Duration::ZERO) {
            match m {
                Uplink::Frame(f) => self.pending.push_back(LiveFrame {
                    seq: f.seq,
                    t_us: f.timestamp.0,
                    config: f.config,
                    voltages: f.voltages.to_vec(),
                    truth: None,
                    chip_class: None,
                }),
                Uplink::Event(Event::Touch { seq, class, margin }) => {
                    if let Some(f) = self.pending.iter_mut().find(|f| f.seq == seq) {
                        f.chip_class = Some((class, margin));
                    }
                }
                Uplink::Event(Event::Status(s)) => self.status = Some(s),
                Uplink::Event(Event::Refused { command, reason }) => {
                    self.last_problem = Some(format!("the board refused {command:?}: {reason:?}"));
                }
                Uplink::Event(Event::Fault(f)) => {
                    self.last_problem = Some(format!("the board reports {f:?}"));
                }
                Uplink::Event(_) => {}
            }
        }
        // A frame's class follows it at once; keep the newest frame back one poll for it.
        let keep = usize::from(self.pending.back().is_some_and(|f| f.chip_class.is_none()));
        let n = self.pending.len().saturating_sub(keep);
        self.pending.drain(..n).collect()
    }
}

/// Where frames come from.
#[derive(Debug)]
pub enum Source {
    /// The simulator.
    Sim(Box<SimSource>),
    /// A recording.
    Replay(Box<ReplaySource>),
    /// A board.
    Port(Box<PortSource>),
}

/// How a source is doing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Health {
    /// Frames that never arrived (sequence gaps, as the receiver saw them).
    pub lost: u64,
    /// Frames the board dropped because the link was busy.
    pub dropped: u64,
    /// Damaged packets.
    pub corrupt: u64,
    /// Reconnections after a pulled cable.
    pub reconnects: u64,
}

impl Source {
    /// What it is, for people.
    #[must_use]
    pub fn describe(&self) -> String {
        match self {
            Source::Sim(s) => format!("simulated sheet: {}", s.name),
            Source::Replay(r) => format!("recording: {}", r.name),
            Source::Port(p) => format!("board on {}", p.path),
        }
    }

    /// Frames available now (at most `max`). The simulator produces frames at its frame rate
    /// in real time (`realtime`) or one per call; a recording one per call while playing.
    ///
    /// # Errors
    /// A message when the simulator fails.
    pub fn poll(&mut self, max: usize, realtime: bool) -> Result<Vec<LiveFrame>, String> {
        match self {
            Source::Sim(s) => {
                let due = if realtime {
                    let period = s.run.frame_period().max(1e-4);
                    let should = (s.started.elapsed().as_secs_f64() / period) as u64 + 1;
                    (should.saturating_sub(s.produced) as usize).min(max)
                } else {
                    max.min(1)
                };
                (0..due).map(|_| s.next_frame()).collect()
            }
            Source::Replay(r) => Ok(r.next_frame().into_iter().collect()),
            Source::Port(p) => {
                let mut frames = p.drain();
                let n = frames.len().saturating_sub(max);
                Ok(frames.split_off(n))
            }
        }
    }

    /// The scan configuration frames come with now (a board's once it has sent a frame).
    #[must_use]
    pub fn config(&self) -> Option<ScanConfig> {
        match self {
            Source::Sim(s) => Some(*s.run.config()),
            Source::Replay(r) => Some(r.recording.header.config),
            Source::Port(p) => p.pending.back().map(|f| f.config),
        }
    }

    /// Switches the scan to `config` (a board is sent `Configure`). A recording cannot
    /// change what it recorded.
    ///
    /// # Errors
    /// A message saying why not.
    pub fn configure(&mut self, config: ScanConfig) -> Result<(), String> {
        match self {
            Source::Sim(s) => s.run.set_config(config).map_err(|e| e.to_string()),
            Source::Replay(r) if r.recording.header.config == config => Ok(()),
            Source::Replay(_) => Err("a recording plays the protocol it was recorded with".into()),
            Source::Port(p) => p
                .link
                .request(&Command::Configure(config), Duration::from_secs(2))
                .map(|_| ())
                .map_err(|e| e.to_string()),
        }
    }

    /// Link counters (a board), or nothing lost (a simulator or a file).
    #[must_use]
    pub fn health(&self) -> Health {
        match self {
            Source::Port(p) => {
                let c: Counters = p.link.counters();
                Health {
                    lost: c.lost_frames,
                    dropped: p.status.map_or(0, |s| u64::from(s.dropped)),
                    corrupt: c.corrupt,
                    reconnects: c.reconnects,
                }
            }
            _ => Health::default(),
        }
    }
}

/// Which source to open.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum SourceSpec {
    /// The simulator, on the scene.
    Sim,
    /// A recording (JSON Lines, from `et sim` or `et record`) made on the scene's sheet.
    Replay(std::path::PathBuf),
    /// A board on this serial port at this baud rate, its sheet the scene's.
    Port(String, u32),
}

/// Opens `spec`. `scene` is the scene file to simulate (with its touches), or the sheet a
/// recording or a board uses (None: the default 13 x 13 cm, 16-electrode sheet, untouched
/// until something presses it). Returns the source and the sheet.
///
/// # Errors
/// A message naming the file or port.
pub fn open_source(spec: &SourceSpec, scene: Option<&Path>) -> Result<(Source, SheetSpec), String> {
    let (scene, name) = match scene {
        Some(p) => (
            Scene::load(p).map_err(|e| e.to_string())?,
            p.display().to_string(),
        ),
        None => {
            let mut scene = default_scene()?;
            scene.touches.clear();
            (scene, crate::demo::DEFAULT_SCENE.0.to_string())
        }
    };
    let sheet = scene.sheet.clone();
    let source = match spec {
        SourceSpec::Sim => Source::Sim(Box::new(SimSource::new(&scene, name)?)),
        SourceSpec::Replay(path) => {
            Source::Replay(Box::new(ReplaySource::open(path, sheet.clone())?))
        }
        SourceSpec::Port(path, baud) => Source::Port(Box::new(PortSource::open(path, *baud)?)),
    };
    Ok((source, sheet))
}

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
    /// strongest image region's centroid.
    pub position_mm: [f64; 2],
    /// The image's strongest pixel over that pixel's noise on the untouched sheet (a z-score:
    /// noise alone stays below about 3.5 on the simulator; a 20 kPa press reaches 8 to 11).
    pub intensity: f64,
    /// The model's posterior of its class (0 to 1), when there is a model.
    pub confidence: Option<f64>,
    /// Touches in the image: its regions split at their saddles (`recon::touches`), above
    /// the touch factor times their noise, with half the strongest peak and a quarter
    /// fingertip's area (`dynamic::significant`).
    pub regions: usize,
}

/// A trained model the host evaluates on each frame.
#[derive(Clone, Debug)]
pub struct Classifier {
    /// As trained.
    pub file: ModelFile,
    fitted: Fitted,
}

impl Classifier {
    /// Wraps a model file.
    ///
    /// # Errors
    /// A message if the file's model is inconsistent.
    pub fn new(file: ModelFile) -> Result<Self, String> {
        let fitted = file.fitted().map_err(|e| e.to_string())?;
        Ok(Self { file, fitted })
    }

    /// Class, its posterior and the posterior-weighted centre (mm) of a frame, given V_0.
    /// None when the model is for another configuration.
    #[must_use]
    pub fn classify(
        &self,
        config: &ScanConfig,
        v: &[f32],
        v0: &[f64],
    ) -> Option<(u16, f64, [f64; 2])> {
        if *config != self.file.config {
            return None;
        }
        let x: Vec<f64> = self
            .file
            .feature_index
            .iter()
            .map(|&i| {
                let i = usize::from(i);
                let m = f64::from(*v.get(i)?);
                Some(if self.file.referenced {
                    m - v0.get(i)?
                } else {
                    m
                })
            })
            .collect::<Option<_>>()?;
        let d = self.fitted.discriminants(&x);
        let top = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let total: f64 = d.iter().map(|v| (v - top).exp()).sum();
        let class = d.iter().position(|&v| v == top)?;
        let centre = posterior_centre(&self.fitted, &x, &self.file.centres_mm, 1.0);
        Some((class as u16, 1.0 / total, centre))
    }
}

/// Settings of the live pipeline.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Tikhonov alpha (dimensionless, as `recon::OneStep`).
    pub alpha: f64,
    /// NOSER exponent s.
    pub s: f64,
    /// ROI threshold f; None: SPEC §6's value for the protocol.
    pub threshold: Option<f64>,
    /// A frame is a touch when one of the image's touches (`recon::touches`) peaks at more
    /// than this many times its pixel's noise on the untouched sheet.
    pub touch_factor: f64,
    /// Untouched frames averaged into V_0 after a start, a configuration change or a tare.
    pub reference_frames: usize,
    /// Triangles of the imaging mesh.
    pub triangles: usize,
    /// Pixels across the image.
    pub pixels: usize,
}

impl Default for Settings {
    /// alpha 0.3 (about what GCV picks on the simulator's noisy frames), s = 0.5, 5 x the
    /// noise for a touch, 20 reference frames, 3 000 triangles, 48 pixels.
    fn default() -> Self {
        Self {
            alpha: 0.3,
            s: 0.5,
            threshold: None,
            touch_factor: 5.0,
            reference_frames: 20,
            triangles: 3_000,
            pixels: 48,
        }
    }
}

/// V_0 and the noise of the untouched frames.
#[derive(Clone, Debug)]
struct Reference {
    config: ScanConfig,
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    count: usize,
    /// What the complete reference gives, made once (and again when alpha or s change).
    noise: Option<Noise>,
}

/// V_0, the noise of dV per channel, and each pixel's noise through the projection built
/// with (alpha, s).
#[derive(Clone, Debug)]
struct Noise {
    alpha: f64,
    s: f64,
    v0: Vec<f64>,
    var_dv: Vec<f64>,
    pixel_sd: Vec<f64>,
}

/// One frame processed.
#[derive(Clone, Debug)]
pub struct Output {
    /// The frame.
    pub frame: LiveFrame,
    /// Reference frames collected so far and needed; the image waits until they are in.
    pub referencing: Option<(usize, usize)>,
    /// Conductivity change per pixel (None outside the sheet), S per square.
    pub image: Vec<Option<f64>>,
    /// The touches in the image (only when touched): regions above the threshold split at
    /// their saddles, each above the touch factor times its noise; strongest first.
    pub regions: Vec<Region>,
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
    imager: Imager,
    /// Settings; change `alpha` or `s` through [`Processor::set_settings`].
    settings: Settings,
    jacobians: Vec<(ScanConfig, DMatrix<f64>)>,
    /// (configuration, alpha, s) and the pixel projection of its one-step matrix.
    projection: Option<(ScanConfig, f64, f64, DMatrix<f32>)>,
    inside: Vec<usize>,
    reference: Option<Reference>,
    /// The model evaluated on each touched frame.
    pub classifier: Option<Classifier>,
}

impl std::fmt::Debug for Processor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Processor")
            .field("imager", &self.imager)
            .field("settings", &self.settings)
            .finish_non_exhaustive()
    }
}

impl Processor {
    /// The pipeline for `sheet`.
    ///
    /// # Errors
    /// A message if the sheet cannot be meshed or modelled.
    pub fn new(sheet: &SheetSpec, settings: Settings) -> Result<Self, String> {
        let mesh = Mesh::with_about(sheet, settings.triangles).map_err(|e| e.to_string())?;
        let imager = Imager::new(sheet, mesh, settings.pixels).map_err(|e| e.to_string())?;
        let inside = imager
            .grid
            .triangle
            .iter()
            .enumerate()
            .filter_map(|(p, t)| t.map(|_| p))
            .collect();
        Ok(Self {
            imager,
            settings,
            jacobians: Vec::new(),
            projection: None,
            inside,
            reference: None,
            classifier: None,
        })
    }

    /// The pixel grid images are on.
    #[must_use]
    pub fn grid(&self) -> &PixelGrid {
        &self.imager.grid
    }

    /// The imager (mesh, forward model, grid), for writing pictures.
    #[must_use]
    pub fn imager(&self) -> &Imager {
        &self.imager
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> Settings {
        self.settings
    }

    /// New settings; the reconstruction matrix is rebuilt on the next frame if alpha or s
    /// changed. Mesh and pixel changes need a new `Processor`.
    pub fn set_settings(&mut self, settings: Settings) {
        self.settings = settings;
    }

    /// Forgets V_0: the next `reference_frames` frames (the sheet untouched) make a new one.
    pub fn tare(&mut self) {
        self.reference = None;
    }

    /// V_0, when complete.
    #[must_use]
    pub fn v0(&self) -> Option<Vec<f64>> {
        let r = self.reference.as_ref()?;
        (r.count >= self.settings.reference_frames.max(1))
            .then(|| r.sum.iter().map(|s| s / r.count as f64).collect())
    }

    fn projection(&mut self, config: &ScanConfig) -> Result<&DMatrix<f32>, String> {
        let Settings { alpha, s, .. } = self.settings;
        let fresh =
            matches!(&self.projection, Some((c, a, e, _)) if c == config && *a == alpha && *e == s);
        if !fresh {
            if !self.jacobians.iter().any(|(c, _)| c == config) {
                let protocol = config.validate().map_err(|e| e.to_string())?;
                let amps = f64::from(config.current_amps());
                let jac = self
                    .imager
                    .jacobian(&protocol, amps)
                    .map_err(|e| e.to_string())?;
                self.jacobians.push((*config, jac));
            }
            let jac = &self
                .jacobians
                .iter()
                .find(|(c, _)| c == config)
                .ok_or("no Jacobian")?
                .1;
            let one = OneStep::new(jac, alpha, s).map_err(|e| e.to_string())?;
            self.projection = Some((*config, alpha, s, self.imager.grid.project(&one)));
        }
        Ok(&self.projection.as_ref().ok_or("no reconstruction")?.3)
    }

    /// Processes one frame.
    ///
    /// # Errors
    /// A message for a frame of the wrong length or with non-finite values, or when the
    /// reconstruction cannot be built.
    pub fn process(&mut self, frame: LiveFrame) -> Result<Output, String> {
        let k = frame.voltages.len();
        let protocol = frame.config.validate().map_err(|e| e.to_string())?;
        if k != protocol.frame_len() {
            return Err(format!(
                "frame {}: {k} values, its protocol has {}",
                frame.seq,
                protocol.frame_len()
            ));
        }
        if frame.voltages.iter().any(|v| !v.is_finite()) {
            return Err(format!("frame {}: a value is not finite", frame.seq));
        }
        let threshold = self
            .settings
            .threshold
            .unwrap_or_else(|| default_threshold(frame.config.protocol));
        let needed = self.settings.reference_frames.max(1);
        let reference = match &mut self.reference {
            Some(r) if r.config == frame.config => r,
            slot => slot.insert(Reference {
                config: frame.config,
                sum: vec![0.0; k],
                sum_sq: vec![0.0; k],
                count: 0,
                noise: None,
            }),
        };
        if reference.count < needed {
            for ((s, q), v) in reference
                .sum
                .iter_mut()
                .zip(&mut reference.sum_sq)
                .zip(&frame.voltages)
            {
                *s += f64::from(*v);
                *q += f64::from(*v) * f64::from(*v);
            }
            reference.count += 1;
            return Ok(Output {
                referencing: Some((reference.count, needed)),
                image: vec![None; self.imager.grid.triangle.len()],
                regions: Vec::new(),
                bvc: 0.0,
                noise: 0.0,
                event: None,
                threshold,
                frame,
            });
        }
        let config = frame.config;
        self.projection(&config)?;
        let projection = &self.projection.as_ref().ok_or("no reconstruction")?.3;
        let reference = self.reference.as_mut().ok_or("no reference")?;
        let Settings { alpha, s, .. } = self.settings;
        if !reference
            .noise
            .as_ref()
            .is_some_and(|n| n.alpha == alpha && n.s == s)
        {
            let n = reference.count as f64;
            let v0: Vec<f64> = reference.sum.iter().map(|s| s / n).collect();
            // Channel variances of an untouched frame's dV.
            let var_dv: Vec<f64> = reference
                .sum_sq
                .iter()
                .zip(&v0)
                .map(|(q, m)| (q / n - m * m).max(0.0) * n / (n - 1.0).max(1.0) * (1.0 + 1.0 / n))
                .collect();
            // The image's own noise level, E|P n|^2 = sum_p sum_k P_pk^2 var_k: the image
            // filters the noise the data carry, so a touch stands out better here than in
            // |dV|.
            let pixel_sd: Vec<f64> = projection
                .row_iter()
                .map(|row| {
                    row.iter()
                        .zip(&var_dv)
                        .map(|(p, v)| f64::from(*p) * f64::from(*p) * v)
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            reference.noise = Some(Noise {
                alpha,
                s,
                v0,
                var_dv,
                pixel_sd,
            });
        }
        let Noise {
            v0,
            var_dv,
            pixel_sd,
            ..
        } = reference.noise.as_ref().ok_or("no reference")?;
        let dv: Vec<f64> = frame
            .voltages
            .iter()
            .zip(v0)
            .map(|(a, b)| f64::from(*a) - b)
            .collect();
        let bvc = dv.iter().map(|v| v * v).sum::<f64>().sqrt();
        let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
        let values = projection * nalgebra::DVector::from_vec(dv32);
        // The strongest pixel in units of its own noise (a touch raises the conductivity).
        let intensity = values
            .iter()
            .zip(pixel_sd)
            .filter(|(_, sd)| **sd > 0.0)
            .map(|(v, sd)| f64::from(*v) / sd)
            .fold(0.0, f64::max);
        let mut image = vec![None; self.imager.grid.triangle.len()];
        for (&p, v) in self.inside.iter().zip(values.iter()) {
            image[p] = Some(f64::from(*v));
        }
        // The touches: regions split at their saddles, each reaching the touch factor times
        // its pixels' noise somewhere. A frame is touched when one does.
        let rois = if intensity > self.settings.touch_factor {
            let mut sd = vec![None; image.len()];
            for (&p, v) in self.inside.iter().zip(pixel_sd) {
                sd[p] = Some(*v);
            }
            above_noise(
                &touches(&self.imager.grid, &image, &sd, threshold, PROMINENCE),
                self.settings.touch_factor,
            )
        } else {
            Vec::new()
        };
        let touched = !rois.is_empty();
        let event = touched.then(|| {
            let model = self
                .classifier
                .as_ref()
                .and_then(|c| c.classify(&config, &frame.voltages, v0));
            let chip = frame.chip_class.map(|c| c.0);
            let image_position = rois.first().map_or([f64::NAN; 2], |r| {
                [r.centroid[0] * 1e3, r.centroid[1] * 1e3]
            });
            TouchEvent {
                t_us: frame.t_us,
                seq: frame.seq,
                class: chip.or(model.map(|m| m.0)),
                position_mm: model.map_or(image_position, |m| m.2),
                intensity,
                confidence: model.map(|m| m.1),
                regions: crate::dynamic::significant(
                    &rois,
                    &crate::dynamic::Settings::new([0.0, 0.0], 1.0),
                )
                .len(),
            }
        });
        Ok(Output {
            frame,
            referencing: None,
            image,
            regions: rois,
            bvc,
            noise: var_dv.iter().sum::<f64>().sqrt(),
            event,
            threshold,
        })
    }
}

/// Frame rate, per-channel SNR and BVC over time.
#[derive(Clone, Debug, Default)]
pub struct Monitor {
    /// (wall time s since start, frames/s over the last second).
    pub rate: VecDeque<(f64, f64)>,
    /// (frame time s, BVC V).
    pub bvc: VecDeque<(f64, f64)>,
    /// Per-channel SNR over the last `WINDOW` frames, dB (20 log10 |mean| / std).
    pub snr_db: Vec<f64>,
    recent: VecDeque<Vec<f32>>,
    arrivals: VecDeque<f64>,
    started: Option<Instant>,
    last_seq: Option<u32>,
    /// Sequence gaps seen.
    pub gaps: u64,
    /// Frames seen.
    pub frames: u64,
}

impl Monitor {
    /// Frames kept for the SNR.
    pub const WINDOW: usize = 50;
    /// Points kept per plot.
    pub const HISTORY: usize = 600;

    /// Takes one processed frame.
    pub fn add(&mut self, out: &Output) {
        let now = self
            .started
            .get_or_insert_with(Instant::now)
            .elapsed()
            .as_secs_f64();
        self.frames += 1;
        if let Some(last) = self.last_seq
            && out.frame.seq > last.wrapping_add(1)
        {
            self.gaps += u64::from(out.frame.seq - last - 1);
        }
        self.last_seq = Some(out.frame.seq);
        self.arrivals.push_back(now);
        while self.arrivals.front().is_some_and(|&t| now - t > 1.0) {
            self.arrivals.pop_front();
        }
        push(&mut self.rate, (now, self.arrivals.len() as f64));
        if out.referencing.is_none() {
            push(&mut self.bvc, (f64::from(out.frame.t_us) * 1e-6, out.bvc));
        }
        if self
            .recent
            .front()
            .is_some_and(|f| f.len() != out.frame.voltages.len())
        {
            self.recent.clear();
        }
        self.recent.push_back(out.frame.voltages.clone());
        if self.recent.len() > Self::WINDOW {
            self.recent.pop_front();
        }
        let n = self.recent.len();
        if n >= 2 {
            let k = out.frame.voltages.len();
            self.snr_db = (0..k)
                .map(|i| {
                    let mean = self.recent.iter().map(|f| f64::from(f[i])).sum::<f64>() / n as f64;
                    let var = self
                        .recent
                        .iter()
                        .map(|f| (f64::from(f[i]) - mean).powi(2))
                        .sum::<f64>()
                        / (n - 1) as f64;
                    if var > 0.0 {
                        20.0 * (mean.abs() / var.sqrt()).log10()
                    } else {
                        f64::NAN
                    }
                })
                .collect();
        }
    }
}

fn push(q: &mut VecDeque<(f64, f64)>, p: (f64, f64)) {
    q.push_back(p);
    if q.len() > Monitor::HISTORY {
        q.pop_front();
    }
}

/// The protocols the live pipeline offers, plus automatic selection (SPEC §8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolChoice {
    /// One protocol.
    Fixed(ProtocolKind),
    /// `dynamic::Selector` picks from the regions.
    Automatic,
}

#[cfg(test)]
pub(crate) mod tests;
