//! Images of the sheet: a conductivity change on the pixel grid, with its colour bar, the
//! true touches, the touches found and the region of interest.

use std::path::Path;

use et_recon::Imager;
use plotters::style::RGBColor;

use super::{Mark, Overlay, PlotError};

/// What is drawn over a sheet image besides the image.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SheetMarks {
    /// The true touches: centre (m) and radius (m), drawn as green circles.
    pub truth: Vec<([f64; 2], f64)>,
    /// The touches found, strongest first: their centroids (m), drawn as crosses numbered
    /// from 1.
    pub found: Vec<[f64; 2]>,
    /// The region of interest's pixels (indices into the grid), outlined in black.
    pub roi: Vec<usize>,
    /// The colour scale's half-range in units of the background (None: this image's largest
    /// |value|). Give several images the same to compare them by colour.
    pub half_range: Option<f64>,
}

/// "1 touch", "2 touches": a count of touches for a title.
#[must_use]
pub fn touches(n: usize) -> String {
    if n == 1 {
        "1 touch".into()
    } else {
        format!("{n} touches")
    }
}

/// The largest |value| of `image` in units of the background (0 for an empty image).
#[must_use]
pub fn half_range(imager: &Imager, image: &[Option<f64>]) -> f64 {
    image
        .iter()
        .flatten()
        .map(|v| (v / imager.sigma0).abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max)
}

/// Writes `image` (one value per pixel of `imager`'s grid, None outside the sheet, S per
/// square) as a PNG in units of the background, on a colour map centred on zero, with axes in
/// mm and `marks` over it (a line under the axis says what they are).
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn sheet_image(
    imager: &Imager,
    path: &Path,
    title: &str,
    image: &[Option<f64>],
    marks: &SheetMarks,
) -> Result<(), PlotError> {
    let grid = &imager.grid;
    // Row 0 at the top.
    let rows: Vec<f64> = (0..grid.height)
        .rev()
        .flat_map(|j| (0..grid.width).map(move |i| j * grid.width + i))
        .map(|p| image[p].map_or(f64::NAN, |v| v / imager.sigma0))
        .collect();
    let hi = marks
        .half_range
        .unwrap_or_else(|| half_range(imager, image))
        .max(f64::MIN_POSITIVE);
    let mm = |v: f64| v * 1e3;
    let extent = super::Extent {
        x: (
            mm(grid.origin[0]),
            mm(grid.origin[0] + grid.width as f64 * grid.size),
        ),
        y: (
            mm(grid.origin[1] + grid.height as f64 * grid.size),
            mm(grid.origin[1]),
        ),
    };
    let mut overlay = Overlay::default();
    // The ROI's outline.
    let mut member = vec![false; grid.width * grid.height];
    for &p in &marks.roi {
        if let Some(m) = member.get_mut(p) {
            *m = true;
        }
    }
    for [a, b] in grid.outline(&member) {
        overlay.marks.push(Mark::Line {
            points: vec![(mm(a[0]), mm(a[1])), (mm(b[0]), mm(b[1]))],
            colour: RGBColor(0, 0, 0),
            width: 2,
        });
    }
    for &(c, r) in &marks.truth {
        overlay.marks.push(Mark::Line {
            points: (0..=72)
                .map(|k| {
                    let a = f64::from(k) * std::f64::consts::TAU / 72.0;
                    (mm(c[0] + r * a.cos()), mm(c[1] + r * a.sin()))
                })
                .collect(),
            colour: RGBColor(0, 150, 80),
            width: 3,
        });
    }
    for (n, g) in marks.found.iter().enumerate() {
        overlay.marks.push(Mark::Cross {
            at: (mm(g[0]), mm(g[1])),
            label: (n + 1).to_string(),
        });
    }
    overlay.key = "green circle: true touch;  x numbered: touch found (1 strongest);  \
                   black outline: ROI, pixels >= f max"
        .into();
    super::heatmap_over(
        path,
        super::Labels {
            title,
            x: "x (mm)",
            y: "y (mm)",
            legend: super::Legend::UpperLeft,
        },
        &rows,
        (grid.height, grid.width),
        extent,
        (-hi, hi),
        "conductivity change / background",
        &overlay,
    )
}
