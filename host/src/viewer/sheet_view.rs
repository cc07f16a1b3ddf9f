//! The sheet: the image in mm with its electrodes, colour bar and legend; the found touches
//! (numbered, with their outlines), the true touches, the class grid. [`SheetView`] keeps
//! what lasts between frames (the texture, the mouse's press, what it drew); each part of the
//! picture is drawn by its own function on a [`Canvas`].

use super::*;

/// Room around the sheet, points: left (y axis), right (colour bar), top, bottom (x axis and
/// the legend).
const MARGIN: [f32; 4] = [70.0, 130.0, 30.0, 80.0];
/// How far outside the outline the axes sit (clear of the electrode numbers), points.
const AXIS_GAP: f32 = 26.0;
/// The found touches' markers and outlines.
const MARKER: Color32 = Color32::from_rgb(20, 20, 20);
/// The electrodes and their numbers.
const ELECTRODE: Color32 = Color32::from_rgb(230, 180, 60);
/// The true touches.
const TRUTH: Color32 = Color32::from_rgb(0, 150, 80);
/// The class the model lit.
const CLASS: Color32 = Color32::from_rgb(120, 60, 200);

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

/// The central panel: the sheet and what it keeps between frames.
#[derive(Default)]
pub struct SheetView {
    texture: Option<TextureHandle>,
    /// The mouse is pressing the simulated sheet.
    pressing: bool,
    /// Outline every pixel above f max (noise specks too), not only the found touches'.
    pub show_specks: bool,
    /// What it drew last.
    pub drawn: Drawn,
}

impl std::fmt::Debug for SheetView {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SheetView")
            .field("pressing", &self.pressing)
            .field("show_specks", &self.show_specks)
            .field("drawn", &self.drawn)
            .finish_non_exhaustive()
    }
}

/// What the sheet view shows on one frame, borrowed from the viewer.
pub(super) struct Shown<'a> {
    /// The pixels the image is drawn on.
    pub grid: &'a PixelGrid,
    /// The untouched sheet's conductivity, S (the image is drawn over it).
    pub sigma0: f64,
    /// The latest processed frame.
    pub last: Option<&'a Output>,
    /// The sheet's outline and electrodes.
    pub sheet: &'a et_core::sheet::Sheet,
    /// A model's class centres, m, when one classifies the touches.
    pub class_centres: Option<&'a [[f64; 2]]>,
    /// The mouse presses the sheet (a simulated one), and says so when hovered.
    pub pressable: bool,
    /// Say what the mouse does when hovered (not in screenshots).
    pub hint: bool,
    /// The number of the first electrode (1 where the scene's protocol file counts from 1).
    pub electrode_base: u16,
}

/// What the mouse did to the sheet.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Press {
    /// Nothing new.
    Nothing,
    /// Pressing here (sheet coordinates, m).
    At([f64; 2]),
    /// Let go.
    Released,
}

/// Where the sheet is drawn: the painter and the map between the sheet (m) and the screen.
struct Canvas<'a> {
    painter: &'a egui::Painter,
    /// The image's rectangle on the screen.
    rect: Rect,
    /// Points per pixel.
    scale: f32,
    grid: &'a PixelGrid,
    small: FontId,
    text: Color32,
}

impl Canvas<'_> {
    /// A point of the sheet (m) on the screen.
    fn to_screen(&self, p: [f64; 2]) -> Pos2 {
        let g = self.grid;
        pos2(
            self.rect.min.x + ((p[0] - g.origin[0]) / g.size) as f32 * self.scale,
            self.rect.max.y - ((p[1] - g.origin[1]) / g.size) as f32 * self.scale,
        )
    }

    /// A point of the screen on the sheet (m).
    fn to_sheet(&self, p: Pos2) -> [f64; 2] {
        let g = self.grid;
        [
            g.origin[0] + f64::from((p.x - self.rect.min.x) / self.scale) * g.size,
            g.origin[1] + f64::from((self.rect.max.y - p.y) / self.scale) * g.size,
        ]
    }

    fn label(&self, at: Pos2, anchor: Align2, text: &str, colour: Color32) -> Rect {
        self.painter
            .text(at, anchor, text, self.small.clone(), colour)
    }

    /// The outline of the pixels `member` marks.
    fn outline(&self, member: &[bool], stroke: Stroke) {
        for [a, b] in self.grid.outline(member) {
            self.painter
                .line_segment([self.to_screen(a), self.to_screen(b)], stroke);
        }
    }
}

impl SheetView {
    /// Draws the sheet into the central panel and says what the mouse did to it.
    pub(super) fn show(&mut self, ui: &mut egui::Ui, shown: &Shown) -> Press {
        let grid = shown.grid;
        let [left, right, top, bottom] = MARGIN;
        let avail = ui.available_size() - vec2(left + right, top + bottom);
        let scale = (avail.x / grid.width as f32)
            .min(avail.y / grid.height as f32)
            .max(1.0);
        let size = vec2(grid.width as f32 * scale, grid.height as f32 * scale);
        let (response, painter) =
            ui.allocate_painter(size + vec2(left + right, top + bottom), Sense::drag());
        let canvas = Canvas {
            painter: &painter,
            rect: Rect::from_min_size(response.rect.min + vec2(left, top), size),
            scale,
            grid,
            small: FontId::proportional(11.0),
            text: ui.visuals().text_color(),
        };
        // The image, in units of the untouched sheet's conductivity, on a map centred on zero.
        let values: Vec<Option<f64>> = shown.last.map_or_else(
            || vec![None; grid.triangle.len()],
            |o| {
                o.image
                    .iter()
                    .map(|v| v.map(|v| v / shown.sigma0))
                    .collect()
            },
        );
        let hi = values
            .iter()
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()))
            .max(1e-6);
        self.image(ui.ctx(), &canvas, &values, hi);
        let mut drawn = Drawn::default();
        electrodes(&canvas, shown.sheet, shown.electrode_base, &mut drawn);
        let x_axis = axes(&canvas, &mut drawn);
        if self.show_specks {
            drawn.specks = specks(&canvas, shown.last, &values);
        }
        touches(&canvas, shown.last, values.len(), &mut drawn);
        if let Some(centres) = shown.class_centres {
            drawn.class = class_grid(&canvas, centres, shown.last);
        }
        drawn.truth = truth(&canvas, shown.last);
        colour_bar(&canvas, hi, &mut drawn);
        legend(&canvas, x_axis, shown.class_centres.is_some());
        self.drawn = drawn;
        if shown.pressable {
            self.press(&response, &canvas, shown.hint)
        } else {
            Press::Nothing
        }
    }

    /// The image as a texture stretched over the sheet's rectangle.
    fn image(&mut self, ctx: &egui::Context, canvas: &Canvas, values: &[Option<f64>], hi: f64) {
        let grid = canvas.grid;
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
        let texture = match &mut self.texture {
            Some(t) => {
                t.set(image, TextureOptions::NEAREST);
                t
            }
            None => self
                .texture
                .insert(ctx.load_texture("sheet", image, TextureOptions::NEAREST)),
        };
        canvas.painter.image(
            texture.id(),
            canvas.rect,
            Rect::from_min_max(pos2(0.0, 0.0), pos2(1.0, 1.0)),
            Color32::WHITE,
        );
    }

    /// Pressing the simulated sheet with the mouse: a press where the button is down, a
    /// release when it lets go.
    fn press(&mut self, response: &egui::Response, canvas: &Canvas, hint: bool) -> Press {
        let down = response.is_pointer_button_down_on();
        let press = match (down, response.interact_pointer_pos()) {
            (true, Some(p)) if canvas.rect.contains(p) => {
                self.pressing = true;
                Press::At(canvas.to_sheet(p))
            }
            _ if self.pressing => {
                self.pressing = false;
                Press::Released
            }
            _ => Press::Nothing,
        };
        if !self.pressing && hint {
            response
                .clone()
                .on_hover_text("press and hold to touch the simulated sheet");
        }
        press
    }
}

/// The outline and the electrodes, numbered outside it from `base`.
fn electrodes(canvas: &Canvas, sheet: &et_core::sheet::Sheet, base: u16, drawn: &mut Drawn) {
    let shape = &sheet.shape;
    let outline: Vec<Pos2> = (0..=240)
        .map(|k| canvas.to_screen(shape.boundary_point(f64::from(k) / 240.0)))
        .collect();
    canvas.painter.add(egui::Shape::line(
        outline,
        Stroke::new(1.0, Color32::from_gray(150)),
    ));
    for (e, t) in sheet
        .electrodes
        .arc_positions(shape)
        .into_iter()
        .enumerate()
    {
        let (p, e) = (shape.boundary_point(t), e + usize::from(base));
        let (a, b) = (
            shape.boundary_point(t - 1e-3),
            shape.boundary_point(t + 1e-3),
        );
        // Walking counter-clockwise, outward is to the right.
        let n = vec2((b[1] - a[1]) as f32, (b[0] - a[0]) as f32).normalized();
        let at = canvas.to_screen(p);
        canvas.painter.circle_filled(at, 4.0, ELECTRODE);
        canvas.label(
            at + n * 13.0,
            Align2::CENTER_CENTER,
            &e.to_string(),
            ELECTRODE,
        );
        drawn.electrodes.push((e, [p[0] * 1e3, p[1] * 1e3]));
    }
}

/// Axes in mm, outside the electrode numbers; the x axis's height on the screen.
fn axes(canvas: &Canvas, drawn: &mut Drawn) -> f32 {
    let (rect, grid, painter) = (canvas.rect, canvas.grid, canvas.painter);
    let axis = Stroke::new(1.0, Color32::from_gray(140));
    let (x_axis, y_axis) = (rect.max.y + AXIS_GAP, rect.min.x - AXIS_GAP);
    let span_mm = |o: f64, n: usize| (o * 1e3, (o + n as f64 * grid.size) * 1e3);
    let (x0, x1) = span_mm(grid.origin[0], grid.width);
    let (y0, y1) = span_mm(grid.origin[1], grid.height);
    painter.line_segment([pos2(rect.min.x, x_axis), pos2(rect.max.x, x_axis)], axis);
    painter.line_segment([pos2(y_axis, rect.min.y), pos2(y_axis, rect.max.y)], axis);
    let tick_label = crate::plot::axis_labels(x0, x1);
    for v in crate::plot::nice_ticks(x0, x1, 6) {
        let x = canvas.to_screen([v * 1e-3, 0.0]).x;
        painter.line_segment([pos2(x, x_axis), pos2(x, x_axis + 4.0)], axis);
        let label = tick_label(&v);
        canvas.label(
            pos2(x, x_axis + 6.0),
            Align2::CENTER_TOP,
            &label,
            canvas.text,
        );
        drawn.ticks_mm.0.push(label);
    }
    painter.text(
        pos2(rect.center().x, x_axis + 22.0),
        Align2::CENTER_TOP,
        "x (mm)",
        FontId::proportional(12.0),
        canvas.text,
    );
    let tick_label = crate::plot::axis_labels(y0, y1);
    for v in crate::plot::nice_ticks(y0, y1, 6) {
        let y = canvas.to_screen([0.0, v * 1e-3]).y;
        painter.line_segment([pos2(y_axis - 4.0, y), pos2(y_axis, y)], axis);
        let label = tick_label(&v);
        canvas.label(
            pos2(y_axis - 6.0, y),
            Align2::RIGHT_CENTER,
            &label,
            canvas.text,
        );
        drawn.ticks_mm.1.push(label);
    }
    painter.text(
        pos2(y_axis - 6.0, rect.min.y - 14.0),
        Align2::RIGHT_BOTTOM,
        "y (mm)",
        FontId::proportional(12.0),
        canvas.text,
    );
    x_axis
}

/// Every pixel above f max outlined (the noise specks too); whether any was.
fn specks(canvas: &Canvas, last: Option<&Output>, values: &[Option<f64>]) -> bool {
    let Some(out) = last.filter(|o| o.referencing.is_none()) else {
        return false;
    };
    let max = values.iter().flatten().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return false;
    }
    let above: Vec<bool> = values
        .iter()
        .map(|v| v.is_some_and(|v| v >= out.threshold * max))
        .collect();
    canvas.outline(&above, Stroke::new(1.0, Color32::from_gray(170)));
    true
}

/// Each found touch: its pixels outlined, a cross at its centroid, its number (1 = strongest).
fn touches(canvas: &Canvas, last: Option<&Output>, pixels: usize, drawn: &mut Drawn) {
    let Some(out) = last.filter(|o| o.event.is_some()) else {
        return;
    };
    let painter = canvas.painter;
    for (n, region) in out.touches.iter().enumerate() {
        let mut member = vec![false; pixels];
        for &p in &region.pixels {
            member[p] = true;
        }
        canvas.outline(&member, Stroke::new(2.0, MARKER));
        drawn.outlines += 1;
        let p = canvas.to_screen(region.centroid);
        let s = Stroke::new(2.5, MARKER);
        painter.line_segment([p - vec2(9.0, 0.0), p + vec2(9.0, 0.0)], s);
        painter.line_segment([p - vec2(0.0, 9.0), p + vec2(0.0, 9.0)], s);
        let galley = painter.layout_no_wrap(
            (n + 1).to_string(),
            FontId::proportional(14.0),
            Color32::WHITE,
        );
        let label = Align2::LEFT_BOTTOM.anchor_size(p + vec2(8.0, -8.0), galley.size());
        painter.rect_filled(label.expand(1.0), 2.0, MARKER);
        painter.galley(label.min, galley, Color32::WHITE);
        drawn
            .touches
            .push((n + 1, [region.centroid[0] * 1e3, region.centroid[1] * 1e3]));
    }
}

/// The class grid (centres in mm), the recognised class lit; the class lit, if any.
fn class_grid(canvas: &Canvas, centres: &[[f64; 2]], last: Option<&Output>) -> Option<u16> {
    let pitch = pitch(centres);
    let lit = last
        .filter(|o| o.event.is_some())
        .and_then(|o| o.event.as_ref())
        .and_then(|e| e.class);
    let mut shown = None;
    for (k, m) in centres.iter().enumerate() {
        let a = canvas.to_screen([m[0] - pitch / 2.0, m[1] + pitch / 2.0]);
        let b = canvas.to_screen([m[0] + pitch / 2.0, m[1] - pitch / 2.0]);
        let cell = Rect::from_two_pos(a, b).shrink(1.0);
        if lit == Some(k as u16) {
            let stroke = Stroke::new(3.0, CLASS);
            canvas
                .painter
                .rect_stroke(cell, 2.0, stroke, StrokeKind::Inside);
            let at = cell.center_bottom() + vec2(0.0, 2.0);
            canvas.label(at, Align2::CENTER_TOP, &format!("class {k}"), CLASS);
            shown = Some(k as u16);
        } else {
            let stroke = Stroke::new(1.0, Color32::from_black_alpha(50));
            canvas
                .painter
                .rect_stroke(cell, 2.0, stroke, StrokeKind::Inside);
        }
    }
    shown
}

/// The true touches (simulator, recordings of it), circled; how many.
fn truth(canvas: &Canvas, last: Option<&Output>) -> usize {
    let Some(truth) = last.and_then(|o| o.frame.truth.as_ref()) else {
        return 0;
    };
    for t in truth {
        canvas.painter.circle_stroke(
            canvas.to_screen(t.position),
            (t.radius / canvas.grid.size) as f32 * canvas.scale,
            Stroke::new(2.0, TRUTH),
        );
    }
    truth.len()
}

/// The colour bar: symmetric about zero (+-`hi`), in units of the untouched sheet.
fn colour_bar(canvas: &Canvas, hi: f64, drawn: &mut Drawn) {
    let (rect, painter) = (canvas.rect, canvas.painter);
    let bar = Rect::from_min_size(
        pos2(rect.max.x + 40.0, rect.min.y),
        vec2(16.0, rect.height()),
    );
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
    let tick_label = crate::plot::axis_labels(-hi, hi);
    for v in crate::plot::nice_ticks(-hi, hi, 4) {
        let y = bar.center().y - (v / hi) as f32 * bar.height() / 2.0;
        painter.line_segment(
            [pos2(bar.max.x, y), pos2(bar.max.x + 3.0, y)],
            Stroke::new(1.0, canvas.text),
        );
        let label = tick_label(&v);
        canvas.label(
            pos2(bar.max.x + 5.0, y),
            Align2::LEFT_CENTER,
            &label,
            canvas.text,
        );
        drawn.colour_bar.1.push(label);
    }
    let caption = "Δσ/σ0";
    painter.text(
        pos2(bar.center().x, bar.min.y - 4.0),
        Align2::CENTER_BOTTOM,
        caption,
        FontId::proportional(12.0),
        canvas.text,
    );
    canvas.label(
        pos2(bar.center().x, bar.max.y + 4.0),
        Align2::CENTER_TOP,
        "no unit:\nchange over\nthe untouched\nsheet",
        canvas.text,
    );
    drawn.colour_bar.0 = caption.into();
}

/// The legend under the x axis, on the sheet's white so its symbols look as they do there.
fn legend(canvas: &Canvas, x_axis: f32, classes: bool) {
    let painter = canvas.painter;
    let mut x = canvas.rect.min.x;
    let y = x_axis + 48.0;
    let legend_colour = Color32::from_gray(30);
    // The backdrop's slot, filled once the entries' width is known.
    let backdrop = painter.add(egui::Shape::Noop);
    let cross = |p: Pos2| {
        let s = Stroke::new(2.0, MARKER);
        painter.line_segment([p - vec2(6.0, 0.0), p + vec2(6.0, 0.0)], s);
        painter.line_segment([p - vec2(0.0, 6.0), p + vec2(0.0, 6.0)], s);
    };
    let square = |p: Pos2, rounding: f32, colour: Color32| {
        painter.rect_stroke(
            Rect::from_center_size(p, vec2(10.0, 10.0)),
            rounding,
            Stroke::new(2.0, colour),
            StrokeKind::Inside,
        );
    };
    let mut entry = |symbol: &dyn Fn(Pos2), text: &str| {
        symbol(pos2(x + 6.0, y));
        let r = canvas.label(pos2(x + 16.0, y), Align2::LEFT_CENTER, text, legend_colour);
        x = r.max.x + 18.0;
    };
    entry(&cross, "touch found (1 = strongest)");
    entry(&|p| square(p, 0.0, MARKER), "its pixels >= f max");
    entry(
        &|p| {
            painter.circle_stroke(p, 5.0, Stroke::new(2.0, TRUTH));
        },
        "true touch",
    );
    entry(
        &|p| {
            painter.circle_filled(p, 4.0, ELECTRODE);
        },
        "electrode",
    );
    if classes {
        entry(&|p| square(p, 1.0, CLASS), "model's class");
    }
    painter.set(
        backdrop,
        egui::Shape::rect_filled(
            Rect::from_min_max(
                pos2(canvas.rect.min.x - 4.0, y - 10.0),
                pos2(x - 8.0, y + 10.0),
            ),
            3.0,
            Color32::from_gray(247),
        ),
    );
}

/// The spacing of a class grid (smallest distance between centres), m (1 cm for one class).
fn pitch(centres: &[[f64; 2]]) -> f64 {
    let mut best = f64::INFINITY;
    for (i, a) in centres.iter().enumerate() {
        for b in &centres[i + 1..] {
            best = best.min((a[0] - b[0]).hypot(a[1] - b[1]));
        }
    }
    if best.is_finite() { best } else { 0.01 }
}
