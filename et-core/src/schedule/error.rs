//! Why a schedule or a schedule file is refused: each fault with its numbers.

/// Why a schedule is refused. Rows are counted from 0, as the frame's values are.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum ScheduleError {
    /// No rows at all.
    #[error("no measurements")]
    Empty,
    /// Fewer than two electrodes.
    #[error("{electrodes} electrodes: a schedule needs 2 or more")]
    Electrodes {
        /// The count given.
        electrodes: u16,
    },
    /// An electrode past the sheet's.
    #[error(
        "row {row}: electrode {electrode}, the sheet has {electrodes} (0 to {last}){hint}",
        last = electrodes.saturating_sub(1),
        hint = if *electrode == *electrodes { ": are the electrodes counted from 1? say base = 1" } else { "" }
    )]
    Electrode {
        /// The row.
        row: usize,
        /// The electrode named.
        electrode: u16,
        /// The sheet's electrode count.
        electrodes: u16,
    },
    /// An electrode to leave out ([`super::Schedule::without`]) past the sheet's.
    #[error(
        "electrode {electrode} to leave out: the sheet has {electrodes} (0 to {last})",
        last = electrodes.saturating_sub(1)
    )]
    Absent {
        /// The electrode named.
        electrode: u16,
        /// The sheet's electrode count.
        electrodes: u16,
    },
    /// More electrodes to leave out ([`super::Schedule::without`]) than half the sheet's.
    #[error(
        "{left_out} of the {electrodes} electrodes to leave out: at most half ({}) may be, \
         the image being made of the rest's values alone",
        electrodes / 2
    )]
    TooManyLeftOut {
        /// Distinct electrodes to leave out.
        left_out: u16,
        /// The sheet's electrode count.
        electrodes: u16,
    },
    /// Every row involves an electrode to leave out ([`super::Schedule::without`]): nothing
    /// would be left to image (opposite's rows each touch four electrodes half a sheet apart).
    #[error(
        "every one of the {rows} values involves one of the {left_out} electrodes to leave out: \
         nothing would be left to image; leave fewer out"
    )]
    NothingLeft {
        /// The schedule's rows.
        rows: usize,
        /// Distinct electrodes to leave out.
        left_out: u16,
    },
    /// The current would enter and leave by one electrode.
    #[error("row {row}: source and sink are both electrode {electrode}")]
    SameDrive {
        /// The row.
        row: usize,
        /// The electrode.
        electrode: u16,
    },
    /// The measurement's two electrodes are one.
    #[error("row {row}: positive and negative are both electrode {electrode}")]
    SameMeasure {
        /// The row.
        row: usize,
        /// The electrode.
        electrode: u16,
    },
    /// A current that is not positive or not finite.
    #[error(
        "row {row}: current {current_a} A: give a current above 0 A{}",
        if *current_a < 0.0 {
            " (a current the other way: swap the row's source and sink, and give its size)"
        } else {
            ""
        }
    )]
    Current {
        /// The row.
        row: usize,
        /// The current given, A.
        current_a: f64,
    },
    /// A current below [`MIN_CURRENT_A`].
    #[error(
        "row {row}: current {current_a:e} A is below 1 nA, the smallest a board drives (systems \
         drive microamperes to milliamperes): currents are in amperes"
    )]
    BelowNano {
        /// The row.
        row: usize,
        /// The current given, A.
        current_a: f64,
    },
    /// A current above [`MAX_UNIT_CURRENT_A`], whoever gave it.
    #[error(
        "row {row}: current {current_a} A is above 1 A, the unit current of simulated frames \
         (pyEIT's): currents are in amperes, a system's a few mA"
    )]
    AboveUnit {
        /// The row.
        row: usize,
        /// The current given, A.
        current_a: f64,
    },
    /// A user's current above [`MAX_CURRENT_A`] (a file's, a scene's).
    #[error("row {row}: current {current_a} A is above 0.05 A (50 mA): current_a is in amperes")]
    TooLarge {
        /// The row.
        row: usize,
        /// The current given, A.
        current_a: f64,
    },
    /// A schedule file could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Why (shared, so the error stays `Clone`).
        source: std::sync::Arc<std::io::Error>,
    },
    /// A line of a schedule file is wrong.
    #[error("{}{}: {fault}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// 1-based line (0: the whole file).
        line: usize,
        /// What is wrong.
        fault: FileFault,
    },
}

/// What is wrong in a schedule file, at its line.
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum FileFault {
    /// The rows could not be read as CSV.
    #[error(transparent)]
    Records(#[from] crate::text::RecordFault),
    /// No rows.
    #[error("no rows")]
    NoRows,
    /// The header lacks a column.
    #[error(
        "the header has no '{0}' column (it needs source, sink, positive, negative and \
         optionally current_a)"
    )]
    MissingColumn(&'static str),
    /// A header naming a list of injections alone (source and sink) or of measurements
    /// alone (positive and negative), as tank archives list them apart.
    #[error(
        "the header names the {0} alone: a protocol file has a row per frame value, its four \
         electrodes; a list of injections and one of measurements, each measured under every \
         injection, are crossed into one by `et protocol --injections injection_pairs.csv \
         --measurements measurement_pairs.csv > protocol.csv`"
    )]
    PairsOnly(&'static str),
    /// A header that names a column twice.
    #[error("the header names {0} twice: which column is meant would be a guess")]
    SameColumn(&'static str),
    /// Without a header, a row of another width.
    #[error(
        "{0} column{s}: without a header give source, sink, positive, negative and optionally \
         current_a, separated by ',', ';', tabs or spaces{wide}",
        s = if *.0 == 1 { "" } else { "s" },
        wide = if *.0 > 5 {
            " (a row of every electrode's current, an injection pattern as EIDORS's \
             stim_pattern writes one, is another form: give one row per frame value, its four \
             electrodes; `et protocol --csv` writes an example)"
        } else {
            ""
        }
    )]
    Columns(usize),
    /// A row of another width than the first (a current in some rows only would be a
    /// guess: the rows without one took the default and the others' were ignored).
    #[error(
        "{cells} cell{s}, where the first row has {first}: give every row the same columns \
         (a current_a for every row or for none)",
        s = if *.cells == 1 { "" } else { "s" }
    )]
    Width {
        /// This row's cells.
        cells: usize,
        /// The first row's (the header's, or the first data row's).
        first: usize,
    },
    /// A header column other than current_a named as a current, which would be ignored.
    #[error(
        "the column '{0}' reads as a current, but et takes a row's current only from a column \
         named current_a, in amperes (1.4142 mA is 0.0014142), and without one each row drives \
         the scene's current_ua: name it current_a in amperes, or leave it out"
    )]
    OtherCurrent(String),
    /// A first row of names, none of them a column's.
    #[error(
        "the header names {0}: name the columns source, sink, positive, negative and \
         optionally current_a (any order; I+, I-, V+, V- and A, B, M, N are read as the four \
         too)"
    )]
    OtherNames(String),
    /// Another of et's files given as a protocol file.
    #[error(
        "{}, not a protocol file (a CSV of source, sink, positive, negative and optionally \
         current_a, as et protocol --csv writes)",
        .0.said()
    )]
    OtherFile(crate::text::EtFile),
    /// Electrodes counted from neither 0 nor 1.
    #[error("base = {0}: electrodes are counted from 0 (et's) or 1")]
    Base(u16),
    /// An electrode's cell is not a whole number (`2`, or `2.0` and `2.000e+00` as NumPy's
    /// `savetxt` writes them; `2.5` is refused, not truncated).
    #[error("{column}: '{cell}' is not an electrode number")]
    NotElectrode {
        /// source, sink, positive or negative.
        column: &'static str,
        /// The cell as written.
        cell: String,
    },
    /// An electrode below the first one's number.
    #[error("{column}: electrode {electrode}, but they are counted from {base}")]
    BelowBase {
        /// source, sink, positive or negative.
        column: &'static str,
        /// The number written.
        electrode: u16,
        /// The first electrode's number.
        base: u16,
    },
    /// The current's cell is not a number.
    #[error("current_a: '{cell}' is not a number{hint}", cell = .0, hint = crate::text::fortran_said(.0))]
    NotCurrent(String),
    /// The row, read, is refused by [`Schedule::new`] (row counted among the data rows).
    #[error(transparent)]
    Row(Box<ScheduleError>),
}
