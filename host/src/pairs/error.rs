//! Why two lists could not be crossed into a protocol, naming the file, its line or pattern,
//! and the fix.

use std::path::{Path, PathBuf};

use et_core::schedule::ScheduleError;

use super::{By, Side};
use crate::frames::FramesError;

/// Why two lists could not be crossed into a protocol.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PairsError {
    /// A file could not be read as numbers (said as frames' files are).
    #[error(transparent)]
    Frames(FramesError),
    /// A file's content is not a list of pairs or patterns.
    #[error("{}{}: {fault}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Content {
        /// The file.
        path: PathBuf,
        /// 1-based line of a text file (0: not about one line).
        line: usize,
        /// What is wrong.
        fault: PairsFault,
    },
    /// The two lists do not make a protocol together, or with what was given.
    #[error("{0}")]
    Crossing(String),
    /// The crossed rows, refused as a protocol file's would be.
    #[error("the crossed protocol: {0}")]
    Schedule(#[from] ScheduleError),
}

impl PairsError {
    pub(super) fn content(path: &Path, line: usize, fault: PairsFault) -> Self {
        Self::Content {
            path: path.into(),
            line,
            fault,
        }
    }
}

/// What is wrong in a file of pairs or patterns.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum PairsFault {
    /// The rows could not be read as CSV.
    #[error(transparent)]
    Records(et_core::text::RecordFault),
    /// Nothing in it.
    #[error("no pairs (an empty file, or a header alone)")]
    Empty,
    /// NaN or an infinite value.
    #[error("row {row}, column {column} (from 0) is not a number: every pair needs its values")]
    NotFinite {
        /// Row (from 0).
        row: usize,
        /// Column (from 0).
        column: usize,
    },
    /// A list (no negative number) of another width.
    #[error(
        "{columns} columns of numbers, none below 0: a list of {noun}s has {wanted} a row \
         (without a header; with one, name the columns {names}), and a matrix of patterns \
         holds a - at each {noun}'s {minus}",
        noun = side.noun(),
        wanted = match side {
            Side::Injections => "source and sink, and optionally the current,",
            Side::Measurements => "positive and negative",
        },
        names = match side {
            Side::Injections => "source, sink and optionally current_a",
            Side::Measurements => "positive and negative",
        },
        minus = match side {
            Side::Injections => "sink",
            Side::Measurements => "negative electrode",
        }
    )]
    Width {
        /// Which list.
        side: Side,
        /// The columns read.
        columns: usize,
    },
    /// A list's electrode that is not a whole number.
    #[error("row {row} (from 0): {value} is not an electrode's number")]
    NotElectrode {
        /// Row (from 0).
        row: usize,
        /// The value.
        value: f64,
    },
    /// A list's current below 0 (a system's sign for the other way round).
    #[error(
        "row {row} (from 0): a current of {value}: currents are above 0 (a system's sign for \
         the current the other way round: swap the row's source and sink)"
    )]
    Negative {
        /// Row (from 0).
        row: usize,
        /// The value.
        value: f64,
    },
    /// A named list's cell that is not a number.
    #[error("{column}: '{cell}' is not {}", if *column == "its current" { "a number" } else { "an electrode's number" })]
    NotNumber {
        /// The column's role.
        column: &'static str,
        /// The cell as written.
        cell: String,
    },
    /// A header without the side's two electrodes.
    #[error(
        "the header names {names}{other}: name the {noun}s' columns {wanted} (any order, other \
         columns ignored; I+, I-, V+, V-, A, B, M, N and names beginning source_, sink_, \
         plus_, minus_ are read too)",
        noun = side.noun(),
        other = if *other {
            match side {
                Side::Injections => ", a list of measurements: give it as --measurements",
                Side::Measurements => ", a list of injections: give it as --injections",
            }
        } else {
            ""
        },
        wanted = match side {
            Side::Injections => "source and sink (and optionally current_a)",
            Side::Measurements => "positive and negative",
        }
    )]
    Names {
        /// Which list.
        side: Side,
        /// The header's first names.
        names: String,
        /// The names are the other side's.
        other: bool,
    },
    /// A square matrix whose rows and columns are both patterns, read differently.
    #[error(
        "{rows} x {columns}, whose rows and columns both read as {noun} patterns, differently: \
         say which with --patterns rows (EIDORS's meas_pattern, a CSV of a pattern a line) or \
         --patterns columns (KIT4's and the Kuopio challenge's Injref and Mpat)",
        noun = side.noun()
    )]
    EitherWay {
        /// Which list.
        side: Side,
        /// Its rows.
        rows: usize,
        /// Its columns.
        columns: usize,
    },
    /// A line of a matrix that is not a pattern.
    #[error(
        "{noun} pattern {n} (its {by} {n}, from 1): {why}",
        noun = side.noun(),
        n = i + 1,
        by = by.said().trim_end_matches('s')
    )]
    Pattern {
        /// Which list.
        side: Side,
        /// How the patterns lie.
        by: By,
        /// The pattern (from 0).
        i: usize,
        /// Why it is not one.
        why: String,
    },
}
