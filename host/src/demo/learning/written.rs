//! The learning section as written: its figures and its text.

use super::*;

/// The section's figures: the next day's confusion and error against distance, and the
/// feature trade (accuracy, and the blob's size against a flash slot).
pub(super) fn figures(dir: &Path, r: &Learning) -> Result<()> {
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
pub(super) fn markdown(r: &Learning, sizes: &Sizes) -> String {
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
