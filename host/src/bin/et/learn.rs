//! `et collect`, `et train`, `et eval`, `et export`: touch classification from raw voltages.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use et_host::plot;
use et_learn::analysis::CurvePoint;
use et_learn::model::Board;
use et_learn::tabular::{self, Choice};
use et_learn::trainer::{BoardTraining, Progress};
use et_learn::{Examples, TrainError, Trainer};
use et_learn::{dataset, pipeline};

use crate::output;
use indicatif::{ProgressBar, ProgressStyle};

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
    /// process learning a length scale per feature), mlp (a multilayer perceptron), or auto (every
    /// method that fits the targets, the best by cross-validation); default auto.
    #[arg(long, value_enum)]
    kind: Option<Choice>,
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
    #[arg(long, value_parser = crate::domain::count(2, et_learn::trainer::MAX_FOLDS))]
    folds: Option<usize>,
    /// How --features rows are dealt to folds: shuffled (stratified by class), or blocks
    /// (contiguous, in file order: for recordings in time order, where a shuffled split
    /// flatters a model).
    /// Default shuffled; with --groups cross-validation always leaves one group out.
    #[arg(long, value_enum, conflicts_with = "groups")]
    cv: Option<tabular::CvScheme>,
    /// Standardise each session's features by that session's own mean and spread (--features;
    /// the sessions from --groups, else all rows as one): its channel offsets and gains
    /// cancel. `et eval` then does the same to each session of the rows it scores, so it
    /// needs a session's worth of rows (two or more per group).
    #[arg(long)]
    per_group: bool,
    /// The longest the training may take, minutes. On --features the Gaussian process, the
    /// perceptron and knn (alone or in auto) estimate their time from a timed piece of their work
    /// before any fit and say it; on --data QDA and LDA do (their time grows with the classes
    /// squared: a 100 x 100 grid takes far longer than a 10 x 10). A training estimated past
    /// this is refused, naming what to cut. Default 60.
    #[arg(long, value_name = "M", value_parser = crate::domain::above(0.0, 10_080.0))]
    max_minutes: Option<f64>,
    /// The seed of the random choices: the shuffled cross-validation folds (the stratified
    /// k-fold on --data, --cv shuffled on --features) and the perceptron's starting weights.
    /// Another seed deals the rows to other folds, to see how much a score owes to one split.
    #[arg(long, default_value_t = 1, value_parser = crate::domain::whole(0, u64::MAX))]
    seed: u64,
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
    #[arg(long, value_name = "N", value_parser = crate::domain::count(1, 1_000_000))]
    keep: Option<usize>,
    /// Where to write the model (JSON).
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

impl TrainArgs {
    /// The trainer these arguments ask for.
    fn trainer(&self) -> Result<Trainer> {
        let method = self.kind.unwrap_or(Choice::Auto);
        let shrinkage = match self.shrinkage.as_deref().unwrap_or("auto") {
            "auto" => None,
            v => Some(
                v.parse::<f64>()
                    .ok()
                    .filter(|s| (0.0..=1.0).contains(s))
                    .with_context(|| format!("--shrinkage '{v}': a number in [0, 1] or auto"))?,
            ),
        };
        Ok(Trainer {
            method,
            shrinkage,
            folds: self.folds,
            scheme: self.cv.unwrap_or(tabular::CvScheme::Shuffled),
            grid: self
                .grid
                .as_deref()
                .map(|g| parse_grid(g, "--grid"))
                .transpose()?,
            raw: self.raw,
            keep: self.keep,
            seed: self.seed,
            per_group: self.per_group,
            budget_s: self
                .max_minutes
                .map_or(et_learn::tabular::BUDGET_S, |m| m * 60.0),
        })
    }
}

/// Draws `board`'s learning curve into `png` (a progress bar while it is scored).
fn learning_curve_png(png: &Path, board: &BoardTraining) -> Result<Vec<CurvePoint>> {
    let bar = ProgressBar::new(board.curve_sizes().len() as u64).with_style(
        ProgressStyle::with_template("learning curve [{bar:30}] {pos}/{len}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let points = board.learning_curve(|| bar.inc(1));
    bar.finish_and_clear();
    let options = board.training.options;
    output::write(png, |partial| {
        plot::chart(
            partial,
            plot::Labels {
                title: &format!(
                    "learning curve: {} ({}), {} classes",
                    options.kind.name(),
                    if board.data.visits() >= 2 {
                        "leave-one-visit-out"
                    } else {
                        "k-fold CV"
                    },
                    board.data.centres.len()
                ),
                x: "observations per class n_c",
                y: "held-out accuracy (%)",
                legend: plot::Legend::UpperLeft,
            },
            &[plot::Series {
                label: format!("shrinkage {}", options.shrinkage),
                points: points
                    .iter()
                    .filter_map(|p| Some((p.n_c as f64, 100.0 * p.accuracy?)))
                    .collect(),
                scatter: false,
            }],
        )
    })?;
    Ok(points)
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
            match args.kind {
                Some(Choice::One(m)) => m.name(),
                _ => "auto",
            }
        )
    })?;
    if let Some(flag) = args.table.table_only_flag() {
        bail!("{flag} applies to any sensor's table (--features), not to an et dataset (--data)");
    }
    if args.grid.is_some() || args.cv.is_some() || args.per_group {
        bail!("--grid, --cv and --per-group apply to any sensor's table (--features)");
    }
    let mut outputs = vec![args.out.as_path()];
    outputs.extend(args.curve.as_deref());
    output::check_all(&outputs, &[], &[data_arg], force)?;
    output::check_format(&args.out, "a model (JSON)", &["json"])?;
    if let Some(curve) = &args.curve {
        output::check_format(curve, "the learning curve (PNG)", &["png"])?;
    }
    let folds = trainer.dataset_folds();
    // Each stage on one line that updates in place, with the time so far.
    let spinner = crate::spinner::Spinner::new(format!("reading {}", data_arg.display()));
    let data = dataset::load(data_arg)?;
    let trained = trainer.train(Examples::Dataset(&data), |stage| match stage {
        Progress::RawFrames => spinner.suspend(|| {
            say!(
                "note: {} has no untouched frames, training on raw frames",
                data_arg.display()
            );
        }),
        Progress::Preparing { rows, features } => {
            spinner.say(format!(
                "preparing {rows} observations x {features} features"
            ));
        }
        // A long training says so on its own line (the spinner shows only on a terminal).
        Progress::Estimate { seconds } if seconds >= 60.0 => {
            spinner.suspend(|| say!("{}", stage.said(folds).0));
        }
        Progress::Estimate { .. } => spinner.say(stage.said(folds).0),
        Progress::Dataset(stage) => spinner.say(stage.said(folds)),
        Progress::Table(..) => {}
    });
    drop(spinner);
    let trained = trained.map_err(|e| match e {
        TrainError::Data(e) => anyhow::anyhow!("{}: {e}", data_arg.display()),
        other => other.into(),
    })?;
    let (board, training) = trained
        .into_board()
        .context("an et dataset trains a board model")?;
    let curve = match &args.curve {
        Some(png) => Some(learning_curve_png(png, &training)?),
        None => None,
    };
    output::write(&args.out, |partial| board.file().save(partial))?;
    print_trained(args, &board, &training, curve.as_deref())
}

/// `et train`'s summary of a board model: JSON, or a line and its notes.
fn print_trained(
    args: &TrainArgs,
    board: &Board,
    training: &BoardTraining,
    curve: Option<&[CurvePoint]>,
) -> Result<()> {
    let scores = training.scores(board);
    let summary = TrainSummary {
        out: &args.out,
        scores: &scores,
        learning_curve: curve,
    };
    for note in training.training.notes() {
        say!("note: {note}");
    }
    if args.json {
        out!("{}", serde_json::to_string(&summary)?);
    } else {
        let s = &scores;
        say!(
            "trained {}{} on {} observations ({} classes, {} features), shrinkage {} ({}): {}-fold CV accuracy {:.1} %, mean error {:.2} mm{}; wrote {}",
            s.kind.name(),
            if s.referenced {
                " (referenced)"
            } else {
                " (raw frames)"
            },
            s.observations,
            s.classes,
            s.features,
            s.shrinkage,
            s.shrinkage_chosen_by,
            s.cv_folds,
            100.0 * s.cv_accuracy,
            s.cv_mean_error_mm,
            (s.leave_one_visit_out_accuracy).map_or(String::new(), |a| format!(
                ", leave-one-visit-out {:.1} %",
                100.0 * a
            )),
            args.out.display()
        );
        let (kind, classes, features) = (s.kind, s.classes, s.features);
        let fit = pipeline::features_that_fit(kind, classes, features);
        if fit < features {
            say!(
                "note: for the board, this model is too big for a model slot even in f16; \
                 train with --keep {fit} (the most that fit for {classes} classes) or fewer classes"
            );
        }
    }
    Ok(())
}

/// `et train --json` of a board model.
#[derive(serde::Serialize)]
struct TrainSummary<'a> {
    out: &'a std::path::Path,
    #[serde(flatten)]
    scores: &'a et_learn::trainer::BoardScores,
    learning_curve: Option<&'a [CurvePoint]>,
}

use et_learn::tabular::GRID_MOST;

/// `ROWSxCOLS`, both at least 1, at least two cells, at most [`GRID_MOST`] each.
pub(crate) fn parse_grid(text: &str, flag: &str) -> Result<(usize, usize)> {
    // 7x7, 7X7 or 7 x 7: as people write a grid.
    let (r, c) = text
        .trim()
        .split_once(['x', 'X'])
        .map(|(r, c)| (r.trim(), c.trim()))
        .and_then(|(r, c)| Some((r.parse::<usize>().ok()?, c.parse::<usize>().ok()?)))
        .with_context(|| format!("{flag} '{text}': write ROWSxCOLS, e.g. 7x7"))?;
    if r == 0 || c == 0 {
        // (It was said as written wrongly.)
        bail!("{flag} '{text}': a grid of no cells; at least 1 row and 1 column (2x1 or more)");
    }
    if r > GRID_MOST || c > GRID_MOST {
        bail!("{flag} '{text}': at most {GRID_MOST} rows and {GRID_MOST} columns");
    }
    if r.saturating_mul(c) < 2 {
        bail!("{flag} '{text}': one class; a classifier tells at least two apart (2x1 or more)");
    }
    Ok((r, c))
}
