//! Learning touch positions from raw voltages (SPEC §9): collect labelled observations,
//! fit QDA / LDA (with shrinkage), cross-validate, export the model blob the firmware runs.
//!
//! - [`analysis`]: error against distance from the electrodes, learning curves against n_c.
//! - [`collect`]: the data-collection procedure of Algorithms 2-3, on the simulator.
//! - [`fit`]: QDA and LDA in f64 with standardisation and shrinkage; export to et-core's blob.
//! - [`cv`]: stratified k-fold cross-validation, confusion matrix, accuracy, AEE [5.9-5.11].
//! - [`fastcv`]: the same cross-validation from sufficient statistics with exact pruning.
//! - [`model_file`]: trained models on disk (JSON), for `et train`, `et eval`, `et export`.
//! - [`pipeline`]: training and testing strung together (features, shrinkage by CV, fit,
//!   test, plots), as `et train`, `et eval` and `et demo` do them.
//! - [`regress`]: continuous position and pressure by regression (linear ridge, kernel ridge,
//!   posterior-weighted class centres).
//! - [`dataset`]: datasets as CSV with provenance (Python and MATLAB read them as they are),
//!   and import of other sensors' CSV.

pub mod analysis;
pub mod collect;
pub mod cv;
pub mod dataset;
pub mod fastcv;
pub mod fit;
pub mod model_file;
pub mod pipeline;
pub mod regress;

#[cfg(test)]
mod tests;
