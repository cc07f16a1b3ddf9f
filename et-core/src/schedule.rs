//! A frame's measurements as any EIT system lists them (docs/method.md §4): for each value of
//! the frame, the two electrodes that drive the current (source, sink), the two that measure
//! (positive, negative: the value is U_positive - U_negative) and the current, in amperes.
//!
//! et's built-in protocols are one way to make a schedule ([`Schedule::of_protocol`]); a CSV
//! file with one row per frame value is another ([`Schedule::read_csv`]): columns `source`,
//! `sink`, `positive`, `negative` and optionally `current_a`, named in a header or in that
//! order without one. A schedule may hold anything other systems measure: several injection
//! families in one frame, all-against-one injections, injections from some electrodes only,
//! repeated rows, measurements on the drive electrodes (the complete electrode model accounts
//! for their contact; the point model cannot), and a current per row.
//!
//! Behind the `std` feature, as [`crate::sheet`]: the board scans its built-in protocols.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::ScanConfig;
use crate::config::ConfigError;
use crate::protocol::{L_MAX, L_MIN, Protocol, ProtocolKind};
use crate::text;

/// The largest current a row may drive, A (tank systems drive up to a few mA; 50 mA is far
/// beyond any of them and below anything that would be a typing error of mA for A).
pub const MAX_CURRENT_A: f64 = 0.05;

/// The largest current any schedule may drive, A: the unit current of simulated frames
/// (pyEIT's, which the Python module images with `current_a=1.0`). A system's own files and
/// scenes are held to [`MAX_CURRENT_A`], where more is a unit slip.
pub const MAX_UNIT_CURRENT_A: f64 = 1.0;

/// The smallest current a row may drive, A: the board's step (1 nA). Systems drive from
/// microamperes to milliamperes; far less is a unit slip, and its frames (1e-300 A gave
/// 1e-297 V) are past the single precision et takes frames in.
pub const MIN_CURRENT_A: f64 = 1e-9;

/// One value of the frame: who drives, who measures, with how much current.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// The electrode the current enters by (0-based).
    pub source: u16,
    /// The electrode it leaves by.
    pub sink: u16,
    /// The measurement's positive electrode: the value is U_positive - U_negative.
    pub positive: u16,
    /// The measurement's negative electrode.
    pub negative: u16,
    /// The current from source to sink, A.
    pub current_a: f64,
}

impl Row {
    /// Whether the measurement touches a drive electrode (it then reads the contact's drop
    /// as well as the sheet's).
    #[must_use]
    pub fn on_drive(&self) -> Option<u16> {
        [self.positive, self.negative]
            .into_iter()
            .find(|&e| e == self.source || e == self.sink)
    }
}

/// The measurements of a frame, in frame order, on a sheet of `electrodes` electrodes.
#[derive(Clone, Debug, PartialEq)]
pub struct Schedule {
    electrodes: u16,
    rows: Vec<Row>,
    /// The built-in protocol it was made from, if it was.
    kind: Option<ProtocolKind>,
}

/// A schedule file's columns, in this order.
pub const COLUMNS: [&str; 5] = ["source", "sink", "positive", "negative", "current_a"];

/// An electrode's number as a cell writes it: `2`, or a whole number written as a decimal
/// (`2.0`; `2.000000000000000000e+00`, as NumPy's `savetxt` writes every number by default);
/// None for a fraction, a negative number or one past `u16`.
fn whole_cell(cell: &str, delimiter: text::Delimiter) -> Option<u16> {
    if let Ok(n) = cell.parse::<u16>() {
        return Some(n);
    }
    let x = text::number(cell, delimiter)?;
    (x.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(&x)).then_some(x as u16)
}

impl Schedule {
    /// A schedule of `rows` on `electrodes` electrodes, every row checked.
    ///
    /// # Errors
    /// [`ScheduleError`] naming the first row that is wrong.
    pub fn new(electrodes: u16, rows: Vec<Row>) -> Result<Self, ScheduleError> {
        if electrodes < 2 {
            return Err(ScheduleError::Electrodes { electrodes });
        }
        if rows.is_empty() {
            return Err(ScheduleError::Empty);
        }
        for (row, r) in rows.iter().enumerate() {
            for electrode in [r.source, r.sink, r.positive, r.negative] {
                if electrode >= electrodes {
                    return Err(ScheduleError::Electrode {
                        row,
                        electrode,
                        electrodes,
                    });
                }
            }
            if r.source == r.sink {
                return Err(ScheduleError::SameDrive {
                    row,
                    electrode: r.source,
                });
            }
            if r.positive == r.negative {
                return Err(ScheduleError::SameMeasure {
                    row,
                    electrode: r.positive,
                });
            }
            if !(r.current_a.is_finite() && r.current_a > 0.0) {
                return Err(ScheduleError::Current {
                    row,
                    current_a: r.current_a,
                });
            }
            if r.current_a > MAX_UNIT_CURRENT_A {
                return Err(ScheduleError::AboveUnit {
                    row,
                    current_a: r.current_a,
                });
            }
            if r.current_a < MIN_CURRENT_A {
                return Err(ScheduleError::BelowNano {
                    row,
                    current_a: r.current_a,
                });
            }
        }
        Ok(Self {
            electrodes,
            rows,
            kind: None,
        })
    }

    /// Every adjacent pair (m, m + 1) measured under each of `injections` (source, sink), the
    /// drive electrodes' pairs too, at `current_a`: how many laboratory systems scan (a tank's
    /// adjacent, skip and all-against-one families in one frame). K = L x injections.
    ///
    /// # Errors
    /// As [`Schedule::new`].
    pub fn adjacent_pairs_under(
        electrodes: u16,
        injections: &[(u16, u16)],
        current_a: f64,
    ) -> Result<Self, ScheduleError> {
        let rows = injections
            .iter()
            .flat_map(|&(source, sink)| {
                (0..electrodes).map(move |m| Row {
                    source,
                    sink,
                    positive: m,
                    negative: (m + 1) % electrodes.max(1),
                    current_a,
                })
            })
            .collect();
        Self::new(electrodes, rows)
    }

    /// The rows of a built-in protocol, each driving `current_a` (any positive current: the
    /// model is linear, and a unit current gives transfer impedances).
    ///
    /// # Errors
    /// [`ScheduleError::Current`] for a current that is not finite and positive.
    pub fn of_protocol(protocol: &Protocol, current_a: f64) -> Result<Self, ScheduleError> {
        if !(current_a.is_finite() && current_a > 0.0) {
            return Err(ScheduleError::Current { row: 0, current_a });
        }
        if current_a < MIN_CURRENT_A {
            return Err(ScheduleError::BelowNano { row: 0, current_a });
        }
        if current_a > MAX_UNIT_CURRENT_A {
            return Err(ScheduleError::AboveUnit { row: 0, current_a });
        }
        Ok(Self::of_valid(protocol, current_a))
    }

    /// A valid protocol's rows at a current already checked: every row is valid (a
    /// protocol's electrodes are below its count, its pairs distinct).
    fn of_valid(protocol: &Protocol, current_a: f64) -> Self {
        let rows = protocol
            .steps()
            .map(|s| Row {
                source: u16::from(s.injection.source.0),
                sink: u16::from(s.injection.sink.0),
                positive: u16::from(s.measurement.positive.0),
                negative: u16::from(s.measurement.negative.0),
                current_a,
            })
            .collect();
        Self {
            electrodes: u16::from(protocol.electrodes()),
            rows,
            kind: Some(protocol.kind()),
        }
    }

    /// Electrode count L.
    #[must_use]
    pub fn electrodes(&self) -> usize {
        usize::from(self.electrodes)
    }

    /// The rows, in frame order.
    #[must_use]
    pub fn rows(&self) -> &[Row] {
        &self.rows
    }

    /// Frame length K: one value per row.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.rows.len()
    }

    /// The built-in protocol it was made from (None for one read from a file).
    #[must_use]
    pub fn kind(&self) -> Option<ProtocolKind> {
        self.kind
    }

    /// The distinct injections (source, sink, current A) in order of first use, and for each
    /// row the index of its injection: one forward solve per injection serves its rows.
    #[must_use]
    pub fn injections(&self) -> (Vec<(u16, u16, f64)>, Vec<usize>) {
        let mut distinct: Vec<(u16, u16, f64)> = Vec::new();
        let of_row = self
            .rows
            .iter()
            .map(|r| {
                let key = (r.source, r.sink, r.current_a);
                distinct.iter().position(|d| *d == key).unwrap_or_else(|| {
                    distinct.push(key);
                    distinct.len() - 1
                })
            })
            .collect();
        (distinct, of_row)
    }

    /// The schedule without every value that `electrodes` (0-based) drive or measure, and the
    /// index in this frame of each value kept: a detached or broken electrode's values left
    /// out. A built-in protocol's rows stay as they are, its name dropped.
    ///
    /// # Errors
    /// [`ScheduleError::Absent`] for an electrode past the sheet's,
    /// [`ScheduleError::TooManyLeftOut`] for more than half the sheet's,
    /// [`ScheduleError::NothingLeft`] when every value involves one of them.
    pub fn without(&self, electrodes: &[u16]) -> Result<(Self, Vec<usize>), ScheduleError> {
        if let Some(&electrode) = electrodes.iter().find(|e| **e >= self.electrodes) {
            return Err(ScheduleError::Absent {
                electrode,
                electrodes: self.electrodes,
            });
        }
        let left_out = (0..self.electrodes)
            .filter(|e| electrodes.contains(e))
            .count() as u16;
        if 2 * left_out > self.electrodes {
            return Err(ScheduleError::TooManyLeftOut {
                left_out,
                electrodes: self.electrodes,
            });
        }
        let (kept, rows): (Vec<usize>, Vec<Row>) = (self.rows.iter().enumerate())
            .filter(|(_, r)| {
                ![r.source, r.sink, r.positive, r.negative]
                    .iter()
                    .any(|e| electrodes.contains(e))
            })
            .map(|(k, r)| (k, *r))
            .unzip();
        if rows.is_empty() {
            return Err(ScheduleError::NothingLeft {
                rows: self.rows.len(),
                left_out,
            });
        }
        Ok((Self::new(self.electrodes, rows)?, kept))
    }

    /// The first row that measures on one of its drive electrodes, and that electrode.
    #[must_use]
    pub fn first_on_drive(&self) -> Option<(usize, u16)> {
        self.rows
            .iter()
            .enumerate()
            .find_map(|(k, r)| r.on_drive().map(|e| (k, e)))
    }

    /// Reads a schedule from CSV text: an optional header naming `source`, `sink`,
    /// `positive`, `negative` and `current_a` (any order, any case; other columns ignored),
    /// else 4 or 5 columns in that order, every row as wide as the first; electrodes as whole
    /// numbers (`2`, or `2.0` as NumPy writes them); cells separated by `,`, `;` or tabs; blank and `#`
    /// lines skipped. Electrodes are counted from `base` (0, or 1 for a system that counts
    /// from 1); rows without a current drive `default_current_a`.
    ///
    /// # Errors
    /// [`ScheduleError::File`] naming `path`, the line and the cell; then the checks of
    /// [`Schedule::new`].
    pub fn parse_csv(
        path: &Path,
        text: &str,
        electrodes: u16,
        base: u16,
        default_current_a: f64,
    ) -> Result<Self, ScheduleError> {
        let fail = |line: usize, fault: FileFault| ScheduleError::File {
            path: path.to_path_buf(),
            line,
            fault,
        };
        if base > 1 {
            return Err(fail(0, FileFault::Base(base)));
        }
        // Another of et's files (a recording, a dataset, a model file) said as what it is.
        if let Some(kind) = text::EtFile::of(text).filter(|k| *k != text::EtFile::Protocol) {
            return Err(fail(1, FileFault::OtherFile(kind)));
        }
        let lines = text::lines(text);
        let records = text::RecordIter::new(&lines);
        let delimiter = records.delimiter;
        let mut records = records.peekable();
        let (first_line, first) = match records.next() {
            Some(r) => r.map_err(|(line, f)| fail(line, f.into()))?,
            None => return Err(fail(0, FileFault::NoRows)),
        };
        // A delimiter ending every line (`0,1,2,3,`) is the line's end, not a fifth column;
        // the first row (perhaps a header written by hand) or the second says so.
        let second_ends =
            matches!(records.peek(), Some(Ok((_, r))) if text::ends_with_delimiter(r));
        let line_ends = text::ends_with_delimiter(&first) || second_ends;
        let first: csv::StringRecord = text::cells(&first, line_ends).into_iter().collect();
        let (header, columns) =
            header_columns(&first, delimiter).map_err(|fault| fail(first_line, fault))?;
        let width = first.len();
        // The rows and the file's line of each (for a row's error): the header's record
        // again when it is data.
        let mut rows = Vec::new();
        let mut row_lines = Vec::new();
        let data = (!header)
            .then_some(Ok((first_line, first)))
            .into_iter()
            .chain(records);
        for record in data {
            let (line, record) = record.map_err(|(line, f)| fail(line, f.into()))?;
            let cells = text::cells(&record, line_ends);
            if cells.len() != width {
                let (cells, first) = (cells.len(), width);
                return Err(fail(line, FileFault::Width { cells, first }));
            }
            row_lines.push(line);
            let cell = |c: usize| cells.get(c).copied().unwrap_or("");
            let electrode = |which: usize| -> Result<u16, ScheduleError> {
                let c = columns[which].unwrap_or(which);
                let v = cell(c);
                let column = COLUMNS[which];
                let n: u16 = whole_cell(v, delimiter).ok_or_else(|| {
                    let cell = v.to_string();
                    fail(line, FileFault::NotElectrode { column, cell })
                })?;
                n.checked_sub(base).ok_or_else(|| {
                    let (electrode, base) = (n, base);
                    fail(
                        line,
                        FileFault::BelowBase {
                            column,
                            electrode,
                            base,
                        },
                    )
                })
            };
            let current_a = match columns[4] {
                Some(c) => {
                    let v = cell(c);
                    text::number(v, delimiter)
                        .ok_or_else(|| fail(line, FileFault::NotCurrent(v.to_string())))?
                }
                None => default_current_a,
            };
            rows.push(Row {
                source: electrode(0)?,
                sink: electrode(1)?,
                positive: electrode(2)?,
                negative: electrode(3)?,
                current_a,
            });
        }
        let too_large = rows
            .iter()
            .position(|r| r.current_a > MAX_CURRENT_A)
            .map(|row| ScheduleError::TooLarge {
                row,
                current_a: rows[row].current_a,
            });
        too_large
            .map_or_else(|| Self::new(electrodes, rows), Err)
            .map_err(|e| match e {
                // Name the file's line for a row's error.
                ScheduleError::Electrode { row, .. }
                | ScheduleError::SameDrive { row, .. }
                | ScheduleError::SameMeasure { row, .. }
                | ScheduleError::Current { row, .. }
                | ScheduleError::AboveUnit { row, .. }
                | ScheduleError::BelowNano { row, .. }
                | ScheduleError::TooLarge { row, .. } => {
                    let line = row_lines.get(row).copied().unwrap_or(0);
                    fail(line, FileFault::Row(Box::new(e)))
                }
                other => fail(0, FileFault::Row(Box::new(other))),
            })
    }

    /// [`Schedule::parse_csv`] of a file.
    ///
    /// # Errors
    /// [`ScheduleError::File`] when it cannot be read, else as [`Schedule::parse_csv`].
    pub fn read_csv(
        path: &Path,
        electrodes: u16,
        base: u16,
        default_current_a: f64,
    ) -> Result<Self, ScheduleError> {
        let text = read_text(path)?;
        Self::parse_csv(path, &text, electrodes, base, default_current_a)
    }

    /// The schedule as CSV with a header, electrodes from 0: what [`Schedule::parse_csv`]
    /// reads back (Python: `numpy.loadtxt(path, delimiter=",", skiprows=1)`).
    #[must_use]
    pub fn to_csv(&self) -> String {
        self.to_csv_counted_from(0)
    }

    /// [`Schedule::to_csv`] with electrodes counted from `base` (0, or 1 for a system that
    /// counts from 1: read back with `base = 1`).
    #[must_use]
    pub fn to_csv_counted_from(&self, base: u16) -> String {
        let mut out = String::from("source,sink,positive,negative,current_a\n");
        for r in &self.rows {
            let [s, k, p, n] = [r.source, r.sink, r.positive, r.negative].map(|e| e + base);
            out += &format!("{s},{k},{p},{n},{:e}\n", r.current_a);
        }
        out
    }
}

/// The text of the protocol file `path` (up to the data files' limit), as
/// [`Schedule::read_csv`] reads it: a MATLAB file given for it is said with the command
/// that writes a protocol file from it.
///
/// # Errors
/// [`ScheduleError::Read`]: unreadable, not text, or a MATLAB file.
pub fn read_text(path: &Path) -> Result<String, ScheduleError> {
    let read = |e: std::io::Error| ScheduleError::Read {
        path: path.to_path_buf(),
        source: std::sync::Arc::new(e),
    };
    let bytes = crate::text::read_at_most(path, crate::text::max_file_bytes()).map_err(read)?;
    // A MATLAB file holds the protocol as another tool keeps it (EIDORS's stimulation, KIT4's
    // patterns), which et's CLI writes out as a protocol file.
    if bytes.starts_with(b"MATLAB 5.0 MAT-file") {
        return Err(read(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "a MATLAB .mat file, not a protocol file (text): write one from it with et protocol \
             --stimulation FILE.mat > protocol.csv (EIDORS's stimulation struct array), or with \
             --injections FILE.mat:VAR --measurements FILE.mat:VAR (current and measurement \
             patterns)",
        )));
    }
    crate::text::table_text_of(bytes).map_err(read)
}

impl ScanConfig {
    /// The schedule this configuration scans: its protocol's rows at its current.
    ///
    /// # Errors
    /// [`ConfigError`] when the configuration is not valid.
    pub fn schedule(&self) -> Result<Schedule, ConfigError> {
        let protocol = self.validate()?;
        Ok(Schedule::of_valid(
            &protocol,
            f64::from(self.current_amps()),
        ))
    }
}

impl Protocol {
    /// This protocol's rows, each driving `current_a` ([`Schedule::of_protocol`]).
    ///
    /// # Errors
    /// [`ScheduleError::Current`] for a current that is not finite and positive.
    pub fn schedule(&self, current_a: f64) -> Result<Schedule, ScheduleError> {
        Schedule::of_protocol(self, current_a)
    }
}

/// What a frame of `n` values may be where the protocol has `k` (`n` != `k`): a built-in
/// protocol's K at some electrode count, every pair of each of L injections (L x L, drive
/// electrodes and repeats included), or half of K (the reciprocal values left out); None when
/// it is none of them. Said beside a frame of the wrong length, whose message named only K.
#[must_use]
pub fn other_frame_len(n: usize, k: usize) -> Option<String> {
    let built_in: Vec<String> = (ProtocolKind::NAMED.iter())
        .flat_map(|&kind| {
            (L_MIN..=L_MAX).step_by(2).filter_map(move |l| {
                let p = Protocol::new(kind, l).ok()?;
                (p.frame_len() == n).then(|| format!("{} at {l} electrodes", kind.name()))
            })
        })
        .collect();
    let fix = "give the rows the frames hold in a protocol file (et protocol --csv writes one \
               to start from)";
    if !built_in.is_empty() {
        Some(format!("{n} values a frame are {}", built_in.join(", ")))
    } else if let Some(l) = (usize::from(L_MIN)..=usize::from(L_MAX)).find(|l| l * l == n) {
        Some(format!(
            "{n} = {l} x {l}: every electrode pair's value for each of {l} injections, the \
             drive electrodes' and repeated ones included? {fix}"
        ))
    } else if 2 * n == k {
        Some(format!(
            "{n} is half of K: the protocol without its reciprocal (repeated) values? {fix}"
        ))
    } else {
        None
    }
}

mod error;
pub use error::*;
mod header;
use header::header_columns;
pub use header::{reads_as_current, role as column_role};

#[cfg(test)]
mod tests;
