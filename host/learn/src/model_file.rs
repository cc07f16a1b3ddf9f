//! A trained model on disk (JSON): the f64 tables of a [`Fitted`] model plus what it needs to
//! be used and exported: feature indices, class centres, the scan configuration, and how it
//! was trained. `et train` writes it; `et eval` and `et export` read it.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::{Path, PathBuf};

use et_core::ScanConfig;
use et_core::model::{ModelKind, Precision};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::fit::{ClassFit, FitError, Fitted};

/// One class as stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassRecord {
    /// Training observations.
    pub count: usize,
    /// Mean in z-space.
    pub mean: Vec<f64>,
    /// log pi_c.
    pub log_prior: f64,
    /// QDA: lower Cholesky factor packed by rows; LDA: empty.
    pub factor: Vec<f64>,
    /// QDA: log|Sigma_c|; LDA: mu^T Sigma^-1 mu.
    pub log_det_or_quad: f64,
    /// LDA: w_c; QDA: empty.
    pub weights: Vec<f64>,
}

/// The model file's format version: 2 keeps the class centres in metres (`centres_m`), 1 kept
/// them in mm (`centres_mm`).
pub const VERSION: u32 = 2;

/// What a model file's numbers are in (its `units` field).
pub const UNITS: &str =
    "SI: class centres in m; feature_mean and feature_scale in V, as the frames";

/// A model file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// Always "et-model".
    pub format: String,
    /// [`VERSION`] (version 1 files, centres in mm, are read and converted).
    pub version: u32,
    /// QDA or LDA (`"qda"` or `"lda"` in the file).
    pub kind: ModelKind,
    /// Shrinkage used.
    pub shrinkage: f64,
    /// Scan settings of the frames it classifies.
    pub config: ScanConfig,
    /// Trained on each frame minus its session's untouched frame (V_m - V_0).
    #[serde(default)]
    pub referenced: bool,
    /// Frame index of each feature.
    pub feature_index: Vec<u16>,
    /// Class centres, m (`centres_m` in the file).
    #[serde(rename = "centres_m")]
    pub centres: Vec<[f64; 2]>,
    /// Nominal electrode centres of the sheet its training data were collected on, m, one
    /// per electrode (`electrodes_m` in the file, from the dataset's): by them a sheet it is
    /// used on is compared ([`crate::model::Board::same_sheet`]). Empty when the data did not
    /// say (files written before it was kept, data without them).
    #[serde(
        rename = "electrodes_m",
        default,
        skip_serializing_if = "Vec::is_empty"
    )]
    pub electrodes: Vec<[f64; 2]>,
    /// Feature standardisation.
    pub feature_mean: Vec<f64>,
    /// Feature standardisation.
    pub feature_scale: Vec<f64>,
    /// Per class.
    pub classes: Vec<ClassRecord>,
    /// Fingerprints of up to [`crate::fingerprint::SEEN_SAMPLE`] of its training observations
    /// (their features as the model reads them: minus their visit's untouched frame when
    /// referenced), by which a test on them is said ([`crate::fingerprint::seen_sample`]); absent
    /// from files written before.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub seen: Vec<String>,
}

impl ModelFile {
    /// Wraps a fitted model.
    #[must_use]
    pub fn new(
        model: &Fitted,
        shrinkage: f64,
        config: ScanConfig,
        feature_index: Vec<u16>,
        centres: Vec<[f64; 2]>,
        referenced: bool,
    ) -> Self {
        Self {
            format: "et-model".into(),
            version: VERSION,
            kind: model.kind,
            shrinkage,
            config,
            referenced,
            feature_index,
            centres,
            electrodes: Vec::new(),
            feature_mean: model.feature_mean.clone(),
            feature_scale: model.feature_scale.clone(),
            classes: class_records(model),
            seen: Vec::new(),
        }
    }

    /// The fitted model back.
    ///
    /// # Errors
    /// [`FitError::Tables`] for an inconsistent file.
    pub fn fitted(&self) -> Result<Fitted, FitError> {
        let kind = self.kind;
        let p = self.feature_mean.len();
        if self.feature_index.len() != p || self.centres.len() != self.classes.len() {
            return Err(FitError::Tables(
                "feature or class tables of different lengths",
            ));
        }
        fitted_from_records(
            kind,
            &self.feature_mean,
            &self.feature_scale,
            &self.classes,
            &self.centres,
        )
    }

    /// The class centres as the board's tables hold them (et-core's blob): mm.
    #[must_use]
    pub fn board_positions(&self) -> Vec<[f64; 2]> {
        self.centres
            .iter()
            .map(|c| [c[0] * 1e3, c[1] * 1e3])
            .collect()
    }

    /// The features this model classifies a frame by: the frame's values `v` (K values, V) at
    /// `feature_index`, minus the untouched frame `v0` there when the model is referenced (an
    /// unreferenced model reads no `v0`). None when either frame is too short.
    #[must_use]
    pub fn features<T: Copy + Into<f64>>(&self, v: &[T], v0: &[f64]) -> Option<Vec<f64>> {
        self.feature_index
            .iter()
            .map(|&i| {
                let i = usize::from(i);
                let m: f64 = (*v.get(i)?).into();
                Some(if self.referenced { m - v0.get(i)? } else { m })
            })
            .collect()
    }

    /// The et-core blob at `precision`.
    ///
    /// # Errors
    /// [`FitError`] from [`Fitted::to_blob`].
    pub fn blob(&self, precision: Precision) -> Result<Vec<u8>, FitError> {
        let positions: Vec<[f32; 2]> = self
            .board_positions()
            .iter()
            .map(|c| [c[0] as f32, c[1] as f32])
            .collect();
        self.fitted()?.to_blob(
            self.config.electrodes,
            self.config.protocol,
            &self.feature_index,
            &positions,
            precision,
            self.referenced,
        )
    }

    /// Checks that the tables are a model the board would accept, with the board's own
    /// validation: the f32 blob through `et_core::model::Model::parse`. Every reader of model
    /// files goes through [`load`](Self::load), which calls this, so `et eval`, `et stream`,
    /// `et view` and `et export` accept and refuse the same files.
    ///
    /// # Errors
    /// [`FitError`]: inconsistent tables, or [`FitError::Invalid`] with the check that failed.
    pub fn validate(&self) -> Result<(), FitError> {
        let blob = self.blob(Precision::F32)?;
        et_core::model::Model::parse(&blob).map_err(FitError::Invalid)?;
        crate::fingerprint::check_seen(&self.seen)?;
        Ok(())
    }

    /// Writes JSON.
    ///
    /// # Errors
    /// [`ModelFileError::Io`] naming the file.
    pub fn save(&self, path: &Path) -> Result<(), ModelFileError> {
        let json = |source| ModelFileError::Json {
            path: path.into(),
            source,
        };
        let mut value = serde_json::to_value(self).map_err(json)?;
        if let Some(o) = value.as_object_mut() {
            o.insert("units".into(), UNITS.into());
            o.insert("version".into(), VERSION.into());
        }
        let text = serde_json::to_string(&value).map_err(json)?;
        std::fs::write(path, text).map_err(|source| ModelFileError::Io {
            path: path.into(),
            source,
        })
    }

    /// Reads JSON and checks it as the board would ([`validate`](Self::validate)).
    ///
    /// # Errors
    /// [`ModelFileError`] naming the file (and for a JSON syntax error, the line and column).
    pub fn load(path: &Path) -> Result<Self, ModelFileError> {
        let text = et_core::text::read_document_at_most(path, et_core::text::max_file_bytes())
            .map_err(|source| ModelFileError::Io {
                path: path.into(),
                source,
            })?;
        let value = serde_json::from_str(&text).map_err(|source| ModelFileError::Json {
            path: path.into(),
            source,
        })?;
        let m = Self::from_value(path, value)?;
        m.validate().map_err(|error| ModelFileError::Invalid {
            path: path.into(),
            error,
        })?;
        Ok(m)
    }

    /// The model file parsed from `path`'s JSON, not yet [`validate`](Self::validate)d (`path`
    /// names the file in errors).
    ///
    /// # Errors
    /// [`ModelFileError::Format`] for another format or version, [`ModelFileError::Json`] for a
    /// missing or mistyped field.
    pub fn from_value(path: &Path, mut value: serde_json::Value) -> Result<Self, ModelFileError> {
        let json = |source| ModelFileError::Json {
            path: path.into(),
            source,
        };
        let format = value.get("format").and_then(serde_json::Value::as_str);
        let version = value.get("version").and_then(serde_json::Value::as_u64);
        if format != Some("et-model") || !matches!(version, Some(1 | 2)) {
            return Err(ModelFileError::Format {
                path: path.into(),
                found: format_found(&value),
            });
        }
        // Version 1 kept the centres in mm.
        if let Some(o) = value.as_object_mut() {
            o.remove("units");
            if let Some(mm) = o.remove("centres_mm") {
                let mm: Vec<[f64; 2]> = serde_json::from_value(mm).map_err(json)?;
                let metres: Vec<[f64; 2]> = mm.iter().map(|c| [c[0] / 1e3, c[1] / 1e3]).collect();
                o.insert("centres_m".into(), serde_json::json!(metres));
            }
        }
        let mut m: ModelFile = from_value_named(value).map_err(json)?;
        m.version = VERSION;
        // The scan it was trained on as the board takes one, and a shrinkage toward the
        // pooled covariance as trained (both were loaded and said only beside data).
        let field = |field, said| ModelFileError::Field {
            path: path.into(),
            field,
            said,
        };
        if let Err(e) = m.config.validate() {
            return Err(field("config", e.to_string()));
        }
        if !(0.0..=1.0).contains(&m.shrinkage) {
            return Err(field("shrinkage", format!("{}: from 0 to 1", m.shrinkage)));
        }
        let (given, scan) = (m.electrodes.len(), usize::from(m.config.electrodes));
        if given != 0 && given != scan {
            let said =
                format!("{given} centres for a scan of {scan} electrodes: one per electrode");
            return Err(field("electrodes_m", said));
        }
        Ok(m)
    }
}

/// A fitted model's classes as stored: QDA's lower Cholesky factor packed by rows.
#[must_use]
pub fn class_records(model: &Fitted) -> Vec<ClassRecord> {
    let p = model.features();
    model
        .classes
        .iter()
        .map(|c| ClassRecord {
            count: c.count,
            mean: c.mean.iter().copied().collect(),
            log_prior: c.log_prior,
            factor: if c.factor.nrows() == p {
                (0..p)
                    .flat_map(|r| (0..=r).map(move |q| (r, q)))
                    .map(|(r, q)| c.factor.get((r, q)).copied().unwrap_or(0.0))
                    .collect()
            } else {
                Vec::new()
            },
            log_det_or_quad: c.log_det_or_quad,
            weights: c.weights.iter().copied().collect(),
        })
        .collect()
}

/// The fitted model from its standardisation, stored classes and their positions (mm; empty
/// when the classes have none), checked as the board checks a model
/// ([`et_core::model::check_class_tables`]): board and table model files accept and refuse the
/// same class tables.
///
/// # Errors
/// [`FitError::Tables`] for tables of inconsistent lengths, [`FitError::Invalid`] for tables
/// the board would refuse.
pub fn fitted_from_records(
    kind: ModelKind,
    feature_mean: &[f64],
    feature_scale: &[f64],
    records: &[ClassRecord],
    centres: &[[f64; 2]],
) -> Result<Fitted, FitError> {
    let p = feature_mean.len();
    if feature_scale.len() != p || records.is_empty() {
        return Err(FitError::Tables(
            "feature or class tables of different lengths",
        ));
    }
    let classes = records
        .iter()
        .map(|c| {
            let packed = p * (p + 1) / 2;
            let ok = c.mean.len() == p
                && match kind {
                    ModelKind::Qda => c.factor.len() == packed,
                    ModelKind::Lda => c.weights.len() == p,
                };
            if !ok {
                return Err(FitError::Tables("a class table has the wrong length"));
            }
            // The packed lower triangle, row by row (its length was checked above).
            let n = if kind == ModelKind::Qda { p } else { 0 };
            let factor = DMatrix::from_fn(n, n, |r, q| {
                if q <= r {
                    c.factor.get(r * (r + 1) / 2 + q).copied().unwrap_or(0.0)
                } else {
                    0.0
                }
            });
            Ok(ClassFit {
                count: c.count,
                mean: DVector::from_vec(c.mean.clone()),
                log_prior: c.log_prior,
                factor,
                log_det_or_quad: c.log_det_or_quad,
                weights: DVector::from_vec(c.weights.clone()),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let fitted = Fitted {
        kind,
        feature_mean: feature_mean.to_vec(),
        feature_scale: feature_scale.to_vec(),
        classes,
    };
    check_tables(&fitted, centres)?;
    Ok(fitted)
}

/// Checks a fitted model's tables as the board checks a model
/// ([`et_core::model::check_class_tables`]), with its classes' centres (m; empty when the
/// classes have none).
///
/// # Errors
/// [`FitError::Tables`] for positions of another count, [`FitError::Invalid`] for tables the
/// board would refuse.
pub fn check_tables(fitted: &Fitted, centres: &[[f64; 2]]) -> Result<(), FitError> {
    if !centres.is_empty() && centres.len() != fitted.classes.len() {
        return Err(FitError::Tables("a position for every class"));
    }
    et_core::model::check_class_tables(&Tables { fitted, centres }).map_err(FitError::Invalid)
}

/// A fitted model's tables as the board reads them (f32), for the board's checks.
struct Tables<'a> {
    fitted: &'a Fitted,
    /// Per class, m, or empty.
    centres: &'a [[f64; 2]],
}

impl et_core::model::ClassTables for Tables<'_> {
    fn kind(&self) -> ModelKind {
        self.fitted.kind
    }
    fn classes(&self) -> usize {
        self.fitted.classes.len()
    }
    fn features(&self) -> usize {
        self.fitted.features()
    }
    fn mean(&self, j: usize) -> f32 {
        at(&self.fitted.feature_mean, j)
    }
    fn scale(&self, j: usize) -> f32 {
        at(&self.fitted.feature_scale, j)
    }
    fn position_mm(&self, c: usize) -> [f32; 2] {
        // The board's tables hold mm.
        let [x, y] = self.centres.get(c).copied().unwrap_or([0.0; 2]);
        [(x * 1e3) as f32, (y * 1e3) as f32]
    }
    fn log_prior(&self, c: usize) -> f32 {
        self.fitted
            .classes
            .get(c)
            .map_or(f32::NAN, |k| k.log_prior as f32)
    }
    fn constant(&self, c: usize) -> f32 {
        (self.fitted.classes.get(c)).map_or(f32::NAN, |k| (-0.5 * k.log_det_or_quad) as f32)
    }
    fn vector(&self, c: usize, j: usize) -> f32 {
        self.fitted
            .classes
            .get(c)
            .map_or(f32::NAN, |k| match self.fitted.kind {
                ModelKind::Qda => at(k.mean.as_slice(), j),
                ModelKind::Lda => at(k.weights.as_slice(), j),
            })
    }
    fn factor(&self, c: usize, r: usize, q: usize) -> f32 {
        (self.fitted.classes.get(c))
            .and_then(|k| k.factor.get((r, q)))
            .map_or(f32::NAN, |&v| v as f32)
    }
}

/// `v[j]` in f32, NaN past the end (refused by the checks).
fn at(v: &[f64], j: usize) -> f32 {
    v.get(j).map_or(f32::NAN, |&x| x as f32)
}

/// Why a model file could not be read or written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ModelFileError {
    /// The file could not be read or written.
    #[error("{}: {source}", .path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// Not JSON, or a field missing or of the wrong type (the message names it and the line).
    #[error("{}: {source}", .path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        source: serde_json::Error,
    },
    /// JSON, but not `"format": "et-model"` of version 1 or 2.
    #[error(
        "{}: not an et-model file of version 1 or 2 ({found}; a later version is a newer et's)",
        .path.display()
    )]
    Format {
        /// The file.
        path: PathBuf,
        /// What it says instead ([`format_found`]).
        found: String,
    },
    /// A field out of its range (the scan's settings, the shrinkage).
    #[error("{}: {field}: {said}", .path.display())]
    Field {
        /// The file.
        path: PathBuf,
        /// The field.
        field: &'static str,
        /// The value and its range.
        said: String,
    },
    /// The tables are not a usable model ([`ModelFile::validate`]).
    #[error("{}: {error}", .path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Why.
        error: FitError,
    },
}

/// What a model file's JSON says of its format and version, for a message that refuses them:
/// `"format": "et-model", "version": 99`, or `no "version"` (each value cut to 40 characters).
#[must_use]
pub fn format_found(value: &serde_json::Value) -> String {
    let field = |key: &str| match value.get(key) {
        Some(v) => {
            let v = v.to_string();
            match v.char_indices().nth(40) {
                Some((at, _)) => format!("\"{key}\": {}...", &v[..at]),
                None => format!("\"{key}\": {v}"),
            }
        }
        None => format!("no \"{key}\""),
    };
    format!("{}, {}", field("format"), field("version"))
}

/// A JSON parser's error for people: what is wrong, then where for text that is not JSON
/// (`expected value (line 3, column 7)`; within one line of a file of JSON lines, whose line
/// the caller says, only the column), without serde_json's `at line 1 column 9` tail, which
/// for a field of the wrong type or missing names a place in text nobody wrote.
#[must_use]
pub fn json_said(e: &serde_json::Error, within_line: bool) -> String {
    let text = e.to_string();
    let tail = format!(" at line {} column {}", e.line(), e.column());
    let what = et_core::said::serde_said(text.strip_suffix(&tail).unwrap_or(&text));
    match e.classify() {
        serde_json::error::Category::Syntax | serde_json::error::Category::Eof if e.line() > 0 => {
            if within_line {
                format!("{what} (column {})", e.column())
            } else {
                format!("{what} (line {}, column {})", e.line(), e.column())
            }
        }
        _ => what.to_string(),
    }
}

/// `NaN`, `Infinity` or `-Infinity` where the JSON parser stopped in `text` (its line and
/// column): what Python's `json` writes for a value past a float's range, which JSON has not
/// (a model file or a recording edited in Python).
pub fn non_finite_at(text: &str, error: &serde_json::Error) -> Option<&'static str> {
    let line = text.lines().nth(error.line().checked_sub(1)?)?;
    // (The column counts characters from 1; the parser stops at the token's first.)
    let from = line.char_indices().nth(error.column().saturating_sub(1))?.0;
    let (before, rest) = line.split_at_checked(from)?;
    // (`-Infinity` stops the parser at its `I`, after the sign.)
    let signed = before.ends_with('-');
    (["-Infinity", "Infinity", "NaN"].into_iter())
        .find(|t| rest.starts_with(t))
        .map(|t| {
            if t == "Infinity" && signed {
                "-Infinity"
            } else {
                t
            }
        })
}

/// `value` read as a `T`, an error naming the field where it went wrong (`tables.method:
/// missing field`, where serde alone said `missing field` of some table) and without serde's
/// names for its own types ("expected internally tagged enum Tables", "expected f64":
/// [`et_core::said::serde_said`]).
///
/// # Errors
/// serde_json's error, its field's path in front.
pub fn from_value_named<T: serde::de::DeserializeOwned>(
    value: serde_json::Value,
) -> Result<T, serde_json::Error> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let said = et_core::said::serde_said(&e.into_inner().to_string());
        let said = if path == "." {
            said
        } else {
            format!("{path}: {said}")
        };
        <serde_json::Error as serde::de::Error>::custom(said)
    })
}
