//! The demo's first stage: touch classification on the default sheet, trained, cross-validated,
//! tested the next day and run through et-core as the chip runs it.

use super::*;

/// The headline numbers of the learning section.
pub(super) struct LearningKey {
    pub(super) next_day: f64,
    /// None when docs/method.md §9's raw-frame QDA cannot be fitted (too few observations per class).
    pub(super) raw: Option<f64>,
    pub(super) cv: f64,
    pub(super) chip: Option<(usize, usize, f64)>,
}

pub(super) fn learning(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<LearningKey>> {
    let scene = load(DEFAULT_SCENE)?;
    let config = collect::training_config(scene.scan_config()?);
    // docs/method.md §9: 49 classes with a 15 mm target on the 13 cm sheet.
    let (rows, radius) = (7, 0.0075);
    let centres = collect::grid(&scene.sheet, rows, rows, 0.0);
    let classes = centres.len();
    let plan = Plan {
        visits: 1,
        scans: sizes.scans,
        radius,
        placement: radius / 4.0,
        ..Plan::default()
    };
    let bar = steps.bar(sizes.visits + sizes.days, "collecting (visits, next days)");
    let mut train: Option<Dataset> = None;
    for v in 0..sizes.visits {
        let part = collect::collect(
            &scene.sheet,
            scene.frontend,
            config,
            &centres,
            &Plan {
                seed: 1_000 + v as u64,
                ..plan.clone()
            },
        )?;
        match train.as_mut() {
            None => train = Some(part),
            Some(d) => d.append(part)?,
        }
        bar.inc(1);
    }
    let train = train.context("no visit collected")?;
    let mut days = Vec::new();
    for d in 0..sizes.days {
        let day = Plan {
            scans: 1,
            seed: 77 + d as u64,
            ..plan.clone()
        };
        days.push(collect::collect(
            &scene.sheet,
            scene.frontend,
            config,
            &centres,
            &day,
        )?);
        bar.inc(1);
    }
    let mut next_day = days.remove(0);
    for d in days {
        next_day.append(d)?;
    }
    let n_c = train.x.nrows() / classes;
    steps.done(
        &bar,
        &format!(
            "collected {} training and {} next-day observations",
            train.x.nrows(),
            next_day.x.nrows()
        ),
    );

    // The model: QDA on referenced frames, shrinkage by leave-one-visit-out.
    let bar = steps.bar(3, "training (QDA, raw QDA, LDA)");
    let mm: Vec<[f64; 2]> = centres.iter().map(|c| [c[0] * 1e3, c[1] * 1e3]).collect();
    let fit = |referenced: bool, kind: ModelKind, shrinkage: Option<f64>, keep: Option<usize>| {
        let mut data = train.clone();
        pipeline::prepare(&mut data, referenced, keep)?;
        let t = pipeline::train(
            &data,
            &TrainOptions {
                kind,
                shrinkage,
                folds: 10,
            },
        )?;
        let file = ModelFile::new(
            &t.model,
            t.options.shrinkage,
            data.config,
            data.feature_index.clone(),
            mm.clone(),
            referenced,
        );
        let tested = pipeline::test(&file, &next_day)?;
        anyhow::Ok((t, file, tested))
    };
    let (qda, qda_file, qda_test) = fit(true, ModelKind::Qda, None, None)?;
    bar.inc(1);
    // docs/method.md §9 as published: QDA on the raw frames, no shrinkage.
    let raw = fit(false, ModelKind::Qda, Some(0.0), None);
    bar.inc(1);
    let (lda, _, lda_test) = fit(true, ModelKind::Lda, None, None)?;
    steps.done(&bar, "trained QDA and LDA, cross-validated");
    qda_file.save(&out.join("learning/model.json"))?;

    // The trade: features kept (Fisher ranking) against accuracy and the chip's model size.
    let p_all = train.x.ncols();
    let keeps: Vec<usize> = [8, 16, 24, 32, 48, 64, 80]
        .into_iter()
        .filter(|&p| p < p_all)
        .chain([p_all])
        .collect();
    let bar = steps.bar(keeps.len(), "features against accuracy and size");
    let mut trade = Vec::new();
    for &p in &keeps {
        let (_, file, tested) = fit(true, ModelKind::Qda, Some(qda.options.shrinkage), Some(p))?;
        let f16 = file.blob(Precision::F16)?.len();
        let f32 = file.blob(Precision::F32)?.len();
        trade.push((p, tested.confusion.accuracy(), f16, f32, file));
        bar.inc(1);
    }
    // The chip's model: the most features whose f16 blob fits a slot, run through et-core.
    let chip = trade
        .iter()
        .filter(|t| t.2 <= MODEL_SLOT_BYTES)
        .max_by_key(|t| t.0)
        .map(|(p, _, f16, _, file)| -> Result<_> {
            let blob = file.blob(Precision::F16)?;
            std::fs::write(out.join("learning/model.etm"), &blob)
                .context("writing learning/model.etm")?;
            let r = pipeline::on_chip(file, &blob, &next_day)?;
            Ok((*p, *f16, r))
        })
        .transpose()?;
    steps.done(
        &bar,
        "feature trade curve; the chip's model checked in et-core",
    );

    // Figures.
    let dir = out.join("learning");
    plot::confusion(
        &dir.join("confusion.png"),
        &qda_test.confusion,
        &format!(
            "next day: accuracy {:.1} %, {} observations",
            100.0 * qda_test.confusion.accuracy(),
            qda_test.confusion.total()
        ),
    )?;
    plot::error_vs_distance(&dir.join("error-vs-distance.png"), &qda_test)?;
    plot::chart(
        &dir.join("features.png"),
        plot::Labels {
            title: "QDA: features kept against next-day accuracy",
            x: "features p (largest Fisher ratio first)",
            y: "next-day accuracy (%)",
            legend: plot::Legend::LowerRight,
        },
        &[plot::Series {
            label: format!("{classes} classes"),
            points: trade.iter().map(|t| (t.0 as f64, 100.0 * t.1)).collect(),
            scatter: false,
        }],
    )?;
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
                    .map(|t| (t.0 as f64, t.3 as f64 / 1024.0))
                    .collect(),
                scatter: false,
            },
            plot::Series {
                label: "f16".into(),
                points: trade
                    .iter()
                    .map(|t| (t.0 as f64, t.2 as f64 / 1024.0))
                    .collect(),
                scatter: false,
            },
            plot::Series {
                label: "one slot".into(),
                points: vec![
                    (trade[0].0 as f64, MODEL_SLOT_BYTES as f64 / 1024.0),
                    (p_all as f64, MODEL_SLOT_BYTES as f64 / 1024.0),
                ],
                scatter: false,
            },
        ],
    )?;

    // Text.
    let raw_acc = raw.as_ref().ok().map(|(_, _, t)| t.confusion.accuracy());
    let lovo = qda.leave_one_visit_out.unwrap_or(f64::NAN);
    let mut md = String::from("## 1. Touch classification (docs/method.md §9)\n\n");
    let _ = writeln!(
        md,
        "Sheet: `{}` ({}). {classes} classes ({rows} x {rows} grid), finger radius {:.1} mm, \
         pressure 5 to 60 kPa. Training: T = {} visits x S_num = {} scans x S_sub = 20 \
         sub-section medians = {n_c} observations per class, electrodes moved 0.5 mm rms \
         between visits, the untouched frame taken at the start of each visit. Test: {} next-day \
         session(s), 20 observations per class each, electrodes moved again.\n",
        DEFAULT_SCENE.0,
        scene.description,
        radius * 1e3,
        sizes.visits,
        sizes.scans,
        sizes.days
    );
    let _ = writeln!(
        md,
        "| model | shrinkage | 10-fold CV | leave-one-visit-out | next day | mean error | AEE |\n| --- | --- | --- | --- | --- | --- | --- |"
    );
    let row = |md: &mut String, name: &str, t: &pipeline::Trained, tested: &pipeline::Tested| {
        let _ = writeln!(
            md,
            "| {name} | {} | {:.1} % | {} | **{:.1} %** | {:.2} mm | {:.1} mm |",
            t.options.shrinkage,
            100.0 * t.cv.accuracy(),
            t.leave_one_visit_out
                .map_or("-".into(), |a| format!("{:.1} %", 100.0 * a)),
            100.0 * tested.confusion.accuracy(),
            tested.confusion.mean_position_error(&mm),
            tested.confusion.aee(&mm) / sizes.days as f64,
        );
    };
    row(
        &mut md,
        "QDA, referenced frames (V_m - V_0)",
        &qda,
        &qda_test,
    );
    row(&mut md, "LDA, referenced frames", &lda, &lda_test);
    match &raw {
        Ok((t, _, tested)) => row(
            &mut md,
            "QDA on raw frames (docs/method.md §9 as published)",
            t,
            tested,
        ),
        Err(e) => {
            let _ = writeln!(
                md,
                "| QDA on raw frames (docs/method.md §9) | - | cannot be fitted: {e} | | | | |"
            );
        }
    }
    let _ = writeln!(
        md,
        "\nReferencing each frame to its session's untouched frame is what survives the \
         electrodes moving between sessions; the raw-frame model learns the training \
         sessions' electrode positions. AEE is docs/method.md §9's [5.9-5.11], per session.\n"
    );
    let _ = writeln!(
        md,
        "![confusion](learning/confusion.png)\n\n![error against distance](learning/error-vs-distance.png)\n"
    );
    let _ = writeln!(
        md,
        "Mean next-day error by distance from the nearest electrode:\n\n| distance | observations | accuracy | mean error |\n| --- | --- | --- | --- |"
    );
    for b in &qda_test.bands {
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
    let _ = writeln!(
        md,
        "\n### The model on the chip\n\nA QDA of {classes} classes over all {p_all} features \
         needs {:.0} KiB in f32: more than a flash slot (384 KiB). Keeping the features of \
         largest Fisher ratio trades accuracy for size:\n\n| features | next day | f16 blob | f32 blob |\n| --- | --- | --- | --- |",
        trade.last().map_or(0.0, |t| t.3 as f64 / 1024.0)
    );
    for t in &trade {
        let fits = |b: usize| {
            if b <= MODEL_SLOT_BYTES {
                format!("{:.0} KiB", b as f64 / 1024.0)
            } else {
                format!("{:.0} KiB (too big)", b as f64 / 1024.0)
            }
        };
        let _ = writeln!(
            md,
            "| {} | {:.1} % | {} | {} |",
            t.0,
            100.0 * t.1,
            fits(t.2),
            fits(t.3)
        );
    }
    if let Some((p, bytes, r)) = &chip {
        let _ = writeln!(
            md,
            "\n`learning/model.etm` ({p} features, f16, {bytes} bytes) classified every next-day \
             frame through `et_core::model`, as the firmware does: **{:.1} %** right, {} of {} \
             decisions differ from the f64 host model. Upload it with \
             `et upload --port PORT --blob learning/model.etm`.\n",
            100.0 * r.right as f64 / r.total.max(1) as f64,
            r.disagree,
            r.total
        );
    }
    let _ = writeln!(
        md,
        "![features](learning/features.png)\n\n![model size](learning/model-size.png)\n"
    );
    let json = json!({
        "scene": DEFAULT_SCENE.0,
        "classes": classes,
        "observations_per_class": n_c,
        "next_day_observations": next_day.x.nrows(),
        "qda": {
            "shrinkage": qda.options.shrinkage,
            "cv_accuracy": qda.cv.accuracy(),
            "leave_one_visit_out": lovo,
            "next_day_accuracy": qda_test.confusion.accuracy(),
            "next_day_mean_error_mm": qda_test.confusion.mean_position_error(&mm),
            "by_distance": qda_test.bands,
        },
        "lda_next_day_accuracy": lda_test.confusion.accuracy(),
        "raw_qda_next_day_accuracy": raw_acc,
        "features_trade": trade.iter().map(|t| json!({
            "features": t.0, "next_day_accuracy": t.1, "f16_bytes": t.2, "f32_bytes": t.3,
        })).collect::<Vec<_>>(),
        "chip": chip.as_ref().map(|(p, bytes, r)| json!({
            "features": p, "bytes": bytes, "right": r.right, "total": r.total, "disagree_with_host": r.disagree,
        })),
    });
    Ok(Section {
        markdown: md,
        json,
        key: LearningKey {
            next_day: qda_test.confusion.accuracy(),
            raw: raw_acc,
            cv: qda.cv.accuracy(),
            chip: chip
                .as_ref()
                .map(|(p, b, r)| (*p, *b, r.right as f64 / r.total.max(1) as f64)),
        },
    })
}
