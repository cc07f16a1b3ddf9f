//! Image metrics against the truth (docs/method.md §7).

use crate::pixels::PixelGrid;
use crate::touches::regions;

/// docs/method.md §7's metrics of one image against the truth.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// BVC = |V_1 - V_0|, V.
    pub bvc: f64,
    /// PE = |r_real - r_detected| / sheet size (largest extent).
    pub pe: f64,
    /// SE = |detected size - real size| / sheet area.
    pub se: f64,
    /// RNG = area of opposite-sign ringing / (sheet area - detected size).
    pub rng: f64,
}

/// Metrics of `image` for a single object of area `object_area` (m^2) centred at `truth`,
/// with ROI threshold `f`.
#[must_use]
pub fn metrics(
    grid: &PixelGrid,
    image: &[Option<f64>],
    f: f64,
    dv: &[f64],
    truth: [f64; 2],
    object_area: f64,
) -> Metrics {
    let bvc = et_core::stats::bvc_dv(dv);
    let pixel = grid.size * grid.size;
    let sheet_area = image.iter().flatten().count() as f64 * pixel;
    let extent = grid.width.max(grid.height) as f64 * grid.size;
    let rois = regions(grid, image, f);
    let detected: f64 = rois.iter().map(|r| r.area).sum();
    let pe = rois.first().map_or(1.0, |r| {
        (r.centroid[0] - truth[0]).hypot(r.centroid[1] - truth[1]) / extent
    });
    let max = image.iter().flatten().copied().fold(0.0f64, f64::max);
    let ringing = image.iter().flatten().filter(|&&v| v <= -f * max).count() as f64 * pixel;
    Metrics {
        bvc,
        pe,
        se: (detected - object_area).abs() / sheet_area,
        rng: if sheet_area > detected {
            ringing / (sheet_area - detected)
        } else {
            0.0
        },
    }
}
