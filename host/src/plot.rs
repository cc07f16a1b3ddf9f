//! PNG plots: line/scatter charts (learning curves, error against distance) and heat maps
//! with a colour bar (confusion matrices, images). Text uses the bundled DejaVu Sans
//! (`host/assets`, its licence beside it), so plots look the same on every machine.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::FontStyle;

mod learning;
mod sheet;

pub use learning::{confusion, error_map, error_vs_distance, predicted_vs_true};
pub use sheet::{SheetMarks, half_range, sheet_image, touches};

/// Why a plot could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct PlotError {
    /// The file.
    pub path: std::path::PathBuf,
    /// What went wrong: the drawing's, the encoder's or the file system's own error, or a
    /// [`PlotFault`].
    pub source: Box<dyn std::error::Error + Send + Sync>,
}

/// What et itself refuses in a plot or a PNG (the libraries' own errors are kept as they are).
#[derive(Debug, thiserror::Error)]
pub enum PlotFault {
    /// The PNG's size does not fit in memory.
    #[error("an image too large to decode")]
    TooLarge,
    /// A PNG of pixels et does not read.
    #[error("{color:?} pixels of {depth:?}: not 8-bit")]
    NotEightBit {
        /// Its colour type.
        color: png::ColorType,
        /// Its bit depth.
        depth: png::BitDepth,
    },
    /// A heat map's values do not fill its rows x cols (or it has none).
    #[error("heat map table of the wrong length: {values} values for {rows} x {cols}")]
    HeatMapLength {
        /// Values given.
        values: usize,
        /// Rows.
        rows: usize,
        /// Columns.
        cols: usize,
    },
}

fn fail(path: &Path, e: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> PlotError {
    PlotError {
        path: path.into(),
        source: e.into(),
    }
}

/// Draws onto a `width` x `height` canvas with `draw` and writes it to `path` as PNG (et's own
/// encoding: any path works, `/dev/stdout` included, whatever its extension).
fn render(
    path: &Path,
    (width, height): (u32, u32),
    draw: impl FnOnce(&DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>) -> Result<(), PlotError>,
) -> Result<(), PlotError> {
    fonts().map_err(|e| fail(path, e))?;
    let mut pixels = vec![0u8; width as usize * height as usize * 3];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(path, e))?;
        draw(&root)?;
        root.present().map_err(|e| fail(path, e))?;
    }
    write_png(path, &pixels, (width, height), false)
}

/// Writes `pixels` (rows of RGB, or RGBA when `alpha`, 8 bits each) to `path` as PNG.
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn write_png(
    path: &Path,
    pixels: &[u8],
    (width, height): (u32, u32),
    alpha: bool,
) -> Result<(), PlotError> {
    let file = std::fs::File::create(path).map_err(|e| fail(path, e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(if alpha {
        png::ColorType::Rgba
    } else {
        png::ColorType::Rgb
    });
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| encoding(path, e))?;
    writer
        .write_image_data(pixels)
        .map_err(|e| encoding(path, e))?;
    writer.finish().map_err(|e| encoding(path, e))
}

/// The encoder's error, its file system error kept as one (the encoder's hides it from
/// `source`, so a closed pipe would not be seen as one).
fn encoding(path: &Path, e: png::EncodingError) -> PlotError {
    match e {
        png::EncodingError::IoError(io) => fail(path, io),
        other => fail(path, other),
    }
}

/// Reads a PNG of 8-bit RGB, RGBA, grey or grey-alpha pixels: its width, height and RGB
/// pixels (rows, 3 bytes a pixel; alpha dropped).
///
/// # Errors
/// [`PlotError`] naming the file, for one that cannot be read or decoded, or another kind of
/// pixel.
pub fn read_png(path: &Path) -> Result<(u32, u32, Vec<u8>), PlotError> {
    let file = std::fs::File::open(path).map_err(|e| fail(path, e))?;
    let mut decoder = png::Decoder::new(std::io::BufReader::new(file));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut reader = decoder.read_info().map_err(|e| fail(path, e))?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| fail(path, PlotFault::TooLarge))?;
    let mut buf = vec![0u8; size];
    let info = reader.next_frame(&mut buf).map_err(|e| fail(path, e))?;
    let data = &buf[..info.buffer_size()];
    let rgb: Vec<u8> = match (info.color_type, info.bit_depth) {
        (png::ColorType::Rgb, png::BitDepth::Eight) => data.to_vec(),
        (png::ColorType::Rgba, png::BitDepth::Eight) => data
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect(),
        (png::ColorType::Grayscale, png::BitDepth::Eight) => {
            data.iter().flat_map(|&g| [g, g, g]).collect()
        }
        (png::ColorType::GrayscaleAlpha, png::BitDepth::Eight) => data
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0]])
            .collect(),
        (color, depth) => return Err(fail(path, PlotFault::NotEightBit { color, depth })),
    };
    Ok((info.width, info.height, rgb))
}

fn fonts() -> Result<(), String> {
    static REGISTERED: OnceLock<Result<(), String>> = OnceLock::new();
    REGISTERED
        .get_or_init(|| {
            plotters::style::register_font(
                "sans-serif",
                FontStyle::Normal,
                include_bytes!("../assets/DejaVuSans.ttf"),
            )
            .map_err(|_| "bundled font unreadable".to_string())
        })
        .clone()
}

/// One curve of a chart.
#[derive(Clone, Debug)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// (x, y) points; non-finite ones are left out.
    pub points: Vec<(f64, f64)>,
    /// Draw points only (a scatter), not a line through them.
    pub scatter: bool,
}

/// Where a chart's legend goes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Legend {
    /// Upper left (curves that start low and rise to the right keep clear of it).
    #[default]
    UpperLeft,
    /// Upper right.
    UpperRight,
    /// Lower right (for curves that rise early, such as distributions).
    LowerRight,
}

/// Chart texts.
#[derive(Clone, Copy, Debug)]
pub struct Labels<'a> {
    /// Title above the chart.
    pub title: &'a str,
    /// Horizontal axis, with unit.
    pub x: &'a str,
    /// Vertical axis, with unit.
    pub y: &'a str,
    /// Legend position (charts only).
    pub legend: Legend,
}

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

fn range(values: impl Iterator<Item = f64>, zero: bool) -> (f64, f64) {
    let (mut lo, mut hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    if zero {
        lo = lo.min(0.0);
    }
    if hi - lo < 1e-12 {
        hi = lo + 1.0;
    }
    let pad = 0.05 * (hi - lo);
    (if zero && lo == 0.0 { 0.0 } else { lo - pad }, hi + pad)
}

/// Writes a line or scatter chart of `series` to `path` (PNG, 800 x 520). The y axis starts
/// at zero when every value is non-negative.
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn chart(path: &Path, labels: Labels<'_>, series: &[Series]) -> Result<(), PlotError> {
    let all = || series.iter().flat_map(|s| s.points.iter());
    let (x0, x1) = range(all().map(|p| p.0), false);
    // From zero when the data come near it (the lowest non-negative value under half the
    // highest), else fitted to the data.
    let finite_y = || all().map(|p| p.1).filter(|v| v.is_finite());
    let (lowest, highest) = finite_y().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
        (a.min(v), b.max(v))
    });
    let from_zero = lowest >= 0.0 && lowest < 0.5 * highest;
    let (y0, mut y1) = range(finite_y(), from_zero);
    // Room at the top for a legend in an upper corner, so that it covers no point.
    let labelled = series.iter().filter(|s| !s.label.is_empty()).count();
    if labelled > 0 && labels.legend != Legend::LowerRight {
        y1 += (y1 - y0) * (0.04 + 0.075 * labelled as f64);
    }
    render(path, (800, 520), |root| {
        draw_chart(path, root, labels, series, [x0, x1, y0, y1])
    })
}

/// [`chart`]'s drawing, on `root`, over [x0, x1] x [y0, y1].
fn draw_chart(
    path: &Path,
    root: &DrawingArea<BitMapBackend<'_>, plotters::coord::Shift>,
    labels: Labels<'_>,
    series: &[Series],
    [x0, x1, y0, y1]: [f64; 4],
) -> Result<(), PlotError> {
    let mut c = ChartBuilder::on(root)
        .caption(labels.title, ("sans-serif", 22))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(|e| fail(path, e))?;
    c.configure_mesh()
        .x_desc(labels.x)
        .y_desc(labels.y)
        .x_label_formatter(&axis_labels(x0, x1))
        .y_label_formatter(&axis_labels(y0, y1))
        .label_style(("sans-serif", 14))
        .axis_desc_style(("sans-serif", 16))
        .draw()
        .map_err(|e| fail(path, e))?;
    for (i, s) in series.iter().enumerate() {
        let colour = PALETTE[i % PALETTE.len()];
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let drawn = if s.scatter {
            c.draw_series(
                pts.iter()
                    .map(|&p| Circle::new(p, 3, colour.mix(0.6).filled())),
            )
            .map_err(|e| fail(path, e))?
        } else {
            // Markers on short curves only; on long ones they would hide the line.
            let marked = if pts.len() <= 30 { &pts[..] } else { &[] };
            c.draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| fail(path, e))?;
            c.draw_series(marked.iter().map(|&p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| fail(path, e))?
        };
        drawn
            .label(s.label.clone())
            .legend(move |(x, y)| Rectangle::new([(x, y - 5), (x + 16, y + 5)], colour.filled()));
    }
    if series.iter().any(|s| !s.label.is_empty()) {
        c.configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .position(match labels.legend {
                Legend::UpperLeft => SeriesLabelPosition::UpperLeft,
                Legend::UpperRight => SeriesLabelPosition::UpperRight,
                Legend::LowerRight => SeriesLabelPosition::LowerRight,
            })
            .draw()
            .map_err(|e| fail(path, e))?;
    }
    Ok(())
}

/// The colour of `v` on a scale from `lo` to `hi`: [`diverging`] centred on zero when the
/// scale spans zero (a signed quantity: white is no change), else [`viridis`].
#[must_use]
pub fn colour_map(v: f64, (lo, hi): (f64, f64)) -> RGBColor {
    if lo < 0.0 && hi > 0.0 {
        diverging(0.5 + 0.5 * v / lo.abs().max(hi))
    } else {
        viridis((v - lo) / if hi > lo { hi - lo } else { 1.0 })
    }
}

/// Red-white-blue for signed values (t in [0, 1], 0.5 white: the value zero; outside is
/// clamped): blue below zero, red above, as ColorBrewer's RdBu reversed.
#[must_use]
pub fn diverging(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (33.0, 102.0, 172.0),
        (146.0, 197.0, 222.0),
        (247.0, 247.0, 247.0),
        (244.0, 165.0, 130.0),
        (178.0, 24.0, 43.0),
    ];
    along(&STOPS, if t.is_finite() { t } else { 0.5 })
}

/// The colour at `t` in [0, 1] (clamped) along five evenly spaced stops, mixed linearly.
fn along(stops: &[(f64, f64, f64); 5], t: f64) -> RGBColor {
    let t = t.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let (a, b) = (stops[i], stops[i + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Round tick values between `lo` and `hi` (inclusive), about `about` of them, spaced 1, 2 or
/// 5 times a power of ten (label them with [`axis_labels`]). Empty for an empty or non-finite
/// range.
#[must_use]
pub fn nice_ticks(lo: f64, hi: f64, about: usize) -> Vec<f64> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let raw = (hi - lo) / about.max(1) as f64;
    let power = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * power)
        .find(|s| *s >= 0.7 * raw)
        .unwrap_or(10.0 * power);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// Viridis, from five stops (t in [0, 1]; outside is clamped).
#[must_use]
pub fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    along(&STOPS, if t.is_finite() { t } else { 0.0 })
}

/// A heat map of `values` (row-major, `rows` x `cols`, row 0 at the top) with a colour bar
/// from `lo` to `hi` labelled `unit`, written to `path` (PNG), axes in cell indices (row 0 at
/// the top). Non-finite cells are grey.
///
/// # Errors
/// [`PlotError`] naming the file, or for a table of the wrong length.
pub fn heatmap(
    path: &Path,
    labels: Labels<'_>,
    values: &[f64],
    (rows, cols): (usize, usize),
    (lo, hi): (f64, f64),
    unit: &str,
) -> Result<(), PlotError> {
    let extent = Extent {
        x: (0.0, cols as f64),
        y: (0.0, rows as f64),
    };
    heatmap_over(
        path,
        labels,
        values,
        (rows, cols),
        extent,
        (lo, hi),
        unit,
        &Overlay::default(),
    )
}

/// What is drawn over a heat map, in its axes' units.
#[derive(Clone, Debug, PartialEq)]
pub enum Mark {
    /// A polyline.
    Line {
        /// Its points.
        points: Vec<(f64, f64)>,
        /// Its colour.
        colour: RGBColor,
        /// Its width, pixels.
        width: u32,
    },
    /// A cross with its label (a number) beside it.
    Cross {
        /// Its centre.
        at: (f64, f64),
        /// The label.
        label: String,
    },
}

/// Marks over a heat map and the line under it that says what they are.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overlay {
    /// The marks.
    pub marks: Vec<Mark>,
    /// Under the x axis: what the marks are (empty: nothing).
    pub key: String,
}

/// Labels for an axis spanning `lo..hi`: integers without decimals, others with as many as a
/// tenth of the span needs and no trailing zeros ("0.05", "0.15", "96", "2000", never "-0").
pub fn axis_labels(lo: f64, hi: f64) -> impl Fn(&f64) -> String {
    let span = (hi - lo).abs();
    let decimals = if span > 0.0 && span.is_finite() {
        ((-(span / 10.0).log10()).ceil().max(0.0) as usize + 1).min(9)
    } else {
        1
    };
    move |v: &f64| {
        let s = format!("{v:.decimals$}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" { "0".into() } else { s }
    }
}

/// What a heat map's axes span: x from left to right edge, y from the top edge to the bottom
/// edge (so an image with y up has y = (top, bottom) = (max, min)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Extent {
    /// (left, right).
    pub x: (f64, f64),
    /// (top, bottom).
    pub y: (f64, f64),
}

/// As [`heatmap`], with axes in the units of `extent` (e.g. mm on the sheet).
///
/// # Errors
/// [`PlotError`] naming the file, or for a table of the wrong length.
pub fn heatmap_over(
    path: &Path,
    labels: Labels<'_>,
    values: &[f64],
    (rows, cols): (usize, usize),
    extent: Extent,
    (lo, hi): (f64, f64),
    unit: &str,
    overlay: &Overlay,
) -> Result<(), PlotError> {
    if values.len() != rows * cols || rows == 0 || cols == 0 {
        let values = values.len();
        return Err(fail(path, PlotFault::HeatMapLength { values, rows, cols }));
    }
    let key_height = if overlay.key.is_empty() { 0 } else { 26 };
    render(path, (780, 640 + key_height), |root| {
        let (root, key) = root.split_vertically(640);
        if !overlay.key.is_empty() {
            key.draw(&Text::new(
                overlay.key.clone(),
                (66, 2),
                ("sans-serif", 14).into_font().color(&BLACK),
            ))
            .map_err(|e| fail(path, e))?;
        }
        let (main, bar) = root.split_horizontally(640);
        let mut c = ChartBuilder::on(&main)
            .caption(labels.title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(54)
            .build_cartesian_2d(extent.x.0..extent.x.1, extent.y.1..extent.y.0)
            .map_err(|e| fail(path, e))?;
        c.configure_mesh()
            .disable_mesh()
            .x_desc(labels.x)
            .y_desc(labels.y)
            .x_label_formatter(&axis_labels(extent.x.0, extent.x.1))
            .y_label_formatter(&axis_labels(extent.y.0, extent.y.1))
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 15))
            .draw()
            .map_err(|e| fail(path, e))?;
        let span = if hi > lo { hi - lo } else { 1.0 };
        c.draw_series((0..rows).flat_map(|r| {
            (0..cols).map(move |q| {
                let v = values[r * cols + q];
                let colour = if v.is_finite() {
                    colour_map(v, (lo, hi))
                } else {
                    RGBColor(160, 160, 160)
                };
                let (w, h) = (
                    (extent.x.1 - extent.x.0) / cols as f64,
                    (extent.y.1 - extent.y.0) / rows as f64,
                );
                let (x, y) = (extent.x.0 + q as f64 * w, extent.y.0 + r as f64 * h);
                Rectangle::new([(x, y), (x + w, y + h)], colour.filled())
            })
        }))
        .map_err(|e| fail(path, e))?;
        for mark in &overlay.marks {
            match mark {
                Mark::Line {
                    points,
                    colour,
                    width,
                } => c
                    .draw_series(std::iter::once(PathElement::new(
                        points.clone(),
                        colour.stroke_width(*width),
                    )))
                    .map(|_| ()),
                Mark::Cross { at, label } => c
                    .draw_series(std::iter::once(
                        EmptyElement::at(*at)
                            + Cross::new((0, 0), 8, BLACK.stroke_width(3))
                            + Text::new(
                                label.clone(),
                                (9, -24),
                                ("sans-serif", 18).into_font().color(&BLACK),
                            ),
                    ))
                    .map(|_| ()),
            }
            .map_err(|e| fail(path, e))?;
        }
        let mut b = ChartBuilder::on(&bar)
            .margin_top(46)
            .margin_bottom(56)
            .margin_right(8)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, lo..lo + span)
            .map_err(|e| fail(path, e))?;
        let bar_label = axis_labels(lo, hi);
        b.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_label_formatter(&bar_label)
            .y_desc(unit)
            .label_style(("sans-serif", 13))
            .axis_desc_style(("sans-serif", 14))
            .draw()
            .map_err(|e| fail(path, e))?;
        let steps = 100;
        b.draw_series((0..steps).map(|i| {
            let (a, z) = (
                lo + span * i as f64 / steps as f64,
                lo + span * (i + 1) as f64 / steps as f64,
            );
            Rectangle::new(
                [(0.0, a), (1.0, z)],
                colour_map(0.5 * (a + z), (lo, hi)).filled(),
            )
        }))
        .map_err(|e| fail(path, e))?;
        Ok(())
    })
}
