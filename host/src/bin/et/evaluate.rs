//! `et eval` and `et export`: a trained model tested on other data, and its blob for the board.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use et_core::model::{ModelKind, Precision};
use et_host::plot;
use et_learn::model::{Board, Tested};
use et_learn::{Model, dataset, pipeline};

use crate::output;

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
    #[arg(long, value_enum, default_value_t = Precision::F32)]
    precision: Precision,
    /// Where to write the blob.
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary.
    #[arg(long)]
    json: bool,
}

pub(crate) fn eval_cmd(args: &EvalArgs, force: bool) -> Result<()> {
    let model = Model::load(&args.model)?;
    let board = match (&model, &args.data) {
        (Model::Table(table_model), None) => {
            return crate::tabular::eval(
                table_model,
                &args.model,
                &args.table,
                args.plots.as_deref(),
                args.predictions.as_deref(),
                args.json,
                force,
            );
        }
        (Model::Table(_), Some(_)) => bail!(
            "{}: trained on a sensor's table: evaluate it with --features (and --targets)",
            args.model.display()
        ),
        (Model::Board(_), None) => bail!(
            "{}: a board model (trained on an et dataset): evaluate it with --data",
            args.model.display()
        ),
        (Model::Board(board), Some(_)) => board,
    };
    let data_arg = args.data.as_deref().unwrap_or(Path::new(""));
    if let Some(flag) = args.table.table_only_flag() {
        bail!("{flag} applies to any sensor's table (--features), not to an et dataset (--data)");
    }
    if args.predictions.is_some() {
        bail!(
            "--predictions writes a sensor's table's predictions (--features); for an et \
             dataset --json has the confusion matrix"
        );
    }
    let plots = args
        .plots
        .as_ref()
        .map(|dir| (dir.join("confusion.png"), dir.join("error-vs-distance.png")));
    if let Some((a, b)) = &plots {
        let folders: Vec<&Path> = args.plots.as_deref().into_iter().collect();
        output::check_all(&[a, b], &folders, &[&args.model, data_arg], force)?;
    }
    let data = dataset::load(data_arg)?;
    // The model was checked when loaded: what goes wrong now is the data's.
    let tested = board
        .test(&data)
        .map_err(|e| anyhow::anyhow!("{}: {e}", data_arg.display()))?;
    let centres_mm = &board.file().board_positions();
    let conf = &tested.confusion;
    if let (Some(dir), Some(pngs)) = (&args.plots, &plots) {
        eval_plots(dir, pngs, &tested, data_arg)?;
    }
    for note in [&tested.scale_note, &tested.trained_note]
        .into_iter()
        .flatten()
    {
        say!("note: {note}");
    }
    let summary = tested.summary();
    let [mean, median, p90] = [
        summary.mean_error_mm,
        summary.median_error_mm,
        summary.p90_error_mm,
    ]
    .map(|v| v.unwrap_or(0.0));
    let known = summary.mean_error_mm.is_some();
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
            conf.mean_position_error(centres_mm),
            conf.aee(centres_mm)
        );
    }
    Ok(())
}

/// `et eval --plots` of a board model: the confusion matrix and the error against the
/// distance from the electrodes (when the data say where the electrodes are).
fn eval_plots(
    dir: &Path,
    (confusion_png, error_png): &(PathBuf, PathBuf),
    tested: &Tested,
    data_arg: &Path,
) -> Result<()> {
    let conf = &tested.confusion;
    let title = format!(
        "confusion: accuracy {:.1} % on {}",
        100.0 * conf.accuracy(),
        data_arg.display()
    );
    let inside = |d: &Path, png: &Path| d.join(png.file_name().unwrap_or_default());
    crate::plots_folder(dir, |d| {
        output::write(&inside(d, confusion_png), |partial| {
            plot::confusion(partial, conf, &title)
        })?;
        if tested.outcomes.is_empty() {
            say!(
                "note: {} does not say where the electrodes are: no error-vs-distance plot",
                data_arg.display()
            );
        } else {
            output::write(&inside(d, error_png), |partial| {
                plot::error_vs_distance(partial, tested)
            })?;
        }
        Ok(())
    })
}

pub(crate) fn export_cmd(args: &ExportArgs, force: bool) -> Result<()> {
    output::check(&args.out, &[&args.model], force)?;
    output::check_format(&args.out, "the board's blob", &["etm", "bin"])?;
    let model = Model::load(&args.model)?;
    let precision = args.precision;
    let blob = model
        .export_blob(precision)
        .map_err(|e| anyhow::anyhow!("{}: {e}", args.model.display()))?;
    let file = model.as_board().map(Board::file).context("a board model")?;
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
        say!(
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

/// `et export --json`.
#[derive(serde::Serialize)]
struct ExportSummary<'a> {
    out: &'a std::path::Path,
    bytes: usize,
    fits_model_slot: bool,
    multiply_adds_per_frame: usize,
}
