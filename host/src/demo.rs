//! `et demo`: the whole method on the simulated sheet, no hardware, into a report folder.
//!
//! 1. **Touch classification** (SPEC §9) on the default 13 x 13 cm, 16-electrode sheet: a
//!    training set collected as the method prescribes, QDA trained and cross-validated, then
//!    tested on three "next day" sessions (electrodes moved, pressure unknown); the model
//!    shrunk to fit the board's flash and run through et-core exactly as the firmware runs it.
//! 2. **Imaging** the reference scenarios of SPEC §7 (22 cm disc) with every protocol,
//!    one-step Gauss-Newton with the complete electrode model, SPEC §7's metrics and SPEC §8's
//!    dynamic choice of protocol.
//! 3. **Speed against accuracy**: mesh size against forward error, position error and set-up
//!    time, one-step against iterative Gauss-Newton, and the live frame's cost.
//!
//! Everything measured comes from the pipeline as the `et` commands run it (`learn::pipeline`,
//! `imaging`); the report states the machine and the command. The scenes are compiled in, so
//! the demo runs from any directory.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use et_core::ScanConfig;
use et_core::model::{ModelKind, Precision};
use et_core::protocol::{Protocol, ProtocolKind};
use et_sim::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use serde_json::json;

use crate::dynamic::{Settings, significant};
use crate::imaging::{Imager, scene_frames_on, simulated_sheet};
use crate::learn::collect::{self, Dataset, Plan};
use crate::learn::model_file::ModelFile;
use crate::learn::pipeline::{self, MODEL_SLOT_BYTES, TrainOptions};
use crate::mesh::Mesh;
use crate::plot;
use crate::recon::{
    self, Data, GaussNewton, OneStep, PROMINENCE, TOUCH_Z, above_noise, default_threshold, metrics,
    regions, touches,
};

/// The default sheet (SPEC §1): 13 x 13 cm, 16 electrodes.
pub const DEFAULT_SCENE: (&str, &str) = (
    "square-13cm-16.toml",
    include_str!("../../sim/scenes/square-13cm-16.toml"),
);

/// SPEC §7's reference scenarios: 22 cm disc, one target at x = 0.75, 0.5, 0.25, 0 of the
/// radius, and two at x = -0.5 and 0.5.
pub const REFERENCE_SCENES: [(&str, &str); 5] = [
    (
        "disc-ref-x075.toml",
        include_str!("../../sim/scenes/disc-ref-x075.toml"),
    ),
    (
        "disc-ref-x050.toml",
        include_str!("../../sim/scenes/disc-ref-x050.toml"),
    ),
    (
        "disc-ref-x025.toml",
        include_str!("../../sim/scenes/disc-ref-x025.toml"),
    ),
    (
        "disc-ref-x000.toml",
        include_str!("../../sim/scenes/disc-ref-x000.toml"),
    ),
    (
        "disc-ref-two.toml",
        include_str!("../../sim/scenes/disc-ref-two.toml"),
    ),
];

/// What to run.
#[derive(Clone, Debug)]
pub struct Options {
    /// The report folder (created; files in it are overwritten).
    pub out: PathBuf,
    /// Small sizes everywhere (a smoke test, about 10 s): fewer scans and visits, coarser
    /// meshes. The numbers are then not the ones to quote.
    pub quick: bool,
    /// Show progress bars on stderr.
    pub progress: bool,
    /// The command line, for the report.
    pub command: String,
}

/// Sizes of one run.
#[derive(Clone, Copy, Debug, Serialize)]
struct Sizes {
    /// Training visits T and scans per class per visit S_num.
    visits: usize,
    scans: usize,
    /// Next-day sessions.
    days: usize,
    /// Triangles of the imaging mesh.
    triangles: usize,
    /// Meshes of the sweep, and its reference mesh.
    sweep: &'static [usize],
    sweep_reference: usize,
    /// Largest mesh the iterative Gauss-Newton runs on.
    iterative_up_to: usize,
}

const FULL: Sizes = Sizes {
    visits: 6,
    scans: 20,
    days: 3,
    triangles: 8_000,
    sweep: &[1_000, 2_000, 4_000, 8_000, 16_000],
    sweep_reference: 32_000,
    iterative_up_to: 8_500,
};

const QUICK: Sizes = Sizes {
    visits: 2,
    scans: 2,
    days: 1,
    triangles: 2_000,
    sweep: &[500, 1_000],
    sweep_reference: 2_000,
    iterative_up_to: 1_200,
};

/// What the demo wrote.
#[derive(Clone, Debug)]
pub struct Report {
    /// The Markdown page.
    pub index: PathBuf,
    /// Every number, as JSON (also written as `summary.json`).
    pub summary: serde_json::Value,
}

/// Progress on stderr: a bar per stage, a line when it ends.
struct Steps {
    show: bool,
    started: Instant,
}

impl Steps {
    fn bar(&self, len: usize, what: &str) -> ProgressBar {
        if !self.show {
            return ProgressBar::hidden();
        }
        let style = ProgressStyle::with_template("{prefix:<34} [{bar:30}] {pos}/{len} (eta {eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar());
        ProgressBar::new(len as u64)
            .with_style(style)
            .with_prefix(what.to_string())
    }

    fn done(&self, bar: &ProgressBar, what: &str) {
        bar.finish_and_clear();
        if self.show {
            eprintln!("{what:<60} {:>6.1} s", self.started.elapsed().as_secs_f64());
        }
    }
}

/// Runs the demo into `options.out`.
///
/// # Errors
/// When the folder cannot be written, or a stage fails (with the stage named).
pub fn run(options: &Options) -> Result<Report> {
    let started = Instant::now();
    let sizes = if options.quick { QUICK } else { FULL };
    let out = &options.out;
    for dir in ["", "learning", "imaging", "sweep"] {
        std::fs::create_dir_all(out.join(dir))
            .with_context(|| format!("creating {}", out.join(dir).display()))?;
    }
    let steps = Steps {
        show: options.progress,
        started,
    };
    let learning = learning(out, &sizes, &steps).context("touch classification")?;
    let imaging = imaging(out, &sizes, &steps).context("imaging the reference scenarios")?;
    let sweep = sweep(out, &sizes, &steps).context("the speed/accuracy sweep")?;
    let seconds = started.elapsed().as_secs_f64();
    let machine = machine();
    let summary = json!({
        "command": options.command,
        "quick": options.quick,
        "sizes": sizes,
        "machine": machine,
        "date_utc": today_utc(),
        "seconds": seconds,
        "learning": learning.json,
        "imaging": imaging.json,
        "sweep": sweep.json,
    });
    let json_path = out.join("summary.json");
    std::fs::write(&json_path, serde_json::to_string_pretty(&summary)?)
        .with_context(|| format!("writing {}", json_path.display()))?;
    let mut page = String::new();
    let _ = writeln!(page, "# et demo report\n");
    let _ = writeln!(
        page,
        "Produced by `{}` (et {}) on {} UTC in {seconds:.0} s, on {machine}.{}\n",
        options.command,
        env!("CARGO_PKG_VERSION"),
        today_utc(),
        if options.quick {
            " **Quick mode: small sizes, not the numbers to quote.**"
        } else {
            ""
        }
    );
    let _ = writeln!(
        page,
        "Every frame comes from the simulated sheet (et-sim's resistor network with calibrated \
         noise); the host images with its own finite elements, never the simulator's model. \
         Every number below is in `summary.json`.\n"
    );
    page.push_str(&summary_table(&learning, &imaging, &sweep));
    page.push_str(&learning.markdown);
    page.push_str(&imaging.markdown);
    page.push_str(&sweep.markdown);
    let index = out.join("index.md");
    std::fs::write(&index, page).with_context(|| format!("writing {}", index.display()))?;
    Ok(Report { index, summary })
}

/// One section of the report.
struct Section<T> {
    markdown: String,
    json: serde_json::Value,
    key: T,
}

/// The headline numbers of the learning section.
struct LearningKey {
    next_day: f64,
    /// None when SPEC §9's raw-frame QDA cannot be fitted (too few observations per class).
    raw: Option<f64>,
    cv: f64,
    chip: Option<(usize, usize, f64)>,
}

/// The headline numbers of the imaging section.
struct ImagingKey {
    /// (found within the touch radius, single-touch images).
    single: (usize, usize),
    /// (found as exactly one touch, within its radius; single-touch images).
    one_touch: (usize, usize),
    /// The same for the protocol SPEC §8 chooses from the AD image of each single touch.
    chosen: (usize, usize),
    /// Protocols that found the two touches as two touches, each within its radius.
    two: Vec<&'static str>,
}

/// The headline numbers of the sweep.
struct SweepKey {
    /// (triangles, set-up s, live frame us) of the mesh nearest 8 000 triangles.
    at_8k: Option<(usize, f64, f64)>,
}

fn summary_table(
    learning: &Section<LearningKey>,
    imaging: &Section<ImagingKey>,
    sweep: &Section<SweepKey>,
) -> String {
    let mut s = String::from(
        "## At a glance\n\n| what | result | reference (SPEC §10) |\n| --- | --- | --- |\n",
    );
    let l = &learning.key;
    let _ = writeln!(
        s,
        "| next-day accuracy, 49 classes, QDA on referenced frames | **{:.1} %** | 91.6 % |",
        100.0 * l.next_day
    );
    let _ = writeln!(
        s,
        "| the same with SPEC §9's QDA on raw frames | {} | 91.6 % |",
        l.raw
            .map_or("cannot be fitted".into(), |a| format!("{:.1} %", 100.0 * a))
    );
    let _ = writeln!(
        s,
        "| 10-fold cross-validation (training set) | {:.1} % | |",
        100.0 * l.cv
    );
    if let Some((p, bytes, acc)) = l.chip {
        let _ = writeln!(
            s,
            "| on the chip: {p} features, f16, {bytes} bytes, through et-core | {:.1} % | |",
            100.0 * acc
        );
    }
    let i = &imaging.key;
    let _ = writeln!(
        s,
        "| single touch: ROI centroid within the touch radius (SPEC §7) | {} of {} images | |",
        i.single.0, i.single.1
    );
    let _ = writeln!(
        s,
        "| single touch: found as one touch, within its radius | {} of {} images | |",
        i.one_touch.0, i.one_touch.1
    );
    let _ = writeln!(
        s,
        "| ... with the protocol SPEC §8 chooses from the AD image | {} of {} touches | |",
        i.chosen.0, i.chosen.1
    );
    let _ = writeln!(
        s,
        "| two touches found as two touches | {} | |",
        if i.two.is_empty() {
            "no protocol".to_string()
        } else {
            i.two.join(", ")
        }
    );
    if let Some((t, setup, live)) = sweep.key.at_8k {
        let _ = writeln!(
            s,
            "| set-up at {t} triangles (mesh, forward, Jacobian, one-step matrix) | {setup:.3} s | |"
        );
        let _ = writeln!(
            s,
            "| live frame onto the mesh at {t} triangles | {live:.0} us ({:.0} frames/s) | about 30 Hz |",
            1e6 / live
        );
    }
    s.push('\n');
    s
}

fn load(scene: (&str, &str)) -> Result<Scene> {
    Scene::parse(scene.1, scene.0).map_err(|e| anyhow!("{e}"))
}

// ----------------------------------------------------------------------------------------
// 1. Touch classification

fn learning(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<LearningKey>> {
    let scene = load(DEFAULT_SCENE)?;
    let config = collect::training_config(scene.scan_config().map_err(|e| anyhow!(e))?);
    // SPEC §9: 49 classes with a 15 mm target on the 13 cm sheet.
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
        )
        .map_err(|e| anyhow!(e))?;
        match train.as_mut() {
            None => train = Some(part),
            Some(d) => d.append(part).map_err(|e| anyhow!(e))?,
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
        days.push(
            collect::collect(&scene.sheet, scene.frontend, config, &centres, &day)
                .map_err(|e| anyhow!(e))?,
        );
        bar.inc(1);
    }
    let mut next_day = days.remove(0);
    for d in days {
        next_day.append(d).map_err(|e| anyhow!(e))?;
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
        pipeline::prepare(&mut data, referenced, keep).map_err(|e| anyhow!(e))?;
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
        let tested = pipeline::test(&file, &next_day).map_err(|e| anyhow!(e))?;
        anyhow::Ok((t, file, tested))
    };
    let (qda, qda_file, qda_test) = fit(true, ModelKind::Qda, None, None)?;
    bar.inc(1);
    // SPEC §9 as published: QDA on the raw frames, no shrinkage.
    let raw = fit(false, ModelKind::Qda, Some(0.0), None);
    bar.inc(1);
    let (lda, _, lda_test) = fit(true, ModelKind::Lda, None, None)?;
    steps.done(&bar, "trained QDA and LDA, cross-validated");
    qda_file
        .save(&out.join("learning/model.json"))
        .map_err(|e| anyhow!(e))?;

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
            let r = pipeline::on_chip(file, &blob, &next_day).map_err(|e| anyhow!(e))?;
            Ok((*p, *f16, r))
        })
        .transpose()?;
    steps.done(
        &bar,
        "feature trade curve; the chip's model checked in et-core",
    );

    // Figures.
    let dir = out.join("learning");
    pipeline::plot_confusion(
        &dir.join("confusion.png"),
        &qda_test.confusion,
        &format!(
            "next day: accuracy {:.1} %, {} observations",
            100.0 * qda_test.confusion.accuracy(),
            qda_test.confusion.total()
        ),
    )?;
    pipeline::plot_error_vs_distance(&dir.join("error-vs-distance.png"), &qda_test)?;
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
    let mut md = String::from("## 1. Touch classification (SPEC §9)\n\n");
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
            "QDA on raw frames (SPEC §9 as published)",
            t,
            tested,
        ),
        Err(e) => {
            let _ = writeln!(
                md,
                "| QDA on raw frames (SPEC §9) | - | cannot be fitted: {e} | | | | |"
            );
        }
    }
    let _ = writeln!(
        md,
        "\nReferencing each frame to its session's untouched frame is what survives the \
         electrodes moving between sessions; the raw-frame model learns the training \
         sessions' electrode positions. AEE is SPEC §9's [5.9-5.11], per session.\n"
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

// ----------------------------------------------------------------------------------------
// 2. Imaging

/// Short names for the protocols, as the report shows them.
fn short(kind: ProtocolKind) -> &'static str {
    match kind {
        ProtocolKind::Adjacent => "AD",
        ProtocolKind::PseudoPolar => "PP",
        ProtocolKind::PpPp => "PP-PP",
        ProtocolKind::Opposite => "opposite",
        ProtocolKind::Custom(_) => "custom",
    }
}

fn imaging(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<ImagingKey>> {
    let scenes: Vec<(&str, Scene)> = REFERENCE_SCENES
        .iter()
        .map(|&s| Ok((s.0.trim_end_matches(".toml"), load(s)?)))
        .collect::<Result<_>>()?;
    let sheet_spec = &scenes[0].1.sheet;
    if scenes.iter().any(|(_, s)| &s.sheet != sheet_spec) {
        return Err(anyhow!("the reference scenes differ in their sheet"));
    }
    let bar = steps.bar(
        1 + ProtocolKind::NAMED.len() * (1 + scenes.len()),
        "imaging SPEC §7 scenes",
    );
    let mesh = Mesh::with_about(sheet_spec, sizes.triangles)?;
    let imager = Imager::new(sheet_spec, mesh, 64)?;
    let sheet = simulated_sheet(&scenes[0].1)?;
    bar.inc(1);
    // SPEC §8's d_c: from the sheet's centre to its outline (where the electrodes are).
    let b = sheet_spec.shape.bounds();
    let centre = [0.5 * (b[0] + b[2]), 0.5 * (b[1] + b[3])];
    let settings = Settings::new(centre, sheet_spec.shape.distance_to_outline(centre));
    let mut rows = Vec::new();
    let mut single = (0, 0);
    let mut one_touch = (0, 0);
    let mut two = Vec::new();
    let mut decisions = Vec::new();
    for kind in ProtocolKind::NAMED {
        let base = scenes[0].1.scan_config().map_err(|e| anyhow!(e))?;
        let config = ScanConfig {
            protocol: kind,
            ..base
        };
        let protocol = config.validate().map_err(|e| anyhow!("{e}"))?;
        let amps = f64::from(config.current_amps());
        let jac = imager.jacobian(&protocol, amps)?;
        bar.inc(1);
        let f = default_threshold(kind);
        for (name, scene) in &scenes {
            let frames = scene_frames_on(&sheet, scene, &config, 10)?;
            let dv = frames.dv();
            // alpha by generalised cross-validation on the frame, as `et reconstruct`.
            let grid_alpha: Vec<f64> = (0..=25)
                .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
                .collect();
            let alpha = recon::gcv_alpha(&jac, 0.5, &dv, &grid_alpha)?.0;
            let recon = OneStep::new(&jac, alpha, 0.5)?;
            let image = imager.grid.image(&recon.reconstruct(&dv)?);
            let rois = regions(&imager.grid, &image, f);
            // Touches: the regions split at their saddles, standing out of the noise
            // (estimated from the reference frames), then SPEC §8's significance.
            let sd = imager.grid.image(&recon.noise_sd(&frames.var)?);
            let counted = significant(
                &above_noise(&touches(&imager.grid, &image, &sd, f, PROMINENCE), TOUCH_Z),
                &settings,
            );
            let png = format!("imaging/{name}-{}.png", kind.name());
            imager.write_png(
                &out.join(&png),
                &format!(
                    "{name}, {}: {} touches (f = {f})",
                    short(kind),
                    counted.len()
                ),
                &image,
            )?;
            // Each touch: the nearest significant region's centroid, and whether it lies
            // within the touch's radius.
            let per_touch: Vec<(f64, bool)> = frames
                .truth
                .iter()
                .map(|&(c, r)| {
                    let off = counted
                        .iter()
                        .map(|g| (g.centroid[0] - c[0]).hypot(g.centroid[1] - c[1]))
                        .fold(f64::INFINITY, f64::min);
                    (off, off < r)
                })
                .collect();
            let (c, r) = frames.truth[0];
            let m = metrics(
                &imager.grid,
                &image,
                f,
                &dv,
                c,
                std::f64::consts::PI * r * r,
            );
            if frames.truth.len() == 1 {
                single.1 += 1;
                // The strongest region is the detection (SPEC §7's PE).
                let found = rois
                    .first()
                    .is_some_and(|g| (g.centroid[0] - c[0]).hypot(g.centroid[1] - c[1]) < r);
                single.0 += usize::from(found);
                one_touch.1 += 1;
                one_touch.0 += usize::from(counted.len() == 1 && per_touch[0].1);
            } else if counted.len() == frames.truth.len() && per_touch.iter().all(|t| t.1) {
                two.push(short(kind));
            }
            if kind == ProtocolKind::Adjacent {
                decisions.push((
                    *name,
                    crate::dynamic::decide(&counted, &settings),
                    counted.len(),
                ));
            }
            rows.push(json!({
                "scene": name,
                "protocol": kind.name(),
                "alpha": alpha,
                "threshold": f,
                "regions": counted.len(),
                "touch_offsets_mm": per_touch.iter().map(|t| t.0 * 1e3).collect::<Vec<_>>(),
                "found_within_radius": per_touch.iter().map(|t| t.1).collect::<Vec<_>>(),
                "metrics": m,
                "png": png,
            }));
            bar.inc(1);
        }
    }
    steps.done(&bar, "imaged 5 scenes x 4 protocols");
    // Each single touch, imaged with the protocol SPEC §8 chose for it.
    let mut chosen = (0, 0);
    for (name, kind, _) in &decisions {
        let found = rows.iter().find(|r| {
            r["scene"] == *name
                && kind.is_some_and(|k| r["protocol"] == k.name())
                && r["found_within_radius"]
                    .as_array()
                    .is_some_and(|a| a.len() == 1)
        });
        if let Some(r) = found {
            chosen.1 += 1;
            chosen.0 += usize::from(r["found_within_radius"][0] == true);
        }
    }

    let mut md = String::from("## 2. Imaging the reference scenarios (SPEC §7)\n\n");
    let _ = writeln!(
        md,
        "22 cm disc, 16 electrodes, targets of 1.46 % of the area at about 20 kPa. Frames: the \
         simulator's noisy frames (V_0 the mean of 10 untouched frames). Imaging: {} triangles, \
         complete electrode model, one-step Gauss-Newton with NOSER (s = 0.5, SPEC §6 [3.8-3.9]), \
         alpha by generalised cross-validation per frame, ROI threshold f per protocol as the \
         reference study (0.10 AD and opposite, 0.08 PP, 0.05 PP-PP). Colour: conductivity \
         change over the background. Touches: the regions of interest split at their saddles \
         (a peak stands apart when the dip below it is a quarter of the image's maximum, \
         `recon::touches`), kept when they reach 5 times their pixels' noise (the noise from \
         the spread of the reference frames through the reconstruction matrix, \
         `recon::above_noise`), and when their peak reaches half the strongest's and their area \
         a quarter of a 10 mm fingertip's (`dynamic::significant`). The \"touches\" columns \
         count these touches.\n",
        imager.triangles()
    );
    let _ = write!(md, "| scene |");
    for kind in ProtocolKind::NAMED {
        let _ = write!(md, " {} |", short(kind));
    }
    let _ = writeln!(md, "\n| --- | --- | --- | --- | --- |");
    for (name, _) in &scenes {
        let _ = write!(md, "| {name} |");
        for kind in ProtocolKind::NAMED {
            let _ = write!(
                md,
                " ![{name} {}](imaging/{name}-{}.png) |",
                short(kind),
                kind.name()
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "\n| scene | protocol | alpha | touches | distance of each true touch from the nearest found | PE | SE | RNG | BVC |\n| --- | --- | --- | --- | --- | --- | --- | --- | --- |"
    );
    for r in &rows {
        let offsets: Vec<String> = r["touch_offsets_mm"]
            .as_array()
            .into_iter()
            .flatten()
            .zip(r["found_within_radius"].as_array().into_iter().flatten())
            .map(|(o, ok)| {
                format!(
                    "{:.1} mm{}",
                    o.as_f64().unwrap_or(f64::NAN),
                    if ok.as_bool() == Some(true) {
                        " (within)"
                    } else {
                        " (outside)"
                    }
                )
            })
            .collect();
        let m = &r["metrics"];
        let _ = writeln!(
            md,
            "| {} | {} | {:.3} | {} | {} | {:.3} | {:.3} | {:.3} | {:.2e} V |",
            r["scene"].as_str().unwrap_or(""),
            r["protocol"].as_str().unwrap_or(""),
            r["alpha"].as_f64().unwrap_or(f64::NAN),
            r["regions"],
            offsets.join(", "),
            m["pe"].as_f64().unwrap_or(f64::NAN),
            m["se"].as_f64().unwrap_or(f64::NAN),
            m["rng"].as_f64().unwrap_or(f64::NAN),
            m["bvc"].as_f64().unwrap_or(f64::NAN),
        );
    }
    let _ = writeln!(
        md,
        "\nPE and SE are of the first touch; SE counts every region above the threshold.\n\n\
         **Dynamic protocol selection (SPEC §8)** on the AD image of each scene (xi = 0.5):\n\n\
         | scene | touches on AD | SPEC §8 switches to |\n| --- | --- | --- |"
    );
    for (name, d, n) in &decisions {
        let _ = writeln!(
            md,
            "| {name} | {n} | {} |",
            match d {
                None => "no touch seen".to_string(),
                Some(ProtocolKind::Adjacent) => "stays on AD".to_string(),
                Some(k) => short(*k).to_string(),
            }
        );
    }
    md.push('\n');
    let json = json!({
        "triangles": imager.triangles(),
        "single_touches_found": single,
        "single_touches_found_as_one_touch": one_touch,
        "single_touches_found_with_chosen_protocol": chosen,
        "two_touches_found_by": two,
        "images": rows,
        "dynamic": decisions.iter().map(|(n, d, c)| json!({
            "scene": n, "regions_on_adjacent": c, "switch_to": d.map(ProtocolKind::name),
        })).collect::<Vec<_>>(),
    });
    Ok(Section {
        markdown: md,
        json,
        key: ImagingKey {
            single,
            one_touch,
            chosen,
            two,
        },
    })
}

// ----------------------------------------------------------------------------------------
// 3. Speed against accuracy

/// One mesh of the sweep.
#[derive(Clone, Debug, Serialize)]
pub struct SweepRow {
    /// Triangles.
    pub triangles: usize,
    /// Largest difference of the untouched frame from the reference mesh's, relative to the
    /// largest voltage.
    pub forward_error: f64,
    /// Mesh + forward model + Jacobian + one-step matrix, s.
    pub setup_s: f64,
    /// One live frame onto the mesh (one matrix-vector product), median, us.
    pub live_frame_us: f64,
    /// PE of the one-step image.
    pub pe_one_step: f64,
    /// PE and time (s) of 4 iterative Gauss-Newton steps, where run.
    pub iterative: Option<(f64, f64)>,
}

/// The speed/accuracy sweep of imaging on SPEC §7's disc with the target at x = 0.5:
/// adjacent protocol, complete electrode model, noiseless simulator frames, alpha 0.03,
/// s = 0.5. Forward error against a mesh of `reference` triangles; the iterative
/// Gauss-Newton (4 steps) on meshes up to `iterative_up_to`. `tick` is called after each mesh.
///
/// # Errors
/// When a mesh, solve or reconstruction fails.
pub fn mesh_sweep(
    triangles: &[usize],
    reference: usize,
    iterative_up_to: usize,
    mut tick: impl FnMut(&SweepRow),
) -> Result<Vec<SweepRow>> {
    let scene = load(REFERENCE_SCENES[1])?;
    let protocol = Protocol::new(ProtocolKind::Adjacent, scene.sheet.electrodes.count)
        .map_err(|e| anyhow!("{e:?}"))?;
    let amps = 32e-6;
    let t = &scene.touches[0];
    let sheet = simulated_sheet(&scene)?;
    let mut sim = et_sim::frontend::SimFrontend::new(sheet, scene.frontend, 1)?;
    let v0 = sim.ideal_frame(&protocol, amps);
    sim.set_touches(&[t.touch()])?;
    let dv: Vec<f64> = sim
        .ideal_frame(&protocol, amps)
        .iter()
        .zip(&v0)
        .map(|(a, b)| a - b)
        .collect();
    let fine = Imager::new(&scene.sheet, Mesh::with_about(&scene.sheet, reference)?, 8)?;
    let v_ref = fine.forward.frame(&fine.background(), &protocol, amps)?;
    let scale = v_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let pe = |imager: &Imager, d: &[f64]| {
        let rois = regions(&imager.grid, &imager.grid.image(d), 0.1);
        let extent = imager.grid.width.max(imager.grid.height) as f64 * imager.grid.size;
        rois.first().map_or(1.0, |r| {
            (r.centroid[0] - t.position[0]).hypot(r.centroid[1] - t.position[1]) / extent
        })
    };
    let mut rows = Vec::new();
    for &target in triangles {
        let started = Instant::now();
        let imager = Imager::new(&scene.sheet, Mesh::with_about(&scene.sheet, target)?, 64)?;
        let (v, jac) = imager
            .forward
            .jacobian(&imager.background(), &protocol, amps)?;
        let one = OneStep::new(&jac, 0.03, 0.5)?;
        let setup_s = started.elapsed().as_secs_f64();
        let forward_error = v
            .iter()
            .zip(&v_ref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        let image = one.reconstruct(&dv)?;
        // The live frame: the median of 41 products.
        let mut times: Vec<f64> = (0..41)
            .map(|_| {
                let t0 = Instant::now();
                let d = one.reconstruct(&dv);
                let dt = t0.elapsed().as_secs_f64() * 1e6;
                std::hint::black_box(d).ok();
                dt
            })
            .collect();
        times.sort_by(f64::total_cmp);
        let iterative = if imager.triangles() <= iterative_up_to {
            let t0 = Instant::now();
            let its = recon::gauss_newton(
                &imager.forward,
                &protocol,
                amps,
                &imager.background(),
                Data::Difference(&dv),
                GaussNewton {
                    alpha: 0.03,
                    s: 0.5,
                    iterations: 4,
                },
            )?;
            let last = its.last().context("no iteration")?;
            let d: Vec<f64> = last.0.iter().map(|v| v - imager.sigma0).collect();
            Some((pe(&imager, &d), t0.elapsed().as_secs_f64()))
        } else {
            None
        };
        let row = SweepRow {
            triangles: imager.triangles(),
            forward_error,
            setup_s,
            live_frame_us: times[times.len() / 2],
            pe_one_step: pe(&imager, &image),
            iterative,
        };
        tick(&row);
        rows.push(row);
    }
    Ok(rows)
}

fn sweep(out: &Path, sizes: &Sizes, steps: &Steps) -> Result<Section<SweepKey>> {
    let bar = steps.bar(sizes.sweep.len(), "speed/accuracy sweep (meshes)");
    let rows = mesh_sweep(
        sizes.sweep,
        sizes.sweep_reference,
        sizes.iterative_up_to,
        |_| bar.inc(1),
    )?;
    steps.done(&bar, "swept mesh sizes");
    let dir = out.join("sweep");
    let xs = |f: fn(&SweepRow) -> Option<f64>| -> Vec<(f64, f64)> {
        rows.iter()
            .filter_map(|r| Some((r.triangles as f64, f(r)?)))
            .collect()
    };
    plot::chart(
        &dir.join("accuracy.png"),
        plot::Labels {
            title: "mesh size against accuracy (AD, CEM, target at x = 0.5)",
            x: "triangles",
            y: "error (%)",
            legend: plot::Legend::UpperRight,
        },
        &[
            plot::Series {
                label: "forward error, % of the largest voltage".into(),
                points: xs(|r| Some(100.0 * r.forward_error)),
                scatter: false,
            },
            plot::Series {
                label: "PE one-step, % of the sheet".into(),
                points: xs(|r| Some(100.0 * r.pe_one_step)),
                scatter: false,
            },
            plot::Series {
                label: "PE iterative (4 steps), % of the sheet".into(),
                points: xs(|r| r.iterative.map(|i| 100.0 * i.0)),
                scatter: false,
            },
        ],
    )?;
    plot::chart(
        &dir.join("time.png"),
        plot::Labels {
            title: "mesh size against time",
            x: "triangles",
            y: "seconds",
            legend: plot::Legend::UpperLeft,
        },
        &[
            plot::Series {
                label: "set-up: mesh + forward + Jacobian + one-step matrix".into(),
                points: xs(|r| Some(r.setup_s)),
                scatter: false,
            },
            plot::Series {
                label: "iterative Gauss-Newton, 4 steps".into(),
                points: xs(|r| r.iterative.map(|i| i.1)),
                scatter: false,
            },
        ],
    )?;
    let mut md = String::from("## 3. Speed against accuracy (imaging)\n\n");
    let _ = writeln!(
        md,
        "22 cm disc, adjacent protocol, complete electrode model, the target at x = 0.5; \
         noiseless simulator frames so that only the mesh matters; alpha = 0.03, s = 0.5. \
         Forward error: the largest difference of the untouched frame from a {}-triangle \
         mesh's, over the largest voltage. Times on one core of the machine above (the live \
         frame is the median of 41).\n\n\
         | triangles | forward error | set-up | live frame | PE one-step | PE iterative (4 steps) | iterative time |\n\
         | --- | --- | --- | --- | --- | --- | --- |",
        sizes.sweep_reference
    );
    for r in &rows {
        let _ = writeln!(
            md,
            "| {} | {:.2} % | {:.3} s | {:.0} us | {:.3} | {} | {} |",
            r.triangles,
            100.0 * r.forward_error,
            r.setup_s,
            r.live_frame_us,
            r.pe_one_step,
            r.iterative.map_or("-".into(), |i| format!("{:.3}", i.0)),
            r.iterative.map_or("-".into(), |i| format!("{:.2} s", i.1)),
        );
    }
    let _ = writeln!(
        md,
        "\n![accuracy](sweep/accuracy.png)\n\n![time](sweep/time.png)\n\n\
         The one-step matrix is built once per (mesh, protocol, alpha); a live frame is one \
         matrix-vector product. The iterative Gauss-Newton refits the nonlinear model and costs \
         a Jacobian per step: use it offline, when accuracy matters more than speed.\n"
    );
    let at_8k = rows
        .iter()
        .min_by_key(|r| r.triangles.abs_diff(8_000))
        .map(|r| (r.triangles, r.setup_s, r.live_frame_us));
    Ok(Section {
        markdown: md,
        json: json!({ "reference_triangles": sizes.sweep_reference, "rows": rows }),
        key: SweepKey { at_8k },
    })
}

// ----------------------------------------------------------------------------------------
// The machine and the date

/// "CPU model, N cores, M GiB" from /proc where it exists.
#[must_use]
pub fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, std::num::NonZero::get);
    let mem = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal"))?;
            let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(format!(", {:.0} GiB", kb / 1024.0 / 1024.0))
        })
        .unwrap_or_default();
    format!("{cpu}, {cores} cores{mem}")
}

/// Today's date, UTC, as YYYY-MM-DD.
#[must_use]
pub fn today_utc() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    civil_date(secs / 86_400)
}

/// Days since 1970-01-01 as YYYY-MM-DD (proleptic Gregorian; H. Hinnant's algorithm).
fn civil_date(days: u64) -> String {
    let z = days as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1_460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!("{y:04}-{m:02}-{d:02}")
}

#[cfg(test)]
mod tests;
