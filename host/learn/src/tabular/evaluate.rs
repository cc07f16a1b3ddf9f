//! A table model scored on rows it did not train on.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

/// How a model did on a table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// Rows evaluated.
    pub observations: usize,
    /// The model's method.
    pub method: Kind,
    /// Mean distance (x, y) from the true position to the predicted one, mm (for classes:
    /// to the predicted class's position).
    pub mean_error_mm: Option<f64>,
    /// Median of the same.
    pub median_error_mm: Option<f64>,
    /// 90th percentile of the same.
    pub p90_error_mm: Option<f64>,
    /// Mean distance in (x, y, z), mm, when z is predicted.
    pub mean_error_3d_mm: Option<f64>,
    /// Mean absolute error of the third target (z mm, or force as given).
    pub third_mae: Option<f64>,
    /// A constant predictor's mean error (the training mean position), mm: the floor to beat.
    pub mean_predictor_error_mm: Option<f64>,
    /// Share of rows whose class is right (classifiers, when the rows have labels or the
    /// model's grid can place them).
    pub accuracy: Option<f64>,
    /// The rows' labels the model has no class of (each once, in order of first row): their
    /// rows count as missed in `accuracy`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unknown_labels: Vec<String>,
    /// What to say when many of the rows are rows the model was trained on
    /// ([`TableModel::trained_note`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub trained_note: Option<String>,
    /// What to say when the rows' features are far larger or smaller than the training's
    /// (another unit or gain; [`TableModel::features_scale_note`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale_note: Option<String>,
    /// What to say when the rows' positions span more than any sheet or less than a finger
    /// in the unit they were read in (mm read as m, m as mm; [`Table::positions_scale_note`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit_note: Option<String>,
    /// Per group (session) of the rows, when they have groups: its rows' errors.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub per_group: Option<Vec<GroupScore>>,
    /// Seconds the training took (from the model file).
    pub fit_seconds: f64,
    /// Seconds to predict every row.
    pub predict_seconds: f64,
    /// Per row: true and predicted (x, y) in mm, where both exist (for plots).
    #[serde(skip)]
    pub pairs: Vec<([f64; 2], [f64; 2])>,
    /// Every row's prediction, in row order.
    #[serde(skip)]
    pub predictions: Vec<Prediction>,
}

/// How a model did on one group's rows.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GroupScore {
    /// The group as written.
    pub group: String,
    /// Its rows.
    pub observations: usize,
    /// Mean position error, mm.
    pub mean_error_mm: Option<f64>,
    /// Median position error, mm.
    pub median_error_mm: Option<f64>,
}

/// Evaluates `model` on `table`: position errors when the rows have positions, accuracy for
/// classifiers when the rows have labels the model knows (an unknown label counts as missed)
/// or positions its grid places.
///
/// # Errors
/// [`TabularError::Usage`] when the features do not match, or the rows have no target the
/// model predicts.
pub fn evaluate(model: &TableModel, table: &Table) -> Result<Evaluation, TabularError> {
    let reordered = aligned(model, table)?;
    let table = reordered.as_ref().unwrap_or(table);
    // The rows as given, as the training kept them (before any standardisation per group).
    let trained_note = model.trained_note(&table.x);
    let standardised;
    let table = if model.per_group {
        standardised = table.standardised_per_group()?;
        &standardised
    } else {
        table
    };
    let started = std::time::Instant::now();
    let pred = model.predict(&table.x)?;
    let predict_seconds = started.elapsed().as_secs_f64();
    let truth = table.targets();
    let accuracy = accuracy(model, table, &pred);
    // Positions score only a model that predicts them (a regressor, or classes with centres).
    let positions_scored = truth.is_some() && pred.iter().any(|p| p.target.is_some());
    if !positions_scored && accuracy.is_none() {
        return Err(usage(if model.method.is_classifier() {
            Misuse::NoLabelTarget
        } else {
            Misuse::NoPositionTarget
        }));
    }
    let z_is_length = model.third_is_length();
    let groups = table.group_index();
    let Errors {
        pairs,
        mut errors,
        errors3,
        third,
        by_group,
    } = errors(model, table, (truth.as_deref(), &pred), groups.as_ref());
    let mean = |v: &[f64]| (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64);
    errors.sort_by(f64::total_cmp);
    let quantile = |f: f64| {
        (!errors.is_empty()).then(|| {
            errors
                .get(((errors.len() as f64 - 1.0) * f).round() as usize)
                .copied()
                .unwrap_or(0.0)
        })
    };
    let mean_predictor_error_mm = model.training_mean_position().and_then(|c| {
        truth.as_ref().map(|t| {
            t.iter()
                .map(|t| 1e3 * (t[0] - c[0]).hypot(t[1] - c[1]))
                .sum::<f64>()
                / t.len().max(1) as f64
        })
    });
    let per_group = groups.map(|(index, names)| {
        names
            .iter()
            .enumerate()
            .map(|(g, name)| {
                let mut e = by_group.get(g).cloned().unwrap_or_default();
                e.sort_by(f64::total_cmp);
                GroupScore {
                    group: name.clone(),
                    observations: index.iter().filter(|&&i| i == g).count(),
                    mean_error_mm: mean(&e),
                    median_error_mm: e.get(e.len().saturating_sub(1) / 2).copied(),
                }
            })
            .collect()
    });
    Ok(Evaluation {
        scale_note: model.features_scale_note(&table.x),
        unit_note: truth.as_ref().and_then(|_| table.positions_scale_note()),
        trained_note,
        unknown_labels: unknown_labels(model, table),
        per_group,
        observations: table.rows(),
        method: model.method,
        mean_error_mm: mean(&errors),
        median_error_mm: quantile(0.5),
        p90_error_mm: quantile(0.9),
        mean_error_3d_mm: if z_is_length { mean(&errors3) } else { None },
        third_mae: mean(&third),
        mean_predictor_error_mm,
        accuracy,
        fit_seconds: model.fit_seconds,
        predict_seconds,
        pairs,
        predictions: pred,
    })
}

/// Each scored row's errors, mm: (x, y) pairs of truth and prediction for the plots, the
/// position errors, with z, the third target's, and the position errors of each group.
struct Errors {
    pairs: Vec<([f64; 2], [f64; 2])>,
    errors: Vec<f64>,
    errors3: Vec<f64>,
    third: Vec<f64>,
    by_group: Vec<Vec<f64>>,
}

/// The errors of the predictions `pred` against the rows' `truth` (m), for the rows whose
/// prediction has a position; `groups`: each row's group and the groups' names.
fn errors(
    model: &TableModel,
    table: &Table,
    (truth, pred): (Option<&[Target3]>, &[Prediction]),
    groups: Option<&(Vec<usize>, Vec<String>)>,
) -> Errors {
    let z_is_length = model.third_is_length();
    // The scores are for people: positions (and a z) in mm.
    let mm = |v: Target3| {
        [
            v[0] * 1e3,
            v[1] * 1e3,
            v[2] * if z_is_length { 1e3 } else { 1.0 },
        ]
    };
    let mut out = Errors {
        pairs: Vec::new(),
        errors: Vec::new(),
        errors3: Vec::new(),
        third: Vec::new(),
        by_group: vec![Vec::new(); groups.map_or(0, |(_, n)| n.len())],
    };
    let Some(truth) = truth else {
        return out;
    };
    for (r, (t, p)) in truth.iter().zip(pred).enumerate() {
        let Some(q) = p.target else {
            continue;
        };
        let (t, q) = (mm(*t), mm(q));
        let error = (q[0] - t[0]).hypot(q[1] - t[1]);
        out.pairs.push(([t[0], t[1]], [q[0], q[1]]));
        out.errors.push(error);
        if let Some(g) = groups
            .and_then(|(index, _)| index.get(r))
            .and_then(|&g| out.by_group.get_mut(g))
        {
            g.push(error);
        }
        if model.third.is_some() && table.third.is_some() {
            out.third.push((q[2] - t[2]).abs());
            out.errors3.push(error.hypot(q[2] - t[2]));
        }
    }
    out
}

/// The rows' labels a classifier has no class of, each once, in order of first row.
fn unknown_labels(model: &TableModel, table: &Table) -> Vec<String> {
    let mut unknown: Vec<String> = Vec::new();
    if let (Some(info), Some(labels)) = (&model.classes, &table.labels)
        && model.method.is_classifier()
    {
        for l in labels {
            if !info.names.contains(l) && !unknown.contains(l) {
                unknown.push(l.clone());
            }
        }
    }
    unknown
}

/// The share of rows whose predicted class is right: a classifier's, when the rows have labels
/// (a label the model does not know counts as missed) or positions its grid places.
fn accuracy(model: &TableModel, table: &Table, pred: &[Prediction]) -> Option<f64> {
    match (&model.classes, model.method.is_classifier()) {
        (Some(info), true) => {
            let true_class: Option<Vec<Option<u16>>> = if let Some(text) = &table.labels {
                Some(
                    text.iter()
                        .map(|l| info.names.iter().position(|n| n == l).map(|c| c as u16))
                        .collect(),
                )
            } else {
                match (&info.grid, &table.positions) {
                    (Some(g), Some(p)) => Some(
                        p.iter()
                            .map(|&q| {
                                let name = g.name(g.cell(q));
                                info.names.iter().position(|n| *n == name).map(|c| c as u16)
                            })
                            .collect(),
                    ),
                    _ => None,
                }
            };
            true_class.map(|t| {
                let right = t
                    .iter()
                    .zip(pred)
                    .filter(|(t, p)| t.is_some() && **t == p.class)
                    .count();
                right as f64 / t.len().max(1) as f64
            })
        }
        _ => None,
    }
}

/// `table`'s feature columns in the model's order, when both name them and the order differs
/// (None: already in order, or the columns are unnamed and taken by position).
///
/// # Errors
/// [`TabularError::Usage`] when named columns are not the model's: one the model reads is
/// missing, or one the model never saw is there.
pub fn aligned(model: &TableModel, table: &Table) -> Result<Option<Table>, TabularError> {
    let (ours, theirs) = (&model.feature_names, &table.feature_names);
    let positional = |names: &[String]| {
        names
            .iter()
            .enumerate()
            .all(|(i, n)| n.parse::<usize>() == Ok(i + 1))
    };
    if ours == theirs || positional(ours) || positional(theirs) {
        return Ok(None);
    }
    // A model trained when such columns were features (the data read now leaves them out).
    if let Some(name) =
        (ours.iter()).find(|n| !theirs.contains(n) && crate::dataset::not_a_feature(n))
    {
        return Err(usage(Misuse::NotAFeature {
            column: name.clone(),
        }));
    }
    if ours.len() != theirs.len() {
        return Err(usage(Misuse::FeatureCount {
            data: theirs.len(),
            model: ours.len(),
            rows: None,
        }));
    }
    let mut order = Vec::with_capacity(ours.len());
    for name in ours {
        let Some(j) = theirs.iter().position(|t| t == name) else {
            return Err(usage(Misuse::MissingFeature {
                column: name.clone(),
            }));
        };
        order.push(j);
    }
    if let Some(extra) = theirs.iter().find(|t| !ours.contains(t)) {
        return Err(usage(Misuse::ExtraFeature {
            column: extra.clone(),
        }));
    }
    let mut out = table.clone();
    out.x = DMatrix::from_fn(table.x.nrows(), order.len(), |r, c| {
        order
            .get(c)
            .and_then(|&j| table.x.get((r, j)))
            .copied()
            .unwrap_or(f64::NAN)
    });
    out.feature_names = ours.clone();
    Ok(Some(out))
}
