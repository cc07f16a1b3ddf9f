//! Learning from Python: [`et_learn::Trainer`] on arrays (any sensor's table) or on an et
//! dataset (a model for the board), and [`Model`], which predicts, is scored, saves itself
//! and makes the board's blob.

use std::path::PathBuf;

use nalgebra::DMatrix;
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use et_core::model::Precision;
use et_learn::model_file::ModelFile;
use et_learn::tabular::{self, Choice, CvScheme, Method, Table, TableModel, Unit};
use et_learn::{Examples, Trained, Trainer, cv, pipeline};

use crate::files::Dataset;
use crate::imaging::{array2, matrix};
use crate::{json, refused, usage};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(train_table, m)?)?;
    m.add_function(wrap_pyfunction!(train_dataset, m)?)?;
    m.add_class::<Model>()?;
    Ok(())
}

/// The method `kind` names ("auto" or one of `et train --kind`'s).
fn choice(kind: &str) -> PyResult<Choice> {
    use Method::*;
    if kind == "auto" {
        return Ok(Choice::Auto);
    }
    [Qda, Lda, Ridge, KernelRidge, Knn, Gp, Mlp]
        .into_iter()
        .find(|m| m.name() == kind)
        .map(Choice::One)
        .ok_or_else(|| {
            usage(format!(
                "kind '{kind}': auto, qda, lda, ridge, kernel-ridge, knn, gp or mlp"
            ))
        })
}

/// An n x p matrix from a C-contiguous float64 array.
fn features(x: &PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<DMatrix<f64>> {
    let (values, n, p) = matrix(x, what)?;
    Ok(DMatrix::from_row_slice(n, p, values))
}

/// A table from arrays: features (n x p), labels (n) and/or positions (n x 2 or n x 3, m),
/// groups (n).
fn table(
    x: &PyReadonlyArray2<'_, f64>,
    labels: Option<Vec<String>>,
    positions_m: Option<PyReadonlyArray2<'_, f64>>,
    groups: Option<Vec<String>>,
) -> PyResult<Table> {
    let x = features(x, "X")?;
    let n = x.nrows();
    let (positions_mm, third) = match &positions_m {
        None => (None, None),
        Some(p) => {
            let (values, rows, cols) = matrix(p, "y")?;
            if rows != n || !(2..=3).contains(&cols) {
                return Err(usage(format!(
                    "y: positions {rows} x {cols} for {n} rows of X; give n x 2 (x, y in m) or \
                     n x 3 (x, y, z in m)"
                )));
            }
            let row = |r: &[f64]| [r[0] * 1e3, r[1] * 1e3];
            let third = (cols == 3).then(|| {
                let z = values.chunks(cols).map(|r| r[2] * 1e3).collect();
                ("z".to_string(), z)
            });
            (Some(values.chunks(cols).map(row).collect()), third)
        }
    };
    for (what, len) in [
        ("labels", labels.as_ref().map(Vec::len)),
        ("groups", groups.as_ref().map(Vec::len)),
    ] {
        if let Some(len) = len.filter(|&l| l != n) {
            return Err(usage(format!("{what}: {len} for {n} rows of X")));
        }
    }
    Ok(Table {
        feature_names: (0..x.ncols()).map(|i| format!("f{i}")).collect(),
        description: format!("{n} rows x {} features from Python", x.ncols()),
        x,
        labels,
        positions_mm,
        third,
        first_row: 0,
        unit: Unit::M,
        groups,
    })
}

/// Trains on any sensor's table (arrays); see `et_touch.train`.
#[pyfunction]
#[pyo3(signature = (x, labels, positions_m, groups, kind, folds, cv, grid, per_group, seed))]
fn train_table(
    py: Python<'_>,
    x: PyReadonlyArray2<'_, f64>,
    labels: Option<Vec<String>>,
    positions_m: Option<PyReadonlyArray2<'_, f64>>,
    groups: Option<Vec<String>>,
    kind: &str,
    folds: Option<usize>,
    cv: &str,
    grid: Option<(usize, usize)>,
    per_group: bool,
    seed: u64,
) -> PyResult<Model> {
    let table = table(&x, labels, positions_m, groups)?;
    let trainer = Trainer {
        method: choice(kind)?,
        folds,
        scheme: match cv {
            "shuffled" => CvScheme::Shuffled,
            "blocks" => CvScheme::Blocks,
            other => return Err(usage(format!("cv '{other}': shuffled or blocks"))),
        },
        grid,
        seed,
        per_group,
        ..Trainer::default()
    };
    let trained = py
        .detach(|| trainer.train(Examples::Table(&table), |_| {}))
        .map_err(|e| refused(&e))?;
    Ok(Model::of(trained))
}

/// Trains QDA or LDA for the board on an et dataset; see `et_touch.train`.
#[pyfunction]
#[pyo3(signature = (dataset, kind, shrinkage, folds, raw, keep))]
fn train_dataset(
    py: Python<'_>,
    dataset: &Dataset,
    kind: &str,
    shrinkage: Option<f64>,
    folds: Option<usize>,
    raw: bool,
    keep: Option<usize>,
) -> PyResult<Model> {
    let trainer = Trainer {
        method: choice(kind)?,
        shrinkage,
        folds,
        raw,
        keep,
        ..Trainer::default()
    };
    trainer.board_kind().map_err(|e| refused(&e))?;
    let data = Box::new(dataset.inner.clone());
    let trained = py
        .detach(|| trainer.train(Examples::Dataset(data), |_| {}))
        .map_err(|e| refused(&e))?;
    let model = Model::of(trained);
    if let Inner::Board(file) = &model.inner {
        // What every reader of model files checks: refuse a model they would refuse.
        file.validate().map_err(|e| {
            usage(format!(
                "the trained model is not usable: {e} (shrinkage {}): train with a larger \
                 shrinkage (e.g. 0.1) or more observations per class",
                file.shrinkage
            ))
        })?;
    }
    Ok(model)
}

/// A trained model: QDA or LDA for the board (et's model file), or a table's model.
#[pyclass(module = "et_touch._native")]
pub(crate) struct Model {
    inner: Inner,
}

enum Inner {
    /// QDA or LDA from an et dataset.
    Board(ModelFile),
    /// Any sensor's table's model.
    Table(Box<TableModel>),
}

impl Model {
    fn of(trained: Trained) -> Self {
        let inner = match trained {
            Trained::Board(b) => Inner::Board(b.file),
            Trained::Table(t) => Inner::Table(t),
        };
        Self { inner }
    }
}

/// Predictions: classes (index), the class names, positions (n x 2, m) and a third target.
type Predicted<'py> = (
    Option<Bound<'py, PyArray1<i64>>>,
    Option<Vec<String>>,
    Option<Bound<'py, numpy::PyArray2<f64>>>,
    Option<Bound<'py, PyArray1<f64>>>,
);

/// A board model's classes and their centres (n x 2, m).
fn board_predictions<'py>(
    py: Python<'py>,
    file: &ModelFile,
    classes: &[u16],
) -> PyResult<Predicted<'py>> {
    let xy = classes
        .iter()
        .map(|&c| file.centres_mm.get(usize::from(c)).copied())
        .collect::<Option<Vec<[f64; 2]>>>()
        .map(|p| {
            array2(
                py,
                p.iter().flatten().map(|v| v * 1e-3).collect(),
                p.len(),
                2,
            )
        })
        .transpose()?;
    let c = PyArray1::from_vec(py, classes.iter().map(|&c| i64::from(c)).collect());
    Ok((Some(c), None, xy, None))
}

#[pymethods]
impl Model {
    /// Reads an et model file: a board model (`et train --data`) or a table's.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| {
            let text = et_core::text::read_text_at_most(&path, et_core::text::MAX_FILE_BYTES)
                .map_err(|e| usage(format!("{}: {e}", path.display())))?;
            if tabular::is_table_model(&text) {
                TableModel::load(&path)
                    .map(|t| Model {
                        inner: Inner::Table(Box::new(t)),
                    })
                    .map_err(|e| refused(&e))
            } else {
                ModelFile::load(&path)
                    .map(|f| Model {
                        inner: Inner::Board(f),
                    })
                    .map_err(|e| refused(&e))
            }
        })
    }

    /// Writes the model file (JSON), as `et train --out` does.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        match &self.inner {
            Inner::Board(f) => f.save(&path).map_err(|e| refused(&e)),
            Inner::Table(t) => t.save(&path).map_err(|e| refused(&e)),
        }
    }

    /// The method: qda, lda, ridge, kernel-ridge, knn, gp, mlp or average.
    #[getter]
    fn kind(&self) -> &'static str {
        match &self.inner {
            Inner::Board(f) => f.kind.name(),
            Inner::Table(t) => t.method.name(),
        }
    }

    /// Whether it is a board model (QDA or LDA from an et dataset: it makes a blob).
    #[getter]
    fn is_board(&self) -> bool {
        matches!(self.inner, Inner::Board(_))
    }

    /// The model file's content (JSON).
    fn file_json(&self) -> PyResult<String> {
        match &self.inner {
            Inner::Board(f) => json(f),
            Inner::Table(t) => json(t),
        }
    }

    /// Predicts each row of `x`: a table model's features (n x p), or a board model's frames
    /// (n x K, V; minus `v0` when the model is referenced).
    #[pyo3(signature = (x, v0=None))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'_, f64>,
        v0: Option<numpy::PyReadonlyArray1<'_, f64>>,
    ) -> PyResult<Predicted<'py>> {
        let (frames, _, k) = matrix(&x, "X")?;
        let positions = |p: Vec<[f64; 2]>| {
            let n = p.len();
            array2(py, p.iter().flatten().map(|v| v * 1e-3).collect(), n, 2)
        };
        match &self.inner {
            Inner::Table(t) => {
                let x = features(&x, "X")?;
                let predicted = py.detach(|| t.predict(&x)).map_err(|e| refused(&e))?;
                let classes = t.classes.as_ref().map(|_| {
                    let c = predicted.iter().map(|p| p.class.map_or(-1, i64::from));
                    PyArray1::from_vec(py, c.collect())
                });
                let targets: Option<Vec<[f64; 3]>> = predicted.iter().map(|p| p.target).collect();
                let xy = targets
                    .as_ref()
                    .map(|t| positions(t.iter().map(|t| [t[0], t[1]]).collect()))
                    .transpose()?;
                let third = (t.third.as_ref().zip(targets.as_ref())).map(|(name, t)| {
                    // A length in mm when named z (returned in m), else as written.
                    let scale = if name.eq_ignore_ascii_case("z") {
                        1e-3
                    } else {
                        1.0
                    };
                    PyArray1::from_vec(py, t.iter().map(|t| t[2] * scale).collect())
                });
                let names = t.classes.as_ref().map(|c| c.names.clone());
                Ok((classes, names, xy, third))
            }
            Inner::Board(f) => {
                let v0 = match (&v0, f.referenced) {
                    (Some(v0), _) => crate::imaging::slice(v0, "v0")?,
                    (None, true) => {
                        return Err(usage(
                            "this model classifies each frame minus the untouched frame: give \
                             v0 (the untouched frame, K values)",
                        ));
                    }
                    (None, false) => &[],
                };
                // Each frame's features as the live pipeline takes them (ModelFile::features).
                let mut chosen =
                    Vec::with_capacity(frames.len() / k.max(1) * f.feature_index.len());
                for frame in frames.chunks(k.max(1)) {
                    chosen.extend(f.features(frame, v0).ok_or_else(|| {
                        usage(format!(
                            "X: frames of {k} values, v0 of {}: the model reads value {} of \
                             frames of {} electrodes ({})",
                            v0.len(),
                            f.feature_index.iter().max().copied().unwrap_or(0),
                            f.config.electrodes,
                            f.config.protocol
                        ))
                    })?);
                }
                let p = f.feature_index.len();
                let chosen = DMatrix::from_row_slice(chosen.len() / p.max(1), p, &chosen);
                let fitted = f.fitted().map_err(|e| refused(&e))?;
                let classes = cv::predict_rows(&fitted, &chosen).map_err(|e| refused(&e))?;
                board_predictions(py, f, &classes)
            }
        }
    }

    /// A board model's class for each observation of an et dataset (its features as the
    /// model takes them, minus each visit's untouched frame when the model is referenced),
    /// and each class's centre (n x 2, m).
    fn predict_dataset<'py>(&self, py: Python<'py>, dataset: &Dataset) -> PyResult<Predicted<'py>> {
        let Inner::Board(file) = &self.inner else {
            return Err(usage(
                "a table model predicts arrays of features: model.predict(X)",
            ));
        };
        let data = &dataset.inner;
        let classes = py
            .detach(|| pipeline::predict(file, data))
            .map_err(|e| refused(&e))?;
        board_predictions(py, file, &classes)
    }

    /// Scores a table model on rows (as `et eval --features --json`): JSON.
    #[pyo3(signature = (x, labels, positions_m, groups))]
    fn evaluate_table(
        &self,
        py: Python<'_>,
        x: PyReadonlyArray2<'_, f64>,
        labels: Option<Vec<String>>,
        positions_m: Option<PyReadonlyArray2<'_, f64>>,
        groups: Option<Vec<String>>,
    ) -> PyResult<String> {
        let Inner::Table(model) = &self.inner else {
            return Err(usage(
                "a board model is scored on an et dataset: model.evaluate(read_dataset(path))",
            ));
        };
        let table = table(&x, labels, positions_m, groups)?;
        let e = py
            .detach(|| tabular::evaluate(model, &table))
            .map_err(|e| refused(&e))?;
        json(&e)
    }

    /// Scores a board model on an et dataset (as `et eval --data --json`): JSON.
    fn evaluate_dataset(&self, py: Python<'_>, dataset: &Dataset) -> PyResult<String> {
        let Inner::Board(file) = &self.inner else {
            return Err(usage(
                "a table model is scored on arrays: model.evaluate(X, y)",
            ));
        };
        let data = &dataset.inner;
        let tested = py
            .detach(|| pipeline::test(file, data))
            .map_err(|e| refused(&e))?;
        json(&tested.summary(&file.centres_mm))
    }

    /// The board's model blob (`et export`): precision "f16" or "f32".
    fn export_blob<'py>(&self, py: Python<'py>, precision: &str) -> PyResult<Bound<'py, PyBytes>> {
        let Inner::Board(file) = &self.inner else {
            return Err(usage(
                "only a board model (QDA or LDA trained on an et dataset) makes a blob",
            ));
        };
        let precision = match precision {
            "f16" => Precision::F16,
            "f32" => Precision::F32,
            other => return Err(usage(format!("precision '{other}': f16 or f32"))),
        };
        let blob = file.blob(precision).map_err(|e| refused(&e))?;
        Ok(PyBytes::new(py, &blob))
    }
}
