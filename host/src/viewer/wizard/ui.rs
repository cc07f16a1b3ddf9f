//! The wizard's panel: the steps, the grid of cells to press, the confusion matrix, saving the
//! model.

use super::*;

impl Wizard {
    /// The wizard's window contents.
    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        source: Option<&Source>,
        sheet: &SheetSpec,
    ) -> Vec<Request> {
        let mut requests = Vec::new();
        let simulated = matches!(source, Some(Source::Sim(_)));
        match self.step.clone() {
            Step::Setup => requests.extend(self.setup_ui(ui, source, sheet)),
            Step::Reference { visit } => {
                ui.label(format!(
                    "Visit {} of {}: keep the sheet untouched (taking V_0).",
                    visit + 1,
                    self.visits
                ));
            }
            Step::Press { visit, cell } => {
                ui.label(format!(
                    "Visit {} of {}: press cell {} (row {}, column {}), highlighted below.",
                    visit + 1,
                    self.visits,
                    cell + 1,
                    cell / self.cols + 1,
                    cell % self.cols + 1
                ));
                self.grid(ui, Some(cell));
                if simulated {
                    if ui.button("Press for me (simulated)").clicked() {
                        requests.push(self.simulated_press(cell));
                        self.step = Step::Recording {
                            visit,
                            cell,
                            frames: 0,
                        };
                    }
                } else if ui.button("Record this press").clicked() {
                    self.step = Step::Recording {
                        visit,
                        cell,
                        frames: 0,
                    };
                }
            }
            Step::Recording {
                visit,
                cell,
                frames,
            } => {
                ui.label(format!(
                    "Visit {} of {}, cell {}: {frames} of {} frames (keep pressing, vary the pressure)",
                    visit + 1,
                    self.visits,
                    cell + 1,
                    self.frames_per_press
                ));
                self.grid(ui, Some(cell));
            }
            Step::Ready => {
                ui.label(format!(
                    "{} observations of {} classes over {} visits.",
                    self.observations(),
                    self.classes(),
                    self.visits
                ));
                if ui.button("Train").clicked()
                    && let Err(e) = self.train()
                {
                    self.message = e.to_string();
                }
            }
            Step::Trained => requests.extend(self.trained_ui(ui, source)),
        }
        if !self.message.is_empty() {
            ui.separator();
            ui.label(&self.message);
        }
        requests
    }

    /// The set-up step: the grid's rows and columns, the visits and frames per press, and
    /// Start.
    fn setup_ui(
        &mut self,
        ui: &mut egui::Ui,
        source: Option<&Source>,
        sheet: &SheetSpec,
    ) -> Option<Request> {
        ui.label("A class grid over the sheet; each cell is pressed in turn, every visit.");
        egui::Grid::new("wizard-setup").show(ui, |ui| {
            let mut row = |name: &str, value: &mut usize, range| {
                ui.label(name);
                ui.add(egui::DragValue::new(value).range(range));
                ui.end_row();
            };
            row("rows", &mut self.rows, 1..=10);
            row("columns", &mut self.cols, 1..=10);
            row("visits", &mut self.visits, 1..=6);
            row("frames per press", &mut self.frames_per_press, 2..=100);
        });
        if ui.button("Start").clicked() {
            if source.is_some_and(|s| !s.switches_scan()) {
                // (It waited without end for frames of its scan, which a recording of another
                // never sends, and would label a recording's presses as cells asked for.)
                self.message = "the wizard records presses as you make them, cell by cell: \
                                open the simulated sheet or a board (a recording plays the \
                                presses it holds)"
                    .into();
                return None;
            }
            match source.and_then(Source::config) {
                Some(base) => match self.start(sheet, base) {
                    Ok(r) => return Some(r),
                    Err(e) => self.message = e.to_string(),
                },
                None => self.message = "no frames yet: open a source first".into(),
            }
        }
        None
    }

    /// The trained step: the cross-validations and confusion, using, exporting and saving the
    /// model, or starting again.
    fn trained_ui(&mut self, ui: &mut egui::Ui, source: Option<&Source>) -> Vec<Request> {
        let mut requests = Vec::new();

        if let Some(t) = &self.trained {
            ui.label(format!(
                "cross-validated accuracy: {:.1} %",
                100.0 * t.cv.accuracy()
            ));
            if let Some(a) = t.leave_one_visit_out {
                ui.label(format!("leave-one-visit-out: {:.1} %", 100.0 * a));
            }
            confusion(ui, &t.cv);
        }
        ui.horizontal(|ui| {
            if ui.button("Use this model").clicked()
                && let Some(t) = &self.trained
            {
                requests.push(Request::UseModel(Box::new(t.board.clone())));
            }
            let board = matches!(source, Some(Source::Port(_)));
            if ui
                .add_enabled(board, egui::Button::new("Export to the board"))
                .on_hover_text("with the sheet untouched: the board takes V_0 after the upload")
                .on_disabled_hover_text("open the board's serial port first")
                .clicked()
            {
                match self.blob() {
                    Ok(b) => requests.push(Request::Upload(b)),
                    Err(e) => self.message = e.to_string(),
                }
            }
        });
        ui.horizontal(|ui| {
            ui.add(egui::TextEdit::singleline(&mut self.save_path));
            if ui.button("Save").clicked() {
                requests.push(Request::Save);
            }
        });
        if ui.button("Start again").clicked() {
            self.step = Step::Setup;
        }
        requests
    }

    /// Saves the model (JSON) and its blob beside it; says what it did. Existing files are
    /// replaced only on a second Save (the first one says so), and never the viewer's
    /// `inputs` (its scene, the scene's protocol file, the recording played, the model given),
    /// as et's commands refuse theirs; each file is written whole (aside, then renamed).
    pub fn save(&mut self, inputs: &[PathBuf]) -> String {
        let Some(t) = &self.trained else {
            return "train first".into();
        };
        let path = PathBuf::from(self.save_path.trim());
        let blob_path = path.with_extension("etm");
        // A model named `.etm` was written, then replaced by its own blob.
        if let Err(e) = crate::output::check_format(&path, "the model (JSON)", &["json"]) {
            return e.to_string();
        }
        let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
        let confirmed = self.replace_confirmed.as_ref() == Some(&path);
        match crate::output::check_all(&[&path, &blob_path], &[], &inputs, confirmed) {
            Err(crate::output::OutputError::Exists { .. }) | Ok(()) => {}
            Err(e) => return e.to_string(),
        }
        let existing: Vec<String> = [&path, &blob_path]
            .into_iter()
            .filter(|p| p.exists())
            .map(|p| p.display().to_string())
            .collect();
        if !existing.is_empty() && !confirmed {
            self.replace_confirmed = Some(path);
            return format!(
                "{} already exist(s): Save again to replace, or change the name",
                existing.join(" and ")
            );
        }
        self.replace_confirmed = None;
        type Failure = Box<dyn std::error::Error>;
        let saved = crate::output::write(&path, |partial| {
            t.board.file().save(partial).map_err(Failure::from)
        });
        if let Err(e) = saved {
            return e.to_string();
        }
        let blob = self.blob().map_err(Failure::from).and_then(|b| {
            crate::output::write(&blob_path, |partial| {
                std::fs::write(partial, b).map_err(Failure::from)
            })
        });
        match blob {
            Err(e) => format!(
                "saved {}; blob: {}: {e}",
                path.display(),
                blob_path.display()
            ),
            Ok(()) => format!("saved {} and {}", path.display(), blob_path.display()),
        }
    }

    /// The class grid, one cell highlighted.
    pub(super) fn grid(&self, ui: &mut egui::Ui, lit: Option<usize>) {
        let cell = 22.0;
        let (rect, _) = ui.allocate_exact_size(
            vec2(self.cols as f32 * cell, self.rows as f32 * cell),
            Sense::hover(),
        );
        let painter = ui.painter_at(rect);
        for k in 0..self.classes() {
            let (r, c) = (k / self.cols, k % self.cols);
            // Row 0 at the bottom, as on the sheet.
            let min = pos2(
                rect.min.x + c as f32 * cell,
                rect.max.y - (r + 1) as f32 * cell,
            );
            let box_ = Rect::from_min_size(min, vec2(cell, cell)).shrink(1.0);
            if lit == Some(k) {
                painter.rect_filled(box_, 2.0, Color32::from_rgb(255, 80, 60));
            }
            painter.rect_stroke(
                box_,
                2.0,
                Stroke::new(1.0, Color32::GRAY),
                StrokeKind::Inside,
            );
        }
    }
}

/// A confusion matrix as shades (rows: true class, columns: predicted).
pub(super) fn confusion(ui: &mut egui::Ui, c: &Confusion) {
    let n = c.classes;
    let side = (240.0 / n.max(1) as f32).clamp(3.0, 24.0);
    let (rect, _) = ui.allocate_exact_size(vec2(n as f32 * side, n as f32 * side), Sense::hover());
    let painter = ui.painter_at(rect);
    for (t, row) in c.counts.chunks(n.max(1)).enumerate() {
        let total = row.iter().sum::<u32>().max(1);
        for (p, &v) in row.iter().enumerate() {
            let share = v as f32 / total as f32;
            let shade = (255.0 * (1.0 - share)) as u8;
            painter.rect_filled(
                Rect::from_min_size(
                    pos2(rect.min.x + p as f32 * side, rect.min.y + t as f32 * side),
                    vec2(side, side),
                ),
                0.0,
                Color32::from_rgb(shade, shade, 255),
            );
        }
    }
    ui.label("confusion: rows true class, columns predicted");
}
