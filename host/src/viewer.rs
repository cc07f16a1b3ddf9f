//! The viewer (`et view`, cargo feature `viewer`): an eframe window over [`crate::live`].
//!
//! - Sources: the simulated sheet (press it with the mouse), a recording (pause, seek) or a
//!   board on a serial port (picked from a list); switched from the top bar.
//! - The live image with its colour bar and ROI outline, the true touches (simulator), the
//!   class grid with the recognised class lit and the continuous position marker.
//! - Protocol (AD, PP, PP-PP, opposite, automatic by SPEC §8), alpha and threshold.
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

use crate::dynamic::{Selector, Settings as DynamicSettings};
use crate::learn::model_file::ModelFile;
use crate::live::{
    Classifier, Health, Monitor, Output, Processor, ProtocolChoice, Settings, Source, SourceSpec,
    open_source,
};

pub mod wizard;

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
    /// Simulate in real time (false: one frame per drawn frame, for tests).
    pub realtime: bool,
    /// For documentation: once V_0 is taken, press the simulated sheet at (30, 25) mm, save
    /// the window as this PNG a second later, and close.
    pub screenshot: Option<PathBuf>,
}

/// Which kind of source the top bar is set to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SourceKind {
    /// The simulator.
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
    sheet: SheetSpec,
    /// The live pipeline.
    pub processor: Processor,
    /// The source kind chosen in the top bar.
    pub source_kind: SourceKind,
    /// The recording path typed in the top bar.
    pub replay_path: String,
    /// The serial port chosen in the top bar.
    pub port: String,
    ports: Vec<String>,
    /// The protocol chosen.
    pub protocol: ProtocolChoice,
    selector: Selector,
    /// The latest processed frame.
    pub last: Option<Output>,
    /// Frame rate, BVC, SNR.
    pub monitor: Monitor,
    texture: Option<TextureHandle>,
    /// The status line (what just happened, or what went wrong).
    pub status: String,
    /// The training wizard (open or not).
    pub wizard: Wizard,
    pressing: bool,
    shot_frames: u32,
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
    /// A message when the scene, the model or the first source cannot be opened.
    pub fn new(options: Options) -> Result<Self, String> {
        let (source, sheet) = open_source(&options.source, options.scene.as_deref())?;
        let mut processor = Processor::new(&sheet, Settings::default())?;
        if let Some(path) = &options.model {
            let file = ModelFile::load(path)?;
            processor.classifier = Some(Classifier::new(file)?);
        }
        let source_kind = match &options.source {
            SourceSpec::Sim => SourceKind::Sim,
            SourceSpec::Replay(_) => SourceKind::Replay,
            SourceSpec::Port(..) => SourceKind::Port,
        };
        let replay_path = match &options.source {
            SourceSpec::Replay(p) => p.display().to_string(),
            _ => String::new(),
        };
        let port = match &options.source {
            SourceSpec::Port(p, _) => p.clone(),
            _ => String::new(),
        };
        let b = sheet.shape.bounds();
        let centre = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
        let selector = Selector::new(DynamicSettings::new(
            centre,
            sheet.shape.distance_to_outline(centre),
        ));
        let mut viewer = Self {
            status: format!(
                "{}: keep the sheet untouched while V_0 is taken",
                source.describe()
            ),
            source: Some(source),
            sheet,
            processor,
            source_kind,
            replay_path,
            port,
            ports: Vec::new(),
            protocol: ProtocolChoice::Fixed(ProtocolKind::Adjacent),
            selector,
            last: None,
            monitor: Monitor::default(),
            texture: None,
            wizard: Wizard::default(),
            pressing: false,
            shot_frames: 0,
            options,
        };
        if let Some(config) = viewer.source.as_ref().and_then(Source::config) {
            viewer.protocol = ProtocolChoice::Fixed(config.protocol);
        }
        if let Some(c) = &viewer.processor.classifier {
            let config = c.file.config;
            viewer.switch_config(config);
        }
        Ok(viewer)
    }

    /// Opens the source chosen in the top bar (the sheet stays the scene's).
    pub fn open_chosen_source(&mut self) {
        let spec = match self.source_kind {
            SourceKind::Sim => SourceSpec::Sim,
            SourceKind::Replay => {
                if self.replay_path.trim().is_empty() {
                    self.status =
                        "type the recording's path first (from et sim or et record)".into();
                    return;
                }
                SourceSpec::Replay(PathBuf::from(self.replay_path.trim()))
            }
            SourceKind::Port => {
                if self.port.is_empty() {
                    self.status = "pick a serial port first (refresh the list)".into();
                    return;
                }
                SourceSpec::Port(self.port.clone(), crate::link::DEFAULT_BAUD)
            }
        };
        match open_source(&spec, self.options.scene.as_deref()) {
            Ok((source, sheet)) => {
                if sheet != self.sheet {
                    match Processor::new(&sheet, self.processor.settings()) {
                        Ok(mut p) => {
                            p.classifier = self.processor.classifier.take();
                            self.processor = p;
                            self.sheet = sheet;
                        }
                        Err(e) => {
                            self.status = e;
                            return;
                        }
                    }
                }
                self.status = format!(
                    "{}: keep the sheet untouched while V_0 is taken",
                    source.describe()
                );
                self.source = Some(source);
                self.processor.tare();
                self.monitor = Monitor::default();
                self.last = None;
                if let Some(config) = self.source.as_ref().and_then(Source::config) {
                    self.protocol = ProtocolChoice::Fixed(config.protocol);
                }
            }
            Err(e) => self.status = e,
        }
    }

    /// Scans with `config` from now on (the source is told; V_0 is taken anew).
    pub fn switch_config(&mut self, config: ScanConfig) {
        let Some(source) = self.source.as_mut() else {
            return;
        };
        match source.configure(config) {
            Ok(()) => {
                self.processor.tare();
                if self.protocol != ProtocolChoice::Automatic {
                    self.protocol = ProtocolChoice::Fixed(config.protocol);
                }
                self.status = format!(
                    "scanning {}: keep the sheet untouched while V_0 is taken",
                    config.protocol.name()
                );
            }
            Err(e) => self.status = e,
        }
    }

    /// Chooses a protocol (automatic starts on adjacent and follows SPEC §8).
    pub fn choose_protocol(&mut self, choice: ProtocolChoice) {
        self.protocol = choice;
        let kind = match choice {
            ProtocolChoice::Fixed(k) => k,
            ProtocolChoice::Automatic => {
                self.selector = Selector::new(*self.selector_settings());
                ProtocolKind::Adjacent
            }
        };
        if let Some(config) = self.source.as_ref().and_then(Source::config)
            && config.protocol != kind
        {
            self.switch_config(ScanConfig {
                protocol: kind,
                ..config
            });
        }
    }

    fn selector_settings(&self) -> &DynamicSettings {
        self.selector.settings()
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
                self.status = e;
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
                        self.status = match self.source.as_ref() {
                            Some(Source::Sim(_)) => {
                                "V_0 taken: press and hold the mouse on the sheet".into()
                            }
                            _ => "V_0 taken: touches show on the sheet".into(),
                        };
                    }
                    for request in self.wizard.observe(&out, &self.processor) {
                        self.apply_wizard_request(request);
                    }
                    if self.protocol == ProtocolChoice::Automatic && out.referencing.is_none() {
                        let regions = if out.event.is_some() {
                            out.regions.clone()
                        } else {
                            Vec::new()
                        };
                        if let Some(kind) = self.selector.step(&regions)
                            && let Some(config) = self.source.as_ref().and_then(Source::config)
                        {
                            self.switch_config(ScanConfig {
                                protocol: kind,
                                ..config
                            });
                        }
                    }
                    self.last = Some(out);
                }
                Err(e) => self.status = format!("frame skipped: {e}"),
            }
        }
    }

    fn apply_wizard_request(&mut self, request: wizard::Request) {
        match request {
            wizard::Request::Configure(config) => self.switch_config(config),
            wizard::Request::Press(touches) => self.press(touches),
            wizard::Request::UseModel(file) => match Classifier::new(*file) {
                Ok(c) => {
                    self.processor.classifier = Some(c);
                    self.status = "the trained model now classifies each touch".into();
                }
                Err(e) => self.status = e,
            },
            wizard::Request::Upload(blob) => {
                self.status = match self.source.as_mut() {
                    Some(Source::Port(p)) => p.install_model(&blob).unwrap_or_else(|e| e),
                    _ => "export to a board needs a board: open its serial port first".into(),
                };
            }
        }
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
        egui::Panel::top("source").show(ui, |ui| self.source_bar(ui));
        egui::Panel::bottom("status").show(ui, |ui| {
            ui.label(&self.status);
        });
        egui::Panel::left("controls")
            .resizable(false)
            .show(ui, |ui| self.controls(ui));
        egui::Panel::right("plots")
            .resizable(false)
            .show(ui, |ui| self.plots(ui));
        egui::CentralPanel::default().show(ui, |ui| self.sheet_view(ui));
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
        if self.shot_frames == 5 {
            self.press(vec![Touch {
                position: [0.03, 0.025],
                radius: 0.0075,
                pressure: 30e3,
            }]);
        }
        if self.shot_frames == 80 {
            let close = ctx.clone();
            ctx.request_screenshot(move |img| {
                let [w, h] = img.size;
                let bytes: Vec<u8> = img.pixels.iter().flat_map(|c| c.to_array()).collect();
                match image::RgbaImage::from_raw(w as u32, h as u32, bytes)
                    .ok_or_else(|| "bad screenshot size".to_string())
                    .and_then(|i| i.save(&path).map_err(|e| e.to_string()))
                {
                    Ok(()) => eprintln!("wrote {}", path.display()),
                    Err(e) => eprintln!("screenshot {}: {e}", path.display()),
                }
                close.send_viewport_cmd(egui::ViewportCommand::Close);
            });
        }
    }

    fn source_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            ui.label("Source:");
            ui.selectable_value(&mut self.source_kind, SourceKind::Sim, "Simulated sheet");
            ui.selectable_value(&mut self.source_kind, SourceKind::Replay, "Recording");
            ui.selectable_value(&mut self.source_kind, SourceKind::Port, "Board");
            match self.source_kind {
                SourceKind::Sim => {}
                SourceKind::Replay => {
                    ui.label("File:");
                    ui.add(
                        egui::TextEdit::singleline(&mut self.replay_path)
                            .hint_text("session.jsonl"),
                    );
                }
                SourceKind::Port => {
                    egui::ComboBox::from_label("Port")
                        .selected_text(if self.port.is_empty() {
                            "(none)"
                        } else {
                            &self.port
                        })
                        .show_ui(ui, |ui| {
                            for p in &self.ports {
                                ui.selectable_value(&mut self.port, p.clone(), p);
                            }
                        });
                    if ui.button("Refresh").clicked() {
                        match crate::link::list_ports() {
                            Ok(p) => {
                                self.status = format!("{} serial ports", p.len());
                                self.ports = p;
                            }
                            Err(e) => self.status = format!("cannot list serial ports: {e}"),
                        }
                    }
                }
            }
            if ui.button("Open").clicked() {
                self.open_chosen_source();
            }
            ui.separator();
            ui.label(
                self.source
                    .as_ref()
                    .map_or("no source".into(), Source::describe),
            );
        });
    }

    fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Protocol");
        let mut choice = self.protocol;
        ui.horizontal_wrapped(|ui| {
            for c in [
                ProtocolChoice::Fixed(ProtocolKind::Adjacent),
                ProtocolChoice::Fixed(ProtocolKind::PseudoPolar),
                ProtocolChoice::Fixed(ProtocolKind::PpPp),
                ProtocolChoice::Fixed(ProtocolKind::Opposite),
                ProtocolChoice::Automatic,
            ] {
                ui.selectable_value(&mut choice, c, protocol_label(c));
            }
        });
        if choice != self.protocol {
            self.choose_protocol(choice);
        }
        if let Some(config) = self.source.as_ref().and_then(Source::config) {
            ui.label(format!("scanning: {}", config.protocol.name()));
        }
        ui.separator();
        ui.heading("Imaging");
        let mut s = self.processor.settings();
        ui.add(
            egui::Slider::new(&mut s.alpha, 1e-3..=10.0)
                .logarithmic(true)
                .text("alpha"),
        );
        let mut auto = s.threshold.is_none();
        ui.checkbox(&mut auto, "threshold per protocol (SPEC §6)");
        let mut f = s
            .threshold
            .unwrap_or(self.last.as_ref().map_or(0.1, |o| o.threshold));
        ui.add_enabled(
            !auto,
            egui::Slider::new(&mut f, 0.01..=0.9).text("threshold f"),
        );
        s.threshold = (!auto).then_some(f);
        ui.add(egui::Slider::new(&mut s.touch_factor, 2.0..=20.0).text("touch at z >"));
        if s != self.processor.settings() {
            self.processor.set_settings(s);
        }
        if ui.button("Tare (sheet untouched)").clicked() {
            self.processor.tare();
            self.status = "taking V_0: keep the sheet untouched".into();
        }
        if let Some(Source::Replay(r)) = self.source.as_mut() {
            ui.separator();
            ui.heading("Replay");
            let label = if r.paused { "Play" } else { "Pause" };
            if ui.button(label).clicked() {
                r.paused = !r.paused;
            }
            let mut at = r.position;
            let last = r.len().saturating_sub(1);
            if ui
                .add(egui::Slider::new(&mut at, 0..=last).text("frame"))
                .changed()
            {
                r.seek(at);
            }
            ui.checkbox(&mut r.looping, "loop");
        }
        ui.separator();
        ui.heading("Touch");
        match self.last.as_ref().and_then(|o| o.event.as_ref()) {
            Some(e) => {
                ui.label(format!(
                    "at ({:.0}, {:.0}) mm",
                    e.position_mm[0], e.position_mm[1]
                ));
                ui.label(format!("intensity z = {:.1}", e.intensity));
                if let Some(c) = e.class {
                    ui.label(format!("class {c}"));
                }
                if let Some(p) = e.confidence {
                    ui.label(format!("confidence {:.0} %", 100.0 * p));
                }
                ui.label(format!("{} region(s)", e.regions));
            }
            None => {
                ui.label(match self.last.as_ref().and_then(|o| o.referencing) {
                    Some((n, of)) => format!("taking V_0: {n} of {of} frames"),
                    None => "no touch".into(),
                });
            }
        }
        ui.separator();
        if ui.button("Open the training wizard").clicked() {
            self.wizard.open = true;
        }
        if self.processor.classifier.is_some() {
            ui.label("a model classifies each touch");
        }
    }

    fn plots(&mut self, ui: &mut egui::Ui) {
        ui.set_width(260.0);
        ui.heading("Signal");
        let rate: Vec<(f64, f64)> = self.monitor.rate.iter().copied().collect();
        sparkline(ui, "frames/s", &rate);
        let bvc: Vec<(f64, f64)> = self
            .monitor
            .bvc
            .iter()
            .map(|&(t, v)| (t, v * 1e3))
            .collect();
        sparkline(ui, "BVC |V_m - V_0| (mV)", &bvc);
        bars(ui, "SNR per channel (dB)", &self.monitor.snr_db);
        ui.separator();
        ui.heading("Link health");
        let h: Health = self.source.as_ref().map(Source::health).unwrap_or_default();
        egui::Grid::new("health").show(ui, |ui| {
            for (name, v) in [
                ("frames", self.monitor.frames),
                ("lost (gaps)", h.lost.max(self.monitor.gaps)),
                ("dropped by board", h.dropped),
                ("corrupt packets", h.corrupt),
                ("reconnects", h.reconnects),
            ] {
                ui.label(name);
                ui.label(v.to_string());
                ui.end_row();
            }
        });
        if let Some(Source::Port(p)) = &self.source {
            if let Some(s) = p.status {
                ui.label(format!(
                    "board: {}scanning, model {}",
                    if s.scanning { "" } else { "not " },
                    if s.model_loaded { "loaded" } else { "none" }
                ));
                if s.suspect_electrodes != 0 {
                    ui.colored_label(
                        Color32::from_rgb(220, 80, 60),
                        format!("suspect electrodes: {:016b}", s.suspect_electrodes),
                    );
                }
            }
            if let Some(problem) = &p.last_problem {
                ui.label(problem);
            }
        }
    }

    fn sheet_view(&mut self, ui: &mut egui::Ui) {
        let grid = self.processor.grid().clone();
        let avail = ui.available_size() - vec2(70.0, 10.0);
        let scale = (avail.x / grid.width as f32)
            .min(avail.y / grid.height as f32)
            .max(1.0);
        let size = vec2(grid.width as f32 * scale, grid.height as f32 * scale);
        let (response, painter) = ui.allocate_painter(size + vec2(70.0, 0.0), Sense::drag());
        let rect = Rect::from_min_size(response.rect.min, size);
        // Sheet coordinates (m) <-> screen.
        let to_screen = |p: [f64; 2]| {
            pos2(
                rect.min.x + ((p[0] - grid.origin[0]) / grid.size) as f32 * scale,
                rect.max.y - ((p[1] - grid.origin[1]) / grid.size) as f32 * scale,
            )
        };
        let to_sheet = |p: Pos2| {
            [
                grid.origin[0] + f64::from((p.x - rect.min.x) / scale) * grid.size,
                grid.origin[1] + f64::from((rect.max.y - p.y) / scale) * grid.size,
            ]
        };
        // The image.
        let values: Vec<Option<f64>> = self
            .last
            .as_ref()
            .map_or_else(|| vec![None; grid.triangle.len()], |o| o.image.clone());
        let hi = values
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(f64::MIN_POSITIVE);
        let mut rgba = Vec::with_capacity(grid.width * grid.height * 4);
        for j in (0..grid.height).rev() {
            for i in 0..grid.width {
                let c = match values.get(j * grid.width + i).copied().flatten() {
                    Some(v) => {
                        let c = crate::plot::viridis(0.5 + 0.5 * v / hi);
                        [c.0, c.1, c.2, 255]
                    }
                    None => [40, 40, 40, 255],
                };
                rgba.extend_from_slice(&c);
            }
        }
        let image = egui::ColorImage::from_rgba_unmultiplied([grid.width, grid.height], &rgba);
        match &mut self.texture {
            Some(t) => t.set(image, TextureOptions::NEAREST),
            None => {
                self.texture = Some(
                    ui.ctx()
                        .load_texture("sheet", image, TextureOptions::NEAREST),
                )
            }
        }
        if let Some(t) = &self.texture {
            painter.image(
                t.id(),
                rect,
                Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
                Color32::WHITE,
            );
        }
        // ROI outline: the edges of the pixels above the threshold.
        if let Some(out) = self.last.as_ref().filter(|o| o.event.is_some()) {
            let max = values
                .iter()
                .flatten()
                .copied()
                .fold(f64::NEG_INFINITY, f64::max);
            let keep = |i: isize, j: isize| {
                i >= 0
                    && j >= 0
                    && (i as usize) < grid.width
                    && (j as usize) < grid.height
                    && values[j as usize * grid.width + i as usize]
                        .is_some_and(|v| v >= out.threshold * max)
            };
            let stroke = Stroke::new(2.0, Color32::WHITE);
            for j in 0..grid.height as isize {
                for i in 0..grid.width as isize {
                    if !keep(i, j) {
                        continue;
                    }
                    let x0 = rect.min.x + i as f32 * scale;
                    let y0 = rect.max.y - (j + 1) as f32 * scale;
                    let (x1, y1) = (x0 + scale, y0 + scale);
                    for (ni, nj, a, b) in [
                        (i - 1, j, pos2(x0, y0), pos2(x0, y1)),
                        (i + 1, j, pos2(x1, y0), pos2(x1, y1)),
                        (i, j - 1, pos2(x0, y1), pos2(x1, y1)),
                        (i, j + 1, pos2(x0, y0), pos2(x1, y0)),
                    ] {
                        if !keep(ni, nj) {
                            painter.line_segment([a, b], stroke);
                        }
                    }
                }
            }
        }
        // The class grid, the recognised class lit, and the position marker.
        if let Some(c) = &self.processor.classifier {
            let centres = &c.file.centres_mm;
            let pitch = pitch_mm(centres);
            let lit = self
                .last
                .as_ref()
                .and_then(|o| o.event.as_ref())
                .and_then(|e| e.class);
            for (k, m) in centres.iter().enumerate() {
                let a = to_screen([(m[0] - pitch / 2.0) * 1e-3, (m[1] + pitch / 2.0) * 1e-3]);
                let b = to_screen([(m[0] + pitch / 2.0) * 1e-3, (m[1] - pitch / 2.0) * 1e-3]);
                let cell = Rect::from_two_pos(a, b).shrink(1.0);
                if lit == Some(k as u16) {
                    painter.rect_filled(
                        cell,
                        2.0,
                        Color32::from_rgba_unmultiplied(255, 80, 60, 110),
                    );
                }
                painter.rect_stroke(
                    cell,
                    2.0,
                    Stroke::new(1.0, Color32::from_white_alpha(90)),
                    StrokeKind::Inside,
                );
            }
        }
        if let Some(e) = self.last.as_ref().and_then(|o| o.event.as_ref())
            && e.position_mm.iter().all(|v| v.is_finite())
        {
            let p = to_screen([e.position_mm[0] * 1e-3, e.position_mm[1] * 1e-3]);
            let s = Stroke::new(2.0, Color32::from_rgb(255, 80, 60));
            painter.line_segment([p - vec2(10.0, 0.0), p + vec2(10.0, 0.0)], s);
            painter.line_segment([p - vec2(0.0, 10.0), p + vec2(0.0, 10.0)], s);
        }
        // The true touches (simulator, recordings of it).
        if let Some(truth) = self.last.as_ref().and_then(|o| o.frame.truth.as_ref()) {
            for t in truth {
                painter.circle_stroke(
                    to_screen(t.position),
                    (t.radius / grid.size) as f32 * scale,
                    Stroke::new(1.5, Color32::from_white_alpha(200)),
                );
            }
        }
        // The colour bar.
        let bar = Rect::from_min_size(pos2(rect.max.x + 14.0, rect.min.y), vec2(16.0, size.y));
        let steps = 64;
        for s in 0..steps {
            let t = 1.0 - s as f64 / f64::from(steps - 1);
            let c = crate::plot::viridis(t);
            let y0 = bar.min.y + s as f32 * bar.height() / steps as f32;
            painter.rect_filled(
                Rect::from_min_size(
                    pos2(bar.min.x, y0),
                    vec2(bar.width(), bar.height() / steps as f32 + 1.0),
                ),
                0.0,
                Color32::from_rgb(c.0, c.1, c.2),
            );
        }
        let sigma0 = self.processor.imager().sigma0;
        for (y, v, anchor) in [
            (bar.min.y, hi, Align2::LEFT_TOP),
            (bar.center().y, 0.0, Align2::LEFT_CENTER),
            (bar.max.y, -hi, Align2::LEFT_BOTTOM),
        ] {
            painter.text(
                pos2(bar.max.x + 3.0, y),
                anchor,
                format!("{:+.2}", v / sigma0),
                FontId::proportional(11.0),
                ui.visuals().text_color(),
            );
        }
        // Pressing the simulated sheet with the mouse.
        if matches!(self.source, Some(Source::Sim(_))) {
            let down = response.is_pointer_button_down_on();
            match (down, response.interact_pointer_pos()) {
                (true, Some(p)) if rect.contains(p) => {
                    let at = to_sheet(p);
                    self.press(vec![Touch {
                        position: at,
                        radius: 0.0075,
                        pressure: 20e3,
                    }]);
                    self.pressing = true;
                }
                _ if self.pressing => {
                    self.press(Vec::new());
                    self.pressing = false;
                }
                _ => {}
            }
            if !self.pressing {
                response.on_hover_text("press and hold to touch the simulated sheet");
            }
        }
    }
}

/// The spacing of a class grid (smallest distance between centres), mm.
fn pitch_mm(centres: &[[f64; 2]]) -> f64 {
    let mut best = f64::INFINITY;
    for (i, a) in centres.iter().enumerate() {
        for b in &centres[i + 1..] {
            best = best.min((a[0] - b[0]).hypot(a[1] - b[1]));
        }
    }
    if best.is_finite() { best } else { 10.0 }
}

/// A plot's caption and its framed area, the full width and 60 points high.
fn plot_area(ui: &mut egui::Ui, caption: &str) -> (Rect, egui::Painter) {
    ui.label(caption);
    let (rect, _) = ui.allocate_exact_size(vec2(ui.available_width(), 60.0), Sense::hover());
    let painter = ui.painter_at(rect);
    painter.rect_stroke(
        rect,
        2.0,
        Stroke::new(1.0, Color32::from_gray(90)),
        StrokeKind::Inside,
    );
    (rect, painter)
}

/// A small line plot with its title and last value.
fn sparkline(ui: &mut egui::Ui, title: &str, points: &[(f64, f64)]) {
    let last = points
        .last()
        .map_or(String::from("-"), |p| format!("{:.2}", p.1));
    let (rect, painter) = plot_area(ui, &format!("{title}: {last}"));
    let finite: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if finite.len() < 2 {
        return;
    }
    let (x0, x1) = (
        finite[0].0,
        finite[finite.len() - 1].0.max(finite[0].0 + 1e-9),
    );
    let (lo, hi) = finite
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1), b.max(p.1))
        });
    let (lo, hi) = (lo.min(0.0), hi.max(lo + 1e-12));
    let line: Vec<Pos2> = finite
        .iter()
        .map(|p| {
            pos2(
                rect.min.x + ((p.0 - x0) / (x1 - x0)) as f32 * rect.width(),
                rect.max.y - ((p.1 - lo) / (hi - lo)) as f32 * (rect.height() - 4.0) - 2.0,
            )
        })
        .collect();
    painter.line(line, Stroke::new(1.5, Color32::from_rgb(90, 170, 255)));
}

/// Bars, one per channel, with the mean in the title.
fn bars(ui: &mut egui::Ui, title: &str, values: &[f64]) {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let mean = if finite.is_empty() {
        f64::NAN
    } else {
        finite.iter().sum::<f64>() / finite.len() as f64
    };
    let (rect, painter) = plot_area(ui, &format!("{title}: mean {mean:.1}"));
    let hi = finite.iter().copied().fold(1.0f64, f64::max);
    let w = rect.width() / values.len().max(1) as f32;
    for (i, v) in values.iter().enumerate() {
        if !v.is_finite() {
            continue;
        }
        let h = (v.max(0.0) / hi) as f32 * (rect.height() - 2.0);
        let x = rect.min.x + i as f32 * w;
        painter.rect_filled(
            Rect::from_min_max(pos2(x, rect.max.y - h), pos2(x + w.max(1.0), rect.max.y)),
            0.0,
            Color32::from_rgb(120, 200, 140),
        );
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
/// A message when the window cannot be created (no display, no OpenGL).
pub fn run(options: Options) -> Result<(), String> {
    let viewer = Viewer::new(options)?;
    let native = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size(Vec2::new(1280.0, 780.0))
            .with_title("et view"),
        ..Default::default()
    };
    eframe::run_native("et view", native, Box::new(|_cc| Ok(Box::new(viewer)))).map_err(|e| {
        format!("cannot open the window: {e} (is there a display? try DISPLAY=:0 or xvfb-run)")
    })
}

#[cfg(test)]
mod tests;
