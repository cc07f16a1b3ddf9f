//! Tables as text, the way users' tools write them: CSV read by the `csv` crate (quoted cells,
//! records over several lines), cells separated by `,`, `;` or tabs (detected from the first
//! row), a UTF-8 byte-order mark, CRLF line ends, blank and `#` lines skipped, spaces around
//! cells trimmed. Every et reader of tables (datasets, other sensors' tables, protocols,
//! frames) reads through [`records`].
//!
//! Behind the `std` feature.

/// What separates the cells of a row.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Delimiter {
    /// `,` (numbers with a decimal point).
    Comma,
    /// `;`, as spreadsheets write CSV where the decimal mark is a comma (`1,5;2,25`).
    Semicolon,
    /// A tab.
    Tab,
    /// Runs of spaces, as NumPy's `savetxt` writes by default and MATLAB's `save -ascii`
    /// (aligned columns, leading spaces): taken where the first row is two or more numbers
    /// separated by spaces alone.
    Spaces,
}

impl Delimiter {
    /// The delimiter of a file whose first row is `line`: a tab if one is outside quotes,
    /// else `;` if one is, else `,`. (Counting would misjudge `1,5;2,5`: a `;` file with
    /// decimal commas has more commas than semicolons.)
    #[must_use]
    pub fn of(line: &str) -> Self {
        let mut quoted = false;
        let (mut tab, mut semicolon) = (false, false);
        for c in line.chars() {
            match c {
                '"' => quoted = !quoted,
                '\t' if !quoted => tab = true,
                ';' if !quoted => semicolon = true,
                _ => {}
            }
        }
        let spaced = || {
            let mut tokens = line.split_whitespace();
            !line.contains(',')
                && tokens.clone().count() >= 2
                && tokens.all(|t| t.parse::<f64>().is_ok())
        };
        if tab {
            Self::Tab
        } else if semicolon {
            Self::Semicolon
        } else if spaced() {
            Self::Spaces
        } else {
            Self::Comma
        }
    }

    /// The delimiter of a file whose first two rows are `first` and `second`: as [`Self::of`]
    /// the first, except that a header of names separated by spaces (`v0 v1 v2`, as pandas'
    /// `to_csv(sep=" ")` writes) above a row of numbers separated by spaces, or of as many
    /// cells separated by spaces with a number among them (`left 0.01 0.02` under `label x
    /// y`), is [`Self::Spaces`] (it was one cell, and every row after it one cell).
    #[must_use]
    pub fn of_head(first: &str, second: Option<&str>) -> Self {
        let d = Self::of(first);
        // No other delimiter, and no quote that could hide one.
        let plain = |l: &str| !l.contains(['\t', ',', ';', '"']);
        let names = first.split_whitespace().count();
        let names_spaced = d == Self::Comma
            && plain(first)
            && names >= 2
            && first.split_whitespace().all(|t| t.parse::<f64>().is_err());
        let cells_spaced = |s: &str| {
            Self::of(s) == Self::Spaces
                || (plain(s)
                    && s.split_whitespace().count() == names
                    && s.split_whitespace().any(|t| t.parse::<f64>().is_ok()))
        };
        if names_spaced && second.is_some_and(cells_spaced) {
            Self::Spaces
        } else {
            d
        }
    }

    /// The byte.
    #[must_use]
    pub fn byte(self) -> u8 {
        match self {
            Self::Comma => b',',
            Self::Semicolon => b';',
            Self::Tab => b'\t',
            Self::Spaces => b' ',
        }
    }

    /// In words, for a reader's description ("" for a comma).
    #[must_use]
    pub fn said(self) -> &'static str {
        match self {
            Self::Comma => "",
            Self::Semicolon => "cells separated by ';'",
            Self::Tab => "cells separated by tabs",
            Self::Spaces => "cells separated by spaces",
        }
    }
}

/// `cell` as a number: `1.5`, `1.5E-05`, `nan`, and where the cells are not separated by
/// commas a decimal comma too (`1,5`).
#[must_use]
pub fn number(cell: &str, delimiter: Delimiter) -> Option<f64> {
    cell.parse::<f64>().ok().or_else(|| {
        let decimal_comma =
            delimiter != Delimiter::Comma && cell.matches(',').count() == 1 && !cell.contains('.');
        decimal_comma
            .then(|| cell.replace(',', ".").parse::<f64>().ok())
            .flatten()
    })
}

/// Whether `cell` says a value is missing: empty, or a word tools write for it (R's `NA`,
/// Excel's `#N/A`, `null`, `None`, a Windows C library's `-1.#IND`: pandas' list of them).
/// NaN is read as a number.
#[must_use]
pub fn says_missing(cell: &str) -> bool {
    const WORDS: [&str; 16] = [
        "NA", "N/A", "n/a", "#N/A", "#NA", "#N/A N/A", "<NA>", "NULL", "null", "None", "1.#IND",
        "-1.#IND", "1.#QNAN", "-1.#QNAN", "-NaN", "-nan",
    ];
    let c = cell.trim();
    c.is_empty() || WORDS.contains(&c)
}

/// Whether `cell` is a number in Fortran's double-precision form (`1.0D-03`, `-3.24d0`),
/// which no other reader takes: said where a cell is not a number, with the fix.
#[must_use]
pub fn fortran_exponent(cell: &str) -> bool {
    let c = cell.trim();
    c.matches(['D', 'd']).count() == 1
        && c.replace(['D', 'd'], "E").parse::<f64>().is_ok()
        && c.starts_with(|ch: char| ch.is_ascii_digit() || "+-.".contains(ch))
}

/// What is said after "'CELL' is not a number" of a Fortran number ("" of any other cell).
#[must_use]
pub fn fortran_said(cell: &str) -> &'static str {
    if fortran_exponent(cell) {
        " but Fortran's D exponent: write E (1.0E-03), as sed 's/D/E/g' does"
    } else {
        ""
    }
}

/// One record's cells, as [`RecordIter`] gives them.
pub use csv::StringRecord;

/// A record: the 1-based line it starts on, and its cells, trimmed.
pub type Record = (usize, Vec<String>);

/// The rows of a table: its delimiter and each record with the 1-based line it starts on.
#[derive(Clone, Debug, PartialEq)]
pub struct Records {
    /// What separated the cells.
    pub delimiter: Delimiter,
    /// (1-based line, cells trimmed) per record, blank and `#` lines left out.
    pub rows: Vec<Record>,
}

/// Why a table's rows could not be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RecordFault {
    /// A quoted cell holds a line break: a closing quote is missing.
    #[error("a quoted cell runs on over the next lines: is a closing quote (\") missing?")]
    RunOn,
    /// The `csv` crate refused the text (its errors are about bytes that are not UTF-8 and
    /// rows of unequal length, neither of which text read flexibly can have).
    #[error("not readable as CSV")]
    Unreadable,
}

/// Reads `lines` ((0-based line number, text) pairs, say from [`lines`]) as CSV records.
///
/// # Errors
/// (1-based line, fault): a cell that runs on over lines (a missing closing quote), or
/// what the `csv` crate could not read.
pub fn read_records(lines: &[(usize, &str)]) -> Result<Records, (usize, RecordFault)> {
    let mut each = RecordIter::new(lines);
    let rows = each
        .by_ref()
        .map(|r| r.map(|(line, cells)| (line, cells.iter().map(str::to_string).collect())))
        .collect::<Result<Vec<Record>, _>>()?;
    Ok(Records {
        delimiter: each.delimiter,
        rows,
    })
}

/// The records of a table one at a time, as [`read_records`] reads them (blank and `#` lines
/// skipped, cells trimmed): a reader keeps what it makes of each record, never the table's
/// cells as text (a table of cells as strings took about 110 times its file's size).
#[derive(Debug)]
pub struct RecordIter<'a> {
    reader: csv::Reader<Kept<'a>>,
    /// What separates the cells (from the first record's line).
    pub delimiter: Delimiter,
    /// After an error, nothing more.
    done: bool,
}

/// The lines a table is read from, blank and `#` lines left out, as bytes for the csv reader
/// (each line then `\n`), remembering the file's line of each one handed on.
#[derive(Debug)]
struct Kept<'a> {
    lines: &'a [(usize, &'a str)],
    /// The rest of the line being handed on.
    pending: &'a [u8],
    /// A `\n` is owed after `pending`.
    newline: bool,
    /// The file's 0-based line of each line handed on, in order.
    kept: Vec<usize>,
}

/// A blank or `#` line: not a record. A row whose first cell is Excel's `#N/A` (a value
/// missing) is a record: it was dropped as a comment, its frame or observation lost.
fn skipped(line: &str) -> bool {
    let t = line.trim_start();
    let excel_na = ["#N/A", "#NA"].iter().any(|na| {
        t.strip_prefix(na)
            .is_some_and(|rest| rest.is_empty() || rest.starts_with([',', ';', '\t', ' ']))
    });
    t.is_empty() || (t.starts_with('#') && !excel_na)
}

impl std::io::Read for Kept<'_> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        loop {
            if !self.pending.is_empty() {
                let n = self.pending.len().min(buf.len());
                let (now, rest) = self.pending.split_at(n);
                if let Some(to) = buf.get_mut(..n) {
                    to.copy_from_slice(now);
                }
                self.pending = rest;
                return Ok(n);
            }
            if self.newline {
                let Some(b) = buf.first_mut() else {
                    return Ok(0);
                };
                *b = b'\n';
                self.newline = false;
                return Ok(1);
            }
            let Some((&(i, line), rest)) = self.lines.split_first() else {
                return Ok(0);
            };
            self.lines = rest;
            if !skipped(line) {
                self.kept.push(i);
                self.pending = line.as_bytes();
                self.newline = true;
            }
        }
    }
}

/// The delimiter Excel's first line `sep=;` names (written so that Excel reads the file in
/// any locale; "Save as CSV" with it, or a script for Excel users): not a record. None for
/// any other line.
#[must_use]
pub fn excel_sep(line: &str) -> Option<Delimiter> {
    let l = line.trim_start();
    let named = l.get(..4).filter(|s| s.eq_ignore_ascii_case("sep="))?;
    match l[named.len()..].trim_end_matches(['\r', '\n', ' ']) {
        "," => Some(Delimiter::Comma),
        ";" => Some(Delimiter::Semicolon),
        "\t" => Some(Delimiter::Tab),
        _ => None,
    }
}

impl<'a> RecordIter<'a> {
    /// The records of `lines` ((0-based line number, text) pairs, say from [`lines`]). A
    /// first line `sep=X` ([`excel_sep`]) names the delimiter and is left out.
    #[must_use]
    pub fn new(lines: &'a [(usize, &'a str)]) -> Self {
        let first = lines.iter().position(|(_, l)| !skipped(l));
        let named = first.and_then(|i| Some((i, excel_sep(lines.get(i)?.1)?)));
        let (lines, named) = match named {
            Some((i, d)) => (lines.get(i + 1..).unwrap_or_default(), Some(d)),
            None => (lines, None),
        };
        let mut head = lines.iter().filter(|(_, l)| !skipped(l)).map(|(_, l)| *l);
        let delimiter = named.unwrap_or_else(|| {
            head.next().map_or(Delimiter::Comma, |first| {
                Delimiter::of_head(first, head.next())
            })
        });
        let kept = Kept {
            lines,
            pending: &[],
            newline: false,
            kept: Vec::new(),
        };
        let reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .delimiter(delimiter.byte())
            .from_reader(kept);
        Self {
            reader,
            delimiter,
            done: false,
        }
    }

    /// The file's 1-based line of the csv reader's 1-based line (0 if unknown).
    fn file_line(&self, line: u64) -> usize {
        usize::try_from(line)
            .ok()
            .and_then(|l| l.checked_sub(1))
            .and_then(|l| self.reader.get_ref().kept.get(l))
            .map_or(0, |i| i + 1)
    }
}

impl Iterator for RecordIter<'_> {
    /// (1-based line the record starts on, its cells trimmed), or (1-based line, fault): a
    /// cell that runs on over lines (a missing closing quote), or what the `csv` crate could
    /// not read. Nothing follows an error.
    type Item = Result<(usize, StringRecord), (usize, RecordFault)>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let mut record = StringRecord::new();
        let read = self.reader.read_record(&mut record);
        let line = |p: Option<&csv::Position>| p.map_or(0, |p| self.file_line(p.line()));
        let item = match read {
            Ok(false) => None,
            Ok(true) => {
                let line = line(record.position());
                if self.delimiter == Delimiter::Spaces {
                    // A run of spaces is one separator: its empty cells are not cells.
                    record = record.iter().filter(|c| !c.is_empty()).collect();
                }
                if record.iter().any(|c| c.contains('\n')) {
                    Some(Err((line, RecordFault::RunOn)))
                } else {
                    Some(Ok((line, record)))
                }
            }
            Err(e) => Some(Err((line(e.position()), RecordFault::Unreadable))),
        };
        self.done = !matches!(item, Some(Ok(_)));
        item
    }
}

/// The lines of `text` with their 0-based numbers, without a leading UTF-8 byte-order mark
/// (CRLF ends are handled by `lines`).
#[must_use]
pub fn lines(text: &str) -> Vec<(usize, &str)> {
    text.strip_prefix('\u{feff}')
        .unwrap_or(text)
        .lines()
        .enumerate()
        .collect()
}

/// Whether `record`, one of a file's first two records, ends with a delimiter (`1,2,3,`: a
/// MATLAB loop's `fprintf('%g,', row)`), so that the file's empty last cells are its lines'
/// ends. Either of the first two decides: a header written by hand without one may stand
/// above rows written by such a loop.
#[must_use]
pub fn ends_with_delimiter(record: &StringRecord) -> bool {
    record.len() > 1 && record.get(record.len() - 1) == Some("")
}

/// `record`'s cells, without the empty last one where the file's lines end with a delimiter
/// ([`ends_with_delimiter`] of either of its first two records).
#[must_use]
pub fn cells(record: &StringRecord, line_ends: bool) -> Vec<&str> {
    let ends = line_ends && record.len() > 1 && record.get(record.len() - 1) == Some("");
    record
        .iter()
        .take(record.len() - usize::from(ends))
        .collect()
}

/// [`read_records`] of a whole text, the rows only.
///
/// # Errors
/// As [`read_records`].
pub fn records(text: &str) -> Result<Vec<Record>, (usize, RecordFault)> {
    read_records(&lines(text)).map(|r| r.rows)
}

mod file;
pub use file::*;
mod kind;
pub use kind::EtFile;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn delimiters_quotes_and_lines_are_read_as_users_write_them() {
        assert_eq!(Delimiter::of("a,b"), Delimiter::Comma);
        assert_eq!(Delimiter::of("1,5;2,5"), Delimiter::Semicolon);
        assert_eq!(Delimiter::of("a\tb;c"), Delimiter::Tab);
        assert_eq!(Delimiter::of("\"a;b\",c"), Delimiter::Comma);
        // Names separated by spaces above numbers separated by spaces; a header alone, or
        // above one number a row, is one cell.
        let spaced = Some("1.0 2.0");
        assert_eq!(Delimiter::of_head("v0 v1", spaced), Delimiter::Spaces);
        assert_eq!(Delimiter::of_head("v0 v1", None), Delimiter::Comma);
        assert_eq!(
            Delimiter::of_head("first value", Some("1.0")),
            Delimiter::Comma
        );
        assert_eq!(Delimiter::of_head("a,b c", spaced), Delimiter::Comma);
        let labelled = Some("left 0.01 0.02");
        assert_eq!(Delimiter::of_head("label x y", labelled), Delimiter::Spaces);
        // Labels with spaces under a header with one: as many cells, none a number.
        assert_eq!(
            Delimiter::of_head("touch class", Some("upper left")),
            Delimiter::Comma
        );
        assert_eq!(Delimiter::of_head("label x", labelled), Delimiter::Comma);
        assert_eq!(number("1,5", Delimiter::Semicolon), Some(1.5));
        assert_eq!(number("1,5", Delimiter::Comma), None);
        assert_eq!(number("1,500.5", Delimiter::Tab), None);
        let rows = records("\u{feff}# note\r\n\r\na,\"b,c\"\r\n1,2\r\n").unwrap();
        assert_eq!(
            rows,
            vec![
                (3, vec!["a".to_string(), "b,c".to_string()]),
                (4, vec!["1".to_string(), "2".to_string()]),
            ]
        );
        // Excel's `sep=;` line names the delimiter and is no record (it was the header, and
        // the real header a row of text where numbers belong); its line numbers kept.
        for (text, delimiter) in [
            ("sep=;\r\nx;y\r\n1,5;2\r\n", Delimiter::Semicolon),
            ("# note\nSEP=,\nx,y\n1.5,2\n", Delimiter::Comma),
            ("sep=\t\nx\ty\n1.5\t2\n", Delimiter::Tab),
        ] {
            let r = read_records(&lines(text)).unwrap();
            assert_eq!(r.delimiter, delimiter, "{text:?}");
            let (at, header) = (r.rows[0].0, &r.rows[0].1);
            assert_eq!(
                (header[0].as_str(), header[1].as_str()),
                ("x", "y"),
                "{text:?}"
            );
            assert_eq!(r.rows.len(), 2, "{text:?}");
            assert_eq!(at + 1, r.rows[1].0);
            assert_eq!(number(&r.rows[1].1[0], r.delimiter), Some(1.5));
        }
        assert_eq!(excel_sep("sep=|"), None);
        for (cell, fortran) in [
            ("1.0D-03", true),
            ("-3.24d0", true),
            ("1.5", false),
            ("D1", false),
        ] {
            assert_eq!(fortran_exponent(cell), fortran, "{cell}");
        }
        assert!(fortran_said("1.0D-03").contains("write E"));
        assert_eq!(
            EtFile::of("sep=,\nsource,sink,positive,negative\n"),
            Some(EtFile::Protocol)
        );
        let (line, fault) = records("a,b\n\"1,2\n3,4\n").unwrap_err();
        assert_eq!((line, fault), (2, super::RecordFault::RunOn));
        assert!(fault.to_string().contains("closing quote"), "{fault}");
    }
}
