//! The viewer (`et view`, cargo feature `viewer`): an eframe window over [`crate::live`].
//!
//! - Sources: the simulated sheet (press it with the mouse), a recording (pause, seek) or a
//!   board on a serial port (picked from a list); switched from the top bar.
//! - The live image with its colour bar and ROI outline, the true touches (simulator), the
//!   class grid with the recognised class lit and the continuous position marker.
//! - Protocol (AD, PP, PP-PP, opposite, automatic by docs/method.md §8), alpha and threshold.
//! - Plots of frame rate, BVC and per-channel SNR; link health.
//! - The training wizard ([`wizard`]): which cell to press next, scans and visits counted,
//!   training, cross-validated accuracy and confusion, the model to the board.
//!
//! All state lives in [`Viewer`], and [`Viewer::ui`] draws it into any `egui::Ui`, so the
//! tests drive the real interface headless with egui_kittest.

use std::path::PathBuf;

use eframe::egui::{
    self, Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, StrokeKind, TextureHandle,
    TextureOptions, Vec2, pos2, vec2,
};
use et_core::ScanConfig;
use et_core::protocol::ProtocolKind;
use et_sim::sheet::SheetSpec;
use et_sim::touch::Touch;

use crate::live::{
    Health, LiveError, Monitor, Output, Processor, ProtocolChoice, Settings, Source, SourceSpec,
    open_source,
};
use et_learn::{Model, ModelError};
use et_recon::PixelGrid;
use et_recon::select::{Selector, Settings as DynamicSettings};

mod controls;
mod plots;
mod protocol;
mod sheet_view;
mod status;
pub mod wizard;

pub use controls::SourceBar;
pub use plots::Plots;
pub use sheet_view::{Drawn, SheetView};
use sheet_view::{Press, Shown};

pub use status::StatusLog;
use wizard::Wizard;

/// How the viewer starts.
#[derive(Clone, Debug)]
pub struct Options {
    /// The scene to simulate, or the sheet of a recording or board (None: the default sheet).
    pub scene: Option<PathBuf>,
    /// The first source.
    pub source: SourceSpec,
    /// A trained model to classify with.
    pub model: Option<PathBuf>,
    /// The reconstruction to image with (switchable in the side panel).
    pub method: et_recon::Method,
    /// Untouched frames averaged into V_0 at the start and after a tare
    /// ([`Settings::reference_frames`]).
    pub reference_frames: usize,
    /// Simulate in real time (false: one frame per drawn frame, for tests).
    pub realtime: bool,
    /// For documentation: once V_0 is taken (and `press` is pressed), save the window as
    /// this PNG and close.
    pub screenshot: Option<PathBuf>,
    /// With `screenshot`: press the simulated sheet here (mm, a 7.5 mm fingertip at 30 kPa)
    /// once V_0 is taken. None presses nothing (a scene's own touches, a recording's frames).
    pub press: Option<[f64; 2]>,
    /// Electrodes whose values are left out of the images, 0-based ([`Processor::set_left_out`];
    /// the side panel changes them).
    pub left_out: Vec<u16>,
}

/// Which kind of source the top bar is set to.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SourceKind {
    /// The simulator.
    #[default]
    Sim,
    /// A recording.
    Replay,
    /// A board.
    Port,
}

/// The viewer's state.
pub struct Viewer {
    options: Options,
    /// The source frames come from (None after a failed open).
    pub source: Option<Source>,
    /// What `source` was opened from (a recording's path is one of the viewer's inputs).
    opened: SourceSpec,
    /// The sheet shown (the source's, or the scene's).
    pub sheet: SheetSpec,
    /// The live pipeline.
    pub processor: Processor,
    /// The top bar: which source to open.
    pub source_bar: SourceBar,
    /// The protocol chosen.
    pub protocol: ProtocolChoice,
    selector: Selector,
    /// Automatic selection: the protocols whose V_0 is still to take, in turn (empty once
    /// taken, and for a fixed protocol).
    round: Vec<ProtocolKind>,
    /// The configuration last sent to the source, until a frame of it arrives.
    asked: Option<ScanConfig>,
    /// The latest processed frame.
    pub last: Option<Output>,
    /// Frame rate, BVC, SNR.
    pub monitor: Monitor,
    /// The status line (what just happened, or what went wrong).
    pub status: String,
    /// What the status line said before, kept to read after the next message replaced it.
    pub said: StatusLog,
    /// The training wizard (open or not).
    pub wizard: Wizard,
    /// The electrodes named detached or broken, which the side panel offers to leave out
    /// (0-based; found when V_0 is taken, or in a frame after it).
    detached: Vec<u16>,
    /// Each electrode named off since V_0, followed until it is back.
    contacts: crate::live::Contacts,
    /// The board's frame flags said in the status, and those of the frames V_0 is being
    /// taken from (`et_core::wire::FLAG_*` bits, said once it is taken).
    flags_said: crate::live::FlagsSaid,
    v0_flags: u8,
    shot_frames: u32,
    /// How the screenshot went: None until it is taken, then its error, if any.
    shot: std::sync::Arc<std::sync::Mutex<Option<Result<(), ShotError>>>>,
    /// The central panel: the sheet, its image and touches.
    pub sheet_view: SheetView,
    /// The right panel: the signal's plots and the link's health.
    pub plots: Plots,
}

impl std::fmt::Debug for Viewer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Viewer")
            .field("source", &self.source.as_ref().map(Source::describe))
            .field("protocol", &self.protocol)
            .field("status", &self.status)
            .finish_non_exhaustive()
    }
}

fn protocol_label(choice: ProtocolChoice) -> &'static str {
    match choice {
        ProtocolChoice::Fixed(ProtocolKind::Adjacent) => "AD",
        ProtocolChoice::Fixed(ProtocolKind::PseudoPolar) => "PP",
        ProtocolChoice::Fixed(ProtocolKind::PpPp) => "PP-PP",
        ProtocolChoice::Fixed(ProtocolKind::Opposite) => "opposite",
        ProtocolChoice::Fixed(ProtocolKind::Custom(_)) => "custom",
        ProtocolChoice::Automatic => "automatic",
    }
}

impl Viewer {
    /// Opens the first source and builds the pipeline.
    ///
    /// # Errors
    /// [`ViewerError`] when the scene, the model or the first source cannot be opened.
    pub fn new(options: Options) -> Result<Self, ViewerError> {
        let (source, sheet) = open_source(&options.source, options.scene.as_deref())?;
        if let Some([x, y]) = options.press
            && !sheet.physical.shape.contains([x * 1e-3, y * 1e-3], 0.0)
        {
            return Err(ViewerError::Press([x, y]));
        }
        let mut processor = Processor::new(
            &sheet.physical,
            Settings {
                method: options.method,
                reference_frames: options.reference_frames,
                ..Settings::default()
            },
        )?;
        if let Some(path) = &options.model {
            let error = |error| ViewerError::Model {
                path: path.clone(),
                error,
            };
            let classifier = Model::load(path)?.into_board().map_err(error)?;
            (processor.set_classifier(classifier)).map_err(|e| error(e.into()))?;
        }
        processor.set_electrode_base(source.electrode_base());
        if !options.left_out.is_empty() {
            let left_out = processor.counted_from_zero(&options.left_out)?;
            (processor.set_left_out(&left_out, source.config())).map_err(|e| match e {
                LiveError::LeftOut(e) => ViewerError::LeftOut(e),
                other => other.into(),
            })?;
        }
        let b = sheet.physical.shape.bounds();
        let centre = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
        let selector = Selector::new(DynamicSettings::new(
            centre,
            sheet.physical.shape.distance_to_outline(centre),
        ));
        let mut viewer = Self {
            status: format!(
                "{}: keep the sheet untouched while V_0 is taken",
                source.describe()
            ),
            source: Some(source),
            opened: options.source.clone(),
            sheet,
            processor,
            source_bar: SourceBar::of(&options.source),
            protocol: ProtocolChoice::Fixed(ProtocolKind::Adjacent),
            selector,
            round: Vec::new(),
            asked: None,
            last: None,
            monitor: Monitor::default(),
            wizard: Wizard::default(),
            detached: Vec::new(),
            contacts: crate::live::Contacts::default(),
            said: StatusLog::default(),
            flags_said: crate::live::FlagsSaid::default(),
            v0_flags: 0,
            shot_frames: 0,
            shot: std::sync::Arc::default(),
            sheet_view: SheetView::default(),
            plots: Plots::default(),
            options,
        };
        if let Some(config) = viewer.source.as_ref().and_then(Source::config) {
            viewer.protocol = ProtocolChoice::Fixed(config.protocol);
        }
        if let Some(c) = &viewer.processor.classifier {
            let config = c.file().config;
            let _ = viewer.switch_config(config);
        }
        Ok(viewer)
    }

    /// Opens the source chosen in the top bar (the sheet stays the scene's).
    pub fn open_chosen_source(&mut self) {
        let bar = &self.source_bar;
        let spec = match bar.kind {
            SourceKind::Sim => SourceSpec::Sim,
            SourceKind::Replay => {
                if bar.replay_path.trim().is_empty() {
                    self.status =
                        "type the recording's path first (from et sim or et record)".into();
                    return;
                }
                SourceSpec::Replay(PathBuf::from(bar.replay_path.trim()))
            }
            SourceKind::Port => {
                if bar.port.is_empty() {
                    self.status = "pick a serial port first (refresh the list)".into();
                    return;
                }
                SourceSpec::Port(bar.port.clone(), et_core::board::BAUD)
            }
        };
        match open_source(&spec, self.options.scene.as_deref()) {
            Ok((source, sheet)) => {
                let mut dropped = None;
                if sheet != self.sheet {
                    match Processor::new(&sheet.physical, self.processor.settings()) {
                        Ok(mut p) => {
                            p.set_electrode_base(source.electrode_base());
                            // The model's classes are places on its own sheet: checked
                            // against the new one (it was moved over unchecked).
                            if let Some(c) = self.processor.classifier.take() {
                                dropped = p.set_classifier(c).err();
                            }
                            // The electrodes left out stay out where the new sheet has them.
                            let _ = p.set_left_out(self.processor.left_out(), source.config());
                            self.processor = p;
                            self.sheet = sheet;
                        }
                        Err(e) => {
                            self.status = e.to_string();
                            return;
                        }
                    }
                }
                self.status = format!(
                    "{}: keep the sheet untouched while V_0 is taken",
                    source.describe()
                );
                if let Some(e) = dropped {
                    self.status = format!("{}; the model is no longer used: {e}", self.status);
                }
                self.source = Some(source);
                self.opened = spec;
                self.processor.tare();
                self.round.clear();
                self.asked = None;
                self.monitor = Monitor::default();
                self.last = None;
                if let Some(config) = self.source.as_ref().and_then(Source::config) {
                    self.protocol = ProtocolChoice::Fixed(config.protocol);
                }
            }
            Err(e) => self.status = e.to_string(),
        }
    }

    /// Takes the frames the source has and runs them through the pipeline (the wizard and
    /// automatic protocol selection see each one).
    pub fn pump(&mut self) {
        let Some(source) = self.source.as_mut() else {
            return;
        };
        let frames = match source.poll(16, self.options.realtime) {
            Ok(f) => f,
            Err(e) => {
                self.status = e.to_string();
                return;
            }
        };
        for frame in frames {
            match self.processor.process(frame) {
                Ok(out) => {
                    self.monitor.add(&out);
                    let was_referencing =
                        self.last.as_ref().is_none_or(|o| o.referencing.is_some());
                    if was_referencing && out.referencing.is_none() {
                        self.status = self.reference_taken();
                    }
                    self.board_flagged(&out);
                    self.electrode_contact(&out);
                    for request in self.wizard.observe(&out, &self.processor) {
                        self.apply_wizard_request(request);
                    }
                    self.follow_the_scan(&out);
                    self.select_automatically(&out);
                    self.last = Some(out);
                }
                Err(e) => self.status = format!("frame skipped: {e}"),
            }
        }
    }

    fn apply_wizard_request(&mut self, request: wizard::Request) {
        match request {
            wizard::Request::Configure(config) => {
                // The wizard's frames are of its one scan: selection would switch it away.
                self.protocol = ProtocolChoice::Fixed(config.protocol);
                self.round.clear();
                // A source that refuses the scan sends none of its frames: the wizard would
                // wait for them without end.
                if !self.switch_config(config) {
                    self.wizard.step = wizard::Step::Setup;
                    self.wizard.message = format!(
                        "the wizard scans {}, which the source refused: {}",
                        config.protocol.name(),
                        self.status
                    );
                } else if let Some(said) = self.trains_on_detached() {
                    self.status = said;
                }
            }
            wizard::Request::Press(touches) => self.press(touches),
            wizard::Request::UseModel(board) => {
                // Trained, hence checked as the board checks a model (`Board::new`).
                self.processor.classifier = Some(*board);
                self.status = "the trained model now classifies each touch".into();
            }
            wizard::Request::Upload(blob) => {
                self.status = match self.source.as_mut() {
                    Some(Source::Port(p)) => {
                        p.install_model(&blob).unwrap_or_else(|e| e.to_string())
                    }
                    _ => "export to a board needs a board: open its serial port first".into(),
                };
            }
            wizard::Request::Save => {
                let inputs = self.inputs();
                self.wizard.message = self.wizard.save(&inputs);
            }
        }
    }

    /// The files the viewer reads, which the wizard's Save never replaces: the scene, the
    /// files it names (its protocol file), the recording played and the model given.
    fn inputs(&self) -> Vec<PathBuf> {
        let scene = self.options.scene.as_ref();
        let mut inputs: Vec<PathBuf> = (scene.into_iter())
            .chain(&self.options.model)
            .cloned()
            .collect();
        if let Some(scene) = scene.and_then(|s| et_sim::scene::Scene::load(s).ok()) {
            inputs.extend(scene.files());
        }
        if let SourceSpec::Replay(path) = &self.opened {
            inputs.push(path.clone());
        }
        inputs
    }

    /// Presses the simulated sheet (nothing for other sources).
    pub fn press(&mut self, touches: Vec<Touch>) {
        if let Some(Source::Sim(s)) = self.source.as_mut() {
            s.press(touches);
        }
    }

    /// The viewer's whole interface.
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        self.pump();
        egui::Panel::top("source").show(ui, |ui| {
            let described = self
                .source
                .as_ref()
                .map_or("no source".into(), Source::describe);
            if self.source_bar.show(ui, &described, &mut self.status) {
                self.open_chosen_source();
            }
        });
        egui::Panel::bottom("status").show(ui, |ui| self.show_status(ui));
        // Scrolled: a window lower than the controls (a recording's Replay section, the
        // wizard's steps) would cut the last ones off.
        egui::Panel::left("controls")
            .resizable(false)
            .show(ui, |ui| {
                egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
            });
        egui::Panel::right("plots").resizable(false).show(ui, |ui| {
            self.plots.show(ui, &self.monitor, self.source.as_ref());
        });
        egui::CentralPanel::default().show(ui, |ui| {
            let shown = Shown {
                grid: self.processor.grid(),
                sigma0: self.processor.imager().sigma0,
                last: self.last.as_ref(),
                sheet: &self.sheet.physical,
                class_centres: (self.processor.classifier.as_ref())
                    .map(|c| c.file().centres.as_slice()),
                electrode_base: self.processor.electrode_base(),
                pressable: matches!(self.source, Some(Source::Sim(_))),
                hint: self.options.screenshot.is_none(),
            };
            match self.sheet_view.show(ui, &shown) {
                Press::At(position) => self.press(vec![Touch {
                    position,
                    radius: 0.0075,
                    pressure: 20e3,
                    footprint: Default::default(),
                }]),
                Press::Released => self.press(Vec::new()),
                Press::Nothing => {}
            }
        });
        if self.wizard.open {
            let mut open = true;
            let mut requests = Vec::new();
            egui::Window::new("Training wizard")
                .open(&mut open)
                .default_width(360.0)
                .show(ui.ctx(), |ui| {
                    requests = self.wizard.ui(ui, self.source.as_ref(), &self.sheet);
                });
            self.wizard.open = open;
            for r in requests {
                self.apply_wizard_request(r);
            }
        }
        self.screenshot(ui.ctx());
        if self
            .source
            .as_ref()
            .is_some_and(|s| !matches!(s, Source::Replay(r) if r.paused))
        {
            ui.ctx().request_repaint();
        }
    }

    fn screenshot(&mut self, ctx: &egui::Context) {
        let Some(path) = self.options.screenshot.clone() else {
            return;
        };
        if self.last.as_ref().is_none_or(|o| o.referencing.is_some()) {
            return;
        }
        self.shot_frames += 1;
        if self.shot_frames == 5
            && let Some([x, y]) = self.options.press
        {
            self.press(vec![Touch {
                position: [x * 1e-3, y * 1e-3],
                radius: 0.0075,
                pressure: 30e3,
                footprint: Default::default(),
            }]);
        }
        if self.shot_frames == 80 {
            let close = ctx.clone();
            let shot = std::sync::Arc::clone(&self.shot);
            ctx.request_screenshot(move |img| {
                let [w, h] = img.size;
                let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
                let saved = crate::output::write(&path, |partial| {
                    crate::plot::write_png(partial, &bytes, (w as u32, h as u32), true)
                        .map_err(ShotError::from)
                });
                if saved.is_ok() {
                    let _ = std::io::Write::write_fmt(
                        &mut std::io::stderr(),
                        format_args!("wrote {}\n", path.display()),
                    );
                }
                *shot
                    .lock()
                    .unwrap_or_else(std::sync::PoisonError::into_inner) = Some(saved);
                close.send_viewport_cmd(egui::ViewportCommand::Close);
            });
        }
    }
}

impl eframe::App for Viewer {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        Viewer::ui(self, ui);
    }
}

/// Opens the window and runs until it is closed.
///
/// # Errors
/// [`ViewerError`] when the sources cannot be opened or the window cannot be created (no
/// display, no OpenGL).
pub fn run(options: Options) -> Result<(), ViewerError> {
    let viewer = Viewer::new(options)?;
    let shot = (viewer.options.screenshot.as_ref()).map(|_| std::sync::Arc::clone(&viewer.shot));
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(Vec2::new(1280.0, 780.0))
            .with_title("et view"),
        ..Default::default()
    };
    eframe::run_native("et view", native, Box::new(|_cc| Ok(Box::new(viewer))))
        .map_err(|e| ViewerError::Window(window_said(&e.to_string())))?;
    match shot.map(|s| s.lock().map(|mut s| s.take()).unwrap_or(None)) {
        None | Some(Some(Ok(()))) => Ok(()),
        Some(Some(Err(e))) => Err(ViewerError::Screenshot(e)),
        Some(None) => Err(ViewerError::NoScreenshot),
    }
}

/// Why the viewer could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ViewerError {
    /// The scene, recording or port could not be opened, or the sheet not modelled.
    #[error(transparent)]
    Live(#[from] LiveError),
    /// The model file could not be read or is not a usable model (the error names it).
    #[error(transparent)]
    Load(#[from] ModelError),
    /// The model is a table's model, which cannot classify the board's frames.
    #[error("{}: {error}", .path.display())]
    Model {
        /// The file.
        path: PathBuf,
        /// Why.
        error: ModelError,
    },
    /// Electrodes that cannot be left out (past the sheet's, or more than half of them).
    #[error("--skip-electrodes: {0}")]
    LeftOut(et_core::schedule::ScheduleError),
    /// `press` is not on the sheet.
    #[error("--press {},{} mm is not on the sheet (give a point inside it, in the scene's coordinates)", .0[0], .0[1])]
    Press([f64; 2]),
    /// The window could not be created: eframe's error as its text (eframe's error type is
    /// neither `Send` nor `Sync`, so it cannot travel inside this one).
    #[error("cannot open the window: {0} (is there a display? try DISPLAY=:0 or xvfb-run)")]
    Window(String),
    /// The screenshot was not written.
    #[error("screenshot not written: {0}")]
    Screenshot(#[source] ShotError),
    /// The window closed before the screenshot was taken.
    #[error("screenshot not written: the window closed before the screenshot was taken")]
    NoScreenshot,
}

/// eframe's error without winit's type and source place ("winit EventLoopError: os error at
/// /root/.cargo/registry/.../mod.rs:765: neither WAYLAND_DISPLAY nor ... is set.").
#[must_use]
pub fn window_said(error: &str) -> String {
    let said = error
        .strip_prefix("winit EventLoopError: ")
        .unwrap_or(error);
    let said = match said
        .strip_prefix("os error at ")
        .and_then(|r| r.split_once(".rs:"))
    {
        Some((_, rest)) => rest.split_once(": ").map_or(rest, |(_, why)| why),
        None => said,
    };
    said.trim_end_matches('.').to_string()
}

/// Why a screenshot's file was not written (the PNG encoder's or the output's error).
pub type ShotError = Box<dyn std::error::Error + Send + Sync>;
