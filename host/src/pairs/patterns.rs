//! A matrix of patterns read as pairs: each line (a row or a column) an L-vector with one
//! entry above 0 and one below, of one size.

use nalgebra::DMatrix;

use super::{By, PairsFault, Side};

/// A pattern's two electrodes and its size, or why it is not one: one entry above 0 and
/// one below, of one size (within 1e-6), every other 0.
pub(super) fn pattern(values: &[f64]) -> Result<([u32; 2], f64), String> {
    let largest = values.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let nonzero: Vec<usize> = (0..values.len())
        .filter(|&i| values[i].abs() > 1e-9 * largest)
        .collect();
    let above: Vec<usize> = nonzero
        .iter()
        .copied()
        .filter(|&i| values[i] > 0.0)
        .collect();
    let below: Vec<usize> = nonzero
        .iter()
        .copied()
        .filter(|&i| values[i] < 0.0)
        .collect();
    match (above.as_slice(), below.as_slice()) {
        ([p], [n]) if (values[*p] + values[*n]).abs() <= 1e-6 * values[*p] => {
            Ok(([*p as u32, *n as u32], values[*p]))
        }
        ([p], [n]) => Err(format!(
            "+{} and {} are not of one size",
            values[*p], values[*n]
        )),
        ([], _) | (_, []) => Err(format!(
            "{} above 0 and {} below: a pattern has one of each (+ at the source or positive \
             electrode, - at the sink or negative; one electrode against ground is not a pair)",
            entries(above.len()),
            entries(below.len())
        )),
        _ => Err(format!(
            "{} above 0 and {} below, where a pattern has one of each",
            entries(above.len()),
            entries(below.len())
        )),
    }
}

/// `n` entries, in words ("no entry", "1 entry", "3 entries").
fn entries(n: usize) -> String {
    match n {
        0 => "no entry".into(),
        1 => "1 entry".into(),
        n => format!("{n} entries"),
    }
}

/// A matrix's patterns.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Patterns {
    /// Each pattern's two electrodes (from 0): the + one, then the - one.
    pub pairs: Vec<[u32; 2]>,
    /// Each pattern's size (its + entry).
    pub sizes: Vec<f64>,
    /// Their length: the sheet's electrodes.
    pub electrodes: usize,
    /// How they lie (by the matrix's shape, else as told).
    pub by: By,
    /// Both ways round read as patterns, differently (read as told).
    pub either_way: bool,
}

/// Reads `m`'s patterns: by rows or by columns, whichever are all patterns; a matrix whose
/// rows and columns both are (a square one) by `by`, refused without it.
pub(super) fn patterns(
    m: &DMatrix<f64>,
    side: Side,
    by: Option<By>,
) -> Result<Patterns, PairsFault> {
    let lines = |by: By| -> Vec<Vec<f64>> {
        match by {
            By::Rows => m.row_iter().map(|r| r.iter().copied().collect()).collect(),
            By::Columns => m
                .column_iter()
                .map(|c| c.iter().copied().collect())
                .collect(),
        }
    };
    let read = |by: By| -> Result<Patterns, (usize, String)> {
        let lines = lines(by);
        let electrodes = lines.first().map_or(0, Vec::len);
        let mut pairs = Vec::with_capacity(lines.len());
        let mut sizes = Vec::with_capacity(lines.len());
        for (i, line) in lines.iter().enumerate() {
            let (pair, size) = pattern(line).map_err(|why| (i, why))?;
            pairs.push(pair);
            sizes.push(size);
        }
        Ok(Patterns {
            pairs,
            sizes,
            electrodes,
            by,
            either_way: false,
        })
    };
    let (rows, columns) = (read(By::Rows), read(By::Columns));
    // Both ways read as patterns, and differently: `by` tells which (asked for only then).
    let either_way =
        matches!((&rows, &columns), (Ok(r), Ok(c)) if r.pairs != c.pairs || r.sizes != c.sizes);
    let with = |p: Patterns| Patterns { either_way, ..p };
    match (rows, columns, by) {
        (Ok(_), Ok(_), None) if either_way => Err(PairsFault::EitherWay {
            side,
            rows: m.nrows(),
            columns: m.ncols(),
        }),
        (Ok(_), Ok(columns), Some(By::Columns)) => Ok(with(columns)),
        (Ok(rows), _, _) => Ok(with(rows)),
        (Err(_), Ok(columns), _) => Ok(with(columns)),
        (Err((i, why)), Err((j, why_columns)), _) => {
            // Said the way whose lines could be a sheet's electrodes (4 to 32), else the way
            // of the longer lines.
            let fits = |n: usize| {
                (usize::from(et_core::protocol::L_MIN)..=usize::from(et_core::protocol::L_MAX))
                    .contains(&n)
            };
            let by_rows = match (fits(m.ncols()), fits(m.nrows())) {
                (true, false) => true,
                (false, true) => false,
                _ => m.ncols() >= m.nrows(),
            };
            let (by, i, why) = if by_rows {
                (By::Rows, i, why)
            } else {
                (By::Columns, j, why_columns)
            };
            Err(PairsFault::Pattern { side, by, i, why })
        }
    }
}
