//! A scene's field at fault, and why.

use super::*;
use et_core::said::Plain;

/// A scene value out of range: the field as written in a scene file, and why.
#[derive(Debug, Clone, thiserror::Error)]
#[error(
    "{}{fault}",
    if matches!(**fault, SceneFault::Sheet(_)) { String::new() } else { format!("{field}: ") }
)]
pub struct FieldError {
    /// The field, e.g. `scan.current_ua` or `touch[2].radius`.
    pub field: String,
    /// What is wrong with its value (boxed: errors that hold this one stay small).
    pub fault: Box<SceneFault>,
}

/// What is wrong with a scene's field.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum SceneFault {
    /// A value out of its range, or fields that break a rule together.
    #[error(transparent)]
    Value(#[from] FieldFault),
    /// The outline.
    #[error(transparent)]
    Shape(et_core::sheet::ShapeError),
    /// The sheet as a whole (electrodes that overlap, a grid too fine), its message naming
    /// the field.
    #[error(transparent)]
    Sheet(SheetError),
    /// A protocol name that is not a built-in protocol.
    #[error(
        "'{0}' is not adjacent, pseudo-polar, pp-pp or opposite (or give any system's protocol \
         as {{ file = \"protocol.csv\" }})"
    )]
    UnknownProtocol(String),
    /// A protocol file of no built-in protocol's rows asked of the simulated board.
    #[error(
        "a protocol file whose rows are none of the built-in protocols' (adjacent, \
         pseudo-polar, pp-pp or opposite, each in et's order and at one current) is imaged \
         from measured frames (et reconstruct --frames), not scanned by the simulated board: \
         name a built-in protocol to simulate the board, or write another system's frames \
         with et sim --out frames.csv"
    )]
    NotScanned,
    /// A protocol file asked of `et stream` or `et view` playing another system's frames.
    #[error(
        "a protocol file whose rows are none of the built-in protocols' (adjacent, \
         pseudo-polar, pp-pp or opposite, each in et's order and at one current): `et stream` \
         and `et view` play another system's frames under those only"
    )]
    NotPlayed,
    /// A current above the simulated board's.
    #[error(
        "{0} uA: the simulated board drives up to 1000 uA (another system's frames at this \
         current are written by `et sim --out frames.csv`, .npy, .npz or .mat, and imaged by \
         `et reconstruct --frames`)"
    )]
    BoardCurrent(f64),
    /// A current beside a protocol file whose rows drive others.
    #[error(
        "{} uA, but {file}'s rows drive {}: each row's own current is imaged, so this one \
         would be ignored; drop current_ua, or give the rows' (uA: 1.4 mA is 1400)",
        Plain(*.ua),
        if Plain(.rows_ua.0).to_string() == Plain(.rows_ua.1).to_string() {
            format!("{} uA", Plain(.rows_ua.0))
        } else {
            format!("{} to {} uA", Plain(.rows_ua.0), Plain(.rows_ua.1))
        }
    )]
    CurrentBesideRows {
        /// The scene's current, uA.
        ua: f64,
        /// The protocol file, as the scene names it.
        file: String,
        /// The rows' least and most current, uA.
        rows_ua: (f64, f64),
    },
    /// The protocol file, or the built-in protocol's schedule.
    #[error(transparent)]
    Schedule(#[from] et_core::schedule::ScheduleError),
    /// The built-in protocol on these electrodes.
    #[error(transparent)]
    Protocol(#[from] et_core::protocol::ProtocolError),
    /// The board's scan configuration.
    #[error(transparent)]
    Config(#[from] et_core::config::ConfigError),
    /// An electrode number past the sheet's.
    #[error("{electrode} is not an electrode (0 to {})", count.saturating_sub(1))]
    Electrode {
        /// The number given.
        electrode: u8,
        /// The sheet's electrodes.
        count: u8,
    },
    /// A short without another electrode.
    #[error("a short needs another electrode, 0 to {}", .0.saturating_sub(1))]
    ShortWith(u8),
    /// A touch's footprint.
    #[error(
        "elongation {elongation} must be in [1, {}] and angle {angle} rad finite",
        crate::touch::MAX_ELONGATION
    )]
    Footprint {
        /// Long over short axis.
        elongation: f64,
        /// The long axis's angle, rad.
        angle: f64,
    },
    /// A point off the sheet.
    #[error("{0:?} is not on the sheet")]
    OffSheet([f64; 2]),
}

impl FieldError {
    pub(super) fn new(field: impl Into<String>, fault: impl Into<SceneFault>) -> Self {
        Self {
            field: field.into(),
            fault: Box::new(fault.into()),
        }
    }

    pub(super) fn rule(field: impl Into<String>, rule: &'static str) -> Self {
        Self::new(field, FieldFault::Rule(rule))
    }

    pub(super) fn value(field: impl Into<String>, value: f64, rule: &'static str) -> Self {
        Self::new(field, FieldFault::Value { value, rule })
    }
}

impl From<SheetError> for FieldError {
    fn from(e: SheetError) -> Self {
        match e {
            SheetError::Spec(et_core::sheet::SheetError::Field { field, fault }) => {
                Self::new(field, fault)
            }
            SheetError::Spec(et_core::sheet::SheetError::Shape(e)) => {
                Self::new("sheet.shape", SceneFault::Shape(e))
            }
            other => Self::new("sheet", SceneFault::Sheet(other)),
        }
    }
}
