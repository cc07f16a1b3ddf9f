//! `et sim`: the simulated sheet, from a scene file into a recording.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use et_host::recording::{self, Header, Record, TouchRecord};
use et_sim::scene::{Detail, Run, Scene};
use indicatif::{ProgressBar, ProgressStyle};

#[derive(Debug, clap::Args)]
pub(crate) struct SimArgs {
    /// The scene file (TOML).
    #[arg(long)]
    scene: PathBuf,
    /// How many frames to simulate.
    #[arg(long, default_value_t = 100)]
    frames: u32,
    /// Where to write the recording (.jsonl).
    #[arg(long)]
    out: PathBuf,
    /// Simulate every ADC sample through the real scan engine (slower) instead of whole frames.
    #[arg(long)]
    samples: bool,
    /// Override the scene's seed.
    #[arg(long)]
    seed: Option<u64>,
}

pub(crate) fn run(args: &SimArgs, force: bool) -> Result<()> {
    crate::output::check(&args.out, &[&args.scene], force)?;
    let mut scene = Scene::load(&args.scene)?;
    if let Some(seed) = args.seed {
        scene.seed = seed;
    }
    let started = Instant::now();
    let mut run = Run::new(&scene)?;
    let setup = started.elapsed();
    let header = Header::new(format!("sim:{}", args.scene.display()), run.config())?;
    let detail = if args.samples {
        Detail::Samples
    } else {
        Detail::Frames
    };
    let bar = ProgressBar::new(u64::from(args.frames)).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} frames ({per_sec}, eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message("simulating");
    let started = Instant::now();
    let (mut rail, mut compliance) = (0u32, 0u32);
    // Written aside and renamed when complete: Ctrl-C leaves no half recording.
    crate::output::write(&args.out, |partial| {
        let mut writer = recording::Writer::create(partial, &header)?;
        for _ in 0..args.frames {
            let (frame, truth) = run.next_frame(detail)?;
            rail += u32::from(frame.flags & et_core::wire::FLAG_RAIL != 0);
            compliance += u32::from(frame.flags & et_core::wire::FLAG_COMPLIANCE != 0);
            let touches = truth
                .touches
                .iter()
                .map(|t| TouchRecord {
                    x: t.position[0],
                    y: t.position[1],
                    radius: t.radius,
                    pressure: t.pressure,
                })
                .collect();
            writer.append(&Record::new(&frame, Some(touches)))?;
            bar.inc(1);
        }
        anyhow::Ok(())
    })?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    eprintln!(
        "wrote {} frames of {} values ({} at L = {}, {:.1} s of scene time) to {} \
         (sheet built in {:.2} s; {:.0} frames/s)",
        args.frames,
        header.frame_len,
        header.protocol,
        header.electrodes,
        f64::from(args.frames) * run.frame_period(),
        args.out.display(),
        setup.as_secs_f64(),
        f64::from(args.frames) / elapsed.max(1e-9)
    );
    if rail > 0 {
        eprintln!(
            "warning: {rail} frames have readings on an ADC rail (flagged in the recording): \
             lower the scene's gain or current"
        );
    }
    if compliance > 0 {
        eprintln!(
            "warning: in {compliance} frames the current source was in compliance (flagged in \
             the recording): the drive load is above V_out_max / (2 I), from contacts too \
             resistive or open, so those readings are too small; lower the current or fix \
             the contacts"
        );
    }
    Ok(())
}
