//! Which frames `et reconstruct` images: simulated from the scene, read from a recording, or
//! another system's table of frames.

use anyhow::{Result, bail};
use et_host::recording;
use et_sim::scene::Scene;

use super::ReconstructArgs;

/// The frames `et reconstruct` images: V_0 and its noise, the frame V, and the truth (centre,
/// radius) where known.
pub(super) fn frames(
    args: &ReconstructArgs,
    scene: &Scene,
    recording: Option<&recording::Recording>,
    config: &et_core::ScanConfig,
) -> Result<(et_recon::Reference, Vec<f32>, Vec<et_sim::still::Truth>)> {
    let Some(r) = recording else {
        // The simulator's frames: the untouched sheet (mean of 10 frames, as captured at
        // set-up) and one frame with the scene's touches.
        let f = et_sim::still::scene_frames(scene, config, 10)?;
        let reference = et_recon::Reference {
            v0: f.v0,
            var_dv: f.var,
        };
        return Ok((reference, f.v1, f.truth));
    };
    let path = args
        .frames
        .as_deref()
        .unwrap_or(std::path::Path::new(""))
        .display();
    let n = r.records.len();
    let reference = args.reference.clamp(1, n.max(1));
    let frame = args.frame.unwrap_or(n.saturating_sub(1));
    if n == 0 || frame >= n || frame < reference {
        bail!("{path}: {n} frames; need the reference frames 0..{reference} and a later --frame");
    }
    if let Some((i, rec)) = r.records[..reference]
        .iter()
        .chain([&r.records[frame]])
        .enumerate()
        .find(|(_, rec)| !rec.invalid.is_empty())
    {
        bail!(
            "{path}: frame {} (seq {}) has non-finite values (null in the file) in \
             columns {:?}; choose other frames with --reference and --frame",
            if i < reference { i } else { frame },
            rec.seq,
            rec.invalid
        );
    }
    let frames: Vec<&[f32]> = r.records[..reference]
        .iter()
        .map(|rec| rec.voltages.as_slice())
        .collect();
    let rec = &r.records[frame];
    let truth = rec
        .touches
        .iter()
        .flatten()
        .map(|t| ([t.x, t.y], t.radius))
        .collect();
    Ok((
        et_recon::Reference::from_frames(&frames)?,
        rec.voltages.clone(),
        truth,
    ))
}

/// Another system's frames from a table file: V_0 from `--reference-file` or the first
/// `--reference` frames, and the frame `--frame` (default the last). No truth is known.
pub(super) fn table_frames(
    args: &ReconstructArgs,
    path: &std::path::Path,
    k: usize,
) -> Result<(et_recon::Reference, Vec<f32>, Vec<et_sim::still::Truth>)> {
    let frames = et_host::frames::read(path, k)?;
    eprintln!("{}", frames.description);
    let n = frames.frames.len();
    let (reference, first) = match &args.reference_file {
        Some(f) => {
            let r = et_host::frames::read(f, k)?;
            eprintln!("reference {}", r.description);
            (et_recon::Reference::from_frames(&r.frames)?, 0)
        }
        None => {
            let count = args.reference.clamp(1, n.max(1));
            if n <= count {
                bail!(
                    "{}: {n} frames; --reference {count} takes the first {count} as V_0 and \
                     leaves none to image (lower --reference, or give --reference-file)",
                    path.display()
                );
            }
            (
                et_recon::Reference::from_frames(&frames.frames[..count])?,
                count,
            )
        }
    };
    let frame = args.frame.unwrap_or(n.saturating_sub(1));
    if frame >= n || frame < first {
        bail!(
            "{}: --frame {frame}: the frames to image are {first} to {}",
            path.display(),
            n.saturating_sub(1)
        );
    }
    Ok((reference, frames.frames[frame].clone(), Vec::new()))
}
