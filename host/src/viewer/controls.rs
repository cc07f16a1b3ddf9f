//! The top bar ([`SourceBar`]: which source) and the side panel (protocol, alpha, thresholds,
//! tare, replay, the touch, the wizard).

use super::*;

/// The top bar: which source to open (the simulated sheet, a recording, a board's port).
#[derive(Debug, Default)]
pub struct SourceBar {
    /// The source kind chosen.
    pub kind: SourceKind,
    /// The recording path typed.
    pub replay_path: String,
    /// The serial port chosen.
    pub port: String,
    /// The ports found by the last refresh.
    ports: Vec<String>,
}

impl SourceBar {
    /// The bar showing the source the viewer opened with.
    pub(super) fn of(spec: &SourceSpec) -> Self {
        let mut bar = Self::default();
        match spec {
            SourceSpec::Sim => bar.kind = SourceKind::Sim,
            SourceSpec::Replay(p) => {
                bar.kind = SourceKind::Replay;
                bar.replay_path = p.display().to_string();
            }
            SourceSpec::Port(p, _) => {
                bar.kind = SourceKind::Port;
                bar.port.clone_from(p);
            }
        }
        bar
    }

    /// Draws the bar beside `described` (the source open now); whether Open was clicked.
    /// Refreshing the ports says what it found in `status`.
    pub(super) fn show(&mut self, ui: &mut egui::Ui, described: &str, status: &mut String) -> bool {
        let mut open = false;
        ui.horizontal(|ui| {
            ui.label("Source:");
            ui.selectable_value(&mut self.kind, SourceKind::Sim, "Simulated sheet");
            ui.selectable_value(&mut self.kind, SourceKind::Replay, "Recording");
            ui.selectable_value(&mut self.kind, SourceKind::Port, "Board");
            match self.kind {
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
                                *status = format!("{} serial ports", p.len());
                                self.ports = p;
                            }
                            Err(e) => *status = format!("cannot list serial ports: {e}"),
                        }
                    }
                }
            }
            open = ui.button("Open").clicked();
            ui.separator();
            ui.label(described);
        });
        open
    }
}

impl Viewer {
    /// The side panel: protocol, imaging settings, tare, replay, the touch, the wizard.
    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
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
        ui.horizontal(|ui| {
            for m in et_recon::Method::NAMED {
                ui.selectable_value(&mut s.method, m, m.to_string());
            }
        });
        ui.add_enabled(
            matches!(s.method, et_recon::Method::GaussNewton { .. }),
            egui::Slider::new(&mut s.alpha, 1e-3..=10.0)
                .logarithmic(true)
                .text("alpha"),
        );
        let mut auto = s.threshold.is_none();
        ui.checkbox(&mut auto, "threshold per protocol (docs/method.md §6)");
        let mut f = s
            .threshold
            .unwrap_or(self.last.as_ref().map_or(0.1, |o| o.threshold));
        ui.add_enabled(
            !auto,
            egui::Slider::new(&mut f, 0.01..=0.9).text("threshold f"),
        );
        s.threshold = (!auto).then_some(f);
        ui.add(egui::Slider::new(&mut s.touch_factor, 2.0..=20.0).text("touch at z >"))
            .on_hover_text("a touch peaks this many times its pixels' noise (z) or more");
        ui.checkbox(
            &mut self.sheet_view.show_specks,
            "outline every pixel >= f max",
        )
        .on_hover_text("noise specks too; off: only the found touches are outlined");
        if s != self.processor.settings() {
            self.processor.set_settings(s);
        }
        if ui.button("Tare (sheet untouched)").clicked() {
            if self.protocol == ProtocolChoice::Automatic {
                self.start_automatic();
            } else {
                self.processor.tare();
                self.status = "taking V_0: keep the sheet untouched".into();
            }
        }
        self.left_out_line(ui);
        let mut sought = false;
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
                .add(
                    egui::Slider::new(&mut at, 0..=last)
                        .show_value(false)
                        .text("seek"),
                )
                .changed()
            {
                r.seek(at);
                sought = true;
            }
            // The frame shown is the last one played (position counts those).
            ui.label(format!("frame {} of {}", r.position, r.len()));
            ui.checkbox(&mut r.looping, "loop");
        }
        // (A frame sought to is no frame lost: "lost (gaps)" counted every seek forward.)
        if sought {
            self.monitor.resume();
        }
        ui.separator();
        ui.heading("Touch");
        self.touch_lines(ui);
        ui.separator();
        if ui.button("Open the training wizard").clicked() {
            self.wizard.open = true;
        }
        if self.processor.classifier.is_some() {
            ui.label("a model classifies each touch");
        }
    }

    /// The electrodes left out of the images, with a button to put them back, and one to
    /// leave out those V_0 names detached or broken (a clip off the sheet, a wire off its
    /// channel: their values would place touches wrongly, or hide them).
    fn left_out_line(&mut self, ui: &mut egui::Ui) {
        let base = u32::from(self.processor.electrode_base());
        let named = |electrodes: &[u16]| {
            let numbers: Vec<String> = (electrodes.iter())
                .map(|&e| (u32::from(e) + base).to_string())
                .collect();
            let noun = if electrodes.len() == 1 {
                "electrode"
            } else {
                "electrodes"
            };
            format!("{noun} {}", numbers.join(", "))
        };
        let left_out = self.processor.left_out().to_vec();
        let mut asked = None;
        ui.horizontal_wrapped(|ui| {
            if left_out.is_empty() {
                ui.label("every electrode imaged");
            } else {
                ui.label(format!("left out: {}", named(&left_out)));
                if ui.button("Put back").clicked() {
                    asked = Some(Vec::new());
                }
            }
            if !self.detached.is_empty()
                && ui
                    .button(format!("Leave out {}", named(&self.detached)))
                    .on_hover_text("V_0 names them detached or broken: image without their values")
                    .clicked()
            {
                asked = Some([&left_out[..], &self.detached[..]].concat());
            }
        });
        let Some(asked) = asked else {
            return;
        };
        self.status = match self.processor.set_left_out(&asked, None) {
            Ok(_) if asked.is_empty() => "every electrode imaged again".into(),
            Ok((values, k)) => {
                let left_out = self.processor.left_out();
                let model = (self.processor.classifier_reads_said(left_out))
                    .map_or(String::new(), |said| format!("; {said}"));
                format!(
                    "{} left out of the images: {values} of the frame's {k} values (every \
                     value they drive or measure){model}",
                    named(left_out)
                )
            }
            Err(e) => e.to_string(),
        };
        // Those still standing out among the values imaged (put back: those named before).
        self.detached = (self.processor.v0_electrode_said()).map_or(Vec::new(), |(_, e)| e);
    }

    /// The last frame's touch, or why there is none, in [`TOUCH_LINES`] lines whatever it
    /// shows: the controls below stay where they are as touches come and go (the wizard's
    /// button moved four lines up and down under a pointer, and clicks missed it).
    fn touch_lines(&self, ui: &mut egui::Ui) {
        let lines: [String; TOUCH_LINES] = match self.last.as_ref().and_then(|o| o.event.as_ref()) {
            Some(e) => [
                format!("at ({:.0}, {:.0}) mm", e.position_mm[0], e.position_mm[1]),
                format!("intensity z = {:.1}", e.intensity),
                e.class.map_or(String::new(), |c| format!("class {c}")),
                (e.confidence).map_or(String::new(), |p| format!("confidence {:.0} %", 100.0 * p)),
                format!("{} region(s)", e.regions),
            ],
            None => [
                match self.last.as_ref().and_then(|o| o.referencing) {
                    Some(r) => format!("taking V_0: {} of {} frames", r.frames, r.needed),
                    None => "no touch".into(),
                },
                String::new(),
                String::new(),
                String::new(),
                String::new(),
            ],
        };
        for line in lines {
            // (An empty label is a line high, as the text's.)
            ui.label(if line.is_empty() { " ".into() } else { line });
        }
    }
}

/// Lines the touch section always takes.
const TOUCH_LINES: usize = 5;
