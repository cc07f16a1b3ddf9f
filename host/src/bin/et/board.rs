//! `et ports`, `et record`, `et upload`: the board over its serial link.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use et_host::recording::{self, Header, Record};
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
    #[arg(long, default_value_t = et_core::board::BAUD)]
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
    #[arg(long, default_value_t = et_core::board::BAUD)]
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

pub(crate) fn ports_cmd() -> Result<()> {
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
pub(crate) fn part_path(out: &std::path::Path, part: u32) -> PathBuf {
    if part == 1 {
        return out.to_path_buf();
    }
    let stem = out.file_stem().unwrap_or_default().to_string_lossy();
    let ext = out
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    out.with_file_name(format!("{stem}-{part}{ext}"))
}

pub(crate) fn record_cmd(args: &RecordArgs) -> Result<()> {
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
pub(crate) fn link_progress(written: u64, c: &et_host::link::Counters) -> String {
    format!(
        "{written} frames, {} lost on the way, {} damaged packets dropped, {} reconnects",
        c.lost_frames, c.corrupt, c.reconnects
    )
}

/// Pings until the board answers (one that is still booting loses what it is sent).
pub(crate) fn wait_for_board(link: &mut et_host::link::Link) -> Result<()> {
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

pub(crate) fn upload_cmd(args: &UploadArgs) -> Result<()> {
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
