//! The trained table model: its tables, predictions, and its JSON file (`et-table-model`).

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

/// One method with one set of hyperparameters, as cross-validation scored it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// The method.
    pub method: Kind,
    /// Its hyperparameters (name, value).
    pub hyperparameters: BTreeMap<String, f64>,
    /// Cross-validated mean position error, mm (positions, or classes with positions).
    pub cv_mean_error_mm: Option<f64>,
    /// Cross-validated accuracy (classes).
    pub cv_accuracy: Option<f64>,
    /// Regressors: the cross-validated mean error of each group's rows (with groups), else of
    /// each of [`STABILITY_BLOCKS`] contiguous blocks of rows in file order, mm: how steady
    /// the error is over the recording.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cv_block_errors_mm: Option<Vec<f64>>,
    /// Regressors: the cross-validated mean error with the held-out rows' channels drifted
    /// ([`DRIFT_GAIN`], [`DRIFT_OFFSET`]; the mean over [`DRIFT_DRAWS`] draws per fold), mm:
    /// how the candidate would take a new session.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cv_drifted_error_mm: Option<f64>,
    /// Regressors, during training only: the out-of-fold prediction of every row, as measured
    /// (n) and drifted ([`DRIFT_DRAWS`] n: draw d's of row r at d n + r), for the average of
    /// the best candidates.
    #[serde(skip)]
    pub(super) out_of_fold: Option<[Vec<Target3>; 2]>,
    /// During training only: why its cross-validation could not be fitted, when it could not.
    #[serde(skip)]
    pub(super) failure: Option<String>,
}

impl Candidate {
    /// `method` at `hyperparameters`, not yet scored.
    #[must_use]
    pub fn new(method: Kind, hyperparameters: BTreeMap<String, f64>) -> Self {
        Self {
            method,
            hyperparameters,
            cv_mean_error_mm: None,
            cv_accuracy: None,
            cv_block_errors_mm: None,
            cv_drifted_error_mm: None,
            out_of_fold: None,
            failure: None,
        }
    }

    /// Smaller is better: the mean error for positions, else 1 - accuracy.
    #[must_use]
    pub fn loss(&self) -> f64 {
        if self.method.is_classifier() {
            // Not fitted in cross-validation: never chosen (as 1.0, it was, and its model
            // written as "could not be fitted").
            self.cv_accuracy.map_or(f64::INFINITY, |a| 1.0 - a)
        } else {
            self.cv_mean_error_mm.unwrap_or(f64::INFINITY)
        }
    }

    /// What `auto` minimises: `loss()`, or for a regressor chosen `by_drift` its plain
    /// cross-validated error P and its error D with the held-out channels drifted weighed
    /// together, P^(1 - w) D^w with w = [`DRIFT_WEIGHT`] (infinite without D).
    #[must_use]
    pub fn choice_loss(&self, by_drift: bool) -> f64 {
        if by_drift && !self.method.is_classifier() {
            self.cv_drifted_error_mm.map_or(f64::INFINITY, |d| {
                self.loss().powf(1.0 - DRIFT_WEIGHT) * d.powf(DRIFT_WEIGHT)
            })
        } else {
            self.loss()
        }
    }

    /// The standard deviation of the block (or group) errors, mm; infinite without them.
    #[must_use]
    pub fn block_spread_mm(&self) -> f64 {
        match &self.cv_block_errors_mm {
            Some(e) if e.len() >= 2 => {
                let m = e.iter().sum::<f64>() / e.len() as f64;
                (e.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (e.len() - 1) as f64).sqrt()
            }
            _ => f64::INFINITY,
        }
    }
}

/// The fitted tables of each method (z-space: features standardised by `feature_mean`,
/// `feature_scale`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case")]
pub enum Tables {
    /// QDA or LDA: the same class tables as et's board models (see `model_file`).
    Discriminant {
        /// QDA or LDA.
        kind: ModelKind,
        /// Per class, in the order of `classes.names`.
        classes: Vec<ClassRecord>,
    },
    /// (x, y, third) = intercept + W^T z.
    Ridge {
        /// p rows of 3 weights.
        weights: Vec<[f64; 3]>,
        /// Targets' training mean.
        intercept: [f64; 3],
    },
    /// (x, y, third) = intercept + sum_i alpha_i exp(-gamma |z - s_i|^2).
    KernelRidge {
        /// gamma, per squared z-distance.
        gamma: f64,
        /// m support rows s_i (z-space).
        support: Vec<Vec<f64>>,
        /// m rows of 3 weights.
        alpha: Vec<[f64; 3]>,
        /// Targets' training mean.
        intercept: [f64; 3],
    },
    /// (x, y, third) = intercept + sum_i alpha_i exp(-1/2 sum_l ((z_l - s_il) / l_l)^2).
    Gp {
        /// The learned length scale l_l of each feature (z-space units).
        length_scales: Vec<f64>,
        /// The learned signal and noise variances (standardised positions' units).
        signal_variance: f64,
        /// (as above)
        noise_variance: f64,
        /// m support rows s_i (z-space).
        support: Vec<Vec<f64>>,
        /// m rows of 3 weights.
        alpha: Vec<[f64; 3]>,
        /// Targets' training mean.
        intercept: [f64; 3],
    },
    /// A multilayer perceptron on the z-space features: hidden layers with `activation`, a
    /// linear output layer of 3; its outputs times `target_scale` plus `target_mean`.
    Mlp {
        /// The hidden layers' nonlinearity.
        activation: Activation,
        /// Hidden layers, then the output layer (weights: one row per input).
        layers: Vec<Dense>,
        /// Targets' training mean (x m, y m, third).
        target_mean: [f64; 3],
        /// Targets' training standard deviation.
        target_scale: [f64; 3],
    },
    /// The mean of several regressors' predictions, each with its own standardisation.
    Average {
        /// The regressors averaged.
        members: Vec<Member>,
    },
    /// The (weighted) mean target of the k nearest support rows.
    Knn {
        /// k.
        k: usize,
        /// Uniform or inverse-distance.
        weighting: Weighting,
        /// m support rows (z-space).
        support: Vec<Vec<f64>>,
        /// Their targets (x m, y m, third).
        targets: Vec<[f64; 3]>,
    },
}

/// One regressor of an [`Tables::Average`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Member {
    /// Its method.
    pub method: Kind,
    /// Its hyperparameters.
    pub hyperparameters: BTreeMap<String, f64>,
    /// Its standardisation of the features.
    pub feature_mean: Vec<f64>,
    /// (as above)
    pub feature_scale: Vec<f64>,
    /// Its tables.
    pub tables: Tables,
}

/// What a classifier's classes are.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassInfo {
    /// The user's class names (or grid cells `r<row>c<col>`), in class order.
    pub names: Vec<String>,
    /// Each class's position, m (its training rows' mean position, or the grid cell's
    /// centre), when the data had positions (version 1 files: `centres_mm`, converted on
    /// reading).
    #[serde(rename = "centres_m")]
    pub centres: Option<Vec<[f64; 2]>>,
    /// The grid, when the classes were made from positions.
    pub grid: Option<Grid>,
    /// What the names were before they were written as text, so that a reader gives them
    /// back as given: "int", "float", "bool", "bytes" (UTF-8 text) or "str" (the Python
    /// module writes it; absent
    /// from files the command line trained, whose names are the file's text).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub label_type: Option<String>,
}

/// A model trained on a table, as saved (JSON; every field documented for Python and MATLAB
/// readers in docs/guide.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableModel {
    /// Always "et-table-model".
    pub format: String,
    /// 2 (version 1 held positions in mm; it is read and converted).
    pub version: u32,
    /// The method.
    pub method: Kind,
    /// Feature column names, in order (p of them).
    pub feature_names: Vec<String>,
    /// Training mean of each feature (the standardisation).
    pub feature_mean: Vec<f64>,
    /// Training standard deviation of each feature (1 for a constant one).
    pub feature_scale: Vec<f64>,
    /// The unit positions were given in (the tables hold m, whatever it was).
    pub unit: Unit,
    /// Name of the third target predicted beside x and y (z, force), if any.
    pub third: Option<String>,
    /// Classes, for QDA and LDA.
    pub classes: Option<ClassInfo>,
    /// The hyperparameters chosen.
    pub hyperparameters: BTreeMap<String, f64>,
    /// Every candidate cross-validation scored, the chosen one included.
    pub search: Vec<Candidate>,
    /// Cross-validation folds and scheme.
    pub cv_folds: usize,
    /// How rows were dealt to folds.
    pub cv_scheme: CvScheme,
    /// The training rows (0-based, half open, in the files).
    pub trained_rows: [usize; 2],
    /// The training files, as imported.
    pub source: String,
    /// Seconds the training took (search and final fit).
    pub fit_seconds: f64,
    /// Whether the regressor and its hyperparameters were chosen with both cross-validated
    /// errors in view, plain and with the held-out rows' channels drifted
    /// ([`Candidate::choice_loss`]), as they are without groups, rather than by the plain
    /// cross-validated error alone.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub chosen_by_drift: bool,
    /// Whether each group's features were standardised by the group's own statistics (then
    /// evaluation does the same to each group of the rows it scores).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub per_group: bool,
    /// How the features were referenced to frames before each press, when they were (the
    /// evaluation's rows need the same references).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Referencing>,
    /// Fingerprints of up to [`SEEN_SAMPLE`] of its training rows (16 hex digits each,
    /// FNV-1a of the features' bits), by which evaluated rows that are training rows are said
    /// ([`TableModel::trained_note`]); absent from files written before.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub seen: Vec<String>,
    /// What the training changed from the request, and why (e.g. a QDA saved as the LDA it
    /// equals); absent when nothing.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// The fitted tables.
    pub tables: Tables,
}

/// One prediction.
#[derive(Clone, Debug, PartialEq)]
pub struct Prediction {
    /// The class (classifiers).
    pub class: Option<u16>,
    /// The position (x, y m) and third target: a regressor's estimate, or the class's
    /// centre; None for a classifier without class positions.
    pub target: Option<Target3>,
}

/// A model rebuilt from its tables, ready to predict.
#[derive(Debug)]
pub(super) enum Ready {
    Discriminant(Fitted),
    Ridge(Ridge),
    KernelRidge(KernelRidge),
    Knn(Knn),
    Mlp(Mlp),
    Average(Vec<Prepared>),
}

/// A table model's tables checked and rebuilt, once, into the fitted model they describe
/// ([`TableModel::prepare`]): predicting with it costs the arithmetic alone, where
/// [`TableModel::predict`] rebuilds the model on every call (an average of three kinds on 2 000
/// training rows spends about 10 ms doing so, whatever the rows predicted).
#[derive(Debug)]
pub struct Prepared {
    /// Features it reads per row (p).
    features: usize,
    /// A classifier's class centres (m), for the positions it reports.
    centres: Option<Vec<[f64; 2]>>,
    ready: Ready,
}

impl TableModel {
    /// Features it reads per row.
    #[must_use]
    pub fn features(&self) -> usize {
        self.feature_mean.len()
    }

    /// The model rebuilt from its tables, to predict many times.
    ///
    /// # Errors
    /// [`TabularError::Tables`] when the model's tables are inconsistent.
    pub fn prepare(&self) -> Result<Prepared, TabularError> {
        Ok(Prepared {
            features: self.features(),
            centres: self.classes.as_ref().and_then(|c| c.centres.clone()),
            ready: self.ready()?,
        })
    }

    /// Predicts every row of `x` (n x p, the training files' units), rebuilding the model
    /// first: to predict many times, [`prepare`](Self::prepare) once. A model trained with
    /// `per_group` reads rows already standardised per session
    /// ([`Table::standardised_per_group`]; [`evaluate`] does it).
    ///
    /// # Errors
    /// [`TabularError::Usage`] when `x` has another feature count, [`TabularError::Tables`]
    /// when the model's tables are inconsistent.
    pub fn predict(&self, x: &DMatrix<f64>) -> Result<Vec<Prediction>, TabularError> {
        if x.ncols() != self.features() {
            return Err(usage(Misuse::FeatureCount {
                data: x.ncols(),
                model: self.features(),
                rows: Some(x.nrows()),
            }));
        }
        self.prepare()?.predict(x)
    }
}

impl TableModel {
    /// Writes JSON.
    ///
    /// # Errors
    /// [`TabularError::Model`] naming the file.
    pub fn save(&self, path: &Path) -> Result<(), TabularError> {
        let err = |source: TableModelError| TabularError::Model {
            path: path.into(),
            source,
        };
        let text = serde_json::to_string(self).map_err(|e| err(e.into()))?;
        std::fs::write(path, text).map_err(|e| err(e.into()))
    }

    /// Reads and checks JSON written by [`save`](Self::save).
    ///
    /// # Errors
    /// [`TabularError::Model`] naming the file and what is wrong.
    pub fn load(path: &Path) -> Result<Self, TabularError> {
        let err = |source: TableModelError| TabularError::Model {
            path: path.into(),
            source,
        };
        let text = et_core::text::read_document_at_most(path, et_core::text::max_file_bytes())
            .map_err(|e| err(e.into()))?;
        Self::from_json(&text).map_err(err)
    }

    /// Parses and checks a model's JSON.
    ///
    /// # Errors
    /// [`TableModelError`]: not JSON of this shape, another format, or inconsistent tables.
    pub fn from_json(text: &str) -> Result<Self, TableModelError> {
        Self::from_value(serde_json::from_str(text)?)
    }

    /// Checks a model's parsed JSON ([`from_json`](Self::from_json)).
    ///
    /// # Errors
    /// As [`from_json`](Self::from_json).
    pub fn from_value(mut value: serde_json::Value) -> Result<Self, TableModelError> {
        // The format and version first: a later version's fields are not this one's.
        let format = value.get("format").and_then(serde_json::Value::as_str);
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        let known = version == Some(1) || version == Some(u64::from(TABLE_MODEL_VERSION));
        if format != Some("et-table-model") || !known {
            return Err(TableModelError::Format(crate::model_file::format_found(
                &value,
            )));
        }
        if version == Some(1) {
            mm_names_to_metres(&mut value);
        }
        let mut m: TableModel = crate::model_file::from_value_named(value)?;
        if m.version == 1 {
            m.migrate_to_metres();
        }
        m.ready()?;
        m.check_record()?;
        Ok(m)
    }

    /// Whether the third target is a length (z: in m like x and y, in mm where people read
    /// it), rather than a value as the files wrote it.
    #[must_use]
    pub fn third_is_length(&self) -> bool {
        self.third.as_deref().is_some_and(crate::dataset::is_length)
    }

    /// A version 1 model (positions in mm) made the current version (m): every table on the
    /// targets' side scaled, the third target's only when it is a length (z).
    fn migrate_to_metres(&mut self) {
        let s = [1e-3, 1e-3, if self.third_is_length() { 1e-3 } else { 1.0 }];
        self.tables.scale_targets(s);
        if let Some(c) = &mut self.classes {
            for q in c.centres.iter_mut().flatten() {
                *q = [q[0] * 1e-3, q[1] * 1e-3];
            }
            if let Some(g) = &mut c.grid {
                g.bounds = g.bounds.map(|b| b * 1e-3);
            }
        }
        self.version = TABLE_MODEL_VERSION;
    }
}

/// The table model file's version: 2, positions in m.
pub const TABLE_MODEL_VERSION: u32 = 2;

/// A version 1 file's mm field names given the current version's m names (the values are
/// scaled after parsing, [`TableModel::migrate_to_metres`]).
fn mm_names_to_metres(value: &mut serde_json::Value) {
    let rename = |o: Option<&mut serde_json::Value>, from: &str, to: &str| {
        if let Some(o) = o.and_then(serde_json::Value::as_object_mut)
            && let Some(v) = o.remove(from)
        {
            o.insert(to.into(), v);
        }
    };
    let classes = value.get_mut("classes");
    rename(classes, "centres_mm", "centres_m");
    let grid = value.get_mut("classes").and_then(|c| c.get_mut("grid"));
    rename(grid, "bounds_mm", "bounds_m");
}

impl Tables {
    /// Multiplies every value on the targets' side by `s` (x, y, third): intercepts, weights
    /// into the targets, the perceptron's target standardisation, the neighbours' targets.
    fn scale_targets(&mut self, s: [f64; 3]) {
        let scale = |r: &mut [f64; 3]| {
            for (v, k) in r.iter_mut().zip(s) {
                *v *= k;
            }
        };
        match self {
            Tables::Discriminant { .. } => {}
            Tables::Ridge { weights, intercept } => {
                weights.iter_mut().for_each(scale);
                scale(intercept);
            }
            Tables::KernelRidge {
                alpha, intercept, ..
            }
            | Tables::Gp {
                alpha, intercept, ..
            } => {
                alpha.iter_mut().for_each(scale);
                scale(intercept);
            }
            Tables::Mlp {
                target_mean,
                target_scale,
                ..
            } => {
                scale(target_mean);
                scale(target_scale);
            }
            Tables::Average { members } => {
                for m in members {
                    m.tables.scale_targets(s);
                }
            }
            Tables::Knn { targets, .. } => targets.iter_mut().for_each(scale),
        }
    }
}

/// Why a table model's JSON is not a usable model.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TableModelError {
    /// Not JSON, or not a table model's fields.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// Another format or version (what the file says instead).
    #[error("not an et-table-model file of version 1 or 2 ({0}; a later version is a newer et's)")]
    Format(String),
    /// The tables disagree in shape, hold a non-finite value, or do not fit the method.
    #[error(transparent)]
    Tables(#[from] TablesError),
    /// The file could not be written or read (said as the system says it, and kept as the
    /// cause, so a closed pipe is seen as one).
    #[error("{0}")]
    Io(#[from] std::io::Error),
}

impl TableModel {
    /// The search's candidate that was chosen (what cross-validation said of it). Its
    /// hyperparameters are among the model's, which may add learned ones (the Gaussian
    /// process's variances).
    #[must_use]
    pub fn chosen(&self) -> Option<&Candidate> {
        self.search.iter().find(|c| {
            c.method == self.method
                && (c.hyperparameters.iter()).all(|(k, v)| self.hyperparameters.get(k) == Some(v))
        })
    }

    /// The mean training position, m (regressors: their intercept or targets' mean; classes:
    /// the count-weighted class positions), when known.
    #[must_use]
    pub fn training_mean_position(&self) -> Option<[f64; 2]> {
        match &self.tables {
            Tables::Ridge { intercept, .. }
            | Tables::KernelRidge { intercept, .. }
            | Tables::Gp { intercept, .. } => Some([intercept[0], intercept[1]]),
            Tables::Mlp { target_mean, .. } => Some([target_mean[0], target_mean[1]]),
            Tables::Average { .. } => self.members().first()?.training_mean_position(),
            Tables::Knn { targets, .. } => {
                let n = targets.len().max(1) as f64;
                Some(
                    targets
                        .iter()
                        .fold([0.0, 0.0], |a, t| [a[0] + t[0] / n, a[1] + t[1] / n]),
                )
            }
            Tables::Discriminant { classes, .. } => {
                let centres = self.classes.as_ref()?.centres.as_ref()?;
                let n = classes.iter().map(|c| c.count).sum::<usize>().max(1) as f64;
                Some(classes.iter().zip(centres).fold([0.0, 0.0], |a, (c, q)| {
                    let w = c.count as f64 / n;
                    [a[0] + w * q[0], a[1] + w * q[1]]
                }))
            }
        }
    }
}

mod fit;
mod predict;
mod ready;
mod scale;
mod seen;
pub use crate::fingerprint::{SEEN_SAID, SEEN_SAMPLE, seen_sample, seen_share};
pub use scale::{FEATURE_SCALE_SAID, features_scale, features_scale_note};

pub use ready::TablesError;

pub(super) use fit::fit_final;
