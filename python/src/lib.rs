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
mod sheets;

pyo3::create_exception!(
    _native,
    EtError,
    pyo3::exceptions::PyValueError,
    "et refused an input: the message names the file, field or value and why."
);

/// `e` as et's message, with the causes it does not already say (as the `et` command
/// prints them), raised as [`EtError`].
pub(crate) fn refused(e: &dyn std::error::Error) -> PyErr {
    EtError::new_err(said(e))
}

/// `e` with the causes it does not already say, as the `et` command prints them.
pub(crate) fn said(e: &dyn std::error::Error) -> String {
    let mut message = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        let said = c.to_string();
        if !message.contains(&said) {
            message = format!("{message}: {said}");
        }
        cause = c.source();
    }
    message
}

/// Raises `KeyboardInterrupt` when Python was asked to stop (Ctrl-C, Jupyter's interrupt)
/// since it last looked: what work done without the GIL checks between its steps, taking
/// the GIL back for the check.
pub(crate) fn interrupted() -> PyResult<()> {
    Python::attach(|py| py.check_signals())
}

/// `work`'s result, made on a thread of its own while this one takes Ctrl-C: one long call
/// of et's (a set-up) has few steps to check between, so the caller returns at the interrupt
/// and the work, given a `stop` to ask between its stages, ends in the background at its
/// next stage, its result dropped.
///
/// # Errors
/// `KeyboardInterrupt` at an interrupt; an [`EtError`] when the thread cannot be started or
/// `work` panicked (a bug).
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(&dyn Fn() -> bool) -> T + Send + 'static,
) -> PyResult<T> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::mpsc::RecvTimeoutError;
    let (tx, mut rx) = std::sync::mpsc::channel();
    // Set at the interrupt: the work asks it between its stages and ends at the next one.
    let stop = std::sync::Arc::new(AtomicBool::new(false));
    let asked = std::sync::Arc::clone(&stop);
    std::thread::Builder::new()
        .name("et set-up".into())
        // The stack of the Python thread it stands in for.
        .stack_size(8 << 20)
        .spawn(move || {
            // (A receiver gone means the caller was interrupted: nothing to tell.)
            let _ = tx.send(work(&|| asked.load(Ordering::Relaxed)));
        })
        .map_err(|e| usage(format!("starting a thread for the work: {e}")))?;
    loop {
        // (The receiver is moved into the wait and back: it is not `Sync`.)
        let waited;
        (rx, waited) = py.detach(move || {
            let waited = rx.recv_timeout(std::time::Duration::from_millis(50));
            (rx, waited)
        });
        match waited {
            Ok(done) => return Ok(done),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(interrupt) = py.check_signals() {
                    stop.store(true, Ordering::Relaxed);
                    return Err(interrupt);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(usage("the work ended without a result (a bug of et's)"));
            }
        }
    }
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

/// A C-contiguous float64 array's values in place (the Python side makes it so).
pub(crate) fn slice<'a>(
    a: &'a numpy::PyReadonlyArray1<'_, f64>,
    what: &str,
) -> PyResult<&'a [f64]> {
    a.as_slice()
        .map_err(|_| usage(format!("{what}: a contiguous float64 array")))
}

/// The rows of a C-contiguous 2-D float64 array (rows x columns, row-major) in place.
pub(crate) fn matrix<'a>(
    a: &'a numpy::PyReadonlyArray2<'_, f64>,
    what: &str,
) -> PyResult<(&'a [f64], usize, usize)> {
    use numpy::PyUntypedArrayMethods as _;
    let [rows, cols] = [a.shape()[0], a.shape()[1]];
    let values = a
        .as_slice()
        .map_err(|_| usage(format!("{what}: a contiguous float64 array")))?;
    Ok((values, rows, cols))
}

/// `values` (rows x cols, row-major) as a 2-D array.
pub(crate) fn array2<T: numpy::Element>(
    py: Python<'_>,
    values: Vec<T>,
    rows: usize,
    cols: usize,
) -> PyResult<Bound<'_, numpy::PyArray2<T>>> {
    use numpy::PyArrayMethods as _;
    numpy::PyArray1::from_vec(py, values).reshape([rows, cols])
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("EtError", m.py().get_type::<EtError>())?;
    // The training budget's default, s, for the Python side's `budget_s=None`.
    m.add("BUDGET_S", et_learn::tabular::BUDGET_S)?;
    // The native bounds of the counts that the Python side checks first (a negative number or
    // a fraction cannot reach the native side), (least, most), to say them when it refuses.
    let counts = pyo3::types::PyDict::new(m.py());
    let (l_min, l_max) = (et_core::protocol::L_MIN, et_core::protocol::L_MAX);
    counts.set_item("electrodes", (usize::from(l_min), usize::from(l_max)))?;
    use et_recon::limits::{ITERATIONS, PIXELS, REPEATS, TRIANGLES};
    for (name, range) in [
        ("triangles", TRIANGLES),
        ("pixels", PIXELS),
        ("iterations", ITERATIONS),
        ("repeats", REPEATS),
        ("folds", 2..=et_learn::trainer::MAX_FOLDS),
    ] {
        counts.set_item(name, (*range.start(), *range.end()))?;
    }
    m.add("COUNTS", counts)?;
    imaging::register(m)?;
    learning::register(m)?;
    files::register(m)?;
    Ok(())
}
