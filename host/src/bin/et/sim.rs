//! `et sim`: the simulated sheet, from a scene file into a recording, or into another
//! system's frames (CSV, .npy, .npz, .mat) under the scene's protocol, whatever it is.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use et_host::recording::{self, Header, Record, TouchRecord};
use et_sim::scene::{Detail, Run, Scene};
use indicatif::ProgressStyle;

#[derive(Debug, clap::Args)]
pub(crate) struct SimArgs {
    /// The scene file (TOML).
    #[arg(long)]
    scene: PathBuf,
    /// How many frames to simulate.
    #[arg(long, default_value_t = 100, value_parser = crate::domain::whole(1, u32::MAX))]
    frames: u32,
    /// Where to write: a recording (.jsonl) of et's simulated board, or another system's
    /// frames in volts (.csv one per row, .npy, or .npz and .mat as array "frames"): the empty
    /// sheet first, then the scene's touches all pressed (their times ignored), under the
    /// scene's protocol whatever it is (a protocol file, any current), measured by
    /// --instrument. The way to try `et reconstruct --frames` with no system of your own.
    #[arg(long)]
    out: PathBuf,
    /// With a .csv/.npy/.npz/.mat --out: the instrument's noise and drift: ideal (none),
    /// laboratory (0.05 % of the rms white and 0.05 % proportional, 0.01 % gain drift a
    /// frame) or noisy (0.2 % and 0.2 %).
    /// (Default laboratory; a recording's board has its own noise: refused with .jsonl.)
    #[arg(long, value_enum)]
    instrument: Option<Instrument>,
    /// With a .jsonl --out: simulate every ADC sample through the real scan engine (slower)
    /// instead of whole frames (refused for another system's files, made whole).
    #[arg(long)]
    samples: bool,
    /// Override the scene's seed.
    #[arg(long, value_parser = crate::domain::whole(0, u64::MAX))]
    seed: Option<u64>,
}

/// `et sim --instrument`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Instrument {
    /// No noise, no drift.
    Ideal,
    /// A good laboratory system.
    Laboratory,
    /// Four times the laboratory's noise.
    Noisy,
}

pub(crate) fn run(args: &SimArgs, force: bool) -> Result<()> {
    let mut scene = Scene::load(&args.scene)?;
    let named = scene.files();
    let mut inputs = vec![args.scene.as_path()];
    inputs.extend(named.iter().map(PathBuf::as_path));
    crate::output::check(&args.out, &inputs, force)?;
    if let Some(seed) = args.seed {
        scene.seed = seed;
    }
    crate::output::check_format(
        &args.out,
        "a recording, or another system's frames,",
        &["jsonl", "csv", "npy", "npz", "mat"],
    )?;
    if et_host::frames::is_table(&args.out) {
        if args.samples {
            anyhow::bail!(
                "--samples simulates the board's ADC for a recording (.jsonl); {} is another \
                 system's frames, made whole: drop --samples, or write a .jsonl",
                args.out.display()
            );
        }
        return foreign_frames(args, &scene);
    }
    if let Some(i) = args.instrument {
        anyhow::bail!(
            "--instrument {} sets another system's noise for a .csv, .npy, .npz or .mat --out; a \
             recording (.jsonl) has the simulated board's own noise (the scene's [frontend]): \
             drop --instrument, or write .csv, .npy, .npz or .mat",
            format!("{i:?}").to_lowercase()
        );
    }
    let started = Instant::now();
    let mut run = Run::new(&scene)?;
    let setup = started.elapsed();
    let header = Header::new(format!("sim:{}", args.scene.display()), run.config())?;
    if let Some(said) = scene.file_said() {
        say!("note: the simulated board scans {}{said}", header.protocol);
    }
    let detail = if args.samples {
        Detail::Samples
    } else {
        Detail::Frames
    };
    let mut pace = et_host::pace::Pace::new("simulate", "frames", u64::from(args.frames));
    let bar = pace.bar(
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
            pace.at(bar.position(), &bar);
        }
        anyhow::Ok(())
    })?;
    bar.finish_and_clear();
    let elapsed = started.elapsed().as_secs_f64();
    say!(
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
    // A scene's faults (open or loose contacts) do both, as real ones do.
    let cause = |fix: &str| {
        if scene.faults.is_empty() {
            fix.to_string()
        } else {
            format!("the scene's [[fault]] contacts do that, as real ones do (else {fix})")
        }
    };
    if rail > 0 {
        say!(
            "warning: {rail} frames have readings on an ADC rail (flagged in the recording): {}",
            cause("lower the scene's gain or current")
        );
    }
    if compliance > 0 {
        say!(
            "warning: in {compliance} frames the current source was in compliance (flagged in \
             the recording): the drive load is above V_out_max / (2 I), from contacts too \
             resistive or open, so those readings are too small; {}",
            cause("lower the current or fix the contacts")
        );
    }
    Ok(())
}

/// The most values (frames x K) `et sim` writes as a MATLAB file, which is made whole in
/// memory: 50 million, about 1.2 GB held.
const MAX_MAT_VALUES: usize = 50_000_000;

/// The most values `et sim` writes as a .csv or .npy file, frame by frame (nothing held): a
/// thousand million, 8 GB as .npy, about 13 GB as text.
const MAX_STREAMED_VALUES: usize = 1_000_000_000;

/// Another system's frames of `scene` (see `--out`), written as the extension of `--out` says:
/// .csv and .npy frame by frame as they are measured, .npz and .mat whole.
fn foreign_frames(args: &SimArgs, scene: &Scene) -> Result<()> {
    use et_sim::foreign::Instrument as I;
    use std::io::Write as _;
    let started = Instant::now();
    let schedule = scene.schedule()?;
    // The sheet as the scene makes it (electrodes moved, shorts); the board's own faults and
    // the temperature's drift are simulated in recordings only: said, not dropped silently.
    let board_only: Vec<String> = (scene.faults.iter())
        .filter(|f| f.kind != et_sim::scene::FaultKind::Shorted)
        .map(|f| format!("electrode {} {:?}", f.electrode, f.kind).to_lowercase())
        .chain(scene.drift.map(|_| "[drift]".to_string()))
        .collect();
    if !board_only.is_empty() {
        say!(
            "note: {} of the scene: simulated in et's board recordings (.jsonl) only; another \
             system's frames are of the sheet and the instrument alone",
            board_only.join(", ")
        );
    }
    let sheet = et_sim::still::simulated_sheet(scene)?;
    let lab = I::laboratory(scene.seed);
    let chosen = args.instrument.unwrap_or(Instrument::Laboratory);
    let instrument = match chosen {
        Instrument::Ideal => I::ideal(),
        Instrument::Laboratory => lab,
        Instrument::Noisy => I {
            noise: 4.0 * lab.noise,
            proportional: 4.0 * lab.proportional,
            ..lab
        },
    };
    let touched: Vec<et_sim::touch::Inclusion> = scene
        .touches
        .iter()
        .map(|t| et_sim::touch::Inclusion::of_touch(&t.touch(), &scene.sheet.piezo))
        .collect();
    // As many as asked: one frame is the empty sheet's alone (1 wrote 2).
    let n = usize::try_from(args.frames)?;
    let k = schedule.frame_len();
    let ext = args
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    // Bounded, and said before any work: a .mat or .npz is made whole in memory (its values,
    // their matrix and the file: three copies), the others on disk.
    let (limit, copies, held, instead) = match ext.as_str() {
        "mat" | "npz" => (
            MAX_MAT_VALUES,
            3.0,
            "in memory before it is written",
            "a .npy or .csv (written frame by frame)",
        ),
        "csv" | "npy" => (
            MAX_STREAMED_VALUES,
            1.0,
            "on disk",
            "an et recording (.jsonl, also written frame by frame)",
        ),
        other => anyhow::bail!(
            "{}: another system's frames are written as .csv, .npy, .npz or .mat, not .{other}",
            args.out.display()
        ),
    };
    if n.saturating_mul(k) > limit {
        anyhow::bail!(
            "{}: {n} frames of {k} values is {:.1} GB {held}; a .{ext} holds at most {} million \
             values here: fewer --frames (at most {}), or {instead}",
            args.out.display(),
            (n as f64) * (k as f64) * 8.0 * copies / 1e9,
            limit / 1_000_000,
            limit / k.max(1)
        );
    }
    let pace = std::cell::RefCell::new(et_host::pace::Pace::new("simulate", "frames", n as u64));
    let bar = pace.borrow().bar(
        ProgressStyle::with_template("simulating [{bar:30}] {pos}/{len} frames (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // The touched scene once, measured n - 1 times (solved once).
    let each = |mut frame: Box<dyn FnMut(Vec<f64>) -> Result<()> + '_>| {
        let scenes = std::iter::repeat_n(touched.as_slice(), n - 1);
        et_sim::foreign::each_frame_between(&sheet, &sheet, &schedule, scenes, &instrument, |f| {
            frame(f)?;
            bar.inc(1);
            pace.borrow_mut().at(bar.position(), &bar);
            anyhow::Ok(())
        })
    };
    crate::output::write(&args.out, |partial| -> Result<()> {
        if ext == "mat" || ext == "npz" {
            let mut values = Vec::with_capacity(n * k);
            each(Box::new(|f| {
                values.extend(f);
                Ok(())
            }))?;
            let m = nalgebra::DMatrix::from_row_slice(n, k, &values);
            drop(values);
            // One variable (MATLAB) or array (NumPy) named "frames", n x K.
            let bytes = if ext == "mat" {
                et_host::frames::mat_v5("frames", &m)
            } else {
                let mut archive = et_learn::npz::Writer::new();
                archive.matrix("frames", &m);
                archive.finish()?
            };
            std::fs::write(partial, bytes)?;
            return Ok(());
        }
        let mut file = std::io::BufWriter::new(std::fs::File::create(partial)?);
        if ext == "npy" {
            file.write_all(&et_learn::npz::npy_header_f64(&[n, k]))?;
        } else {
            let names: Vec<String> = (0..k).map(|j| format!("v{j}")).collect();
            writeln!(file, "{}", names.join(","))?;
        }
        each(Box::new(|f| {
            if ext == "npy" {
                f.iter()
                    .try_for_each(|v| file.write_all(&v.to_le_bytes()))?;
            } else {
                let row: Vec<String> = f.iter().map(|v| format!("{v:e}")).collect();
                writeln!(file, "{}", row.join(","))?;
            }
            Ok(())
        }))?;
        file.flush()?;
        Ok(())
    })?;
    bar.finish_and_clear();
    let touches = scene.touches.len();
    say!(
        "wrote {n} frame{} of {k} values ({}; {}; instrument {:?}) to {} in {:.2} s",
        if n == 1 { "" } else { "s" },
        schedule.kind().map_or_else(
            || "the scene's protocol file".to_string(),
            |p| p.to_string()
        ),
        if n == 1 {
            "the empty sheet only".to_string()
        } else {
            format!(
                "the empty sheet first, then {touches} touch{} pressed",
                if touches == 1 { "" } else { "es" }
            )
        },
        chosen,
        args.out.display(),
        started.elapsed().as_secs_f64()
    );
    if n >= 2 && touches > 0 {
        // Its one untouched frame is the reference (`et reconstruct` averages 20 by default).
        say!(
            "image them against the first, untouched frame: et reconstruct --scene {} --frames \
             {} --reference 1 --all --out last.png",
            args.scene.display(),
            args.out.display()
        );
    }
    Ok(())
}
