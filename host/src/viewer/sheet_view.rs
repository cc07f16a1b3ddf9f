//! The sheet: the image with its colour bar, the touches and the truth, the class grid.

use super::*;

impl Viewer {
    pub(super) fn sheet_view(&mut self, ui: &mut egui::Ui) {
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
