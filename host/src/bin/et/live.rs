//! `et view` and `et stream`: live sensing from the simulator, a recording or a board.

use std::path::PathBuf;

use anyhow::Result;

/// Where live frames come from (`et stream`, `et view`).
#[derive(Debug, Clone, clap::Args)]
pub(crate) struct SourceArgs {
    /// The scene to simulate; with --replay or --port, the sheet they were made on (its
    /// shape and electrodes, for imaging). Default: the 13 x 13 cm, 16-electrode sheet;
    /// another system's frames (a CSV, .npy, .npz or .mat) need the scene of their own.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Replay a recording (JSON Lines from `et sim` or `et record`), or another system's
    /// frames in volts for the scene's built-in protocol (or a protocol file of one's rows,
    /// as `et protocol --csv` writes them): a CSV (one frame per row), .npy,
    /// .npz (FILE.npz:NAME) or MATLAB .mat (FILE.mat:VARIABLE, or FILE.mat:vi.meas), as
    /// `et reconstruct --frames` reads them.
    #[arg(long, conflicts_with = "port")]
    replay: Option<PathBuf>,
    /// A board's serial port (`et ports` lists them).
    #[arg(long)]
    port: Option<String>,
    /// Baud rate of --port (default: the firmware's, 2000000).
    #[arg(long, requires = "port", value_parser = crate::domain::whole(1, u32::MAX))]
    baud: Option<u32>,
    /// A trained model (`et train`) to classify each touch with on the host.
    #[arg(long)]
    model: Option<PathBuf>,
    /// The reconstruction the images are made with: gn (one-step Gauss-Newton, alpha 0.3)
    /// or greit (GREIT at the consensus noise figure 0.5). docs/method.md §6.
    #[arg(long, value_enum, default_value_t = et_recon::Method::default())]
    method: et_recon::Method,
    /// Untouched frames averaged into V_0 at the start (and after a tare), the sheet not
    /// touched while they come. Another system's file with fewer untouched frames at its
    /// start: give their count; with 1, each frame's noise is estimated from the frame
    /// itself, as `et reconstruct` does.
    #[arg(long, default_value_t = 20, value_name = "FRAMES",
          value_parser = crate::domain::count(1, REFERENCE_MOST))]
    reference: usize,
    /// Leave out of the images every value these electrodes drive or measure, counted from 0
    /// as the board counts them, or from 1 where the scene's protocol file does (several:
    /// 3,7): a detached or broken electrode, which is named once V_0 is taken. At most half
    /// the electrodes; a model still classifies whole frames.
    #[arg(long, value_name = "E,...", value_delimiter = ',',
          value_parser = crate::domain::electrode)]
    skip_electrodes: Vec<u16>,
}

/// The most untouched frames --reference takes (10 minutes of a board's frames).
const REFERENCE_MOST: usize = 100_000;

impl SourceArgs {
    fn spec(&self) -> et_host::live::SourceSpec {
        use et_host::live::SourceSpec;
        match (&self.replay, &self.port) {
            (Some(path), _) => SourceSpec::Replay(path.clone()),
            (None, Some(port)) => {
                SourceSpec::Port(port.clone(), self.baud.unwrap_or(et_core::board::BAUD))
            }
            (None, None) => SourceSpec::Sim,
        }
    }

    /// Leaves `--skip-electrodes` out of `processor`'s images, saying how many values of
    /// `scan`'s frames (the source's first, when known) that is.
    fn leave_out(
        &self,
        processor: &mut et_host::live::Processor,
        scan: Option<et_core::ScanConfig>,
    ) -> Result<()> {
        if self.skip_electrodes.is_empty() {
            return Ok(());
        }
        // As the source's user counts them (a protocol file's from 1), as every electrode
        // et stream names is.
        let said = |e: et_host::live::LiveError| anyhow::anyhow!("--skip-electrodes: {e}");
        let zero_based = processor
            .counted_from_zero(&self.skip_electrodes)
            .map_err(said)?;
        let (left_out, k) = processor
            .set_left_out(&zero_based, scan)
            .map_err(|e| match e {
                et_host::live::LiveError::LeftOut(e) => anyhow::anyhow!("--skip-electrodes: {e}"),
                other => other.into(),
            })?;
        say!(
            "note: --skip-electrodes {}: {left_out} of {}'s {k} values left out of the images \
             (every value they drive or measure)",
            skip_with(processor, &[]),
            scan.map_or("the frame", |c| c.protocol.name())
        );
        Ok(())
    }

    fn classifier(&self) -> Result<Option<et_learn::model::Board>> {
        self.model
            .as_deref()
            .map(|p| {
                // Load errors name the file already.
                et_learn::Model::load(p)?
                    .into_board()
                    .map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
            })
            .transpose()
    }
}

#[derive(Debug, clap::Args)]
pub(crate) struct ViewArgs {
    #[command(flatten)]
    source: SourceArgs,
    /// For documentation: once V_0 is taken (and --press is pressed), save the window as
    /// this PNG a second later, and close. Runs under Xvfb too:
    /// `xvfb-run -a -s "-screen 0 1280x800x24" et view --screenshot view.png`.
    #[arg(long, value_name = "PNG")]
    screenshot: Option<PathBuf>,
    /// With --screenshot: press the simulated sheet at X,Y mm (a 7.5 mm fingertip, 30 kPa)
    /// once V_0 is taken. Without it nothing is pressed: a scene's own touches, or a
    /// recording's frames, are what the picture shows.
    #[arg(long, value_name = "X,Y", requires = "screenshot", value_parser = parse_point_mm)]
    press: Option<[f64; 2]>,
}

/// "X,Y" in mm (finite numbers).
fn parse_point_mm(s: &str) -> std::result::Result<[f64; 2], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let [x, y] = parts[..] else {
        return Err(format!("'{s}': give the point as X,Y in mm, e.g. 30,25"));
    };
    let number = |v: &str| {
        v.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{v}' is not a number of mm"))
    };
    Ok([number(x)?, number(y)?])
}

#[derive(Debug, clap::Args)]
pub(crate) struct StreamArgs {
    #[command(flatten)]
    source: SourceArgs,
    /// JSON lines on stdout (the only output format; the flag says so in scripts).
    #[arg(long)]
    json: bool,
    /// Stop after this many frames (default: run until Ctrl-C or the end of a recording).
    #[arg(long, value_parser = crate::domain::whole(1, u64::MAX))]
    frames: Option<u64>,
    /// Simulate as fast as possible instead of in real time (the simulator's frames only: a
    /// recording is streamed as fast as it is read, a board at its own rate).
    #[arg(long, conflicts_with_all = ["replay", "port"])]
    fast: bool,
}

#[cfg(feature = "viewer")]
pub(crate) fn view_cmd(args: &ViewArgs, force: bool) -> Result<()> {
    if let Some(png) = &args.screenshot {
        // The scene's own named files (its protocol file) too; a scene that does not load
        // is said where the viewer reads it.
        let named = (args.source.scene.as_deref())
            .and_then(|s| et_sim::scene::Scene::load(s).ok())
            .map(|s| s.files())
            .unwrap_or_default();
        let mut inputs: Vec<&std::path::Path> =
            [&args.source.scene, &args.source.replay, &args.source.model]
                .into_iter()
                .filter_map(|p| p.as_deref())
                .collect();
        inputs.extend(named.iter().map(PathBuf::as_path));
        crate::output::check(png, &inputs, force)?;
        crate::output::check_format(png, "the screenshot (PNG)", &["png"])?;
    }
    if args.press.is_some() && args.source.spec() != et_host::live::SourceSpec::Sim {
        anyhow::bail!("--press presses the simulated sheet: drop --replay / --port, or --press");
    }
    et_host::viewer::run(et_host::viewer::Options {
        scene: args.source.scene.clone(),
        source: args.source.spec(),
        model: args.source.model.clone(),
        method: args.source.method,
        reference_frames: args.source.reference,
        realtime: true,
        screenshot: args.screenshot.clone(),
        press: args.press,
        left_out: args.source.skip_electrodes.clone(),
    })?;
    Ok(())
}

#[cfg(not(feature = "viewer"))]
pub(crate) fn view_cmd(_: &ViewArgs, _force: bool) -> Result<()> {
    anyhow::bail!(
        "this et was built without the viewer (the `viewer` feature, off by default: it doubles a \
         fresh build); build it with the feature:\n  cargo run --release -p et-host --features \
         viewer --bin et -- view\n(or install it once: cargo install --path host --features viewer)"
    )
}

/// Faults or refusals a board may report with no frame between them before `et stream`
/// ends: one is a scan that failed, several in a row (one a second) a scan it cannot make.
const FAULTS_WITHOUT_A_FRAME: usize = 5;

pub(crate) fn stream_cmd(args: &StreamArgs) -> Result<()> {
    use et_host::live::{Processor, Settings, Source, open_source};
    use std::io::Write as _;
    crate::note_stdout_closed();
    let (mut source, sheet) = open_source(&args.source.spec(), args.source.scene.as_deref())?;
    let mut processor = Processor::new(
        &sheet.physical,
        Settings {
            method: args.source.method,
            reference_frames: args.source.reference,
            ..Settings::default()
        },
    )?;
    if let Some((board, path)) = args.source.classifier()?.zip(args.source.model.as_ref()) {
        (processor.set_classifier(board))
            .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    if let Some(c) = &processor.classifier {
        // The model classifies frames of the configuration it was trained on.
        source.configure(c.file().config).map_err(|e| {
            anyhow::anyhow!(
                "the model was trained on {} frames and the source cannot scan them: {e}",
                c.file().config.protocol.name()
            )
        })?;
    }
    processor.set_electrode_base(source.electrode_base());
    args.source.leave_out(&mut processor, source.config())?;
    if let Some(said) = processor.classifier_reads_said(processor.left_out()) {
        say!("warning: --skip-electrodes: {said}");
    }
    if let Source::Replay(r) = &mut source {
        r.looping = false;
        say_replay(r);
        // The reconstruction for the recording's scans, made before its first frame.
        processor.prepare(&r.recording.header.config)?;
    }
    if !args.json {
        say!("note: et stream prints JSON lines (--json); streaming them anyway");
    }
    let reference = match args.source.reference {
        1 => "the first frame is the untouched reference; each frame's noise is estimated from \
              the frame itself"
            .to_string(),
        n => format!("the first {n} frames are the untouched reference"),
    };
    say!(
        "streaming touch events from the {} ({reference})",
        source.describe()
    );
    let limit = args.frames.unwrap_or(u64::MAX);
    let (mut seen, mut imaged) = (0u64, 0u64);
    let needed = processor.settings().reference_frames.max(1);
    let started = std::time::Instant::now();
    let mut stdout = std::io::stdout().lock();
    // Faults and refusals a board reported since its last frame: past a few, it cannot scan
    // what was asked (it said so every second, without end).
    let (mut unscanned, mut reported) = (0, 0);
    // Electrodes said to stand out as detached (in V_0, or in a frame since).
    let mut contacts = et_host::live::Contacts::default();
    // The board's flags said (`FLAG_*` bits), and the frames flagged.
    let (mut said_flags, mut flagged) = (et_host::live::FlagsSaid::default(), 0u64);
    while seen < limit {
        let frames = source.poll(64, !args.fast)?;
        for change in source.link_changes() {
            say!("{}: {change}", source.describe());
        }
        if !frames.is_empty() {
            unscanned = 0;
        }
        for report in source.board_reports() {
            say!("{}: {report}", source.describe());
            unscanned += 1;
            reported += 1;
        }
        if unscanned >= FAULTS_WITHOUT_A_FRAME {
            let asked = match &processor.classifier {
                Some(c) => format!(
                    "the model's scan ({} electrodes, {}): a model trained on another sheet \
                     than the board's? Train on data of this board's sheet",
                    c.file().config.electrodes,
                    c.file().config.protocol.name()
                ),
                None => "the scan it was last given (see its reports above)".into(),
            };
            anyhow::bail!(
                "{}: {unscanned} faults or refusals reported and no frame since: the board cannot \
                 scan {asked}. It keeps that scan until it is reset (it starts on its own) or \
                 given one it can make (et upload --model, et stream --model with a model of \
                 its sheet)",
                source.describe()
            );
        }
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
            // A board whose front end refused the model's scan goes back to the one it made
            // before and reports the fault: its frames would stream unclassified.
            if let Some(c) = &processor.classifier
                && reported > 0
                && frame.config != c.file().config
            {
                anyhow::bail!(
                    "{}: the board reported a fault and scans {} electrodes, {}, not the \
                     model's scan ({} electrodes, {}), which its front end cannot make: a model \
                     trained on another sheet than the board's? Train on data of this board's \
                     sheet",
                    source.describe(),
                    frame.config.electrodes,
                    frame.config.protocol.name(),
                    c.file().config.electrodes,
                    c.file().config.protocol.name()
                );
            }
            seen += 1;
            let out = match processor.process(frame) {
                Ok(o) => o,
                Err(e) if e.is_reference() => {
                    anyhow::bail!("{}: {e}", source.describe())
                }
                Err(e) => {
                    say!("skipped: {e}");
                    continue;
                }
            };
            flagged += u64::from(say_flagged(&mut said_flags, &out));
            if out.referencing.is_none() {
                imaged += 1;
                // Once the reference is complete: what is wrong with it.
                if imaged == 1 {
                    contacts.reference(&say_of_the_reference(&processor));
                }
            }
            // An electrode that came off since V_0, or came back, or off again.
            if let Some(contact) = contacts.watch(&out, &processor) {
                say_contact(&contact, &processor, out.frame.seq);
            }
            if let Some(event) = out.event {
                let line = serde_json::to_string(&event)?;
                match writeln!(stdout, "{line}").and_then(|()| stdout.flush()) {
                    Ok(()) => {}
                    // The reader went away (a closed pipe): stop quietly.
                    Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => return Ok(()),
                    Err(e) => anyhow::bail!("writing to stdout: {e}"),
                }
            }
        }
    }
    // A replay's pace: every frame through the whole pipeline on one core (reading the
    // recording and setting up the reconstruction not counted); none when none was imaged
    // (the reference's frames alone are not that pipeline).
    let elapsed = started.elapsed().as_secs_f64();
    if matches!(source, Source::Replay(_)) && imaged > 0 {
        say!(
            "{seen} frames ({imaged} imaged{}) in {elapsed:.3} s: {:.0} frames/s on one core \
             (each referenced, imaged, searched for touches and its event written; the \
             recording was read before the clock started)",
            match flagged {
                0 => String::new(),
                n => format!(", {n} flagged by the board"),
            },
            seen as f64 / elapsed
        );
    }
    // A replay that ended before any frame was imaged gave no events: say why, not nothing.
    if imaged == 0 && matches!(source, Source::Replay(_)) {
        return Err(nothing_imaged(&source.describe(), seen, limit, needed));
    }
    Ok(())
}

/// What `et stream` says of a recording or file it replays before its first frame: the
/// recording's notes, another system's frames' missing clock (every event said t_us 0), and
/// a sheet other than the one it was made on.
fn say_replay(r: &et_host::live::ReplaySource) {
    for note in r.recording.notes() {
        say!("note: {}: {note}", r.name);
    }
    if let Some(file) = r.recording.header.source.strip_prefix("file:") {
        say!(
            "note: {file}: no board clock in the file: every event's t_us is 0, and its seq is \
             the frame's number in the file, from 0"
        );
    }
    if let Some(other) = r.recording.made_on_another_sheet(&r.sheet.physical) {
        say!("warning: {}: {other}", r.name);
    }
}

/// Says what the board flagged in `out`'s frame (readings on an ADC rail, the current source
/// in compliance) the first time it flags each. Returns whether the frame was flagged.
fn say_flagged(said: &mut et_host::live::FlagsSaid, out: &et_host::live::Output) -> bool {
    if let Some(words) = said.first(out.frame.flags) {
        say!(
            "warning: frame {}{}: {words}: such frames' values may not be the sheet's, and \
             their images place touches wrongly (said once; a replay counts them at its end)",
            out.frame.seq,
            if out.referencing.is_some() {
                " (of V_0)"
            } else {
                ""
            }
        );
    }
    et_host::live::readings_flagged(out.frame.flags)
}

/// What is wrong with the reference just taken, said: frames of another protocol, numbering
/// or sheet than the scene's (which would stream touches in the wrong places without a word),
/// a detached electrode, frames not in volts, a reference taken while touched. Returns the
/// electrodes said to be detached.
fn say_of_the_reference(processor: &et_host::live::Processor) -> Vec<u16> {
    use et_recon::background::{not_volts_said, poor_fit_said, reference_changes_said};
    if let Some(said) = processor.v0_unexplained().and_then(poor_fit_said) {
        say!("warning: {said}");
    }
    let detached = processor.v0_electrode_said().map(|(said, electrodes)| {
        say!(
            "warning: {said}; --skip-electrodes {} leaves {} values out",
            skip_with(processor, &electrodes),
            if electrodes.len() + processor.left_out().len() == 1 {
                "its"
            } else {
                "their"
            }
        );
        if let Some(said) = processor.classifier_reads_said(&electrodes) {
            say!("warning: {said}");
        }
        electrodes
    });
    if let Some(said) = (processor.v0()).and_then(|v0| not_volts_said(&v0)) {
        say!("note: {said}");
    }
    let fewer = |n| format!("--reference {n}");
    if let Some(said) =
        (processor.reference_changes()).and_then(|c| reference_changes_said(c, Some(fewer)))
    {
        say!("warning: {said}");
    }
    detached.unwrap_or_default()
}

/// Says what changed of an electrode's contact at frame `seq` ([`et_host::live::Contacts`]):
/// come off since V_0 was taken (with what the classifier reads of it), back, or off again.
fn say_contact(contact: &et_host::live::Contact, processor: &et_host::live::Processor, seq: u32) {
    use et_host::live::Contact;
    let electrode = contact.electrode();
    let leave = format!(
        "--skip-electrodes {} leaves its values out",
        skip_with(processor, &[electrode])
    );
    let said = match contact {
        Contact::Off {
            misfit, times: 1, ..
        } => misfit.said(processor.electrode_base()).map(|said| {
            format!(
                "{said} Not in V_0: a clip or wire come off while streaming, or a contact that \
                 opens now and then? Its values place touches wrongly: {leave}"
            )
        }),
        other => other.said(
            processor.electrode_base(),
            "start et stream again with the sheet untouched",
            &leave,
        ),
    };
    let Some(said) = said else { return };
    match contact {
        Contact::Back { in_v0: false, .. } => say!("note: frame {seq}: {said}"),
        _ => say!("warning: frame {seq}: {said}"),
    }
    if matches!(contact, Contact::Off { times: 1, .. })
        && let Some(said) = processor.classifier_reads_said(&[electrode])
    {
        say!("warning: {said}");
    }
}

/// `--skip-electrodes`' value for the electrodes `processor` leaves out and `more` (0-based),
/// as the source's user counts them: "3,7".
fn skip_with(processor: &et_host::live::Processor, more: &[u16]) -> String {
    let mut skip = [processor.left_out(), more].concat();
    skip.sort_unstable();
    skip.dedup();
    let base = u32::from(processor.electrode_base());
    let skip: Vec<String> = (skip.iter())
        .map(|&e| (u32::from(e) + base).to_string())
        .collect();
    skip.join(",")
}

/// Why a replay (`source`) imaged no frame: it ended, or `--frames` (`limit`) stopped it,
/// after `seen` frames, before the untouched reference's `needed`.
fn nothing_imaged(source: &str, seen: u64, limit: u64, needed: usize) -> anyhow::Error {
    let stopped = if seen >= limit {
        format!("--frames {limit} stopped it")
    } else {
        format!(
            "it ended after {seen} frame{}",
            if seen == 1 { "" } else { "s" }
        )
    };
    let fewer = if seen >= 2 && seen < limit {
        format!(
            "; if fewer of its first frames are untouched, give their count (--reference 1 to \
             {})",
            seen - 1
        )
    } else {
        String::new()
    };
    if seen >= needed as u64 {
        // The reference complete, nothing after it (its frames were all it took).
        let what = if seen == needed as u64 {
            "every frame went into the untouched reference"
        } else {
            "no frame after the untouched reference was imaged"
        };
        return anyhow::anyhow!(
            "{source}: {stopped}, and {what} (--reference {needed}): no frame was imaged{fewer}"
        );
    }
    anyhow::anyhow!(
        "{source}: {stopped} before the untouched reference ({needed} frames) was complete: no \
         frame was imaged{fewer}"
    )
}
