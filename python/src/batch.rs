//! How frames from Python go through the reconstruction: taken in single precision, as
//! et's frames are, and a batch in runs, each failure named by its frame's place among all.

use numpy::PyReadonlyArray2;
use pyo3::prelude::*;

use et_recon::Reference;

use crate::{matrix, refused, usage};

/// Frames a batch images at once (their pixels held until copied out).
pub(crate) const FRAMES_AT_ONCE: usize = 64;

/// A batch's error with its frame's place among all the frames, from its place in run `r`.
pub(crate) fn in_run(
    e: et_recon::reconstructor::ImagingError,
    r: usize,
) -> et_recon::reconstructor::ImagingError {
    match e {
        et_recon::reconstructor::ImagingError::Frame { index, source } => {
            et_recon::reconstructor::ImagingError::Frame {
                index: r * FRAMES_AT_ONCE + index,
                source,
            }
        }
        e => e,
    }
}

/// Refuses a batch whose stacked pixels (`n` frames of `per_frame` values, 8 bytes each) would
/// not fit in the memory free now, naming the size and the run that fits: allocating them
/// failed inside NumPy and surfaced as a panic ("PyObject pointer is null").
pub(crate) fn check_fits(n: usize, per_frame: usize) -> Result<(), String> {
    let need = (n as u128) * (per_frame as u128) * 8;
    let Some(free) = et_core::text::available_memory_bytes() else {
        return Ok(());
    };
    // Half of what is free: the frames, their differences and the images of a run are held
    // beside the stack.
    let budget = u128::from(free / 2);
    if need <= budget {
        return Ok(());
    }
    let fits = (budget / (per_frame as u128 * 8).max(1)).max(1);
    Err(format!(
        "{n} frames' images need {:.1} GB ({per_frame} pixels each, 8 bytes a pixel), over half \
         the {:.1} GB of memory free: image them in runs, r.images(V[i:i + {fits}])",
        need as f64 / 1e9,
        free as f64 / 1e9
    ))
}

/// V_0 and the noise of dV from untouched frames (n x K, V), taken in single precision as
/// et's frames are.
pub(crate) fn reference_of(frames: &PyReadonlyArray2<'_, f64>) -> PyResult<Reference> {
    let (values, n, k) = matrix(frames, "v0")?;
    let frames: Vec<Vec<f32>> = single(values, k, "v0")?
        .chunks(k.max(1))
        .take(n)
        .map(<[f32]>::to_vec)
        .collect();
    Reference::from_frames(&frames).map_err(|e| refused(&e))
}

/// Frames (n x K, V) in single precision, as et's frames are, with n and K.
pub(crate) fn frames_f32(
    frames: &PyReadonlyArray2<'_, f64>,
) -> PyResult<(Vec<Vec<f32>>, usize, usize)> {
    let (values, n, k) = matrix(frames, "V")?;
    let frames = single(values, k, "V")?
        .chunks(k.max(1))
        .take(n)
        .map(<[f32]>::to_vec)
        .collect();
    Ok((frames, n, k))
}

/// Voltages `what` in single precision, as et's frames are (the board's, and every
/// reader's): values it cannot hold are refused as a frames file's are
/// ([`et_host::frames::Single`]: 1e300 was said as "NaN or infinite", 1e-300 as "0 in every
/// entry").
pub(crate) fn single(values: &[f64], k: usize, what: &str) -> PyResult<Vec<f32>> {
    use et_host::frames::Single;
    match Single::check(values) {
        Some((i, fault @ Single::Past(_))) if values.len() > k => Err(usage(format!(
            "{what}[{}, {}]: {fault}",
            i / k.max(1),
            i % k.max(1)
        ))),
        Some((i, fault @ Single::Past(_))) => Err(usage(format!("{what}[{i}]: {fault}"))),
        Some((_, fault)) => Err(usage(format!("{what}: {fault}"))),
        None => Ok(()),
    }?;
    #[allow(clippy::cast_possible_truncation)]
    Ok(values.iter().map(|&v| v as f32).collect())
}
