//! Learning from Python: [`et_learn::Trainer`] on arrays (any sensor's table) or on an et
//! dataset (a model for the board), and [`Model`], which predicts, is scored, saves itself
//! and makes the board's blob.

use std::path::PathBuf;
use std::sync::OnceLock;

use nalgebra::DMatrix;
use numpy::{PyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

use et_core::model::Precision;
use et_learn::model::{Evaluation, Model as Estimator};
use et_learn::tabular::{Choice, CvScheme, Prediction, Prepared, Table, Unit};
use et_learn::{Examples, Trainer};

use crate::files::Dataset;
use crate::{array2, matrix};
use crate::{json, refused, said, usage};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(train_table, m)?)?;
    m.add_function(wrap_pyfunction!(train_dataset, m)?)?;
    m.add_function(wrap_pyfunction!(not_a_feature, m)?)?;
    m.add_class::<Model>()?;
    Ok(())
}

/// The method `kind` names ("auto" or one of `et train --kind`'s).
fn choice(kind: &str) -> PyResult<Choice> {
    Choice::from_name(kind).ok_or_else(|| {
        let names: Vec<&str> = Choice::ASKED.iter().map(|c| c.name()).collect();
        usage(format!("kind '{kind}': one of {}", names.join(", ")))
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
    let (positions, third) = match &positions_m {
        None => (None, None),
        Some(p) => {
            let (values, rows, cols) = matrix(p, "y")?;
            if rows != n || !(2..=3).contains(&cols) {
                // One column: labels kept as a matrix's column (a table's column, y[:, None]).
                let labels = if cols == 1 {
                    " (a column of labels? give them as one row: y.ravel())"
                } else {
                    ""
                };
                return Err(usage(format!(
                    "y: positions {rows} x {cols} for {n} rows of X; give n x 2 (x, y in m) or \
                     n x 3 (x, y, z in m){labels}"
                )));
            }
            let row = |r: &[f64]| [r[0], r[1]];
            let third = (cols == 3).then(|| {
                let z = values.chunks(cols).map(|r| r[2]).collect();
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
        positions,
        third,
        first_row: 0,
        unit: Unit::M,
        groups,
    })
}

/// Whether a column named `name` holds the rows' numbers, times or sessions (`id`,
/// `time_ms`, `session`), which `et train --features` leaves out of the features.
#[pyfunction]
fn not_a_feature(name: &str) -> bool {
    et_learn::dataset::not_a_feature(name)
}

/// Trains on any sensor's table (arrays); see `et_touch.train`.
#[pyfunction]
#[pyo3(signature = (x, labels, positions_m, groups, kind, folds, cv, grid, per_group, seed, label_type=None, budget_s=et_learn::tabular::BUDGET_S, progress=None, feature_names=None))]
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
    label_type: Option<String>,
    budget_s: f64,
    progress: Option<Py<PyAny>>,
    feature_names: Option<Vec<String>>,
) -> PyResult<Model> {
    let mut table = table(&x, labels, positions_m, groups)?;
    // A DataFrame's columns, so that its predictions' columns are read by name.
    if let Some(names) = feature_names {
        if names.len() != table.x.ncols() {
            return Err(usage(format!(
                "feature_names: {} for {} columns of X",
                names.len(),
                table.x.ncols()
            )));
        }
        table.feature_names = names;
    }
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
        budget_s,
        ..Trainer::default()
    };
    let mut trained = train_telling(py, &trainer, Examples::Table(&table), progress)?;
    // The labels' type, so that predictions give them back as they were given.
    if let et_learn::model::Model::Table(t) = &mut trained.model
        && let Some(c) = &mut t.classes
    {
        c.label_type = label_type;
    }
    Ok(Model::new(trained.model))
}

/// Trains QDA or LDA for the board on an et dataset; see `et_touch.train`.
#[pyfunction]
#[pyo3(signature = (dataset, kind, shrinkage, folds, raw, keep, seed, budget_s=et_learn::tabular::BUDGET_S, progress=None))]
#[allow(clippy::too_many_arguments)]
fn train_dataset(
    py: Python<'_>,
    dataset: &Dataset,
    kind: &str,
    shrinkage: Option<f64>,
    folds: Option<usize>,
    raw: bool,
    keep: Option<usize>,
    seed: u64,
    budget_s: f64,
    progress: Option<Py<PyAny>>,
) -> PyResult<Model> {
    let trainer = Trainer {
        method: choice(kind)?,
        shrinkage,
        folds,
        raw,
        keep,
        seed,
        budget_s,
        ..Trainer::default()
    };
    trainer.board_kind().map_err(|e| refused(&e))?;
    let data = &dataset.inner;
    // The trainer refuses a model the board (or any reader of model files) would refuse.
    let trained = train_telling(py, &trainer, Examples::Dataset(data), progress)?;
    // What `et train --data` prints as its notes: the recipe's changes for too few data, and
    // an accuracy no better than guessing.
    let (board, training) = trained
        .into_board()
        .ok_or_else(|| usage("an et dataset trains a board model"))?;
    let notes = training.training.notes();
    let scores = json(&training.scores(&board))?;
    let mut model = Model::new(Estimator::Board(Box::new(board)));
    model.training_note = (!notes.is_empty()).then(|| notes.join("; "));
    model.training_scores = Some(scores);
    Ok(model)
}

/// Trains without the GIL, calling `progress(what, done, total)` (when given) at each step:
/// a new `what` as each stage starts, the estimated time of the long ones in it. The first
/// exception the callable raises stops the calls, and is raised when the training ends.
fn train_telling(
    py: Python<'_>,
    trainer: &Trainer,
    examples: Examples<'_>,
    progress: Option<Py<PyAny>>,
) -> PyResult<et_learn::trainer::Trained> {
    /// The unwind that ends a training interrupted by Ctrl-C, caught below (not a panic:
    /// `resume_unwind` runs no panic hook and prints nothing).
    struct Interrupted;
    let folds = trainer.dataset_folds();
    let mut raised: Option<PyErr> = None;
    let mut checked = std::time::Instant::now();
    let trained = py.detach(|| {
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            trainer.train(examples, |stage| {
                // Ctrl-C (SIGINT: Jupyter's interrupt too) is taken at the next step, not
                // when the training ends (it ran on, minutes or an hour, with the signal
                // pending): Python's handler runs here, and a KeyboardInterrupt, or one the
                // progress callable raised, ends the training by unwinding out of it (each
                // step's state is the learner's own, dropped on the way).
                let mut interrupt = None;
                if let (Some(callable), None) = (&progress, &raised) {
                    let (what, done, total) = stage.said(folds);
                    // The callable's exception, and whether it is Ctrl-C's.
                    let failed = Python::attach(|py| {
                        let e = callable.call1(py, (what, done, total)).err()?;
                        let ctrl_c = e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py);
                        Some((e, ctrl_c))
                    });
                    match failed {
                        Some((e, true)) => interrupt = Some(e),
                        Some((e, false)) => raised = Some(e),
                        None => {}
                    }
                } else if checked.elapsed().as_millis() >= 50 {
                    checked = std::time::Instant::now();
                    interrupt = Python::attach(|py| py.check_signals()).err();
                }
                if let Some(e) = interrupt {
                    raised = Some(e);
                    std::panic::resume_unwind(Box::new(Interrupted));
                }
            })
        }))
    });
    if let Some(e) = raised {
        return Err(e);
    }
    match trained {
        Ok(trained) => trained.map_err(|e| refused(&e)),
        // Only an unwind of ours sets `raised`; any other is a panic, passed on.
        Err(unwound) => std::panic::resume_unwind(unwound),
    }
}

/// A trained model: QDA or LDA for the board (et's model file), or a table's model.
#[pyclass(module = "et_touch._native")]
pub(crate) struct Model {
    inner: Estimator,
    /// A table model rebuilt from its tables at its first prediction, kept for the next
    /// (a model is not changed once made).
    prepared: OnceLock<Prepared>,
    /// A board model trained here: what its training said (its file keeps no note).
    training_note: Option<String>,
    /// A board model trained here: its cross-validated scores, JSON (its file keeps none).
    training_scores: Option<String>,
}

/// Predictions: classes (index), the class names, positions (n x 2, m) and a third target.
type Predicted<'py> = (
    Option<Bound<'py, PyArray1<i64>>>,
    Option<Vec<String>>,
    Option<Bound<'py, numpy::PyArray2<f64>>>,
    Option<Bound<'py, PyArray1<f64>>>,
);

/// Predictions as Python takes them: classes, their names, positions (n x 2, m) and the
/// third target (z in m, else as written).
fn predicted<'py>(
    py: Python<'py>,
    model: &Estimator,
    p: &[Prediction],
) -> PyResult<Predicted<'py>> {
    let (classified, names, third) = match model {
        Estimator::Board(_) => (true, None, None),
        Estimator::Table(t) => (
            t.classes.is_some(),
            t.classes.as_ref().map(|c| c.names.clone()),
            t.third.as_deref(),
        ),
    };
    let classes = classified.then(|| {
        let c = p.iter().map(|p| p.class.map_or(-1, i64::from));
        PyArray1::from_vec(py, c.collect())
    });
    let targets: Option<Vec<[f64; 3]>> = p.iter().map(|p| p.target).collect();
    let xy = targets
        .as_ref()
        .map(|t| {
            let metres = t.iter().flat_map(|t| [t[0], t[1]]).collect();
            array2(py, metres, t.len(), 2)
        })
        .transpose()?;
    // A length in m when named z, else as written.
    let third = third
        .zip(targets.as_ref())
        .map(|(_, t)| PyArray1::from_vec(py, t.iter().map(|t| t[2]).collect()));
    Ok((classes, names, xy, third))
}

#[pymethods]
impl Model {
    /// Reads an et model file: a board model (`et train --data`) or a table's.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        py.detach(|| Estimator::load(&path))
            .map(Model::new)
            .map_err(|e| refused(&e))
    }

    /// A model from its file's text (JSON, as `file_json` gives it): how a pickled model is
    /// made again, checked as a file is; a board model trained here with its training's
    /// `scores` (JSON) and `note` (its file keeps neither).
    #[staticmethod]
    #[pyo3(signature = (text, scores=None, note=None))]
    fn from_json(
        py: Python<'_>,
        text: String,
        scores: Option<String>,
        note: Option<String>,
    ) -> PyResult<Self> {
        let origin = std::path::Path::new("the pickled model");
        let mut model = py
            .detach(|| Estimator::from_text(&text, origin))
            .map(Model::new)
            .map_err(|e| refused(&e))?;
        if matches!(model.inner, Estimator::Board(_)) {
            model.training_scores = scores;
            model.training_note = note;
        }
        Ok(model)
    }

    /// Writes the model file (JSON), as `et train --out` does: aside, then moved over the
    /// path, so that a write that fails (a full disk, a folder's name) leaves the file that
    /// was there and no partial one (it wrote in place).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        /// The save's failure: the model's (as said), or the move's over the path.
        enum Unsaved {
            Model(String),
            Output(et_host::output::OutputError),
        }
        impl From<et_host::output::OutputError> for Unsaved {
            fn from(e: et_host::output::OutputError) -> Self {
                Self::Output(e)
            }
        }
        // Checked as the CLI's outputs are (a folder, a path whose folder is missing: the
        // system's "Is a directory (os error 21)" and the file aside's name were said); a
        // file there is replaced, as Python's writers do.
        et_host::output::check(&path, &[], true).map_err(|e| refused(&e))?;
        et_host::output::write(&path, |aside| {
            self.inner.save(aside).map_err(|e| Unsaved::Model(said(&e)))
        })
        .map_err(|e| match e {
            // The user's path first, the file written aside only after it (as the CLI says).
            Unsaved::Model(e) => usage(format!("writing {}: {e}", path.display())),
            Unsaved::Output(e) => refused(&e),
        })
    }

    /// A table model's feature columns' names (None for a board model): a DataFrame's
    /// columns when it was trained on one, `f0`, `f1`, ... for arrays.
    #[getter]
    fn feature_names(&self) -> Option<Vec<String>> {
        match &self.inner {
            Estimator::Table(t) => Some(t.feature_names.clone()),
            Estimator::Board(_) => None,
        }
    }

    /// Its classes (None for a table's regression) and the features it reads per row: what
    /// its repr says, without writing the model file out (a board model of 49 classes is
    /// megabytes of it).
    #[getter]
    fn size(&self) -> (Option<usize>, usize) {
        match &self.inner {
            Estimator::Table(t) => (t.classes.as_ref().map(|c| c.names.len()), t.features()),
            Estimator::Board(b) => (Some(b.file().classes.len()), b.file().feature_index.len()),
        }
    }

    /// The method: qda, lda, ridge, kernel-ridge, knn, gp, mlp or average.
    #[getter]
    fn kind(&self) -> &'static str {
        self.inner.method()
    }

    /// Whether it is a board model (QDA or LDA from an et dataset: it makes a blob).
    #[getter]
    fn is_board(&self) -> bool {
        self.inner.as_board().is_some()
    }

    /// A table classifier's label type as given ("int", "float", "bool", "str"; None when
    /// not recorded, or not a table classifier), so predictions give labels back as given
    /// without writing the whole model file out for each call.
    #[getter]
    fn label_type(&self) -> Option<String> {
        match &self.inner {
            Estimator::Table(t) => t.classes.as_ref()?.label_type.clone(),
            Estimator::Board(_) => None,
        }
    }

    /// What the training changed from the request, and why, or found in the data (a table
    /// model's note: a feature of one value, a QDA saved as the LDA it equals; a board model
    /// trained here: the recipe's changes for too few data; either: a score no better than
    /// guessing); None when nothing.
    #[getter]
    fn note(&self) -> Option<String> {
        match &self.inner {
            Estimator::Table(t) => t.note.clone(),
            Estimator::Board(_) => self.training_note.clone(),
        }
    }

    /// What cross-validation said of the model, as `et train --json` prints it (JSON): a
    /// table model's from its file; a board model's when trained here (its file keeps no
    /// scores: None once loaded).
    fn scores_json(&self) -> PyResult<Option<String>> {
        match &self.inner {
            Estimator::Table(t) => json(&t.scores()).map(Some),
            Estimator::Board(_) => Ok(self.training_scores.clone()),
        }
    }

    /// The model file's content (JSON).
    fn file_json(&self) -> PyResult<String> {
        match &self.inner {
            Estimator::Board(b) => json(b.file()),
            Estimator::Table(t) => json(t),
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
        let x = features(&x, "X")?;
        let v0 = v0.as_ref().map(|v0| crate::slice(v0, "v0")).transpose()?;
        let note = match (self.inner.as_table(), self.inner.as_board()) {
            (Some(t), _) => t.features_scale_note(&x),
            (None, Some(b)) => b.frames_scale_note(&x, v0.unwrap_or_default()),
            (None, None) => None,
        };
        if let Some(note) = note {
            // Raised at the user's call (predict or predict_positions, `_predicted`, then
            // `_Serialised`'s call).
            let category = py.import("et_touch")?.getattr("EtWarning")?;
            let note = std::ffi::CString::new(note).map_err(|e| refused(&e))?;
            PyErr::warn(py, &category, &note, 4)?;
        }
        let p = match self.inner.as_table() {
            Some(table) => py
                .detach(|| {
                    let prepared = match self.prepared.get() {
                        Some(p) => p,
                        None => {
                            let p = table.prepare()?;
                            self.prepared.get_or_init(|| p)
                        }
                    };
                    prepared.predict(&x)
                })
                .map_err(|e| refused(&e))?,
            None => py
                .detach(|| self.inner.predict(&x, v0))
                .map_err(|e| refused(&e))?,
        };
        predicted(py, &self.inner, &p)
    }

    /// A board model's class for each observation of an et dataset (its features as the
    /// model takes them, minus each visit's untouched frame when the model is referenced),
    /// and each class's centre (n x 2, m).
    fn predict_dataset<'py>(&self, py: Python<'py>, dataset: &Dataset) -> PyResult<Predicted<'py>> {
        let data = &dataset.inner;
        let p = py
            .detach(|| self.inner.predict_dataset(data))
            .map_err(|e| refused(&e))?;
        predicted(py, &self.inner, &p)
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
        let mut table = table(&x, labels, positions_m, groups)?;
        // Columns by position (an array; a DataFrame is put in the model's order first), so
        // under the model's names: a model trained on a DataFrame scored arrays as "the
        // model reads a feature column 'ch0' that the data does not have".
        if let Estimator::Table(t) = &self.inner
            && t.feature_names.len() == table.x.ncols()
        {
            table.feature_names.clone_from(&t.feature_names);
        }
        self.evaluation(py, Examples::Table(&table))
    }

    /// Scores a board model on an et dataset (as `et eval --data --json`): JSON.
    fn evaluate_dataset(&self, py: Python<'_>, dataset: &Dataset) -> PyResult<String> {
        self.evaluation(py, Examples::Dataset(&dataset.inner))
    }

    /// The board's model blob (`et export`): precision "f16" or "f32".
    fn export_blob<'py>(&self, py: Python<'py>, precision: &str) -> PyResult<Bound<'py, PyBytes>> {
        let precision = match precision {
            "f16" => Precision::F16,
            "f32" => Precision::F32,
            other => return Err(usage(format!("precision '{other}': f16 or f32"))),
        };
        let blob = self.inner.export_blob(precision).map_err(|e| refused(&e))?;
        Ok(PyBytes::new(py, &blob))
    }
}

impl Model {
    fn new(inner: Estimator) -> Self {
        Model {
            inner,
            prepared: OnceLock::new(),
            training_note: None,
            training_scores: None,
        }
    }

    /// The model scored on `examples`, as `et eval --json` prints it (JSON).
    fn evaluation(&self, py: Python<'_>, examples: Examples<'_>) -> PyResult<String> {
        let e = py
            .detach(|| self.inner.evaluate(examples))
            .map_err(|e| refused(&e))?;
        match &e {
            Evaluation::Table(e) => json(e),
            Evaluation::Board(tested) => json(&tested.summary()),
        }
    }
}
