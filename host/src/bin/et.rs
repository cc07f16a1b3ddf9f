//! `et`: the command-line program of the et workspace.

use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};
use et_core::model::{ModelKind, Precision};
use et_core::protocol::{Pattern, Protocol, ProtocolKind, SkipSet};
use et_host::learn::model_file::ModelFile;
use et_host::learn::{analysis, collect, dataset, fastcv, pipeline};
use et_host::plot;
use et_host::recording::{self, Header, Record, TouchRecord};
use et_host::tables::ProtocolTables;
use et_sim::scene::{Detail, Run, Scene};
use indicatif::{ProgressBar, ProgressStyle};

/// Touch sensing with electrical tomography: protocols, simulation, imaging and learning.
#[derive(Debug, Parser)]
#[command(
    name = "et",
    version,
    about,
    long_about = None,
    after_help = "Start here: `et demo` runs the whole method on the simulated sheet (no hardware) \
                  and writes a report. Every command's --help has examples."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole method on the simulated sheet into a report folder (no hardware).
    ///
    /// The whole method on the simulated sheet, no hardware needed: collect a training set,
    /// train and cross-validate QDA, test it on next-day sessions and on the chip's model
    /// blob, image SPEC §7's reference scenarios with every protocol, and sweep mesh size
    /// against accuracy and time. Writes a report folder (index.md with PNG figures, and
    /// summary.json) and prints where it is. About 1 to 2 minutes in a release build.
    ///
    /// Examples:
    ///   et demo
    ///   et demo --out /tmp/report --json
    ///   et demo --quick            (small sizes: a 10-second smoke test)
    #[command(verbatim_doc_comment)]
    Demo(DemoArgs),
    /// Print a protocol's tables: injection pairs, measurement pairs, K and p (SPEC §4).
    ///
    /// Examples:
    ///   et protocol --electrodes 16 --protocol adjacent
    ///   et protocol -l 16 -p opposite --json > opposite16.json
    ///   et protocol -l 16 --drive-skip 3 --measure-skip 0 --measure-skip 3
    #[command(verbatim_doc_comment)]
    Protocol(ProtocolArgs),
    /// Simulate a scene into a recording of frames (JSON Lines).
    ///
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
    /// Collect a labelled training set on the simulated sheet (SPEC §9), as CSV.
    ///
    /// Collect a labelled training set on the simulated sheet, the SPEC §9 way: a grid of
    /// touch classes, visited T times, S_num scans per class and visit with the pressure varied,
    /// S_sub observations per scan; electrodes move between visits. Each visit starts with
    /// an untouched frame (the sheet as it was put down), which referenced models subtract.
    /// Writes CSV (Python: csv or numpy.loadtxt(comments="#"); MATLAB: readmatrix).
    ///
    /// Examples:
    ///   et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --out train.csv
    ///   et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --visits 1 --scans 1 --seed 77 --out nextday.csv
    #[command(verbatim_doc_comment)]
    Collect(CollectArgs),
    /// Train a QDA or LDA touch classifier and cross-validate it.
    ///
    /// Train a QDA or LDA model on a collected training set (shrinkage chosen by
    /// leave-one-visit-out cross-validation unless given), and cross-validate it. By default
    /// the model is referenced: it classifies each frame minus its session's untouched frame,
    /// which cancels electrode movement between sessions (--raw: SPEC §9's raw frames).
    ///
    /// Examples:
    ///   et train --data train.csv --out model.json
    ///   et train --data train.csv --kind lda --out lda.json --curve learning-curve.png
    #[command(verbatim_doc_comment)]
    Train(TrainArgs),
    /// Evaluate a trained model on a test set: accuracy, mean position error, AEE, confusion.
    ///
    /// Examples:
    ///   et eval --model model.json --data nextday.csv
    ///   et eval --model model.json --data nextday.csv --plots plots/ --json
    #[command(verbatim_doc_comment)]
    Eval(EvalArgs),
    /// Export a trained model as the board's model blob.
    ///
    /// Export a trained model as the model blob the firmware evaluates (f32, or f16 at half
    /// the flash), with its size and evaluation cost.
    ///
    /// Example:
    ///   et export --model model.json --precision f16 --out model.etm
    #[command(verbatim_doc_comment)]
    Export(ExportArgs),
    /// Image touches (a scene's, or recorded frames) by one-step Gauss-Newton, as PNG + metrics.
    ///
    /// Image a scene's touches by one-step Gauss-Newton difference imaging (SPEC §6): mesh the
    /// sheet, the complete electrode model's Jacobian at the untouched sheet, the NOSER
    /// reconstruction matrix; then the simulator's frames without and with the touches (its
    /// resistor network, not these finite elements) give the image, its regions and the
    /// SPEC §7 metrics. Writes the image as PNG with a colour bar.
    ///
    /// Examples:
    ///   et reconstruct --scene sim/scenes/disc-ref-x050.toml --out x050.png
    ///   et reconstruct --scene sim/scenes/disc-ref-two.toml --alpha 0.01 --out two.png --json
    ///   et reconstruct --scene sim/scenes/square-13cm-16-swipe.toml --frames swipe.jsonl --frame 60 --out f60.png
    ///   et reconstruct --scene sim/scenes/disc-ref-x050.toml --refine 55,0,25 --out x050-roi.png
    #[command(verbatim_doc_comment)]
    Reconstruct(ReconstructArgs),
    /// Boundary voltages of a scene by the finite elements.
    ///
    /// Boundary voltages of a scene by the finite elements (complete electrode model): the
    /// scene's protocol and current, the untouched sheet and the sheet with its touches (each
    /// touch's disc at the conductance its pressure gives), V_0, V_1 and their difference.
    /// The mesh is refined at the touches (a quarter of their radius), so their edges are
    /// resolved within the triangle budget.
    ///
    /// Examples:
    ///   et forward --scene sim/scenes/disc-ref-x050.toml
    ///   et forward --scene sim/scenes/square-13cm-16.toml --triangles 30000 --json > v.json
    #[command(verbatim_doc_comment)]
    Forward(ForwardArgs),
    /// List the serial ports of this machine (for --port).
    ///
    /// Example:
    ///   et ports
    #[command(verbatim_doc_comment)]
    Ports,
    /// Record frames from a board into a recording (JSON Lines).
    ///
    /// Record frames from a board on a serial port into a recording (JSON Lines, one frame per
    /// line, flushed as it arrives: a crash or a pulled cable loses at most the frame in
    /// flight). Starts the scan, records until --frames or --seconds or Ctrl-C, and rides out a
    /// pulled cable (the port is reopened when it comes back). A change of configuration on
    /// the board continues in FILE-2.jsonl, FILE-3.jsonl, ...
    ///
    /// Examples:
    ///   et record --port /dev/ttyUSB0 --out session.jsonl --seconds 60
    ///   et record --port /dev/serial/by-id/usb-FTDI_FT232R-if00-port0 --out s.jsonl --frames 500
    #[command(verbatim_doc_comment)]
    Record(RecordArgs),
    /// Open the viewer: live image, class grid, plots, training wizard (feature `viewer`).
    ///
    /// Open the viewer: the live image with its colour bar and ROI outline, the class grid
    /// with the recognised class lit and the position marker, protocol (or automatic),
    /// alpha and threshold, plots of frame rate, BVC and per-channel SNR, link health, and the
    /// training wizard. Press the simulated sheet with the mouse. Needs the `viewer` feature:
    ///   cargo run --release -p et-host --features viewer -- view
    ///
    /// Examples:
    ///   et view                                   (the simulated 13 x 13 cm sheet)
    ///   et view --scene sim/scenes/disc-22cm-16.toml
    ///   et view --replay session.jsonl
    ///   et view --port /dev/ttyUSB0 --model model.json
    #[command(verbatim_doc_comment)]
    View(ViewArgs),
    /// Print touch events as JSON lines for other programs.
    ///
    /// Print touch events as JSON lines for downstream programs (a robot, a game, a logger):
    /// class, position, intensity, confidence, timestamp, one line per touched frame. From
    /// a simulated scene (--scene; its touches start once the reference is taken), a
    /// recording (--replay) or a board (--port). The first 20 frames, with the sheet
    /// untouched, make the reference V_0.
    ///
    /// Examples:
    ///   et stream --json --scene sim/scenes/square-13cm-16-swipe.toml --frames 300
    ///   et stream --json --scene sim/scenes/square-13cm-16.toml --model model.json
    ///   et stream --json --replay session.jsonl
    ///   et stream --json --port /dev/ttyUSB0 --model model.json | my-robot
    #[command(verbatim_doc_comment)]
    Stream(StreamArgs),
    /// Upload a model blob to the board (which verifies it before using it).
    ///
    /// Upload a model blob (from `et export`) to the board over its serial port. The board
    /// verifies it (CRC, model checks, scan configuration) before it replaces the old model;
    /// a refused upload leaves the old one classifying. A referenced model needs the untouched
    /// frame V_0: add --tare (with the sheet untouched and the board scanning).
    ///
    /// Examples:
    ///   et export --model model.json --precision f16 --out model.bin
    ///   et upload --port /dev/ttyUSB0 --blob model.bin --tare
    #[command(verbatim_doc_comment)]
    Upload(UploadArgs),
}

#[derive(Debug, clap::Args)]
struct DemoArgs {
    /// The report folder (created; its files are overwritten).
    #[arg(long, default_value = "et-demo-report")]
    out: PathBuf,
    /// Small sizes everywhere: checks the whole pipeline in seconds, numbers not to quote.
    #[arg(long)]
    quick: bool,
    /// Print the summary as JSON on stdout (progress stays on stderr).
    #[arg(long)]
    json: bool,
}

/// Where live frames come from (`et stream`, `et view`).
#[derive(Debug, Clone, clap::Args)]
struct SourceArgs {
    /// The scene to simulate; with --replay or --port, the sheet they were made on (its
    /// shape and electrodes, for imaging). Default: the 13 x 13 cm, 16-electrode sheet.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Replay a recording (JSON Lines from `et sim` or `et record`).
    #[arg(long, conflicts_with = "port")]
    replay: Option<PathBuf>,
    /// A board's serial port (`et ports` lists them).
    #[arg(long)]
    port: Option<String>,
    /// Baud rate of --port.
    #[arg(long, default_value_t = et_host::link::DEFAULT_BAUD)]
    baud: u32,
    /// A trained model (`et train`) to classify each touch with on the host.
    #[arg(long)]
    model: Option<PathBuf>,
}

impl SourceArgs {
    fn spec(&self) -> et_host::live::SourceSpec {
        use et_host::live::SourceSpec;
        match (&self.replay, &self.port) {
            (Some(path), _) => SourceSpec::Replay(path.clone()),
            (None, Some(port)) => SourceSpec::Port(port.clone(), self.baud),
            (None, None) => SourceSpec::Sim,
        }
    }

    fn classifier(&self) -> Result<Option<et_host::live::Classifier>> {
        self.model
            .as_deref()
            .map(|p| {
                let file = ModelFile::load(p).map_err(anyhow::Error::msg)?;
                et_host::live::Classifier::new(file)
                    .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
            })
            .transpose()
    }
}

#[derive(Debug, clap::Args)]
struct ViewArgs {
    #[command(flatten)]
    source: SourceArgs,
    /// For documentation: once V_0 is taken, press the simulated sheet at (30, 25) mm, save
    /// the window as this PNG, and close.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
}

#[derive(Debug, clap::Args)]
struct StreamArgs {
    #[command(flatten)]
    source: SourceArgs,
    /// JSON lines on stdout (the only output format; the flag says so in scripts).
    #[arg(long)]
    json: bool,
    /// Stop after this many frames (default: run until Ctrl-C or the end of a recording).
    #[arg(long)]
    frames: Option<u64>,
    /// Simulate as fast as possible instead of in real time.
    #[arg(long)]
    fast: bool,
}

#[derive(Debug, clap::Args)]
struct UploadArgs {
    /// The board's serial port (`et ports` lists them).
    #[arg(long)]
    port: String,
    /// The model blob (`et export --out`).
    #[arg(long)]
    blob: PathBuf,
    /// Baud rate (the firmware's is the default).
    #[arg(long, default_value_t = et_host::link::DEFAULT_BAUD)]
    baud: u32,
    /// Then take the next frame as V_0 (the sheet must not be touched).
    #[arg(long)]
    tare: bool,
}

#[derive(Debug, clap::Args)]
struct RecordArgs {
    /// The board's serial port (`et ports` lists them).
    #[arg(long)]
    port: String,
    /// Where to write the recording (.jsonl).
    #[arg(long)]
    out: PathBuf,
    /// Baud rate (the firmware's is the default).
    #[arg(long, default_value_t = et_host::link::DEFAULT_BAUD)]
    baud: u32,
    /// Stop after this many frames.
    #[arg(long)]
    frames: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long)]
    seconds: Option<f64>,
    /// Do not send Start (the board is already scanning).
    #[arg(long)]
    no_start: bool,
}

/// How a command gets its mesh.
#[derive(Debug, clap::Args)]
struct MeshArgs {
    /// About how many triangles to mesh the sheet with.
    #[arg(long, default_value_t = 8_000)]
    triangles: usize,
    /// Use this mesh instead of meshing the scene's sheet: a Gmsh 2.2 ASCII `.msh` (one
    /// physical line per electrode), or `nodes.csv,triangles.csv,electrodes.csv`.
    #[arg(long, value_name = "FILE")]
    mesh: Option<String>,
    /// Mesh a disc of the sheet finer: centre x, y and radius R in mm, edges of R/6 inside
    /// (repeat for several; the triangle budget stays the same). `et forward` refines at the
    /// scene's touches by itself.
    #[arg(long, value_name = "X,Y,R", allow_hyphen_values = true)]
    refine: Vec<String>,
}

#[derive(Debug, clap::Args)]
struct ForwardArgs {
    /// Scene file.
    #[arg(long)]
    scene: PathBuf,
    #[command(flatten)]
    mesh: MeshArgs,
    /// Print JSON (all K values of V_0 and V_1, in volts).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
struct ReconstructArgs {
    /// Scene file: the sheet, its electrodes, the scan protocol and the touches.
    #[arg(long)]
    scene: PathBuf,
    #[command(flatten)]
    mesh: MeshArgs,
    /// Gauss-Newton iterations: 1 is the one-step reconstruction; more refit the data
    /// (slower, for when accuracy matters more than speed).
    #[arg(long, default_value_t = 1)]
    iterations: usize,
    /// Regularisation alpha (dimensionless: lambda = alpha^2 tr(J P^-1 J^T) / K), or "auto":
    /// chosen by generalised cross-validation on the frame.
    #[arg(long, default_value = "auto")]
    alpha: String,
    /// NOSER exponent s in [0, 1] (prior diag(J^T J)^s).
    #[arg(long, default_value_t = 0.5)]
    s: f64,
    /// ROI threshold f (keep pixels >= f max); default per protocol as SPEC §6: adjacent
    /// 0.10, pseudo-polar 0.08, PP-PP 0.05, others 0.10.
    #[arg(long)]
    threshold: Option<f64>,
    /// Pixels across the image.
    #[arg(long, default_value_t = 64)]
    pixels: usize,
    /// Image recorded frames (from `et sim`, later from the board) instead of simulating
    /// the scene's touches; the scene still gives the sheet and electrodes.
    #[arg(long, value_name = "JSONL")]
    frames: Option<PathBuf>,
    /// With --frames: average the first N frames as the untouched reference V_0 (as
    /// `et stream` and `et view` do; record them with the sheet untouched).
    #[arg(long, default_value_t = 20)]
    reference: usize,
    /// With --frames: which frame to image (0-based; default the last).
    #[arg(long)]
    frame: Option<usize>,
    /// Where to write the image (PNG).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary (regions, metrics, timings).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
struct CollectArgs {
    /// Scene file: the sheet, its electrodes and the front end (its touches are not used).
    #[arg(long)]
    scene: PathBuf,
    /// Class grid, ROWSxCOLS (SPEC §9: 7x7 with a 15 mm target, 10x10 with 10 mm).
    #[arg(long, default_value = "7x7")]
    grid: String,
    /// T: visits of the whole grid.
    #[arg(long, default_value_t = 6)]
    visits: usize,
    /// S_num: scans per class and visit.
    #[arg(long, default_value_t = 20)]
    scans: usize,
    /// S_sub: observations (sub-section medians) per scan.
    #[arg(long, default_value_t = 20)]
    subsections: usize,
    /// Lowest pressure while pressing, kPa.
    #[arg(long, default_value_t = 5.0)]
    min_kpa: f64,
    /// Highest pressure while pressing, kPa.
    #[arg(long, default_value_t = 60.0)]
    max_kpa: f64,
    /// Finger (target) radius, mm.
    #[arg(long, default_value_t = 7.5)]
    radius_mm: f64,
    /// Rms electrode movement between visits, mm.
    #[arg(long, default_value_t = 0.5)]
    movement_mm: f64,
    /// Electrode poses within a visit: each press finds the electrodes in one of them (1 =
    /// they stay put while the grid is visited).
    #[arg(long, default_value_t = 1)]
    poses: usize,
    /// Rms movement of each pose around the visit's electrode positions, mm.
    #[arg(long, default_value_t = 0.0)]
    press_movement_mm: f64,
    /// Seed of the session.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Where to write the dataset (CSV).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
struct TrainArgs {
    /// Training set (CSV from `et collect`).
    #[arg(long)]
    data: PathBuf,
    /// qda or lda.
    #[arg(long, default_value = "qda")]
    kind: String,
    /// Shrinkage in [0, 1], or "auto" (chosen by leave-one-visit-out cross-validation).
    #[arg(long, default_value = "auto")]
    shrinkage: String,
    /// Folds of the reported stratified cross-validation.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Train on the frames as measured (SPEC §9 exactly) instead of each frame minus its
    /// session's untouched frame. Referenced is the default when the dataset has untouched
    /// frames: it cancels electrode movement between sessions, but on the board it needs an
    /// untouched frame taken when the sheet is put down.
    #[arg(long)]
    raw: bool,
    /// Also write a learning curve (PNG): held-out accuracy against observations per class
    /// n_c (leave-one-visit-out when the set has several visits, else the k-fold CV).
    #[arg(long, value_name = "PNG")]
    curve: Option<PathBuf>,
    /// Keep only this many features, those that separate the classes best (Fisher ratio):
    /// QDA's size and cost grow with the square of the feature count.
    #[arg(long)]
    features: Option<usize>,
    /// Where to write the model (JSON).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
struct EvalArgs {
    /// Model (JSON from `et train`).
    #[arg(long)]
    model: PathBuf,
    /// Test set (CSV from `et collect`).
    #[arg(long)]
    data: PathBuf,
    /// Write plots into this directory: confusion.png (row-normalised confusion matrix) and
    /// error-vs-distance.png (position error against distance from the nearest electrode).
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// Print JSON (with the confusion matrix and accuracy by distance from the electrodes).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
struct ExportArgs {
    /// Model (JSON from `et train`).
    #[arg(long)]
    model: PathBuf,
    /// f32, or f16 (half the flash, about 3 significant digits).
    #[arg(long, default_value = "f32")]
    precision: String,
    /// Where to write the blob.
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
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

fn collect_cmd(args: &CollectArgs) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    let (rows, cols) = args
        .grid
        .split_once('x')
        .and_then(|(r, c)| Some((r.parse::<usize>().ok()?, c.parse::<usize>().ok()?)))
        .filter(|&(r, c)| r > 0 && c > 0)
        .with_context(|| format!("--grid '{}': write ROWSxCOLS, e.g. 7x7", args.grid))?;
    if !(args.min_kpa >= 0.0 && args.max_kpa >= args.min_kpa) {
        bail!("--min-kpa and --max-kpa: need 0 <= min <= max");
    }
    if args.visits == 0 || args.scans == 0 || args.subsections == 0 {
        bail!("--visits, --scans and --subsections must be at least 1");
    }
    let config = collect::training_config(scene.scan_config().map_err(anyhow::Error::msg)?);
    let centres = collect::grid(&scene.sheet, rows, cols, 0.0);
    let plan = collect::Plan {
        visits: 1,
        scans: args.scans,
        subsections: args.subsections,
        pressure_pa: (args.min_kpa * 1e3, args.max_kpa * 1e3),
        radius: args.radius_mm * 1e-3,
        placement: args.radius_mm * 1e-3 / 4.0,
        electrode_movement: args.movement_mm * 1e-3,
        poses: args.poses.max(1),
        press_movement: args.press_movement_mm * 1e-3,
        seed: args.seed,
    };
    let bar = ProgressBar::new(args.visits as u64).with_style(
        ProgressStyle::with_template("collecting [{bar:30}] visit {pos}/{len} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    let mut data: Option<collect::Dataset> = None;
    for v in 0..args.visits {
        let seed = args.seed.wrapping_mul(1_000).wrapping_add(v as u64);
        let part = collect::collect(
            &scene.sheet,
            scene.frontend,
            config,
            &centres,
            &collect::Plan {
                seed,
                ..plan.clone()
            },
        )
        .map_err(anyhow::Error::msg)?;
        match data.as_mut() {
            None => data = Some(part),
            Some(d) => d.append(part).map_err(anyhow::Error::msg)?,
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let data = data.context("no visit collected")?;
    let provenance = format!(
        "et collect: {}, grid {rows}x{cols}, T={} S_num={} S_sub={}, {}-{} kPa, radius {} mm, movement {} mm, seed {}",
        args.scene.display(),
        args.visits,
        args.scans,
        args.subsections,
        args.min_kpa,
        args.max_kpa,
        args.radius_mm,
        args.movement_mm,
        args.seed
    );
    dataset::save_csv(&data, &args.out, &provenance)?;
    let summary = serde_json::json!({
        "out": args.out.display().to_string(),
        "observations": data.x.nrows(),
        "features": data.x.ncols(),
        "classes": centres.len(),
        "seconds": started.elapsed().as_secs_f64(),
    });
    if args.json {
        println!("{summary}");
    } else {
        eprintln!(
            "wrote {} observations of {} features, {} classes, to {} in {:.1} s",
            data.x.nrows(),
            data.x.ncols(),
            centres.len(),
            args.out.display(),
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn kind_of(name: &str) -> Result<ModelKind> {
    match name {
        "qda" => Ok(ModelKind::Qda),
        "lda" => Ok(ModelKind::Lda),
        other => bail!("--kind '{other}': use qda or lda"),
    }
}

fn train_cmd(args: &TrainArgs) -> Result<()> {
    let mut data = dataset::load_csv(&args.data)?;
    let classes = data.centres.len();
    let kind = kind_of(&args.kind)?;
    let referenced = !args.raw && data.has_untouched();
    if !args.raw && !referenced {
        eprintln!(
            "note: {} has no untouched frames, training on raw frames",
            args.data.display()
        );
    }
    pipeline::prepare(&mut data, referenced, args.features)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.data.display()))?;
    let shrinkage = match args.shrinkage.as_str() {
        "auto" => None,
        v => Some(
            v.parse::<f64>()
                .with_context(|| format!("--shrinkage '{v}': a number in [0, 1] or auto"))?,
        ),
    };
    let trained = pipeline::train(
        &data,
        &pipeline::TrainOptions {
            kind,
            shrinkage,
            folds: args.folds,
        },
    )?;
    let (model, opts, cv_conf, lovo) = (
        &trained.model,
        trained.options,
        &trained.cv,
        trained.leave_one_visit_out,
    );
    let (shrinkage, scores) = (opts.shrinkage, &trained.shrinkage_scores);
    let visits = data.visits();
    let curve = match &args.curve {
        Some(png) => {
            let fold = &trained.selection_folds;
            let largest = (0..classes)
                .map(|c| data.y.iter().filter(|&&y| usize::from(y) == c).count())
                .max()
                .unwrap_or(0);
            let sizes: Vec<usize> = [12, 24, 60, 120, 240, 480, 960, 1_200, 2_400, 4_800]
                .into_iter()
                .filter(|&n| n < largest)
                .chain([largest])
                .collect();
            let bar = ProgressBar::new(sizes.len() as u64).with_style(
                ProgressStyle::with_template("learning curve [{bar:30}] {pos}/{len}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            let points = analysis::learning_curve(&data.y, classes, &sizes, |rows| {
                bar.inc(1);
                let ys: Vec<u16> = rows.iter().map(|&r| data.y[r]).collect();
                let folds: Vec<usize> = rows.iter().map(|&r| fold[r]).collect();
                fastcv::cross_validate_fast(
                    &analysis::select_rows(&data.x, rows),
                    &ys,
                    classes,
                    &opts,
                    &folds,
                )
            });
            bar.finish_and_clear();
            plot::chart(
                png,
                plot::Labels {
                    title: &format!(
                        "learning curve: {} ({}), {} classes",
                        args.kind,
                        if visits >= 2 {
                            "leave-one-visit-out"
                        } else {
                            "k-fold CV"
                        },
                        classes
                    ),
                    x: "observations per class n_c",
                    y: "held-out accuracy (%)",
                    legend: plot::Legend::UpperLeft,
                },
                &[plot::Series {
                    label: format!("shrinkage {shrinkage}"),
                    points: points
                        .iter()
                        .filter_map(|p| Some((p.n_c as f64, 100.0 * p.accuracy?)))
                        .collect(),
                    scatter: false,
                }],
            )?;
            Some(points)
        }
        None => None,
    };
    let mm: Vec<[f64; 2]> = data
        .centres
        .iter()
        .map(|c| [c[0] * 1e3, c[1] * 1e3])
        .collect();
    let file = ModelFile::new(
        model,
        shrinkage,
        data.config,
        data.feature_index.clone(),
        mm.clone(),
        referenced,
    );
    file.save(&args.out).map_err(anyhow::Error::msg)?;
    let summary = serde_json::json!({
        "out": args.out.display().to_string(),
        "kind": args.kind,
        "referenced": referenced,
        "shrinkage": shrinkage,
        "shrinkage_scores": scores.iter().map(|(l, a)| serde_json::json!({"shrinkage": l, "accuracy": a})).collect::<Vec<_>>(),
        "classes": classes,
        "observations": data.x.nrows(),
        "features": data.x.ncols(),
        "cv_folds": args.folds.max(2),
        "cv_accuracy": cv_conf.accuracy(),
        "cv_mean_error_mm": cv_conf.mean_position_error(&mm),
        "cv_aee_mm": cv_conf.aee(&mm),
        "leave_one_visit_out_accuracy": lovo,
        "learning_curve": curve,
    });
    if args.json {
        println!("{summary}");
    } else {
        eprintln!(
            "trained {}{} on {} observations ({} classes, {} features), shrinkage {}: {}-fold CV accuracy {:.1} %, mean error {:.2} mm{}; wrote {}",
            args.kind,
            if referenced {
                " (referenced)"
            } else {
                " (raw frames)"
            },
            data.x.nrows(),
            classes,
            data.x.ncols(),
            shrinkage,
            args.folds.max(2),
            100.0 * cv_conf.accuracy(),
            cv_conf.mean_position_error(&mm),
            lovo.map_or(String::new(), |a| format!(
                ", leave-one-visit-out {:.1} %",
                100.0 * a
            )),
            args.out.display()
        );
        let fit = pipeline::features_that_fit(kind, classes, data.x.ncols());
        if fit < data.x.ncols() {
            eprintln!(
                "note: for the board, this model is too big for a model slot even in f16; \
                 train with --features {fit} (the most that fit for {classes} classes) or fewer classes"
            );
        }
    }
    Ok(())
}

fn eval_cmd(args: &EvalArgs) -> Result<()> {
    let file = ModelFile::load(&args.model).map_err(anyhow::Error::msg)?;
    let data = dataset::load_csv(&args.data)?;
    let classes = file.classes.len();
    let tested = pipeline::test(&file, &data)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.data.display()))?;
    let (conf, bands) = (&tested.confusion, &tested.bands);
    if let Some(dir) = &args.plots {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        pipeline::plot_confusion(
            &dir.join("confusion.png"),
            conf,
            &format!(
                "confusion: accuracy {:.1} % on {}",
                100.0 * conf.accuracy(),
                args.data.display()
            ),
        )?;
        if tested.outcomes.is_empty() {
            eprintln!(
                "note: {} does not say where the electrodes are: no error-vs-distance plot",
                args.data.display()
            );
        } else {
            pipeline::plot_error_vs_distance(&dir.join("error-vs-distance.png"), &tested)?;
        }
    }
    let summary = serde_json::json!({
        "observations": conf.total(),
        "accuracy": conf.accuracy(),
        "mean_error_mm": conf.mean_position_error(&file.centres_mm),
        "aee_mm": conf.aee(&file.centres_mm),
        "by_distance_from_electrodes": bands,
        "confusion": conf.counts.chunks(classes).map(<[u32]>::to_vec).collect::<Vec<_>>(),
    });
    if args.json {
        println!("{summary}");
    } else {
        println!(
            "{} observations: accuracy {:.1} %, mean position error {:.2} mm, AEE {:.1} mm",
            conf.total(),
            100.0 * conf.accuracy(),
            conf.mean_position_error(&file.centres_mm),
            conf.aee(&file.centres_mm)
        );
    }
    Ok(())
}

fn export_cmd(args: &ExportArgs) -> Result<()> {
    let file = ModelFile::load(&args.model).map_err(anyhow::Error::msg)?;
    let precision = match args.precision.as_str() {
        "f32" => Precision::F32,
        "f16" => Precision::F16,
        other => bail!("--precision '{other}': use f32 or f16"),
    };
    let blob = file.blob(precision)?;
    std::fs::write(&args.out, &blob).with_context(|| format!("writing {}", args.out.display()))?;
    let (c, p) = (file.classes.len(), file.feature_index.len());
    // Multiply-adds per frame on the chip: QDA a forward substitution per class, LDA a dot.
    let macs = if file.kind == "qda" {
        c * (p * (p + 1) / 2 + p)
    } else {
        c * p
    };
    // One model slot of the board's flash (firmware/src/store.rs).
    const SLOT: usize = pipeline::MODEL_SLOT_BYTES;
    let summary = serde_json::json!({
        "out": args.out.display().to_string(),
        "bytes": blob.len(),
        "fits_model_slot": blob.len() <= SLOT,
        "multiply_adds_per_frame": macs,
    });
    if args.json {
        println!("{summary}");
    } else {
        eprintln!(
            "wrote {} ({} bytes, {:.0} % of the board's 384 KiB model slot{}); {} multiply-adds per frame",
            args.out.display(),
            blob.len(),
            100.0 * blob.len() as f64 / SLOT as f64,
            if blob.len() <= SLOT {
                String::new()
            } else {
                let kind = kind_of(&file.kind)?;
                if precision == Precision::F32
                    && et_core::model::model_len(kind, Precision::F16, c, p) <= SLOT
                {
                    ": does NOT fit; --precision f16 does".to_string()
                } else {
                    format!(
                        ": does NOT fit; retrain with et train --features {} (the most that fit in f16) or fewer classes",
                        pipeline::features_that_fit(kind, c, p)
                    )
                }
            },
            macs
        );
    }
    Ok(())
}

fn forward_cmd(args: &ForwardArgs) -> Result<()> {
    use et_host::fem::{Electrodes, Forward};
    let scene = Scene::load(&args.scene)?;
    let config = scene.scan_config().map_err(anyhow::Error::msg)?;
    let protocol = config.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let started = Instant::now();
    let mesh = scene_mesh(&scene, &args.mesh, true)?;
    let sigma0 = 1.0 / scene.sheet.sheet_resistance;
    // Each touch multiplies the conductivity of the triangles whose centroid it covers.
    let sigma1: Vec<f64> = (0..mesh.triangles.len())
        .map(|t| {
            let c = mesh.centroid(t);
            scene.touches.iter().fold(sigma0, |s, touch| {
                let inside =
                    (c[0] - touch.position[0]).hypot(c[1] - touch.position[1]) <= touch.radius;
                if inside {
                    s * scene.sheet.piezo.multiplier(touch.pressure)
                } else {
                    s
                }
            })
        })
        .collect();
    let t_n = mesh.triangles.len();
    let e = &scene.sheet.electrodes;
    let fwd = Forward::new(
        mesh,
        Electrodes::Complete(vec![e.contact_ohm * e.width; usize::from(e.count)]),
    )?;
    let amps = f64::from(config.current_amps());
    let v0 = fwd.frame(&vec![sigma0; t_n], &protocol, amps)?;
    let v1 = fwd.frame(&sigma1, &protocol, amps)?;
    let bvc = v1
        .iter()
        .zip(&v0)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    if args.json {
        println!(
            "{}",
            serde_json::json!({
                "triangles": t_n,
                "protocol": format!("{:?}", config.protocol),
                "current_a": amps,
                "v0": v0,
                "v1": v1,
                "bvc": bvc,
                "seconds": started.elapsed().as_secs_f64(),
            })
        );
    } else {
        println!(
            "{} triangles, {:?} protocol, K = {}, {:.1} uA",
            t_n,
            config.protocol,
            v0.len(),
            amps * 1e6
        );
        println!("    k        V_0 (V)        V_1 (V)     V_1 - V_0 (V)");
        for (k, (a, b)) in v0.iter().zip(&v1).enumerate() {
            println!("{k:5} {a:14.6e} {b:14.6e} {:14.6e}", b - a);
        }
        println!(
            "BVC |V_1 - V_0| = {bvc:.4e} V ({:.2} s)",
            started.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// The mesh of a command: `--mesh` (Gmsh `.msh`, or three CSV files separated by commas) or
/// the scene's sheet meshed to about `--triangles`; its electrode count must be the sheet's.
fn scene_mesh(scene: &Scene, args: &MeshArgs, at_touches: bool) -> Result<et_host::mesh::Mesh> {
    use et_host::mesh::{Mesh, Refinement};
    let mut regions = Vec::new();
    for r in &args.refine {
        let v: Vec<f64> = r
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()
            .filter(|v: &Vec<f64>| v.len() == 3)
            .with_context(|| {
                format!("--refine '{r}': three numbers X,Y,R in mm, e.g. 20,-15,12")
            })?;
        regions.push(Refinement {
            centre: [v[0] * 1e-3, v[1] * 1e-3],
            radius: v[2] * 1e-3,
            edge: v[2] * 1e-3 / 6.0,
        });
    }
    if at_touches {
        regions.extend(
            scene
                .touches
                .iter()
                .map(|t| Refinement::touch(t.position, t.radius)),
        );
    }
    if args.mesh.is_some() && !args.refine.is_empty() {
        bail!("--refine meshes the scene's sheet; it cannot change an imported --mesh");
    }
    let mesh = match args.mesh.as_deref() {
        None => Mesh::with_about_refined(&scene.sheet, args.triangles, &regions)?,
        Some(f) => match f.split(',').collect::<Vec<_>>()[..] {
            [one] => Mesh::from_gmsh(std::path::Path::new(one))?,
            [n, t, e] => Mesh::from_csv(n.as_ref(), t.as_ref(), e.as_ref())?,
            _ => bail!("--mesh '{f}': a .msh file, or nodes.csv,triangles.csv,electrodes.csv"),
        },
    };
    if mesh.electrodes.len() != usize::from(scene.sheet.electrodes.count) {
        bail!(
            "the mesh has {} electrodes, the scene's sheet {}",
            mesh.electrodes.len(),
            scene.sheet.electrodes.count
        );
    }
    Ok(mesh)
}

fn reconstruct_cmd(args: &ReconstructArgs) -> Result<()> {
    use et_host::imaging::{Imager, Truth, scene_frames};
    use et_host::recon::{
        OneStep, PROMINENCE, TOUCH_Z, above_noise, default_threshold, metrics, regions, touches,
    };
    let scene = Scene::load(&args.scene)?;
    let recording = args.frames.as_deref().map(recording::read).transpose()?;
    let config = match &recording {
        Some(r) => r.header.config,
        None => scene.scan_config().map_err(anyhow::Error::msg)?,
    };
    if config.electrodes != scene.sheet.electrodes.count {
        bail!(
            "the frames are of {} electrodes, the scene's sheet has {}",
            config.electrodes,
            scene.sheet.electrodes.count
        );
    }
    let protocol = config.validate().map_err(|e| anyhow::anyhow!("{e}"))?;
    let amps = f64::from(config.current_amps());
    let started = Instant::now();
    let stage = |what: &str| eprintln!("{what:<40} {:>8.3} s", started.elapsed().as_secs_f64());
    let mesh = scene_mesh(&scene, &args.mesh, false)?;
    let t_n = mesh.triangles.len();
    stage(&format!("mesh ({t_n} triangles)"));
    let imager = Imager::new(&scene.sheet, mesh, args.pixels)?;
    let jac = imager.jacobian(&protocol, amps)?;
    let grid = &imager.grid;
    stage(&format!("forward + Jacobian (K = {})", jac.nrows()));
    // V_0 and V_1, with the truth (centre, radius) where known, and dV's noise variance.
    let (v0, v1, truth, var): (Vec<f64>, Vec<f32>, Vec<Truth>, Vec<f64>) = match &recording {
        Some(r) => {
            let n = r.records.len();
            let reference = args.reference.clamp(1, n.max(1));
            let frame = args.frame.unwrap_or(n.saturating_sub(1));
            if n == 0 || frame >= n || frame < reference {
                bail!(
                    "{}: {n} frames; need the reference frames 0..{reference} and a later --frame",
                    args.frames
                        .as_deref()
                        .map(|p| p.display().to_string())
                        .unwrap_or_default()
                );
            }
            let frames: Vec<Vec<f64>> = r.records[..reference]
                .iter()
                .map(|rec| rec.voltages.iter().map(|&v| f64::from(v)).collect())
                .collect();
            let v0: Vec<f64> = (0..protocol.frame_len())
                .map(|c| frames.iter().map(|f| f[c]).sum::<f64>() / reference as f64)
                .collect();
            let var = et_host::recon::dv_variance(&frames);
            let rec = &r.records[frame];
            let truth = rec
                .touches
                .iter()
                .flatten()
                .map(|t| ([t.x, t.y], t.radius))
                .collect();
            (v0, rec.voltages.clone(), truth, var)
        }
        None => {
            // The simulator's frames: the untouched sheet (mean of 10 frames, as captured at
            // set-up) and one frame with the scene's touches.
            let f = scene_frames(&scene, &config, 10)?;
            (f.v0, f.v1, f.truth, f.var)
        }
    };
    let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| f64::from(*a) - b).collect();
    stage("frames");
    let alpha = match args.alpha.as_str() {
        "auto" => {
            let grid_alpha: Vec<f64> = (0..=25)
                .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
                .collect();
            et_host::recon::gcv_alpha(&jac, args.s, &dv, &grid_alpha)?.0
        }
        v => v
            .parse::<f64>()
            .with_context(|| format!("--alpha '{v}': a number or auto"))?,
    };
    // The image, and its noise where the one-step matrix gives it.
    let (image, sd) = if args.iterations <= 1 {
        let recon = OneStep::new(&jac, alpha, args.s)?;
        stage(&format!("reconstruction matrix (alpha {alpha:.3e})"));
        (
            grid.image(&recon.reconstruct(&dv)?),
            grid.image(&recon.noise_sd(&var)?),
        )
    } else {
        let sigma0 = imager.background();
        let its = et_host::recon::gauss_newton(
            &imager.forward,
            &protocol,
            amps,
            &sigma0,
            et_host::recon::Data::Difference(&dv),
            et_host::recon::GaussNewton {
                alpha,
                s: args.s,
                iterations: args.iterations,
            },
        )?;
        let (last, norm) = its.last().cloned().context("no iteration")?;
        stage(&format!(
            "{} Gauss-Newton steps (alpha {alpha:.3e}, residual {norm:.3e} V)",
            args.iterations
        ));
        let d: Vec<f64> = last.iter().zip(&sigma0).map(|(a, b)| a - b).collect();
        (grid.image(&d), Vec::new())
    };
    let f = args.threshold.unwrap_or(default_threshold(config.protocol));
    let rois = regions(grid, &image, f);
    let found = above_noise(&touches(grid, &image, &sd, f, PROMINENCE), TOUCH_Z);
    let m = truth.first().map(|&(centre, radius)| {
        metrics(
            grid,
            &image,
            f,
            &dv,
            centre,
            std::f64::consts::PI * radius * radius,
        )
    });
    imager.write_png(
        &args.out,
        &format!(
            "{}: {} regions (f = {f})",
            args.scene
                .file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into_owned()),
            rois.len()
        ),
        &image,
    )?;
    let summary = serde_json::json!({
        "out": args.out.display().to_string(),
        "triangles": t_n,
        "protocol": format!("{:?}", config.protocol),
        "alpha": alpha,
        "s": args.s,
        "threshold": f,
        "regions": rois.iter().map(|r| serde_json::json!({
            "centroid_mm": [r.centroid[0] * 1e3, r.centroid[1] * 1e3],
            "area_mm2": r.area * 1e6,
            "peak": r.peak,
        })).collect::<Vec<_>>(),
        "found_touches": found.iter().map(|r| serde_json::json!({
            "centroid_mm": [r.centroid[0] * 1e3, r.centroid[1] * 1e3],
            "area_mm2": r.area * 1e6,
            "peak": r.peak,
            "z": r.z,
        })).collect::<Vec<_>>(),
        "touches_mm": truth.iter().map(|(c, _)| [c[0] * 1e3, c[1] * 1e3]).collect::<Vec<_>>(),
        "metrics_first_touch": m,
        "seconds": started.elapsed().as_secs_f64(),
    });
    if args.json {
        println!("{summary}");
    } else {
        for (i, r) in rois.iter().enumerate().take(5) {
            eprintln!(
                "region {i}: centroid ({:.1}, {:.1}) mm, area {:.0} mm^2",
                r.centroid[0] * 1e3,
                r.centroid[1] * 1e3,
                r.area * 1e6
            );
        }
        for (i, r) in found.iter().enumerate() {
            eprintln!(
                "touch {i}: at ({:.1}, {:.1}) mm{}",
                r.centroid[0] * 1e3,
                r.centroid[1] * 1e3,
                r.z.map_or(String::new(), |z| format!(", {z:.1} x its noise"))
            );
        }
        if let Some(m) = m {
            eprintln!(
                "PE {:.3}, SE {:.3}, RNG {:.3}, BVC {:.3e} V",
                m.pe, m.se, m.rng, m.bvc
            );
        }
        eprintln!("wrote {}", args.out.display());
    }
    Ok(())
}

fn ports_cmd() -> Result<()> {
    let ports = et_host::link::list_ports().context("listing serial ports")?;
    if ports.is_empty() {
        println!("no serial ports found (is the board plugged in?)");
    }
    for p in ports {
        println!("{p}");
    }
    Ok(())
}

/// `FILE.jsonl` for part 1, `FILE-2.jsonl`, `FILE-3.jsonl`, ... after configuration changes.
fn part_path(out: &std::path::Path, part: u32) -> PathBuf {
    if part == 1 {
        return out.to_path_buf();
    }
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}-{part}{ext}"))
}

fn record_cmd(args: &RecordArgs) -> Result<()> {
    use et_core::wire::{Command as Cmd, Uplink};
    use et_host::link::Link;
    use std::time::Duration;

    let mut link = Link::open(&args.port, args.baud)?;
    if !args.no_start {
        wait_for_board(&mut link)?;
        link.request(&Cmd::Start, Duration::from_secs(1))
            .with_context(|| format!("starting the scan on {}", args.port))?;
    }
    let deadline = args
        .seconds
        .map(|s| Instant::now() + Duration::from_secs_f64(s));
    let bar = ProgressBar::new_spinner().with_style(
        ProgressStyle::with_template("{spinner} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let (mut part, mut written) = (0u32, 0u64);
    let mut writer: Option<(et_core::ScanConfig, recording::Writer)> = None;
    while args.frames.is_none_or(|n| written < n) && deadline.is_none_or(|d| Instant::now() < d) {
        let frame = match link.next(Duration::from_millis(200)) {
            Ok(Uplink::Frame(f)) => f,
            Ok(Uplink::Event(_)) | Err(_) => {
                bar.set_message(link_progress(written, &link.counters()));
                bar.tick();
                continue;
            }
        };
        if writer
            .as_ref()
            .is_none_or(|(config, _)| *config != frame.config)
        {
            part += 1;
            let path = part_path(&args.out, part);
            let header = Header::new(format!("port:{}", args.port), &frame.config)?;
            let w = recording::Writer::create(&path, &header)?;
            bar.println(format!(
                "recording {} ({} electrodes, {}) into {}",
                args.port,
                frame.config.electrodes,
                frame.config.protocol.name(),
                path.display()
            ));
            writer = Some((frame.config, w));
        }
        if let Some((_, w)) = writer.as_mut() {
            w.append(&Record::new(&frame, None))?;
        }
        written += 1;
        if written % 25 == 0 {
            bar.set_message(link_progress(written, &link.counters()));
        }
    }
    bar.finish_and_clear();
    println!("recorded {}", link_progress(written, &link.counters()));
    Ok(())
}

/// "N frames, lost, damaged, reconnects": what a recording session has seen of the link.
fn link_progress(written: u64, c: &et_host::link::Counters) -> String {
    format!(
        "{written} frames, {} lost on the way, {} damaged packets dropped, {} reconnects",
        c.lost_frames, c.corrupt, c.reconnects
    )
}

/// Pings until the board answers (one that is still booting loses what it is sent).
fn wait_for_board(link: &mut et_host::link::Link) -> Result<()> {
    use std::time::Duration;
    let mut last = None;
    for nonce in 0..5 {
        match link.request(
            &et_core::wire::Command::Ping { nonce },
            Duration::from_secs(1),
        ) {
            Ok(_) => return Ok(()),
            Err(e) => last = Some(e),
        }
    }
    Err(anyhow::anyhow!(
        "no answer from the board on {}: {}",
        link.path(),
        last.map_or_else(String::new, |e| e.to_string())
    ))
}

fn upload_cmd(args: &UploadArgs) -> Result<()> {
    use std::time::Duration;
    let blob =
        std::fs::read(&args.blob).with_context(|| format!("reading {}", args.blob.display()))?;
    let model = et_core::model::Model::parse(&blob)
        .map_err(|e| anyhow::anyhow!("{}: not a valid model blob: {e:?}", args.blob.display()))?;
    let mut link = et_host::link::Link::open(&args.port, args.baud)?;
    wait_for_board(&mut link)?;
    let started = Instant::now();
    // Flash erase of a 384 KiB slot takes a few seconds.
    link.upload_model(&blob, Duration::from_secs(2), Duration::from_secs(15))
        .with_context(|| format!("uploading {}", args.blob.display()))?;
    println!(
        "uploaded {} ({} bytes, {} classes, {} features) in {:.1} s; the board verified it",
        args.blob.display(),
        blob.len(),
        model.classes(),
        model.features(),
        started.elapsed().as_secs_f64()
    );
    if args.tare {
        link.request(&et_core::wire::Command::Tare, Duration::from_secs(2))
            .context("taring (is the board scanning? `et record` starts it)")?;
        println!("V_0 taken: the board classifies every frame from now on");
    } else if model.referenced() {
        println!(
            "this model is referenced: it classifies once the board has V_0 (run again with --tare)"
        );
    }
    Ok(())
}

#[cfg(feature = "viewer")]
fn view_cmd(args: &ViewArgs) -> Result<()> {
    et_host::viewer::run(et_host::viewer::Options {
        scene: args.source.scene.clone(),
        source: args.source.spec(),
        model: args.source.model.clone(),
        realtime: true,
        screenshot: args.screenshot.clone(),
    })
    .map_err(anyhow::Error::msg)
}

#[cfg(not(feature = "viewer"))]
fn view_cmd(_: &ViewArgs) -> Result<()> {
    bail!(
        "this et was built without the viewer; build it with the `viewer` feature:\n  cargo run --release -p et-host --features viewer -- view"
    )
}

fn stream_cmd(args: &StreamArgs) -> Result<()> {
    use et_host::live::{Processor, Settings, Source, open_source};
    use std::io::Write as _;
    let (mut source, sheet) = open_source(&args.source.spec(), args.source.scene.as_deref())
        .map_err(anyhow::Error::msg)?;
    let mut processor = Processor::new(&sheet, Settings::default()).map_err(anyhow::Error::msg)?;
    processor.classifier = args.source.classifier()?;
    if let Some(c) = &processor.classifier {
        // The model classifies frames of the configuration it was trained on.
        source.configure(c.file.config).map_err(|e| {
            anyhow::anyhow!(
                "the model was trained on {} frames and the source cannot scan them: {e}",
                c.file.config.protocol.name()
            )
        })?;
    }
    if let Source::Replay(r) = &mut source {
        r.looping = false;
    }
    if !args.json {
        eprintln!("note: et stream prints JSON lines (--json); streaming them anyway");
    }
    eprintln!(
        "streaming touch events from the {} (the first {} frames are the untouched reference)",
        source.describe(),
        Settings::default().reference_frames
    );
    let limit = args.frames.unwrap_or(u64::MAX);
    let mut seen = 0u64;
    let mut stdout = std::io::stdout().lock();
    while seen < limit {
        let frames = source.poll(64, !args.fast).map_err(anyhow::Error::msg)?;
        if frames.is_empty() {
            if let Source::Replay(r) = &source
                && r.position >= r.len()
            {
                break;
            }
            std::thread::sleep(std::time::Duration::from_millis(2));
            continue;
        }
        for frame in frames {
            if seen >= limit {
                break;
            }
            seen += 1;
            let out = match processor.process(frame) {
                Ok(o) => o,
                Err(e) => {
                    eprintln!("skipped: {e}");
                    continue;
                }
            };
            if let Some(event) = out.event {
                let line = serde_json::to_string(&event)?;
                if writeln!(stdout, "{line}")
                    .and_then(|()| stdout.flush())
                    .is_err()
                {
                    // The reader went away (a closed pipe): stop quietly.
                    return Ok(());
                }
            }
        }
    }
    Ok(())
}

fn demo_cmd(args: &DemoArgs) -> Result<()> {
    let command = std::iter::once("et".to_string())
        .chain(std::env::args().skip(1))
        .collect::<Vec<_>>()
        .join(" ");
    let report = et_host::demo::run(&et_host::demo::Options {
        out: args.out.clone(),
        quick: args.quick,
        progress: !args.json,
        command,
    })?;
    if args.json {
        println!("{}", report.summary);
    } else {
        eprintln!("\nreport: {}", report.index.display());
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Demo(args) => demo_cmd(args),
        Command::Protocol(args) => protocol(args),
        Command::Sim(args) => sim(args),
        Command::Collect(args) => collect_cmd(args),
        Command::Train(args) => train_cmd(args),
        Command::Eval(args) => eval_cmd(args),
        Command::Export(args) => export_cmd(args),
        Command::Reconstruct(args) => reconstruct_cmd(args),
        Command::Forward(args) => forward_cmd(args),
        Command::Ports => ports_cmd(),
        Command::Record(args) => record_cmd(args),
        Command::Upload(args) => upload_cmd(args),
        Command::Stream(args) => stream_cmd(args),
        Command::View(args) => view_cmd(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
