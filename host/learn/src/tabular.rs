//! Any sensor's table in, touch positions out: learning from data that et did not collect.
//!
//! A [`Table`] is n rows of p features (any channel count) with a target per row: a class
//! label (any text), a position (x, y in mm; files may be in metres) with an optional third
//! value (z, force), or both. [`train`] fits one [`Method`] (or tries several with
//! [`Choice::Auto`]) with its hyperparameters chosen by cross-validation inside the training
//! rows only ([`CvScheme::Shuffled`]: stratified for classes; [`CvScheme::Blocks`]:
//! contiguous blocks, for recordings where presses drift over time), and returns a
//! [`TableModel`] that saves as JSON and predicts new rows; [`evaluate`] scores it on other
//! rows.
//!
//! Every model standardises its features with the training rows' mean and standard deviation
//! and stores them. Positions are millimetres inside; the model remembers the unit of the
//! files it was trained on.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use et_core::model::ModelKind;
use faer::Mat;
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::cv::{self, Confusion};
use super::dataset::{DatasetError, import_csv};
use super::fastcv::cross_validate_fast;
use super::fit::{FitError, FitOptions, Fitted, Target};
use super::gp::{Gp, GpOptions};
use super::model_file::{ClassRecord, class_records, fitted_from_records};
use super::regress::{self, KernelRidge, Knn, Ridge, Target3, Weighting, summarise};

/// Why a table could not be used.
#[derive(Debug)]
#[non_exhaustive]
pub enum TabularError {
    /// A file could not be read, or its content is wrong (names the file, line, column).
    Dataset(DatasetError),
    /// A fit failed.
    Fit(FitError),
    /// The request does not fit the data (e.g. a regressor without positions).
    Usage(String),
    /// A model file is not JSON, or not an et table model.
    Model {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

impl std::fmt::Display for TabularError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TabularError::Dataset(e) => write!(f, "{e}"),
            TabularError::Fit(e) => write!(f, "{e}"),
            TabularError::Usage(m) => write!(f, "{m}"),
            TabularError::Model { path, message } => write!(f, "{}: {message}", path.display()),
        }
    }
}

impl std::error::Error for TabularError {}

impl From<DatasetError> for TabularError {
    fn from(e: DatasetError) -> Self {
        Self::Dataset(e)
    }
}

impl From<FitError> for TabularError {
    fn from(e: FitError) -> Self {
        Self::Fit(e)
    }
}

fn usage(message: impl Into<String>) -> TabularError {
    TabularError::Usage(message.into())
}

/// The unit of positions in the files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Metres.
    M,
    /// Millimetres.
    #[default]
    Mm,
}

impl Unit {
    /// Millimetres per unit.
    #[must_use]
    pub fn to_mm(self) -> f64 {
        match self {
            Unit::M => 1e3,
            Unit::Mm => 1.0,
        }
    }
}

/// Rows `start..end` (0-based, half open) of a table; `end` None means to the last row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RowRange {
    /// First row.
    pub start: usize,
    /// One past the last row, or None for all that follow.
    pub end: Option<usize>,
}

impl std::str::FromStr for RowRange {
    type Err = String;

    /// `A..B`, `A..` or `..B`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once("..")
            .ok_or_else(|| format!("'{s}': write A..B (0-based, B excluded), A.. or ..B"))?;
        let num = |v: &str, default: Option<usize>| -> Result<Option<usize>, String> {
            match v.trim() {
                "" => Ok(default),
                v => v
                    .parse::<usize>()
                    .map(Some)
                    .map_err(|_| format!("'{s}': '{v}' is not a row number")),
            }
        };
        let start = num(a, Some(0))?.unwrap_or(0);
        let end = num(b, None)?;
        if end.is_some_and(|e| e <= start) {
            return Err(format!("'{s}': the range is empty"));
        }
        Ok(Self { start, end })
    }
}

impl std::fmt::Display for RowRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.end {
            Some(e) => write!(f, "{}..{e}", self.start),
            None => write!(f, "{}..", self.start),
        }
    }
}

/// Class labels: each row's class index into `names`, the user's own names.
#[derive(Clone, Debug, PartialEq)]
pub struct Labels {
    /// Class of each row, 0..names.len().
    pub index: Vec<u16>,
    /// Class names as written in the file (numbers in numeric order, else sorted).
    pub names: Vec<String>,
}

impl Labels {
    /// Maps labels as written to classes 0..C-1, numbers in numeric order, else sorted.
    ///
    /// # Errors
    /// [`TabularError::Usage`] for more than 65 535 classes.
    pub fn from_text(labels: &[String]) -> Result<Self, TabularError> {
        let mut names: Vec<String> = labels.to_vec();
        names.sort();
        names.dedup();
        if names.iter().all(|n| n.parse::<f64>().is_ok()) {
            names.sort_by(|a, b| {
                a.parse::<f64>()
                    .unwrap_or(0.0)
                    .total_cmp(&b.parse::<f64>().unwrap_or(0.0))
            });
        }
        if names.len() > usize::from(u16::MAX) {
            return Err(usage(format!("{} classes: at most 65535", names.len())));
        }
        let lookup: BTreeMap<&str, u16> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i as u16))
            .collect();
        let index = labels
            .iter()
            .map(|l| lookup.get(l.as_str()).copied().unwrap_or(0))
            .collect();
        Ok(Self { index, names })
    }
}

/// A table of features and targets from any sensor.
#[derive(Clone, Debug)]
pub struct Table {
    /// n x p features, in the file's units (volts, board codes, ...).
    pub x: DMatrix<f64>,
    /// The feature columns' names.
    pub feature_names: Vec<String>,
    /// Class labels as written, when the data has them.
    pub labels: Option<Vec<String>>,
    /// Positions in mm, when the data has them.
    pub positions_mm: Option<Vec<[f64; 2]>>,
    /// A third target (name; values: a length in mm when named z, else as written).
    pub third: Option<(String, Vec<f64>)>,
    /// Which columns were taken as what, and the unit.
    pub description: String,
    /// The first row's index in the file (after `--rows`).
    pub first_row: usize,
}

impl Table {
    /// Imports `features` (and `targets`, a second file with the same rows) as
    /// [`import_csv`] reads them; positions (and a third target named z) are in `unit`.
    ///
    /// # Errors
    /// [`TabularError::Dataset`] naming the file, line and column.
    pub fn import(
        features: &Path,
        targets: Option<&Path>,
        unit: Unit,
    ) -> Result<Self, TabularError> {
        let imported = import_csv(features, targets)?;
        let mm = unit.to_mm();
        let third = imported.third.map(|(name, v)| {
            let length = name.eq_ignore_ascii_case("z");
            let v = if length {
                v.iter().map(|z| z * mm).collect()
            } else {
                v
            };
            (name, v)
        });
        let mut description = format!(
            "{}; positions in {}",
            imported.description,
            match unit {
                Unit::M => "m (read as mm x 1000)",
                Unit::Mm => "mm",
            }
        );
        // Positions in metres read as mm span less than a millimetre: say so.
        if let (Unit::Mm, Some(p)) = (unit, &imported.positions) {
            let span = |i: usize| {
                let (lo, hi) = p
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| {
                        let v = q.get(i).copied().unwrap_or(0.0);
                        (l.min(v), h.max(v))
                    });
                hi - lo
            };
            let widest = span(0).max(span(1));
            if widest > 0.0 && widest < 1.0 {
                description.push_str(&format!(
                    "; note: the positions span only {widest:.3} mm: if they are in metres, \
                     give --unit m"
                ));
            }
        }
        Ok(Self {
            x: imported.x,
            feature_names: imported.feature_names,
            labels: imported.labels,
            positions_mm: imported
                .positions
                .map(|p| p.iter().map(|q| [q[0] * mm, q[1] * mm]).collect()),
            third,
            description,
            first_row: 0,
        })
    }

    /// Rows.
    #[must_use]
    pub fn rows(&self) -> usize {
        self.x.nrows()
    }

    /// The rows of `range` only.
    ///
    /// # Errors
    /// [`TabularError::Usage`] when the range reaches past the table or holds no row.
    pub fn select(&self, range: RowRange) -> Result<Self, TabularError> {
        let n = self.rows();
        let end = range.end.unwrap_or(n);
        if end > n || range.start >= end {
            return Err(usage(format!("--rows {range}: the data has rows 0..{n}")));
        }
        let rows = range.start..end;
        Ok(Self {
            x: self.x.rows(rows.start, rows.len()).into_owned(),
            feature_names: self.feature_names.clone(),
            labels: self
                .labels
                .as_ref()
                .and_then(|l| l.get(rows.clone()).map(<[String]>::to_vec)),
            positions_mm: self
                .positions_mm
                .as_ref()
                .and_then(|p| p.get(rows.clone()).map(<[[f64; 2]]>::to_vec)),
            third: self
                .third
                .as_ref()
                .and_then(|(name, v)| v.get(rows.clone()).map(|v| (name.clone(), v.to_vec()))),
            description: self.description.clone(),
            first_row: self.first_row + range.start,
        })
    }

    /// Targets as (x mm, y mm, third or 0), when the table has positions.
    #[must_use]
    pub fn targets(&self) -> Option<Vec<Target3>> {
        let p = self.positions_mm.as_ref()?;
        Some(
            p.iter()
                .enumerate()
                .map(|(r, q)| {
                    let third = self
                        .third
                        .as_ref()
                        .and_then(|(_, v)| v.get(r).copied())
                        .unwrap_or(0.0);
                    [q[0], q[1], third]
                })
                .collect(),
        )
    }
}

/// A learning method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Quadratic discriminant analysis (classes), shrinkage by cross-validation.
    Qda,
    /// Linear discriminant analysis (classes).
    Lda,
    /// Linear ridge regression (positions), lambda by cross-validation.
    Ridge,
    /// Gaussian-kernel ridge regression (positions), width and lambda by cross-validation.
    KernelRidge,
    /// k nearest neighbours (positions), k and weighting by cross-validation.
    Knn,
    /// Gaussian process with one length scale per feature (positions), every hyperparameter
    /// learned by marginal likelihood (`gp`).
    Gp,
}

impl Method {
    /// The name on the command line and in files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Qda => "qda",
            Method::Lda => "lda",
            Method::Ridge => "ridge",
            Method::KernelRidge => "kernel-ridge",
            Method::Knn => "knn",
            Method::Gp => "gp",
        }
    }

    /// Whether it predicts classes (else positions).
    #[must_use]
    pub fn is_classifier(self) -> bool {
        matches!(self, Method::Qda | Method::Lda)
    }
}

/// What to train.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// One method.
    One(Method),
    /// Every method that fits the targets, the best by cross-validation: regressors for
    /// positions (mean error), classifiers for labels only (accuracy).
    Auto,
}

/// How the training rows are split for cross-validation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CvScheme {
    /// Rows dealt to folds at random (stratified by class for classifiers).
    #[default]
    Shuffled,
    /// Contiguous blocks of rows in file order: for recordings in time order, where presses
    /// drift and a shuffled split flatters a model.
    Blocks,
}

/// A class grid made from positions (`--grid RxC`): the targets' bounding box cut into
/// `rows` x `cols` cells.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// Cells along y.
    pub rows: usize,
    /// Cells along x.
    pub cols: usize,
    /// Bounding box [x0, y0, x1, y1], mm.
    pub bounds_mm: [f64; 4],
}

impl Grid {
    /// The grid over the bounding box of `positions`.
    #[must_use]
    pub fn over(positions: &[[f64; 2]], rows: usize, cols: usize) -> Self {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in positions {
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
        Self {
            rows: rows.max(1),
            cols: cols.max(1),
            bounds_mm: b,
        }
    }

    /// The cell (row-major) of a position, clamped into the grid.
    #[must_use]
    pub fn cell(&self, p: [f64; 2]) -> usize {
        let [x0, y0, x1, y1] = self.bounds_mm;
        let at = |v: f64, lo: f64, hi: f64, n: usize| {
            let f = if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
            ((f * n as f64).floor().max(0.0) as usize).min(n - 1)
        };
        at(p[1], y0, y1, self.rows) * self.cols + at(p[0], x0, x1, self.cols)
    }

    /// The centre of a cell, mm.
    #[must_use]
    pub fn centre(&self, cell: usize) -> [f64; 2] {
        let [x0, y0, x1, y1] = self.bounds_mm;
        let (r, c) = (cell / self.cols, cell % self.cols);
        [
            x0 + (x1 - x0) * (c as f64 + 0.5) / self.cols as f64,
            y0 + (y1 - y0) * (r as f64 + 0.5) / self.rows as f64,
        ]
    }

    /// A cell's name: `r<row>c<col>`, 1-based from the lowest x and y.
    #[must_use]
    pub fn name(&self, cell: usize) -> String {
        format!("r{}c{}", cell / self.cols + 1, cell % self.cols + 1)
    }
}

/// How to train.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainOptions {
    /// Folds of the cross-validation that chooses hyperparameters (and [`Choice::Auto`]'s
    /// method).
    pub folds: usize,
    /// How rows are dealt to folds.
    pub scheme: CvScheme,
    /// Classes from positions: a grid of rows x cols cells over the targets' bounding box.
    pub grid: Option<(usize, usize)>,
    /// Seed of the shuffled folds.
    pub seed: u64,
}

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            folds: 5,
            scheme: CvScheme::Shuffled,
            grid: None,
            seed: 1,
        }
    }
}

/// One method with one set of hyperparameters, as cross-validation scored it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// The method.
    pub method: Method,
    /// Its hyperparameters (name, value).
    pub hyperparameters: BTreeMap<String, f64>,
    /// Cross-validated mean position error, mm (positions, or classes with positions).
    pub cv_mean_error_mm: Option<f64>,
    /// Cross-validated accuracy (classes).
    pub cv_accuracy: Option<f64>,
}

impl Candidate {
    /// Smaller is better: the mean error for positions, else 1 - accuracy.
    fn loss(&self) -> f64 {
        if self.method.is_classifier() {
            1.0 - self.cv_accuracy.unwrap_or(0.0)
        } else {
            self.cv_mean_error_mm.unwrap_or(f64::INFINITY)
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
    /// The (weighted) mean target of the k nearest support rows.
    Knn {
        /// k.
        k: usize,
        /// Uniform or inverse-distance.
        weighting: Weighting,
        /// m support rows (z-space).
        support: Vec<Vec<f64>>,
        /// Their targets (x mm, y mm, third).
        targets: Vec<[f64; 3]>,
    },
}

/// What a classifier's classes are.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassInfo {
    /// The user's class names (or grid cells `r<row>c<col>`), in class order.
    pub names: Vec<String>,
    /// Each class's position, mm (its training rows' mean position, or the grid cell's
    /// centre), when the data had positions.
    pub centres_mm: Option<Vec<[f64; 2]>>,
    /// The grid, when the classes were made from positions.
    pub grid: Option<Grid>,
}

/// A model trained on a table, as saved (JSON; every field documented for Python and MATLAB
/// readers in docs/guide.md).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TableModel {
    /// Always "et-table-model".
    pub format: String,
    /// 1.
    pub version: u32,
    /// The method.
    pub method: Method,
    /// Feature column names, in order (p of them).
    pub feature_names: Vec<String>,
    /// Training mean of each feature (the standardisation).
    pub feature_mean: Vec<f64>,
    /// Training standard deviation of each feature (1 for a constant one).
    pub feature_scale: Vec<f64>,
    /// The unit positions were given in (predictions are reported in mm).
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
    /// The position (x, y mm) and third target: a regressor's estimate, or the class's
    /// centre; None for a classifier without class positions.
    pub target: Option<Target3>,
}

/// Progress of a long training: (what, done, of).
pub type Progress<'a> = &'a mut dyn FnMut(&str, usize, usize);

/// Shrinkage candidates for QDA and LDA.
const SHRINKAGES: [f64; 6] = [0.0, 0.01, 0.03, 0.1, 0.3, 1.0];
/// Ridge's lambda candidates (times n on the z-space Gram matrix).
const RIDGE_LAMBDAS: [f64; 9] = [1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0];
/// Kernel ridge: widths (gamma = width / median squared distance) and lambdas.
const KRR_WIDTHS: [f64; 4] = [0.25, 0.5, 1.0, 2.0];
const KRR_LAMBDAS: [f64; 4] = [1e-4, 1e-3, 1e-2, 1e-1];
/// Kernel ridge keeps at most this many support rows (spread evenly over the training rows).
pub const KRR_SUPPORT: usize = 3_000;
/// ... and searches on at most this many per fold.
const KRR_SEARCH_SUPPORT: usize = 1_200;
/// k-nearest-neighbour candidates.
const KNN_KS: [usize; 8] = [1, 2, 3, 5, 8, 12, 20, 30];
/// The Gaussian process's learning rows, iterations and support.
const GP: GpOptions = GpOptions::DEFAULT;

/// Trains `choice` on `table` (all its rows: select the training rows first), hyperparameters
/// by `opts.folds`-fold cross-validation inside them.
///
/// # Errors
/// [`TabularError::Usage`] when the targets do not suit the method (a regressor without
/// positions, a classifier without labels or a grid, a single class, too few rows for the
/// folds), [`TabularError::Fit`] when no candidate could be fitted.
pub fn train(
    table: &Table,
    choice: Choice,
    opts: &TrainOptions,
    progress: Progress<'_>,
) -> Result<TableModel, TabularError> {
    let started = std::time::Instant::now();
    let n = table.rows();
    if opts.folds < 2 || opts.folds > n {
        return Err(usage(format!(
            "{} folds for {n} training rows: use 2 to {n}",
            opts.folds
        )));
    }
    let targets = table.targets();
    let classes = class_targets(table, opts.grid)?;
    let methods: Vec<Method> = match choice {
        Choice::One(m) => vec![m],
        Choice::Auto if targets.is_some() && opts.grid.is_none() => {
            vec![Method::Ridge, Method::Knn, Method::KernelRidge, Method::Gp]
        }
        Choice::Auto => vec![Method::Lda, Method::Qda],
    };
    let mut search: Vec<Candidate> = Vec::new();
    for &method in &methods {
        let found = if method.is_classifier() {
            let (labels, _) = classes.as_ref().ok_or_else(|| {
                usage(format!(
                    "{} needs class labels: give a label column, or make classes from the \
                     positions with a grid (--grid 7x7)",
                    method.name()
                ))
            })?;
            search_classifier(table, method, labels, opts, progress)?
        } else {
            let t = targets.as_ref().ok_or_else(|| {
                usage(format!(
                    "{} predicts positions: the targets need x and y columns (the data has \
                     only class labels: use qda or lda)",
                    method.name()
                ))
            })?;
            search_regressor(&table.x, t, method, opts, progress)?
        };
        search.extend(found);
    }
    // Best first; a candidate whose fit on every row fails (a covariance that cross-validated
    // but is singular on the whole set) gives way to the next.
    let mut ranked: Vec<&Candidate> = search.iter().filter(|c| c.loss().is_finite()).collect();
    ranked.sort_by(|a, b| a.loss().total_cmp(&b.loss()));
    let mut fitted = None;
    let mut last_error = None;
    for best in ranked {
        let lda = as_lda_if_equal(best, table.x.ncols(), classes.as_ref().map(|(l, _)| l));
        let best = lda.as_ref().unwrap_or(best);
        progress(&format!("fitting {}", best.method.name()), 0, 1);
        match fit_final(table, best, targets.as_deref(), classes.as_ref(), progress) {
            Ok(f) => {
                fitted = Some((best.clone(), f, lda.is_some()));
                break;
            }
            Err(e) => last_error = Some(e),
        }
    }
    let (best, (tables, mean, scale), qda_is_lda) = fitted.ok_or_else(|| {
        last_error.unwrap_or_else(|| {
            TabularError::Fit(FitError::Shape(
                "no candidate could be fitted in cross-validation".into(),
            ))
        })
    })?;
    progress(&format!("fitting {}", best.method.name()), 1, 1);
    let note = qda_is_lda.then(|| {
        // Its cross-validation is the QDA's: the same classifier in every fold.
        search.push(best.clone());
        format!(
            "qda's best shrinkage is 1 toward the pooled covariance: every class then has the \
             pooled covariance, which is lda (the same decisions); saved the lda, one \
             covariance instead of {}",
            classes.as_ref().map_or(0, |(l, _)| l.names.len())
        )
    });
    let mut hyperparameters = best.hyperparameters.clone();
    if let Tables::Gp {
        length_scales,
        signal_variance,
        noise_variance,
        ..
    } = &tables
    {
        let mut sorted = length_scales.clone();
        sorted.sort_by(f64::total_cmp);
        hyperparameters.extend([
            ("signal_variance".to_string(), *signal_variance),
            ("noise_variance".to_string(), *noise_variance),
            (
                "length_scale_median".to_string(),
                sorted.get(sorted.len() / 2).copied().unwrap_or(f64::NAN),
            ),
        ]);
    }
    Ok(TableModel {
        format: "et-table-model".into(),
        version: 1,
        method: best.method,
        feature_names: table.feature_names.clone(),
        feature_mean: mean,
        feature_scale: scale,
        unit: Unit::Mm,
        third: table.third.as_ref().map(|(n, _)| n.clone()),
        classes: if best.method.is_classifier() {
            classes.map(|(_, info)| info)
        } else {
            None
        },
        hyperparameters,
        search,
        cv_folds: opts.folds,
        cv_scheme: opts.scheme,
        trained_rows: [table.first_row, table.first_row + n],
        source: table.description.clone(),
        fit_seconds: started.elapsed().as_secs_f64(),
        note,
        tables,
    })
}

/// QDA at shrinkage 1 toward the pooled covariance gives every class the pooled covariance,
/// in every fold as on all rows: that is LDA at shrinkage 0, as that LDA candidate (scored
/// as the QDA was), C times smaller. `None` for any other candidate.
fn as_lda_if_equal(c: &Candidate, p: usize, labels: Option<&Labels>) -> Option<Candidate> {
    let full = c
        .hyperparameters
        .get("shrinkage")
        .is_some_and(|&s| s >= 1.0);
    (c.method == Method::Qda && full && shrink_target(p, labels?) == Target::Pooled).then(|| {
        Candidate {
            method: Method::Lda,
            hyperparameters: params(&[("shrinkage", 0.0)]),
            ..c.clone()
        }
    })
}

/// The classes of a table: its labels, or the grid cells of its positions (cells without
/// rows dropped), with each class's position where known.
fn class_targets(
    table: &Table,
    grid: Option<(usize, usize)>,
) -> Result<Option<(Labels, ClassInfo)>, TabularError> {
    if let Some((rows, cols)) = grid {
        let p = table.positions_mm.as_ref().ok_or_else(|| {
            usage("--grid makes classes from positions: the targets need x and y columns")
        })?;
        if rows == 0 || cols == 0 {
            return Err(usage("--grid: at least 1x1"));
        }
        let g = Grid::over(p, rows, cols);
        let cells: Vec<usize> = p.iter().map(|&q| g.cell(q)).collect();
        let mut used: Vec<usize> = cells.clone();
        used.sort_unstable();
        used.dedup();
        let of: BTreeMap<usize, u16> = used
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u16))
            .collect();
        let labels = Labels {
            index: cells
                .iter()
                .map(|c| of.get(c).copied().unwrap_or(0))
                .collect(),
            names: used.iter().map(|&c| g.name(c)).collect(),
        };
        let info = ClassInfo {
            names: labels.names.clone(),
            centres_mm: Some(used.iter().map(|&c| g.centre(c)).collect()),
            grid: Some(g),
        };
        return Ok(Some((labels, info)));
    }
    let Some(text) = &table.labels else {
        return Ok(None);
    };
    let labels = Labels::from_text(text)?;
    let centres_mm = table.positions_mm.as_ref().map(|p| {
        let mut sum = vec![[0.0, 0.0, 0.0]; labels.names.len()];
        for (&c, q) in labels.index.iter().zip(p) {
            if let Some(s) = sum.get_mut(usize::from(c)) {
                *s = [s[0] + q[0], s[1] + q[1], s[2] + 1.0];
            }
        }
        sum.iter()
            .map(|s| [s[0] / s[2].max(1.0), s[1] / s[2].max(1.0)])
            .collect()
    });
    let info = ClassInfo {
        names: labels.names.clone(),
        centres_mm,
        grid: None,
    };
    Ok(Some((labels, info)))
}

/// Fold of each row: contiguous blocks, or shuffled (stratified by `labels` when given).
#[must_use]
pub fn folds(
    n: usize,
    k: usize,
    scheme: CvScheme,
    labels: Option<&[u16]>,
    seed: u64,
) -> Vec<usize> {
    let k = k.max(1);
    match (scheme, labels) {
        (CvScheme::Blocks, _) => (0..n).map(|r| r * k / n.max(1)).collect(),
        (CvScheme::Shuffled, Some(y)) => cv::folds(y, k, seed),
        (CvScheme::Shuffled, None) => cv::folds(&vec![0; n], k, seed),
    }
}

/// Rows of `x` as a matrix.
fn rows_of(x: &DMatrix<f64>, rows: &[usize]) -> DMatrix<f64> {
    DMatrix::from_fn(rows.len(), x.ncols(), |i, j| {
        rows.get(i).map_or(0.0, |&r| x[(r, j)])
    })
}

fn params(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
    pairs.iter().map(|&(k, v)| (k.to_string(), v)).collect()
}

/// Mean position error (x, y) of predictions against truth.
fn mean_error(pred: &[Target3], truth: &[Target3]) -> f64 {
    summarise(pred, truth, false).mean_mm
}

/// Every hyperparameter candidate of a regressor, scored by cross-validation.
fn search_regressor(
    x: &DMatrix<f64>,
    t: &[Target3],
    method: Method,
    opts: &TrainOptions,
    progress: Progress<'_>,
) -> Result<Vec<Candidate>, TabularError> {
    let n = x.nrows();
    let fold = folds(n, opts.folds, opts.scheme, None, opts.seed);
    let grid: Vec<BTreeMap<String, f64>> = match method {
        Method::Ridge => RIDGE_LAMBDAS
            .iter()
            .map(|&l| params(&[("lambda", l)]))
            .collect(),
        Method::KernelRidge => KRR_WIDTHS
            .iter()
            .flat_map(|&w| {
                KRR_LAMBDAS
                    .iter()
                    .map(move |&l| params(&[("width", w), ("lambda", l)]))
            })
            .collect(),
        Method::Knn => KNN_KS
            .iter()
            .flat_map(|&k| [0.0, 1.0].map(|d| params(&[("k", k as f64), ("distance_weighted", d)])))
            .collect(),
        Method::Gp => vec![params(&[
            ("learn_rows", GP.learn_rows.min(n) as f64),
            ("iterations", GP.iterations as f64),
        ])],
        Method::Qda | Method::Lda => return Err(usage("not a regressor")),
    };
    // Out-of-fold predictions of every candidate.
    let mut pred: Vec<Vec<Option<Target3>>> = vec![vec![None; n]; grid.len()];
    // Progress steps per fold: the Gaussian process reports each of its iterations, and says
    // beforehand how long its folds and final fit will take.
    let steps = if method == Method::Gp {
        GP.iterations
    } else {
        1
    };
    let what = if method == Method::Gp {
        format!(
            "cross-validating gp ({} folds, then the final fit: about {:.0} s)",
            opts.folds,
            Gp::estimate_seconds(x, &GP, opts.folds + 1)
        )
    } else {
        format!(
            "cross-validating {} ({} candidates)",
            method.name(),
            grid.len()
        )
    };
    let total = opts.folds * steps;
    for f in 0..opts.folds {
        progress(&what, f * steps, total);
        let train: Vec<usize> = (0..n).filter(|&r| fold.get(r) != Some(&f)).collect();
        let test: Vec<usize> = (0..n).filter(|&r| fold.get(r) == Some(&f)).collect();
        if test.is_empty() || train.len() < 2 {
            continue;
        }
        let (xt, xv) = (rows_of(x, &train), rows_of(x, &test));
        let tt: Vec<Target3> = train.iter().filter_map(|&r| t.get(r).copied()).collect();
        let fold_pred: Vec<Option<Vec<Target3>>> = match method {
            Method::Ridge => Ridge::fit_path(&xt, &tt, &RIDGE_LAMBDAS)?
                .into_iter()
                .map(|m| m.map(|m| m.predict_many(&xv)))
                .collect(),
            Method::KernelRidge => {
                let fits =
                    KernelRidge::fit_grid(&xt, &tt, KRR_SEARCH_SUPPORT, &KRR_WIDTHS, &KRR_LAMBDAS)?;
                // Every fit of the grid shares the support: the held-out rows' distances once.
                let d2 = fits.iter().flatten().next().map(|m| m.distances(&xv));
                fits.into_iter()
                    .map(|m| Some(m?.predict_from_distances(d2.as_ref()?)))
                    .collect()
            }
            Method::Knn => {
                let model = Knn::fit(&xt, &tt, 1, Weighting::Uniform)?;
                let k_max = KNN_KS.iter().copied().max().unwrap_or(1);
                let near = model.neighbours(&xv, k_max);
                grid.iter()
                    .map(|h| {
                        let k = h.get("k").copied().unwrap_or(1.0) as usize;
                        let w = if h.get("distance_weighted").copied().unwrap_or(0.0) > 0.5 {
                            Weighting::Distance
                        } else {
                            Weighting::Uniform
                        };
                        Some(near.iter().map(|nr| model.combine(nr, k, w)).collect())
                    })
                    .collect()
            }
            Method::Gp => {
                let mut step = |done: usize, _: usize| progress(&what, f * steps + done, total);
                vec![
                    Gp::fit(&xt, &tt, &GP, &mut step)
                        .ok()
                        .map(|m| m.predict_many(&xv)),
                ]
            }
            Method::Qda | Method::Lda => Vec::new(),
        };
        for (c, p) in fold_pred.into_iter().enumerate() {
            let (Some(p), Some(slot)) = (p, pred.get_mut(c)) else {
                continue;
            };
            for (&r, v) in test.iter().zip(p) {
                if let Some(s) = slot.get_mut(r) {
                    *s = Some(v);
                }
            }
        }
    }
    progress(&what, total, total);
    Ok(grid
        .into_iter()
        .zip(pred)
        .map(|(hyperparameters, p)| {
            // A candidate that failed in any fold scores nothing.
            let all: Option<Vec<Target3>> = p.into_iter().collect();
            Candidate {
                method,
                hyperparameters,
                cv_mean_error_mm: all.map(|p| mean_error(&p, t)).filter(|e| e.is_finite()),
                cv_accuracy: None,
            }
        })
        .collect())
}

/// Every shrinkage of QDA or LDA, scored by cross-validation (accuracy; and the mean distance
/// from the true position to the predicted class's position when the rows have positions).
fn search_classifier(
    table: &Table,
    method: Method,
    labels: &Labels,
    opts: &TrainOptions,
    progress: Progress<'_>,
) -> Result<Vec<Candidate>, TabularError> {
    let classes = labels.names.len();
    if classes < 2 {
        return Err(usage(format!(
            "one class ('{}') only: nothing to tell apart; give rows of at least two classes",
            labels.names.first().map_or("", String::as_str)
        )));
    }
    let fold = folds(
        table.rows(),
        opts.folds,
        opts.scheme,
        Some(&labels.index),
        opts.seed,
    );
    let kind = discriminant(method);
    let what = format!(
        "cross-validating {} ({} shrinkages)",
        method.name(),
        SHRINKAGES.len()
    );
    let mut out = Vec::new();
    for (i, &lambda) in SHRINKAGES.iter().enumerate() {
        progress(&what, i, SHRINKAGES.len());
        let fit = FitOptions {
            kind,
            shrinkage: lambda,
            // Toward the diagonal when a class has fewer rows than features.
            target: shrink_target(table.x.ncols(), labels),
        };
        let conf = match cross_validate_fast(&table.x, &labels.index, classes, &fit, &fold) {
            Ok(conf) => Some(conf),
            // A fold whose training rows lack some class (blocks of a recording): fit on the
            // classes present, and count the absent class's rows as missed.
            Err(FitError::EmptyClass { .. }) => cv_present_classes(&table.x, labels, &fit, &fold),
            // A singular fit: the candidate scores nothing.
            Err(_) => None,
        };
        out.push(Candidate {
            method,
            hyperparameters: params(&[("shrinkage", lambda)]),
            cv_mean_error_mm: None,
            cv_accuracy: conf.as_ref().map(Confusion::accuracy),
        });
    }
    progress(&what, SHRINKAGES.len(), SHRINKAGES.len());
    Ok(out)
}

/// QDA shrinks toward the pooled covariance, unless some class has no more rows than
/// features (then toward the diagonal, which needs no pooled estimate of full rank).
fn shrink_target(p: usize, labels: &Labels) -> Target {
    if labels.index.len() <= p + labels.names.len() {
        Target::Diagonal
    } else {
        Target::Pooled
    }
}

fn discriminant(method: Method) -> ModelKind {
    if method == Method::Lda {
        ModelKind::Lda
    } else {
        ModelKind::Qda
    }
}

/// Cross-validation where a fold's training rows may lack classes: each fold fits on the
/// classes it has (relabelled), and held-out rows of a class it lacks count as missed. None
/// when a fold cannot be fitted.
fn cv_present_classes(
    x: &DMatrix<f64>,
    labels: &Labels,
    fit: &FitOptions,
    fold: &[usize],
) -> Option<Confusion> {
    let classes = labels.names.len();
    let k = fold.iter().max().map_or(0, |m| m + 1);
    let mut conf = Confusion::new(classes);
    for f in 0..k {
        let train: Vec<usize> = (0..x.nrows())
            .filter(|&r| fold.get(r) != Some(&f))
            .collect();
        let test: Vec<usize> = (0..x.nrows())
            .filter(|&r| fold.get(r) == Some(&f))
            .collect();
        let y = |r: usize| labels.index.get(r).copied().unwrap_or(0);
        let mut present: Vec<u16> = train.iter().map(|&r| y(r)).collect();
        present.sort_unstable();
        present.dedup();
        if present.len() < 2 {
            return None;
        }
        let local: BTreeMap<u16, u16> = present
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u16))
            .collect();
        let yt: Vec<u16> = train
            .iter()
            .map(|&r| local.get(&y(r)).copied().unwrap_or(0))
            .collect();
        let model = Fitted::fit(&rows_of(x, &train), &yt, present.len(), fit).ok()?;
        let mut row = vec![0.0; x.ncols()];
        for &r in &test {
            for (j, v) in row.iter_mut().enumerate() {
                *v = x[(r, j)];
            }
            let predicted = present
                .get(usize::from(model.predict(&row)))
                .copied()
                .unwrap_or(0);
            conf.add(y(r), predicted);
        }
    }
    Some(conf)
}

/// The final fit of the chosen candidate on every row: its tables and the standardisation.
fn fit_final(
    table: &Table,
    best: &Candidate,
    targets: Option<&[Target3]>,
    classes: Option<&(Labels, ClassInfo)>,
    progress: Progress<'_>,
) -> Result<(Tables, Vec<f64>, Vec<f64>), TabularError> {
    let h = |name: &str| best.hyperparameters.get(name).copied().unwrap_or(0.0);
    let need_targets = || targets.ok_or_else(|| usage("this method needs positions"));
    Ok(match best.method {
        Method::Qda | Method::Lda => {
            let (labels, _) = classes.ok_or_else(|| usage("this method needs classes"))?;
            let fit = FitOptions {
                kind: discriminant(best.method),
                shrinkage: h("shrinkage"),
                target: shrink_target(table.x.ncols(), labels),
            };
            let model = Fitted::fit(&table.x, &labels.index, labels.names.len(), &fit)?;
            (
                Tables::Discriminant {
                    kind: if best.method == Method::Lda {
                        ModelKind::Lda
                    } else {
                        ModelKind::Qda
                    },
                    classes: class_records(&model),
                },
                model.feature_mean,
                model.feature_scale,
            )
        }
        Method::Ridge => {
            let m = Ridge::fit(&table.x, need_targets()?, h("lambda"))?;
            (
                Tables::Ridge {
                    weights: m.weight_rows(),
                    intercept: m.intercept,
                },
                m.mean,
                m.scale,
            )
        }
        Method::KernelRidge => {
            let m = KernelRidge::fit(
                &table.x,
                need_targets()?,
                KRR_SUPPORT,
                h("width"),
                h("lambda"),
            )?;
            (
                Tables::KernelRidge {
                    gamma: m.gamma,
                    support: regress::rows_of(&m.support),
                    alpha: regress::rows3(&m.alpha),
                    intercept: m.intercept,
                },
                m.mean,
                m.scale,
            )
        }
        Method::Gp => {
            let what = "fitting gp (learning its length scales on every training row)";
            let mut step = |done: usize, of: usize| progress(what, done, of);
            let m = Gp::fit(&table.x, need_targets()?, &GP, &mut step)?;
            let k = &m.predictor;
            // The predictor's scales are the features' spreads times the length scales.
            let scale = k
                .scale
                .iter()
                .zip(&m.length_scales)
                .map(|(s, l)| s / l)
                .collect();
            (
                Tables::Gp {
                    support: (0..k.support.nrows())
                        .map(|i| {
                            (k.support.row(i).iter())
                                .zip(&m.length_scales)
                                .map(|(v, l)| v * l)
                                .collect()
                        })
                        .collect(),
                    alpha: regress::rows3(&k.alpha),
                    intercept: k.intercept,
                    length_scales: m.length_scales,
                    signal_variance: m.signal_variance,
                    noise_variance: m.noise_variance,
                },
                k.mean.clone(),
                scale,
            )
        }
        Method::Knn => {
            let weighting = if h("distance_weighted") > 0.5 {
                Weighting::Distance
            } else {
                Weighting::Uniform
            };
            let m = Knn::fit(
                &table.x,
                need_targets()?,
                h("k").max(1.0) as usize,
                weighting,
            )?;
            (
                Tables::Knn {
                    k: m.k,
                    weighting,
                    support: regress::rows_of(&m.support),
                    targets: m.targets.clone(),
                },
                m.mean,
                m.scale,
            )
        }
    })
}

/// A model rebuilt from its tables, ready to predict.
enum Ready {
    Discriminant(Fitted),
    Ridge(Ridge),
    KernelRidge(KernelRidge),
    Knn(Knn),
}

impl TableModel {
    /// Features it reads per row.
    #[must_use]
    pub fn features(&self) -> usize {
        self.feature_mean.len()
    }

    /// Rebuilds the fitted model, checking every table's shape.
    fn ready(&self) -> Result<Ready, String> {
        let p = self.features();
        if self.feature_scale.len() != p || self.feature_names.len() != p || p == 0 {
            return Err("feature_mean, feature_scale and feature_names differ in length".into());
        }
        if let Some(v) = self
            .feature_mean
            .iter()
            .chain(&self.feature_scale)
            .find(|v| !v.is_finite())
        {
            return Err(format!("a non-finite standardisation value ({v})"));
        }
        if self.feature_scale.iter().any(|&s| s <= 0.0) {
            return Err("feature_scale must be positive".into());
        }
        let matrix = |rows: &[Vec<f64>], what: &str| -> Result<Mat<f64>, String> {
            if rows.is_empty() || rows.iter().any(|r| r.len() != p) {
                return Err(format!("{what}: every row needs {p} values"));
            }
            if rows.iter().flatten().any(|v| !v.is_finite()) {
                return Err(format!("{what}: a non-finite value"));
            }
            Ok(Mat::from_fn(rows.len(), p, |i, j| {
                rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
            }))
        };
        let finite3 = |v: &[[f64; 3]], what: &str| -> Result<(), String> {
            if v.iter().flatten().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(format!("{what}: a non-finite value"))
            }
        };
        let method_ok = |m: Method| {
            if m == self.method {
                Ok(())
            } else {
                Err(format!(
                    "method {} with the tables of {}",
                    self.method.name(),
                    m.name()
                ))
            }
        };
        Ok(match &self.tables {
            Tables::Discriminant { kind, classes } => {
                let (method, mk) = match kind {
                    ModelKind::Qda => (Method::Qda, *kind),
                    ModelKind::Lda => (Method::Lda, *kind),
                };
                method_ok(method)?;
                let info = self
                    .classes
                    .as_ref()
                    .ok_or("a classifier without 'classes'")?;
                if info.names.len() != classes.len()
                    || info
                        .centres_mm
                        .as_ref()
                        .is_some_and(|c| c.len() != classes.len())
                {
                    return Err("classes.names (and centres_mm) must list every class".into());
                }
                let fitted =
                    fitted_from_records(mk, &self.feature_mean, &self.feature_scale, classes)
                        .map_err(|e| e.to_string())?;
                Ready::Discriminant(fitted)
            }
            Tables::Ridge { weights, intercept } => {
                method_ok(Method::Ridge)?;
                if weights.len() != p {
                    return Err(format!(
                        "ridge: {} weight rows for {p} features",
                        weights.len()
                    ));
                }
                finite3(weights, "ridge weights")?;
                finite3(&[*intercept], "ridge intercept")?;
                Ready::Ridge(Ridge {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    weights: DMatrix::from_fn(p, 3, |j, c| {
                        weights
                            .get(j)
                            .and_then(|w| w.get(c))
                            .copied()
                            .unwrap_or(0.0)
                    }),
                    intercept: *intercept,
                })
            }
            Tables::KernelRidge {
                gamma,
                support,
                alpha,
                intercept,
            } => {
                method_ok(Method::KernelRidge)?;
                let support = matrix(support, "kernel-ridge support")?;
                if alpha.len() != support.nrows() {
                    return Err("kernel-ridge: one alpha row per support row".into());
                }
                finite3(alpha, "kernel-ridge alpha")?;
                finite3(&[*intercept], "kernel-ridge intercept")?;
                if !(gamma.is_finite() && *gamma > 0.0) {
                    return Err("kernel-ridge: gamma must be positive".into());
                }
                Ready::KernelRidge(KernelRidge {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    alpha: Mat::from_fn(alpha.len(), 3, |i, c| {
                        alpha.get(i).and_then(|a| a.get(c)).copied().unwrap_or(0.0)
                    }),
                    support,
                    gamma: *gamma,
                    intercept: *intercept,
                })
            }
            Tables::Gp {
                length_scales,
                signal_variance,
                noise_variance,
                support,
                alpha,
                intercept,
            } => {
                method_ok(Method::Gp)?;
                let support = matrix(support, "gp support")?;
                if alpha.len() != support.nrows() || length_scales.len() != p {
                    return Err(
                        "gp: one alpha row per support row, one length scale per feature".into(),
                    );
                }
                finite3(alpha, "gp alpha")?;
                finite3(&[*intercept], "gp intercept")?;
                let positive = |v: f64| v.is_finite() && v > 0.0;
                if !(length_scales.iter().all(|&l| positive(l))
                    && positive(*signal_variance)
                    && positive(*noise_variance))
                {
                    return Err("gp: length scales and variances must be positive".into());
                }
                // The posterior mean is kernel ridge in the length-scaled space.
                Ready::KernelRidge(KernelRidge {
                    mean: self.feature_mean.clone(),
                    scale: self
                        .feature_scale
                        .iter()
                        .zip(length_scales)
                        .map(|(s, l)| s * l)
                        .collect(),
                    alpha: Mat::from_fn(alpha.len(), 3, |i, c| {
                        alpha.get(i).and_then(|a| a.get(c)).copied().unwrap_or(0.0)
                    }),
                    support: Mat::from_fn(support.nrows(), p, |i, j| {
                        support[(i, j)] / length_scales.get(j).copied().unwrap_or(1.0)
                    }),
                    gamma: 0.5,
                    intercept: *intercept,
                })
            }
            Tables::Knn {
                k,
                weighting,
                support,
                targets,
            } => {
                method_ok(Method::Knn)?;
                let support = matrix(support, "knn support")?;
                if targets.len() != support.nrows() || *k == 0 || *k > targets.len() {
                    return Err("knn: one target per support row, 1 <= k <= rows".into());
                }
                finite3(targets, "knn targets")?;
                Ready::Knn(Knn {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    support,
                    targets: targets.clone(),
                    k: *k,
                    weighting: *weighting,
                })
            }
        })
    }

    /// Predicts every row of `x` (n x p, the training files' units).
    ///
    /// # Errors
    /// [`TabularError::Usage`] when `x` has another feature count, or the model's tables are
    /// inconsistent.
    pub fn predict(&self, x: &DMatrix<f64>) -> Result<Vec<Prediction>, TabularError> {
        if x.ncols() != self.features() {
            return Err(usage(format!(
                "the data has {} feature columns, the model reads {}",
                x.ncols(),
                self.features()
            )));
        }
        let ready = self.ready().map_err(usage)?;
        let regression = |t: Vec<Target3>| {
            t.into_iter()
                .map(|t| Prediction {
                    class: None,
                    target: Some(t),
                })
                .collect()
        };
        Ok(match ready {
            Ready::Discriminant(m) => {
                let centres = self.classes.as_ref().and_then(|c| c.centres_mm.as_ref());
                let mut row = vec![0.0; x.ncols()];
                (0..x.nrows())
                    .map(|r| {
                        for (j, v) in row.iter_mut().enumerate() {
                            *v = x[(r, j)];
                        }
                        let class = m.predict(&row);
                        Prediction {
                            class: Some(class),
                            target: centres
                                .and_then(|c| c.get(usize::from(class)))
                                .map(|c| [c[0], c[1], 0.0]),
                        }
                    })
                    .collect()
            }
            Ready::Ridge(m) => regression(m.predict_many(x)),
            Ready::KernelRidge(m) => regression(m.predict_many(x)),
            Ready::Knn(m) => regression(m.predict_many(x)),
        })
    }

    /// Writes JSON.
    ///
    /// # Errors
    /// [`TabularError::Model`] naming the file.
    pub fn save(&self, path: &Path) -> Result<(), TabularError> {
        let err = |message: String| TabularError::Model {
            path: path.into(),
            message,
        };
        let text = serde_json::to_string(self).map_err(|e| err(e.to_string()))?;
        std::fs::write(path, text).map_err(|e| err(e.to_string()))
    }

    /// Reads and checks JSON written by [`save`](Self::save).
    ///
    /// # Errors
    /// [`TabularError::Model`] naming the file and what is wrong.
    pub fn load(path: &Path) -> Result<Self, TabularError> {
        let err = |message: String| TabularError::Model {
            path: path.into(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        Self::from_json(&text).map_err(err)
    }

    /// Parses and checks a model's JSON.
    ///
    /// # Errors
    /// What is wrong, in words.
    pub fn from_json(text: &str) -> Result<Self, String> {
        let m: TableModel = serde_json::from_str(text).map_err(|e| e.to_string())?;
        if m.format != "et-table-model" || m.version != 1 {
            return Err("not an et-table-model version 1 file".into());
        }
        m.ready()?;
        Ok(m)
    }
}

/// Whether a JSON file is an et table model (else an et board model, `"format": "et-model"`).
#[must_use]
pub fn is_table_model(text: &str) -> bool {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .and_then(|v| v.get("format").and_then(|f| f.as_str().map(String::from)))
        .is_some_and(|f| f == "et-table-model")
}

/// How a model did on a table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// Rows evaluated.
    pub observations: usize,
    /// The model's method.
    pub method: Method,
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

/// Evaluates `model` on `table`: position errors when the rows have positions, accuracy for
/// classifiers when the rows have labels the model knows (an unknown label counts as missed)
/// or positions its grid places.
///
/// # Errors
/// [`TabularError::Usage`] when the features do not match, or the rows have no target the
/// model predicts.
pub fn evaluate(model: &TableModel, table: &Table) -> Result<Evaluation, TabularError> {
    let started = std::time::Instant::now();
    let pred = model.predict(&table.x)?;
    let predict_seconds = started.elapsed().as_secs_f64();
    let truth = table.targets();
    let accuracy = match (&model.classes, model.method.is_classifier()) {
        (Some(info), true) => {
            let true_class: Option<Vec<Option<u16>>> = if let Some(text) = &table.labels {
                Some(
                    text.iter()
                        .map(|l| info.names.iter().position(|n| n == l).map(|c| c as u16))
                        .collect(),
                )
            } else {
                match (&info.grid, &table.positions_mm) {
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
                    .zip(&pred)
                    .filter(|(t, p)| t.is_some() && **t == p.class)
                    .count();
                right as f64 / t.len().max(1) as f64
            })
        }
        _ => None,
    };
    if truth.is_none() && accuracy.is_none() {
        return Err(usage(
            "the rows have no target this model predicts: give positions (x, y) or class labels",
        ));
    }
    let mut pairs = Vec::new();
    let (mut errors, mut errors3, mut third) = (Vec::new(), Vec::new(), Vec::new());
    if let Some(truth) = &truth {
        for (t, p) in truth.iter().zip(&pred) {
            if let Some(q) = p.target {
                pairs.push(([t[0], t[1]], [q[0], q[1]]));
                errors.push((q[0] - t[0]).hypot(q[1] - t[1]));
                if model.third.is_some() && table.third.is_some() {
                    third.push((q[2] - t[2]).abs());
                    errors3.push(
                        ((q[0] - t[0]).powi(2) + (q[1] - t[1]).powi(2) + (q[2] - t[2]).powi(2))
                            .sqrt(),
                    );
                }
            }
        }
    }
    let z_is_length = model
        .third
        .as_deref()
        .is_some_and(|n| n.eq_ignore_ascii_case("z"));
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
                .map(|t| (t[0] - c[0]).hypot(t[1] - c[1]))
                .sum::<f64>()
                / t.len().max(1) as f64
        })
    });
    Ok(Evaluation {
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

    /// The mean training position, mm (regressors: their intercept or targets' mean; classes:
    /// the count-weighted class positions), when known.
    #[must_use]
    pub fn training_mean_position(&self) -> Option<[f64; 2]> {
        match &self.tables {
            Tables::Ridge { intercept, .. }
            | Tables::KernelRidge { intercept, .. }
            | Tables::Gp { intercept, .. } => Some([intercept[0], intercept[1]]),
            Tables::Knn { targets, .. } => {
                let n = targets.len().max(1) as f64;
                Some(
                    targets
                        .iter()
                        .fold([0.0, 0.0], |a, t| [a[0] + t[0] / n, a[1] + t[1] / n]),
                )
            }
            Tables::Discriminant { classes, .. } => {
                let centres = self.classes.as_ref()?.centres_mm.as_ref()?;
                let n = classes.iter().map(|c| c.count).sum::<usize>().max(1) as f64;
                Some(classes.iter().zip(centres).fold([0.0, 0.0], |a, (c, q)| {
                    let w = c.count as f64 / n;
                    [a[0] + w * q[0], a[1] + w * q[1]]
                }))
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use crate::standin;
    use std::sync::LazyLock;

    fn tmp(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("et-tabular-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn quiet() -> impl FnMut(&str, usize, usize) {
        |_: &str, _: usize, _: usize| {}
    }

    /// The stand-in written in the foreign format and read back (positions in metres): 360
    /// presses over 3 sessions, in time order.
    static STANDIN: LazyLock<Table> = LazyLock::new(|| {
        let dir = tmp("standin");
        let (f, t) = (dir.join("features.csv"), dir.join("targets.csv"));
        standin::make(360, 3, 11).unwrap().write(&f, &t).unwrap();
        let table = Table::import(&f, Some(&t), Unit::M).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        table
    });

    fn opts() -> TrainOptions {
        TrainOptions {
            folds: 3,
            ..TrainOptions::default()
        }
    }

    #[test]
    fn the_stand_in_reads_as_the_foreign_files_say() {
        let t = &*STANDIN;
        assert_eq!((t.rows(), t.x.ncols()), (360, 192));
        assert!(t.labels.is_none());
        let p = t.positions_mm.as_ref().unwrap();
        // Metres became mm: every press within 40 mm (+ rounding) of the sheet's centre.
        let [cx, cy, cz] = standin::SHEET_ORIGIN_M.map(|v| v * 1e3);
        assert!(
            p.iter().all(|q| (q[0] - cx).hypot(q[1] - cy) <= 40.01),
            "{:?}",
            p[0]
        );
        let (name, z) = t.third.as_ref().unwrap();
        assert_eq!(name, "z");
        assert!(z.iter().all(|&z| z <= cz && z >= cz - 2.01), "{}", z[0]);
        assert!(t.description.contains("no header row") && t.description.contains("m (read"));
        assert!(!t.description.contains("--unit m"));
        // The same metres read as the default mm span a fraction of a millimetre: said.
        let dir = tmp("unit");
        let (f, tf) = (dir.join("features.csv"), dir.join("targets.csv"));
        standin::make(40, 1, 3).unwrap().write(&f, &tf).unwrap();
        let as_mm = Table::import(&f, Some(&tf), Unit::Mm).unwrap();
        assert!(
            as_mm.description.contains("give --unit m"),
            "{}",
            as_mm.description
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Each regressor, trained on the first 300 rows (a chronological split), places the last
    /// 60 presses well inside what a constant guess gets, and its model file predicts the same
    /// after a round trip through JSON.
    #[test]
    fn every_regressor_learns_the_stand_in_and_survives_its_file() {
        let train_rows = STANDIN.select("0..300".parse().unwrap()).unwrap();
        let test_rows = STANDIN.select("300..".parse().unwrap()).unwrap();
        assert_eq!(test_rows.first_row, 300);
        let dir = tmp("regressors");
        for method in [Method::Ridge, Method::Knn, Method::KernelRidge, Method::Gp] {
            let model = train(&train_rows, Choice::One(method), &opts(), &mut quiet()).unwrap();
            assert_eq!(model.method, method);
            assert_eq!(model.trained_rows, [0, 300]);
            assert!(model.search.iter().all(|c| c.method == method));
            let e = evaluate(&model, &test_rows).unwrap();
            let (mean, floor) = (e.mean_error_mm.unwrap(), e.mean_predictor_error_mm.unwrap());
            assert!(
                mean < 0.5 * floor,
                "{method:?}: {mean} mm against a constant's {floor}"
            );
            assert!(e.median_error_mm.unwrap() <= e.p90_error_mm.unwrap());
            assert!(e.mean_error_3d_mm.unwrap() >= mean && e.third_mae.is_some());
            let path = dir.join(format!("{}.json", method.name()));
            model.save(&path).unwrap();
            let back = TableModel::load(&path).unwrap();
            assert!(
                back == model,
                "{method:?}: the model changed through its file"
            );
            let again = evaluate(&back, &test_rows).unwrap();
            assert_eq!(again.mean_error_mm, e.mean_error_mm);
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Auto tries the regressors and keeps the one cross-validation liked best.
    #[test]
    fn auto_keeps_the_best_cross_validated_regressor() {
        let train_rows = STANDIN.select("0..240".parse().unwrap()).unwrap();
        let model = train(&train_rows, Choice::Auto, &opts(), &mut quiet()).unwrap();
        let best = model
            .search
            .iter()
            .filter_map(|c| c.cv_mean_error_mm.map(|e| (e, c.method)))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .unwrap();
        assert_eq!(model.method, best.1);
        let tried: std::collections::HashSet<Method> =
            model.search.iter().map(|c| c.method).collect();
        assert_eq!(tried.len(), 4);
    }

    /// Classes made from positions on a grid: QDA and LDA beat chance on later presses, and
    /// an evaluation places each press in the model's own grid.
    #[test]
    fn a_grid_of_classes_from_positions() {
        let train_rows = STANDIN.select("0..300".parse().unwrap()).unwrap();
        let test_rows = STANDIN.select("300..360".parse().unwrap()).unwrap();
        for method in [Method::Lda, Method::Qda] {
            let o = TrainOptions {
                grid: Some((3, 3)),
                ..opts()
            };
            let model = train(&train_rows, Choice::One(method), &o, &mut quiet()).unwrap();
            let info = model.classes.as_ref().unwrap();
            // A disc in a 3 x 3 grid: every cell has presses.
            assert_eq!(info.names.len(), 9, "{:?}", info.names);
            let e = evaluate(&model, &test_rows).unwrap();
            assert!(e.accuracy.unwrap() > 3.0 / 9.0, "{method:?}: {e:?}");
            assert!(e.mean_error_mm.unwrap() < e.mean_predictor_error_mm.unwrap());
            // A QDA whose best shrinkage is 1 toward the pooled covariance is kept as the LDA
            // it equals, and says so; any other stays QDA.
            let best = |m: Method| {
                model
                    .search
                    .iter()
                    .filter(|c| c.method == m)
                    .min_by(|a, b| a.loss().total_cmp(&b.loss()))
                    .unwrap()
                    .hyperparameters["shrinkage"]
            };
            if method == Method::Qda && best(Method::Qda) >= 1.0 {
                assert_eq!(model.method, Method::Lda);
                assert_eq!(model.chosen().unwrap().hyperparameters["shrinkage"], 0.0);
                assert!(model.note.as_ref().unwrap().contains("lda"));
                eprintln!("QDA-IS-LDA case exercised");
            } else {
                assert_eq!(model.method, method);
                assert!(model.note.is_none());
            }
        }
    }

    /// The substitution itself: only QDA, only at full shrinkage, only toward the pooled
    /// covariance (enough rows for it to have full rank).
    #[test]
    fn qda_at_full_pooled_shrinkage_is_the_lda() {
        let names: Vec<String> = (0..40).map(|i| ["a", "b"][i % 2].to_string()).collect();
        let labels = Labels::from_text(&names).unwrap();
        let qda = |s: f64| Candidate {
            method: Method::Qda,
            hyperparameters: params(&[("shrinkage", s)]),
            cv_mean_error_mm: None,
            cv_accuracy: Some(0.9),
        };
        let lda = as_lda_if_equal(&qda(1.0), 5, Some(&labels)).unwrap();
        assert_eq!((lda.method, lda.cv_accuracy), (Method::Lda, Some(0.9)));
        assert_eq!(lda.hyperparameters["shrinkage"], 0.0);
        assert!(as_lda_if_equal(&qda(0.3), 5, Some(&labels)).is_none());
        // 40 rows, 2 classes, 40 features: the pooled covariance is singular, the target is
        // the diagonal, and QDA at 1 is not LDA.
        assert!(as_lda_if_equal(&qda(1.0), 40, Some(&labels)).is_none());
        assert!(as_lda_if_equal(&qda(1.0), 5, None).is_none());
    }

    #[test]
    fn labels_are_the_users_own_names() {
        let l = Labels::from_text(&["10", "2", "10", "7.5"].map(String::from)).unwrap();
        assert_eq!(l.names, ["2", "7.5", "10"]);
        assert_eq!(l.index, [2, 0, 2, 1]);
        let l = Labels::from_text(&["right", "left", "right"].map(String::from)).unwrap();
        assert_eq!(
            (l.names.as_slice(), l.index.as_slice()),
            (
                &["left".to_string(), "right".to_string()][..],
                &[1, 0, 1][..]
            )
        );
        // A classifier on named classes predicts names; an unknown name in the test rows
        // counts as missed.
        let mut rng = et_core::rng::Rng::new(4);
        let n = 120;
        let labels: Vec<String> = (0..n)
            .map(|r| ["left", "middle", "right"][r % 3].to_string())
            .collect();
        let x = DMatrix::from_fn(n, 4, |r, j| {
            (r % 3) as f64 * (1.0 + j as f64) + 0.1 * rng.normal()
        });
        let table = Table {
            x,
            feature_names: (0..4).map(|j| format!("c{j}")).collect(),
            labels: Some(labels),
            positions_mm: None,
            third: None,
            description: String::new(),
            first_row: 0,
        };
        let model = train(&table, Choice::Auto, &opts(), &mut quiet()).unwrap();
        assert!(model.method.is_classifier());
        assert_eq!(
            model.classes.as_ref().unwrap().names,
            ["left", "middle", "right"]
        );
        assert_eq!(evaluate(&model, &table).unwrap().accuracy, Some(1.0));
        let mut renamed = table.clone();
        if let Some(l) = renamed.labels.as_mut() {
            l[0] = "elsewhere".into();
        }
        let acc = evaluate(&model, &renamed).unwrap().accuracy.unwrap();
        assert!((acc - (n - 1) as f64 / n as f64).abs() < 1e-12);
    }

    #[test]
    fn row_ranges_and_folds() {
        assert_eq!(
            "2000..2500".parse::<RowRange>().unwrap(),
            RowRange {
                start: 2000,
                end: Some(2500)
            }
        );
        assert_eq!("..10".parse::<RowRange>().unwrap().start, 0);
        assert_eq!("5..".parse::<RowRange>().unwrap().end, None);
        for bad in ["5", "a..b", "10..10", "9..3"] {
            assert!(bad.parse::<RowRange>().is_err(), "{bad}");
        }
        let e = STANDIN.select("300..400".parse().unwrap()).unwrap_err();
        assert!(e.to_string().contains("rows 0..360"), "{e}");
        // Blocks are contiguous and in order; shuffled folds are not.
        let b = folds(10, 3, CvScheme::Blocks, None, 1);
        assert_eq!(b, [0, 0, 0, 0, 1, 1, 1, 2, 2, 2]);
        let s = folds(300, 3, CvScheme::Shuffled, None, 1);
        assert!(s.windows(2).any(|w| w[1] < w[0]));
        assert_eq!(s.iter().filter(|&&f| f == 2).count(), 100);
    }

    /// A k-nearest-neighbour prediction equals the brute-force mean of the k nearest rows.
    #[test]
    fn knn_equals_brute_force() {
        let mut rng = et_core::rng::Rng::new(9);
        let x = DMatrix::from_fn(50, 3, |_, _| rng.normal());
        let t: Vec<Target3> = (0..50).map(|r| [r as f64, 2.0 * r as f64, 0.0]).collect();
        let knn = Knn::fit(&x, &t, 4, Weighting::Uniform).unwrap();
        let q = DMatrix::from_fn(5, 3, |_, _| rng.normal());
        let (mean, scale) = crate::fit::standardisation(&x);
        let z = |m: &DMatrix<f64>, r: usize| -> Vec<f64> {
            (0..3).map(|j| (m[(r, j)] - mean[j]) / scale[j]).collect()
        };
        for (r, p) in knn.predict_many(&q).iter().enumerate() {
            let zq = z(&q, r);
            let mut d: Vec<(f64, usize)> = (0..50)
                .map(|i| {
                    let zi = z(&x, i);
                    (zi.iter().zip(&zq).map(|(a, b)| (a - b).powi(2)).sum(), i)
                })
                .collect();
            d.sort_by(|a, b| a.0.total_cmp(&b.0));
            let want = d[..4].iter().map(|&(_, i)| t[i][0]).sum::<f64>() / 4.0;
            assert!((p[0] - want).abs() < 1e-9, "{p:?} vs {want}");
        }
    }

    #[test]
    fn bad_requests_are_refused_with_the_reason() {
        let mut small = STANDIN.select("0..60".parse().unwrap()).unwrap();
        // A classifier with positions only and no grid.
        let e = train(&small, Choice::One(Method::Qda), &opts(), &mut quiet()).unwrap_err();
        assert!(e.to_string().contains("--grid"), "{e}");
        // More folds than rows.
        let o = TrainOptions {
            folds: 61,
            ..opts()
        };
        let e = train(&small, Choice::One(Method::Ridge), &o, &mut quiet()).unwrap_err();
        assert!(e.to_string().contains("61 folds"), "{e}");
        // A regressor without positions; a single class.
        small.positions_mm = None;
        small.third = None;
        small.labels = Some(vec!["only".into(); 60]);
        let e = train(&small, Choice::One(Method::Ridge), &opts(), &mut quiet()).unwrap_err();
        assert!(e.to_string().contains("x and y"), "{e}");
        let e = train(&small, Choice::One(Method::Lda), &opts(), &mut quiet()).unwrap_err();
        assert!(e.to_string().contains("one class ('only')"), "{e}");
        // A model refuses another channel count; broken model files are named.
        let rows = STANDIN.select("0..60".parse().unwrap()).unwrap();
        let model = train(&rows, Choice::One(Method::Ridge), &opts(), &mut quiet()).unwrap();
        let e = model.predict(&DMatrix::zeros(2, 5)).unwrap_err();
        assert!(e.to_string().contains("5 feature columns"), "{e}");
        let mut text = serde_json::to_string(&model).unwrap();
        text = text.replacen("\"weights\":[[", "\"weights\":[[1e999,", 1);
        assert!(TableModel::from_json(&text).is_err());
        let mut short = model.clone();
        if let Tables::Ridge { weights, .. } = &mut short.tables {
            weights.pop();
        }
        let e = TableModel::from_json(&serde_json::to_string(&short).unwrap()).unwrap_err();
        assert!(e.contains("weight rows"), "{e}");
        assert!(!is_table_model("{\"format\": \"et-model\"}"));
        assert!(is_table_model(&serde_json::to_string(&model).unwrap()));
    }

    /// More channels than rows, and constant channels (a dead electrode): every regressor
    /// still fits.
    #[test]
    fn more_channels_than_rows_and_dead_channels_still_fit() {
        let mut rows = STANDIN.select("0..40".parse().unwrap()).unwrap();
        for r in 0..rows.rows() {
            rows.x[(r, 7)] = 3.0;
        }
        for method in [Method::Ridge, Method::Knn, Method::KernelRidge] {
            let model = train(&rows, Choice::One(method), &opts(), &mut quiet()).unwrap();
            let p = model.predict(&rows.x).unwrap();
            assert!(
                p.iter()
                    .all(|p| p.target.unwrap().iter().all(|v| v.is_finite()))
            );
        }
    }
}
