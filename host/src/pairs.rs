//! A protocol from its injections and its measurements listed apart, as tank archives and
//! other tools keep them: KIT4's and the Kuopio challenge's `injection_pairs` and
//! `measurement_pairs`, or their current and measurement patterns (`Injref`, `Mpat`),
//! EIDORS's `stim_pattern` and `meas_pattern`, pyEIT's `ex_mat`. Every measurement is taken
//! under every injection, in that order (value index = injection x M + measurement, the
//! frames those systems write), which [`cross`] turns into et's protocol file: a row per value
//! of the frame, its four electrodes and its current.
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

use et_core::schedule::{MAX_CURRENT_A, MIN_CURRENT_A, Row, Schedule};
use nalgebra::DMatrix;

use crate::frames::{self, FramesError};

mod error;
mod list;
mod patterns;
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
    let u = (unit.trim())
        .trim_start_matches(['(', '['])
        .trim_end_matches([')', ']'])
        .trim();
    let word = u.to_ascii_lowercase();
    let word = word.trim_end_matches('s');
    match (u, word) {
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
        let (matrix, said) = matrix.map_err(PairsError::Frames)?;
        return listed(spec, side, &matrix, &said, by);
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

/// Crosses `injections` with `measurements` (each a file of pairs or patterns: every
/// measurement under every injection, injection by injection) into a protocol, as
/// `crossing` tells.
///
/// # Errors
/// [`PairsError`]: a file unread or not pairs, the two not of one sheet, a current past
/// et's range (said with the unit to give), or more than [`MAX_VALUES`] values.
pub fn cross(
    injections: &Path,
    measurements: &Path,
    crossing: &Crossing,
) -> Result<Crossed, PairsError> {
    let by = crossing.by;
    let sides = [
        (injections, read(injections, Side::Injections, by)?),
        (measurements, read(measurements, Side::Measurements, by)?),
    ];
    let mut said: Vec<String> = sides.iter().map(|(_, l)| l.said.clone()).collect();
    let fail = |why: String| Err(PairsError::Crossing(why));
    if let Some(by) = by
        && !sides.iter().any(|(_, l)| l.either_way)
    {
        return fail(format!(
            "--patterns {}: no file needed it (each is read by its shape, as said above, or is \
             a list of pairs): leave it out",
            by.said()
        ));
    }
    for ((path, l), noun) in sides.iter().zip(["injection", "measurement"]) {
        if let Some((i, [e, _])) = l.pairs.iter().enumerate().find(|(_, p)| p[0] == p[1]) {
            return fail(format!(
                "{}: {noun} {} is between electrode {e} and itself: a pair is two electrodes",
                path.display(),
                i + 1
            ));
        }
    }
    let values = sides[0]
        .1
        .pairs
        .len()
        .saturating_mul(sides[1].1.pairs.len());
    if values > MAX_VALUES {
        return fail(format!(
            "{} injections x {} measurements = {values} values a frame, past the {MAX_VALUES} \
             et takes (every ordered pair of 32 electrodes under every other is 984 064): are \
             these the lists of pairs?",
            sides[0].1.pairs.len(),
            sides[1].1.pairs.len()
        ));
    }
    let (electrodes, base) = numbering(&sides, crossing, &mut said)?;
    let currents = currents_a(injections, &sides[0].1, crossing, &mut said)?;
    // Every pair from 0, as et counts.
    let from_zero = |l: &Listed| -> Vec<[u16; 2]> {
        let shift = if l.patterns.is_some() {
            0
        } else {
            u32::from(base)
        };
        (l.pairs.iter())
            .map(|p| p.map(|e| u16::try_from(e - shift).unwrap_or(u16::MAX)))
            .collect()
    };
    let (drives, measured) = (from_zero(&sides[0].1), from_zero(&sides[1].1));
    let mut rows = Vec::with_capacity(values);
    for (&[source, sink], &current_a) in drives.iter().zip(&currents) {
        for &[positive, negative] in &measured {
            let on_drive = [positive, negative]
                .iter()
                .any(|e| *e == source || *e == sink);
            if crossing.no_meas_current && on_drive {
                continue;
            }
            rows.push(Row {
                source,
                sink,
                positive,
                negative,
                current_a,
            });
        }
    }
    let left_out = values - rows.len();
    if crossing.no_meas_current && rows.is_empty() {
        return fail(format!(
            "--no-meas-current leaves none of the {values} values: every measurement uses a \
             drive electrode"
        ));
    }
    let k = rows.len();
    let schedule = Schedule::new(electrodes, rows)?;
    let (first, last) = (base, electrodes - 1 + base);
    let counted = if sides.iter().any(|(_, l)| l.patterns.is_none()) {
        "as the lists count them"
    } else if base == 1 {
        "counted from 1 (--base 1)"
    } else {
        "counted from 0, et's way (--base 1 writes them from 1)"
    };
    said.push(format!(
        "K = {k} values a frame: {} injections x {} measurements, injection by injection{}; \
         electrodes {first} to {last}, {counted} (a scene reads the file as [scan] protocol = \
         {{ file = \"protocol.csv\"{} }})",
        drives.len(),
        measured.len(),
        if left_out > 0 {
            format!(", less the {left_out} on an injection's drive electrodes (--no-meas-current)")
        } else {
            String::new()
        },
        if base == 1 { ", base = 1" } else { "" },
    ));
    Ok(Crossed {
        schedule,
        base,
        said,
    })
}

/// The sheet's electrodes and what the lists count from: as given, else from the files (a
/// matrix's patterns' length; a list's largest number; electrode 0 in a list counts from
/// 0, none from 1), every list's number checked against them.
fn numbering(
    sides: &[(&Path, Listed); 2],
    crossing: &Crossing,
    said: &mut Vec<String>,
) -> Result<(u16, u16), PairsError> {
    let fail = |why: String| Err(PairsError::Crossing(why));
    let lists = || sides.iter().filter(|(_, l)| l.patterns.is_none());
    let least = lists()
        .flat_map(|(_, l)| l.pairs.iter().flatten())
        .min()
        .copied();
    let most = lists()
        .flat_map(|(_, l)| l.pairs.iter().flatten())
        .max()
        .copied();
    let base = match (crossing.base, least) {
        (Some(base), Some(0)) if base > 0 => {
            return fail(format!(
                "--base {base}: the lists hold electrode 0, which is none of their electrodes \
                 counted from {base}: leave --base out, or give --base 0"
            ));
        }
        (Some(0), Some(least)) if least > 0 => {
            said.push(format!(
                "the lists count electrodes from 0 (--base 0), though none is electrode 0 (the \
                 least is {least}): do they count from 1? then leave --base out"
            ));
            0
        }
        (Some(base), _) => base,
        (None, Some(0)) => {
            said.push("the lists count electrodes from 0 (they hold an electrode 0)".into());
            0
        }
        (None, Some(_)) => {
            said.push(
                "the lists count electrodes from 1 (they hold no electrode 0; give --base 0 if \
                 they count from 0)"
                    .into(),
            );
            1
        }
        (None, None) => 0,
    };
    let mut lengths = sides
        .iter()
        .filter_map(|(p, l)| l.patterns.map(|n| (*p, n)));
    let patterns = lengths.next();
    if let (Some((a, n)), Some((b, m))) = (patterns, lengths.next())
        && n != m
    {
        return fail(format!(
            "{} has patterns of {n} electrodes and {} of {m}: they are not of one sheet",
            a.display(),
            b.display()
        ));
    }
    let electrodes = match (crossing.electrodes, patterns, most) {
        (Some(l), Some((path, n)), _) if usize::from(l) != n => {
            return fail(format!(
                "-l {l}, but {}'s patterns are of {n} electrodes: leave -l out, or give -l {n}",
                path.display()
            ));
        }
        (Some(l), _, _) => usize::from(l),
        (None, Some((_, n)), _) => n,
        (None, None, Some(most)) => {
            let l = (most + 1).saturating_sub(u32::from(base)) as usize;
            said.push(format!(
                "{l} electrodes, the largest number in the lists (give -l if the sheet has more)"
            ));
            l
        }
        (None, None, None) => unreachable!("two lists hold a pair each"),
    };
    let range = usize::from(et_core::protocol::L_MIN)..=usize::from(et_core::protocol::L_MAX);
    if !range.contains(&electrodes) {
        return fail(format!(
            "{electrodes} electrodes: et takes {} to {}",
            range.start(),
            range.end()
        ));
    }
    let past = u32::try_from(electrodes).unwrap_or(u32::MAX) - 1 + u32::from(base);
    for (path, l) in lists() {
        if let Some(e) = l.pairs.iter().flatten().find(|&&e| e > past) {
            return fail(format!(
                "{}: electrode {e}, past the sheet's {electrodes} (counted from {base}, the last \
                 is {past}): give -l with the sheet's electrodes",
                path.display()
            ));
        }
    }
    Ok((u16::try_from(electrodes).unwrap_or(u16::MAX), base))
}

/// Each injection's current, A: as given (`--current-a`), else the file's in its unit (its
/// name's, or as given), else 1 mA; each in et's range, a unit slip said with the fix.
fn currents_a(
    path: &Path,
    injections: &Listed,
    crossing: &Crossing,
    said: &mut Vec<String>,
) -> Result<Vec<f64>, PairsError> {
    let fail = |why: String| Err(PairsError::Crossing(why));
    let n = injections.pairs.len();
    let (file, unit) = match (
        &injections.currents,
        crossing.current_a,
        &crossing.current_unit,
    ) {
        (None, Some(a), _) => return Ok(vec![a; n]),
        (None, None, Some((u, _))) => {
            return fail(format!(
                "--current-unit {u}: {} gives no currents (a list of two columns): give every \
                 injection's with --current-a",
                path.display()
            ));
        }
        (None, None, None) => {
            said.push("every injection drives 1 mA (give --current-a for another)".into());
            return Ok(vec![1e-3; n]);
        }
        (Some((file, _)), Some(a), _) => {
            if file.iter().any(|c| *c != file[0]) {
                return fail(format!(
                    "--current-a {a:e}: {} gives each injection its own current ({:e} to {:e}): \
                     leave --current-a out, and give their unit with --current-unit",
                    path.display(),
                    file.iter().copied().fold(f64::INFINITY, f64::min),
                    file.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                ));
            }
            said.push(format!(
                "every injection drives {a:e} A (--current-a, in place of the file's {:e} for \
                 each)",
                file[0]
            ));
            return Ok(vec![a; n]);
        }
        (Some((file, unit)), None, given) => (file, (unit, given)),
    };
    let (name, per) = match unit {
        (Unit::Named(named, per), Some((given, g))) if per != g => {
            return fail(format!(
                "--current-unit {given}, but {} names its currents' unit {named}: leave \
                 --current-unit out",
                path.display()
            ));
        }
        (Unit::Named(named, per), _) => (named.clone(), *per),
        (Unit::Unsaid | Unit::Asked(_), Some((given, g))) => (given.clone(), *g),
        (Unit::Unsaid, None) => ("A".to_string(), 1.0),
        (Unit::Asked(column), None) => {
            return fail(format!(
                "{}: the column '{column}' gives each injection's current in a unit its name does \
                 not say: give it with --current-unit mA (or A, uA, as the system writes them), \
                 or name the column current_ma",
                path.display()
            ));
        }
    };
    let amperes: Vec<f64> = file.iter().map(|c| c * per).collect();
    for (i, &a) in amperes.iter().enumerate() {
        if !(MIN_CURRENT_A..=MAX_CURRENT_A).contains(&a) {
            let hint = if per == 1.0 && (1.0..=50.0).contains(&file[i]) {
                if file.iter().all(|c| *c == 1.0) {
                    ": patterns of 1 are a unit current's; give the current driven with \
                     --current-a (1e-3 for 1 mA)"
                } else {
                    ": in mA? give --current-unit mA"
                }
            } else {
                ""
            };
            return fail(format!(
                "{}: injection {} drives {} {name} = {a:e} A, outside the {MIN_CURRENT_A:e} to \
                 {MAX_CURRENT_A} A et takes{hint}",
                path.display(),
                i + 1,
                file[i]
            ));
        }
    }
    let (least, most) = amperes
        .iter()
        .fold((f64::INFINITY, 0.0_f64), |(l, m), &a| (l.min(a), m.max(a)));
    said.push(if least == most {
        format!(
            "every injection drives {least:e} A (the file's {} {name})",
            file[0]
        )
    } else {
        format!("injections drive {least:e} to {most:e} A (the file's, in {name})")
    });
    Ok(amperes)
}
