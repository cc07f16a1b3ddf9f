//! Datasets: labelled observations ([`Dataset`]: features, classes, positions, visits and each
//! visit's untouched frame), what can go wrong using one ([`DataError`]), and their files: CSV
//! that Python and MATLAB read as they are, or the same content as a NumPy `.npz` archive
//! that loads at disk speed ([`save_npz`], [`load_npz`]; [`save`] and [`load`] choose by the
//! file's extension).
//!
//! ```text
//! # et-dataset 2
//! # units: SI: features and untouched in V, positions and centres in m, pressure in Pa
//! # config: {"electrodes":16,"protocol":"Opposite",...}      (scan settings, JSON)
//! # feature_index: 0 1 2 4 ...                                (frame index of each feature)
//! # centres_m: 0.0093 0.0093; 0.0279 0.0093; ...              (class centres)
//! # electrodes_m: 0.0041 0; 0.0122 0; ...                     (optional: nominal electrode centres)
//! # untouched: 0.0121 ...; 0.0119 ...                        (optional: each visit's untouched frame, V)
//! # provenance: sim sheet 13 x 13 cm, seed 1, T=6 S_num=20 S_sub=20
//! f0,f1,...,f95,label,x_m,y_m,visit,pressure_pa               (pressure_pa optional)
//! 0.0123,...,3,0.0271,0.0088,0,23500
//! ```
//!
//! Every number in the file is in SI units, as in the `.npz` and the recordings (mm and kPa
//! are for what people read: plots, reports, printed positions). Version 1 files (`x_mm`,
//! `y_mm`, `pressure_kpa`, `centres_mm`, `electrodes_mm`) are read as well, converted.
//!
//! Python: `numpy.loadtxt(path, delimiter=",", comments="#", skiprows=...)` or the `csv`
//! module skipping `#` lines; MATLAB: `readmatrix(path, "CommentStyle", "#")`.
//!
//! [`Table::import`] brings data from other sensors: any channel count, a header row or none,
//! a UTF-8 byte-order mark, CRLF line ends, quoted cells, cells separated by `,`, `;` (with
//! decimal commas) or tabs (detected and said); the columns named `label` (class, any text) or `x`
//! and `y` (position, and `z`, `force` or `pressure` as a third target) are targets and all
//! others are features; targets may also come from a second file with the same rows (without
//! a header: one column is a label, two or more are x, y and a third target, e.g. z or force;
//! further columns unused).

mod check;
mod fault;
mod file;
mod import;
mod table;

use std::path::{Path, PathBuf};

use et_core::ScanConfig;
use nalgebra::DMatrix;

pub use fault::DatasetFault;
pub use file::{from_npz_bytes, load, load_csv, load_npz, npz_bytes, save, save_csv, save_npz};
pub use import::{
    GroupsFrom, Table, Unit, is_length, is_target_name, not_a_feature, read_reference,
};

/// A labelled set of observations.
#[derive(Clone, Debug)]
pub struct Dataset {
    /// n x p features (volts).
    pub x: DMatrix<f64>,
    /// Class of each observation.
    pub y: Vec<u16>,
    /// Where the finger really was for each observation, m.
    pub positions: Vec<[f64; 2]>,
    /// Pressure of each observation's touch, Pa (empty when not known).
    pub pressure: Vec<f64>,
    /// Nominal electrode centres on the sheet, m (empty when not known).
    pub electrodes: Vec<[f64; 2]>,
    /// Class centres, m.
    pub centres: Vec<[f64; 2]>,
    /// Visit of each observation (0..T): observations of one visit share the electrodes'
    /// positions, so cross-validation that must generalise across sessions folds by visit.
    pub visit: Vec<u16>,
    /// Frame index of each feature.
    pub feature_index: Vec<u16>,
    /// T x p: each visit's untouched frame (features, volts; the mean of one scan's
    /// sub-section medians, taken when the sheet is put down, before any press).
    pub baselines: DMatrix<f64>,
    /// The scan settings.
    pub config: ScanConfig,
}

impl Dataset {
    /// Visits T (one more than the largest visit number; 0 when empty).
    #[must_use]
    pub fn visits(&self) -> usize {
        self.visit
            .iter()
            .map(|&v| usize::from(v) + 1)
            .max()
            .unwrap_or(0)
    }

    /// Whether every visit has its untouched frame, so referenced features exist.
    #[must_use]
    pub fn has_untouched(&self) -> bool {
        self.baselines.nrows() >= self.visits() && self.baselines.ncols() == self.x.ncols()
    }

    /// The features a model trains on: `x` as measured, or (`referenced`) each observation
    /// minus its visit's untouched frame (V_m - V_0, see `et_core::model`).
    ///
    /// # Errors
    /// [`DataError::NoUntouched`] when `referenced` is asked of a dataset without untouched
    /// frames.
    pub fn features(&self, referenced: bool) -> Result<DMatrix<f64>, DataError> {
        if !referenced {
            return Ok(self.x.clone());
        }
        if !self.has_untouched() {
            return Err(DataError::NoUntouched {
                visits: self.visits(),
                untouched: self.baselines.nrows(),
            });
        }
        Ok(DMatrix::from_fn(self.x.nrows(), self.x.ncols(), |r, j| {
            self.x[(r, j)] - self.baselines[(usize::from(self.visit[r]), j)]
        }))
    }

    /// Appends `other` (same features) as further visits: its visit numbers and untouched
    /// frames follow this set's.
    ///
    /// # Errors
    /// [`DataError::DifferentFeatures`] when the feature sets differ.
    pub fn append(&mut self, other: Dataset) -> Result<(), DataError> {
        if other.feature_index != self.feature_index {
            return Err(DataError::DifferentFeatures {
                this: self.feature_index.len(),
                other: other.feature_index.len(),
            });
        }
        let shift = self.visits() as u16;
        let stack = |a: &DMatrix<f64>, b: &DMatrix<f64>| {
            DMatrix::from_fn(a.nrows() + b.nrows(), a.ncols(), |r, c| {
                if r < a.nrows() {
                    a[(r, c)]
                } else {
                    b[(r - a.nrows(), c)]
                }
            })
        };
        self.x = stack(&self.x, &other.x);
        self.baselines = stack(&self.baselines, &other.baselines);
        self.y.extend(other.y);
        self.positions.extend(other.positions);
        self.pressure.extend(other.pressure);
        self.visit.extend(other.visit.iter().map(|v| v + shift));
        Ok(())
    }
}

/// Why a dataset cannot give what was asked of it.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum DataError {
    /// Referenced features (V_m - V_0) need an untouched frame V_0 per visit.
    #[error(
        "referenced features need an untouched frame per visit: {visits} visits, {untouched} untouched frames"
    )]
    NoUntouched {
        /// Visits in the dataset.
        visits: usize,
        /// Untouched frames it holds.
        untouched: usize,
    },
    /// Two datasets to be joined hold different features.
    #[error("datasets with different features ({this} and {other} frame values)")]
    DifferentFeatures {
        /// Features of the set appended to.
        this: usize,
        /// Features of the set appended.
        other: usize,
    },
    /// The dataset lacks frame values a model uses.
    #[error("it lacks frame values the model uses (its {dataset} features vs the model's {model})")]
    MissingFeatures {
        /// Features in the dataset.
        dataset: usize,
        /// Features the model uses.
        model: usize,
    },
    /// A feature count to keep of 0 or more than there are.
    #[error("keep 1 to {available} features, not {keep}")]
    Keep {
        /// Asked for.
        keep: usize,
        /// Available.
        available: usize,
    },
}

/// Why a dataset file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DatasetError {
    /// The file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// The `.npz` archive, or one of its arrays, could not be read or written.
    #[error("{}: {source}", .path.display())]
    Npz {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        source: crate::npz::NpzError,
    },
    /// A text array of an `.npz` dataset is not the JSON it should hold.
    #[error("{}: array '{array}': {source}", .path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The array.
        array: &'static str,
        /// What is wrong.
        source: serde_json::Error,
    },
    /// Something in the file is wrong.
    #[error("{}: {fault}", place(path, *line, column.as_deref()))]
    Content {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when not about one line).
        line: usize,
        /// Column name or number, where it is about one.
        column: Option<String>,
        /// What is wrong (boxed: the error stays small).
        fault: Box<DatasetFault>,
    },
}

/// "file:line, column c" (the line left out when 0, the column when none).
fn place(path: &Path, line: usize, column: Option<&str>) -> String {
    let mut place = path.display().to_string();
    if line > 0 {
        place += &format!(":{line}");
    }
    if let Some(c) = column {
        place += &format!(", column {c}");
    }
    place
}

fn content(path: &Path, line: usize, column: Option<String>, fault: DatasetFault) -> DatasetError {
    DatasetError::Content {
        path: path.into(),
        line,
        column,
        fault: Box::new(fault),
    }
}
