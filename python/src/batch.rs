//! How a batch of frames goes through the reconstruction: in runs, each failure named by
//! its frame's place among all.

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
