//! et's files from Python: datasets (`et collect`'s .csv and .npz), recordings (`et sim`,
//! `et record`) and any system's frame files, as NumPy arrays.

use std::path::PathBuf;

use nalgebra::DMatrix;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;

use crate::array2;
use crate::{json, refused, usage};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(read_recording, m)?)?;
    m.add_function(wrap_pyfunction!(read_frames, m)?)?;
    m.add_class::<Dataset>()?;
    Ok(())
}

/// An n x p matrix as a row-major 2-D array.
fn rows_of<'py>(py: Python<'py>, m: &DMatrix<f64>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    array2(py, m.transpose().as_slice().to_vec(), m.nrows(), m.ncols())
}

/// Points (m) as an n x 2 array.
fn points<'py>(py: Python<'py>, p: &[[f64; 2]]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    array2(py, p.iter().flatten().copied().collect(), p.len(), 2)
}

/// An et dataset (`et collect`'s .csv or .npz, [`et_learn::dataset::Dataset`]).
#[pyclass(module = "et_touch._native", frozen)]
pub(crate) struct Dataset {
    pub(crate) inner: et_learn::dataset::Dataset,
}

#[pymethods]
impl Dataset {
    /// Reads `path` (.csv or .npz).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py
            .detach(|| et_learn::dataset::load(&path))
            .map_err(|e| refused(&e))?;
        Ok(Self { inner })
    }

    /// How pickle (copy.deepcopy, multiprocessing, joblib) makes the dataset again: from the
    /// `.npz` `et collect` writes, by `et_touch._dataset_from_npz`.
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, pyo3::types::PyBytes>,))> {
        let bytes = et_learn::dataset::npz_bytes(&self.inner, "pickled by et_touch")
            .map_err(|e| refused(&e))?;
        let make = py.import("et_touch")?.getattr("_dataset_from_npz")?;
        Ok((make, (pyo3::types::PyBytes::new(py, &bytes),)))
    }

    /// A dataset from the bytes of its `.npz` (what `__reduce__` gives pickle).
    #[staticmethod]
    fn from_npz_bytes(py: Python<'_>, bytes: Vec<u8>) -> PyResult<Self> {
        let origin = std::path::Path::new("the pickled dataset");
        let inner = py
            .detach(|| et_learn::dataset::from_npz_bytes(bytes, origin))
            .map_err(|e| refused(&e))?;
        Ok(Self { inner })
    }

    /// Observations, n x p (V).
    #[getter]
    fn x<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows_of(py, &self.inner.x)
    }

    /// Class of each observation, n.
    #[getter]
    fn y<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(py, self.inner.y.iter().map(|&c| i64::from(c)).collect())
    }

    /// Where each press really was, n x 2 (m).
    #[getter]
    fn positions_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        points(py, &self.inner.positions)
    }

    /// Each press's pressure, n (Pa; empty when not known).
    #[getter]
    fn pressure_pa<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.inner.pressure.clone())
    }

    /// The classes' centres, C x 2 (m).
    #[getter]
    fn centres_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        points(py, &self.inner.centres)
    }

    /// The electrodes' nominal centres, L x 2 (m; empty when not known).
    #[getter]
    fn electrodes_m<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        points(py, &self.inner.electrodes)
    }

    /// Visit (session) of each observation, n.
    #[getter]
    fn visit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        PyArray1::from_vec(py, self.inner.visit.iter().map(|&v| i64::from(v)).collect())
    }

    /// The frame index of each feature, p.
    #[getter]
    fn feature_index<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let index = self.inner.feature_index.iter().map(|&i| i64::from(i));
        PyArray1::from_vec(py, index.collect())
    }

    /// Each visit's untouched frame, T x p (V).
    #[getter]
    fn untouched<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        rows_of(py, &self.inner.baselines)
    }

    /// The scan settings (JSON).
    #[getter]
    fn config_json(&self) -> PyResult<String> {
        json(&self.inner.config)
    }

    /// Its size and scan, as `et train` says it (it was `<et_touch._native.Dataset object>`).
    fn __repr__(&self) -> String {
        let d = &self.inner;
        format!(
            "Dataset({} observations of {} features, {} classes, {} visits; {} electrodes, {})",
            d.x.nrows(),
            d.x.ncols(),
            d.centres.len(),
            d.visits(),
            d.config.electrodes,
            format!("{:?}", d.config.protocol).to_lowercase()
        )
    }
}

/// A recording's voltages, n x K row after row (the reader refuses frames of another
/// length; NaN would stand in).
fn volts(r: &et_host::recording::Recording) -> Vec<f64> {
    let k = r.header.frame_len;
    (r.records.iter())
        .flat_map(|rec| (0..k).map(|i| rec.voltages.get(i).map_or(f64::NAN, |&v| f64::from(v))))
        .collect()
}

/// A recording: its header (JSON), the voltages (n x K, V; NaN where the board sent NaN or
/// infinity), seq (n), t_us (n), flags (n), each frame's truth (JSON: a list per frame, null
/// where unknown), and whether a cut last line was skipped.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn read_recording<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(
    String,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    Bound<'py, PyArray1<i64>>,
    String,
    bool,
)> {
    let r = py
        .detach(|| et_host::recording::read(&path))
        .map_err(|e| refused(&e))?;
    let k = r.header.frame_len;
    let column = |f: &dyn Fn(&et_host::recording::Record) -> i64| {
        PyArray1::from_vec(py, r.records.iter().map(f).collect())
    };
    let touches: Vec<_> = r.records.iter().map(|rec| &rec.touches).collect();
    Ok((
        json(&r.header)?,
        array2(py, volts(&r), r.records.len(), k)?,
        column(&|rec| i64::from(rec.seq)),
        column(&|rec| i64::from(rec.t_us)),
        column(&|rec| i64::from(rec.flags)),
        json(&touches)?,
        r.truncated_tail,
    ))
}

/// Any system's frames (CSV, .npy, FILE.npz:NAME, FILE.mat:VARIABLE; `et reconstruct
/// --frames`'s reader) for a protocol of `k` values a frame: n x K (V) and what was read.
#[pyfunction]
fn read_frames<'py>(
    py: Python<'py>,
    path: PathBuf,
    k: usize,
) -> PyResult<(Bound<'py, PyArray2<f64>>, String)> {
    if !et_host::frames::reads_as_table(&path) {
        // An et recording, as `et reconstruct --frames` takes one (it was read as a CSV and
        // refused for its JSON): its voltages.
        let r = py
            .detach(|| et_host::recording::read(&path))
            .map_err(|e| refused(&e))?;
        if r.header.frame_len != k {
            return Err(usage(format!(
                "{}: an et recording of K = {} values a frame, not {k}",
                path.display(),
                r.header.frame_len
            )));
        }
        let n = r.records.len();
        let said = format!(
            "{}: {n} frames of {k} values (an et recording)",
            path.display()
        );
        return Ok((array2(py, volts(&r), n, k)?, said));
    }
    let frames = py
        .detach(|| et_host::frames::read(&path, k))
        .map_err(|e| refused(&e))?;
    let n = frames.frames.len();
    let flat = frames.frames.iter().flatten().map(|&v| f64::from(v));
    Ok((array2(py, flat.collect(), n, k)?, frames.description))
}
