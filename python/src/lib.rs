//! et from Python: the native part of the `et_touch` module (`et_touch._native`), over et's
//! two entry points, [`et_recon::Reconstructor`] and [`et_learn::Trainer`], and its file
//! readers. The Python API (`python/et_touch/__init__.py`) wraps these functions and classes:
//! it turns arguments into contiguous float64 arrays (no copy when they already are) and the
//! summaries, made by the same serde types the `et` command prints as JSON, into dicts.
//!
//! Every error et refuses an input with is raised as `et_touch.EtError` (a `ValueError`)
//! carrying et's message; set-up, training and long reads run without the GIL.

use pyo3::prelude::*;

mod batch;
mod files;
mod imaging;
mod learning;

pyo3::create_exception!(
    _native,
    EtError,
    pyo3::exceptions::PyValueError,
    "et refused an input: the message names the file, field or value and why."
);

/// `e` as et's message, with the causes it does not already say (as the `et` command
/// prints them), raised as [`EtError`].
pub(crate) fn refused(e: &dyn std::error::Error) -> PyErr {
    let mut message = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let said = c.to_string();
        if !message.contains(&said) {
            message = format!("{message}: {said}");
        }
        cause = c.source();
    }
    EtError::new_err(message)
}

/// A usage error of the Python API (a wrong shape, an unknown name), raised as [`EtError`].
pub(crate) fn usage(message: impl Into<String>) -> PyErr {
    EtError::new_err(message.into())
}

/// Serialises `value` as JSON for the Python side's `json.loads` (the `et` command's field
/// names, by the same types).
pub(crate) fn json(value: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| refused(&e))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("EtError", m.py().get_type::<EtError>())?;
    imaging::register(m)?;
    learning::register(m)?;
    files::register(m)?;
    Ok(())
}
