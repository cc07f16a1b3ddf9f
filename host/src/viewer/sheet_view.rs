//! The sheet: the image in mm with its electrodes, colour bar and legend; the found touches
//! (numbered, with their outlines), the true touches, the class grid.

use super::*;

/// Room around the sheet, points: left (y axis), right (colour bar), top, bottom (x axis and
/// the legend).
const MARGIN: [f32; 4] = [70.0, 130.0, 30.0, 80.0];
/// How far outside the outline the axes sit (clear of the electrode numbers), points.
const AXIS_GAP: f32 = 26.0;

/// What the sheet view drew on its last frame, in words and numbers: what a reader of the
/// picture sees (the tests check it).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Drawn {
    /// Tick labels of the x and y axes, mm.
    pub ticks_mm: (Vec<String>, Vec<String>),
    /// Each electrode drawn: its number (as `et protocol` counts, from 0) and centre, mm.
    pub electrodes: Vec<(usize, [f64; 2])>,
    /// The colour bar's caption and tick labels.
    pub colour_bar: (String, Vec<String>),
    /// Each found touch marked: its number (1 = strongest) and centroid, mm.
    pub touches: Vec<(usize, [f64; 2])>,
    /// True touches circled (simulator, its recordings).
    pub truth: usize,
    /// Outlines drawn around found touches.
    pub outlines: usize,
    /// Whether every pixel above f max was outlined too (the noise specks).
    pub specks: bool,
    /// The class a model lit, if any.
    pub class: Option<u16>,
}

impl Viewer {
    pub(super) fn sheet_view(&mut self, ui: &mut egui::Ui) {
        let grid = self.processor.grid().clone();
        let [left, right, top, bottom] = MARGIN;
        let avail = ui.available_size() - vec2(left + right, top + bottom);
        let scale = (avail.x / grid.width as f32)
            .min(avail.y / grid.height as f32)
            .max(1.0);
        let size = vec2(grid.width as f32 * scale, grid.height as f32 * scale);
        let (response, painter) =
            ui.allocate_painter(size + vec2(left + right, top + bottom), Sense::drag());
        let rect = Rect::from_min_size(response.rect.min + vec2(left, top), size);
        let mut drawn = Drawn::default();
        let text_colour = ui.visuals().text_color();
        let small = FontId::proportional(11.0);
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
        // The image, in units of the untouched sheet's conductivity, on a map centred on zero.
        let sigma0 = self.processor.imager().sigma0;
        let values: Vec<Option<f64>> = self.last.as_ref().map_or_else(
            || vec![None; grid.triangle.len()],
            |o| o.image.iter().map(|v| v.map(|v| v / sigma0)).collect(),
        );
        let hi = values
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-6);
        let mut rgba = Vec::with_capacity(grid.width * grid.height * 4);
        for j in (0..grid.height).rev() {
            for i in 0..grid.width {
                let c = match values.get(j * grid.width + i).copied().flatten() {
                    Some(v) => {
                        let c = crate::plot::colour_map(v, (-hi, hi));
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
        // The outline and the electrodes, numbered outside it.
        let shape = &self.sheet.physical.shape;
        let outline: Vec<Pos2> = (0..=240)
            .map(|k| to_screen(shape.boundary_point(f64::from(k) / 240.0)))
            .collect();
        painter.add(egui::Shape::line(
            outline,
            Stroke::new(1.0, Color32::from_gray(150)),
        ));
        let electrode_colour = Color32::from_rgb(230, 180, 60);
        for (e, t) in self
            .sheet
            .physical
            .electrodes
            .arc_positions()
            .into_iter()
            .enumerate()
        {
            let p = shape.boundary_point(t);
            let (a, b) = (
                shape.boundary_point(t - 1e-3),
                shape.boundary_point(t + 1e-3),
            );
            // Walking counter-clockwise, outward is to the right.
            let n = vec2((b[1] - a[1]) as f32, (b[0] - a[0]) as f32).normalized();
            let at = to_screen(p);
            painter.circle_filled(at, 4.0, electrode_colour);
            painter.text(
                at + n * 13.0,
                Align2::CENTER_CENTER,
                e.to_string(),
                small.clone(),
                electrode_colour,
            );
            drawn.electrodes.push((e, [p[0] * 1e3, p[1] * 1e3]));
        }
        // Axes in mm, outside the electrode numbers.
        let axis = Stroke::new(1.0, Color32::from_gray(140));
        let (x_axis, y_axis) = (rect.max.y + AXIS_GAP, rect.min.x - AXIS_GAP);
        let span_mm = |o: f64, n: usize| (o * 1e3, (o + n as f64 * grid.size) * 1e3);
        let (x0, x1) = span_mm(grid.origin[0], grid.width);
        let (y0, y1) = span_mm(grid.origin[1], grid.height);
        painter.line_segment([pos2(rect.min.x, x_axis), pos2(rect.max.x, x_axis)], axis);
        painter.line_segment([pos2(y_axis, rect.min.y), pos2(y_axis, rect.max.y)], axis);
        let ticks = crate::plot::nice_ticks(x0, x1, 6);
        let tick_label = crate::plot::axis_labels(x0, x1);
        for v in ticks {
            let x = to_screen([v * 1e-3, 0.0]).x;
            painter.line_segment([pos2(x, x_axis), pos2(x, x_axis + 4.0)], axis);
            let label = tick_label(&v);
            painter.text(
                pos2(x, x_axis + 6.0),
                Align2::CENTER_TOP,
                &label,
                small.clone(),
                text_colour,
            );
            drawn.ticks_mm.0.push(label);
        }
        painter.text(
            pos2(rect.center().x, x_axis + 22.0),
            Align2::CENTER_TOP,
            "x (mm)",
            FontId::proportional(12.0),
            text_colour,
        );
        let ticks = crate::plot::nice_ticks(y0, y1, 6);
        let tick_label = crate::plot::axis_labels(y0, y1);
        for v in ticks {
            let y = to_screen([0.0, v * 1e-3]).y;
            painter.line_segment([pos2(y_axis - 4.0, y), pos2(y_axis, y)], axis);
            let label = tick_label(&v);
            painter.text(
                pos2(y_axis - 6.0, y),
                Align2::RIGHT_CENTER,
                &label,
                small.clone(),
                text_colour,
            );
            drawn.ticks_mm.1.push(label);
        }
        painter.text(
            pos2(y_axis - 6.0, rect.min.y - 14.0),
            Align2::RIGHT_BOTTOM,
            "y (mm)",
            FontId::proportional(12.0),
            text_colour,
        );
        // Outlines: each found touch's pixels; every pixel above f max on request.
        let pixel_outline = |member: &[bool], stroke: Stroke| {
            for [a, b] in grid.outline(member) {
                painter.line_segment([to_screen(a), to_screen(b)], stroke);
            }
        };
        let touched = self.last.as_ref().filter(|o| o.event.is_some());
        if self.show_specks
            && let Some(out) = self.last.as_ref().filter(|o| o.referencing.is_none())
        {
            let max = values.iter().flatten().copied().fold(0.0, f64::max);
            if max > 0.0 {
                let above: Vec<bool> = values
                    .iter()
                    .map(|v| v.is_some_and(|v| v >= out.threshold * max))
                    .collect();
                pixel_outline(&above, Stroke::new(1.0, Color32::from_gray(170)));
                drawn.specks = true;
            }
        }
        let marker = Color32::from_rgb(20, 20, 20);
        if let Some(out) = touched {
            for (n, region) in out.touches.iter().enumerate() {
                let mut member = vec![false; values.len()];
                for &p in &region.pixels {
                    member[p] = true;
                }
                pixel_outline(&member, Stroke::new(2.0, marker));
                drawn.outlines += 1;
                let p = to_screen(region.centroid);
                let s = Stroke::new(2.5, marker);
                painter.line_segment([p - vec2(9.0, 0.0), p + vec2(9.0, 0.0)], s);
                painter.line_segment([p - vec2(0.0, 9.0), p + vec2(0.0, 9.0)], s);
                let galley = painter.layout_no_wrap(
                    (n + 1).to_string(),
                    FontId::proportional(14.0),
                    Color32::WHITE,
                );
                let label = Align2::LEFT_BOTTOM.anchor_size(p + vec2(8.0, -8.0), galley.size());
                painter.rect_filled(label.expand(1.0), 2.0, marker);
                painter.galley(label.min, galley, Color32::WHITE);
                drawn
                    .touches
                    .push((n + 1, [region.centroid[0] * 1e3, region.centroid[1] * 1e3]));
            }
        }
        // The class grid, the recognised class lit.
        if let Some(c) = &self.processor.classifier {
            let centres = &c.file.centres_mm;
            let pitch = pitch_mm(centres);
            let lit = touched.and_then(|o| o.event.as_ref()).and_then(|e| e.class);
            for (k, m) in centres.iter().enumerate() {
                let a = to_screen([(m[0] - pitch / 2.0) * 1e-3, (m[1] + pitch / 2.0) * 1e-3]);
                let b = to_screen([(m[0] + pitch / 2.0) * 1e-3, (m[1] - pitch / 2.0) * 1e-3]);
                let cell = Rect::from_two_pos(a, b).shrink(1.0);
                if lit == Some(k as u16) {
                    painter.rect_stroke(
                        cell,
                        2.0,
                        Stroke::new(3.0, Color32::from_rgb(120, 60, 200)),
                        StrokeKind::Inside,
                    );
                    painter.text(
                        cell.center_bottom() + vec2(0.0, 2.0),
                        Align2::CENTER_TOP,
                        format!("class {k}"),
                        small.clone(),
                        Color32::from_rgb(120, 60, 200),
                    );
                    drawn.class = Some(k as u16);
                } else {
                    painter.rect_stroke(
                        cell,
                        2.0,
                        Stroke::new(1.0, Color32::from_black_alpha(50)),
                        StrokeKind::Inside,
                    );
                }
            }
        }
        // The true touches (simulator, recordings of it).
        if let Some(truth) = self.last.as_ref().and_then(|o| o.frame.truth.as_ref()) {
            for t in truth {
                painter.circle_stroke(
                    to_screen(t.position),
                    (t.radius / grid.size) as f32 * scale,
                    Stroke::new(2.0, Color32::from_rgb(0, 150, 80)),
                );
                drawn.truth += 1;
            }
        }
        // The colour bar: symmetric about zero, in units of the untouched sheet.
        let bar = Rect::from_min_size(pos2(rect.max.x + 40.0, rect.min.y), vec2(16.0, size.y));
        let steps = 64;
        for s in 0..steps {
            let v = hi * (1.0 - 2.0 * (f64::from(s) + 0.5) / f64::from(steps));
            let c = crate::plot::colour_map(v, (-hi, hi));
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
        let ticks = crate::plot::nice_ticks(-hi, hi, 4);
        let tick_label = crate::plot::axis_labels(-hi, hi);
        for v in ticks {
            let y = bar.center().y - (v / hi) as f32 * bar.height() / 2.0;
            painter.line_segment(
                [pos2(bar.max.x, y), pos2(bar.max.x + 3.0, y)],
                Stroke::new(1.0, text_colour),
            );
            let label = tick_label(&v);
            painter.text(
                pos2(bar.max.x + 5.0, y),
                Align2::LEFT_CENTER,
                &label,
                small.clone(),
                text_colour,
            );
            drawn.colour_bar.1.push(label);
        }
        let caption = "Δσ/σ0";
        painter.text(
            pos2(bar.center().x, bar.min.y - 4.0),
            Align2::CENTER_BOTTOM,
            caption,
            FontId::proportional(12.0),
            text_colour,
        );
        painter.text(
            pos2(bar.center().x, bar.max.y + 4.0),
            Align2::CENTER_TOP,
            "no unit:\nchange over\nthe untouched\nsheet",
            small.clone(),
            text_colour,
        );
        drawn.colour_bar.0 = caption.into();
        // The legend under the axis, on the sheet's white so its symbols look as they do there.
        let mut x = rect.min.x;
        let y = x_axis + 48.0;
        let legend_colour = Color32::from_gray(30);
        // The backdrop's slot, filled once the entries' width is known.
        let backdrop = painter.add(egui::Shape::Noop);
        let cross = |p: Pos2| {
            let s = Stroke::new(2.0, marker);
            painter.line_segment([p - vec2(6.0, 0.0), p + vec2(6.0, 0.0)], s);
            painter.line_segment([p - vec2(0.0, 6.0), p + vec2(0.0, 6.0)], s);
        };
        let mut entry = |symbol: &dyn Fn(Pos2), text: &str| {
            symbol(pos2(x + 6.0, y));
            let r = painter.text(
                pos2(x + 16.0, y),
                Align2::LEFT_CENTER,
                text,
                small.clone(),
                legend_colour,
            );
            x = r.max.x + 18.0;
        };
        entry(&cross, "touch found (1 = strongest)");
        entry(
            &|p: Pos2| {
                painter.rect_stroke(
                    Rect::from_center_size(p, vec2(10.0, 10.0)),
                    0.0,
                    Stroke::new(2.0, marker),
                    StrokeKind::Inside,
                );
            },
            "its pixels >= f max",
        );
        entry(
            &|p: Pos2| {
                painter.circle_stroke(p, 5.0, Stroke::new(2.0, Color32::from_rgb(0, 150, 80)));
            },
            "true touch",
        );
        entry(
            &|p: Pos2| {
                painter.circle_filled(p, 4.0, electrode_colour);
            },
            "electrode",
        );
        if self.processor.classifier.is_some() {
            entry(
                &|p: Pos2| {
                    painter.rect_stroke(
                        Rect::from_center_size(p, vec2(10.0, 10.0)),
                        1.0,
                        Stroke::new(2.0, Color32::from_rgb(120, 60, 200)),
                        StrokeKind::Inside,
                    );
                },
                "model's class",
            );
        }
        painter.set(
            backdrop,
            egui::Shape::rect_filled(
                Rect::from_min_max(pos2(rect.min.x - 4.0, y - 10.0), pos2(x - 8.0, y + 10.0)),
                3.0,
                Color32::from_gray(247),
            ),
        );
        self.drawn = drawn;
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
                        footprint: Default::default(),
                    }]);
                    self.pressing = true;
                }
                _ if self.pressing => {
                    self.press(Vec::new());
                    self.pressing = false;
                }
                _ => {}
            }
            if !self.pressing && self.options.screenshot.is_none() {
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
