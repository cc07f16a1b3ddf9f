//! `et demo`: the whole method on the simulated sheet, no hardware, into a report folder.
//!
//! 1. **Touch classification** (docs/method.md §9) on the default 13 x 13 cm, 16-electrode sheet: a
//!    training set collected as the method prescribes, QDA trained and cross-validated, then
//!    tested on three "next day" sessions (electrodes moved, pressure unknown); the model
//!    shrunk to fit the board's flash and run through et-core exactly as the firmware runs it.
//! 2. **Imaging** the reference scenarios of docs/method.md §7 (22 cm disc) with every protocol,
//!    one-step Gauss-Newton with the complete electrode model, docs/method.md §7's metrics and docs/method.md §8's
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

use et_core::ScanConfig;
use et_core::model::{ModelKind, Precision};
use et_core::protocol::{Protocol, ProtocolKind};
use et_sim::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use crate::plot;
use et_core::board::MODEL_SLOT_BYTES;
use et_learn::collect::{self, Plan};
use et_learn::model::Tested;
use et_learn::pipeline;
use et_learn::tabular::{Choice, Kind};
use et_learn::{Examples, Trainer};
use et_recon::Imager;
use et_recon::mesh::Mesh;
use et_recon::select::{Settings, significant};
use et_recon::{Data, GaussNewton, metrics, regions};
use et_sim::still::{scene_frames_on, simulated_sheet};

mod error;
mod imaging;
mod learning;
pub mod report;
mod sweep;

use imaging::{ImagingKey, imaging};
use learning::{LearningKey, learning};
use report::{Section, machine, summary_table, today_utc};
use sweep::{SweepKey, sweep};
pub use sweep::{SweepRow, mesh_sweep};

pub use error::DemoError;
use error::{Result, Staged as _, io};
pub use et_sim::scenes::{DEFAULT_SCENE, REFERENCE_SCENES};

/// What to run.
#[derive(Clone, Debug)]
pub struct Options {
    /// The report folder (created; an existing one that is not empty is refused unless
    /// `force`).
    pub out: PathBuf,
    /// Replace an existing report (its index.md and summary.json are removed first, so a
    /// run stopped midway never leaves an old index beside new figures).
    pub force: bool,
    /// Small sizes everywhere (a smoke test, about 10 s): fewer scans and visits, coarser
    /// meshes. The numbers are then not the ones to quote.
    pub quick: bool,
    /// Show progress bars on stderr.
    pub progress: bool,
    /// The command line, for the report.
    pub command: String,
}

/// `summary.json`: the run, then each section's numbers.
#[derive(Serialize)]
struct Summary<'a> {
    command: &'a str,
    quick: bool,
    sizes: Sizes,
    machine: &'a str,
    date_utc: String,
    seconds: f64,
    learning: &'a serde_json::Value,
    imaging: &'a serde_json::Value,
    sweep: &'a serde_json::Value,
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

/// The meshes (triangles) `--quick`'s sweep times.
pub const QUICK_SWEEP: &[usize] = &[500, 1_000];

const QUICK: Sizes = Sizes {
    visits: 2,
    scans: 2,
    days: 1,
    triangles: 2_000,
    sweep: QUICK_SWEEP,
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
            // A message that cannot be written (`2> /dev/full`) is dropped, not a panic.
            use std::io::Write as _;
            let took = self.started.elapsed().as_secs_f64();
            let _ = writeln!(std::io::stderr(), "{what:<60} {took:>6.1} s");
        }
    }
}

/// Runs the demo into `options.out`.
///
/// # Errors
/// When the folder cannot be written, or a stage fails (with the stage named).
pub fn run(options: &Options) -> Result<Report> {
    let started = Instant::now();
    crate::output::check_folder(&options.out, options.force)?;
    // (Made aside and renamed at the end, unless a report is there to replace in place.)
    let summary = crate::output::write_folder(&options.out, |out| make(out, options, started))?;
    let index = options.out.join("index.md");
    Ok(Report { index, summary })
}

/// The report made in the folder `out`, and its summary.
fn make(out: &Path, options: &Options, started: Instant) -> Result<serde_json::Value> {
    let sizes = if options.quick { QUICK } else { FULL };
    for stale in ["index.md", "summary.json"] {
        match std::fs::remove_file(out.join(stale)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(io(out.join(stale))(e));
            }
            _ => {}
        }
    }
    for dir in ["", "learning", "imaging", "sweep"] {
        std::fs::create_dir_all(out.join(dir)).map_err(io(out.join(dir)))?;
    }
    let steps = Steps {
        show: options.progress,
        started,
    };
    let learning = learning(out, &sizes, &steps).stage("touch classification")?;
    let imaging = imaging(out, &sizes, &steps).stage("imaging the reference scenarios")?;
    let sweep = sweep(out, &sizes, &steps).stage("the speed/accuracy sweep")?;
    let seconds = started.elapsed().as_secs_f64();
    let machine = machine();
    let summary = serde_json::to_value(Summary {
        command: &options.command,
        quick: options.quick,
        sizes,
        machine: &machine,
        date_utc: today_utc(),
        seconds,
        learning: &learning.json,
        imaging: &imaging.json,
        sweep: &sweep.json,
    })?;
    let json_path = out.join("summary.json");
    let json = serde_json::to_string_pretty(&summary)?;
    crate::output::write(&json_path, |partial| {
        std::fs::write(partial, &json).map_err(io(&json_path))
    })?;
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
    page.push_str(report::GLOSSARY);
    let index = out.join("index.md");
    // Last, and whole: an index.md exists only beside a complete report.
    crate::output::write(&index, |partial| {
        std::fs::write(partial, &page).map_err(io(&index))
    })?;
    Ok(summary)
}

fn load(scene: (&str, &str)) -> Result<Scene> {
    Ok(Scene::parse(scene.1, scene.0)?)
}

// ----------------------------------------------------------------------------------------
// 1. Touch classification

// ----------------------------------------------------------------------------------------
// 2. Imaging

// ----------------------------------------------------------------------------------------
// 3. Speed against accuracy

// ----------------------------------------------------------------------------------------
// The machine and the date
