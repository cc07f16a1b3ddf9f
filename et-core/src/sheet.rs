//! The physical sheet, as both the simulator and the reconstruction see it (docs/method.md §1):
//! its outline, its fabric's sheet resistance, and its electrodes (where they sit on the
//! outline, how wide they are, their contact resistance and how the finite elements model
//! them). What only the simulator needs (its grid, the piezoresistive law, a bend) is the
//! simulator's own (`et_sim::sheet::SheetSpec`).
//!
//! Behind the `std` feature: outlines use `Vec` and floating-point functions, and the board
//! never needs them.

pub mod shape;

use serde::{Deserialize, Serialize};

pub use shape::{Shape, ShapeError};

/// Default sheet resistance of the PPy fabric, ohm per square (docs/method.md §1).
pub const SHEET_RESISTANCE: f64 = 30e3;

/// Where the electrodes are and how they touch the fabric.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ElectrodeSpec {
    /// Electrode count L (4 to 32).
    pub count: u8,
    /// Width along the outline, m (a clip: about 5 mm).
    pub width: f64,
    /// Contact resistance of each electrode, ohm.
    pub contact_ohm: f64,
    /// Arc-length fraction of the outline where electrode 0 sits; the others follow equally
    /// spaced, counter-clockwise. Default: half a pitch from the outline's start.
    pub first: Option<f64>,
    /// Explicit arc-length fractions, one per electrode (overrides `first`).
    pub positions: Option<Vec<f64>>,
    /// How et's finite elements model the electrodes when imaging (the simulator always
    /// models the contact over its width, as the fabric has it).
    pub model: ElectrodeModel,
}

/// How the imaging's finite elements model an electrode (docs/method.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ElectrodeModel {
    /// The complete electrode model: current spreads over the electrode's width through its
    /// contact resistance, and the electrode reads one potential.
    #[default]
    Complete,
    /// Point electrodes: current enters and potential is read at the node at the electrode's
    /// centre (width and contact resistance do not enter the image's model). Cheaper, and
    /// adequate where electrodes are narrow against their spacing.
    Point,
    /// The shunt model: ideal electrodes without contact resistance, every point under an
    /// electrode at its potential (the complete model's limit of zero contact resistance).
    Shunt,
}

impl Default for ElectrodeSpec {
    fn default() -> Self {
        Self {
            count: 16,
            width: 0.005,
            contact_ohm: 1_000.0,
            first: None,
            positions: None,
            model: ElectrodeModel::Complete,
        }
    }
}

impl ElectrodeSpec {
    /// The arc-length fraction of every electrode.
    #[must_use]
    pub fn arc_positions(&self) -> Vec<f64> {
        if let Some(p) = &self.positions {
            return p.clone();
        }
        let l = f64::from(self.count);
        let first = self.first.unwrap_or(0.5 / l);
        (0..self.count).map(|e| first + f64::from(e) / l).collect()
    }
}

/// The physical sheet: outline, fabric and electrodes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sheet {
    /// Outline.
    pub shape: Shape,
    /// Sheet resistance, ohm per square.
    #[serde(default = "default_rs")]
    pub sheet_resistance: f64,
    /// Electrodes.
    #[serde(default)]
    pub electrodes: ElectrodeSpec,
}

fn default_rs() -> f64 {
    SHEET_RESISTANCE
}

/// Why a sheet's description is not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SheetError {
    /// The outline is not valid.
    #[error("sheet.shape: {0}")]
    Shape(ShapeError),
    /// A field is out of range.
    #[error("{field}: {why}")]
    Field {
        /// The field's name, as in a scene file.
        field: &'static str,
        /// What is wrong.
        why: String,
    },
}

impl Sheet {
    /// A flat `width` x `height` m rectangle of the default fabric (30 kohm/sq) with
    /// `electrodes` default clips (5 mm, 1 kohm) equally spaced.
    #[must_use]
    pub fn rectangle(width: f64, height: f64, electrodes: u8) -> Self {
        Self {
            shape: Shape::Rectangle { width, height },
            sheet_resistance: SHEET_RESISTANCE,
            electrodes: ElectrodeSpec {
                count: electrodes,
                ..ElectrodeSpec::default()
            },
        }
    }

    /// A disc of `radius` m of the default fabric with `electrodes` default clips.
    #[must_use]
    pub fn disc(radius: f64, electrodes: u8) -> Self {
        Self {
            shape: Shape::Disc { radius },
            ..Self::rectangle(1.0, 1.0, electrodes)
        }
    }

    /// Checks the outline, the sheet resistance and the electrodes.
    ///
    /// # Errors
    /// [`SheetError`] naming the field, as a scene file spells it.
    pub fn validate(&self) -> Result<(), SheetError> {
        self.shape.validate().map_err(SheetError::Shape)?;
        let field = |field, why: String| Err(SheetError::Field { field, why });
        if !(self.sheet_resistance.is_finite() && self.sheet_resistance > 0.0) {
            return field(
                "sheet.sheet_resistance",
                format!(
                    "{} must be positive (ohm per square)",
                    self.sheet_resistance
                ),
            );
        }
        let e = &self.electrodes;
        if !(4..=32).contains(&e.count) || !e.count.is_multiple_of(2) {
            return field(
                "sheet.electrodes.count",
                format!("{} must be even, 4 to 32", e.count),
            );
        }
        if !(e.width.is_finite() && e.width > 0.0) {
            return field(
                "sheet.electrodes.width",
                format!("{} must be a positive length in m", e.width),
            );
        }
        if !(e.contact_ohm.is_finite() && e.contact_ohm >= 0.0) {
            return field(
                "sheet.electrodes.contact_ohm",
                format!("{} must be >= 0 ohm", e.contact_ohm),
            );
        }
        if let Some(p) = &e.positions
            && (p.len() != usize::from(e.count) || p.iter().any(|x| !x.is_finite()))
        {
            return field(
                "sheet.electrodes.positions",
                format!("need {} finite arc fractions", e.count),
            );
        }
        Ok(())
    }
}
