//! `et train` and `et eval` on any sensor's table (`--features F.csv [--targets T.csv]`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use et_host::plot;
use et_learn::tabular::{self, GroupsFrom, Referencing, RowRange, Table, TableModel, Unit};
use et_learn::trainer::Progress;
use et_learn::{Examples, Model, Trainer};
use indicatif::{ProgressBar, ProgressStyle};

use crate::output;

/// The table a command reads.
#[derive(Debug, clap::Args)]
pub(crate) struct TableArgs {
    /// Features from any sensor (CSV): one row per observation, any channel count; a header
    /// row is optional, a UTF-8 byte-order mark and CRLF are fine. Columns named label, x, y
    /// (and z, force or pressure) are targets; id, index, sample or time (the rows' numbers
    /// and times) and session, visit, subject, day or run (the groups, unless --groups) are
    /// not features; the rest are.
    #[arg(long, value_name = "CSV")]
    features: Option<PathBuf>,
    /// Targets in a second CSV with the same rows: named columns as above, or without a
    /// header one column (a class label, any text) or x, y and an optional third (z or
    /// force).
    #[arg(long, value_name = "CSV", requires = "features")]
    targets: Option<PathBuf>,
    /// Unit of the positions in the files (reports are in mm); columns named x_mm or x_m say
    /// their own.
    #[arg(long, value_enum, requires = "features")]
    unit: Option<Unit>,
    /// Only rows A..B (0-based, B excluded; A.. or ..B), e.g. the first 80 % to train and
    /// the rest to test: a chronological split (real presses drift: a random split
    /// flatters a model).
    #[arg(
        long,
        value_name = "A..B",
        allow_hyphen_values = true,
        requires = "features"
    )]
    rows: Option<RowRange>,
    /// Which session (visit, subject) each row belongs to: a CSV with one column and a row per
    /// row of --features (any text; a header row optional), or the name of a column of
    /// --features or --targets (a column named session, visit, subject, day or run is taken
    /// unless this says otherwise). With two groups or more, cross-validation leaves one group out (so
    /// `auto` chooses the model that holds on a session it never saw), and `et eval` reports
    /// the error per group.
    #[arg(long, value_name = "CSV|COLUMN", requires = "features")]
    pub(crate) groups: Option<String>,
    /// Frames taken just before each press (or one per session with --groups, or one for all
    /// rows), same columns as --features: the features become (F - B) / B, or F - B with
    /// --reference-as difference. A relative change cancels each channel's gain, a difference
    /// its offset: features that survive a new session. The model remembers it; `et eval`
    /// then needs the evaluated rows' references too.
    #[arg(long, value_name = "CSV", requires = "features")]
    reference_features: Option<PathBuf>,
    /// How --reference-features is applied.
    #[arg(long, value_enum, default_value_t = Referencing::Ratio, requires = "reference_features")]
    reference_as: Referencing,
}

impl TableArgs {
    /// The first flag given that applies to a sensor's table (--features) only, for commands
    /// that were given an et dataset (--data) instead.
    pub(crate) fn table_only_flag(&self) -> Option<&'static str> {
        [
            (self.targets.is_some(), "--targets"),
            (self.unit.is_some(), "--unit"),
            (self.rows.is_some(), "--rows"),
            (self.groups.is_some(), "--groups"),
            (self.reference_features.is_some(), "--reference-features"),
        ]
        .into_iter()
        .find_map(|(given, flag)| given.then_some(flag))
    }

    /// The table, its rows selected, with what was taken as what printed.
    fn load(&self) -> Result<Table> {
        let features = self
            .features
            .as_ref()
            .context("give --features (and --targets)")?;
        if !features.exists()
            && features
                .to_str()
                .is_some_and(|s| s.parse::<usize>().is_ok())
        {
            bail!(
                "--features {}: --features takes a CSV file; to keep only N features of an et \
                 dataset use --keep N",
                features.display()
            );
        }
        let unit = self.unit.unwrap_or(Unit::Mm);
        let groups = self.groups.as_ref().map(|g| {
            if Path::new(g).is_file() {
                GroupsFrom::File(g.into())
            } else {
                GroupsFrom::Column(g.clone())
            }
        });
        let mut table =
            Table::import_grouped(features, self.targets.as_deref(), unit, groups.as_ref())?;
        if let Some(given) = self.unit.filter(|&u| u != table.unit) {
            let name = |u: Unit| match u {
                Unit::M => "m",
                Unit::Mm => "mm",
            };
            bail!(
                "--unit {}: the position columns name their unit, {} (x_{}): drop --unit",
                name(given),
                name(table.unit),
                name(table.unit)
            );
        }
        if let (Some(b), Some(how)) = (&self.reference_features, self.referencing()) {
            let reference = et_learn::dataset::read_reference(b, &table.feature_names)?;
            table = table.referenced(&reference, how, &b.display().to_string())?;
        }
        say!("read {}", table.description);
        Ok(match self.rows {
            Some(r) => {
                let t = table.select(r)?;
                say!("using rows {r} ({} rows)", t.rows());
                t
            }
            None => table,
        })
    }

    /// How the features are referenced, when they are.
    fn referencing(&self) -> Option<Referencing> {
        self.reference_features.as_ref().map(|_| self.reference_as)
    }

    fn inputs(&self) -> Vec<&Path> {
        self.features
            .iter()
            .chain(self.targets.iter())
            .map(PathBuf::as_path)
            .chain(self.groups.iter().map(Path::new).filter(|p| p.is_file()))
            .chain(self.reference_features.iter().map(PathBuf::as_path))
            .collect()
    }
}

/// A progress bar for the stages of a long training.
fn bar() -> ProgressBar {
    let bar = ProgressBar::new(1).with_style(
        ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed}, {eta} left)")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    if !console_is_interactive() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    bar
}

fn console_is_interactive() -> bool {
    use std::io::IsTerminal;
    std::io::stderr().is_terminal()
}

/// Formats hyperparameters as `name=value, ...`.
fn hyper(h: &std::collections::BTreeMap<String, f64>) -> String {
    h.iter()
        .map(|(k, v)| format!("{k}={}", significant(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// `v` to 4 significant digits, for printing (the model file keeps every digit).
pub(crate) fn significant(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    let scale = 10f64.powi(3 - v.abs().log10().floor() as i32);
    (v * scale).round() / scale
}

/// Every non-integer number of `v` to 4 significant digits (what `--json` prints).
fn rounded(v: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match v {
        Value::Number(n) if n.is_f64() => n
            .as_f64()
            .and_then(|f| serde_json::Number::from_f64(significant(f)))
            .map_or(Value::Null, Value::Number),
        Value::Array(a) => Value::Array(a.into_iter().map(rounded).collect()),
        Value::Object(o) => Value::Object(o.into_iter().map(|(k, v)| (k, rounded(v))).collect()),
        other => other,
    }
}

pub(crate) fn train(
    args: &TableArgs,
    trainer: &Trainer,
    out: &Path,
    json: bool,
    force: bool,
) -> Result<()> {
    output::check(out, &args.inputs(), force)?;
    output::check_format(out, "a model (JSON)", &["json"])?;
    let table = args.load()?;
    say_groups(&table);
    let bar = bar();
    let mut last = String::new();
    let progress = |stage: Progress<'_>| {
        let Progress::Table(what, done, of) = stage else {
            return;
        };
        if what != last {
            if !last.is_empty() && !console_is_interactive() {
                say!("{last}: done");
            }
            last = what.to_string();
            bar.set_message(what.to_string());
            bar.set_length(of as u64);
        }
        bar.set_position(done as u64);
    };
    let trained = trainer.train(Examples::Table(&table), progress);
    bar.finish_and_clear();
    let Model::Table(mut model) = trained?.model else {
        bail!("a table trains a table model");
    };
    model.reference = args.referencing();
    output::write(out, |partial| model.save(partial))?;
    if json {
        let mut said = serde_json::to_value(model.scores())?;
        if let Some(fields) = said.as_object_mut() {
            fields.insert("out".into(), serde_json::json!(out));
            fields.insert("fit_seconds".into(), serde_json::json!(model.fit_seconds));
            fields.insert("source".into(), serde_json::json!(model.source));
        }
        out!("{}", serde_json::to_string(&rounded(said))?);
        return Ok(());
    }
    report(&model, out);
    Ok(())
}

/// What the groups of `table` mean for its cross-validation, said on standard error.
fn say_groups(table: &tabular::Table) {
    match table.group_index() {
        // (Of classes alone the drifted figure is not weighed: said only of positions.)
        None if table.positions.is_some() => say!(
            "note: no --groups: every row is taken as one session, and nothing in the data can \
             show how a model holds on a new session; sensors drift between sessions, so \
             positions are predicted by the model best on two figures together ({}): its \
             cross-validated error P, and D, the same with each channel's gain and level \
             drifted (give --groups to choose by leaving a session out)",
            tabular::drift_weighting()
        ),
        None => say!(
            "note: no --groups: every row is taken as one session, and nothing in the data can \
             show how a model holds on a new session (give --groups to cross-validate by \
             leaving a session out)"
        ),
        Some((_, names)) if names.len() < 2 => say!(
            "note: one group ('{}') only: nothing in the data can show how a model holds on a \
             new session",
            names.first().map_or("", String::as_str)
        ),
        Some((_, names)) => say!(
            "{} groups: cross-validation leaves one group out",
            names.len()
        ),
    }
}

/// A trained model's summary on standard error: its note, the best candidate of each method
/// tried, and the choice, written to `out`.
fn report(model: &tabular::TableModel, out: &Path) {
    let best = model.chosen();
    if let Some(note) = &model.note {
        say!("note: {note}");
    }
    // The best of each method tried, then the winner.
    let mut methods: Vec<tabular::Kind> = model.search.iter().map(|c| c.method).collect();
    methods.dedup();
    for m in &methods {
        let best_of = model
            .search
            .iter()
            .filter(|c| c.method == *m)
            .min_by(|a, b| {
                let by = model.chosen_by_drift;
                a.choice_loss(by).total_cmp(&b.choice_loss(by))
            });
        if let Some(c) = best_of {
            say!(
                "  {:<13} {}{}  ({})",
                m.name(),
                describe(c),
                c.cv_drifted_error_mm
                    .map_or(String::new(), |d| format!(", {d:.2} mm if channels drift")),
                hyper(&c.hyperparameters)
            );
        }
    }
    say!(
        "trained {} on rows {}..{} ({} features{}), {}-fold {} cross-validation {}{}; chose {}; \
         {:.1} s; wrote {}",
        model.method.name(),
        model.trained_rows[0],
        model.trained_rows[1],
        model.features(),
        model
            .classes
            .as_ref()
            .map_or(String::new(), |c| format!(", {} classes", c.names.len())),
        model.cv_folds,
        model.cv_scheme.said(),
        best.map_or("-".into(), describe),
        best.and_then(|b| b.cv_drifted_error_mm)
            .filter(|_| model.chosen_by_drift)
            .map_or(String::new(), |d| format!(
                " ({d:.2} mm with channels drifted)"
            )),
        hyper(&model.hyperparameters),
        model.fit_seconds,
        out.display()
    );
}

/// Smaller is better.
fn describe(c: &tabular::Candidate) -> String {
    match (c.cv_mean_error_mm, c.cv_accuracy) {
        (_, Some(a)) => format!("accuracy {:.1} %", 100.0 * a),
        (Some(e), None) => format!("mean error {e:.2} mm"),
        (None, None) => "could not be fitted".into(),
    }
}

pub(crate) fn eval(
    model: &TableModel,
    model_path: &Path,
    args: &TableArgs,
    plots: Option<&Path>,
    predictions: Option<&Path>,
    json: bool,
    force: bool,
) -> Result<()> {
    let pngs = plots.map(|d| (d.join("error-map.png"), d.join("predicted-vs-true.png")));
    let mut inputs = args.inputs();
    inputs.push(model_path);
    let mut outputs: Vec<&Path> = Vec::new();
    if let Some((a, b)) = &pngs {
        outputs.extend([a.as_path(), b.as_path()]);
    }
    outputs.extend(predictions);
    let folders: Vec<&Path> = plots.into_iter().collect();
    output::check_all(&outputs, &folders, &inputs, force)?;
    if let Some(p) = predictions {
        output::check_format(p, "the predictions (CSV)", &["csv"])?;
    }
    same_referencing(model, model_path, args)?;
    let table = scored_rows(args)?;
    let e = tabular::evaluate(model, &table).map_err(|e| {
        anyhow::anyhow!(
            "{} with {}: {e}",
            model_path.display(),
            args.features
                .as_deref()
                .map_or_else(String::new, |p| p.display().to_string())
        )
    })?;
    if let (Some(dir), Some((map, scatter))) = (plots, &pngs) {
        if e.pairs.is_empty() {
            say!("note: no positions to plot (the rows or the model have none)");
        } else {
            let title = format!("{} on {} rows", model.method.name(), e.observations);
            let inside = |d: &Path, png: &Path| d.join(png.file_name().unwrap_or_default());
            crate::plots_folder(dir, |d| {
                output::write(&inside(d, map), |partial| {
                    plot::error_map(partial, &e.pairs, &title)
                })?;
                output::write(&inside(d, scatter), |partial| {
                    plot::predicted_vs_true(partial, &e.pairs, &title)
                })
            })?;
        }
    }
    if let Some(csv) = predictions {
        output::write(csv, |partial| {
            std::fs::write(partial, predictions_csv(model, &e, table.first_row))
        })?;
    }
    say_notes(&e, &table);
    if json {
        out!("{}", serde_json::to_string(&e)?);
    } else {
        print_scores(model, &e);
    }
    Ok(())
}

/// Refuses rows referenced otherwise than the rows `model` (read from `model_path`) was
/// trained on.
fn same_referencing(model: &TableModel, model_path: &Path, args: &TableArgs) -> Result<()> {
    if model.reference == args.referencing() {
        return Ok(());
    }
    let said = |r: Option<Referencing>| match r {
        None => "raw features".to_string(),
        Some(Referencing::Ratio) => "features relative to --reference-features (ratio)".into(),
        Some(Referencing::Difference) => "features minus --reference-features (difference)".into(),
    };
    bail!(
        "{} was trained on {}; these rows would be {}: give the same --reference-features and \
         --reference-as as in training",
        model_path.display(),
        said(model.reference),
        said(args.referencing())
    )
}

/// The rows to score, read from `args`' files.
fn scored_rows(args: &TableArgs) -> Result<tabular::Table> {
    args.load().map_err(|e| {
        // New rows without their targets are not scored: say what eval is for, and where
        // such rows are predicted (the file's "add a 'label' column" alone asked for labels
        // the user does not have).
        let no_target = e
            .downcast_ref::<et_learn::dataset::DatasetError>()
            .is_some_and(|d| {
                matches!(d, et_learn::dataset::DatasetError::Content { fault, .. }
                    if matches!(**fault, et_learn::dataset::DatasetFault::NoTarget { .. }))
            });
        if no_target {
            anyhow::anyhow!(
                "{e:#} (et eval scores a model against the rows' own targets; rows without \
                 them are predicted by Python's model.predict, or live by et stream)"
            )
        } else {
            e
        }
    })
}

/// The evaluation's notes (another unit, another scale, the training's own rows) and the
/// labels the model has no class of, on standard error.
fn say_notes(e: &tabular::Evaluation, table: &tabular::Table) {
    for note in [&e.unit_note, &e.scale_note, &e.trained_note]
        .into_iter()
        .flatten()
    {
        say!("note: {note}");
    }
    if e.unknown_labels.is_empty() {
        return;
    }
    let shown: Vec<&str> = e
        .unknown_labels
        .iter()
        .take(5)
        .map(String::as_str)
        .collect();
    let missed = table.labels.as_ref().map_or(0, |l| {
        l.iter().filter(|l| e.unknown_labels.contains(l)).count()
    });
    say!(
        "note: {} label{} the model has no class of ({}{}): {missed} row{} counted as missed",
        e.unknown_labels.len(),
        if e.unknown_labels.len() == 1 { "" } else { "s" },
        shown.join(", "),
        if e.unknown_labels.len() > 5 {
            ", ..."
        } else {
            ""
        },
        if missed == 1 { "" } else { "s" }
    );
}

/// The scores in a line, and each group's, on standard output.
fn print_scores(model: &TableModel, e: &tabular::Evaluation) {
    let mut parts = Vec::new();
    if let Some(a) = e.accuracy {
        parts.push(format!("accuracy {:.1} %", 100.0 * a));
    }
    if let (Some(m), Some(md), Some(p90)) = (e.mean_error_mm, e.median_error_mm, e.p90_error_mm) {
        parts.push(format!(
            "position error mean {m:.2} mm, median {md:.2} mm, 90th percentile {p90:.2} mm"
        ));
    }
    if let Some(c) = e.mean_predictor_error_mm {
        parts.push(format!("(always guessing the training mean: {c:.2} mm)"));
    }
    if let Some(d3) = e.mean_error_3d_mm {
        parts.push(format!("with z: {d3:.2} mm"));
    }
    out!(
        "{} rows, {}: {}; predicted in {:.1} ms",
        e.observations,
        model.method.name(),
        parts.join(", "),
        1e3 * e.predict_seconds
    );
    for g in e.per_group.iter().flatten() {
        if let (Some(m), Some(md)) = (g.mean_error_mm, g.median_error_mm) {
            out!(
                "  group {}: {} rows, mean {m:.2} mm, median {md:.2} mm",
                g.group,
                g.observations
            );
        }
    }
}

/// Every row's prediction as CSV: `row` (0-based, in the file), `class` (classifiers: the
/// user's name), `x_mm`, `y_mm`, and the third target when predicted (`z_mm`, or its own
/// name and unit).
fn predictions_csv(model: &TableModel, e: &tabular::Evaluation, first_row: usize) -> String {
    use std::fmt::Write as _;
    let names = model.classes.as_ref().map(|c| &c.names);
    let mut header = vec!["row"];
    if names.is_some() {
        header.push("class");
    }
    header.extend(["x_mm", "y_mm"]);
    // The third target: a length in mm when named z, else in the file's own unit.
    let z_scale = if model.third_is_length() { 1e3 } else { 1.0 };
    let third = model.third.as_ref().map(|t| {
        if model.third_is_length() {
            "z_mm".to_string()
        } else {
            t.clone()
        }
    });
    if let Some(third) = &third {
        header.push(third);
    }
    let mut s = header.join(",");
    s.push('\n');
    for (i, p) in e.predictions.iter().enumerate() {
        let _ = write!(s, "{}", first_row + i);
        if let Some(names) = names {
            let name = p.class.and_then(|c| names.get(usize::from(c)));
            // Names are the user's text: quoted when they hold a comma or a quote.
            let name = name.map_or_else(String::new, |n| {
                if n.contains([',', '"', '\n']) {
                    format!("\"{}\"", n.replace('"', "\"\""))
                } else {
                    n.clone()
                }
            });
            let _ = write!(s, ",{name}");
        }
        let t = p.target;
        // The model predicts m; the file is for people: mm.
        let cell = |v: Option<f64>| v.map_or_else(String::new, |v| format!("{:.4}", v * 1e3));
        let _ = write!(s, ",{},{}", cell(t.map(|t| t[0])), cell(t.map(|t| t[1])));
        if third.is_some() {
            let v = t.map_or_else(String::new, |t| (t[2] * z_scale).to_string());
            let _ = write!(s, ",{v}");
        }
        s.push('\n');
    }
    s
}
