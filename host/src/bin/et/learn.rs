//! `et collect`, `et train`, `et eval`, `et export`: touch classification from raw voltages.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result, bail};
use et_core::model::{ModelKind, Precision};
use et_host::plot;
use et_learn::model_file::ModelFile;
use et_learn::tabular::{self, Choice, Method};
use et_learn::trainer::{BoardModel, Progress};
use et_learn::{Examples, TrainError, Trained, Trainer};
use et_learn::{analysis, collect, dataset, fastcv, pipeline};
use et_sim::scene::Scene;

use crate::output;
use indicatif::{ProgressBar, ProgressStyle};

#[derive(Debug, clap::Args)]
pub(crate) struct CollectArgs {
    /// Scene file: the sheet, its electrodes and the front end (its touches are not used).
    #[arg(long)]
    scene: PathBuf,
    /// Class grid, ROWSxCOLS (docs/method.md §9: 7x7 with a 15 mm target, 10x10 with 10 mm).
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
    /// Finger contact radius (the median over presses), mm.
    #[arg(long, default_value_t = 7.5)]
    radius_mm: f64,
    /// Radius of the target the finger's centre lands in (uniformly) around each class
    /// centre, mm (default: the finger's radius; the method's 10 mm targets for 100 classes
    /// are 5).
    #[arg(long)]
    target_mm: Option<f64>,
    /// Relative rms of the contact radius from press to press (0.15: 15 %).
    #[arg(long, default_value_t = collect::Plan::default().radius_spread)]
    radius_spread: f64,
    /// Fraction of a press's pressure the fabric still holds at the next press (0 to 1).
    #[arg(long, default_value_t = collect::Plan::default().creep)]
    creep: f64,
    /// How far the front end drifts during a visit, as a fraction of the spread between
    /// measurement sets (0 to 1).
    #[arg(long, default_value_t = collect::Plan::default().drift)]
    drift: f64,
    /// Rms electrode movement between visits (clips put back), mm.
    #[arg(long, default_value_t = collect::Plan::default().electrode_movement * 1e3)]
    movement_mm: f64,
    /// Electrode poses within a visit: each press finds the electrodes in one of them (1 =
    /// they stay put while the grid is visited).
    #[arg(long, default_value_t = 1)]
    poses: usize,
    /// Rms movement of each pose around the visit's electrode positions, mm.
    #[arg(long, default_value_t = 0.0)]
    press_movement_mm: f64,
    /// Rms change of each clip's junction potential at every press (pressing tugs on the
    /// clips), uV.
    #[arg(long, default_value_t = collect::Plan::default().press_junction * 1e6)]
    press_junction_uv: f64,
    /// Relative rms of the hand's force about each press's pressure while a scan runs.
    #[arg(long, default_value_t = collect::Plan::default().wobble)]
    wobble: f64,
    /// Largest elongation of the finger's contact (long over short axis; each press draws one
    /// between 1 and this): 1 presses discs, about 1.5 a finger pressed at a slant, its long
    /// axis along +y (the hand coming from the bottom edge), 20 degrees rms.
    #[arg(long, default_value_t = collect::Plan::default().elongation)]
    elongation: f64,
    /// Seed of the session.
    #[arg(long, default_value_t = 1)]
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

#[derive(Debug, clap::Args)]
pub(crate) struct TrainArgs {
    /// Training set: an et dataset from `et collect` (.csv, or .npz to load at disk speed).
    #[arg(
        long,
        required_unless_present = "features",
        conflicts_with = "features"
    )]
    data: Option<PathBuf>,
    #[command(flatten)]
    table: crate::tabular::TableArgs,
    /// The model. On --data: qda (a covariance per class) or lda (one pooled covariance);
    /// default qda. On --features: also ridge, kernel-ridge (RBF), knn, gp (a Gaussian
    /// process learning a length scale per feature), or auto (every
    /// method that fits the targets, the best by cross-validation); default auto.
    #[arg(long, value_enum)]
    kind: Option<KindArg>,
    /// Classes from positions (--features only): ROWSxCOLS cells over the targets' bounding
    /// box, cells without training rows dropped.
    #[arg(long, value_name = "ROWSxCOLS")]
    grid: Option<String>,
    /// Shrinkage in [0, 1], or "auto" (--data: chosen by leave-one-visit-out
    /// cross-validation when the set has several visits, else by stratified k-fold; the
    /// summary says which). With --features it is always chosen by cross-validation.
    #[arg(long)]
    shrinkage: Option<String>,
    /// Folds of the cross-validation: the reported one on --data (default 10), the one that
    /// chooses hyperparameters on --features (default 5).
    #[arg(long)]
    folds: Option<usize>,
    /// How --features rows are dealt to folds: shuffled (stratified by class), or blocks
    /// (contiguous, in file order: for recordings in time order, where a shuffled split
    /// flatters a model).
    #[arg(long, value_enum, default_value_t = CvArg::Shuffled)]
    cv: CvArg,
    /// Train on the frames as measured (docs/method.md §9 exactly) instead of each frame minus its
    /// session's untouched frame. Referenced is the default when the dataset has untouched
    /// frames: it cancels electrode movement between sessions, but on the board it needs an
    /// untouched frame taken when the sheet is put down.
    #[arg(long)]
    raw: bool,
    /// Also write a learning curve (PNG): held-out accuracy against observations per class
    /// n_c (leave-one-visit-out when the set has several visits, else the k-fold CV).
    #[arg(long, value_name = "PNG")]
    curve: Option<PathBuf>,
    /// Keep only this many features (--data), those that separate the classes best (Fisher
    /// ratio): QDA's size and cost grow with the square of the feature count.
    #[arg(long, value_name = "N")]
    keep: Option<usize>,
    /// Where to write the model (JSON).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
pub(crate) struct EvalArgs {
    /// Model (JSON from `et train`).
    #[arg(long)]
    model: PathBuf,
    /// Test set: an et dataset from `et collect` (.csv or .npz), for models trained with
    /// --data.
    #[arg(
        long,
        required_unless_present = "features",
        conflicts_with = "features"
    )]
    data: Option<PathBuf>,
    #[command(flatten)]
    table: crate::tabular::TableArgs,
    /// Write plots into this directory. --data: confusion.png (row-normalised confusion
    /// matrix) and error-vs-distance.png (position error against distance from the nearest
    /// electrode). --features: error-map.png (each true position coloured by its error) and
    /// predicted-vs-true.png.
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
    /// --features: also write every row's prediction to this CSV (`row`: the row's 0-based
    /// index in the file; `class` for classifiers; `x_mm`, `y_mm`; the third target where
    /// predicted), for Python's `csv` or `numpy.loadtxt(path, delimiter=",", skiprows=1)`
    /// and MATLAB's `readtable`.
    #[arg(long, value_name = "CSV", requires = "features")]
    predictions: Option<PathBuf>,
    /// Print JSON (with the confusion matrix and accuracy by distance from the electrodes).
    #[arg(long)]
    json: bool,
}

#[derive(Debug, clap::Args)]
pub(crate) struct ExportArgs {
    /// Model (JSON from `et train`).
    #[arg(long)]
    model: PathBuf,
    /// f32, or f16 (half the flash, about 3 significant digits).
    #[arg(long, value_enum, default_value_t = PrecisionArg::F32)]
    precision: PrecisionArg,
    /// Where to write the blob.
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

pub(crate) fn collect_cmd(args: &CollectArgs, force: bool) -> Result<()> {
    output::check(&args.out, &[&args.scene], force)?;
    let scene = Scene::load(&args.scene)?;
    let (rows, cols) = parse_grid(&args.grid, "--grid")?;
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
    let config = collect::training_config(scene.scan_config()?);
    let centres = collect::grid(&scene.sheet, rows, cols, 0.0);
    let plan = collect::Plan {
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
    };
    let bar = ProgressBar::new(args.visits as u64).with_style(
        ProgressStyle::with_template("collecting [{bar:30}] visit {pos}/{len} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let started = Instant::now();
    let mut data: Option<et_learn::dataset::Dataset> = None;
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
        )?;
        match data.as_mut() {
            None => data = Some(part),
            Some(d) => d.append(part)?,
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let data = data.context("no visit collected")?;
    let provenance = format!(
        "et collect: {}, grid {rows}x{cols}, T={} S_num={} S_sub={}, {}-{} kPa, radius {} mm, target {} mm, movement {} mm, press junction {} uV, wobble {}, elongation up to {}, seed {}",
        args.scene.display(),
        args.visits,
        args.scans,
        args.subsections,
        args.min_kpa,
        args.max_kpa,
        args.radius_mm,
        target_mm,
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

/// `--kind`: which model to train.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum KindArg {
    /// Quadratic discriminant analysis: a covariance per class.
    Qda,
    /// Linear discriminant analysis: one pooled covariance.
    Lda,
    /// Linear ridge regression of the position (--features).
    Ridge,
    /// Gaussian-kernel (RBF) ridge regression of the position (--features).
    KernelRidge,
    /// k nearest neighbours' mean position (--features).
    Knn,
    /// Gaussian process with a length scale per feature, learned by marginal likelihood
    /// (--features): slower (it shows how long), learns which channels matter.
    Gp,
    /// Every method that fits the targets, the best by cross-validation (--features).
    Auto,
}

/// `--cv`: how rows are dealt to folds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum CvArg {
    /// At random (stratified by class).
    Shuffled,
    /// Contiguous blocks in file order.
    Blocks,
}

/// `--precision`: how the blob stores its tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum PrecisionArg {
    /// 4 bytes per value.
    F32,
    /// 2 bytes per value (IEEE binary16).
    F16,
}

impl From<PrecisionArg> for Precision {
    fn from(p: PrecisionArg) -> Self {
        match p {
            PrecisionArg::F32 => Precision::F32,
            PrecisionArg::F16 => Precision::F16,
        }
    }
}

impl TrainArgs {
    /// The trainer these arguments ask for.
    fn trainer(&self) -> Result<Trainer> {
        let method = match self.kind {
            None | Some(KindArg::Auto) => Choice::Auto,
            Some(KindArg::Qda) => Choice::One(Method::Qda),
            Some(KindArg::Lda) => Choice::One(Method::Lda),
            Some(KindArg::Ridge) => Choice::One(Method::Ridge),
            Some(KindArg::KernelRidge) => Choice::One(Method::KernelRidge),
            Some(KindArg::Knn) => Choice::One(Method::Knn),
            Some(KindArg::Gp) => Choice::One(Method::Gp),
        };
        let shrinkage = match self.shrinkage.as_deref().unwrap_or("auto") {
            "auto" => None,
            v => Some(
                v.parse::<f64>()
                    .with_context(|| format!("--shrinkage '{v}': a number in [0, 1] or auto"))?,
            ),
        };
        Ok(Trainer {
            method,
            shrinkage,
            folds: self.folds,
            scheme: match self.cv {
                CvArg::Shuffled => tabular::CvScheme::Shuffled,
                CvArg::Blocks => tabular::CvScheme::Blocks,
            },
            grid: self
                .grid
                .as_deref()
                .map(|g| parse_grid(g, "--grid"))
                .transpose()?,
            raw: self.raw,
            keep: self.keep,
            seed: 1,
        })
    }
}

pub(crate) fn train_cmd(args: &TrainArgs, force: bool) -> Result<()> {
    let Some(data_arg) = &args.data else {
        if args.curve.is_some() || args.keep.is_some() || args.raw {
            bail!("--curve, --keep and --raw apply to et datasets (--data)");
        }
        if args.shrinkage.as_deref().is_some_and(|s| s != "auto") {
            bail!("--shrinkage: with --features it is chosen by cross-validation; leave it out");
        }
        return crate::tabular::train(&args.table, &args.trainer()?, &args.out, args.json, force);
    };
    let trainer = args.trainer()?;
    trainer.board_kind().map_err(|_| {
        anyhow::anyhow!(
            "--kind {}: et datasets (--data) train qda or lda for the board; regressors take \
             any sensor's table (--features)",
            format!("{:?}", args.kind.unwrap_or(KindArg::Qda)).to_lowercase()
        )
    })?;
    if args.grid.is_some() || args.cv != CvArg::Shuffled {
        bail!("--grid and --cv apply to any sensor's table (--features)");
    }
    output::check(&args.out, &[data_arg], force)?;
    if let Some(png) = &args.curve {
        output::check(png, &[data_arg, &args.out], force)?;
    }
    let folds = args.folds.unwrap_or(10);
    // Each stage on one line that updates in place, with the time so far (stderr, and only
    // on a terminal: scripts and --json see nothing of it). Cleared on every way out.
    let spinner = ProgressBar::new_spinner().with_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})")
            .unwrap_or_else(|_| ProgressStyle::default_spinner()),
    );
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    let cleared = |e: anyhow::Error| {
        spinner.finish_and_clear();
        e
    };
    spinner.set_message(format!("reading {}", data_arg.display()));
    let data = dataset::load(data_arg).map_err(|e| cleared(e.into()))?;
    let classes = data.centres.len();
    let trained = trainer.train(Examples::Dataset(Box::new(data)), |stage| match stage {
        Progress::RawFrames => spinner.suspend(|| {
            eprintln!(
                "note: {} has no untouched frames, training on raw frames",
                data_arg.display()
            );
        }),
        Progress::Preparing { rows, features } => {
            spinner.set_message(format!(
                "preparing {rows} observations x {features} features"
            ));
        }
        Progress::Dataset(stage) => spinner.set_message(training_stage(stage, folds)),
        Progress::Table(..) => {}
    });
    spinner.finish_and_clear();
    let board = match trained.map_err(|e| match e {
        TrainError::Data(e) => anyhow::anyhow!("{}: {e}", data_arg.display()),
        other => other.into(),
    })? {
        Trained::Board(board) => board,
        Trained::Table(_) => bail!("an et dataset trains a board model"),
    };
    let BoardModel {
        file,
        training: trained,
        data,
    } = *board;
    let referenced = file.referenced;
    let (opts, cv_conf, lovo) = (trained.options, &trained.cv, trained.leave_one_visit_out);
    let (shrinkage, scores) = (opts.shrinkage, &trained.shrinkage_scores);
    // What was fitted: qda shrunk fully toward the pooled covariance is saved as the lda.
    let kind = opts.kind;
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
            output::write(png, |partial| {
                plot::chart(
                    partial,
                    plot::Labels {
                        title: &format!(
                            "learning curve: {} ({}), {} classes",
                            kind.name(),
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
                )
            })?;
            Some(points)
        }
        None => None,
    };
    let mm = &file.centres_mm;
    // What every reader of model files checks (et eval, stream, view, export): refuse to
    // write a model they would refuse.
    file.validate().with_context(|| {
        format!(
            "the trained model is not usable (shrinkage {shrinkage}); train with a larger \
             --shrinkage (e.g. 0.1) or more observations per class"
        )
    })?;
    output::write(&args.out, |partial| file.save(partial))?;
    let summary = TrainSummary {
        out: &args.out,
        kind,
        referenced,
        shrinkage,
        shrinkage_chosen_by: trained.chosen_by,
        shrinkage_scores: scores
            .iter()
            .map(|&(shrinkage, accuracy)| ShrinkageScore {
                shrinkage,
                accuracy,
            })
            .collect(),
        classes,
        observations: data.x.nrows(),
        features: data.x.ncols(),
        cv_folds: folds.max(2),
        cv_accuracy: cv_conf.accuracy(),
        cv_mean_error_mm: cv_conf.mean_position_error(mm),
        cv_aee_mm: cv_conf.aee(mm),
        leave_one_visit_out_accuracy: lovo,
        fallbacks: &trained.fallbacks,
        learning_curve: curve.as_deref(),
    };
    for f in &trained.fallbacks {
        eprintln!("note: {f}");
    }
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        eprintln!(
            "trained {}{} on {} observations ({} classes, {} features), shrinkage {} ({}): {}-fold CV accuracy {:.1} %, mean error {:.2} mm{}; wrote {}",
            kind.name(),
            if referenced {
                " (referenced)"
            } else {
                " (raw frames)"
            },
            data.x.nrows(),
            classes,
            data.x.ncols(),
            shrinkage,
            trained.chosen_by,
            folds.max(2),
            100.0 * cv_conf.accuracy(),
            cv_conf.mean_position_error(mm),
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
                 train with --keep {fit} (the most that fit for {classes} classes) or fewer classes"
            );
        }
    }
    Ok(())
}

/// The spinner's line for a stage of training on an et dataset.
fn training_stage(stage: pipeline::Stage, folds: usize) -> String {
    match stage {
        pipeline::Stage::Statistics => "each fold's statistics".to_string(),
        pipeline::Stage::Candidate {
            index,
            of,
            shrinkage,
            by_visit,
        } => format!(
            "choosing the shrinkage: {shrinkage} ({} of {of}), {}",
            index + 1,
            if by_visit {
                "leave-one-visit-out".to_string()
            } else {
                format!("{folds}-fold")
            }
        ),
        pipeline::Stage::Final => format!(
            "fitting the model beside its {folds}-fold and leave-one-visit-out cross-validations"
        ),
    }
}

pub(crate) fn eval_cmd(args: &EvalArgs, force: bool) -> Result<()> {
    let text = std::fs::read_to_string(&args.model)
        .with_context(|| format!("reading {}", args.model.display()))?;
    let table_model = tabular::is_table_model(&text);
    let Some(data_arg) = &args.data else {
        if !table_model {
            bail!(
                "{}: a board model (trained on an et dataset): evaluate it with --data",
                args.model.display()
            );
        }
        return crate::tabular::eval(
            &args.model,
            &args.table,
            args.plots.as_deref(),
            args.predictions.as_deref(),
            args.json,
            force,
        );
    };
    if table_model {
        bail!(
            "{}: trained on a sensor's table: evaluate it with --features (and --targets)",
            args.model.display()
        );
    }
    let plots = args
        .plots
        .as_ref()
        .map(|dir| (dir.join("confusion.png"), dir.join("error-vs-distance.png")));
    if let Some((a, b)) = &plots {
        for png in [a, b] {
            output::check(png, &[&args.model, data_arg], force)?;
        }
    }
    let file = ModelFile::load(&args.model)?;
    let data = dataset::load(data_arg)?;
    let classes = file.classes.len();
    let tested = pipeline::test(&file, &data).map_err(|e| {
        // Name the file at fault: the model's tables, or the data.
        let blamed = match e {
            pipeline::UseError::Model(_) => &args.model,
            _ => data_arg,
        };
        anyhow::anyhow!("{}: {e}", blamed.display())
    })?;
    let (conf, bands) = (&tested.confusion, &tested.bands);
    if let (Some(dir), Some((confusion_png, error_png))) = (&args.plots, &plots) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        let title = format!(
            "confusion: accuracy {:.1} % on {}",
            100.0 * conf.accuracy(),
            data_arg.display()
        );
        output::write(confusion_png, |partial| {
            plot::confusion(partial, conf, &title)
        })?;
        if tested.outcomes.is_empty() {
            eprintln!(
                "note: {} does not say where the electrodes are: no error-vs-distance plot",
                data_arg.display()
            );
        } else {
            output::write(error_png, |partial| {
                plot::error_vs_distance(partial, &tested)
            })?;
        }
    }
    let mut from_truth = tested.errors_from_truth_mm.clone();
    from_truth.sort_by(f64::total_cmp);
    let [mean, median, p90] = et_learn::regress::mean_median_p90(&from_truth);
    let known = !from_truth.is_empty();
    let summary = EvalSummary {
        observations: conf.total(),
        accuracy: conf.accuracy(),
        mean_error_mm: known.then_some(mean),
        median_error_mm: known.then_some(median),
        p90_error_mm: known.then_some(p90),
        mean_cell_error_mm: conf.mean_position_error(&file.centres_mm),
        aee_mm: conf.aee(&file.centres_mm),
        by_distance_from_electrodes: bands,
        confusion: conf.counts.chunks(classes).collect(),
    };
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        out!(
            "{} observations: accuracy {:.1} %, {}mean cell error {:.2} mm (predicted class \
             centre to true class centre), AEE {:.1} mm",
            conf.total(),
            100.0 * conf.accuracy(),
            if known {
                format!(
                    "position error from the true press positions {mean:.2} mm mean, \
                     {median:.2} median, {p90:.2} 90th percentile; "
                )
            } else {
                String::new()
            },
            conf.mean_position_error(&file.centres_mm),
            conf.aee(&file.centres_mm)
        );
    }
    Ok(())
}

pub(crate) fn export_cmd(args: &ExportArgs, force: bool) -> Result<()> {
    output::check(&args.out, &[&args.model], force)?;
    let file = ModelFile::load(&args.model)?;
    let precision = Precision::from(args.precision);
    let blob = file.blob(precision)?;
    output::write(&args.out, |partial| {
        std::fs::write(partial, &blob).with_context(|| format!("writing {}", args.out.display()))
    })?;
    let (c, p) = (file.classes.len(), file.feature_index.len());
    // Multiply-adds per frame on the chip: QDA a forward substitution per class, LDA a dot.
    let macs = if file.kind == ModelKind::Qda {
        c * (p * (p + 1) / 2 + p)
    } else {
        c * p
    };
    // One model slot of the board's flash (firmware/src/store.rs).
    const SLOT: usize = et_core::board::MODEL_SLOT_BYTES;
    let summary = ExportSummary {
        out: &args.out,
        bytes: blob.len(),
        fits_model_slot: blob.len() <= SLOT,
        multiply_adds_per_frame: macs,
    };
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        eprintln!(
            "wrote {} ({} bytes, {:.0} % of the board's 384 KiB model slot{}); {} multiply-adds per frame",
            args.out.display(),
            blob.len(),
            100.0 * blob.len() as f64 / SLOT as f64,
            if blob.len() <= SLOT {
                String::new()
            } else {
                let kind = file.kind;
                if precision == Precision::F32
                    && et_core::model::model_len(kind, Precision::F16, c, p) <= SLOT
                {
                    ": does NOT fit; --precision f16 does".to_string()
                } else {
                    format!(
                        ": does NOT fit; retrain with et train --keep {} (the most that fit in f16) or fewer classes",
                        pipeline::features_that_fit(kind, c, p)
                    )
                }
            },
            macs
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

/// `et train --json`.
#[derive(serde::Serialize)]
struct TrainSummary<'a> {
    out: &'a std::path::Path,
    kind: ModelKind,
    referenced: bool,
    shrinkage: f64,
    /// "given", "leave-one-visit-out" or {"k-fold": k}.
    shrinkage_chosen_by: pipeline::ChosenBy,
    /// Cross-validated accuracy of each shrinkage tried (empty when it was given).
    shrinkage_scores: Vec<ShrinkageScore>,
    classes: usize,
    observations: usize,
    features: usize,
    cv_folds: usize,
    cv_accuracy: f64,
    cv_mean_error_mm: f64,
    cv_aee_mm: f64,
    leave_one_visit_out_accuracy: Option<f64>,
    /// Where training changed its recipe because the data are too few (empty normally).
    fallbacks: &'a [pipeline::Fallback],
    learning_curve: Option<&'a [analysis::CurvePoint]>,
}

/// One shrinkage tried and its cross-validated accuracy.
#[derive(serde::Serialize)]
struct ShrinkageScore {
    shrinkage: f64,
    accuracy: f64,
}

/// `et eval --json`.
#[derive(serde::Serialize)]
struct EvalSummary<'a> {
    observations: u32,
    accuracy: f64,
    /// From the true press position to the predicted class's centre (null when the dataset
    /// has no positions): the figure to compare with a regressor's.
    mean_error_mm: Option<f64>,
    median_error_mm: Option<f64>,
    p90_error_mm: Option<f64>,
    /// From the true class's centre to the predicted one's (0 when right).
    mean_cell_error_mm: f64,
    aee_mm: f64,
    by_distance_from_electrodes: &'a [analysis::Band],
    /// Rows: true class; columns: predicted class.
    confusion: Vec<&'a [u32]>,
}

/// `et export --json`.
#[derive(serde::Serialize)]
struct ExportSummary<'a> {
    out: &'a std::path::Path,
    bytes: usize,
    fits_model_slot: bool,
    multiply_adds_per_frame: usize,
}

/// `ROWSxCOLS`, both at least 1.
fn parse_grid(text: &str, flag: &str) -> Result<(usize, usize)> {
    text.split_once('x')
        .and_then(|(r, c)| Some((r.parse::<usize>().ok()?, c.parse::<usize>().ok()?)))
        .filter(|&(r, c)| r > 0 && c > 0)
        .with_context(|| format!("{flag} '{text}': write ROWSxCOLS, e.g. 7x7"))
}
