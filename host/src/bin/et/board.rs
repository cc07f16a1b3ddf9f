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
    /// The model blob (`et export --out`).
    #[arg(long)]
    blob: PathBuf,
    /// Baud rate (the firmware's is the default).
    #[arg(long, default_value_t = et_core::board::BAUD,
          value_parser = clap::value_parser!(u32).range(1..))]
    baud: u32,
    /// Then take the next frame as V_0 (the sheet must not be touched).
    #[arg(long)]
    tare: bool,
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
          value_parser = clap::value_parser!(u32).range(1..))]
    baud: u32,
    /// Stop after this many frames.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
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

pub(crate) fn upload_cmd(args: &UploadArgs) -> Result<()> {
    use std::time::Duration;
    let blob = et_core::text::read_at_most(&args.blob, 1 << 24)
        .with_context(|| format!("reading {}", args.blob.display()))?;
    let model = et_core::model::Model::parse(&blob).map_err(|e| {
        let path = args.blob.display();
        // The model file `et train` wrote, given for the blob made from it.
        if blob.trim_ascii_start().starts_with(b"{") {
            anyhow::anyhow!(
                "{path}: a model file (JSON, as et train writes), not the board's blob: \
                 `et export --model {path} --out model.etm` makes the blob, then upload that"
            )
        } else {
            anyhow::anyhow!("{path}: not a valid model blob: {e}")
        }
    })?;
    // A flag that changes nothing is refused (it took a V_0 the model never reads).
    if args.tare && !model.referenced() {
        anyhow::bail!(
            "--tare: {} reads frames as measured (trained with --raw) and takes no V_0: drop \
             --tare",
            args.blob.display()
        );
    }
    let mut link = et_host::link::Link::open(&args.port, args.baud)?;
    wait_for_board(&mut link, args.baud)?;
    let started = Instant::now();
    // Flash erase of a 384 KiB slot takes a few seconds.
    link.upload_model(&blob, Duration::from_secs(2), Duration::from_secs(15))
        .with_context(|| format!("uploading {}", args.blob.display()))?;
    out!(
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
        out!("V_0 taken: the board classifies every frame from now on");
    } else if model.referenced() {
        out!(
            "this model is referenced: it classifies once the board has V_0 (run again with --tare)"
        );
    }
    Ok(())
}
