//! `et collect`: the data-collection procedure on the simulated sheet, into an et dataset.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Result, bail};
use et_learn::{collect, dataset};
use et_sim::scene::Scene;
use indicatif::ProgressStyle;

use crate::learn::parse_grid;
use crate::output;

#[derive(Debug, clap::Args)]
pub(crate) struct CollectArgs {
    /// Scene file: the sheet, its electrodes and the front end (its touches are not used).
    #[arg(long)]
    scene: PathBuf,
    /// Class grid, ROWSxCOLS (docs/method.md §9: 7x7 with a 15 mm target, 10x10 with 10 mm).
    #[arg(long, default_value = "7x7")]
    grid: String,
    /// T: visits of the whole grid.
    #[arg(long, default_value_t = 6, value_parser = crate::domain::count(1, 1_000))]
    visits: usize,
    /// S_num: scans per class and visit.
    #[arg(long, default_value_t = 20, value_parser = crate::domain::count(1, 10_000))]
    scans: usize,
    /// S_sub: observations (sub-section medians) per scan.
    #[arg(long, default_value_t = 20, value_parser = crate::domain::count(1, 1_000))]
    subsections: usize,
    /// Lowest pressure while pressing, kPa.
    #[arg(long, default_value_t = 5.0, value_parser = crate::domain::real(0.0, 1_000.0))]
    min_kpa: f64,
    /// Highest pressure while pressing, kPa (0.1 to 1 000: a lighter touch barely changes
    /// the sheet).
    #[arg(long, default_value_t = 60.0, value_parser = crate::domain::real(0.1, 1_000.0))]
    max_kpa: f64,
    /// Finger contact radius (the median over presses), mm (0.5 to 100: a smaller contact
    /// is no finger's; and at least half the scene's grid spacing, sheet.resolution, which
    /// the simulated sheet resolves).
    #[arg(long, default_value_t = 7.5, value_parser = crate::domain::real(0.5, 100.0))]
    radius_mm: f64,
    /// Radius of the target the finger's centre lands in (uniformly) around each class
    /// centre, mm (default: the finger's radius; the method's 10 mm targets for 100 classes
    /// are 5).
    #[arg(long, value_parser = crate::domain::above(0.0, 1_000.0))]
    target_mm: Option<f64>,
    /// Relative rms of the contact radius from press to press (0.15: 15 %).
    #[arg(long, default_value_t = collect::Plan::default().radius_spread, value_parser = crate::domain::real(0.0, 1.0))]
    radius_spread: f64,
    /// Fraction of a press's pressure the fabric still holds at the next press (0 to 1).
    #[arg(long, default_value_t = collect::Plan::default().creep, value_parser = crate::domain::real(0.0, 1.0))]
    creep: f64,
    /// How far the front end drifts during a visit, as a fraction of the spread between
    /// measurement sets (0 to 1).
    #[arg(long, default_value_t = collect::Plan::default().drift, value_parser = crate::domain::real(0.0, 1.0))]
    drift: f64,
    /// Rms electrode movement between visits (clips put back), mm.
    #[arg(long, default_value_t = collect::Plan::default().electrode_movement * 1e3, value_parser = crate::domain::real(0.0, 50.0))]
    movement_mm: f64,
    /// Electrode poses within a visit: each press finds the electrodes in one of them (1 =
    /// they stay put while the grid is visited).
    #[arg(long, default_value_t = 1, value_parser = crate::domain::count(1, 1_000))]
    poses: usize,
    /// Rms movement of each pose around the visit's electrode positions, mm.
    #[arg(long, default_value_t = 0.0, value_parser = crate::domain::real(0.0, 50.0))]
    press_movement_mm: f64,
    /// Rms change of each clip's junction potential at every press (pressing tugs on the
    /// clips), uV.
    #[arg(long, default_value_t = collect::Plan::default().press_junction * 1e6, value_parser = crate::domain::real(0.0, 10_000.0))]
    press_junction_uv: f64,
    /// Relative rms of the hand's force about each press's pressure while a scan runs.
    #[arg(long, default_value_t = collect::Plan::default().wobble, value_parser = crate::domain::real(0.0, 1.0))]
    wobble: f64,
    /// Largest elongation of the finger's contact (long over short axis; each press draws one
    /// between 1 and this): 1 presses discs, about 1.5 a finger pressed at a slant, its long
    /// axis along +y (the hand coming from the bottom edge), 20 degrees rms.
    #[arg(long, default_value_t = collect::Plan::default().elongation, value_parser = crate::domain::real(1.0, 10.0))]
    elongation: f64,
    /// Seed of the session.
    #[arg(long, default_value_t = 1, value_parser = crate::domain::whole(0, u64::MAX))]
    seed: u64,
    /// Where to write the dataset: NAME.csv (text, with its provenance in `#` lines) or
    /// NAME.npz (the same content as NumPy arrays: `numpy.load`, and et reads it at disk
    /// speed, about 100x faster than the CSV).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

impl CollectArgs {
    /// The collection plan these arguments ask for (one visit; the command runs --visits of
    /// them), each range checked.
    fn plan(&self) -> Result<collect::Plan> {
        let args = self;
        if !(args.min_kpa >= 0.0 && args.max_kpa >= args.min_kpa) {
            bail!("--min-kpa and --max-kpa: need 0 <= min <= max");
        }
        if !(args.radius_spread.is_finite() && (0.0..=1.0).contains(&args.radius_spread)) {
            bail!("--radius-spread: a relative spread between 0 and 1");
        }
        if !(0.0..=1.0).contains(&args.creep) || !(0.0..=1.0).contains(&args.drift) {
            bail!("--creep and --drift: fractions between 0 and 1");
        }
        if !(args.movement_mm.is_finite() && args.movement_mm >= 0.0) {
            bail!("--movement-mm: at least 0");
        }
        let target_mm = args.target_mm.unwrap_or(args.radius_mm);
        if !(target_mm.is_finite() && target_mm >= 0.0) {
            bail!("--target-mm: at least 0");
        }
        if !(args.press_junction_uv.is_finite() && args.press_junction_uv >= 0.0) {
            bail!("--press-junction-uv: at least 0");
        }
        if !(args.wobble.is_finite() && (0.0..=1.0).contains(&args.wobble)) {
            bail!("--wobble: a relative rms between 0 and 1");
        }
        if !(1.0..=et_sim::touch::MAX_ELONGATION).contains(&args.elongation) {
            bail!(
                "--elongation: between 1 (a disc) and {}",
                et_sim::touch::MAX_ELONGATION
            );
        }
        if args.visits == 0 || args.scans == 0 || args.subsections == 0 {
            bail!("--visits, --scans and --subsections must be at least 1");
        }
        Ok(collect::Plan {
            visits: 1,
            scans: args.scans,
            subsections: args.subsections,
            pressure_pa: (args.min_kpa * 1e3, args.max_kpa * 1e3),
            radius: args.radius_mm * 1e-3,
            radius_spread: args.radius_spread,
            target_radius: target_mm * 1e-3,
            creep: args.creep,
            drift: args.drift,
            electrode_movement: args.movement_mm * 1e-3,
            poses: args.poses.max(1),
            press_movement: args.press_movement_mm * 1e-3,
            press_junction: args.press_junction_uv * 1e-6,
            unevenness: collect::Plan::default().unevenness,
            wobble: args.wobble,
            wobble_s: collect::Plan::default().wobble_s,
            elongation: args.elongation,
            finger_angle: collect::Plan::default().finger_angle,
            seed: args.seed,
        })
    }
}

pub(crate) fn collect_cmd(args: &CollectArgs, force: bool) -> Result<()> {
    let scene = Scene::load(&args.scene)?;
    let named = scene.files();
    let mut inputs = vec![args.scene.as_path()];
    inputs.extend(named.iter().map(std::path::PathBuf::as_path));
    output::check(&args.out, &inputs, force)?;
    output::check_format(&args.out, "a dataset", &["csv", "npz"])?;
    let (rows, cols) = parse_grid(&args.grid, "--grid")?;
    let base = scene.board_config()?;
    let config = collect::training_config(base);
    // (The scene's protocol was replaced without a word.)
    if base.protocol != config.protocol {
        say!(
            "note: et collect scans the {} protocol, the method's training scan (docs/method.md \
             §9); the scene's {}{} is not used here",
            config.protocol.name(),
            base.protocol.name(),
            scene.file_said().unwrap_or_default()
        );
    }
    let centres = collect::grid(&scene.sheet, rows, cols, 0.0);
    let plan = args.plan()?;
    // The finger against the simulator's grid, as a scene's touches are.
    let spacing = scene.sheet.spacing();
    if plan.radius < spacing / 2.0 {
        bail!(
            "--radius-mm {}: under half the simulated sheet's grid spacing ({} mm), so the \
             presses' frames would depend on where each falls between the grid's nodes: set \
             sheet.resolution in the scene to at most {} m (twice the radius)",
            args.radius_mm,
            spacing * 1e3,
            2.0 * plan.radius
        );
    }
    plan.fits_in_memory(config, centres.len(), args.visits)?;
    say!(
        "collecting {} classes x {} visits x {} scans x {} sub-sections: {} observations",
        centres.len(),
        args.visits,
        args.scans,
        args.subsections,
        plan.observations(centres.len(), args.visits)
    );
    // Counted by press (classes x scans a visit), so the ETA shows within seconds of a long
    // collection, not after its first visit.
    let presses = centres.len() * args.scans;
    let pace = std::cell::RefCell::new(et_host::pace::Pace::new(
        "collect",
        "presses",
        (args.visits * presses) as u64,
    ));
    let bar = pace.borrow().bar(
        ProgressStyle::with_template("collecting [{bar:30}] {msg} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    let data = collect::collect_visits(
        &scene.sheet,
        scene.frontend,
        config,
        &centres,
        &plan,
        (0..args.visits).map(|v| args.seed.wrapping_mul(1_000).wrapping_add(v as u64)),
        |pressed, visits| {
            bar.set_message(format!(
                "{pressed} of {} presses, {visits} of {} visits done",
                bar.length().unwrap_or(0),
                args.visits
            ));
            bar.set_position(pressed as u64);
            pace.borrow_mut().at(pressed as u64, &bar);
        },
    )?;
    bar.finish_and_clear();
    let provenance = format!(
        "et collect: {}, grid {rows}x{cols}, T={} S_num={} S_sub={}, {}-{} kPa, radius {} mm, target {} mm, movement {} mm, press junction {} uV, wobble {}, elongation up to {}, seed {}",
        args.scene.display(),
        args.visits,
        args.scans,
        args.subsections,
        args.min_kpa,
        args.max_kpa,
        args.radius_mm,
        args.target_mm.unwrap_or(args.radius_mm),
        args.movement_mm,
        args.press_junction_uv,
        args.wobble,
        args.elongation,
        args.seed
    );
    output::write(&args.out, |partial| {
        dataset::save(&data, partial, &provenance)
    })?;
    let summary = CollectSummary {
        out: &args.out,
        observations: data.x.nrows(),
        features: data.x.ncols(),
        classes: centres.len(),
        seconds: started.elapsed().as_secs_f64(),
    };
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        say!(
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

/// `et collect --json`.
#[derive(serde::Serialize)]
struct CollectSummary<'a> {
    out: &'a std::path::Path,
    observations: usize,
    features: usize,
    classes: usize,
    seconds: f64,
}
