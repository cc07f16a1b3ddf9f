//! The small plots: frame rate and BVC over time, SNR per channel.

use super::*;

/// The right panel: frame rate, BVC and SNR per channel; the link's health.
#[derive(Debug, Default)]
pub struct Plots {
    /// The labels the small plots' axes drew last.
    pub axes: Vec<String>,
}

impl Plots {
    /// Draws the signal of `monitor` and the health of `source`.
    pub(super) fn show(&mut self, ui: &mut egui::Ui, monitor: &Monitor, source: Option<&Source>) {
        ui.set_width(260.0);
        ui.heading("Signal");
        let rate: Vec<(f64, f64)> = monitor.rate.iter().copied().collect();
        let mut axes = sparkline(ui, "frames/s", &rate);
        let bvc: Vec<(f64, f64)> = monitor.bvc.iter().map(|&(t, v)| (t, v * 1e3)).collect();
        axes.extend(sparkline(ui, "BVC |V_m - V_0| (mV)", &bvc));
        axes.extend(bars(ui, "SNR per channel (dB)", &monitor.snr_db));
        self.axes = axes;
        ui.separator();
        ui.heading("Link health");
        let h: Health = source.map(Source::health).unwrap_or_default();
        egui::Grid::new("health").show(ui, |ui| {
            for (name, v) in [
                ("frames", monitor.frames),
                ("lost (gaps)", h.lost.max(monitor.gaps)),
                ("dropped by board", h.dropped),
                ("corrupt packets", h.corrupt),
                ("reconnects", h.reconnects),
                ("on an ADC rail", monitor.rail_frames),
                ("source in compliance", monitor.compliance_frames),
            ] {
                ui.label(name);
                ui.label(v.to_string());
                ui.end_row();
            }
        });
        if let Some(Source::Port(p)) = source {
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
}

/// A plot: its caption, and its framed area (the full width, 60 points high) with room for
/// the axis labels to its left and below.
struct Plot {
    rect: Rect,
    painter: egui::Painter,
    /// The labels drawn on the axes.
    labels: Vec<String>,
}

impl Plot {
    fn new(ui: &mut egui::Ui, caption: &str) -> Self {
        ui.label(caption);
        let (outer, _) = ui.allocate_exact_size(vec2(ui.available_width(), 78.0), Sense::hover());
        let painter = ui.painter_at(outer);
        let rect = Rect::from_min_max(outer.min + vec2(40.0, 2.0), outer.max - vec2(4.0, 16.0));
        painter.rect_stroke(
            rect,
            2.0,
            Stroke::new(1.0, Color32::from_gray(90)),
            StrokeKind::Inside,
        );
        Self {
            rect,
            painter,
            labels: Vec::new(),
        }
    }

    /// A label at `at`, kept in `labels`.
    fn label(&mut self, at: Pos2, anchor: Align2, text: String) {
        self.painter.text(
            at,
            anchor,
            &text,
            FontId::proportional(10.0),
            Color32::from_gray(170),
        );
        self.labels.push(text);
    }

    /// The y axis from `lo` (bottom) to `hi` (top): both ends labelled.
    fn y_axis(&mut self, lo: f64, hi: f64) {
        let label = crate::plot::axis_labels(lo, hi);
        let (top, bottom) = (self.rect.min, self.rect.left_bottom());
        self.label(top - vec2(3.0, 0.0), Align2::RIGHT_TOP, label(&hi));
        self.label(bottom - vec2(3.0, 0.0), Align2::RIGHT_BOTTOM, label(&lo));
    }

    /// The x axis: a label under each end and the quantity in the middle.
    fn x_axis(&mut self, left: String, middle: &str, right: String) {
        let y = self.rect.max.y + 1.0;
        self.label(pos2(self.rect.min.x, y), Align2::LEFT_TOP, left);
        self.label(
            pos2(self.rect.center().x, y),
            Align2::CENTER_TOP,
            middle.to_string(),
        );
        self.label(pos2(self.rect.max.x, y), Align2::RIGHT_TOP, right);
    }
}

/// A small line plot of (time s, value) with its title and last value; time runs to now at
/// the right.
fn sparkline(ui: &mut egui::Ui, title: &str, points: &[(f64, f64)]) -> Vec<String> {
    let last = points
        .last()
        .map_or(String::from("-"), |p| format!("{:.2}", p.1));
    let mut plot = Plot::new(ui, &format!("{title}: {last}"));
    let finite: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if finite.len() < 2 {
        return plot.labels;
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
    let rect = plot.rect;
    let line: Vec<Pos2> = finite
        .iter()
        .map(|p| {
            pos2(
                rect.min.x + ((p.0 - x0) / (x1 - x0)) as f32 * rect.width(),
                rect.max.y - ((p.1 - lo) / (hi - lo)) as f32 * (rect.height() - 4.0) - 2.0,
            )
        })
        .collect();
    plot.painter
        .line(line, Stroke::new(1.5, Color32::from_rgb(90, 170, 255)));
    plot.y_axis(lo, hi);
    plot.x_axis(format!("-{:.0} s", x1 - x0), "time", "now".into());
    plot.labels
}

/// Bars, one per channel, with the mean in the title.
fn bars(ui: &mut egui::Ui, title: &str, values: &[Option<f64>]) -> Vec<String> {
    let finite: Vec<f64> = values.iter().flatten().copied().collect();
    let mean = if finite.is_empty() {
        f64::NAN
    } else {
        finite.iter().sum::<f64>() / finite.len() as f64
    };
    let mut plot = Plot::new(ui, &format!("{title}: mean {mean:.1}"));
    let hi = finite.iter().copied().fold(1.0f64, f64::max);
    let rect = plot.rect;
    let w = rect.width() / values.len().max(1) as f32;
    for (i, v) in values.iter().enumerate() {
        let Some(v) = v else {
            continue;
        };
        let h = (v.max(0.0) / hi) as f32 * (rect.height() - 2.0);
        let x = rect.min.x + i as f32 * w;
        plot.painter.rect_filled(
            Rect::from_min_max(pos2(x, rect.max.y - h), pos2(x + w.max(1.0), rect.max.y)),
            0.0,
            Color32::from_rgb(120, 200, 140),
        );
    }
    if !values.is_empty() {
        plot.y_axis(0.0, hi);
        plot.x_axis("1".into(), "channel k", values.len().to_string());
    }
    plot.labels
}
