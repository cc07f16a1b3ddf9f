//! Why collection failed.

use et_core::scan::ScanError;
use et_sim::frontend::SimError;
use et_sim::sheet::SheetError;

/// Why collection failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CollectError {
    /// The scan configuration is not valid for the sheet.
    #[error("scan configuration: {0}")]
    Config(#[from] et_core::config::ConfigError),
    /// The simulated sheet could not be built or pressed.
    #[error(transparent)]
    Sheet(#[from] SheetError),
    /// A scan failed.
    #[error("scan: {0}")]
    Scan(#[from] ScanError<SimError>),
    /// The simulated front end refused a request.
    #[error("simulated front end: {0}")]
    Sim(SimError),
    /// The untouched frames could not be averaged into V_0.
    #[error("untouched frames: {0}")]
    Stats(#[from] et_core::stats::StatsError),
    /// A press without touches.
    #[error("press {label} has no touches")]
    EmptyPress {
        /// Its label.
        label: u16,
    },
    /// A built-in scene could not be read.
    #[error("scene: {0}")]
    Scene(#[source] et_sim::scene::SceneError),
    /// A built-in scene's scan settings are not usable.
    #[error("scene: {0}")]
    SceneField(#[source] et_sim::scene::FieldError),
    /// A collection past the memory free.
    #[error(
        "{observations} observations of {features} features hold about {} GB while they \
         are collected, where {} GB is free: collect fewer classes (--grid), scans (--scans), \
         sub-sections (--subsections) or visits (--visits)",
        crate::tabular::gb(*need_bytes),
        crate::tabular::gb(*free_bytes)
    )]
    TooLarge {
        /// Rows asked for.
        observations: usize,
        /// Features per row.
        features: usize,
        /// Bytes they would hold.
        need_bytes: u64,
        /// Bytes free.
        free_bytes: u64,
    },
    /// No visit was asked for.
    #[error("no visit to collect: ask for at least one")]
    NoVisits,
    /// A length of the plan does not fit the sheet.
    #[error(
        "{name}: {:.1} mm on a sheet {:.1} mm across: at most {:.1} mm",
        value * 1e3,
        side * 1e3,
        limit * 1e3
    )]
    Plan {
        /// The length's name (its command-line flag).
        name: &'static str,
        /// Its value, m.
        value: f64,
        /// The sheet's shorter side, m.
        side: f64,
        /// The most it may be, m.
        limit: f64,
    },
    /// The visits' datasets could not be joined.
    #[error("joining the visits: {0}")]
    Data(crate::dataset::DataError),
}
