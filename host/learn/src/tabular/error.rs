//! Why a table could not be used ([`TabularError`]), and a request that does not fit the data
//! or the model ([`Misuse`]), with the numbers they say.

use super::*;

/// Why a table could not be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TabularError {
    /// A file could not be read, or its content is wrong (names the file, line, column).
    #[error(transparent)]
    Dataset(#[from] DatasetError),
    /// A fit failed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The request does not fit the data (e.g. a regressor without positions).
    #[error(transparent)]
    Usage(#[from] Misuse),
    /// A model's tables that are not the model they claim to be.
    #[error(transparent)]
    Tables(#[from] TablesError),
    /// No candidate could be fitted in cross-validation: the first reason each method gave.
    #[error("no candidate could be fitted in cross-validation: {0}")]
    NothingFitted(String),
    /// No candidate could be fitted on every row, and some features are constant.
    #[error("{source}; {constant}")]
    Constant {
        /// Why the last candidate failed.
        source: Box<TabularError>,
        /// The constant features, said ([`constant_said`]).
        constant: String,
    },
    /// A model file that could not be written or read, is not JSON, or not an et table model.
    #[error("{}: {source}", .path.display())]
    Model {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: TableModelError,
    },
}

/// A request that does not fit the data or the model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Misuse {
    /// A feature value to train on or predict from that is NaN or infinite.
    #[error("row {row}, feature {column}: {value}, where a finite number belongs")]
    NonFiniteFeature {
        /// Its row (0-based among those given).
        row: usize,
        /// Its column (0-based).
        column: usize,
        /// The value.
        value: f64,
    },
    /// Predictions (or a classifier's discriminants) that came out NaN or infinite from
    /// finite features: the features are far beyond the training's, or the model's tables
    /// overflow.
    #[error(
        "row {row}'s prediction is not finite from finite features: they are far beyond \
         those the model was trained on (another unit?), or the model's tables overflow (an \
         edited weight of 1e308? retrain it)"
    )]
    NonFinitePrediction {
        /// The first such row (0-based).
        row: usize,
    },
    /// A discriminant whose covariance tables would not fit in the memory free: a table of
    /// features x features per class (20 000 features: 3.2 GB each) is held several times
    /// while it is fitted and cross-validated.
    #[error(
        "{} on {features} features holds covariance tables of {features} x {features} for \
         each of {classes} classes while it is fitted, about {} GB, where {} GB is free: give \
         fewer features (a frame of 32 electrodes has at most 1 024 values; select or average \
         columns), or positions for a regressor (ridge, knn), which works on wide tables",
        .method.name(), gb(*.need_bytes), gb(*.free_bytes)
    )]
    TooWide {
        /// The discriminant.
        method: Kind,
        /// The table's features.
        features: usize,
        /// Its classes.
        classes: usize,
        /// The memory the fit would hold, bytes.
        need_bytes: u64,
        /// The memory free, bytes.
        free_bytes: u64,
    },
    /// A training estimated to take longer than its budget.
    #[error(
        "{what} would take {}, past the budget of {}: train \
         on fewer rows (--rows) or features, choose a faster kind (ridge; for labels, lda), \
         or raise the budget (--max-minutes, budget_s=)",
        crate::pipeline::cost::about(*.estimate_s), crate::pipeline::cost::time_said(*.budget_s)
    )]
    OverBudget {
        /// What was estimated.
        what: String,
        /// The estimate, s.
        estimate_s: f64,
        /// The budget, s.
        budget_s: f64,
    },
    /// More groups than cross-validation leaves out one at a time.
    #[error(
        "{groups} groups among {rows} rows: leaving each out fits every candidate {groups} \
         times; groups are sessions (at most 100), not rows: give each row its session"
    )]
    TooManyGroups {
        /// The groups named.
        groups: usize,
        /// The rows.
        rows: usize,
    },
    /// A regressor's fit without positions.
    #[error("this method needs positions")]
    NeedsPositions,
    /// A classifier's fit without classes.
    #[error("this method needs classes")]
    NeedsClasses,
    /// An average of no regressor.
    #[error("an average of no regressor")]
    EmptyAverage,
    /// A classifier searched as a regressor.
    #[error("not a regressor")]
    NotARegressor,
    /// Rows of another feature count than the model's.
    #[error(
        "the data has {data} feature columns, the model reads {model}{}",
        if *rows == Some(*model) {
            " (and the data has as many rows: are its columns the observations? give it \
             transposed, X.T in NumPy)"
        } else {
            ""
        }
    )]
    FeatureCount {
        /// The data's.
        data: usize,
        /// The model's.
        model: usize,
        /// The data's rows, where known.
        rows: Option<usize>,
    },
    /// A feature column the model reads that holds the rows' numbers, times or sessions,
    /// which tables' features no longer include.
    #[error(
        "the model reads column '{column}' as a feature, but its name says it holds the rows' \
         numbers, times or sessions, which et leaves out of the features (as features they \
         predict from the row's place in the recording): train the model again"
    )]
    NotAFeature {
        /// The column's name.
        column: String,
    },
    /// A feature column the model reads that the data does not have.
    #[error(
        "the model reads a feature column '{column}' that the data does not have (its columns must \
         be the model's feature_names, in any order)"
    )]
    MissingFeature {
        /// The column's name.
        column: String,
    },
    /// A feature column the model was not trained on.
    #[error(
        "the data has a feature column '{column}' the model was not trained on (its columns must be \
         the model's feature_names, in any order)"
    )]
    ExtraFeature {
        /// The column's name.
        column: String,
    },
    /// Too few training rows to cross-validate: each fold fits on at least two rows and tests
    /// on others.
    #[error(
        "{0} training row(s): cross-validation needs at least 3, each fold fitting on 2 or more \
         and testing on the rest (give more rows: --rows on the command line)"
    )]
    TooFewRows(usize),
    /// More folds than rows, or fewer than 2.
    #[error(
        "{folds} folds for {rows} training rows: use 2 to {rows} (--folds on the command line, \
         folds= in Python), or give more rows"
    )]
    Folds {
        /// The folds asked for.
        folds: usize,
        /// The training rows.
        rows: usize,
    },
    /// Leaving a group out without groups.
    #[error("leave-one-group-out cross-validation needs each row's group (--groups, groups=)")]
    NoGroups,
    /// A classifier asked for on rows without labels.
    #[error(
        "{} needs class labels: give a label column, or make classes from the positions with a \
         grid (--grid 7x7, grid=(7, 7))",
        .0.name()
    )]
    NeedsLabels(Kind),
    /// A regressor asked for on rows with labels only.
    #[error(
        "{} predicts positions: the targets need x and y columns (the data has only class \
         labels: use qda or lda)",
        .0.name()
    )]
    NeedsXy(Kind),
    /// Rows with no target a classifier predicts.
    #[error(
        "the rows have no target this model predicts: it predicts class labels (and positions \
         only when its classes have centres); give the rows a label column"
    )]
    NoLabelTarget,
    /// Rows with no position for a regressor.
    #[error("the rows have no target this model predicts: give positions (x, y)")]
    NoPositionTarget,
    /// More classes than a model holds.
    #[error("{0} classes: at most 65535")]
    TooManyClasses(usize),
    /// A row range past the data, or empty.
    #[error("--rows {range}: the data has rows 0..{rows}")]
    Rows {
        /// The range asked for.
        range: RowRange,
        /// The data's rows.
        rows: usize,
    },
    /// Reference features of another column count.
    #[error("{reference}: {columns} columns, the features have {features}")]
    ReferenceColumns {
        /// The reference (its file).
        reference: String,
        /// Its columns.
        columns: usize,
        /// The features'.
        features: usize,
    },
    /// Reference features of a row count that is none of one per row, one per group or one.
    #[error(
        "{reference}: {rows} rows; give one per row of the features ({features}), one per group \
         (with --groups){}, or one for all",
        groups.map_or(String::new(), |g| format!(": {g}"))
    )]
    ReferenceRows {
        /// The reference (its file).
        reference: String,
        /// Its rows.
        rows: usize,
        /// The features' rows.
        features: usize,
        /// The groups, when the rows have them.
        groups: Option<usize>,
    },
    /// A ratio's reference value that is 0 (or not finite).
    #[error(
        "{reference}: row {row} column {column}: {value}: a ratio needs a reference that is not \
         0 (use difference)"
    )]
    ZeroReference {
        /// The reference (its file).
        reference: String,
        /// Its row (1-based).
        row: usize,
        /// Its column (1-based).
        column: usize,
        /// The value.
        value: f64,
    },
    /// A group of one row, standardised per group.
    #[error("group '{group}' has {rows} row: standardising per group needs two or more")]
    SmallGroup {
        /// The group's name.
        group: String,
        /// Its rows.
        rows: usize,
    },
    /// A class grid without positions.
    #[error(
        "a grid (--grid, grid=) makes classes from positions: the targets need x and y columns"
    )]
    GridNeedsPositions,
    /// A class grid of fewer than two cells, or more rows or columns than [`GRID_MOST`].
    #[error(
        "grid {rows}x{cols}: a classifier tells at least two classes apart (2x1 or more), and \
         a grid has at most {GRID_MOST} rows and {GRID_MOST} columns"
    )]
    EmptyGrid {
        /// Rows asked for.
        rows: usize,
        /// Columns asked for.
        cols: usize,
    },
    /// One class only.
    #[error("one class ('{class}') only: nothing to tell apart; give rows of at least two classes")]
    OneClass {
        /// The class's name.
        class: String,
    },
    /// Every class of one row: none can be both learned and tested.
    #[error(
        "{classes} classes among {rows} rows, each of one row: a class needs rows to learn \
         from and rows to test on, at least 2 (are the labels row ids, names or times rather \
         than touch classes? for positions give x and y columns)"
    )]
    OneRowClasses {
        /// The classes.
        classes: usize,
        /// The rows.
        rows: usize,
    },
}

/// Bytes in GB to two significant digits (0.5, 3.2, 83).
pub(crate) fn gb(bytes: u64) -> String {
    let g = bytes as f64 / 1e9;
    if g >= 10.0 {
        format!("{g:.0}")
    } else {
        format!("{g:.2}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    }
}
