//! Pictures of a trained model: its confusion matrix, its error against distance from the
//! electrodes.

use std::path::Path;

use et_learn::cv::Confusion;
use et_learn::pipeline::Tested;

use super::PlotError;

/// Writes the confusion matrix as a heat map (each true class's row as shares, %).
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn confusion(path: &Path, confusion: &Confusion, title: &str) -> Result<(), PlotError> {
    let classes = confusion.classes;
    let row_share: Vec<f64> = confusion
        .counts
        .chunks(classes.max(1))
        .flat_map(|row| {
            let n = row.iter().sum::<u32>().max(1);
            row.iter()
                .map(move |&v| 100.0 * f64::from(v) / f64::from(n))
        })
        .collect();
    super::heatmap(
        path,
        super::Labels {
            title,
            x: "predicted class",
            y: "true class",
            legend: super::Legend::UpperLeft,
        },
        &row_share,
        (classes, classes),
        (0.0, 100.0),
        "share of the true class (%)",
    )
}

/// Writes position error against distance from the electrodes: every observation, and the
/// mean per band.
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn error_vs_distance(path: &Path, tested: &Tested) -> Result<(), PlotError> {
    super::chart(
        path,
        super::Labels {
            title: "position error against distance from the electrodes",
            x: "distance of the true class from the nearest electrode (mm)",
            y: "position error (mm)",
            legend: super::Legend::UpperRight,
        },
        &[
            super::Series {
                label: "observations".into(),
                points: tested
                    .outcomes
                    .iter()
                    .map(|o| (o.distance_mm, o.error_mm))
                    .collect(),
                scatter: true,
            },
            super::Series {
                label: "mean per 10 mm band".into(),
                points: tested
                    .bands
                    .iter()
                    .map(|b| (0.5 * (b.from_mm + b.to_mm), b.mean_error_mm))
                    .collect(),
                scatter: false,
            },
        ],
    )
}
