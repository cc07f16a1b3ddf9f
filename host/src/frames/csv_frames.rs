//! Frames from a CSV: one frame per row, read record by record, a header (names, or the
//! columns' numbers), a row of units, pandas' row index and columns named as no frame's
//! values skipped and said; values in a unit of voltage the file names (`mV` under or in a
//! column's name) read as volts; an empty or NaN cell a value missing.

use std::path::Path;

use et_core::text::{self, Delimiter};
use nalgebra::DMatrix;

use super::{FramesError, FramesFault, content};

/// What stands above a CSV's frames, and what it says of them: a header (its first cell, and
/// the columns it names as no frame's values), a row of units under it, or a row of the
/// columns' numbers; whether every line ends with a delimiter.
#[derive(Default)]
struct Head {
    /// The header's first cell, where there is a header.
    first_name: Option<String>,
    /// Whether the first row counts the columns (0, 1, 2, ... or 1, 2, 3, ...: a DAQ's
    /// channel numbers), which was read as the first frame, the reference.
    numbered: bool,
    /// The header's columns (from 0) of the rows' numbers, times or sessions (a DAQ's `Time`
    /// first), or of targets (a recording annotated with `label`, `x`, `y`): left out of
    /// every row (they were refused as one column too many, or as text).
    skipped: Vec<(usize, String)>,
    /// Whether a row of units stood under the header.
    units_row: bool,
    /// Each column's unit of voltage as the file names it (under its name, or in it:
    /// `ch1 (mV)`), with its factor to volts; empty where none is named.
    units: Vec<Option<(String, f64)>>,
    /// The first word of a row of units that is not a unit of voltage (`Ohm`, `counts`).
    not_volts: Option<String>,
    /// Whether each line ends with a delimiter.
    line_ends: bool,
    /// The first record's cells.
    first_len: usize,
}

impl Head {
    /// Notes the `i`th record: a delimiter at the end of each line (`fprintf('%g,', frame)`
    /// in a loop) ends the row, not an empty last value. The first row (a header, perhaps
    /// written by hand) or the second says so; the second not where a header names as many
    /// cells (an annotated row's empty last cell, `none,,` under `label,x,y`).
    fn see(&mut self, i: usize, record: &text::StringRecord) {
        if i == 0 {
            self.first_len = record.len();
        }
        let named_as_many = i == 1 && self.first_name.is_some() && record.len() == self.first_len;
        self.line_ends |= i <= 1 && text::ends_with_delimiter(record) && !named_as_many;
    }

    /// Whether the `i`th record's `cells` stand above the frames (taken here), not a frame.
    fn takes(&mut self, i: usize, cells: &[&str], delimiter: Delimiter) -> bool {
        // A first row with a cell of text is a header, as is pandas' over columns numbered
        // 0, 1, 2, ... (its first cell empty); an empty cell alone is a value missing from the
        // first frame (it was taken as a header: the reference lost).
        if i == 0 && (named_row(cells, delimiter) || pandas_header(cells, delimiter)) {
            self.first_name = cells.first().map(|c| (*c).to_string());
            self.skipped = (cells.iter().enumerate())
                .filter(|(_, name)| left_out_by_name(name))
                .map(|(c, name)| (c, (*name).to_string()))
                .collect();
            self.units = cells.iter().map(|name| in_name(name)).collect();
            return true;
        }
        // A second header row under the names, of words alone (a DAQ's units: `V,V,V`; a row
        // of numbers written wrongly, `1.0D-03`, is said by its cell, and `NaN` is a value
        // missing, a frame the system did not send).
        let word = |c: &str| {
            !text::says_missing(c)
                && !c.contains(|ch: char| ch.is_ascii_digit())
                && text::number(c, delimiter).is_none()
        };
        if i == 1 && self.first_name.is_some() {
            let units = {
                let mut kept = self.values(cells).peekable();
                kept.peek().is_some() && kept.all(|(_, c)| word(c))
            };
            if units {
                self.units_row = true;
                let named: Vec<_> = (self.values(cells))
                    .map(|(c, word)| (c, word, volts_per(word)))
                    .collect();
                self.not_volts = (named.iter())
                    .find(|(_, _, per)| per.is_none())
                    .map(|(_, word, _)| (*word).to_string());
                // A row of units of voltage names each column's (over units in the names).
                if self.not_volts.is_none() {
                    self.units.resize(cells.len(), None);
                    for (c, word, per) in named {
                        self.units[c] = per.map(|per| (word.trim().to_string(), per));
                    }
                }
                return true;
            }
        }
        if i == 0 && counts_columns(cells, delimiter) {
            self.numbered = true;
            return true;
        }
        false
    }

    /// A frame row's cells of values, with their columns (from 0): the skipped ones left out.
    fn values<'c>(&self, cells: &[&'c str]) -> impl Iterator<Item = (usize, &'c str)> {
        let skipped = &self.skipped;
        (cells.iter().enumerate())
            .filter(move |(c, _)| !skipped.iter().any(|(s, _)| s == c))
            .map(|(c, cell)| (c, *cell))
    }

    /// Notes, at the first frame's `cells`, a first column unnamed whose cells are text: the
    /// rows' index pandas writes for a frame of times (a `DatetimeIndex`, `2026-12-07
    /// 10:00:00`) or labels, left out as a named time column is (it was "not a number").
    fn index_of_text(&mut self, cells: &[&str], delimiter: Delimiter) {
        let text = cells
            .first()
            .is_some_and(|c| !text::says_missing(c) && text::number(c, delimiter).is_none());
        if self.first_name.as_deref() == Some("") && text && cells.len() > 1 {
            self.skipped.insert(0, (0, String::new()));
        }
    }

    /// The factor from column `c`'s unit to volts (1 where the file names none).
    fn volts_per(&self, c: usize) -> f64 {
        self.units
            .get(c)
            .and_then(|u| u.as_ref())
            .map_or(1.0, |u| u.1)
    }

    /// Whether a header (of names or numbers) was read.
    fn header(&self) -> bool {
        self.first_name.is_some() || self.numbered
    }

    /// What is said of what stood above the frames.
    fn said(&self, delimiter: Delimiter) -> String {
        let mut said = match delimiter {
            Delimiter::Comma => String::new(),
            d => format!("{}, ", d.said()),
        };
        if self.numbered {
            said.push_str("its first row (the columns' numbers) skipped as a header, ");
        }
        let mut units: Vec<&(String, f64)> = Vec::new();
        for u in self.units.iter().flatten() {
            if !units.iter().any(|k| k.0 == u.0) {
                units.push(u);
            }
        }
        let words: Vec<&str> = units.iter().map(|u| u.0.as_str()).collect();
        if let Some(word) = &self.not_volts {
            said.push_str(&format!(
                "its second row (units? '{word}', not a unit of voltage: the values are taken as \
                 volts) skipped as a header, "
            ));
        } else if self.units_row {
            said.push_str(&format!(
                "its second row (units: {}) skipped as a header, ",
                words.join(", ")
            ));
        }
        if units.iter().any(|u| u.1 != 1.0) {
            let factors: Vec<String> = (units.iter())
                .map(|(word, per)| format!("{word} x {per:e}"))
                .collect();
            said.push_str(&format!(
                "its values read as volts ({}{}), ",
                factors.join(", "),
                if self.units_row {
                    ""
                } else {
                    ", as its columns' names say"
                }
            ));
        }
        if self.skipped.first().is_some_and(|(_, n)| n.is_empty()) {
            said.push_str(
                "its first column (unnamed, of text: pandas' index of times?) skipped as the \
                 rows' index, ",
            );
        }
        let named: Vec<&(usize, String)> =
            self.skipped.iter().filter(|(_, n)| !n.is_empty()).collect();
        let names: Vec<&str> = named.iter().map(|(_, n)| n.as_str()).collect();
        said.push_str(&left_out_said("its column", &names));
        said
    }
}

/// A CSV of numbers, a header row skipped; its matrix and what was said of the delimiter.
/// Read record by record: what is kept is the numbers (8 bytes a value), not the cells.
pub(super) fn csv_matrix(path: &Path, text: &str) -> Result<(DMatrix<f64>, String), FramesError> {
    let lines = text::lines(text);
    let records = text::RecordIter::new(&lines);
    let delimiter = records.delimiter;
    let mut values = Vec::new();
    let mut width = None;
    let mut n = 0;
    let mut head = Head::default();
    let mut records = records.enumerate().peekable();
    while let Some((i, record)) = records.next() {
        let (line, record) = record.map_err(|(line, f)| content(path, line, f.into()))?;
        head.see(i, &record);
        let cells = text::cells(&record, head.line_ends);
        if head.takes(i, &cells, delimiter) {
            continue;
        }
        if n == 0 {
            head.index_of_text(&cells, delimiter);
        }
        let w = *width.get_or_insert(cells.len());
        if cells.len() != w {
            let fault = FramesFault::RowLength {
                found: cells.len(),
                first: w,
                last: cells.len() < w && records.peek().is_none(),
            };
            return Err(content(path, line, fault));
        }
        for (c, cell) in head.values(&cells) {
            let (column, written) = (c + 1, || cell.to_string());
            // An empty cell is a value not measured (a DAQ's dropped sample), as NaN is, and R's
            // NA, Excel's #N/A: its frame is kept with it, NaN, and no image takes it.
            if text::says_missing(cell) {
                values.push(f64::NAN);
                continue;
            }
            let v = head.volts_per(c)
                * text::number(cell, delimiter).ok_or_else(|| {
                    content(
                        path,
                        line,
                        FramesFault::NotNumber {
                            column,
                            cell: written(),
                            first_row: n == 0 && head.header(),
                        },
                    )
                })?;
            // (Said by the file's line and cell: the matrix's check counts from 0.)
            let volts = v.is_finite() && v.abs() <= f64::from(f32::MAX);
            if !(v.is_nan() || volts) {
                let fault = FramesFault::NotVolts {
                    column,
                    cell: written(),
                    value: v,
                };
                return Err(content(path, line, fault));
            }
            values.push(v);
        }
        n += 1;
    }
    let header = head.header();
    let w = width.ok_or_else(|| content(path, 0, FramesFault::NoFrames { header }))?;
    let w = w - head.skipped.iter().filter(|(c, _)| *c < w).count();
    if w == 0 {
        let names = head.skipped.iter().map(|(_, n)| n.clone()).collect();
        return Err(content(path, 0, FramesFault::NoValues(names)));
    }
    let mut said = head.said(delimiter);
    // Row after row is a w x n column-major matrix: transposed, n x w.
    let matrix = DMatrix::from_vec(w, n, values).transpose();
    // pandas' `to_csv` writes each row's number first, under a header cell with no name, and
    // R's `write.csv` its row names, "1", "2", ...: a column unnamed whose values count the
    // rows from 0 or 1 is that index, not a value.
    let unnamed = head.first_name.is_some_and(|name| {
        name.is_empty() || name.eq_ignore_ascii_case("index") || name == "Unnamed: 0"
    });
    let counts_rows = |from: f64| (0..n).all(|r| matrix[(r, 0)] == from + r as f64);
    if let Some(from) = [0, 1].into_iter().find(|&f| counts_rows(f64::from(f)))
        && unnamed
        && w > 1
    {
        said.push_str(&format!(
            "its first column (unnamed, {from}, {}, {}, ...) skipped as the rows' index, ",
            from + 1,
            from + 2
        ));
        return Ok((matrix.remove_column(0), said));
    }
    Ok((matrix, said))
}

/// Whether a column (or a JSON frame's value) of this name is left out of the frames: the
/// rows' numbers, times or sessions (a DAQ's `Time`), or targets (`label`, `x`, `y`), by the
/// names `et train --features` takes as no feature.
pub(super) fn left_out_by_name(name: &str) -> bool {
    et_learn::dataset::not_a_feature(name) || et_learn::dataset::is_target_name(name)
}

/// What is said of the columns (`what`: "its column") left out by name; empty for none.
pub(super) fn left_out_said(what: &str, names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
    match quoted.len() {
        0 => String::new(),
        n => format!(
            "{what}{} {} skipped (the rows' numbers, times, sessions or targets by name, not a \
             frame's values), ",
            if n == 1 { "" } else { "s" },
            quoted.join(", ")
        ),
    }
}

/// Whether a row has a cell that is text, not a number (an empty cell is a value missing).
fn named_row(cells: &[&str], delimiter: Delimiter) -> bool {
    (cells.iter()).any(|c| !text::says_missing(c) && text::number(c, delimiter).is_none())
}

/// Whether a row is pandas' header over columns named by their numbers: an empty first cell
/// (its index's), then 0, 1, 2, ... (or from 1).
fn pandas_header(cells: &[&str], delimiter: Delimiter) -> bool {
    let rest = cells.get(1..).unwrap_or_default();
    cells.first() == Some(&"")
        && !rest.is_empty()
        && [0.0, 1.0].iter().any(|from| {
            (rest.iter().enumerate())
                .all(|(j, c)| text::number(c, delimiter) == Some(from + j as f64))
        })
}

/// Whether a row's `cells` count its columns from 0 or 1 (eight or more: a frame's values
/// never do).
fn counts_columns(cells: &[&str], delimiter: Delimiter) -> bool {
    let values: Option<Vec<f64>> = cells.iter().map(|c| text::number(c, delimiter)).collect();
    values.is_some_and(|v| {
        v.len() >= 8
            && [0.0, 1.0]
                .iter()
                .any(|from| v.iter().enumerate().all(|(j, x)| *x == from + j as f64))
    })
}

/// Whether `cell` is a complex number as NumPy (`(1.5+0.2j)`), Python (`1.5-0.2j`) or MATLAB
/// (`1.5+0.2i`) writes it.
pub(super) fn complex(cell: &str) -> bool {
    let c = cell.trim().trim_start_matches('(').trim_end_matches(')');
    let Some(body) = c.strip_suffix(['j', 'J', 'i', 'I']) else {
        return false;
    };
    // The sign that starts the imaginary part: the last + or - not at the start and not an
    // exponent's.
    let split = body
        .char_indices()
        .rev()
        .find(|&(i, ch)| i > 0 && (ch == '+' || ch == '-') && !body[..i].ends_with(['e', 'E']));
    split.is_some_and(|(i, _)| {
        body[..i].trim().parse::<f64>().is_ok() && body[i..].trim().parse::<f64>().is_ok()
    })
}

/// The factor to volts of a unit of voltage as a DAQ writes it under a column's name (`mV`,
/// `[uV]`, `(V)`, `µV`, `volts`); None for any other word (`Ohm`, `counts`, `MV`).
fn volts_per(unit: &str) -> Option<f64> {
    let (u, word) = unit_words(unit);
    match (u, word.as_str()) {
        ("V" | "v", _) | (_, "volt") => Some(1.0),
        ("mV" | "mv", _) | (_, "millivolt") => Some(1e-3),
        ("uV" | "uv" | "µV" | "μV", _) | (_, "microvolt") => Some(1e-6),
        ("nV", _) | (_, "nanovolt") => Some(1e-9),
        ("kV", _) | (_, "kilovolt") => Some(1e3),
        _ => None,
    }
}

/// A unit as written, without its brackets (`(mV)` is `mV`), and as a word: in lower case,
/// without a plural's `s` (`Volts` is `volt`).
pub(crate) fn unit_words(unit: &str) -> (&str, String) {
    let u = (unit.trim())
        .trim_start_matches(['(', '['])
        .trim_end_matches([')', ']'])
        .trim();
    let word = u.to_ascii_lowercase();
    (u, word.trim_end_matches('s').to_string())
}

/// The unit of voltage a column's `name` ends with: in brackets (`ch1 (mV)`, `U1 [uV]`),
/// after a slash as a quantity over its unit (`U1/mV`), or after an underscore (`ch1_mV`,
/// as et's own `x_mm`); as named and with its factor to volts.
pub(super) fn in_name(name: &str) -> Option<(String, f64)> {
    unit_in_name(name, volts_per)
}

/// The unit a column's `name` ends with as [`in_name`] finds it, for any quantity: `per`
/// gives a unit's factor to the quantity's SI unit (None: not one of its units).
pub(crate) fn unit_in_name(name: &str, per: fn(&str) -> Option<f64>) -> Option<(String, f64)> {
    let name = name.trim_end();
    let unit = match name.chars().last()? {
        ')' => &name[name.rfind('(')? + 1..name.len() - 1],
        ']' => &name[name.rfind('[')? + 1..name.len() - 1],
        _ => &name[name.rfind(['/', '_'])? + 1..],
    };
    per(unit).map(|factor| (unit.trim().to_string(), factor))
}
