//! The training wizard: docs/method.md §9's collection done by hand, one cell at a time.
//!
//! Setup (grid, visits, frames per press) → for each visit: V_0 of the untouched sheet, then
//! each cell pressed in turn (the simulator can press for you) while its frames are recorded →
//! QDA trained on referenced frames with the shrinkage chosen by leave-one-visit-out →
//! cross-validated accuracy and confusion → the model used here, saved, or sent to the board.
//! Frames are taken with the opposite protocol, whose independent voltages are docs/method.md §9's
//! features.

use std::path::{Path, PathBuf};

use eframe::egui::{self, Color32, Rect, Sense, Stroke, StrokeKind, pos2, vec2};
use et_core::ScanConfig;
use et_core::board::MODEL_SLOT_BYTES;
use et_core::model::ModelKind;
use et_core::protocol::{Halving, ProtocolKind};
use et_sim::sheet::SheetSpec;
use et_sim::touch::Touch;
use nalgebra::DMatrix;

use crate::live::{Output, Processor, Source};
use et_learn::collect;
use et_learn::cv::Confusion;
use et_learn::dataset::Dataset;
use et_learn::model::{Board, SlotError};
use et_learn::pipeline;
use et_learn::tabular::{Choice, Kind};
use et_learn::{Examples, TrainError, Trainer};

/// What the wizard asks of the viewer.
#[derive(Clone, Debug, PartialEq)]
pub enum Request {
    /// Scan with this configuration (and take V_0 anew).
    Configure(ScanConfig),
    /// Press the simulated sheet (empty: release).
    Press(Vec<Touch>),
    /// Classify with this model from now on.
    UseModel(Box<Board>),
    /// Send this blob to the board.
    Upload(Vec<u8>),
    /// Save the model where the wizard says ([`Wizard::save`], given the viewer's inputs).
    Save,
}

/// Where the wizard is.
#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    /// Choosing the grid.
    Setup,
    /// Taking V_0 of visit `visit`.
    Reference {
        /// Visit (0-based).
        visit: usize,
    },
    /// Waiting for cell `cell` of visit `visit` to be pressed.
    Press {
        /// Visit (0-based).
        visit: usize,
        /// Cell (row-major from the lower left).
        cell: usize,
    },
    /// Recording the frames of a press.
    Recording {
        /// Visit (0-based).
        visit: usize,
        /// Cell.
        cell: usize,
        /// Frames recorded of this press.
        frames: usize,
    },
    /// Everything collected.
    Ready,
    /// Trained.
    Trained,
}

/// The model the wizard trained, and how it cross-validated.
#[derive(Clone, Debug)]
pub struct TrainedBoard {
    /// The model.
    pub board: Board,
    /// Stratified k-fold cross-validation.
    pub cv: Confusion,
    /// Leave-one-visit-out accuracy (several visits).
    pub leave_one_visit_out: Option<f64>,
}

/// The wizard's state.
#[derive(Clone, Debug)]
pub struct Wizard {
    /// The window is shown.
    pub open: bool,
    /// Rows of the class grid.
    pub rows: usize,
    /// Columns of the class grid.
    pub cols: usize,
    /// Visits T of the whole grid.
    pub visits: usize,
    /// Frames recorded per press (observations per class and visit).
    pub frames_per_press: usize,
    /// Where it is.
    pub step: Step,
    /// After training.
    pub trained: Option<TrainedBoard>,
    /// Where "Save" writes the model (JSON) and its blob (`.etm` beside it).
    pub save_path: String,
    /// The existing file the user was warned about: a second Save replaces it.
    replace_confirmed: Option<PathBuf>,
    /// What just happened.
    pub message: String,
    config: Option<ScanConfig>,
    centres: Vec<[f64; 2]>,
    electrodes: Vec<[f64; 2]>,
    feature_index: Vec<u16>,
    rows_x: Vec<f64>,
    y: Vec<u16>,
    visit_of: Vec<u16>,
    baselines: Vec<f64>,
    seed: u64,
}

impl Default for Wizard {
    fn default() -> Self {
        Self {
            open: false,
            rows: 3,
            cols: 3,
            visits: 2,
            frames_per_press: 10,
            step: Step::Setup,
            trained: None,
            save_path: "model.json".into(),
            replace_confirmed: None,
            message: String::new(),
            config: None,
            centres: Vec::new(),
            electrodes: Vec::new(),
            feature_index: Vec::new(),
            rows_x: Vec::new(),
            y: Vec::new(),
            visit_of: Vec::new(),
            baselines: Vec::new(),
            seed: 1,
        }
    }
}

impl Wizard {
    /// Classes of the grid.
    #[must_use]
    pub fn classes(&self) -> usize {
        self.rows * self.cols
    }

    /// Observations recorded so far.
    #[must_use]
    pub fn observations(&self) -> usize {
        self.y.len()
    }

    /// Starts collecting on `sheet` with `base`'s scan settings and the opposite protocol.
    ///
    /// # Errors
    /// [`WizardError::Config`] when the opposite protocol does not exist for this sheet.
    pub fn start(&mut self, sheet: &SheetSpec, base: ScanConfig) -> Result<Request, WizardError> {
        let config = ScanConfig {
            protocol: ProtocolKind::Opposite,
            ..base
        };
        let protocol = config.validate().map_err(WizardError::Config)?;
        self.feature_index = protocol
            .features(Halving::Reciprocity)
            .map(|k| k as u16)
            .collect();
        self.centres = collect::grid(sheet, self.rows, self.cols, 0.0);
        self.electrodes = (sheet.physical.electrodes).centres(&sheet.physical.shape);
        self.rows_x.clear();
        self.y.clear();
        self.visit_of.clear();
        self.baselines.clear();
        self.trained = None;
        self.config = Some(config);
        self.step = Step::Reference { visit: 0 };
        self.message = "keep the sheet untouched: taking V_0".into();
        Ok(Request::Configure(config))
    }

    /// The simulated press of `cell`: near its centre (a quarter finger radius off, as a
    /// hand lands), at 5 to 60 kPa.
    fn simulated_press(&mut self, cell: usize) -> Request {
        let mut rng = et_core::rng::Rng::new(self.seed);
        self.seed = self.seed.wrapping_add(1);
        let c = self.centres[cell];
        let radius = 0.0075;
        Request::Press(vec![Touch {
            position: [
                c[0] + radius / 4.0 * rng.normal(),
                c[1] + radius / 4.0 * rng.normal(),
            ],
            radius,
            pressure: 5e3 + 55e3 * rng.uniform(),
            footprint: Default::default(),
        }])
    }

    /// Takes one processed frame; returns what the viewer must do next, in order.
    pub fn observe(&mut self, out: &Output, processor: &Processor) -> Vec<Request> {
        let Some(config) = self.config else {
            return Vec::new();
        };
        if out.frame.config != config || out.referencing.is_some() {
            return Vec::new();
        }
        match self.step.clone() {
            Step::Reference { visit } => {
                let Some(v0) = processor.v0() else {
                    return Vec::new();
                };
                self.baselines
                    .extend(self.feature_index.iter().map(|&i| v0[usize::from(i)]));
                self.step = Step::Press { visit, cell: 0 };
                self.message = format!(
                    "visit {} of {}: press the highlighted cell",
                    visit + 1,
                    self.visits
                );
                Vec::new()
            }
            Step::Recording {
                visit,
                cell,
                frames,
            } => {
                if out.event.is_none() {
                    return Vec::new();
                }
                self.rows_x.extend(
                    self.feature_index
                        .iter()
                        .map(|&i| f64::from(out.frame.voltages[usize::from(i)])),
                );
                self.y.push(cell as u16);
                self.visit_of.push(visit as u16);
                let frames = frames + 1;
                if frames < self.frames_per_press {
                    self.step = Step::Recording {
                        visit,
                        cell,
                        frames,
                    };
                    return Vec::new();
                }
                // This press is done: release, then the next cell, visit or training.
                if cell + 1 < self.classes() {
                    self.step = Step::Press {
                        visit,
                        cell: cell + 1,
                    };
                    self.message = "lift the finger, then press the next cell".into();
                    vec![Request::Press(Vec::new())]
                } else if visit + 1 < self.visits {
                    self.step = Step::Reference { visit: visit + 1 };
                    self.message =
                        "visit done: lift the finger, the sheet may be moved; taking V_0".into();
                    // Released, then a new V_0 for the new visit (the configuration is
                    // re-sent, which tares).
                    vec![Request::Press(Vec::new()), Request::Configure(config)]
                } else {
                    self.step = Step::Ready;
                    self.message = format!("{} observations collected: train", self.observations());
                    vec![Request::Press(Vec::new())]
                }
            }
            _ => Vec::new(),
        }
    }

    /// The dataset collected so far.
    ///
    /// # Errors
    /// [`WizardError::Empty`] when nothing was collected.
    pub fn dataset(&self) -> Result<Dataset, WizardError> {
        let p = self.feature_index.len();
        let Some(config) = self.config.filter(|_| !self.y.is_empty() && p > 0) else {
            return Err(WizardError::Empty);
        };
        let visits = self.baselines.len() / p;
        Ok(Dataset {
            x: DMatrix::from_row_slice(self.y.len(), p, &self.rows_x),
            positions: self
                .y
                .iter()
                .map(|&c| self.centres[usize::from(c)])
                .collect(),
            y: self.y.clone(),
            pressure: Vec::new(),
            electrodes: self.electrodes.clone(),
            centres: self.centres.clone(),
            visit: self.visit_of.clone(),
            feature_index: self.feature_index.clone(),
            baselines: DMatrix::from_row_slice(visits, p, &self.baselines),
            config,
        })
    }

    /// Trains QDA on the referenced observations (shrinkage by cross-validation).
    ///
    /// # Errors
    /// [`WizardError`] when the data cannot be fitted.
    pub fn train(&mut self) -> Result<(), WizardError> {
        let data = self.dataset()?;
        // Keep the features that separate the classes best when all of them would not fit
        // a model slot of the board (f16).
        let all = data.feature_index.len();
        let fit = pipeline::features_that_fit(ModelKind::Qda, self.classes(), all);
        if fit == 0 {
            return Err(WizardError::TooManyClasses);
        }
        let per_class = self.y.len() / self.classes().max(1);
        let trainer = Trainer {
            method: Choice::One(Kind::Qda),
            folds: Some(per_class.clamp(2, 10)),
            keep: (fit < all).then_some(fit),
            ..Trainer::default()
        };
        let (board, training) = match trainer.train(Examples::Dataset(&data), |_| {}) {
            Ok(trained) => trained.into_board().ok_or(WizardError::NotBoard)?,
            Err(TrainError::Data(e)) => return Err(WizardError::Data(e)),
            Err(TrainError::Fit(e) | TrainError::Unusable { error: e, .. }) => {
                return Err(WizardError::Fit(e));
            }
            // A dataset trains a board model, QDA here: nothing else can go wrong.
            Err(other) => return Err(WizardError::Train(other)),
        };
        let (t, data) = (training.training, training.data);
        self.message = format!(
            "cross-validated accuracy {:.1} % (shrinkage {}, {} of {all} features{})",
            100.0 * t.cv.accuracy(),
            t.options.shrinkage,
            data.feature_index.len(),
            if fit < all {
                ": the ones that separate the classes best, so the model fits the board"
            } else {
                ""
            }
        );
        for note in t.notes() {
            self.message.push_str(&format!("\nnote: {note}"));
        }
        self.trained = Some(TrainedBoard {
            board,
            cv: t.cv,
            leave_one_visit_out: t.leave_one_visit_out,
        });
        self.step = Step::Trained;
        Ok(())
    }

    /// The model blob for the board: f32 if it fits a slot, else f16.
    fn blob(&self) -> Result<Vec<u8>, WizardError> {
        let t = self.trained.as_ref().ok_or(WizardError::NotTrained)?;
        t.board.slot_blob().map_err(|e| match e {
            SlotError::Fit(e) => WizardError::Fit(e),
            SlotError::TooLarge { bytes } => WizardError::TooLarge { bytes },
        })
    }
}

/// Why the wizard cannot go on.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum WizardError {
    /// The sheet cannot be scanned with the opposite protocol.
    #[error("the opposite protocol: {0}")]
    Config(et_core::config::ConfigError),
    /// Nothing collected yet.
    #[error("no observations yet")]
    Empty,
    /// Even one feature per class would not fit a model slot of the board.
    #[error("too many classes for a model slot of the board: use a smaller grid")]
    TooManyClasses,
    /// The collected set cannot give the features.
    #[error(transparent)]
    Data(et_learn::dataset::DataError),
    /// The fit failed.
    #[error(transparent)]
    Fit(et_learn::fit::FitError),
    /// The training failed otherwise.
    #[error(transparent)]
    Train(et_learn::trainer::TrainError),
    /// The training gave a model other than a board model.
    #[error("the training gave a table model, not a board model")]
    NotBoard,
    /// No model trained yet.
    #[error("train first")]
    NotTrained,
    /// The model is larger than a slot, even in f16.
    #[error("the model needs {bytes} bytes, a slot holds {MODEL_SLOT_BYTES}: use a smaller grid")]
    TooLarge {
        /// Its size, bytes.
        bytes: usize,
    },
}
mod ui;
