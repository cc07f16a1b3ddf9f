//! `et reconstruct --all` and `--range`: every chosen frame imaged with one set-up, a JSON
//! line each, and their pixels and classes in stacks.

use std::time::Instant;

use anyhow::{Context, Result};

use super::{ReconstructArgs, RegionSummary};

/// One frame's line of `et reconstruct --all`.
#[derive(serde::Serialize)]
struct FrameLine {
    /// The frame's 0-based index in the file.
    frame: usize,
    alpha: f64,
    noise: et_recon::FrameNoise,
    objects: Vec<et_recon::touches::ObjectSummary>,
    found_touches: Vec<RegionSummary>,
}

/// `--all` and `--range`: every chosen frame imaged against `reference` with the set-up made
/// once, its line on standard output and its pixels kept for --image-out; the last frame's
/// image (what --out draws).
pub(super) fn each_frame(
    args: &ReconstructArgs,
    recon: &mut et_recon::Reconstructor,
    reference: et_recon::Reference,
    chosen: &[(usize, Vec<f32>)],
    skipped: &[usize],
) -> Result<et_recon::Image> {
    recon.set_reference(reference)?;
    // Objects and pixels are read, not the values on the mesh.
    recon.keep_mesh_values(false);
    let clock = Instant::now();
    let sigma0 = recon.imager().sigma0;
    let (grid, n) = (recon.grid().clone(), chosen.len());
    // The pixels (--image-out) and the classes (--segment) of every frame, as asked.
    let (mut stack, mut classes): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    // A frame skipped (values missing) is a NaN image in the stacks, in its place.
    let (mut gaps, pixels) = (skipped.iter().peekable(), grid.height * grid.width);
    // Its time said a few seconds in (no bar: the lines go to standard output).
    let (mut pace, no_bar) = (
        et_host::pace::Pace::new("image", "frames", n as u64),
        indicatif::ProgressBar::hidden(),
    );
    // In runs (a recording's frames need not all be held imaged at once), each run over
    // every core.
    for (done, run) in chosen.chunks(FRAMES_AT_ONCE).enumerate() {
        let frames: Vec<&[f32]> = run.iter().map(|(_, v)| v.as_slice()).collect();
        let imaged = recon.image_frames(&frames, true).map_err(|e| match e {
            et_recon::ImagingError::Frame { index, source } => {
                anyhow::anyhow!("frame {}: {source}", run[index].0)
            }
            e => e.into(),
        })?;
        for ((i, _), image) in run.iter().zip(imaged) {
            let found = image.found.unwrap_or_else(|| et_recon::Found {
                objects: Vec::new(),
                touches: Vec::new(),
            });
            let line = FrameLine {
                frame: *i,
                alpha: image.pixels.alpha,
                noise: image.noise,
                objects: (found.objects.iter())
                    .map(|o| et_recon::touches::ObjectSummary::of(o, sigma0))
                    .collect(),
                found_touches: found.touches.iter().map(RegionSummary::of).collect(),
            };
            out!("{}", serde_json::to_string(&line)?);
            let before = std::iter::from_fn(|| gaps.next_if(|g| *g < i)).count();
            if args.image_out.is_some() {
                stack.extend(std::iter::repeat_n(f64::NAN, pixels * before));
                grid.top_first_into(&image.pixels.pixels, 1.0 / sigma0, &mut stack);
            }
            if args.segment.is_some() {
                classes.extend(std::iter::repeat_n(f64::NAN, pixels * before));
                let segmented = et_recon::segment(
                    &image.pixels.pixels,
                    &found.objects,
                    et_recon::SEGMENT_LEVEL,
                );
                let values = et_recon::segment::as_values(&segmented);
                grid.top_first_into(&values, 1.0, &mut classes);
            }
        }
        pace.at(((done * FRAMES_AT_ONCE) + run.len()) as u64, &no_bar);
    }
    let took = clock.elapsed().as_secs_f64();
    say!(
        "imaged {n} frames in {took:.3} s after the set-up ({:.2} ms a frame, objects included)",
        1e3 * took / n.max(1) as f64
    );
    let after = gaps.count();
    let outputs = [
        (&args.image_out, stack, "pixels, Delta sigma / sigma_0"),
        (
            &args.segment,
            classes,
            "classes: 0 background, 1 resistive, 2 conductive",
        ),
    ];
    for (path, mut values, what) in outputs {
        let Some(path) = path else { continue };
        values.extend(std::iter::repeat_n(f64::NAN, pixels * after));
        let n = n + skipped.len();
        let bytes = et_learn::npz::npy_of_array(&values, &[n, grid.height, grid.width]);
        crate::output::write(path, |partial| std::fs::write(partial, &bytes))?;
        say!(
            "wrote {} ({n} x {} x {} {what}, top row first{})",
            path.display(),
            grid.height,
            grid.width,
            match skipped {
                [] => String::new(),
                gaps => format!(
                    "; NaN for the frames skipped: {}",
                    et_host::frames::said_list(gaps)
                ),
            }
        );
    }
    // The last frame's whole image, for --out.
    let (i, last) = chosen.last().context("no frames to image")?;
    recon
        .image_frame(last)
        .with_context(|| format!("frame {i}"))
}

/// Frames imaged at once by `--all` and `--range` (their pixels held until written).
const FRAMES_AT_ONCE: usize = 512;
