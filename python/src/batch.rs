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
