//! The demo's first stage: touch classification on the default sheet, trained, cross-validated,
//! tested the next day and run through et-core as the chip runs it.

use super::*;
use et_learn::dataset::Dataset;
use et_learn::model::Board;

/// The headline numbers of the learning section.
pub(super) struct LearningKey {
    pub(super) next_day: f64,
    /// None when docs/method.md §9's raw-frame QDA cannot be fitted (too few observations per class).
    pub(super) raw: Option<f64>,
    pub(super) cv: f64,
    pub(super) chip: Option<ChipCheck>,
}

/// The section: collect, train and test ([`measure`]), then its figures and text.
pub(super) fn learning(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<LearningKey>> {
    let results = measure(out, sizes, steps)?;
    figures(&out.join("learning"), &results)?;
    Ok(Section {
        markdown: markdown(&results, sizes),
        json: serde_json::to_value(&results)?,
        key: LearningKey {
            next_day: results.qda.next_day_accuracy,
            raw: results.raw_qda_next_day_accuracy,
            cv: results.qda.cv_accuracy,
            chip: results.chip,
        },
    })
}

/// What the learning section measured (`summary.json`'s "learning").
#[derive(Serialize)]
pub(super) struct Learning {
    scene: &'static str,
    #[serde(skip)]
    description: String,
    classes: usize,
    /// Grid rows (= columns).
    #[serde(skip)]
    rows: usize,
    /// Finger radius, m.
    #[serde(skip)]
    radius: f64,
    observations_per_class: usize,
    next_day_observations: usize,
    /// Features of a whole (reciprocity-halved) frame.
    #[serde(skip)]
    features: usize,
    qda: QdaResult,
    lda_next_day_accuracy: f64,
    raw_qda_next_day_accuracy: Option<f64>,
    /// Each model's row of the report's table.
    models: Vec<ModelRow>,
    features_trade: Vec<TradePoint>,
    chip: Option<ChipCheck>,
    /// The QDA's next-day test, for the figures.
    #[serde(skip)]
    qda_test: Tested,
}

/// The referenced QDA, the section's model.
#[derive(Serialize)]
struct QdaResult {
    shrinkage: f64,
    cv_accuracy: f64,
    leave_one_visit_out: Option<f64>,
    next_day_accuracy: f64,
    next_day_mean_error_mm: f64,
    by_distance: Vec<et_learn::analysis::Band>,
}

/// One model trained and tested.
#[derive(Serialize)]
struct ModelRow {
    name: String,
    /// None when the model cannot be fitted.
    result: Option<ModelResult>,
    /// Why it cannot be fitted.
    #[serde(skip_serializing_if = "Option::is_none")]
    error: Option<String>,
}

#[derive(Serialize)]
struct ModelResult {
    shrinkage: f64,
    cv_accuracy: f64,
    leave_one_visit_out: Option<f64>,
    next_day_accuracy: f64,
    next_day_mean_error_mm: f64,
    /// docs/method.md §9's AEE per next-day session, mm.
    aee_mm: f64,
}

/// A feature count kept, its next-day accuracy and its blob sizes.
#[derive(Serialize)]
struct TradePoint {
    features: usize,
    next_day_accuracy: f64,
    f16_bytes: usize,
    f32_bytes: usize,
}

/// The chip's model run through et-core on the next-day frames.
#[derive(Clone, Copy, Serialize)]
pub(super) struct ChipCheck {
    pub(super) features: usize,
    pub(super) bytes: usize,
    pub(super) right: usize,
    pub(super) total: usize,
    pub(super) disagree_with_host: usize,
}

impl ChipCheck {
    pub(super) fn accuracy(&self) -> f64 {
        self.right as f64 / self.total.max(1) as f64
    }
}

/// Collects the training and next-day sets, trains QDA (referenced and raw) and LDA, tests
/// them the next day, trades features for size, and checks the chip's model in et-core; the
/// model and blob are written into `out/learning`.
fn measure(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Learning> {
    let scene = load(DEFAULT_SCENE)?;
    // docs/method.md §9: 49 classes with a 15 mm target on the 13 cm sheet.
    let (rows, radius) = (7, 0.0075);
    let centres = collect::grid(&scene.sheet, rows, rows, 0.0);
    let classes = centres.len();
    let (train, next_day) = collect_sets(&scene, &centres, radius, sizes, steps)?;
    let n_c = train.x.nrows() / classes;

    // The model: QDA on referenced frames, shrinkage by leave-one-visit-out.
    let bar = steps.bar(3, "training (QDA, raw QDA, LDA)");
    let mm: Vec<[f64; 2]> = centres.iter().map(|c| [c[0] * 1e3, c[1] * 1e3]).collect();
    let sets = (&train, &next_day);
    let (qda, qda_file, qda_test) = fit(sets, true, ModelKind::Qda, None, None)?;
    bar.inc(1);
    // docs/method.md §9 as published: QDA on the raw frames, no shrinkage.
    let raw = fit(sets, false, ModelKind::Qda, Some(0.0), None);
    bar.inc(1);
    let (lda, _, lda_test) = fit(sets, true, ModelKind::Lda, None, None)?;
    steps.done(&bar, "trained QDA and LDA, cross-validated");
    qda_file.file().save(&out.join("learning/model.json"))?;
    let (trade, chip) = feature_trade(out, sets, &qda, steps)?;
    let p_all = train.x.ncols();
    let row = |name: &str, t: &pipeline::Training, tested: &Tested| ModelRow {
        name: if t
            .fallbacks
            .iter()
            .any(|f| matches!(f, pipeline::Fallback::QdaIsLda { .. }))
        {
            format!(
                "{name}, saved as the LDA it equals (best shrinkage: 1 toward the pooled covariance)"
            )
        } else {
            name.to_string()
        },
        result: Some(ModelResult {
            shrinkage: t.options.shrinkage,
            cv_accuracy: t.cv.accuracy(),
            leave_one_visit_out: t.leave_one_visit_out,
            next_day_accuracy: tested.confusion.accuracy(),
            next_day_mean_error_mm: tested.confusion.mean_position_error(&mm),
            aee_mm: tested.confusion.aee(&mm) / sizes.days as f64,
        }),
        error: None,
    };
    let mut models = vec![
        row("QDA, referenced frames (V_m - V_0)", &qda, &qda_test),
        row("LDA, referenced frames", &lda, &lda_test),
    ];
    let raw_name = "QDA on raw frames (docs/method.md §9 as published)";
    models.push(match &raw {
        Ok((t, _, tested)) => row(raw_name, t, tested),
        Err(e) => ModelRow {
            name: raw_name.to_string(),
            result: None,
            error: Some(e.to_string()),
        },
    });
    Ok(Learning {
        scene: DEFAULT_SCENE.0,
        description: scene.description.clone(),
        classes,
        rows,
        radius,
        observations_per_class: n_c,
        next_day_observations: next_day.x.nrows(),
        features: p_all,
        qda: QdaResult {
            shrinkage: qda.options.shrinkage,
            cv_accuracy: qda.cv.accuracy(),
            leave_one_visit_out: qda.leave_one_visit_out,
            next_day_accuracy: qda_test.confusion.accuracy(),
            next_day_mean_error_mm: qda_test.confusion.mean_position_error(&mm),
            by_distance: qda_test.bands.clone(),
        },
        lda_next_day_accuracy: lda_test.confusion.accuracy(),
        raw_qda_next_day_accuracy: raw.as_ref().ok().map(|(_, _, t)| t.confusion.accuracy()),
        models,
        features_trade: trade,
        chip,
        qda_test,
    })
}

/// The training visits and next-day sessions on `scene`'s sheet: a press of `radius` (m) in
/// each class's target around `centres`, sizes.scans scans a visit, one scan a next-day
/// session.
fn collect_sets(
    scene: &Scene,
    centres: &[[f64; 2]],
    radius: f64,
    sizes: &Sizes,
    steps: &Steps,
) -> Result<(Dataset, Dataset)> {
    let config = collect::training_config(scene.board_config()?);
    let plan = Plan {
        visits: 1,
        scans: sizes.scans,
        radius,
        target_radius: radius,
        ..Plan::default()
    };
    // Counted in presses, so the bar moves within a visit (by visits it sat at 0 for the
    // first seconds of each, saying "eta 0s").
    let (visit_presses, day_presses) = (centres.len() * sizes.scans, centres.len());
    let trained = sizes.visits * visit_presses;
    let bar = steps.bar(
        trained + sizes.days * day_presses,
        "collecting presses (visits, next days)",
    );
    let train = collect::collect_visits(
        &scene.sheet,
        scene.frontend,
        config,
        centres,
        &plan,
        (0..sizes.visits).map(|v| 1_000 + v as u64),
        |pressed, _| bar.set_position(pressed as u64),
    )?;
    let day = Plan {
        scans: 1,
        ..plan.clone()
    };
    let next_day = collect::collect_visits(
        &scene.sheet,
        scene.frontend,
        config,
        centres,
        &day,
        (0..sizes.days).map(|d| 77 + d as u64),
        |pressed, _| bar.set_position((trained + pressed) as u64),
    )?;
    steps.done(
        &bar,
        &format!(
            "collected {} training and {} next-day observations",
            train.x.nrows(),
            next_day.x.nrows()
        ),
    );
    Ok((train, next_day))
}

/// A board model trained on the first of `sets` (training, next day) as the demo trains
/// them: referenced frames or raw, QDA or LDA, shrinkage by cross-validation (10 folds)
/// unless given, `keep` features when given; its training, the model, and its test on the
/// next day.
fn fit(
    (train, next_day): (&Dataset, &Dataset),
    referenced: bool,
    kind: ModelKind,
    shrinkage: Option<f64>,
    keep: Option<usize>,
) -> Result<(pipeline::Training, Board, Tested)> {
    let trainer = Trainer {
        method: Choice::One(match kind {
            ModelKind::Qda => Kind::Qda,
            ModelKind::Lda => Kind::Lda,
        }),
        shrinkage,
        folds: Some(10),
        raw: !referenced,
        keep,
        ..Trainer::default()
    };
    let (board, training) = trainer
        .train(Examples::Dataset(train), |_| {})?
        .into_board()
        .ok_or(DemoError::Scenes("an et dataset trains a board model"))?;
    let tested = board.test(next_day)?;
    Ok((training.training, board, tested))
}

/// The trade of features kept (Fisher ranking) against the next day's accuracy and the
/// chip's model size, for the main model's kind and shrinkage (`qda`: a QDA whose best
/// shrinkage is full toward the pooled covariance was saved as the LDA it equals); and the
/// chip's model, the most features whose f16 blob fits a slot, written to
/// `out/learning/model.etm` and run through et-core on the next day's frames.
fn feature_trade(
    out: &Path,
    sets: (&Dataset, &Dataset),
    qda: &pipeline::Training,
    steps: &Steps,
) -> Result<(Vec<TradePoint>, Option<ChipCheck>)> {
    let p_all = sets.0.x.ncols();
    let keeps: Vec<usize> = [8, 16, 24, 32, 48, 64, 80]
        .into_iter()
        .filter(|&p| p < p_all)
        .chain([p_all])
        .collect();
    let bar = steps.bar(keeps.len(), "features against accuracy and size");
    let mut trade = Vec::new();
    for &p in &keeps {
        let (_, board, tested) = fit(
            sets,
            true,
            qda.options.kind,
            Some(qda.options.shrinkage),
            Some(p),
        )?;
        let f16 = board.blob(Precision::F16)?.len();
        let f32 = board.blob(Precision::F32)?.len();
        trade.push((
            TradePoint {
                features: p,
                next_day_accuracy: tested.confusion.accuracy(),
                f16_bytes: f16,
                f32_bytes: f32,
            },
            board,
        ));
        bar.inc(1);
    }
    let chip = trade
        .iter()
        .filter(|(t, _)| t.f16_bytes <= MODEL_SLOT_BYTES)
        .max_by_key(|(t, _)| t.features)
        .map(|(t, board)| -> Result<_> {
            let blob = board.blob(Precision::F16)?;
            let etm = out.join("learning/model.etm");
            std::fs::write(&etm, &blob).map_err(io(&etm))?;
            let r = board.on_chip(&blob, sets.1)?;
            Ok(ChipCheck {
                features: t.features,
                bytes: t.f16_bytes,
                right: r.right,
                total: r.total,
                disagree_with_host: r.disagree,
            })
        })
        .transpose()?;
    steps.done(
        &bar,
        "feature trade curve; the chip's model checked in et-core",
    );
    Ok((trade.into_iter().map(|(t, _)| t).collect(), chip))
}

/// The section's figures: the next day's confusion and error against distance, and the
/// feature trade (accuracy, and the blob's size against a flash slot).
fn figures(dir: &Path, r: &Learning) -> Result<()> {
    let tested = &r.qda_test;
    plot::confusion(
        &dir.join("confusion.png"),
        &tested.confusion,
        &format!(
            "next day: accuracy {:.1} %, {} observations",
            100.0 * tested.confusion.accuracy(),
            tested.confusion.total()
        ),
    )?;
    plot::error_vs_distance(&dir.join("error-vs-distance.png"), tested)?;
    let trade = &r.features_trade;
    plot::chart(
        &dir.join("features.png"),
        plot::Labels {
            title: "QDA: features kept against next-day accuracy",
            x: "features p (largest Fisher ratio first)",
            y: "next-day accuracy (%)",
            legend: plot::Legend::LowerRight,
        },
        &[plot::Series {
            label: format!("{} classes", r.classes),
            points: trade
                .iter()
                .map(|t| (t.features as f64, 100.0 * t.next_day_accuracy))
                .collect(),
            scatter: false,
        }],
    )?;
    let kib = |b: usize| b as f64 / 1024.0;
    let slot = kib(MODEL_SLOT_BYTES);
    plot::chart(
        &dir.join("model-size.png"),
        plot::Labels {
            title: "the chip's model: size against features (one flash slot = 384 KiB)",
            x: "features p",
            y: "model blob (KiB)",
            legend: plot::Legend::UpperLeft,
        },
        &[
            plot::Series {
                label: "f32".into(),
                points: trade
                    .iter()
                    .map(|t| (t.features as f64, kib(t.f32_bytes)))
                    .collect(),
                scatter: false,
            },
            plot::Series {
                label: "f16".into(),
                points: trade
                    .iter()
                    .map(|t| (t.features as f64, kib(t.f16_bytes)))
                    .collect(),
                scatter: false,
            },
            plot::Series {
                label: "one slot".into(),
                points: vec![
                    (trade.first().map_or(0.0, |t| t.features as f64), slot),
                    (r.features as f64, slot),
                ],
                scatter: false,
            },
        ],
    )?;
    Ok(())
}

/// The section's text: the set-up, the models' table, error by distance, the chip's model.
fn markdown(r: &Learning, sizes: &Sizes) -> String {
    let (classes, rows) = (r.classes, r.rows);
    let mut md = String::from("## 1. Touch classification (docs/method.md §9)\n\n");
    let _ = writeln!(
        md,
        "Sheet: `{}` ({}). {classes} classes ({rows} x {rows} grid), finger radius {:.1} mm, \
         pressure 5 to 60 kPa. Training: T = {} visits x S_num = {} scans x S_sub = 20 \
         sub-section medians = {} observations per class; each visit a new measurement set \
         (the sheet left mounted, junction potentials and conductance redrawn, \
         docs/calibration.md) with the untouched frame taken at its start; each press lands \
         anywhere in its target, radius spread {:.0} %, the hand's force wandering {:.0} % \
         rms, the clips' junction potentials moving {:.0} uV at each press, creep {}, drift \
         {} within a visit. \
         Test: {} next-day session(s), 20 observations per class each, a new set again.\n",
        r.scene,
        r.description,
        r.radius * 1e3,
        sizes.visits,
        sizes.scans,
        r.observations_per_class,
        Plan::default().radius_spread * 100.0,
        Plan::default().wobble * 100.0,
        Plan::default().press_junction * 1e6,
        Plan::default().creep,
        Plan::default().drift,
        sizes.days
    );
    models_table(&mut md, &r.models);
    let _ = writeln!(
        md,
        "\nReferencing each frame to its session's untouched frame removes what moves from one \
         session to the next (the clips' junction potentials, the sheet's conductance); the \
         raw-frame model must have seen the next session's shift among its training \
         sessions'.\n\n\
         How to read the table: *shrinkage* is the weight that pulls each class's covariance \
         toward a common one (0: none), chosen by leave-one-visit-out cross-validation; \
         *10-fold CV* and *leave-one-visit-out* are accuracies on held-out training \
         observations (random folds, or a whole session held out); *next day* is the accuracy \
         on sessions the model never saw; *mean error* is the mean distance between the true \
         and the predicted class centre over all next-day observations (0 when right); *AEE*, \
         the aggregated estimation error of docs/method.md §9 [5.9-5.11], is the distances of \
         the wrong decisions summed and divided by the number of classes, per session.\n"
    );
    let _ = writeln!(
        md,
        "![confusion](learning/confusion.png)\n\n\
         How to read this: a row is the class pressed, a column the class the model answered \
         (classes numbered row by row over the grid); each row's cells are shares of its \
         observations and sum to 100 %. A perfect model lights only the diagonal; a lit cell \
         beside it is a neighbouring target taken for the one pressed.\n\n\
         ![error against distance](learning/error-vs-distance.png)\n\n\
         How to read this: each blue dot is one next-day observation (they overlap: a right \
         answer sits at 0 mm, a wrong one at the distance between the two class centres); the \
         orange line is the mean of each 10 mm band of distance from the nearest electrode. \
         The middle of the sheet, far from every electrode, is where the boundary voltages \
         change least for a press.\n"
    );
    let _ = writeln!(
        md,
        "Mean next-day error by distance from the nearest electrode:\n\n| distance | observations | accuracy | mean error |\n| --- | --- | --- | --- |"
    );
    for b in &r.qda.by_distance {
        let _ = writeln!(
            md,
            "| {:.0} to {:.0} mm | {} | {:.1} % | {:.2} mm |",
            b.from_mm,
            b.to_mm,
            b.count,
            100.0 * b.accuracy,
            b.mean_error_mm
        );
    }
    chip_markdown(&mut md, r);
    md
}

/// The models' table: each model's shrinkage, cross-validations and next-day results, or why
/// it could not be fitted.
fn models_table(md: &mut String, models: &[ModelRow]) {
    let _ = writeln!(
        md,
        "| model | shrinkage | 10-fold CV | leave-one-visit-out | next day | mean error | AEE |\n| --- | --- | --- | --- | --- | --- | --- |"
    );
    for m in models {
        match (&m.result, &m.error) {
            (Some(t), _) => {
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.1} % | {} | **{:.1} %** | {:.2} mm | {:.1} mm |",
                    m.name,
                    t.shrinkage,
                    100.0 * t.cv_accuracy,
                    t.leave_one_visit_out
                        .map_or("-".into(), |a| format!("{:.1} %", 100.0 * a)),
                    100.0 * t.next_day_accuracy,
                    t.next_day_mean_error_mm,
                    t.aee_mm,
                );
            }
            (None, e) => {
                let _ = writeln!(
                    md,
                    "| {} | - | cannot be fitted: {} | | | | |",
                    m.name,
                    e.as_deref().unwrap_or("")
                );
            }
        }
    }
}

/// "The model on the chip": the feature trade's table and the chip's model checked in
/// et-core.
fn chip_markdown(md: &mut String, r: &Learning) {
    let classes = r.classes;
    let _ = writeln!(
        md,
        "\n### The model on the chip\n\nA QDA of {classes} classes over all {} features \
         needs {:.0} KiB in f32: more than a flash slot (384 KiB). Keeping the features of \
         largest Fisher ratio trades accuracy for size:\n\n| features | next day | f16 blob | f32 blob |\n| --- | --- | --- | --- |",
        r.features,
        r.features_trade
            .last()
            .map_or(0.0, |t| t.f32_bytes as f64 / 1024.0)
    );
    let fits = |b: usize| {
        if b <= MODEL_SLOT_BYTES {
            format!("{:.0} KiB", b as f64 / 1024.0)
        } else {
            format!("{:.0} KiB (too big)", b as f64 / 1024.0)
        }
    };
    for t in &r.features_trade {
        let _ = writeln!(
            md,
            "| {} | {:.1} % | {} | {} |",
            t.features,
            100.0 * t.next_day_accuracy,
            fits(t.f16_bytes),
            fits(t.f32_bytes)
        );
    }
    if let Some(c) = &r.chip {
        let _ = writeln!(
            md,
            "\n`learning/model.etm` ({} features, f16, {} bytes) classified every next-day \
             frame through `et_core::model`, as the firmware does: **{:.1} %** right, {} of {} \
             decisions differ from the f64 host model. Upload it with \
             `et upload --port PORT --blob learning/model.etm`.\n",
            c.features,
            c.bytes,
            100.0 * c.accuracy(),
            c.disagree_with_host,
            c.total
        );
    }
    let _ = writeln!(
        md,
        "![features](learning/features.png)\n\n\
         How to read this: the same QDA trained on the p features of largest Fisher ratio \
         (the spread of the class means over the spread within the classes), tested on the \
         next-day sessions; the vertical axis spans the data, not 0 to 100 %.\n\n\
         ![model size](learning/model-size.png)\n\n\
         How to read this: the blob `et export` writes for the board, by the number of features \
         kept and the precision of its tables; a model fits the board when its line is under \
         the flash slot's (it grows as 49 classes x p^2 / 2 numbers).\n"
    );
}
