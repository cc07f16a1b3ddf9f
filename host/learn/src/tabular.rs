//! Any sensor's table in, touch positions out: learning from data that et did not collect.
//!
//! A [`Table`] is n rows of p features (any channel count) with a target per row: a class
//! label (any text), a position (x, y in mm; files may be in metres) with an optional third
//! value (z, force), or both. [`train`] fits one [`Kind`] (or tries several with
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
use super::dataset::DatasetError;
pub use super::dataset::{GroupsFrom, Table, Unit};
use super::fastcv::cross_validate_fast;
use super::fit::{FitError, FitOptions, Fitted, Target};
use super::gp::{Gp, GpOptions};
use super::mlp::{Activation, Dense, LayersError, Mlp, MlpOptions};
use super::model_file::{ClassRecord, class_records, fitted_from_records};
use super::regress::{self, KernelRidge, Knn, Ridge, Target3, Weighting, summarise};

/// The most rows, and the most columns, of a grid of classes made from positions: 10 000
/// classes, far beyond what a sheet resolves (the method's finest grid is 10 x 10).
pub const GRID_MOST: usize = 100;

fn usage(misuse: Misuse) -> TabularError {
    TabularError::Usage(misuse)
}

/// The first NaN or infinite value of features `x` (n x p), refused by its row and column:
/// what every table trains on and predicts from is finite (a reader checks its cells; an
/// array from Python was trained on, an infinity said as a feature's mean "beyond single
/// precision").
fn finite_features(x: &DMatrix<f64>) -> Result<(), TabularError> {
    match x.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        // Column-major: the i-th value is row i % n of column i / n.
        Some((i, value)) => Err(usage(Misuse::NonFiniteFeature {
            row: i % x.nrows().max(1),
            column: i / x.nrows().max(1),
            value: *value,
        })),
        None => Ok(()),
    }
}

/// A learning method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
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
    /// A multilayer perceptron (positions): dense layers, relu or tanh, size and L2 penalty by
    /// cross-validation (`mlp`).
    Mlp,
    /// The mean of the best two or three methods' predictions, kept by `auto` when
    /// cross-validation says the mean beats the best of them.
    Average,
}

impl Kind {
    /// The name on the command line and in files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Kind::Qda => "qda",
            Kind::Lda => "lda",
            Kind::Ridge => "ridge",
            Kind::KernelRidge => "kernel-ridge",
            Kind::Knn => "knn",
            Kind::Gp => "gp",
            Kind::Mlp => "mlp",
            Kind::Average => "average",
        }
    }

    /// Whether it predicts classes (else positions).
    #[must_use]
    pub fn is_classifier(self) -> bool {
        matches!(self, Kind::Qda | Kind::Lda)
    }
}

/// What to train.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// One method.
    One(Kind),
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
    /// One fold per group (session, visit): each group held out in turn, so the score is
    /// that of a session the model never saw. Used whenever the table has two groups or more.
    Groups,
}

impl CvScheme {
    /// How it is said in reports.
    #[must_use]
    pub fn said(self) -> &'static str {
        match self {
            CvScheme::Shuffled => "shuffled",
            CvScheme::Blocks => "blocks",
            CvScheme::Groups => "leave-one-group-out",
        }
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
    /// Seed of the shuffled folds and of the final perceptron's random starts.
    pub seed: u64,
    /// Standardise each group's (session's) features by that group's own mean and spread
    /// before anything else, so a session's offsets and gains cancel; evaluation does the
    /// same to the rows it scores.
    pub per_group: bool,
    /// The longest the training may be estimated to take, s ([`BUDGET_S`] by default): the
    /// methods whose time grows fastest (the Gaussian process, the perceptron) estimate theirs
    /// before any fit, and a training past this is refused, said with the estimate.
    pub budget_s: f64,
}

/// The default training budget, s: an hour.
pub const BUDGET_S: f64 = 3_600.0;

impl Default for TrainOptions {
    fn default() -> Self {
        Self {
            per_group: false,
            budget_s: BUDGET_S,
            folds: 5,
            scheme: CvScheme::Shuffled,
            grid: None,
            seed: 1,
        }
    }
}

/// How features are referenced to a frame taken before each press (`--reference-features`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Referencing {
    /// (F - B) / B: relative change; a channel's gain cancels.
    Ratio,
    /// F - B: the change; a channel's offset cancels.
    Difference,
}

impl Choice {
    /// What a user can ask for: each method (but the average, which `auto` makes), and auto.
    pub const ASKED: [Choice; 8] = [
        Choice::One(Kind::Qda),
        Choice::One(Kind::Lda),
        Choice::One(Kind::Ridge),
        Choice::One(Kind::KernelRidge),
        Choice::One(Kind::Knn),
        Choice::One(Kind::Gp),
        Choice::One(Kind::Mlp),
        Choice::Auto,
    ];

    /// The name on the command line, in Python and in files: the method's, or "auto".
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Choice::One(m) => m.name(),
            Choice::Auto => "auto",
        }
    }

    /// The choice [`ASKED`](Self::ASKED) holds by this name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ASKED.into_iter().find(|c| c.name() == name)
    }
}

/// The methods and `auto` as command-line values (`--kind`), by their names.
#[cfg(feature = "clap")]
impl clap::ValueEnum for Choice {
    fn value_variants<'a>() -> &'a [Self] {
        &Self::ASKED
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let help = match self {
            Choice::One(Kind::Qda) => "Quadratic discriminant analysis: a covariance per class",
            Choice::One(Kind::Lda) => "Linear discriminant analysis: one pooled covariance",
            Choice::One(Kind::Ridge) => "Linear ridge regression of the position (--features)",
            Choice::One(Kind::KernelRidge) => {
                "Gaussian-kernel (RBF) ridge regression of the position (--features)"
            }
            Choice::One(Kind::Knn) => "k nearest neighbours' mean position (--features)",
            Choice::One(Kind::Gp) => {
                "Gaussian process with a length scale per feature, learned by marginal \
                 likelihood (--features): slower (it shows how long), learns which channels \
                 matter"
            }
            Choice::One(Kind::Mlp) => {
                "A multilayer perceptron (--features): three hidden layers (300, 50, 20), relu \
                 or tanh and its L2 penalty by cross-validation, Adam with early stopping, \
                 three random starts"
            }
            Choice::Auto => {
                "Every method that fits the targets, the best by cross-validation (--features)"
            }
            // Made by `auto`, not asked for.
            Choice::One(Kind::Average) => return None,
        };
        Some(clap::builder::PossibleValue::new(self.name()).help(help))
    }
}

/// The schemes a user chooses (`--cv`); leaving one group out follows from `--groups`.
#[cfg(feature = "clap")]
impl clap::ValueEnum for CvScheme {
    fn value_variants<'a>() -> &'a [Self] {
        &[CvScheme::Shuffled, CvScheme::Blocks]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        use clap::builder::PossibleValue;
        match self {
            CvScheme::Shuffled => {
                Some(PossibleValue::new("shuffled").help("At random (stratified by class)"))
            }
            CvScheme::Blocks => {
                Some(PossibleValue::new("blocks").help("Contiguous blocks in file order"))
            }
            CvScheme::Groups => None,
        }
    }
}

/// Progress of a long training: (what, done, of).
pub type Progress<'a> = &'a mut dyn FnMut(&str, usize, usize);

mod choose;
mod classify;
mod error;
mod evaluate;
mod model;
mod scores;
mod search;
mod table;

pub use choose::*;
use classify::*;
pub use error::*;
pub use evaluate::*;
pub use model::*;
pub use scores::*;
pub use search::*;
pub use table::*;
