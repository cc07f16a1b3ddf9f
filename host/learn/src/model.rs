//! The one trained-model type: [`Model`], a board model (QDA or LDA from an et dataset, what
//! the board's blob is made from) or a table's model (any sensor's features, any method). It
//! is what [`Trainer::train`](crate::Trainer::train) makes, and it predicts, is evaluated,
//! saves, loads (whichever of the two a file holds) and exports the board's blob; the checks a
//! model must pass (usable tables, the board's own validation) are made where it is loaded.
//! `et train`, `et eval`, `et export`, `et stream`, the viewer, the demo and the Python module
//! all use it.
//!
//! ```no_run
//! use et_core::model::Precision;
//! use et_learn::{Examples, Model};
//!
//! let model = Model::load("model.json".as_ref())?;
//! let data = et_learn::dataset::load("next-day.npz".as_ref())?;
//! let evaluation = model.evaluate(Examples::Dataset(&data))?;
//! let blob = model.export_blob(Precision::F16)?; // for `et upload`
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::{Path, PathBuf};

use et_core::model::Precision;
use nalgebra::DMatrix;

use crate::dataset::Dataset;
use crate::fit::FitError;
use crate::model_file::{ModelFile, ModelFileError};
use crate::tabular::Table;
use crate::tabular::{self, Prediction, TableModel, TabularError};

mod board;
mod summary;

pub use board::{Board, Classification, OnChip, SlotError, Tested, UseError};
pub use summary::TestSummary;

/// What a model is trained on ([`Trainer::train`](crate::Trainer::train)) or evaluated on
/// ([`Model::evaluate`]).
#[derive(Debug)]
pub enum Examples<'a> {
    /// An et dataset (classes, visits and their untouched frames): a model for the board.
    Dataset(&'a Dataset),
    /// Any sensor's table.
    Table(&'a Table),
}

/// A trained model.
#[derive(Clone, Debug)]
pub enum Model {
    /// QDA or LDA from an et dataset: classifies frames, on the host or on the board.
    Board(Box<Board>),
    /// A model of any sensor's table.
    Table(Box<TableModel>),
}

/// How a model did on examples it was not trained on.
#[derive(Clone, Debug)]
pub enum Evaluation {
    /// A board model on an et dataset.
    Board(Box<Tested>),
    /// A table's model on a table.
    Table(Box<tabular::Evaluation>),
}

/// Why a model could not be loaded, saved or used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelError {
    /// The file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// Not JSON, or JSON cut short (the message names the line and column, and the first
    /// line of a file that does not start as JSON does).
    #[error("{}: {}", .path.display(), json_fault(.error, .first_line.as_deref(), *.non_finite))]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's error (said in the message, not as a cause).
        error: serde_json::Error,
        /// The file's first line (at most 60 characters) when it is not JSON from its first
        /// character (a table or a scene given as a model were said as "expected ident"
        /// alone).
        first_line: Option<String>,
        /// `NaN`, `Infinity` or `-Infinity` where the parser stopped: what Python's `json`
        /// writes for a value past a float's range (an edited model was "not an et model
        /// file ... expected value").
        non_finite: Option<&'static str>,
    },
    /// Another of et's files (a dataset, a recording) given as a model: said as what it is
    /// (a recording was "trailing characters (line 2, column 1)", a dataset "expected value").
    #[error("{}: {what}, not a model file: {fix}", .path.display())]
    OtherFile {
        /// The file.
        path: PathBuf,
        /// What it is.
        what: &'static str,
        /// Where it goes.
        fix: &'static str,
    },
    /// JSON, but neither `"format": "et-model"` (a board model) nor `"et-table-model"`.
    #[error(
        "{}: not an et model file (its \"format\" is neither \"et-model\", a board model, nor \
         \"et-table-model\", a table's model: {found})",
        .path.display()
    )]
    Format {
        /// The file.
        path: PathBuf,
        /// What it says instead ([`crate::model_file::format_found`]).
        found: String,
    },
    /// A "format" that names one kind of model on the fields of the other (an edited format).
    #[error(
        "{}: its \"format\" says \"{said}\" ({}), but its fields ({}) are those of {}, \
         whose format is \"{}\": was \"format\" edited?",
        .path.display(),
        kind_of(.said), fields_of(.holds), kind_of(.holds), .holds
    )]
    OtherFormat {
        /// The file.
        path: PathBuf,
        /// The format it says.
        said: &'static str,
        /// The format its fields are.
        holds: &'static str,
    },
    /// A board model's file is not usable.
    #[error(transparent)]
    BoardFile(#[from] ModelFileError),
    /// A table's model is not usable, or could not be used on the rows.
    #[error(transparent)]
    Table(#[from] TabularError),
    /// A board model could not be used on the examples.
    #[error(transparent)]
    Use(#[from] UseError),
    /// The tables could not be exported.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The call needs the other kind of model, or the other kind of examples.
    #[error("{0}")]
    Mismatch(Mismatch),
}

/// A call that needs the other kind of model or examples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Mismatch {
    /// A blob for the board from a table's model.
    BlobFromTable,
    /// A board model given a table's rows.
    BoardOnTable,
    /// A table's model given an et dataset.
    TableOnDataset,
    /// A table's model asked to classify the board's frames (live, or in the viewer).
    TableOnFrames,
    /// A board model's referenced frames without the untouched frame.
    NoUntouchedFrame,
}

impl std::fmt::Display for Mismatch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Mismatch::BlobFromTable => {
                "only a board model (QDA or LDA trained on an et dataset) makes a blob for the \
                 board; this model was trained on a sensor's table"
            }
            Mismatch::BoardOnTable => {
                "a board model (trained on an et dataset) classifies et datasets and frames, \
                 not a sensor's table"
            }
            Mismatch::TableOnDataset => {
                "a table's model (trained on a sensor's table) is evaluated on a table of the \
                 same features, not on an et dataset"
            }
            Mismatch::TableOnFrames => {
                "a table's model (trained on a sensor's table) predicts rows of its own \
                 features, not the board's frames: give a board model (et train --data)"
            }
            Mismatch::NoUntouchedFrame => {
                "this model classifies each frame minus the untouched frame: give the \
                 untouched frame (K values)"
            }
        })
    }
}

/// What `text` is, and where it goes, when it is another of et's files than a model
/// ([`et_core::text::EtFile`]); None for any other text.
fn other_file(text: &str) -> Option<(&'static str, &'static str)> {
    use et_core::text::EtFile;
    let kind = EtFile::of(text)?;
    let fix = match kind {
        EtFile::Dataset => {
            "give it as --data (et train --data makes a model of it, et eval --data tests one)"
        }
        EtFile::Recording => {
            "`et stream --replay FILE --model MODEL` classifies its frames, and `et reconstruct \
             --frames FILE` images them"
        }
        EtFile::Protocol => "a scene names it as [scan] protocol = { file = \"FILE\" }",
        EtFile::Model => return None,
    };
    Some((kind.said(), fix))
}

/// [`ModelError::Json`]'s words after the file's name.
fn json_fault(
    error: &serde_json::Error,
    first_line: Option<&str>,
    non_finite: Option<&str>,
) -> String {
    let at = || format!("line {}, column {}", error.line(), error.column());
    if let Some(token) = non_finite {
        return format!(
            "{token} at {}: not JSON, which has no NaN or infinity (Python's json writes them \
             for values past a float's range; an edit?): a model's values are finite numbers",
            at()
        );
    }
    let what = if error.classify() == serde_json::error::Category::Eof {
        "the file ends inside its JSON (a copy cut short? write it again with et train)"
    } else {
        "not an et model file (et train writes JSON)"
    };
    let first = first_line.map_or(String::new(), |l| {
        format!(", and its first line reads {l:?}: a file of another kind given?")
    });
    format!(
        "{what}: {}{first}",
        crate::model_file::json_said(error, false)
    )
}

/// The first line of `text` (at most 60 characters, control characters left out) when
/// parsing it as JSON failed on its first characters: the text is not JSON at all.
fn first_line_if_not_json(text: &str, error: &serde_json::Error) -> Option<String> {
    const SHOWN: usize = 60;
    if error.classify() != serde_json::error::Category::Syntax
        || error.line() != 1
        || error.column() > 2
    {
        return None;
    }
    let line = text.lines().next()?.trim();
    let mut said: String = (line.chars().filter(|c| !c.is_control()))
        .take(SHOWN)
        .collect();
    if line.chars().count() > SHOWN {
        said.push_str(" ...");
    }
    (!said.is_empty()).then_some(said)
}

/// A model file's format in words.
fn kind_of(format: &str) -> &'static str {
    if format == "et-model" {
        "a board model"
    } else {
        "a table's model"
    }
}

/// The fields that tell a model file's kind.
fn fields_of(format: &str) -> &'static str {
    if format == "et-model" {
        "config, feature_index"
    } else {
        "feature_names, tables"
    }
}

impl From<Mismatch> for ModelError {
    fn from(m: Mismatch) -> Self {
        ModelError::Mismatch(m)
    }
}

impl Model {
    /// Reads a model file, a board model or a table's, and checks it is usable (a board
    /// model as the board itself would check its blob).
    ///
    /// # Errors
    /// [`ModelError`] naming the file and what is wrong with it.
    pub fn load(path: &Path) -> Result<Self, ModelError> {
        let text = et_core::text::read_document_at_most(path, et_core::text::max_file_bytes())
            .map_err(|source| ModelError::Io {
                path: path.into(),
                source,
            })?;
        Self::from_text(&text, path)
    }

    /// A model file's text (JSON, as [`load`](Self::load) reads it from a file), checked as
    /// the file would be; `origin` names it in errors (a path, or where the text came from).
    ///
    /// # Errors
    /// As [`load`](Self::load).
    pub fn from_text(text: &str, origin: &Path) -> Result<Self, ModelError> {
        let path = origin;
        if let Some((what, fix)) = other_file(text) {
            return Err(ModelError::OtherFile {
                path: path.into(),
                what,
                fix,
            });
        }
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|error| ModelError::Json {
                path: path.into(),
                first_line: first_line_if_not_json(text, &error),
                non_finite: crate::model_file::non_finite_at(text, &error),
                error,
            })?;
        let format = value.get("format").and_then(serde_json::Value::as_str);
        // Each kind's own fields: a board model's scan and frame indices, a table's tables.
        let board_fields = value.get("feature_index").is_some() && value.get("config").is_some();
        let table_fields = value.get("tables").is_some() && value.get("feature_names").is_some();
        let other = |said, holds| ModelError::OtherFormat {
            path: path.into(),
            said,
            holds,
        };
        match format {
            Some("et-model") if table_fields && !board_fields => {
                Err(other("et-model", "et-table-model"))
            }
            Some("et-table-model") if board_fields && !table_fields => {
                Err(other("et-table-model", "et-model"))
            }
            Some("et-model") => {
                let file = ModelFile::from_value(path, value)?;
                Ok(Self::board(file).map_err(|error| ModelFileError::Invalid {
                    path: path.into(),
                    error,
                })?)
            }
            Some("et-table-model") => Ok(Model::Table(Box::new(
                TableModel::from_value(value).map_err(|source| TabularError::Model {
                    path: path.into(),
                    source,
                })?,
            ))),
            _ => Err(ModelError::Format {
                path: path.into(),
                found: crate::model_file::format_found(&value),
            }),
        }
    }

    /// A board model from its file ([`Board::new`]: checked as the board would check it).
    ///
    /// # Errors
    /// [`FitError`] when its tables are not a usable model.
    pub fn board(file: ModelFile) -> Result<Self, FitError> {
        Ok(Model::Board(Box::new(Board::new(file)?)))
    }

    /// Writes the model file (JSON).
    ///
    /// # Errors
    /// [`ModelError`] naming the file.
    pub fn save(&self, path: &Path) -> Result<(), ModelError> {
        match self {
            Model::Board(b) => Ok(b.file().save(path)?),
            Model::Table(t) => Ok(t.save(path)?),
        }
    }

    /// The method's name: qda, lda, ridge, kernel-ridge, knn, gp, mlp or average.
    #[must_use]
    pub fn method(&self) -> &'static str {
        match self {
            Model::Board(b) => b.file().kind.name(),
            Model::Table(t) => t.method.name(),
        }
    }

    /// The board model, when it is one.
    #[must_use]
    pub fn as_board(&self) -> Option<&Board> {
        match self {
            Model::Board(b) => Some(b),
            Model::Table(_) => None,
        }
    }

    /// The board model, or [`Mismatch::TableOnFrames`] for a table's model (what the live
    /// pipeline and the viewer classify frames with).
    ///
    /// # Errors
    /// [`Mismatch::TableOnFrames`] for a table's model.
    pub fn into_board(self) -> Result<Board, ModelError> {
        match self {
            Model::Board(b) => Ok(*b),
            Model::Table(_) => Err(Mismatch::TableOnFrames.into()),
        }
    }

    /// The table's model, when it is one.
    #[must_use]
    pub fn as_table(&self) -> Option<&TableModel> {
        match self {
            Model::Table(t) => Some(t),
            Model::Board(_) => None,
        }
    }

    /// Predicts each row of `x`: a table's model reads features (n x p), a board model frames
    /// (n x K, V; minus `v0`, K values, when the model is referenced) and gives each frame's
    /// class and the class's centre as its position (m).
    ///
    /// # Errors
    /// [`ModelError::Table`] or [`ModelError::Use`] when the rows do not fit the model;
    /// [`Mismatch::NoUntouchedFrame`] when a referenced board model has no `v0`.
    pub fn predict(
        &self,
        x: &DMatrix<f64>,
        v0: Option<&[f64]>,
    ) -> Result<Vec<Prediction>, ModelError> {
        match self {
            Model::Table(t) => Ok(t.predict(x)?),
            Model::Board(b) => {
                // Frames of another scan are said as that first (a table's rows were asked
                // for their untouched frame).
                b.frame_lengths(x.ncols(), v0.map_or(0, <[f64]>::len))?;
                let v0 = match (v0, b.file().referenced) {
                    (Some(v0), _) => v0,
                    (None, true) => return Err(Mismatch::NoUntouchedFrame.into()),
                    (None, false) => &[],
                };
                let classes = b.predict_frames(x, v0)?;
                Ok(b.predictions(&classes))
            }
        }
    }

    /// Predicts each observation of an et dataset (a board model only).
    ///
    /// # Errors
    /// [`ModelError::Use`] when the dataset does not fit the model;
    /// [`Mismatch::TableOnDataset`] for a table's model.
    pub fn predict_dataset(&self, data: &Dataset) -> Result<Vec<Prediction>, ModelError> {
        let b = self.as_board().ok_or(Mismatch::TableOnDataset)?;
        let classes = b.predict(data)?;
        Ok(b.predictions(&classes))
    }

    /// Scores the model on examples it was not trained on: a board model on an et dataset
    /// (as `et eval --data`), a table's model on a table (as `et eval --features`).
    ///
    /// # Errors
    /// [`ModelError`] when the examples do not fit the model.
    pub fn evaluate(&self, examples: Examples<'_>) -> Result<Evaluation, ModelError> {
        match (self, examples) {
            (Model::Board(b), Examples::Dataset(data)) => {
                Ok(Evaluation::Board(Box::new(b.test(data)?)))
            }
            (Model::Table(t), Examples::Table(table)) => {
                Ok(Evaluation::Table(Box::new(tabular::evaluate(t, table)?)))
            }
            (Model::Board(_), Examples::Table(_)) => Err(Mismatch::BoardOnTable.into()),
            (Model::Table(_), Examples::Dataset(_)) => Err(Mismatch::TableOnDataset.into()),
        }
    }

    /// The board's blob at `precision` (what `et export` writes and `et upload` sends).
    ///
    /// # Errors
    /// [`Mismatch::BlobFromTable`] for a table's model; [`ModelError::Fit`] when the blob's
    /// own validation refuses the tables.
    pub fn export_blob(&self, precision: Precision) -> Result<Vec<u8>, ModelError> {
        let b = self.as_board().ok_or(Mismatch::BlobFromTable)?;
        Ok(b.blob(precision)?)
    }
}

impl Board {
    /// Each class with its centre as the position (m), a table model's prediction's shape.
    fn predictions(&self, classes: &[u16]) -> Vec<Prediction> {
        let centres = &self.file().centres;
        classes
            .iter()
            .map(|&c| Prediction {
                class: Some(c),
                target: centres.get(usize::from(c)).map(|p| [p[0], p[1], 0.0]),
            })
            .collect()
    }
}
