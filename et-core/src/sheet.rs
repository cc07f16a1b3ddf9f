//! The physical sheet, as both the simulator and the reconstruction see it (docs/method.md §1):
//! its outline, its fabric's sheet resistance, and its electrodes (where they sit on the
//! outline, how wide they are, their contact resistance and how the finite elements model
//! them). What only the simulator needs (its grid, the piezoresistive law, a bend) is the
//! simulator's own (`et_sim::sheet::SheetSpec`).
//!
//! Behind the `std` feature: outlines use `Vec` and floating-point functions, and the board
//! never needs them.

pub mod shape;
pub mod xy;

use crate::said::{Plain, Sig};
use serde::{Deserialize, Serialize};

pub use shape::{Shape, ShapeError};

/// Default sheet resistance of the PPy fabric, ohm per square (docs/method.md §1).
pub const SHEET_RESISTANCE: f64 = 30e3;

/// The sheet resistances et models, ohm per square: from below a thick metal plate's (1 cm of
/// copper has 2e-6) to past an antistatic film's (1e11). A frame is the current times the
/// sheet resistance times a factor of the geometry, and et takes frames in single precision:
/// 1e-300 ohm/sq gave frames of zeros without a word, 1e300 infinite ones.
pub const SHEET_OHM_RANGE: (f64, f64) = (1e-9, 1e15);

/// The conductivities of [`SHEET_OHM_RANGE`]'s sheets, S per square.
pub const SHEET_SIGMA_RANGE: (f64, f64) = (1e-15, 1e9);

/// The largest contact resistance, as a multiple of the sheet resistance (ohm per ohm/sq).
/// There the frames have reached their limit (the current spreads evenly under each
/// electrode; from 1e5 to 1e6 they change by 1e-7 of their size), and past it both the finite
/// elements and the simulator's network lose digits to round-off, ten times more each decade
/// (1e-5 of the frame at 1e8, 1e-3 at 1e10, nothing right at 1e13):
/// `et_recon`'s `a_contact_past_its_limit_changes_nothing`.
pub const MAX_CONTACT_RATIO: f64 = 1e6;

/// Where the electrodes are and how they touch the fabric.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ElectrodeSpec {
    /// Electrode count L (4 to 32).
    #[serde(deserialize_with = "electrode_count")]
    pub count: u8,
    /// Width along the outline, m (a clip: about 5 mm).
    pub width: f64,
    /// Contact resistance of each electrode, ohm.
    pub contact_ohm: f64,
    /// Arc-length fraction of the outline where electrode 0 sits; the others follow equally
    /// spaced. Default: half a pitch from the outline's start (the disc's +x direction, the
    /// rectangle's lower-left corner), so on a disc of 16 electrode 0 sits at 11.25 degrees.
    pub first: Option<f64>,
    /// The angle of electrode 0's centre, degrees counter-clockwise from +x as seen from the
    /// outline's centre (the middle of its bounding box): 90 for a system that numbers from
    /// the top. Instead of `first`.
    pub first_deg: Option<f64>,
    /// The way the numbers run round the outline: "ccw" (counter-clockwise, the default) or
    /// "cw" (clockwise), as seen with +x to the right and +y up.
    pub direction: Direction,
    /// Explicit arc-length fractions, one per electrode (overrides `first`, `first_deg` and
    /// `direction`).
    pub positions: Option<Vec<f64>>,
    /// How et's finite elements model the electrodes when imaging (the simulator always
    /// models the contact over its width, as the fabric has it).
    pub model: ElectrodeModel,
}

/// An electrode count as a file or a caller gives it: any whole number is read, and one a
/// count cannot be (negative, past 255) is said by the rule counts keep, not as the
/// parser's "expected u8".
fn electrode_count<'de, D: serde::Deserializer<'de>>(d: D) -> Result<u8, D::Error> {
    let v = crate::whole::any_whole(d)?;
    u8::try_from(v).map_err(|_| serde::de::Error::custom(format_args!("{v} must be even, 4 to 32")))
}

/// The way electrode numbers run round the outline.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Direction {
    /// Counter-clockwise (et's own numbering).
    #[default]
    Ccw,
    /// Clockwise.
    Cw,
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
            first_deg: None,
            direction: Direction::Ccw,
            positions: None,
            model: ElectrodeModel::Complete,
        }
    }
}

impl ElectrodeSpec {
    /// The arc-length fraction of every electrode on `shape`'s outline, in electrode order.
    #[must_use]
    pub fn arc_positions(&self, shape: &Shape) -> Vec<f64> {
        if let Some(p) = &self.positions {
            return p.clone();
        }
        let l = f64::from(self.count);
        let first = match self.first_deg {
            Some(deg) => shape.arc_at_angle(deg),
            None => self.first.unwrap_or(0.5 / l),
        };
        let step = match self.direction {
            Direction::Ccw => 1.0 / l,
            Direction::Cw => -1.0 / l,
        };
        (0..self.count)
            .map(|e| {
                let t = first + f64::from(e) * step;
                if t < 0.0 { t + 1.0 } else { t }
            })
            .collect()
    }

    /// The centre of every electrode on `shape`'s outline, m.
    #[must_use]
    pub fn centres(&self, shape: &Shape) -> Vec<[f64; 2]> {
        self.arc_positions(shape)
            .into_iter()
            .map(|t| shape.boundary_point(t))
            .collect()
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
    #[error("{field}: {fault}")]
    Field {
        /// The field's name, as in a scene file.
        field: &'static str,
        /// What is wrong.
        fault: FieldFault,
    },
    /// Two electrodes overlap (or share a place) on the outline.
    #[error(
        "sheet.electrodes: electrodes {a} and {b} overlap: {count} electrodes {} m wide on an \
         outline {} m long (narrower electrodes, fewer, or a larger sheet)",
        Plain(*.width), Plain(*.perimeter)
    )]
    Overlap {
        /// One electrode.
        a: usize,
        /// The next along the outline.
        b: usize,
        /// The electrodes.
        count: u8,
        /// Their width, m.
        width: f64,
        /// The outline's length, m.
        perimeter: f64,
    },
}

/// What is wrong with a field's value: the value and the rule it breaks (as a scene file's
/// reader says it).
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FieldFault {
    /// The value breaks its rule: `rule` says what it must be, with its unit.
    #[error("{value} must be {rule}")]
    Value {
        /// The value given.
        value: f64,
        /// What it must be ("positive (ohm per square)").
        rule: &'static str,
    },
    /// The value is outside (`low`, `high`] in `unit`.
    #[error("{value} must be in ({low}, {high}] {unit}")]
    Range {
        /// The value given.
        value: f64,
        /// The bound it must be above.
        low: f64,
        /// The bound it may reach.
        high: f64,
        /// The unit.
        unit: &'static str,
    },
    /// A list of the wrong length or with values that are not finite.
    #[error("{found} given, need {need} {what}")]
    Count {
        /// The usable entries given.
        found: usize,
        /// The entries needed.
        need: usize,
        /// Of what ("finite arc fractions").
        what: &'static str,
    },
    /// The fields given together break a rule (no one value is at fault).
    #[error("{0}")]
    Rule(&'static str),
    /// The value is outside `low` to `high` in `unit`, said in powers of ten.
    #[error("{} {unit} is outside {} to {}: {why}", Sig(*.value), Sig(*.low), Sig(*.high))]
    Span {
        /// The value given.
        value: f64,
        /// The smallest value taken.
        low: f64,
        /// The largest value taken.
        high: f64,
        /// The unit.
        unit: &'static str,
        /// Why the range, and what a value outside it may mean.
        why: &'static str,
    },
    /// The contact resistance is over [`MAX_CONTACT_RATIO`] times the sheet resistance.
    #[error(
        "{} ohm is over {} times the sheet resistance ({} ohm/sq): past that the frames no \
         longer change (the current spreads evenly under each electrode) and the solvers lose \
         digits; give at most {} ohm, which gives the same frames",
        Sig(*.contact_ohm), Sig(MAX_CONTACT_RATIO), Sig(*.sheet_ohm),
        Sig(MAX_CONTACT_RATIO * .sheet_ohm)
    )]
    ContactRatio {
        /// The contact resistance, ohm.
        contact_ohm: f64,
        /// The sheet resistance, ohm per square.
        sheet_ohm: f64,
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
        let field = |field, fault| Err(SheetError::Field { field, fault });
        let value = |value, rule| FieldFault::Value { value, rule };
        if !(self.sheet_resistance.is_finite() && self.sheet_resistance > 0.0) {
            let rule = "positive (ohm per square)";
            return field("sheet.sheet_resistance", value(self.sheet_resistance, rule));
        }
        let (low, high) = SHEET_OHM_RANGE;
        if !(low..=high).contains(&self.sheet_resistance) {
            let fault = FieldFault::Span {
                value: self.sheet_resistance,
                low,
                high,
                unit: "ohm per square",
                why: "from a metal plate's (above 1e-6) to an antistatic film's (below \
                      1e12), so that frames, the current times it, stay within single precision",
            };
            return field("sheet.sheet_resistance", fault);
        }
        let e = &self.electrodes;
        if !(4..=32).contains(&e.count) || !e.count.is_multiple_of(2) {
            let count = f64::from(e.count);
            return field("sheet.electrodes.count", value(count, "even, 4 to 32"));
        }
        if !(e.width.is_finite() && e.width > 0.0) {
            let rule = "a positive length in m";
            return field("sheet.electrodes.width", value(e.width, rule));
        }
        if !(e.contact_ohm.is_finite() && e.contact_ohm >= 0.0) {
            return field(
                "sheet.electrodes.contact_ohm",
                value(e.contact_ohm, ">= 0 ohm"),
            );
        }
        if e.contact_ohm > MAX_CONTACT_RATIO * self.sheet_resistance {
            let fault = FieldFault::ContactRatio {
                contact_ohm: e.contact_ohm,
                sheet_ohm: self.sheet_resistance,
            };
            return field("sheet.electrodes.contact_ohm", fault);
        }
        e.placement_checked()?;
        // The electrodes apart on the outline (the simulator and the meshes alike): each
        // covers its width of the outline (a point electrode only its place).
        let perimeter = self.shape.perimeter();
        let half = match e.model {
            ElectrodeModel::Point => 0.0,
            _ => 0.5 * e.width / perimeter,
        };
        let mut at: Vec<(f64, usize)> = (e.arc_positions(&self.shape).iter().enumerate())
            .map(|(l, t)| (t.rem_euclid(1.0), l))
            .collect();
        at.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (w, &(t, l)) in at.iter().enumerate() {
            let (next, m) = match at.get(w + 1) {
                Some(&n) => n,
                None => at.first().map_or((t, l), |&(u, m)| (u + 1.0, m)),
            };
            if m != l && next - t <= 2.0 * half || next <= t {
                return Err(SheetError::Overlap {
                    a: l,
                    b: m,
                    count: e.count,
                    width: e.width,
                    perimeter,
                });
            }
        }
        Ok(())
    }
}

impl ElectrodeSpec {
    /// Checks where the electrodes are placed: `first_deg` finite, `first` and each of
    /// `positions` an arc-length fraction within (-1, 1) (an angle given there, 90 for
    /// `first_deg = 90` or 6.28 rad, wrapped round the outline to another place: a rotated
    /// image without a word), one way of placing them at a time.
    fn placement_checked(&self) -> Result<(), SheetError> {
        let field = |field, fault| Err(SheetError::Field { field, fault });
        let value = |value, rule| FieldFault::Value { value, rule };
        if let Some(deg) = self.first_deg {
            if !deg.is_finite() {
                let rule = "a finite angle in degrees";
                return field("sheet.electrodes.first_deg", value(deg, rule));
            }
            if self.first.is_some() {
                let rule = "give first_deg (an angle) or first (an arc fraction), not both";
                return field("sheet.electrodes.first_deg", FieldFault::Rule(rule));
            }
        }
        // Positions place every electrode: a first place or a direction beside them would
        // be ignored without a word.
        if self.positions.is_some()
            && (self.first.is_some()
                || self.first_deg.is_some()
                || self.direction != Direction::Ccw)
        {
            let rule = "positions place every electrode: give them, or first/first_deg and \
                        direction, not both";
            return field("sheet.electrodes.positions", FieldFault::Rule(rule));
        }
        if let Some(p) = &self.positions
            && (p.len() != usize::from(self.count) || p.iter().any(|x| !x.is_finite()))
        {
            let fault = FieldFault::Count {
                found: p.iter().filter(|x| x.is_finite()).count(),
                need: usize::from(self.count),
                what: "finite arc fractions",
            };
            return field("sheet.electrodes.positions", fault);
        }
        let fraction = "an arc-length fraction of the outline from its start, between -1 and 1 \
                        (an angle in degrees is first_deg; positions of angles: each / 360 \
                        degrees, or / 2 pi radians)";
        let outside = |f: f64| f.is_nan() || f.abs() >= 1.0;
        if let Some(first) = self.first.filter(|f| outside(*f)) {
            return field("sheet.electrodes.first", value(first, fraction));
        }
        if let Some(&at) = (self.positions.iter().flatten()).find(|p| outside(**p)) {
            return field("sheet.electrodes.positions", value(at, fraction));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn near(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-9
    }

    /// Electrodes that do not fit apart on the outline are refused here, for the simulator
    /// and the meshes alike (a 1 nm disc with 5 mm electrodes was simulated, then refused by
    /// the mesher).
    #[test]
    fn electrodes_that_overlap_on_the_outline_are_refused() {
        let mut tiny = Sheet::disc(1e-9, 16);
        tiny.electrodes.width = 0.005;
        let e = tiny.validate().unwrap_err().to_string();
        assert!(
            e.contains("overlap") && e.contains("sheet.electrodes"),
            "{e}"
        );
        let mut fits = Sheet::disc(0.1, 16);
        fits.electrodes.width = 0.039; // 16 x 39 mm on a 628 mm outline: 0.3 mm apart
        fits.validate().unwrap();
        fits.electrodes.width = 0.04; // 640 mm
        assert!(fits.validate().is_err());
        // Two electrodes given at one place.
        let mut same = Sheet::disc(0.1, 4);
        same.electrodes.positions = Some(vec![0.1, 0.3, 0.3, 0.8]);
        let e = same.validate().unwrap_err().to_string();
        assert!(e.contains("electrodes 1 and 2 overlap"), "{e}");
        // Positions beside a first place or a direction (which they would override unsaid).
        let mut both = Sheet::disc(0.1, 4);
        both.electrodes.positions = Some(vec![0.1, 0.3, 0.5, 0.8]);
        both.validate().unwrap();
        both.electrodes.first_deg = Some(90.0);
        let e = both.validate().unwrap_err().to_string();
        assert!(e.contains("positions") && e.contains("not both"), "{e}");
        both.electrodes.first_deg = None;
        both.electrodes.direction = Direction::Cw;
        assert!(both.validate().is_err());
    }

    /// An angle where an arc-length fraction is read (`first = 90` for `first_deg = 90`,
    /// positions in radians) wrapped round the outline to another place: the 28 cm tank's
    /// touch imaged at (36.8, -44.8) mm for (50, 40), with the fit as good as the right
    /// numbering's (a disc turned fits alike). Refused naming the field and first_deg; a
    /// fraction a little before the start (-0.03) places as 0.97 does.
    #[test]
    fn an_angle_given_as_an_arc_fraction_is_refused() {
        let mut first = Sheet::disc(0.14, 16);
        first.electrodes.first = Some(90.0);
        let e = first.validate().unwrap_err().to_string();
        assert!(
            e.starts_with("sheet.electrodes.first: 90 must be an arc-length fraction")
                && e.contains("an angle in degrees is first_deg"),
            "{e}"
        );
        let mut radians = Sheet::disc(0.14, 16);
        radians.electrodes.positions = Some(
            (0..16)
                .map(|i| f64::from(i) * std::f64::consts::TAU / 16.0)
                .collect(),
        );
        let e = radians.validate().unwrap_err().to_string();
        assert!(
            e.starts_with("sheet.electrodes.positions: 1.1780972450961724 must be")
                && e.contains("/ 2 pi radians"),
            "{e}"
        );
        first.electrodes.first = Some(-0.03);
        first.validate().unwrap();
        let before = first.electrodes.centres(&first.shape);
        first.electrodes.first = Some(0.97);
        let after = first.electrodes.centres(&first.shape);
        assert!(before.iter().zip(&after).all(|(a, b)| near(*a, *b)));
        first.electrodes.first = Some(f64::NAN);
        assert!(first.validate().is_err());
    }

    /// A tank numbered clockwise from the top, on a disc and on a rectangle; et's default.
    #[test]
    fn electrodes_sit_where_the_users_numbering_puts_them() {
        let mut disc = Sheet::disc(0.14, 16);
        let default = disc.electrodes.centres(&disc.shape);
        let at = |deg: f64| {
            let a = deg.to_radians();
            [0.14 * a.cos(), 0.14 * a.sin()]
        };
        assert!(near(default[0], at(11.25)) && near(default[1], at(33.75)));
        disc.electrodes.first_deg = Some(90.0);
        disc.electrodes.direction = Direction::Cw;
        disc.validate().unwrap();
        let cw = disc.electrodes.centres(&disc.shape);
        assert!(near(cw[0], at(90.0)), "{:?}", cw[0]);
        assert!(near(cw[1], at(67.5)), "{:?}", cw[1]);
        assert!(near(cw[4], at(0.0)), "{:?}", cw[4]);
        assert!(near(cw[15], at(112.5)), "{:?}", cw[15]);
        let mut square = Sheet::rectangle(0.2, 0.1, 8);
        square.electrodes.first_deg = Some(90.0);
        let c = square.electrodes.centres(&square.shape);
        // The top edge's middle (the rectangle is centred on the origin).
        assert!(near(c[0], [0.0, 0.05]), "{:?}", c[0]);
        square.electrodes.first = Some(0.1);
        assert!(
            square
                .validate()
                .unwrap_err()
                .to_string()
                .contains("not both")
        );
        square.electrodes.first = None;
        square.electrodes.first_deg = Some(f64::NAN);
        assert!(
            square
                .validate()
                .unwrap_err()
                .to_string()
                .contains("first_deg")
        );
    }

    /// A sheet resistance is taken from 1e-9 to 1e15 ohm/sq, ends included (1e-300 gave
    /// frames of zeros, 1e300 infinite ones), and the contact up to MAX_CONTACT_RATIO times it.
    #[test]
    fn sheets_past_the_range_of_real_ones_are_refused_by_name() {
        let mut sheet = Sheet::disc(0.1, 16);
        let (low, high) = SHEET_OHM_RANGE;
        for r in [low, high] {
            sheet.sheet_resistance = r;
            sheet.electrodes.contact_ohm = r;
            assert_eq!(sheet.validate(), Ok(()), "{r}");
        }
        for r in [low / 2.0, 2.0 * high, 1e-300, 1e300] {
            sheet.sheet_resistance = r;
            let e = sheet.validate().unwrap_err().to_string();
            assert!(
                e.starts_with("sheet.sheet_resistance: ") && e.contains("outside 1e-9 to 1e15"),
                "{e}"
            );
        }
        sheet.sheet_resistance = 1.0;
        sheet.electrodes.contact_ohm = MAX_CONTACT_RATIO;
        assert_eq!(sheet.validate(), Ok(()));
        sheet.electrodes.contact_ohm = 1.5 * MAX_CONTACT_RATIO;
        let e = sheet.validate().unwrap_err().to_string();
        assert!(
            e.contains("1.5e6 ohm is over 1e6 times the sheet resistance (1 ohm/sq)"),
            "{e}"
        );
    }

    /// A count no electrode count can be is said by the counts' rule, by every reader (a
    /// scene's TOML, the Python module's JSON), not as the parser's "expected u8".
    #[test]
    fn an_electrode_count_past_a_byte_is_said_by_the_rule() {
        for count in ["300", "-4", "1099511627776"] {
            let e = serde_json::from_str::<ElectrodeSpec>(&format!(r#"{{"count": {count}}}"#))
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("{count} must be even, 4 to 32")), "{e}");
        }
        let read: ElectrodeSpec = serde_json::from_str(r#"{"count": 16}"#).unwrap();
        assert_eq!(read.count, 16);
    }
}
