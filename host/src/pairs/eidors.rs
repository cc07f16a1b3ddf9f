//! EIDORS's protocol as EIDORS keeps it: the struct array `mk_stim_patterns` returns (a
//! forward model's `stimulation`), an element an injection with its own measurements:
//! `stim_pattern` (L x 1, the electrodes' currents: +I at the source, -I at the sink) and
//! `meas_pattern` (M x L, a row a measurement: +1 at the positive electrode, -1 at the
//! negative), both sparse as EIDORS makes them or dense. Its frame is `meas_pattern * u` of
//! each element in turn, which [`stimulation`] turns into et's protocol file. The
//! measurements may differ from one injection to the next (`rotate_meas`, `no_redundant`,
//! `no_meas_current`): each keeps its own.

use std::path::Path;

use super::cross::{counted_from, currents_a, finish};
use super::patterns::pattern;
use super::{Crossed, Crossing, Listed, MAX_VALUES, PairsError, Unit};
// The fields read of each element.
use crate::frames::STIMULATION as FIELDS;
use crate::frames::{self, Numeric};

/// The protocol of the EIDORS stimulation struct array `spec` (`file.mat`, or
/// `file.mat:NAME`: `stim.mat:stim`, `model.mat:fmdl.stimulation`), as `crossing` tells
/// (its electrodes, numbering, currents and `no_meas_current`; patterns lie one way here).
///
/// # Errors
/// [`PairsError`] naming the file, the element and its field: no such struct array, a
/// pattern that is not a pair (EIDORS's `{trig}` and `{mono}` drives are not), elements of
/// other electrode counts, a current past et's range, more than [`MAX_VALUES`] values.
pub fn stimulation(spec: &Path, crossing: &Crossing) -> Result<Crossed, PairsError> {
    let fail = |why: String| Err(PairsError::Crossing(why));
    if let Some(by) = crossing.by {
        return fail(format!(
            "--patterns {}: EIDORS's patterns lie one way (stim_pattern a vector, meas_pattern \
             a row a measurement): leave it out",
            by.said()
        ));
    }
    let (array, read) = frames::struct_array(spec, &FIELDS).map_err(PairsError::Frames)?;
    let name = &array.name;
    // The file, its struct array named by the messages (`stim.mat: stim(3).stim_pattern`).
    let file = file_of(spec);
    let mut electrodes: Option<usize> = None;
    let mut drives = Vec::with_capacity(array.elements.len());
    let mut sizes = Vec::with_capacity(array.elements.len());
    let mut measured: Vec<Vec<[u16; 2]>> = Vec::with_capacity(array.elements.len());
    let mut values = 0_usize;
    for (k, element) in array.elements.iter().enumerate() {
        let field = |i: usize| format!("{file}: {name}({}).{}", k + 1, FIELDS[i]);
        let (Some(stim), Some(meas)) = (&element[0], &element[1]) else {
            let i = usize::from(element[0].is_some());
            return fail(format!(
                "{}: not a matrix of real numbers (text, a cell, or a complex or empty value)",
                field(i)
            ));
        };
        for (i, value) in [stim, meas].into_iter().enumerate() {
            if let Some(&(r, c, v)) = value.nonzero.iter().find(|e| !e.2.is_finite()) {
                return fail(format!(
                    "{}: its entry ({}, {}) is {v}: a pattern's entries are numbers",
                    field(i),
                    r + 1,
                    c + 1
                ));
            }
        }
        let l = match (stim.rows, stim.columns) {
            (l, 1) | (1, l) => l,
            (r, c) => {
                return fail(format!(
                    "{}: {r} x {c}, where it is a vector of the electrodes' currents",
                    field(0)
                ));
            }
        };
        let range = usize::from(et_core::protocol::L_MIN)..=usize::from(et_core::protocol::L_MAX);
        match electrodes {
            None if !range.contains(&l) => {
                return fail(format!(
                    "{}: {l} electrodes: et takes {} to {}",
                    field(0),
                    range.start(),
                    range.end()
                ));
            }
            Some(first) if first != l => {
                return fail(format!(
                    "{}: {l} electrodes, where {name}(1)'s are {first}: the elements are not of \
                     one sheet",
                    field(0)
                ));
            }
            _ => electrodes = Some(l),
        }
        let mut line = vec![0.0; l];
        for &(r, c, v) in &stim.nonzero {
            line[r + c] = v; // (a vector: one of the two is 0)
        }
        let ([source, sink], size) =
            pattern(&line).map_err(|why| PairsError::Crossing(format!("{}: {why}", field(0))))?;
        if meas.columns != l {
            return fail(format!(
                "{}: {} x {}, where it is a row a measurement of the {l} electrodes (EIDORS's M \
                 x L){}",
                field(1),
                meas.rows,
                meas.columns,
                if meas.rows == l { ": transpose it" } else { "" }
            ));
        }
        values = values.saturating_add(meas.rows);
        if values > MAX_VALUES {
            return fail(format!(
                "{file}: past {MAX_VALUES} values a frame with {name}({}), more than et takes: is \
                 it EIDORS's stimulation?",
                k + 1
            ));
        }
        measured.push(rows_of(meas, &mut line).map_err(|(row, why)| {
            PairsError::Crossing(format!("{}: its row {row}: {why}", field(1)))
        })?);
        drives.push([source, sink]);
        sizes.push(size);
    }
    let Some(l) = electrodes else {
        return fail(format!("{file}: '{name}' has no elements"));
    };
    if let Some(given) = crossing.electrodes
        && usize::from(given) != l
    {
        return fail(format!(
            "-l {given}, but {name}'s patterns are of {l} electrodes: leave -l out, or give -l {l}"
        ));
    }
    let mut said = vec![format!("{file}: {read}")];
    let injections = Listed {
        pairs: drives.clone(),
        currents: Some((sizes, Unit::Unsaid)),
        patterns: Some(l),
        either_way: false,
        said: String::new(),
    };
    let currents = currents_a(spec, &injections, crossing, &mut said)?;
    let from_zero = |[a, b]: [u32; 2]| [a, b].map(|e| u16::try_from(e).unwrap_or(u16::MAX));
    let blocks: Vec<_> = (drives.iter().zip(&currents).zip(&measured))
        .map(|((&d, &c), m)| (from_zero(d), c, m.as_slice()))
        .collect();
    let (least, most) =
        (measured.iter().map(Vec::len)).fold((usize::MAX, 0), |(l, m), n| (l.min(n), m.max(n)));
    let what = format!(
        "{} injections, each with its own measurements ({}), in {name}'s order as EIDORS \
         writes the frame",
        drives.len(),
        if least == most {
            format!("{least} each")
        } else {
            format!("{least} to {most}")
        }
    );
    let base = crossing.base.unwrap_or(0);
    let electrodes = u16::try_from(l).unwrap_or(u16::MAX);
    finish(
        &blocks,
        crossing,
        (electrodes, base),
        &what,
        counted_from(base),
        said,
    )
}

/// `error`, or where `spec`'s MATLAB file holds EIDORS's stimulation struct array (given as
/// a list of injections or measurements), what it holds and the command that reads it whole.
pub(super) fn given_as_lists(spec: &Path, error: PairsError) -> PairsError {
    let names = frames::struct_array_names(spec, &FIELDS);
    let Some(first) = names.first() else {
        return error;
    };
    let file = file_of(spec);
    PairsError::Crossing(format!(
        "{file} holds EIDORS's stimulation, the struct array{} {}: each injection with its \
         own measurements, which et protocol --stimulation {file}:{first} reads whole (it is \
         neither list alone)",
        if names.len() > 1 { "s" } else { "" },
        names.join(", ")
    ))
}

/// The file `spec` names (`stim.mat` of `stim.mat:stim`).
fn file_of(spec: &Path) -> String {
    frames::split_array(spec).0.display().to_string()
}

/// Each row of `meas` as a pair (+1 at its positive electrode, -1 at its negative), from 0;
/// or the row (from 1) that is not one and why. `line`: an L-vector to fill.
fn rows_of(meas: &Numeric, line: &mut [f64]) -> Result<Vec<[u16; 2]>, (usize, String)> {
    let mut entries = meas.nonzero.clone();
    entries.sort_by_key(|&(r, c, _)| (r, c));
    let mut entries = entries.into_iter().peekable();
    let mut pairs = Vec::with_capacity(meas.rows);
    for r in 0..meas.rows {
        line.fill(0.0);
        while let Some((_, c, v)) = entries.next_if(|e| e.0 == r) {
            line[c] = v;
        }
        let ([positive, negative], _) = pattern(line).map_err(|why| (r + 1, why))?;
        let e = |e: u32| u16::try_from(e).unwrap_or(u16::MAX);
        pairs.push([e(positive), e(negative)]);
    }
    Ok(pairs)
}
