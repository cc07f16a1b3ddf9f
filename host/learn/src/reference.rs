//! The reference's touch-classification figures (docs/method.md §10) and the procedure that
//! measures them on the simulator (docs/method.md §9, docs/calibration.md): a class grid over
//! the sheet, T = 6 visits of S_num scans x S_sub = 20 observations, plain QDA on the raw
//! frames (the opposite protocol's reciprocity-halved features), tested on "next day"
//! sessions of 20 observations per class. Training accuracy is 10-fold cross-validation on
//! the training set.

use et_core::ScanConfig;
use et_sim::frontend::{CALIBRATION_GAIN, FrontendSpec};
use et_sim::sheet::SheetSpec;
use et_sim::touch::Piezo;

use crate::collect::{CollectError, Plan, collect, collect_visits, grid, training_config};
use crate::cv::evaluate;
use crate::fastcv::cross_validate_fast;
use crate::fit::{FitError, FitOptions, Fitted};

/// One published figure: a sheet, an electrode count, a class grid and the reference's
/// next-day accuracy there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Case {
    /// Side of the square sheet, m.
    pub side: f64,
    /// Electrodes L.
    pub electrodes: u8,
    /// Classes per side (7: 49 classes, 10: 100).
    pub grid: usize,
    /// The reference's next-day accuracy, 0 to 1.
    pub reference: f64,
}

impl Case {
    /// The radius of each class's target, m: the reference's 15 mm target for 49 classes,
    /// 10 mm for 100 (the finger's centre lands anywhere in it).
    #[must_use]
    pub fn target_radius(&self) -> f64 {
        if self.grid <= 7 { 0.0075 } else { 0.005 }
    }

    /// Classes C.
    #[must_use]
    pub fn classes(&self) -> usize {
        self.grid * self.grid
    }

    /// "13 cm, L = 16, 49 classes".
    #[must_use]
    pub fn name(&self) -> String {
        format!(
            "{:.0} cm, L = {}, {} classes",
            self.side * 100.0,
            self.electrodes,
            self.classes()
        )
    }
}

/// The six published figures of docs/method.md §10 (QDA on raw frames, next day).
pub const CASES: [Case; 6] = [
    Case {
        side: 0.13,
        electrodes: 16,
        grid: 7,
        reference: 0.916,
    },
    Case {
        side: 0.13,
        electrodes: 16,
        grid: 10,
        reference: 0.778,
    },
    Case {
        side: 0.17,
        electrodes: 16,
        grid: 7,
        reference: 0.887,
    },
    Case {
        side: 0.17,
        electrodes: 16,
        grid: 10,
        reference: 0.806,
    },
    Case {
        side: 0.13,
        electrodes: 8,
        grid: 7,
        reference: 0.690,
    },
    Case {
        side: 0.13,
        electrodes: 8,
        grid: 10,
        reference: 0.299,
    },
];

/// What the procedure measured for one case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    /// Next-day accuracy over all test sessions, 0 to 1.
    pub next_day: f64,
    /// 10-fold cross-validated accuracy on the training set, 0 to 1.
    pub training: f64,
}

/// Why a case could not be measured.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ReferenceError {
    /// Collecting the data failed.
    #[error("collecting: {0}")]
    Collect(#[from] CollectError),
    /// Plain QDA could not be fitted (too few observations for the features).
    #[error("fitting plain QDA: {0}")]
    Fit(#[from] FitError),
}

/// Runs the procedure for `case` on a fabric of `piezo`: `plan` (its visits, scans,
/// sub-sections, finger, variability and seed; the target's radius set from the case) for
/// training, `days` next-day sessions of one scan per class (seeds 77, 78, ...) for the test,
/// all through `frontend` at the calibration's gain.
///
/// # Errors
/// [`ReferenceError`] when collection or the fit fails.
pub fn measure(
    case: &Case,
    frontend: FrontendSpec,
    piezo: Piezo,
    plan: &Plan,
    days: usize,
) -> Result<Outcome, ReferenceError> {
    let spec = SheetSpec {
        piezo,
        ..SheetSpec::rectangle(case.side, case.side, case.electrodes)
    };
    let config = training_config(ScanConfig {
        electrodes: case.electrodes,
        gain: CALIBRATION_GAIN,
        ..ScanConfig::REFERENCE
    });
    let centres = grid(&spec, case.grid, case.grid, 0.0);
    // The same fingertip presses both grids; only the target it aims at shrinks.
    let plan = Plan {
        target_radius: case.target_radius(),
        ..plan.clone()
    };
    let train = collect(&spec, frontend, config, &centres, &plan)?;
    let opts = FitOptions::default();
    let folds: Vec<usize> = (0..train.y.len()).map(|i| i % 10).collect();
    let training = cross_validate_fast(&train.x, &train.y, centres.len(), &opts, &folds)?;
    let model = Fitted::fit(&train.x, &train.y, centres.len(), &opts)?;
    let day = Plan {
        visits: 1,
        scans: 1,
        ..plan.clone()
    };
    let seeds = (0..days).map(|d| 77 + d as u64);
    let next_day = if days == 0 {
        0.0
    } else {
        let test = collect_visits(&spec, frontend, config, &centres, &day, seeds, |_, _| {})?;
        evaluate(&model, &test.x, &test.y)?.accuracy()
    };
    Ok(Outcome {
        next_day,
        training: training.accuracy(),
    })
}
