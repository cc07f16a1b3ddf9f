//! The one entry point from examples to a model: a [`Trainer`] says what to fit and how to
//! cross-validate it, [`Trainer::train`] fits it on an et dataset (QDA or LDA for the board,
//! docs/method.md §9) or on any sensor's table (`tabular`: classifiers and regressors, or the
//! best of them), and returns the [`Model`] (which predicts, is evaluated, saves itself and
//! makes the board's blob) with, for a board model, how its training went.
//! The command line, the demo, the viewer's wizard and the tests train through it.
//!
//! ```text
//! Dataset --prepare (V_m - V_0, keep p)--> shrinkage by CV --> fit --> ModelFile --> blob
//! Table --------------------------------> every candidate by CV --> fit --> TableModel
//! ```
//!
//! QDA for the board from `et collect`'s dataset, then its blob:
//!
//! ```no_run
//! use et_core::model::Precision;
//! use et_learn::{Examples, Trainer};
//!
//! let data = et_learn::dataset::load("train.npz".as_ref())?;
//! let trained = Trainer::qda().train(Examples::Dataset(&data), |_| {})?;
//! trained.model.save("model.json".as_ref())?;
//! let blob = trained.model.export_blob(Precision::F16)?; // for `et upload`
//! println!("{} bytes", blob.len());
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use et_core::model::ModelKind;

use crate::analysis::{self, CurvePoint};
use crate::dataset::{DataError, Dataset};
use crate::fastcv;
use crate::fit::FitError;
use crate::model::{Board, Examples, Model};
use crate::model_file::{ModelFile, ModelFileError};
use crate::pipeline::{self, Stage, TrainOptions};
use crate::tabular::{self, Choice, CvScheme, Kind, TabularError};

/// Why a model could not be trained.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum TrainError {
    /// The dataset cannot give the features asked for.
    #[error(transparent)]
    Data(#[from] DataError),
    /// Fitting or cross-validation failed.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// A table could not be trained on.
    #[error(transparent)]
    Table(#[from] TabularError),
    /// A fixed shrinkage outside [0, 1].
    #[error("shrinkage {0}: a number from 0 to 1 (or none: chosen by cross-validation)")]
    Shrinkage(f64),
    /// Folds of the cross-validation outside 2 to [`MAX_FOLDS`] (one fold tests on nothing;
    /// the CLI refused 1, Python trained with it).
    #[error("folds = {0}: a cross-validation takes 2 to {MAX_FOLDS} folds")]
    Folds(usize),
    /// A class of an et dataset with fewer than two observations: a cross-validation holds
    /// some of each class out and fits on the rest (one observation per class was said as
    /// "at least 2 folds (1 given)", no folds having been given).
    #[error(
        "class {class} has {count} observation{}: a cross-validation holds some of each class \
         out and fits on the rest, so each class needs at least 2 (collect more: et collect \
         --scans, --subsections or --visits)",
        if *count == 1 { "" } else { "s" }
    )]
    FewPerClass {
        /// The first such class.
        class: usize,
        /// Its observations.
        count: usize,
    },
    /// A budget that is not a number of seconds above 0 (infinity: no limit).
    #[error("budget_s = {0}: a number of seconds above 0 (inf: no limit)")]
    Budget(f64),
    /// A method an et dataset does not train (the board takes QDA or LDA).
    #[error("{0}: et datasets train qda or lda for the board; regressors take any sensor's table")]
    NotForTheBoard(&'static str),
    /// The model file could not be written.
    #[error(transparent)]
    File(#[from] ModelFileError),
    /// Training on an et dataset would hold more memory than is free.
    #[error(
        "training on {} observations of {} classes x {} features holds about {} GB (a {} x {} \
         table per class in each fold), where {} GB is free: fewer classes (et collect --grid), \
         fewer features (--keep) or fewer folds (--folds)",
        .shape.n, .shape.classes, .shape.p, tabular::gb(*.need_bytes), .shape.p, .shape.p,
        tabular::gb(*.free_bytes)
    )]
    TooLarge {
        /// The training's shape.
        shape: pipeline::cost::Shape,
        /// The memory it would hold, bytes.
        need_bytes: u64,
        /// The memory free, bytes.
        free_bytes: u64,
    },
    /// Training on an et dataset estimated to take longer than the budget.
    #[error(
        "training on {} observations of {} classes x {} features would take {}, past \
         the budget of {}: fewer classes (et collect --grid), fewer features (--keep), a \
         shrinkage given (--shrinkage: no search), or raise the budget (--max-minutes, \
         budget_s=)",
        .shape.n, .shape.classes, .shape.p, pipeline::cost::about(*.estimate_s),
        pipeline::cost::time_said(*.budget_s)
    )]
    OverBudget {
        /// The training's shape.
        shape: pipeline::cost::Shape,
        /// The estimate, s.
        estimate_s: f64,
        /// The budget, s.
        budget_s: f64,
    },
    /// The trained tables are not a model the board, or any reader of model files, would
    /// accept (`ModelFile::validate`): `train` refuses to return one.
    #[error("the trained model is not usable: {error}{}", unusable_advice(error, *shrinkage))]
    Unusable {
        /// The check that failed.
        error: FitError,
        /// The shrinkage it was fitted at.
        shrinkage: f64,
    },
}

/// What to do about an [`TrainError::Unusable`] model: a larger shrinkage when a covariance
/// is the cause, else look at the data.
fn unusable_advice(error: &FitError, shrinkage: f64) -> String {
    use et_core::model::ModelError::{IllConditioned, Singular};
    let covariance = matches!(
        error,
        FitError::Invalid(Singular { .. } | IllConditioned { .. })
            | FitError::NotPositiveDefinite { .. }
    );
    if covariance {
        format!(
            " (shrinkage {shrinkage}): train with a larger shrinkage (e.g. 0.1) \
             or more observations per class"
        )
    } else {
        " (check the dataset's header: its scan and feature columns)".into()
    }
}

/// What to train and how.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trainer {
    /// The method, or the best by cross-validation. An et dataset trains QDA (the default,
    /// also for `Auto`) or LDA.
    pub method: Choice,
    /// Et datasets: a fixed shrinkage in [0, 1], or None to choose it by cross-validation.
    pub shrinkage: Option<f64>,
    /// Folds of the cross-validation: the reported one on et datasets (None: 10), the one
    /// that chooses hyperparameters on tables (None: 5).
    pub folds: Option<usize>,
    /// Tables: how rows are dealt to folds.
    pub scheme: CvScheme,
    /// Tables: classes from positions, ROWS x COLS cells over the targets' bounding box.
    pub grid: Option<(usize, usize)>,
    /// Et datasets: train on the frames as measured instead of each frame minus its visit's
    /// untouched frame (referenced is used whenever the dataset has untouched frames).
    pub raw: bool,
    /// Et datasets: keep only this many features, those that separate the classes best.
    pub keep: Option<usize>,
    /// The seed of the shuffled folds (tables; et datasets' stratified k-fold) and of the
    /// perceptron's starts.
    pub seed: u64,
    /// Tables: standardise each group's (session's) features by its own statistics.
    pub per_group: bool,
    /// The longest a training may be estimated to take, s: on tables the Gaussian process,
    /// the perceptron, knn, kernel ridge and the discriminants estimate their time before
    /// they start, on et datasets QDA and LDA do; one past this is refused.
    pub budget_s: f64,
}

impl Default for Trainer {
    /// QDA on et datasets (referenced, shrinkage and folds as docs/method.md §9 does them),
    /// the best method by cross-validation on tables.
    fn default() -> Self {
        Self {
            method: Choice::Auto,
            shrinkage: None,
            folds: None,
            scheme: CvScheme::Shuffled,
            grid: None,
            raw: false,
            keep: None,
            seed: 1,
            per_group: false,
            budget_s: crate::tabular::BUDGET_S,
        }
    }
}

/// A stage of training, as it starts (for a progress display).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Progress<'a> {
    /// The dataset has no untouched frames: training on raw frames.
    RawFrames,
    /// Preparing the features (referencing, choosing the features kept).
    Preparing {
        /// Observations.
        rows: usize,
        /// Features before any are dropped.
        features: usize,
    },
    /// Training on an et dataset is estimated to take this long, s (said before its work).
    Estimate {
        /// The estimate, s.
        seconds: f64,
    },
    /// A stage of training on an et dataset.
    Dataset(Stage),
    /// A stage of training on a table: what, done of total.
    Table(&'a str, usize, usize),
}

/// How a board model's training went: the fit, the shrinkage's choice and the
/// cross-validations, and the features it was trained on.
#[derive(Clone, Debug)]
pub struct BoardTraining {
    /// The fit, the shrinkage's choice and the cross-validations.
    pub training: pipeline::Training,
    /// The dataset as trained on (referenced, its features kept).
    pub data: Dataset,
}

/// A trained model and, for a board model, how its training went.
#[derive(Clone, Debug)]
pub struct Trained {
    /// The model.
    pub model: Model,
    /// A board model's training (None for a table's model, whose file holds its search).
    pub board: Option<Box<BoardTraining>>,
}

impl Trained {
    /// A board model's model and training, None for a table's model.
    #[must_use]
    pub fn into_board(self) -> Option<(Board, BoardTraining)> {
        match (self.model, self.board) {
            (Model::Board(model), Some(training)) => Some((*model, *training)),
            _ => None,
        }
    }
}

/// A board model's cross-validated scores, as `et train --data --json` prints them and
/// Python's `Model.scores` gives them (accuracies are fractions, errors mm).
#[derive(Clone, Debug, serde::Serialize)]
pub struct BoardScores {
    /// QDA or LDA.
    pub kind: ModelKind,
    /// Whether the model classifies frames minus the untouched frame.
    pub referenced: bool,
    /// The shrinkage fitted.
    pub shrinkage: f64,
    /// "given", "leave-one-visit-out" or {"k-fold": k}.
    pub shrinkage_chosen_by: pipeline::ChosenBy,
    /// Cross-validated accuracy of each shrinkage tried (empty when it was given).
    pub shrinkage_scores: Vec<ShrinkageScore>,
    /// Classes, observations and features trained on.
    pub classes: usize,
    /// Observations (rows) trained on.
    pub observations: usize,
    /// Features each observation has.
    pub features: usize,
    /// k of the stratified k-fold cross-validation.
    pub cv_folds: usize,
    /// Its accuracy.
    pub cv_accuracy: f64,
    /// Its mean distance from the true class's centre to the predicted one's, mm.
    pub cv_mean_error_mm: f64,
    /// Its average Euclidean error (the misclassified observations only), mm.
    pub cv_aee_mm: f64,
    /// Leave-one-visit-out accuracy, with at least two visits: what a new session scores.
    pub leave_one_visit_out_accuracy: Option<f64>,
    /// Where training changed its recipe because the data are too few (empty normally).
    pub fallbacks: Vec<pipeline::Fallback>,
    /// When the cross-validated accuracy is no better than always guessing the commonest
    /// class: why the model learnt nothing ([`crate::guess`]).
    pub no_better_than_guessing: Option<String>,
}

/// One shrinkage tried and its cross-validated accuracy (None: its fit is not positive
/// definite in some fold, too few observations for the features).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ShrinkageScore {
    /// The candidate.
    pub shrinkage: f64,
    /// Its accuracy.
    pub accuracy: Option<f64>,
}

impl BoardTraining {
    /// The scores of this training of `board` (the model it trained).
    #[must_use]
    pub fn scores(&self, board: &Board) -> BoardScores {
        let (t, file) = (&self.training, board.file());
        let mm = file.board_positions();
        BoardScores {
            kind: t.options.kind,
            referenced: file.referenced,
            shrinkage: t.options.shrinkage,
            shrinkage_chosen_by: t.chosen_by,
            shrinkage_scores: (t.shrinkage_scores.iter())
                .map(|&(shrinkage, accuracy)| ShrinkageScore {
                    shrinkage,
                    accuracy,
                })
                .collect(),
            classes: self.data.centres.len(),
            observations: self.data.x.nrows(),
            features: self.data.x.ncols(),
            cv_folds: t.folds,
            cv_accuracy: t.cv.accuracy(),
            cv_mean_error_mm: t.cv.mean_position_error(&mm),
            cv_aee_mm: t.cv.aee(&mm),
            leave_one_visit_out_accuracy: t.leave_one_visit_out,
            fallbacks: t.fallbacks.clone(),
            no_better_than_guessing: t.cv.no_better_than_guessing().map(|g| g.to_string()),
        }
    }

    /// The sizes a learning curve is drawn at: observations per class from 12 up to the
    /// largest class.
    #[must_use]
    pub fn curve_sizes(&self) -> Vec<usize> {
        let classes = self.data.centres.len();
        let largest = (0..classes)
            .map(|c| self.data.y.iter().filter(|&&y| usize::from(y) == c).count())
            .max()
            .unwrap_or(0);
        [12, 24, 60, 120, 240, 480, 960, 1_200, 2_400, 4_800]
            .into_iter()
            .filter(|&n| n < largest)
            .chain([largest])
            .collect()
    }

    /// Held-out accuracy against observations per class n_c ([`BoardTraining::curve_sizes`]), on
    /// the folds the shrinkage was chosen on (leave-one-visit-out with several visits, else
    /// k-fold), at the fitted shrinkage; `each` is called before each size.
    #[must_use]
    pub fn learning_curve(&self, mut each: impl FnMut()) -> Vec<CurvePoint> {
        let (data, fold) = (&self.data, &self.training.selection_folds);
        let classes = data.centres.len();
        analysis::learning_curve(&data.y, classes, &self.curve_sizes(), |rows| {
            each();
            let ys: Vec<u16> = rows.iter().map(|&r| data.y[r]).collect();
            let folds: Vec<usize> = rows.iter().map(|&r| fold[r]).collect();
            fastcv::cross_validate_fast(
                &analysis::select_rows(&data.x, rows),
                &ys,
                classes,
                &self.training.options,
                &folds,
            )
        })
    }
}

impl Progress<'_> {
    /// The stage in words and how far it is (done of total; 0 of 0 where nothing is
    /// counted), as a progress display shows it; `folds` the k of an et dataset's k-fold
    /// ([`Trainer::dataset_folds`]). A table's Gaussian process and perceptron say their
    /// estimated time here before their work.
    #[must_use]
    pub fn said(&self, folds: usize) -> (String, usize, usize) {
        match *self {
            Self::RawFrames => (
                "the dataset has no untouched frames: training on raw frames".to_string(),
                0,
                0,
            ),
            Self::Preparing { rows, features } => (
                format!("preparing {rows} observations x {features} features"),
                0,
                0,
            ),
            Self::Estimate { seconds } => (
                format!("training: {}", pipeline::cost::about(seconds)),
                0,
                0,
            ),
            Self::Dataset(stage) => {
                let (done, of) = match stage {
                    Stage::Candidate { index, of, .. } => (index, of),
                    Stage::Statistics | Stage::Final => (0, 0),
                };
                (stage.said(folds), done, of)
            }
            Self::Table(what, done, of) => (what.to_string(), done, of),
        }
    }
}

/// The most folds a cross-validation takes (the command line's bound on `--folds`).
pub const MAX_FOLDS: usize = 1_000;

impl Trainer {
    /// The folds of the cross-validation reported on an et dataset: `folds`, or 10.
    #[must_use]
    pub fn dataset_folds(&self) -> usize {
        self.folds.unwrap_or(10)
    }

    /// QDA (shrinkage and folds as docs/method.md §9) on et datasets.
    #[must_use]
    pub fn qda() -> Self {
        Self::default()
    }

    /// Trains on `examples`, calling `progress` as each stage starts.
    ///
    /// # Errors
    /// [`TrainError`] when the examples do not suit the method or cannot be fitted.
    pub fn train(
        &self,
        examples: Examples<'_>,
        mut progress: impl FnMut(Progress<'_>),
    ) -> Result<Trained, TrainError> {
        if let Some(s) = self.shrinkage.filter(|s| !(0.0..=1.0).contains(s)) {
            return Err(TrainError::Shrinkage(s));
        }
        if let Some(k) = self.folds.filter(|k| !(2..=MAX_FOLDS).contains(k)) {
            return Err(TrainError::Folds(k));
        }
        // A NaN budget refused nothing (no estimate passes it); an infinite one is no limit
        // (it was refused as "not above 0").
        if self.budget_s.is_nan() || self.budget_s <= 0.0 {
            return Err(TrainError::Budget(self.budget_s));
        }
        match examples {
            Examples::Dataset(data) => {
                let (model, training) = self.train_dataset(data.clone(), &mut progress)?;
                Ok(Trained {
                    model: Model::Board(Box::new(model)),
                    board: Some(Box::new(training)),
                })
            }
            Examples::Table(table) => {
                let options = tabular::TrainOptions {
                    folds: self.folds.unwrap_or(5),
                    scheme: self.scheme,
                    grid: self.grid,
                    seed: self.seed,
                    per_group: self.per_group,
                    budget_s: self.budget_s,
                };
                let mut table_progress =
                    |what: &str, done: usize, of: usize| progress(Progress::Table(what, done, of));
                let model = tabular::train(table, self.method, &options, &mut table_progress)?;
                Ok(Trained {
                    model: Model::Table(Box::new(model)),
                    board: None,
                })
            }
        }
    }

    /// The board's discriminant kind this trainer fits on an et dataset.
    ///
    /// # Errors
    /// [`TrainError::NotForTheBoard`] for a regressor.
    pub fn board_kind(&self) -> Result<ModelKind, TrainError> {
        match self.method {
            Choice::Auto | Choice::One(Kind::Qda) => Ok(ModelKind::Qda),
            Choice::One(Kind::Lda) => Ok(ModelKind::Lda),
            Choice::One(other) => Err(TrainError::NotForTheBoard(other.name())),
        }
    }

    /// The seconds training `kind` on `data` is estimated to take ([`pipeline::cost`]),
    /// when it fits in the memory free and within the budget.
    ///
    /// # Errors
    /// [`TrainError::TooLarge`] past the memory free, [`TrainError::OverBudget`] past
    /// [`budget_s`](Self::budget_s).
    fn affordable(&self, data: &Dataset, kind: ModelKind) -> Result<f64, TrainError> {
        let shape = pipeline::cost::Shape {
            n: data.x.nrows(),
            p: data.x.ncols(),
            classes: data.centres.len(),
            folds: self.dataset_folds(),
            visits: data.visits(),
            choose: self.shrinkage.is_none(),
        };
        let need_bytes = shape.bytes();
        if let Some(free_bytes) = et_core::text::available_memory_bytes()
            && need_bytes > free_bytes
        {
            return Err(TrainError::TooLarge {
                shape,
                need_bytes,
                free_bytes,
            });
        }
        let seconds = pipeline::cost::estimate(&shape, data, kind, self.seed);
        if seconds > self.budget_s {
            return Err(TrainError::OverBudget {
                shape,
                estimate_s: seconds,
                budget_s: self.budget_s,
            });
        }
        Ok(seconds)
    }

    /// QDA or LDA on an et dataset: features (referenced when it can be), shrinkage by
    /// cross-validation unless given, the fit, and the model file it makes, checked as the
    /// board would check it ([`TrainError::Unusable`] when it would refuse it).
    fn train_dataset(
        &self,
        mut data: Dataset,
        progress: &mut impl FnMut(Progress<'_>),
    ) -> Result<(Board, BoardTraining), TrainError> {
        let kind = self.board_kind()?;
        let referenced = !self.raw && data.has_untouched();
        if !self.raw && !referenced {
            progress(Progress::RawFrames);
        }
        progress(Progress::Preparing {
            rows: data.x.nrows(),
            features: data.x.ncols(),
        });
        pipeline::prepare(&mut data, referenced, self.keep)?;
        let labelled = data.y.iter().max().map_or(0, |&c| usize::from(c) + 1);
        let mut counts = vec![0usize; data.centres.len().max(labelled)];
        for &c in &data.y {
            counts[usize::from(c)] += 1;
        }
        if let Some((class, &count)) = counts.iter().enumerate().find(|(_, n)| **n < 2) {
            return Err(TrainError::FewPerClass { class, count });
        }
        let seconds = self.affordable(&data, kind)?;
        progress(Progress::Estimate { seconds });
        let training = pipeline::train_reporting(
            &data,
            &TrainOptions {
                kind,
                shrinkage: self.shrinkage,
                folds: self.dataset_folds(),
                seed: self.seed,
            },
            |stage| progress(Progress::Dataset(stage)),
        )?;

        let mut file = ModelFile::new(
            &training.model,
            training.options.shrinkage,
            data.config,
            data.feature_index.clone(),
            data.centres.clone(),
            referenced,
        );
        file.seen = crate::fingerprint::seen_sample(&data.x);
        file.electrodes.clone_from(&data.electrodes);
        // What every reader of model files checks (et eval, stream, view, export, Python's
        // load): a model they would refuse is not returned.
        let shrinkage = file.shrinkage;
        let board = Board::new(file).map_err(|error| TrainError::Unusable { error, shrinkage })?;
        Ok((board, BoardTraining { training, data }))
    }
}
