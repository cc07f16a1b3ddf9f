//! Where frames come from: the simulator (which a pointer can press), a recording (replay with
//! pause and seek) or a board on a serial port.

use super::*;

/// The default sheet of the simulator and of boards whose sheet is not given: 13 x 13 cm, 16
/// electrodes (docs/method.md §1).
///
/// # Errors
/// Never for the compiled-in scene ([`SceneError`] otherwise).
pub fn default_scene() -> Result<Scene, SceneError> {
    let (name, text) = crate::demo::DEFAULT_SCENE;
    Scene::parse(text, name)
}

/// A simulated scene, running in real time, that a pointer can press.
#[derive(Debug)]
pub struct SimSource {
    /// The scene's name.
    pub name: String,
    /// The number of its first electrode as its user counts them (its protocol file's base).
    pub electrode_base: u16,
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
    /// [`SceneError`] if the sheet cannot be built.
    pub fn new(scene: &Scene, name: impl Into<String>) -> Result<Self, SceneError> {
        let mut run = Run::new(scene)?;
        run.hold_scene(true);
        Ok(Self {
            name: name.into(),
            electrode_base: scene.electrode_base(),
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
    /// [`SceneError`] if the simulation fails.
    pub fn next_frame(&mut self) -> Result<LiveFrame, SceneError> {
        if self.produced == Self::LEAD_FRAMES {
            self.run.hold_scene(false);
        }
        let (frame, truth) = self.run.next_frame(Detail::Frames)?;
        self.produced += 1;
        Ok(LiveFrame {
            seq: frame.seq,
            t_us: frame.timestamp.0,
            config: frame.config,
            flags: frame.flags,
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
    /// The number of its first electrode as its user counts them: 0 for a recording (et's),
    /// the scene's protocol file's base for another system's frames.
    pub electrode_base: u16,
}

impl ReplaySource {
    /// Reads `path`; `sheet` is the sheet it was recorded on.
    ///
    /// # Errors
    /// [`LiveError::Recording`] naming the file, [`LiveError::OtherSheet`] when its frames
    /// are of another electrode count than `sheet`.
    pub fn open(path: &Path, sheet: SheetSpec) -> Result<Self, LiveError> {
        let recording = recording::read(path)?;
        if recording.header.electrodes != sheet.physical.electrodes.count {
            return Err(LiveError::OtherSheet {
                path: path.into(),
                recorded: recording.header.electrodes,
                sheet: sheet.physical.electrodes.count,
            });
        }
        Ok(Self {
            name: path.display().to_string(),
            recording,
            sheet,
            position: 0,
            paused: false,
            looping: true,
            electrode_base: 0,
        })
    }

    /// Another system's frames (a CSV, .npy, .npz or .mat of frames in volts,
    /// [`crate::frames`]) played as a recording of `scene`'s built-in protocol (or the one its
    /// protocol file's rows are) and current
    /// (`scene_name`, its file as the user named it, for messages). A current above the
    /// board's 1 mA plays as 1 mA, the frames scaled to it ([`Scene::replay_config`]) and
    /// the source's name saying so.
    ///
    /// # Errors
    /// [`LiveError::Table`] for a scene whose protocol is a file of rows no built-in
    /// protocol's (the live pipeline scans et's built-in protocols; `et reconstruct --frames`
    /// images any), [`LiveError::Frames`] naming the file.
    pub fn open_table(path: &Path, scene: &Scene, scene_name: &str) -> Result<Self, LiveError> {
        let (config, scale) = scene.replay_config().map_err(|error| LiveError::Table {
            scene: scene_name.into(),
            frames: path.into(),
            error,
        })?;
        let header = recording::Header::new(format!("file:{}", path.display()), &config)?;
        let frames = crate::frames::read(path, header.frame_len)?;
        let records = frames
            .frames
            .into_iter()
            .enumerate()
            .map(|(i, mut voltages)| {
                if scale != 1.0 {
                    voltages
                        .iter_mut()
                        .for_each(|v| *v = (f64::from(*v) * scale) as f32);
                }
                // (A value missing, NaN, is one the board did not send: the frame is
                // skipped and said when played, as a recording's.)
                let invalid = recording::invalid_columns(&voltages);
                recording::Record {
                    seq: u32::try_from(i).unwrap_or(u32::MAX),
                    t_us: 0,
                    flags: 0,
                    rail_count: 0,
                    voltages,
                    invalid,
                    touches: None,
                }
            })
            .collect();
        let mut name = frames.description;
        let played_ua = f64::from(config.current_na) / 1e3;
        // (Streamed electrodes are the board's, from 0, whatever the file counts from.)
        name += &scene.file_said().unwrap_or_default();
        if scale != 1.0 {
            name += &format!(
                " (driven at {} uA, played as the board's {played_ua} uA: its volts times \
                 {scale:.4}, the same images, positions and intensities)",
                played_ua / scale,
            );
        }
        Ok(Self {
            name,
            recording: Recording {
                header,
                records,
                truncated_tail: false,
            },
            sheet: scene.sheet.clone(),
            position: 0,
            paused: false,
            looping: true,
            electrode_base: scene.electrode_base(),
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
            flags: r.flags,
            voltages: r.voltages.clone(),
            truth: r.touches.as_ref().map(|ts| {
                ts.iter()
                    .map(|t| Touch {
                        position: [t.x, t.y],
                        radius: t.radius,
                        pressure: t.pressure,
                        footprint: Default::default(),
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
    /// Watches the port and restarts a board that comes back idle.
    keepalive: Keepalive,
    /// Link changes not yet taken by [`Source::link_changes`].
    changes: Vec<LinkChange>,
    /// The board's reports not yet taken by [`Source::board_reports`].
    reports: Vec<String>,
}

/// The board's reports a [`PortSource`] keeps until they are taken.
const REPORTS_KEPT: usize = 64;

impl PortSource {
    /// Opens `path` and starts the scan.
    ///
    /// # Errors
    /// [`LiveError::Link`] if the port cannot be opened or the board does not answer.
    pub fn open(path: &str, baud: u32) -> Result<Self, LiveError> {
        let at = |error| LiveError::Link {
            port: path.to_string(),
            error,
        };
        let mut link = Link::open(path, baud).map_err(at)?;
        link.request(&Command::Start, Duration::from_secs(2))
            .map_err(|error| match error {
                LinkError::Timeout { .. } => LiveError::Silent {
                    port: path.to_string(),
                    baud,
                    error,
                },
                error => at(error),
            })?;
        let keepalive = Keepalive::new(&link, true);
        Ok(Self {
            path: path.to_string(),
            link,
            status: None,
            last_problem: None,
            pending: VecDeque::new(),
            keepalive,
            changes: Vec::new(),
            reports: Vec::new(),
        })
    }

    /// Puts a model on the board: uploads `blob` (the board verifies it before it replaces
    /// its model; erasing a slot takes seconds) and, for a referenced model, has the board
    /// take V_0 from its next frames, so the sheet must be untouched. Returns what happened,
    /// for people.
    ///
    /// # Errors
    /// [`LiveError::Blob`] when the blob is not a model, [`LiveError::Link`] when the board
    /// refuses or does not answer (it then keeps its old model), [`LiveError::Tare`] when it
    /// loaded the model but could not take V_0.
    pub fn install_model(&mut self, blob: &[u8]) -> Result<String, LiveError> {
        let model = et_core::model::Model::parse(blob).map_err(LiveError::Blob)?;
        self.link
            .upload_model(blob, Duration::from_secs(2), Duration::from_secs(15))
            .map_err(|error| LiveError::Link {
                port: self.path.clone(),
                error,
            })?;
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
            .map_err(LiveError::Tare)?;
        Ok(format!("{loaded} and took V_0: it classifies every frame"))
    }

    /// Everything that arrived, without waiting: frames (each with its on-chip class when
    /// the board sent one), and status and problems kept for [`Source::health`].
    fn drain(&mut self) -> Vec<LiveFrame> {
        if let Some(change) = self.keepalive.check(&self.link) {
            self.last_problem = Some(format!("{}: {change}", self.path));
            self.changes.push(change);
        }
        let before = self.pending.len();
        while let Ok(m) = self.link.next(Duration::ZERO) {
            match m {
                Uplink::Frame(f) => self.pending.push_back(LiveFrame::from(f)),
                Uplink::Event(Event::Touch { seq, class, margin }) => {
                    if let Some(f) = self.pending.iter_mut().find(|f| f.seq == seq) {
                        f.chip_class = Some(ChipClass { class, margin });
                    }
                }
                Uplink::Event(Event::Status(s)) => self.status = Some(s),
                Uplink::Event(e) => {
                    if let Some(report) = super::board_report(&e) {
                        // Bounded for a caller that never takes them (the viewer shows the
                        // last): a fault each frame would grow it without end.
                        if self.reports.len() < REPORTS_KEPT {
                            self.reports.push(report.clone());
                        }
                        self.last_problem = Some(report);
                    }
                }
            }
        }
        if self.pending.len() > before {
            self.keepalive.frame();
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
    /// The number of the first electrode as the source's user counts them, in what is said
    /// of electrodes: a scene's protocol file's base (1 for a file counting from 1), else 0
    /// (et's and the board's numbering).
    #[must_use]
    pub fn electrode_base(&self) -> u16 {
        match self {
            Source::Sim(s) => s.electrode_base,
            Source::Replay(r) => r.electrode_base,
            Source::Port(_) => 0,
        }
    }

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
    /// [`SceneError`] when the simulator fails.
    pub fn poll(&mut self, max: usize, realtime: bool) -> Result<Vec<LiveFrame>, SceneError> {
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

    /// Whether the source can scan another configuration (the simulator and a board; a
    /// recording plays the one it was recorded with, [`Source::configure`]).
    #[must_use]
    pub fn switches_scan(&self) -> bool {
        !matches!(self, Source::Replay(_))
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

    /// Switches the scan to `config` (a board is sent `Configure`, and again when it comes
    /// back from a reset or a pulled cable). A recording cannot change what it recorded.
    ///
    /// # Errors
    /// [`LiveError`] saying why not.
    pub fn configure(&mut self, config: ScanConfig) -> Result<(), LiveError> {
        match self {
            Source::Sim(s) => Ok(s.run.set_config(config)?),
            Source::Replay(r) if r.recording.header.config == config => Ok(()),
            Source::Replay(_) => Err(LiveError::Recorded),
            Source::Port(p) => {
                (p.link)
                    .request(&Command::Configure(config), Duration::from_secs(2))
                    .map_err(|error| LiveError::Link {
                        port: p.path.clone(),
                        error,
                    })?;
                // A board that restarts (a reset, a power cycle) is asked for it again.
                p.keepalive.keep_scan(config);
                Ok(())
            }
        }
    }

    /// What changed on a board's link since the last call (the port vanished, came back, a
    /// silent board was restarted); nothing for a simulator or a file.
    pub fn link_changes(&mut self) -> Vec<LinkChange> {
        match self {
            Source::Port(p) => std::mem::take(&mut p.changes),
            _ => Vec::new(),
        }
    }

    /// What a board reported since the last call ([`board_report`](super::board_report): its
    /// faults and refusals, in words); nothing for a simulator or a file.
    pub fn board_reports(&mut self) -> Vec<String> {
        match self {
            Source::Port(p) => std::mem::take(&mut p.reports),
            _ => Vec::new(),
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
/// until something presses it; another system's frames need theirs). Returns the source and
/// the sheet.
///
/// # Errors
/// [`LiveError`] naming the file or port; [`LiveError::NoScene`] for another system's frames
/// without a scene.
pub fn open_source(
    spec: &SourceSpec,
    scene: Option<&Path>,
) -> Result<(Source, SheetSpec), LiveError> {
    if let (SourceSpec::Replay(path), None) = (spec, scene)
        && crate::frames::reads_as_table(path)
    {
        return Err(LiveError::NoScene(path.clone()));
    }
    let (scene, name) = match scene {
        Some(p) => (Scene::load(p)?, p.display().to_string()),
        None => {
            let mut scene = default_scene()?;
            scene.touches.clear();
            (scene, crate::demo::DEFAULT_SCENE.0.to_string())
        }
    };
    let sheet = scene.sheet.clone();
    let source = match spec {
        SourceSpec::Sim => Source::Sim(Box::new(SimSource::new(&scene, name)?)),
        SourceSpec::Replay(path) if crate::frames::reads_as_table(path) => {
            Source::Replay(Box::new(ReplaySource::open_table(path, &scene, &name)?))
        }
        SourceSpec::Replay(path) => {
            Source::Replay(Box::new(ReplaySource::open(path, sheet.clone())?))
        }
        SourceSpec::Port(path, baud) => Source::Port(Box::new(PortSource::open(path, *baud)?)),
    };
    Ok((source, sheet))
}
