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

/// One true touch matched to the found touch nearest it (docs/method.md §7's PE and SE for
/// each of several touches).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct TouchMatch {
    /// The true centre, m.
    pub truth: [f64; 2],
    /// Index into the found touches of the nearest one; `None` when nothing was found.
    pub found: Option<usize>,
    /// PE = distance to it / sheet size (largest extent); 1 when nothing was found.
    pub pe: f64,
    /// SE = |its area - the true area| / sheet area; 1 when nothing was found.
    pub se: f64,
}

/// Each true touch (centre, radius in m) matched to the nearest of the `found` touches
/// ([`crate::touches::touches`] on `grid`'s image), with its own PE and SE. Several true touches
/// may match the same found one (two touches imaged as one: both PEs then show it); the found
/// touches no true touch matched are the false ones (`found.len()` minus the distinct matches).
#[must_use]
pub fn match_touches(
    grid: &PixelGrid,
    found: &[crate::touches::Region],
    truth: &[([f64; 2], f64)],
) -> Vec<TouchMatch> {
    let extent = grid.width.max(grid.height) as f64 * grid.size;
    let pixel = grid.size * grid.size;
    let sheet_area = grid.triangle.iter().flatten().count() as f64 * pixel;
    truth
        .iter()
        .map(|&(centre, radius)| {
            let dist = |r: &crate::touches::Region| {
                (r.centroid[0] - centre[0]).hypot(r.centroid[1] - centre[1])
            };
            let nearest =
                (0..found.len()).min_by(|&a, &b| dist(&found[a]).total_cmp(&dist(&found[b])));
            match nearest {
                Some(i) => TouchMatch {
                    truth: centre,
                    found: Some(i),
                    pe: dist(&found[i]) / extent,
                    se: (found[i].area - std::f64::consts::PI * radius * radius).abs()
                        / sheet_area.max(f64::MIN_POSITIVE),
                },
                None => TouchMatch {
                    truth: centre,
                    found: None,
                    pe: 1.0,
                    se: 1.0,
                },
            }
        })
        .collect()
}

/// GREIT's figures of merit of the image of one small target (Adler et al. 2009, the
/// consensus figures; docs/method.md §6.6). The "quarter set" is the pixels at or above a
/// quarter of the image's largest value.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Merit {
    /// Amplitude response: the image's sum over the sheet (value x pixel area) over the
    /// target's (contrast x area). Its spread over the sheet is what GREIT keeps small.
    pub amplitude: f64,
    /// Position error: from the target's centre to the quarter set's centroid, m.
    pub position_error: f64,
    /// Resolution: sqrt(quarter set's area / sheet's area).
    pub resolution: f64,
    /// Shape deformation: the share of the quarter set outside the circle of its own area
    /// about its centroid.
    pub shape_deformation: f64,
    /// Ringing: the opposite-sign sum outside that circle over the sum inside it.
    pub ringing: f64,
}

/// [`Merit`] of `image` (on `grid`, None outside the sheet) of a target of `contrast` (S per
/// square) and `area` (m^2) centred at `centre` (m). None for an image with no positive value.
#[must_use]
pub fn merit(
    grid: &PixelGrid,
    image: &[Option<f64>],
    centre: [f64; 2],
    contrast: f64,
    area: f64,
) -> Option<Merit> {
    let max = image.iter().flatten().copied().fold(0.0f64, f64::max);
    if max <= 0.0 || !max.is_finite() {
        return None;
    }
    let pixel = grid.size * grid.size;
    let inside: Vec<(usize, f64)> = image
        .iter()
        .enumerate()
        .filter_map(|(p, v)| v.map(|v| (p, v)))
        .collect();
    let quarter: Vec<usize> = inside
        .iter()
        .filter(|(_, v)| *v >= 0.25 * max)
        .map(|(p, _)| *p)
        .collect();
    let c = grid.centroid(&quarter);
    let q_area = quarter.len() as f64 * pixel;
    let r_q = (q_area / std::f64::consts::PI).sqrt();
    let within = |p: usize| {
        let x = grid.centre(p);
        (x[0] - c[0]).hypot(x[1] - c[1]) <= r_q
    };
    let outside_circle = quarter.iter().filter(|&&p| !within(p)).count();
    let (mut in_sum, mut opposite) = (0.0, 0.0);
    for &(p, v) in &inside {
        if within(p) {
            in_sum += v;
        } else if v < 0.0 {
            opposite -= v;
        }
    }
    Some(Merit {
        amplitude: inside.iter().map(|(_, v)| v).sum::<f64>() * pixel / (contrast * area),
        position_error: (c[0] - centre[0]).hypot(c[1] - centre[1]),
        resolution: (q_area / (inside.len() as f64 * pixel)).sqrt(),
        shape_deformation: outside_circle as f64 / quarter.len().max(1) as f64,
        ringing: if in_sum > 0.0 { opposite / in_sum } else { 0.0 },
    })
}
