//! A protocol from its injections and its measurements listed apart, as tank archives and
//! other tools keep them: KIT4's and the Kuopio challenge's `injection_pairs` and
//! `measurement_pairs`, or their current and measurement patterns (`Injref`, `Mpat`),
//! EIDORS's `stim_pattern` and `meas_pattern`, an injections list as pyEIT's `ex_mat`. Every
//! measurement is taken under every injection, in that order (value index = injection x M +
//! measurement, the frames those systems write), which [`cross`] turns into et's protocol
//! file: a row per value of the frame, its four electrodes and its current.
//!
//! Each side is a list of pairs or a matrix of patterns. A list has a row per injection
//! (`source`, `sink` and optionally its current) or measurement (`positive`, `negative`),
//! named in a header (et's names, other tools', or names beginning with them:
//! `source_electrode(+)`, `plus_electrode`; other columns, such as a row's number, ignored)
//! or, without one, the two electrodes first. A matrix has a pattern per injection (an
//! L-vector of electrode currents: +I at the source, -I at the sink, 0 elsewhere) or per
//! measurement (+1 at the positive electrode, -1 at the negative), by rows or by columns,
//! in a CSV, `.npy`, `.npz:NAME` or `.mat:VARIABLE` as frames are read. A file with a
//! negative number is a matrix; one without is a list.

use std::path::Path;

use et_core::schedule::Schedule;
use nalgebra::DMatrix;

use crate::frames::{self, FramesError};

mod cross;
mod eidors;
mod error;
mod list;
mod patterns;
pub use cross::cross;
pub use eidors::stimulation;
pub use error::{PairsError, PairsFault};
use patterns::patterns;

/// The most values a crossed frame may hold: every ordered pair of 32 electrodes driving
/// every such pair measuring is 984 064.
pub const MAX_VALUES: usize = 1 << 20;

/// Which list a file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// Pairs driving a current (source, sink).
    Injections,
    /// Pairs measured (positive, negative).
    Measurements,
}

impl Side {
    /// The protocol file's columns (`schedule::COLUMNS`) this side's two electrodes are.
    fn columns(self) -> [usize; 2] {
        match self {
            Self::Injections => [0, 1],
            Self::Measurements => [2, 3],
        }
    }

    /// One of the side's rows, in words.
    fn noun(self) -> &'static str {
        match self {
            Self::Injections => "injection",
            Self::Measurements => "measurement",
        }
    }
}

/// How a matrix's patterns lie, where its shape does not tell (a square matrix whose rows
/// and columns are both patterns).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum By {
    /// A pattern a row (EIDORS's `meas_pattern`, a CSV of one pattern a line).
    Rows,
    /// A pattern a column (KIT4's and the Kuopio challenge's `Injref` and `Mpat`).
    Columns,
}

impl By {
    fn said(self) -> &'static str {
        match self {
            Self::Rows => "rows",
            Self::Columns => "columns",
        }
    }
}

/// One side as read.
#[derive(Clone, Debug)]
pub struct Listed {
    /// Each pair's electrodes: as the file numbers them (a list) or from 0 (patterns).
    pub pairs: Vec<[u32; 2]>,
    /// Each pair's current in the file's unit, where the file gives one (a current column,
    /// an injection pattern's +I), and that unit.
    pub currents: Option<(Vec<f64>, Unit)>,
    /// A matrix's electrodes (its patterns' length); None for a list.
    pub patterns: Option<usize>,
    /// A square matrix whose rows and columns both read as patterns (read by `by`).
    pub either_way: bool,
    /// What was read, in words.
    pub said: String,
}

/// The unit of a file's currents.
#[derive(Clone, Debug, PartialEq)]
pub enum Unit {
    /// Named by the file (`current_a`, `current_ma`, `amplitude (mA)`): as named, and
    /// amperes per it.
    Named(String, f64),
    /// Not said (a pattern's +I, a list's third column without a header): amperes, unless
    /// given.
    Unsaid,
    /// A column named as a current whose name says no unit (`amplitude`): to be given.
    Asked(String),
}

/// What a crossing is told; None where the files tell it.
#[derive(Clone, Debug, Default)]
pub struct Crossing {
    /// Electrodes L (else a matrix's patterns' length, or the largest number a list holds).
    pub electrodes: Option<u16>,
    /// What the lists count electrodes from (else 0 where a list holds electrode 0, and 1
    /// where none does).
    pub base: Option<u16>,
    /// Every injection's current, A (else the files' currents; else 1 mA).
    pub current_a: Option<f64>,
    /// The unit of the files' currents, as named and in amperes (`("mA", 1e-3)`).
    pub current_unit: Option<(String, f64)>,
    /// How a square matrix whose rows and columns are both patterns is read.
    pub by: Option<By>,
    /// Leave out each injection's measurements on its drive electrodes (EIDORS's
    /// `no_meas_current`).
    pub no_meas_current: bool,
}

/// A protocol crossed from two lists.
#[derive(Clone, Debug)]
pub struct Crossed {
    /// Its rows, electrodes from 0.
    pub schedule: Schedule,
    /// What the files count electrodes from (the protocol file is written so).
    pub base: u16,
    /// What was read and done, a line each.
    pub said: Vec<String>,
}

impl Crossed {
    /// The protocol file: its header and a row per frame value, electrodes counted from
    /// [`Crossed::base`] as the files count them.
    #[must_use]
    pub fn to_csv(&self) -> String {
        self.schedule.to_csv_counted_from(self.base)
    }
}

/// The amperes per a unit of current as a file names it (`A`, `mA`, `uA`, `µA`, `nA`,
/// `amperes`, `milliamps`); None for any other word.
#[must_use]
pub fn amperes_per(unit: &str) -> Option<f64> {
    let (u, word) = frames::unit_words(unit);
    match (u, word.as_str()) {
        ("A", _) | (_, "amp" | "ampere") => Some(1.0),
        ("mA" | "ma", _) | (_, "milliamp" | "milliampere") => Some(1e-3),
        ("uA" | "ua" | "µA" | "μA", _) | (_, "microamp" | "microampere") => Some(1e-6),
        ("nA", _) | (_, "nanoamp" | "nanoampere") => Some(1e-9),
        _ => None,
    }
}

/// Reads one side from `spec` (a file, or `file.npz:NAME`, `file.mat:VARIABLE`).
///
/// # Errors
/// [`PairsError`] naming the file (its line or pattern) and the fix.
pub fn read(spec: &Path, side: Side, by: Option<By>) -> Result<Listed, PairsError> {
    if let Some(matrix) = frames::array_matrix(spec) {
        let read = (matrix.map_err(PairsError::Frames))
            .and_then(|(matrix, said)| listed(spec, side, &matrix, &said, by));
        return read.map_err(|e| eidors::given_as_lists(spec, e));
    }
    let text = et_core::text::read_text_at_most(spec, et_core::text::max_file_bytes()).map_err(
        |source| {
            PairsError::Frames(FramesError::Io {
                path: spec.into(),
                source,
            })
        },
    )?;
    let other = match list::named(spec, &text, side)? {
        list::Named::Listed(listed) => return Ok(listed),
        list::Named::Numbers => None,
        list::Named::Other(line, fault) => Some((line, fault)),
    };
    let (matrix, said) = frames::table_matrix(spec, &text).map_err(PairsError::Frames)?;
    let read = listed(spec, side, &matrix, &said, by)?;
    // A header of other names is a matrix of patterns' (the electrodes'); a list's columns it
    // would leave to their order, a row's number taken as its first electrode.
    match other {
        Some((line, fault)) if read.patterns.is_none() => {
            Err(PairsError::content(spec, line, fault))
        }
        _ => Ok(read),
    }
}

/// A matrix of numbers as one side: patterns where it holds a negative number, else a list
/// (two electrodes a row, and an injection's current third).
fn listed(
    spec: &Path,
    side: Side,
    m: &DMatrix<f64>,
    said: &str,
    by: Option<By>,
) -> Result<Listed, PairsError> {
    let fail = |fault| PairsError::content(spec, 0, fault);
    if m.is_empty() {
        return Err(fail(PairsFault::Empty));
    }
    if let Some(i) = m.iter().position(|v| !v.is_finite()) {
        let (row, column) = (i % m.nrows(), i / m.nrows());
        return Err(fail(PairsFault::NotFinite { row, column }));
    }
    let shape = format!("{} x {}", m.nrows(), m.ncols());
    // (A list is 2 or 3 columns wide: a negative number there, not a pattern, is said as a
    // list's, by its row.)
    let as_patterns = m.iter().any(|&v| v < 0.0).then(|| patterns(m, side, by));
    if let Some(read) = as_patterns.filter(|p| p.is_ok() || m.ncols() > 3) {
        let patterns::Patterns {
            pairs,
            sizes: currents,
            electrodes,
            by: read_by,
            either_way,
        } = read.map_err(fail)?;
        let n = pairs.len();
        let said = format!(
            "{}: {said}{shape}, {n} {} patterns of {electrodes} electrodes, one a {}",
            spec.display(),
            side.noun(),
            read_by.said().trim_end_matches('s'),
        );
        let currents = (side == Side::Injections).then_some((currents, Unit::Unsaid));
        return Ok(Listed {
            pairs,
            currents,
            patterns: Some(electrodes),
            either_way,
            said,
        });
    }
    let width = match side {
        Side::Injections => 2..=3,
        Side::Measurements => 2..=2,
    };
    if !width.contains(&m.ncols()) {
        return Err(fail(PairsFault::Width {
            side,
            columns: m.ncols(),
        }));
    }
    let mut pairs = Vec::with_capacity(m.nrows());
    for (row, r) in m.row_iter().enumerate() {
        let electrode = |c: usize| {
            let v = r[c];
            (v.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(&v))
                .then_some(v as u32)
                .ok_or(PairsFault::NotElectrode { row, value: v })
        };
        pairs.push([electrode(0).map_err(fail)?, electrode(1).map_err(fail)?]);
        if m.ncols() == 3 && r[2] < 0.0 {
            return Err(fail(PairsFault::Negative { row, value: r[2] }));
        }
    }
    let currents = (m.ncols() == 3).then(|| (m.column(2).iter().copied().collect(), Unit::Unsaid));
    let said = format!(
        "{}: {said}{shape}, {} {} pairs{}",
        spec.display(),
        pairs.len(),
        side.noun(),
        if currents.is_some() {
            " and their currents"
        } else {
            ""
        }
    );
    Ok(Listed {
        pairs,
        currents,
        patterns: None,
        either_way: false,
        said,
    })
}
