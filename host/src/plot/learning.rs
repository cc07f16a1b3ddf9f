//! Pictures of a trained model: its confusion matrix, its error against distance from the
//! electrodes.

use std::path::Path;

use et_learn::cv::Confusion;
use et_learn::model::Tested;

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

/// Writes the error against position: each true position (x, y mm) as a dot coloured by its
/// position error (viridis, 0 to the largest error, stated in the title).
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn error_map(
    path: &Path,
    pairs: &[([f64; 2], [f64; 2])],
    title: &str,
) -> Result<(), PlotError> {
    use plotters::prelude::*;
    let err = |p: &([f64; 2], [f64; 2])| (p.1[0] - p.0[0]).hypot(p.1[1] - p.0[1]);
    let top = pairs.iter().map(err).fold(0.0f64, f64::max).max(1e-9);
    let (x0, x1) = super::range(pairs.iter().map(|p| p.0[0]), false);
    let (y0, y1) = super::range(pairs.iter().map(|p| p.0[1]), false);
    // Equal scales on both axes: the sheet keeps its shape.
    let side = (x1 - x0).max(y1 - y0);
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let caption = format!("{title} (colour: position error, 0 to {top:.1} mm)");
    super::render(path, (720, 680), |root| {
        let mut c = ChartBuilder::on(root)
            .caption(caption, ("sans-serif", 18))
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(
                (cx - side / 2.0)..(cx + side / 2.0),
                (cy - side / 2.0)..(cy + side / 2.0),
            )
            .map_err(|e| super::fail(path, e))?;
        c.configure_mesh()
            .x_desc("true x (mm)")
            .y_desc("true y (mm)")
            .label_style(("sans-serif", 14))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(|e| super::fail(path, e))?;
        c.draw_series(
            pairs
                .iter()
                .filter(|p| err(p).is_finite())
                .map(|p| Circle::new((p.0[0], p.0[1]), 4, super::viridis(err(p) / top).filled())),
        )
        .map_err(|e| super::fail(path, e))?;
        Ok(())
    })
}

/// Writes predicted against true coordinates (x and y, mm) with the identity line.
///
/// # Errors
/// [`PlotError`] naming the file.
pub fn predicted_vs_true(
    path: &Path,
    pairs: &[([f64; 2], [f64; 2])],
    title: &str,
) -> Result<(), PlotError> {
    let (lo, hi) = super::range(
        pairs.iter().flat_map(|p| [p.0[0], p.0[1], p.1[0], p.1[1]]),
        false,
    );
    super::chart(
        path,
        super::Labels {
            title,
            x: "true coordinate (mm)",
            y: "predicted coordinate (mm)",
            legend: super::Legend::UpperLeft,
        },
        &[
            super::Series {
                label: "x".into(),
                points: pairs.iter().map(|p| (p.0[0], p.1[0])).collect(),
                scatter: true,
            },
            super::Series {
                label: "y".into(),
                points: pairs.iter().map(|p| (p.0[1], p.1[1])).collect(),
                scatter: true,
            },
            super::Series {
                label: "predicted = true".into(),
                points: vec![(lo, lo), (hi, hi)],
                scatter: false,
            },
        ],
    )
}
