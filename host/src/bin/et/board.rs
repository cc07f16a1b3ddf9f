//! `et ports`, `et record`, `et upload`: the board over its serial link.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

#[derive(Debug, clap::Args)]
pub(crate) struct UploadArgs {
    /// The board's serial port (`et ports` lists them).
    #[arg(long)]
    port: String,
    /// The model blob (`et export --out`). The board must be scanning the model's protocol
    /// and electrode count; a fresh board scans adjacent (see --model). The board keeps the
    /// model across resets and power cycles, scanning the scan it took it under.
    #[arg(long, required_unless_present_any = ["model", "clear"], conflicts_with = "model")]
    blob: Option<PathBuf>,
    /// The model file (`et train --out`) instead of a blob: the board is first set to the scan
    /// the model was trained on (its protocol, electrodes, samples, rate, current and gain),
    /// then sent the model's blob (f32 when it fits a slot, else f16).
    #[arg(long)]
    model: Option<PathBuf>,
    /// Baud rate (the firmware's is the default).
    #[arg(long, default_value_t = et_core::board::BAUD,
          value_parser = crate::domain::whole(1, u32::MAX))]
    baud: u32,
    /// Then start the scan (if it was not running) and take the next frame as V_0 (the sheet
    /// must not be touched).
    #[arg(long)]
    tare: bool,
    /// Instead of uploading: remove the board's model, which it keeps across restarts
    /// otherwise (its frames go on, unclassified).
    #[arg(long, conflicts_with_all = ["blob", "model", "tare"])]
    clear: bool,
}

#[derive(Debug, clap::Args)]
pub(crate) struct RecordArgs {
    /// The board's serial port (`et ports` lists them).
    #[arg(long)]
    port: String,
    /// Where to write the recording (.jsonl).
    #[arg(long)]
    out: PathBuf,
    /// Baud rate (the firmware's is the default).
    #[arg(long, default_value_t = et_core::board::BAUD,
          value_parser = crate::domain::whole(1, u32::MAX))]
    baud: u32,
    /// Stop after this many frames.
    #[arg(long, value_parser = crate::domain::whole(1, u64::MAX))]
    frames: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long, value_parser = crate::domain::above(0.0, 31_536_000.0))]
    seconds: Option<f64>,
    /// Do not send Start (the board is already scanning).
    #[arg(long)]
    no_start: bool,
}

pub(crate) fn ports_cmd() -> Result<()> {
    let ports = et_host::link::list_ports().context("listing serial ports")?;
    if ports.is_empty() {
        out!("no serial ports found (is the board plugged in?)");
    }
    for p in ports {
        out!("{p}");
    }
    Ok(())
}

pub(crate) fn record_cmd(args: &RecordArgs, force: bool) -> Result<()> {
    use et_host::link::Link;
    use et_host::recorder::{self, Notice, Plan};
    use std::time::Duration;

    let plan = Plan {
        out: args.out.clone(),
        frames: args.frames,
        duration: args.seconds.map(Duration::from_secs_f64),
        send_start: !args.no_start,
        force,
    };
    // Refuse an existing recording before the board is touched.
    crate::output::check(&plan.out, &[], force)?;
    crate::output::check_format(&plan.out, "a recording", &["jsonl"])?;
    let mut link = Link::open(&args.port, args.baud)?;
    if !args.no_start {
        wait_for_board(&mut link, args.baud)?;
        link.request(&et_core::wire::Command::Start, Duration::from_secs(1))
            .with_context(|| format!("starting the scan on {}", args.port))?;
    }
    let bar = ProgressBar::new_spinner().with_style(
        ProgressStyle::with_template("{spinner} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    let mut skipped_shown = 0u32;
    // Lines said above the spinner (its own `println` says nothing where standard error is
    // not a terminal: a board that sent nothing was waited for without a word in scripts).
    let said = |line: String| bar.suspend(|| say!("{line}"));
    let tally = recorder::record(&mut link, &plan, |notice| match notice {
        Notice::Part { path, config } => said(format!(
            "recording {} ({} electrodes, {}) into {}",
            args.port,
            config.electrodes,
            config.protocol.name(),
            path.display()
        )),
        Notice::Skipped { seq, got, expected } => {
            // The first few in full; the rest are counted in the summary.
            skipped_shown += 1;
            if skipped_shown <= 5 {
                said(format!(
                    "skipped frame {seq}: {got} values, its configuration has K = {expected}"
                ));
            }
        }
        Notice::Link(change) => said(format!("{}: {change}", args.port)),
        Notice::Board(report) => said(format!("{}: {report}", args.port)),
        Notice::Flagged { seq, said: words } => said(format!(
            "warning: frame {seq}: {words} (said once; the summary counts them): such frames' \
             values may not be the sheet's"
        )),
        Notice::Progress(t) => {
            bar.set_message(t.to_string());
            bar.tick();
        }
    })?;
    bar.finish_and_clear();
    out!("recorded {tally}");
    Ok(())
}

/// Pings until the board answers (one that is still booting loses what it is sent); `baud`
/// is the rate the port was opened at, named when the board never answers.
pub(crate) fn wait_for_board(link: &mut et_host::link::Link, baud: u32) -> Result<()> {
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
        "no answer from the board on {} at {baud} baud ({}): {}",
        link.path(),
        last.map_or_else(String::new, |e| e.to_string()),
        et_host::link::silent_board_hint(baud)
    ))
}

/// The blob at `path` (at most 16 MiB).
fn read_blob(path: &std::path::Path) -> Result<Vec<u8>> {
    et_core::text::read_at_most(path, 1 << 24)
        .with_context(|| format!("reading {}", path.display()))
}

/// `et upload --clear`: the board's model removed, for good.
fn clear_model(args: &UploadArgs) -> Result<()> {
    let mut link = et_host::link::Link::open(&args.port, args.baud)?;
    wait_for_board(&mut link, args.baud)?;
    link.request(
        &et_core::wire::Command::ModelClear,
        std::time::Duration::from_secs(2),
    )
    .context("clearing the board's model")?;
    out!(
        "cleared the board's model: it classifies no frame from now on, nor after a restart \
         (its frames go on)"
    );
    Ok(())
}

pub(crate) fn upload_cmd(args: &UploadArgs) -> Result<()> {
    use std::time::Duration;
    if args.clear {
        return clear_model(args);
    }
    let (path, blob, config) = match (&args.blob, &args.model) {
        (_, Some(path)) => {
            let board = et_learn::Model::load(path)?
                .into_board()
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            let blob =
                (board.slot_blob()).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            (path, blob, Some(board.file().config))
        }
        (Some(path), None) => (path, read_blob(path)?, None),
        (None, None) => anyhow::bail!("give the model: --blob (et export's) or --model"),
    };
    let model = et_core::model::Model::parse(&blob).map_err(|e| {
        let shown = path.display();
        // The model file `et train` wrote, given for the blob made from it.
        if blob.trim_ascii_start().starts_with(b"{") {
            anyhow::anyhow!(
                "{shown}: a model file (JSON, as et train writes), not the board's blob: \
                 upload it with --model {shown} (which also sets the board to its scan), or \
                 `et export --model {shown} --out model.etm` makes the blob"
            )
        } else {
            anyhow::anyhow!("{shown}: not a valid model blob: {e}")
        }
    })?;
    // A flag that changes nothing is refused (it took a V_0 the model never reads).
    if args.tare && !model.referenced() {
        anyhow::bail!(
            "--tare: {} reads frames as measured (trained with --raw) and takes no V_0: drop \
             --tare",
            path.display()
        );
    }
    let mut link = et_host::link::Link::open(&args.port, args.baud)?;
    wait_for_board(&mut link, args.baud)?;
    if let Some(config) = config {
        link.request(
            &et_core::wire::Command::Configure(config),
            Duration::from_secs(2),
        )
        .with_context(|| {
            format!(
                "setting the board to the scan {} was trained on",
                path.display()
            )
        })?;
        out!(
            "set the board to the scan the model was trained on: L = {}, {}, {} samples a step at {} Hz, {} uA, gain {}",
            config.electrodes,
            config.protocol.name(),
            config.samples_per_step,
            config.sample_rate_hz,
            f64::from(config.current_na) / 1e3,
            config.gain
        );
    }
    let started = Instant::now();
    // Flash erase of a 384 KiB slot takes a few seconds.
    link.upload_model(&blob, Duration::from_secs(2), Duration::from_secs(15))
        .map_err(|e| match e {
            et_host::link::LinkError::Refused {
                reason: et_core::wire::Refusal::ModelMismatch,
                ..
            } => anyhow::anyhow!(
                "uploading {}: the board refused it: the model was trained for {} at L = {}, \
                 and the board scans another protocol or electrode count (a board starts on \
                 adjacent): upload the model file instead, `et upload --model model.json`, \
                 which first sets the board to the scan it was trained on",
                path.display(),
                model.protocol().kind().name(),
                model.protocol().electrodes()
            ),
            e => anyhow::Error::new(e).context(format!("uploading {}", path.display())),
        })?;
    out!(
        "uploaded {} ({} bytes, {} classes, {} features) in {:.1} s; the board verified it \
         and keeps it across restarts (et upload --clear removes it)",
        path.display(),
        blob.len(),
        model.classes(),
        model.features(),
        started.elapsed().as_secs_f64()
    );
    if args.tare {
        // V_0 is the next frame: a board that was not scanning (a fresh one) is started
        // (Start is idempotent; the tare waited for a frame that never came).
        link.request(&et_core::wire::Command::Start, Duration::from_secs(2))
            .context("starting the scan for V_0")?;
        link.request(&et_core::wire::Command::Tare, Duration::from_secs(2))
            .context("taring")?;
        out!("V_0 taken: the board scans and classifies every frame from now on");
    } else if model.referenced() {
        out!(
            "this model is referenced: it classifies once the board has V_0 (run again with --tare)"
        );
    }
    Ok(())
}
