//! A CSV file as et reads one: names from a header row or column numbers, numbers per row,
//! text kept for the columns that may hold class labels.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;

use nalgebra::DMatrix;

use et_core::text::{Delimiter, RecordFault, RecordIter, StringRecord, number};

use super::{DatasetError, DatasetFault, content};

pub(super) struct Csv {
    pub(super) names: Vec<String>,
    /// Whether the names came from a header row (else they are the column numbers, 1-based).
    pub(super) header: bool,
    /// What separated the cells.
    pub(super) delimiter: Delimiter,
    /// (1-based line, values): every row has a value for every name (`parse_table` checks);
    /// NaN in a text column.
    pub(super) rows: Vec<(usize, Vec<f64>)>,
    /// Per column: its cells as written, for the columns that may hold text (class labels).
    pub(super) text: Vec<Option<Vec<String>>>,
}

impl Csv {
    /// Column `c` of every row.
    pub(super) fn column(&self, path: &Path, c: usize) -> Result<Vec<f64>, DatasetError> {
        self.rows
            .iter()
            .map(|(line, v)| {
                v.get(c).copied().filter(|v| v.is_finite()).ok_or_else(|| {
                    content(
                        path,
                        *line,
                        self.names.get(c).cloned(),
                        DatasetFault::Missing,
                    )
                })
            })
            .collect()
    }

    /// Column `c` as written (labels: any text, numbers as their text).
    pub(super) fn text_column(&self, path: &Path, c: usize) -> Result<Vec<String>, DatasetError> {
        match self.text.get(c) {
            Some(Some(t)) => Ok(t.clone()),
            _ => Err(content(
                path,
                0,
                self.names.get(c).cloned(),
                DatasetFault::NotText,
            )),
        }
    }

    /// A one-column table of text read without a header (its first row text like the rest)
    /// whose first row is its header after all: it has one row more than `rows` (the
    /// features', read with a header) and its first cell recurs nowhere below, where the
    /// cells below do recur (a class or session named `label` or `session` above `left`,
    /// `right`, `left`, ... as pandas writes `y.to_csv(index=False)`). Whether it was made so.
    pub(super) fn first_row_as_header(&mut self, rows: usize, features_header: bool) -> bool {
        if !features_header || self.header_like(rows).is_none() {
            return false;
        }
        if let Some(Some(cells)) = self.text.first_mut() {
            self.names = vec![cells.remove(0)];
        }
        self.rows.remove(0);
        self.header = true;
        true
    }

    /// The first cell of a one-column table of text read without a header, when it reads as
    /// a header beside features of `rows` rows: one row more than theirs, the cell recurring
    /// nowhere below and the cells below recurring ([`Csv::first_row_as_header`]).
    pub(super) fn header_like(&self, rows: usize) -> Option<&str> {
        let Some(Some(cells)) = self.text.first() else {
            return None;
        };
        let first = cells.first()?;
        let below = cells.get(1..).unwrap_or_default();
        let recurs = {
            let mut seen = std::collections::HashSet::new();
            below.iter().any(|c| !seen.insert(c))
        };
        let named = !below.contains(first) && first.parse::<f64>().is_err();
        (!self.header && self.names.len() == 1 && self.rows.len() == rows + 1 && named && recurs)
            .then_some(first.as_str())
    }

    /// Columns `cols`, as an n x cols.len() matrix.
    pub(super) fn matrix(&self, path: &Path, cols: &[usize]) -> Result<DMatrix<f64>, DatasetError> {
        let mut x = DMatrix::zeros(self.rows.len(), cols.len());
        for (j, &c) in cols.iter().enumerate() {
            x.set_column(j, &nalgebra::DVector::from_vec(self.column(path, c)?));
        }
        Ok(x)
    }

    /// Column `c` as whole numbers 0..=65535 (class labels, visits).
    pub(super) fn whole(&self, path: &Path, c: usize) -> Result<Vec<u16>, DatasetError> {
        self.column(path, c)?
            .into_iter()
            .zip(&self.rows)
            .map(|(v, (line, _))| {
                if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u16::MAX) {
                    Ok(v as u16)
                } else {
                    let name = self.names.get(c).cloned();
                    Err(content(path, *line, name, DatasetFault::NotWhole(v)))
                }
            })
            .collect()
    }
}

/// The columns' names: the header's (`header`), else 1, 2, ... for the `first` row's cells;
/// refused where one is empty or two are one name (letter case aside), on line `hl`.
fn column_names(
    path: &Path,
    hl: usize,
    first: &[&str],
    header: bool,
) -> Result<Vec<String>, DatasetError> {
    let names: Vec<String> = if header {
        first.iter().map(|c| (*c).to_string()).collect()
    } else {
        (1..=first.len()).map(|c| c.to_string()).collect()
    };
    if let Some(c) = names.iter().position(String::is_empty) {
        let (column, columns) = (c + 1, names.len());
        return Err(content(
            path,
            hl,
            None,
            DatasetFault::EmptyName { column, columns },
        ));
    }
    // Two columns of one name: which one a reader takes would be a guess (a second `x` was
    // dropped silently).
    let mut seen = std::collections::HashMap::with_capacity(names.len());
    for (b, name) in names.iter().enumerate() {
        if let Some(&a) = seen.get(&name.to_ascii_lowercase()) {
            let (first, second, name) = (a + 1, b + 1, name.clone());
            let fault = DatasetFault::SameName {
                first,
                second,
                name: name.clone(),
            };
            return Err(content(path, hl, Some(name), fault));
        }
        seen.insert(name.to_ascii_lowercase(), b);
    }
    Ok(names)
}

/// Line `i`'s `cells` as numbers, one per column of `names`: a column that keeps its text
/// (a `Some` of `text`) takes the cell as written (NaN where it is no number; empty refused);
/// any other cell must be a finite number.
fn row_values(
    path: &Path,
    i: usize,
    cells: &[&str],
    names: &[String],
    text: &mut [Option<Vec<String>>],
    delimiter: Delimiter,
) -> Result<Vec<f64>, DatasetError> {
    let mut values = Vec::with_capacity(cells.len());
    for ((cell, name), t) in cells.iter().zip(names).zip(text.iter_mut()) {
        if let Some(t) = t {
            if cell.is_empty() {
                return Err(content(
                    path,
                    i,
                    Some(name.clone()),
                    DatasetFault::EmptyLabel,
                ));
            }
            t.push(cell.to_string());
            values.push(number(cell, delimiter).unwrap_or(f64::NAN));
            continue;
        }
        values.push(match number(cell, delimiter) {
            Some(v) if v.is_finite() => v,
            Some(v) => {
                let fault = DatasetFault::NotFinite(v);
                return Err(content(path, i, Some(name.clone()), fault));
            }
            None => {
                let fault = DatasetFault::NotNumber(cell.to_string());
                return Err(content(path, i, Some(name.clone()), fault));
            }
        });
    }
    Ok(values)
}

/// An optional header row, then numeric rows; blank and `#` lines skipped; every value finite.
/// Cells are read by the `csv` crate: quoted cells (`"1,5"`, `"a ""b"""`), cells separated by
/// `,`, `;`, tabs or runs of spaces (detected from the first row, [`Delimiter::of`]), spaces
/// around cells trimmed, a delimiter ending every line taken as the line's end. The first row is a header when it has a cell that is not a number, unless the
/// second row has text in exactly the same columns (a headerless file with text labels).
/// `text_ok(name, columns)` says which columns may hold text (kept as written besides their
/// numbers).
pub(super) fn parse_table(
    path: &Path,
    lines: &[(usize, &str)],
    text_ok: &dyn Fn(&str, usize) -> bool,
) -> Result<Csv, DatasetError> {
    // JSON (an et recording, a model file) is said as what it is: its text was read as cells
    // ("columns 8 and 11 are both named 'protocol:\"Adjacent\"'").
    if let Some((line, first)) = lines.first()
        && first.trim_start().starts_with('{')
    {
        let format = serde_json::from_str::<serde_json::Value>(first)
            .ok()
            .and_then(|v| Some(v.get("format")?.as_str()?.chars().take(40).collect()));
        return Err(content(path, *line, None, DatasetFault::NotTable(format)));
    }
    // A protocol file (its four electrode columns, and the current): read as features, its
    // electrode numbers were a sensor's values.
    if let Some((line, first)) = lines.first()
        && et_core::text::EtFile::columns_beside_protocol(first) == Some(0)
    {
        return Err(content(path, *line, None, DatasetFault::ProtocolTable));
    }
    let mut records = RecordIter::new(lines);
    let delimiter = records.delimiter;
    let read = |r: Result<(usize, StringRecord), (usize, RecordFault)>| {
        r.map_err(|(line, f)| content(path, line, None, f.into()))
    };
    // The first two records decide the header; the rest are read one at a time (what is kept
    // is each row's numbers, not its cells as text).
    let head = records
        .by_ref()
        .take(2)
        .map(read)
        .collect::<Result<Vec<_>, _>>()?;
    let (hl, first) = head
        .first()
        .map(|(line, cells)| (*line, cells))
        .ok_or_else(|| content(path, 0, None, DatasetFault::NoRows))?;
    // A delimiter ending the first or second row's line (`fprintf('%g,', row)` in a loop,
    // perhaps under a header written by hand) ends each row that has one: it is not an empty
    // last column.
    let trailing = head
        .iter()
        .any(|(_, r)| et_core::text::ends_with_delimiter(r));
    let texts = |r: &StringRecord| -> Vec<bool> {
        et_core::text::cells(r, trailing)
            .iter()
            .map(|c| number(c, delimiter).is_none())
            .collect()
    };
    let first_text = texts(first);
    let second_text = head.get(1).map(|(_, r)| texts(r));
    let header =
        first_text.iter().any(|&t| t) && second_text.is_none_or(|second| second != first_text);
    let names = column_names(path, hl, &et_core::text::cells(first, trailing), header)?;
    let keep_text: Vec<bool> = names.iter().map(|n| text_ok(n, names.len())).collect();
    let mut text: Vec<Option<Vec<String>>> = keep_text.iter().map(|&k| k.then(Vec::new)).collect();
    let mut rows = Vec::new();
    let mut body = head
        .into_iter()
        .skip(usize::from(header))
        .map(Ok)
        .chain(records.map(read))
        .peekable();
    while let Some(record) = body.next() {
        let (i, record) = record?;
        let cells = et_core::text::cells(&record, trailing);
        if cells.len() != names.len() {
            let (found, columns) = (cells.len(), names.len());
            let fault = DatasetFault::RowLength {
                found,
                columns,
                header,
                last: found < columns && body.peek().is_none(),
            };
            return Err(content(path, i, None, fault));
        }
        let values = row_values(path, i, &cells, &names, &mut text, delimiter)?;
        rows.push((i, values));
    }
    if rows.is_empty() {
        return Err(content(path, 0, None, DatasetFault::NoDataRows));
    }
    Ok(Csv {
        names,
        header,
        delimiter,
        rows,
        text,
    })
}
