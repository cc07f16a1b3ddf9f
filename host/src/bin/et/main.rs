//! `et`: the command-line program of the et workspace.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// `eprintln!` that never panics: a message to standard error that cannot be written (`2>
/// /dev/full`, a closed stream) is dropped, and the command's work and outputs go on.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stderr(), $($arg)*);
    }};
}

/// Says once that what goes to standard output is dropped, where the caller closed it
/// (`>&-`; [`et_host::output::stdout_closed`]).
fn note_stdout_closed() {
    static SAID: std::sync::Once = std::sync::Once::new();
    if et_host::output::stdout_closed() {
        SAID.call_once(|| {
            say!(
                "note: standard output is closed (>&-) or the null device: what et prints there \
                 is dropped"
            );
        });
    }
}

/// Whether standard output's reader went away while the command had files to write: what it
/// prints there is dropped from then on ([`reader_went_away`]).
static READER_GONE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Standard output's reader went away (a closed pipe: `et protocol --json | head`): the program
/// ends quietly, as Unix tools do, unless it has files to write (`et reconstruct --all --out
/// last.png --image-out stack.npy | head -1` ended without them, exit 0); then it goes on
/// without standard output, said once, and writes them.
fn reader_went_away() {
    use std::sync::atomic::Ordering::Relaxed;
    if !et_host::output::files_to_write() {
        std::process::exit(0);
    }
    if !READER_GONE.swap(true, Relaxed) {
        say!(
            "note: standard output's reader went away (| head?): the rest of what et prints \
             there is dropped; the files asked for are still written"
        );
    }
}

/// Writes a `--plots` folder with `write` (given the folder to write into): a new one made
/// aside and renamed when complete (`output::write_folder`: a stopped run left a folder of
/// one plot, which the next run refused without --force), its parent folders made first.
fn plots_folder(
    dir: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> anyhow::Result<()>,
) -> anyhow::Result<()> {
    use anyhow::Context as _;
    if let Some(parent) = dir.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    et_host::output::write_folder(dir, write)
}

/// `println!` for a command's output on stdout: when the reader goes away the program ends
/// quietly or goes on without it ([`reader_went_away`]), instead of panicking; where the caller
/// closed standard output (`>&-`) the result is dropped, said once.
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        crate::note_stdout_closed();
        if !crate::READER_GONE.load(std::sync::atomic::Ordering::Relaxed) {
            let mut stdout = std::io::stdout().lock();
            if let Err(e) = writeln!(stdout, $($arg)*).and_then(|()| stdout.flush()) {
                if e.kind() == std::io::ErrorKind::BrokenPipe {
                    crate::reader_went_away();
                } else {
                    say!("error: writing to stdout: {e}");
                    std::process::exit(1);
                }
            }
        }
    }};
}

mod board;
mod collect;
mod demo;
mod domain;
mod evaluate;
mod imaging;
mod learn;
mod live;
mod output;
mod protocol;
mod sim;
mod spinner;
mod tabular;

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
    /// Replace output files and report folders that exist (never a command's own input;
    /// without it, et refuses to overwrite anything). Refused by the commands that write no
    /// file (protocol, forward, ports, upload, stream).
    #[arg(long, global = true)]
    force: bool,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run the whole method on the simulated sheet into a report folder (no hardware).
    ///
    /// The whole method on the simulated sheet, no hardware needed: collect a training set,
    /// train and cross-validate QDA, test it on next-day sessions and on the chip's model
    /// blob, image docs/method.md §7's reference scenarios with every protocol, and sweep mesh size
    /// against accuracy and time. Writes a report folder (index.md with PNG figures, and
    /// summary.json) and prints where it is. About 1 to 2 minutes in a release build.
    ///
    /// Examples:
    ///   et demo
    ///   et demo --out /tmp/report --json
    ///   et demo --quick            (small sizes: a 10-second smoke test)
    #[command(verbatim_doc_comment)]
    Demo(demo::DemoArgs),
    /// Print a protocol's tables: injection pairs, measurement pairs, K and p (docs/method.md §4).
    ///
    /// Print a protocol's tables (docs/method.md §4), or a protocol file: a built-in one
    /// (--csv), or one crossed from another system's lists of injections and measurements
    /// (--injections, --measurements: pairs or patterns) or read from EIDORS's stimulation
    /// struct array (--stimulation), for a scene's `[scan] protocol = { file = "protocol.csv" }`.
    ///
    /// Examples:
    ///   et protocol --electrodes 16 --protocol adjacent
    ///   et protocol -l 16 -p opposite --json > opposite16.json
    ///   et protocol -l 16 --drive-skip 3 --measure-skip 0 --measure-skip 3
    ///   et protocol -l 16 -p adjacent --csv --current-a 1.4e-3 > protocol.csv
    ///   et protocol --injections inj.csv --measurements meas.csv --current-unit mA > protocol.csv
    ///   et protocol --injections ref.mat:Injref --measurements ref.mat:Mpat --patterns columns
    ///   et protocol --stimulation stim.mat > protocol.csv      (EIDORS's mk_stim_patterns)
    #[command(verbatim_doc_comment)]
    Protocol(protocol::ProtocolArgs),
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
    Sim(sim::SimArgs),
    /// Collect a labelled training set on the simulated sheet (docs/method.md §9), as CSV or .npz.
    ///
    /// Collect a labelled training set on the simulated sheet, the docs/method.md §9 way: a grid of
    /// touch classes, visited T times, S_num scans per class and visit with the pressure varied,
    /// S_sub observations per scan. Each visit is a measurement set (the clips' junction
    /// potentials and the sheet's conductance drawn anew, docs/calibration.md) and starts with
    /// an untouched frame, which referenced models subtract. Each press varies as a hand's do
    /// (where in its target it lands, its size, the force wandering during the scan).
    /// Writes CSV ('#' lines, a row of column names, then the rows; Python:
    /// python/et_dataset.py, whose docstring also gives the numpy recipe), or NumPy arrays
    /// when --out ends in .npz (numpy.load).
    ///
    /// Examples:
    ///   et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --out train.csv
    ///   et collect --scene sim/scenes/square-13cm-16.toml --grid 7x7 --visits 1 --scans 1 --seed 77 --out nextday.csv
    #[command(verbatim_doc_comment)]
    Collect(collect::CollectArgs),
    /// Train a touch model (classes or positions) and cross-validate it.
    ///
    /// On an et dataset (--data, from et collect): a QDA or LDA classifier for the board
    /// (shrinkage chosen by leave-one-visit-out cross-validation unless given). By default the
    /// model is referenced: it classifies each frame minus its session's untouched frame,
    /// which cancels electrode movement between sessions (--raw: docs/method.md §9's raw frames).
    ///
    /// On any sensor's data (--features F.csv, optionally --targets T.csv with the same rows):
    /// qda, lda (class labels, or --grid RxC cells made from positions), ridge, kernel-ridge,
    /// knn, gp (positions x, y and an optional z or force), or auto (tries them by
    /// cross-validation and says which won). Hyperparameters are chosen by cross-validation
    /// inside the training rows (--rows A..B; --cv blocks for recordings in time order) and
    /// printed. Files may have a UTF-8 byte-order mark, a header row or none, CRLF ends.
    ///
    /// Examples:
    ///   et train --data train.csv --out model.json
    ///   et train --data train.csv --kind lda --out lda.json --curve learning-curve.png
    ///   et train --features F.csv --targets T.csv --unit m --rows 0..2000 --kind auto --out m.json
    ///   et train --features F.csv --targets T.csv --unit m --grid 7x7 --kind lda --out cells.json
    #[command(verbatim_doc_comment)]
    Train(learn::TrainArgs),
    /// Evaluate a trained model on a test set: accuracy, mean position error, AEE, confusion.
    ///
    /// Evaluate a trained model on a test set (collected on another day). It reports:
    ///   accuracy             the share of observations given their true class
    ///   mean position error  the distance between the true and the predicted class centre,
    ///                        averaged over every observation (0 when right), mm
    ///   AEE                  aggregated estimation error (docs/method.md §9): the distances
    ///                        of the wrong decisions summed, over the number of classes, mm
    ///   confusion            counts per (true class, predicted class)
    /// and the same by distance from the nearest electrode (where on the sheet the model is
    /// weaker).
    ///
    /// A model trained on any sensor's data (--features) is evaluated on --features and
    /// --targets files of the same shape: mean, median and 90th-percentile position error
    /// (mm), accuracy for classes, and fit and predict times.
    ///
    /// Examples:
    ///   et eval --model model.json --data nextday.csv
    ///   et eval --model model.json --data nextday.csv --plots plots/ --json
    ///   et eval --model m.json --features F.csv --targets T.csv --unit m --rows 2000..2500 --json
    #[command(verbatim_doc_comment)]
    Eval(evaluate::EvalArgs),
    /// Export a trained model as the board's model blob.
    ///
    /// Export a trained model as the model blob the firmware evaluates (f32, or f16 at half
    /// the flash), with its size and evaluation cost.
    ///
    /// Example:
    ///   et export --model model.json --precision f16 --out model.etm
    #[command(verbatim_doc_comment)]
    Export(evaluate::ExportArgs),
    /// Image touches (a scene's, or recorded frames) by one-step Gauss-Newton, as PNG + metrics.
    ///
    /// Image a scene's touches by one-step Gauss-Newton difference imaging (docs/method.md §6): mesh the
    /// sheet, the complete electrode model's Jacobian at the untouched sheet, the NOSER
    /// reconstruction matrix; then the simulator's frames without and with the touches (its
    /// resistor network, not these finite elements) give the image, its regions and the
    /// docs/method.md §7 metrics. Writes the image as PNG with a colour bar.
    ///
    /// alpha is the regularisation weight (larger: smoother, less noisy images; default:
    /// chosen per frame by generalised cross-validation, GCV); s the NOSER exponent that
    /// weights the prior by the sensitivity. The region of interest (ROI) is the pixels above
    /// f times the image's maximum; a touch is an ROI peak split at its saddles whose height
    /// reaches z = 5 times its pixels' noise. Metrics, of the first touch (0 is best):
    ///   PE   position error: true centre to ROI centroid, over the sheet's largest extent
    ///   SE   size error: |ROI area - touch area| over the sheet's area
    ///   RNG  ringing: area of opposite-sign change over the area outside the ROI
    ///   BVC  boundary voltage change |V_m - V_0|, V (larger: the touch is easier to see)
    ///
    /// Examples:
    ///   et reconstruct --scene sim/scenes/disc-ref-x050.toml --out x050.png
    ///   et reconstruct --scene sim/scenes/disc-ref-two.toml --alpha 0.01 --out two.png --json
    ///   et reconstruct --scene sim/scenes/square-13cm-16-swipe.toml --frames swipe.jsonl --frame 60 --out f60.png
    ///   et reconstruct --scene sim/scenes/disc-ref-x050.toml --refine 55,0,25 --out x050-roi.png
    #[command(verbatim_doc_comment)]
    Reconstruct(imaging::ReconstructArgs),
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
    Forward(imaging::ForwardArgs),
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
    Record(board::RecordArgs),
    /// Open the viewer: live image, class grid, plots, training wizard (feature `viewer`).
    ///
    /// Open the viewer: the live image with its colour bar and ROI outline, the class grid
    /// with the recognised class lit and the position marker, protocol (or automatic),
    /// alpha and threshold, plots of frame rate, BVC and per-channel SNR, link health, and the
    /// training wizard. Press the simulated sheet with the mouse. Needs the `viewer` feature
    /// (off by default: `cargo run --release -p et-host --features viewer --bin et -- view`).
    ///
    /// Examples:
    ///   et view                                   (the simulated 13 x 13 cm sheet)
    ///   et view --scene sim/scenes/disc-22cm-16.toml
    ///   et view --replay session.jsonl
    ///   et view --port /dev/ttyUSB0 --model model.json
    #[command(verbatim_doc_comment)]
    View(live::ViewArgs),
    /// Print touch events as JSON lines for other programs.
    ///
    /// Print touch events as JSON lines for downstream programs (a robot, a game, a logger):
    /// class, position, intensity (the image's strongest pixel in units of its noise on the
    /// untouched sheet, a z-score), confidence (the model's posterior), timestamp, one line per
    /// touched frame. From
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
    Stream(live::StreamArgs),
    /// Upload a model to the board (which verifies it before using it).
    ///
    /// Upload a model to the board over its serial port: the model file `et train` wrote
    /// (--model: the board is first set to the scan it was trained on) or a blob from `et
    /// export` (--blob: the board must already scan its protocol and electrode count; a board
    /// starts on adjacent). The board verifies it (CRC, model checks, scan configuration)
    /// before it replaces the old model; a refused upload leaves the old one classifying. A
    /// referenced model needs the untouched frame V_0: add --tare (with the sheet untouched;
    /// the scan is started if it was not running).
    ///
    /// Examples:
    ///   et upload --port /dev/ttyUSB0 --model model.json --tare
    ///   et export --model model.json --precision f16 --out model.etm
    ///   et upload --port /dev/ttyUSB0 --blob model.etm --tare
    #[command(verbatim_doc_comment)]
    Upload(board::UploadArgs),
}

/// `--flag -1e-3` as `--flag=-1e-3`: clap takes a negative number for a value only in its
/// plain forms (`-1`, `-0.1`), and read the exponent's form as short flags ("unexpected
/// argument '-1' found"); joined, the value reaches its flag's domain. A number is never a
/// flag, so nothing else changes (a flag that takes no value still refuses one).
fn negatives_joined(args: impl IntoIterator<Item = std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let mut out: Vec<std::ffi::OsString> = Vec::new();
    let mut args = args.into_iter().peekable();
    while let Some(arg) = args.next() {
        let long = arg
            .to_str()
            .filter(|a| a.len() > 2 && a.starts_with("--") && !a.contains('='));
        let number = args
            .peek()
            .and_then(|next| next.to_str())
            .filter(|next| next.starts_with('-') && next.parse::<f64>().is_ok());
        match (long, number) {
            (Some(flag), Some(value)) => {
                out.push(format!("{flag}={value}").into());
                args.next();
            }
            _ => out.push(arg),
        }
    }
    out
}

/// The command line, or exit: help and version go to stdout, and a stdout that cannot take
/// them (a full device) is an error, not a silent success.
fn parse() -> Cli {
    use clap::{CommandFactory as _, FromArgMatches as _};
    use std::io::Write as _;
    // A negative number reaches its flag's own domain ("-0.1 is outside 0 to 1"), where clap
    // would read it as short flags ("unexpected argument '-0' found").
    let negative = |arg: clap::Arg| {
        let takes_values = arg.get_action().takes_values();
        arg.allow_negative_numbers(takes_values)
    };
    let mut command = Cli::command()
        .mut_args(negative)
        .mut_subcommands(|sub| sub.mut_args(negative));
    let parsed = command
        .try_get_matches_from_mut(negatives_joined(std::env::args_os()))
        .and_then(|matches| Cli::from_arg_matches(&matches))
        .map_err(|e| e.format(&mut command));
    match parsed {
        Ok(cli) => cli,
        Err(e)
            if matches!(
                e.kind(),
                clap::error::ErrorKind::DisplayHelp | clap::error::ErrorKind::DisplayVersion
            ) =>
        {
            use std::io::IsTerminal as _;
            let mut stdout = std::io::stdout().lock();
            let text = if stdout.is_terminal() {
                e.render().ansi().to_string()
            } else {
                e.render().to_string()
            };
            match stdout
                .write_all(text.as_bytes())
                .and_then(|()| stdout.flush())
            {
                Ok(()) => std::process::exit(0),
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => std::process::exit(0),
                Err(e) => {
                    say!("error: writing to stdout: {e}");
                    std::process::exit(1);
                }
            }
        }
        Err(e) => e.exit(),
    }
}

impl Command {
    /// The command's name where it writes no file (it prints, or talks to a board), for which
    /// `--force` means nothing.
    fn writes_nothing(&self) -> Option<&'static str> {
        match self {
            Command::Protocol(_) => Some("protocol"),
            Command::Forward(_) => Some("forward"),
            Command::Ports => Some("ports"),
            Command::Upload(_) => Some("upload"),
            Command::Stream(_) => Some("stream"),
            _ => None,
        }
    }
}

fn main() -> ExitCode {
    et_host::output::note_standard_streams();
    let cli = parse();
    if let Err(e) = et_host::output::clean_up_on_signals() {
        say!("warning: Ctrl-C will not remove partial outputs: {e}");
    }
    let force = cli.force;
    if let (true, Some(name)) = (force, cli.command.writes_nothing()) {
        // A flag that changes nothing is refused, not ignored.
        say!(
            "error: --force: et {name} writes no file, so there is nothing to replace; drop --force"
        );
        return ExitCode::FAILURE;
    }
    let result = match &cli.command {
        Command::Demo(args) => demo::run(args, force),
        Command::Protocol(args) => protocol::run(args),
        Command::Sim(args) => sim::run(args, force),
        Command::Collect(args) => collect::collect_cmd(args, force),
        Command::Train(args) => learn::train_cmd(args, force),
        Command::Eval(args) => evaluate::eval_cmd(args, force),
        Command::Export(args) => evaluate::export_cmd(args, force),
        Command::Reconstruct(args) => imaging::reconstruct_cmd(args, force),
        Command::Forward(args) => imaging::forward_cmd(args),
        Command::Ports => board::ports_cmd(),
        Command::Record(args) => board::record_cmd(args, force),
        Command::Upload(args) => board::upload_cmd(args),
        Command::Stream(args) => live::stream_cmd(args),
        Command::View(args) => live::view_cmd(args, force),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if et_host::message::reader_went_away(&e) => ExitCode::SUCCESS,
        Err(e) => {
            say!("error: {}", et_host::message::one_line(&e));
            ExitCode::FAILURE
        }
    }
}
