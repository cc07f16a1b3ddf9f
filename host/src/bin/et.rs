//! `et`: the command-line program of the et workspace.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use et_core::protocol::{Pattern, Protocol, ProtocolKind, SkipSet};
use et_host::recording::{self, Header, Record, TouchRecord};
use et_host::tables::ProtocolTables;
use et_sim::scene::{Detail, Run, Scene};
use indicatif::{ProgressBar, ProgressStyle};

/// Touch sensing with electrical tomography: protocols, simulation, imaging and learning.
#[derive(Debug, Parser)]
#[command(name = "et", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print a protocol's tables: injection pairs, measurement pairs, K and p (SPEC §4).
    ///
    /// Examples:
    ///   et protocol --electrodes 16 --protocol adjacent
    ///   et protocol -l 16 -p opposite --json > opposite16.json
    ///   et protocol -l 16 --drive-skip 3 --measure-skip 0 --measure-skip 3
    #[command(verbatim_doc_comment)]
    Protocol(ProtocolArgs),
    /// Simulate a scene: frames of the emulated fabric sheet, with the true touches, written
    /// as a recording (JSON Lines; read it from Python with python/et_recording.py).
    ///
    /// Scenes are TOML files; sim/scenes/ has one for every geometry of the method and its
    /// reference scenarios.
    ///
    /// Examples:
    ///   et sim --scene sim/scenes/square-13cm-16.toml --frames 200 --out touch.jsonl
    ///   et sim --scene sim/scenes/square-13cm-16-swipe.toml --frames 150 --out swipe.jsonl --samples
    #[command(verbatim_doc_comment)]
    Sim(SimArgs),
}

#[derive(Debug, clap::Args)]
struct SimArgs {
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

#[derive(Debug, clap::Args)]
struct ProtocolArgs {
    /// Electrode count L: even, 4 to 32.
    #[arg(short = 'l', long, default_value_t = 16)]
    electrodes: u8,
    /// adjacent (ad), pseudo-polar (pp), pp-pp, or opposite (polar). Ignored with --drive-skip.
    #[arg(short, long, default_value = "adjacent")]
    protocol: String,
    /// General form: inject between i and i + drive_skip + 1 (needs --measure-skip).
    #[arg(long, requires = "measure_skip")]
    drive_skip: Option<u8>,
    /// General form: measure between j and j + s + 1; give once or twice.
    #[arg(long)]
    measure_skip: Vec<u8>,
    /// Print JSON (all tables, machine-readable) instead of text.
    #[arg(long)]
    json: bool,
}

fn protocol(args: &ProtocolArgs) -> Result<()> {
    let kind = match args.drive_skip {
        Some(drive_skip) => {
            let mut skips = SkipSet(0);
            for &s in &args.measure_skip {
                if s >= 32 {
                    bail!("--measure-skip {s} is too large: use a skip below L/2");
                }
                skips = skips.with(s);
            }
            ProtocolKind::Custom(Pattern {
                drive_skip,
                measure_skips: skips,
            })
        }
        None => {
            if !args.measure_skip.is_empty() {
                bail!("--measure-skip needs --drive-skip (the general form)");
            }
            ProtocolKind::from_name(&args.protocol).with_context(|| {
                format!(
                    "unknown protocol '{}': use adjacent, pseudo-polar, pp-pp or opposite",
                    args.protocol
                )
            })?
        }
    };
    let protocol = Protocol::new(kind, args.electrodes)?;
    let tables = ProtocolTables::new(&protocol);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&tables)?);
    } else {
        print!("{}", tables.to_text());
    }
    Ok(())
}

fn sim(args: &SimArgs) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    if let Some(seed) = args.seed {
        scene.seed = seed;
    }
    let started = Instant::now();
    let mut run = Run::new(&scene)?;
    let setup = started.elapsed();
    let header = Header::new(format!("sim:{}", args.scene.display()), run.config())?;
    let mut writer = recording::Writer::create(&args.out, &header)?;
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
    for _ in 0..args.frames {
        let (frame, truth) = run.next_frame(detail)?;
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
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Protocol(args) => protocol(args),
        Command::Sim(args) => sim(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
