//! The demo's first stage: touch classification on the default sheet, trained, cross-validated,
//! tested the next day and run through et-core as the chip runs it.

use super::*;
use et_learn::dataset::Dataset;
use et_learn::model::Board;

mod written;
use written::{figures, markdown};

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
