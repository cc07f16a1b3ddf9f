//! Position errors summarised: mean, median and 90th percentile, and pressure's.

use super::*;

/// Error statistics of a set of predictions.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ErrorSummary {
    /// Mean position error, mm.
    pub mean_mm: f64,
    /// Median position error, mm.
    pub median_mm: f64,
    /// 90th percentile position error, mm.
    pub p90_mm: f64,
    /// Mean absolute pressure error, kPa (NaN-free: 0 when not predicted).
    pub pressure_mae_kpa: f64,
    /// Correlation of predicted and true pressure (0 when not predicted).
    pub pressure_r: f64,
}

/// Position errors (mm) of predictions against truth (both m), sorted ascending.
#[must_use]
pub fn sorted_position_errors(pred: &[Target3], truth: &[Target3]) -> Vec<f64> {
    let mut e: Vec<f64> = pred
        .iter()
        .zip(truth)
        .map(|(p, t)| 1e3 * (p[0] - t[0]).hypot(p[1] - t[1]))
        .collect();
    e.sort_by(f64::total_cmp);
    e
}

/// Mean, median and 90th percentile (nearest rank) of `sorted` (ascending); zeros for none.
#[must_use]
pub fn mean_median_p90(sorted: &[f64]) -> [f64; 3] {
    let q = |f: f64| {
        sorted
            .get(((sorted.len() as f64 - 1.0) * f).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    [
        sorted.iter().sum::<f64>() / sorted.len().max(1) as f64,
        q(0.5),
        q(0.9),
    ]
}

/// Summarises predictions against truth (positions in m, summarised in mm; the third
/// component as given; `pressure`: whether it counts).
#[must_use]
pub fn summarise(pred: &[Target3], truth: &[Target3], pressure: bool) -> ErrorSummary {
    let [mean_mm, median_mm, p90_mm] = mean_median_p90(&sorted_position_errors(pred, truth));
    let n = pred.len().max(1) as f64;
    let (mae, r) = if pressure && pred.len() > 1 {
        let mae = pred
            .iter()
            .zip(truth)
            .map(|(p, t)| (p[2] - t[2]).abs())
            .sum::<f64>()
            / n;
        let (mp, mt) = (
            pred.iter().map(|p| p[2]).sum::<f64>() / n,
            truth.iter().map(|t| t[2]).sum::<f64>() / n,
        );
        let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
        for (p, t) in pred.iter().zip(truth) {
            sxy += (p[2] - mp) * (t[2] - mt);
            sxx += (p[2] - mp).powi(2);
            syy += (t[2] - mt).powi(2);
        }
        let r = if sxx > 0.0 && syy > 0.0 {
            sxy / (sxx * syy).sqrt()
        } else {
            0.0
        };
        (mae, r)
    } else {
        (0.0, 0.0)
    };
    ErrorSummary {
        mean_mm,
        median_mm,
        p90_mm,
        pressure_mae_kpa: mae,
        pressure_r: r,
    }
}
