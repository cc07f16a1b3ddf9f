//! What the accuracy depends on (docs/method.md §9's observations): error against distance from the
//! electrodes, and learning curves against n_c (observations per class).

use nalgebra::DMatrix;

use super::cv::Confusion;
use super::fit::{FitError, FitOptions, Fitted};

/// Distance from `p` to the nearest of `electrodes` (same units; infinite when there are none).
#[must_use]
pub fn electrode_distance(p: [f64; 2], electrodes: &[[f64; 2]]) -> f64 {
    electrodes
        .iter()
        .map(|e| (p[0] - e[0]).hypot(p[1] - e[1]))
        .fold(f64::INFINITY, f64::min)
}

/// One test observation's outcome.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Distance of the true class centre from the nearest electrode, mm.
    pub distance_mm: f64,
    /// Distance between the true and the predicted class centre, mm (0 when right).
    pub error_mm: f64,
}

/// Per observation, how far its class lies from the electrodes and how far off its
/// prediction `predicted` (one class per label in `y`) was. `centres_mm` and `electrodes_mm`
/// in mm.
///
/// # Errors
/// [`FitError::Label`] for a label or prediction that is not one of the classes, [`FitError::Counts`] for counts
/// that differ.
pub fn outcomes(
    predicted: &[u16],
    y: &[u16],
    centres_mm: &[[f64; 2]],
    electrodes_mm: &[[f64; 2]],
) -> Result<Vec<Outcome>, FitError> {
    if predicted.len() != y.len() {
        return Err(FitError::Counts {
            what: "predictions",
            got: predicted.len(),
            expected: y.len(),
            of: "labels",
        });
    }
    y.iter()
        .zip(predicted)
        .enumerate()
        .map(|(r, (&label, &p))| {
            let class = |c: u16| {
                centres_mm
                    .get(usize::from(c))
                    .copied()
                    .ok_or(FitError::Label {
                        row: r,
                        label: usize::from(c),
                        classes: centres_mm.len(),
                    })
            };
            let (t, p) = (class(label)?, class(p)?);
            Ok(Outcome {
                distance_mm: electrode_distance(t, electrodes_mm),
                error_mm: (t[0] - p[0]).hypot(t[1] - p[1]),
            })
        })
        .collect()
}

/// One distance band.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Band {
    /// Band from this distance, mm.
    pub from_mm: f64,
    /// To this distance, mm.
    pub to_mm: f64,
    /// Observations in it.
    pub count: usize,
    /// Fraction predicted right.
    pub accuracy: f64,
    /// Mean position error, mm.
    pub mean_error_mm: f64,
}

/// Groups outcomes into bands of `width_mm` of distance from the electrodes (empty bands left
/// out).
#[must_use]
pub fn by_distance(outcomes: &[Outcome], width_mm: f64) -> Vec<Band> {
    let width = if width_mm > 0.0 { width_mm } else { 1.0 };
    let mut bands: Vec<Band> = Vec::new();
    for o in outcomes.iter().filter(|o| o.distance_mm.is_finite()) {
        let b = (o.distance_mm / width).floor() as usize;
        if bands.len() <= b {
            bands.extend((bands.len()..=b).map(|i| Band {
                from_mm: i as f64 * width,
                to_mm: (i + 1) as f64 * width,
                count: 0,
                accuracy: 0.0,
                mean_error_mm: 0.0,
            }));
        }
        let band = &mut bands[b];
        band.count += 1;
        band.accuracy += f64::from(u8::from(o.error_mm == 0.0));
        band.mean_error_mm += o.error_mm;
    }
    bands.retain(|b| b.count > 0);
    for b in &mut bands {
        b.accuracy /= b.count as f64;
        b.mean_error_mm /= b.count as f64;
    }
    bands
}

/// Rows keeping at most `n_c` observations of every class, spread evenly over each class's
/// observations in order (so every visit keeps its share).
#[must_use]
pub fn per_class_subset(y: &[u16], classes: usize, n_c: usize) -> Vec<usize> {
    let mut of_class: Vec<Vec<usize>> = vec![Vec::new(); classes];
    for (r, &c) in y.iter().enumerate() {
        if let Some(v) = of_class.get_mut(usize::from(c)) {
            v.push(r);
        }
    }
    let mut rows: Vec<usize> = of_class
        .iter()
        .flat_map(|rows| {
            let take = n_c.min(rows.len());
            (0..take).map(move |i| rows[i * rows.len() / take.max(1)])
        })
        .collect();
    rows.sort_unstable();
    rows
}

/// One point of a learning curve.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CurvePoint {
    /// Observations per class used.
    pub n_c: usize,
    /// Held-out accuracy (None: the fit failed at this size, e.g. too few observations for
    /// an unshrunk covariance).
    pub accuracy: Option<f64>,
}

/// Accuracy against n_c: for each size, the rows of [`per_class_subset`] are scored by
/// `score` (e.g. leave-one-visit-out cross-validation on those rows).
pub fn learning_curve(
    y: &[u16],
    classes: usize,
    sizes: &[usize],
    mut score: impl FnMut(&[usize]) -> Result<Confusion, FitError>,
) -> Vec<CurvePoint> {
    sizes
        .iter()
        .map(|&n_c| {
            let rows = per_class_subset(y, classes, n_c);
            CurvePoint {
                n_c,
                accuracy: score(&rows).ok().map(|c| c.accuracy()),
            }
        })
        .collect()
}

/// Rows `rows` of `x`.
#[must_use]
pub fn select_rows(x: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), x.ncols(), |r, j| x[(rows[r], j)])
}

/// Columns `cols` of `x`.
#[must_use]
pub fn select_columns(x: &DMatrix<f64>, cols: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(x.nrows(), cols.len(), |r, j| x[(r, cols[j])])
}

/// Fits on `rows` of a training set and evaluates on a test set: the building block of a
/// learning curve against a separate (next-day) test set.
///
/// # Errors
/// [`FitError`] from the fit or the evaluation.
pub fn fit_rows_and_test(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
    opts: &FitOptions,
    rows: &[usize],
    test: (&DMatrix<f64>, &[u16]),
) -> Result<Confusion, FitError> {
    let ys: Vec<u16> = rows.iter().map(|&r| y[r]).collect();
    let model = Fitted::fit(&select_rows(x, rows), &ys, classes, opts)?;
    super::cv::evaluate(&model, test.0, test.1)
}
