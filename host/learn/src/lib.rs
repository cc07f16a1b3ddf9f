//! `et-learn`: touch positions learnt from raw voltages (docs/method.md §9). It owns fitting,
//! cross-validation, regression, datasets and model files; it has no command line and no
//! plotting.
//!
//! The entry point is [`Trainer`]: [`Trainer::train`] fits an et dataset (QDA or LDA for the
//! board) or any sensor's table and returns a [`Model`] (in a [`Trained`], with how a board
//! model's training went): the one model type, which predicts, is evaluated, saves, loads and
//! makes the board's blob. The modules below are its stages, in the order a model is made:
//!
//! - [`collect`]: the data-collection procedure (§9.4) on the simulated sheet.
//! - [`dataset`]: datasets as CSV with provenance (Python and MATLAB read them as they are)
//!   or `.npz`, and import of other sensors' CSV.
//! - [`npz`]: NumPy's `.npz` archives written and read without numpy (what `.npz` datasets
//!   are stored in).
//! - [`fit`]: QDA and LDA in f64 with standardisation and shrinkage; export to et-core's blob.
//! - [`cv`]: stratified and leave-one-visit-out cross-validation, confusion matrix, accuracy,
//!   AEE (§9.5).
//! - [`fastcv`]: the same cross-validation from sufficient statistics with exact pruning.
//! - [`analysis`]: error against distance from the electrodes, learning curves against n_c.
//! - [`regress`]: continuous position and pressure by regression (linear ridge, kernel ridge,
//!   posterior-weighted class centres).
//! - [`gp`]: Gaussian-process regression with one learned length scale per feature.
//! - [`mlp`]: a multilayer perceptron for positions (Adam, L2, early stopping, several
//!   starts).
//! - [`model`]: the trained model in use ([`Model`]): a board model or a table's, predicting,
//!   evaluated, saved and loaded.
//! - [`model_file`]: board models on disk (JSON).
//! - [`standin`]: another lab's e-skin data set made on the simulated sheet, in its own
//!   file format (what the tabular path is tested on).
//! - [`tabular`]: any sensor's table (features and targets from CSV): QDA, LDA, ridge, kernel
//!   ridge, k nearest neighbours, the Gaussian process and the perceptron, with
//!   hyperparameters by cross-validation inside the training rows, the model file,
//!   evaluation.
//! - [`reference`](mod@reference): the reference's six published accuracies and the procedure that measures
//!   them on the simulator (the calibration's table).
//! - [`trainer`]: the entry point.
//! - [`pipeline`]: a board model's training strung together (features, shrinkage by CV, fit),
//!   as `et train`, the viewer's wizard and `et demo` do it.
#![forbid(unsafe_code)]

pub mod analysis;
pub mod collect;
pub mod cv;
pub mod dataset;
pub mod fastcv;
pub mod fingerprint;
pub mod fit;
pub mod gp;
pub mod guess;
pub mod mlp;
pub mod model;
pub mod model_file;
pub mod npz;
pub mod pipeline;
pub mod reference;
pub mod regress;
pub mod standin;
pub mod tabular;
pub mod trainer;

pub use model::{Examples, Model, ModelError};
pub use trainer::{TrainError, Trained, Trainer};
