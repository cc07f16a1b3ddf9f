//! A list of pairs under a header of names: its two electrodes' columns by name, an
//! injection's current by its name and the unit the name says.

use std::path::Path;

use et_core::schedule::{COLUMNS, column_role, reads_as_current};
use et_core::text;

use super::{Listed, PairsError, PairsFault, Side, Unit, amperes_per};
use crate::frames::unit_in_name;

/// What a table's first row says.
pub(super) enum Named {
    /// A header naming the side's columns: the list read by them.
    Listed(Listed),
    /// A row of numbers: the table is read as a matrix.
    Numbers,
    /// A header naming none of a protocol's columns (a matrix of patterns' electrodes, say):
    /// the table is read as a matrix, and a list under it refused by this fault.
    Other(usize, PairsFault),
}

/// The side read from `text` when its first row is a header naming its columns; else what
/// the first row is.
///
/// # Errors
/// [`PairsError::Content`] naming the line: the header lacks the side's two electrodes, a
/// cell is not an electrode or a current, a row is short.
pub(super) fn named(path: &Path, text: &str, side: Side) -> Result<Named, PairsError> {
    let fail = |line: usize, fault| PairsError::content(path, line, fault);
    let lines = text::lines(text);
    let records = text::RecordIter::new(&lines);
    let delimiter = records.delimiter;
    let mut records = records.peekable();
    let (first_line, first) = match records.next() {
        Some(Ok(r)) => r,
        Some(Err((line, fault))) => return Err(fail(line, PairsFault::Records(fault))),
        None => return Err(fail(0, PairsFault::Empty)),
    };
    if first.iter().all(|c| text::number(c, delimiter).is_some()) {
        return Ok(Named::Numbers);
    }
    let find = |role: usize| first.iter().position(|c| column_role(c) == Some(role));
    let [a, b] = side.columns();
    let (Some(ca), Some(cb)) = (find(a), find(b)) else {
        let names = first.iter().take(6).collect::<Vec<_>>().join(", ");
        let [oa, ob] = match side {
            Side::Injections => Side::Measurements,
            Side::Measurements => Side::Injections,
        }
        .columns();
        let other = find(oa).is_some() && find(ob).is_some();
        let fault = PairsFault::Names { side, names, other };
        if (0..4).all(|role| find(role).is_none()) {
            return Ok(Named::Other(first_line, fault));
        }
        return Err(fail(first_line, fault));
    };
    // An injection's current: current_a in amperes, or another name read as a current (by a
    // word, or a unit of current: `I (mA)`; the protocol file's rule) in the unit it says (`current_ma`, `amplitude
    // (mA)`), else in a unit to be given.
    let current = (side == Side::Injections)
        .then(|| {
            first.iter().enumerate().find_map(|(c, name)| {
                if column_role(name) == Some(4) {
                    Some((c, name, Unit::Named("A".to_string(), 1.0)))
                } else if reads_as_current(name) {
                    let unit = unit_in_name(name, amperes_per).map_or_else(
                        || Unit::Asked(name.to_string()),
                        |(u, per)| Unit::Named(u, per),
                    );
                    Some((c, name, unit))
                } else {
                    None
                }
            })
        })
        .flatten();
    let mut pairs = Vec::new();
    let mut currents = Vec::new();
    for record in records {
        let (line, record) = record.map_err(|(line, f)| fail(line, PairsFault::Records(f)))?;
        let cell = |c: usize| record.get(c).unwrap_or("").trim();
        let electrode = |c: usize, role: usize| {
            let v = cell(c);
            text::number(v, delimiter)
                .filter(|x| x.fract() == 0.0 && (0.0..=f64::from(u16::MAX)).contains(x))
                .map(|x| x as u32)
                .ok_or_else(|| {
                    let (column, cell) = (COLUMNS[role], v.to_string());
                    fail(line, PairsFault::NotNumber { column, cell })
                })
        };
        pairs.push([electrode(ca, a)?, electrode(cb, b)?]);
        if let Some((c, _, _)) = &current {
            let v = cell(*c);
            let x = text::number(v, delimiter)
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    let (column, cell) = ("its current", v.to_string());
                    fail(line, PairsFault::NotNumber { column, cell })
                })?;
            currents.push(x);
        }
    }
    if pairs.is_empty() {
        return Err(fail(first_line, PairsFault::Empty));
    }
    let name = |c: usize| format!("'{}'", first.get(c).unwrap_or(""));
    // The columns read for none of these, said (a current under a name not read as one would
    // otherwise drive the default without a word).
    let used = [Some(ca), Some(cb), current.as_ref().map(|(c, _, _)| *c)];
    let ignored: Vec<String> = (0..first.len())
        .filter(|c| !used.contains(&Some(*c)))
        .map(name)
        .collect();
    let said = format!(
        "{}: {} {} pairs under a header ({}, {}{}{})",
        path.display(),
        pairs.len(),
        side.noun(),
        name(ca),
        name(cb),
        current.as_ref().map_or(String::new(), |(_, name, unit)| {
            let unit = match unit {
                Unit::Named(u, _) => format!(" in {u}"),
                _ => String::new(),
            };
            format!("; currents from '{name}'{unit}")
        }),
        match ignored.as_slice() {
            [] => String::new(),
            [one] => format!("; its column {one} ignored"),
            many => format!("; its columns {} ignored", many.join(", ")),
        }
    );
    Ok(Named::Listed(Listed {
        pairs,
        currents: current.map(|(_, _, unit)| (currents, unit)),
        patterns: None,
        either_way: false,
        said,
    }))
}
