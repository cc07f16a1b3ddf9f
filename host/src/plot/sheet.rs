//! Images of the sheet: a conductivity change on the pixel grid, with its colour bar.

use std::path::Path;

use et_recon::Imager;

use super::PlotError;

/// Writes `image` (one value per pixel of `imager`'s grid, None outside the sheet, S per
/// square) as a PNG in units of the background, with a symmetric colour bar and axes in mm.
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn sheet_image(
    imager: &Imager,
    path: &Path,
    title: &str,
    image: &[Option<f64>],
) -> Result<(), PlotError> {
    let grid = &imager.grid;
    // Row 0 at the top.
    let rows: Vec<f64> = (0..grid.height)
        .rev()
        .flat_map(|j| (0..grid.width).map(move |i| j * grid.width + i))
        .map(|p| image[p].map_or(f64::NAN, |v| v / imager.sigma0))
        .collect();
    let hi = rows
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
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
        (-hi, hi.max(f64::MIN_POSITIVE)),
        "conductivity change / background",
    )
}
