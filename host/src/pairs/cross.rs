//! Two lists crossed into a protocol: every measurement under every injection, the sheet's
//! electrodes, the lists' numbering and the injections' currents from the files or as told.

use std::path::Path;

use et_core::schedule::{MAX_CURRENT_A, MIN_CURRENT_A, Row, Schedule};

use super::{Crossed, Crossing, Listed, MAX_VALUES, PairsError, Side, Unit, read};

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
    let counted = if sides.iter().any(|(_, l)| l.patterns.is_none()) {
        "as the lists count them"
    } else {
        counted_from(base)
    };
    let injections: Vec<_> = (drives.iter().zip(&currents))
        .map(|(&drive, &current_a)| (drive, current_a, measured.as_slice()))
        .collect();
    let what = format!(
        "{} injections x {} measurements, injection by injection",
        drives.len(),
        measured.len()
    );
    finish(
        &injections,
        crossing,
        (electrodes, base),
        &what,
        counted,
        said,
    )
}

/// How patterns' electrodes (from 0) are written, counted from `base`.
pub(super) fn counted_from(base: u16) -> &'static str {
    if base == 1 {
        "counted from 1 (--base 1)"
    } else {
        "counted from 0, et's way (--base 1 writes them from 1)"
    }
}

/// An injection's pair (source, sink, from 0), its current, A, and the measurements (positive,
/// negative) taken under it.
pub(super) type Injection<'a> = ([u16; 2], f64, &'a [[u16; 2]]);

/// The protocol of `injections` (each its pair, its current, A, and the measurements taken
/// under it; electrodes from 0), less each one's measurements on its drive electrodes where
/// `crossing` says so, on `(electrodes, base)`; its K said after `said` with `what` was
/// crossed and how its electrodes are `counted`.
pub(super) fn finish(
    injections: &[Injection<'_>],
    crossing: &Crossing,
    (electrodes, base): (u16, u16),
    what: &str,
    counted: &str,
    mut said: Vec<String>,
) -> Result<Crossed, PairsError> {
    let values: usize = injections.iter().map(|(_, _, m)| m.len()).sum();
    let mut rows = Vec::with_capacity(values);
    for &([source, sink], current_a, measured) in injections {
        for &[positive, negative] in measured {
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
        return Err(PairsError::Crossing(format!(
            "--no-meas-current leaves none of the {values} values: every measurement uses a \
             drive electrode"
        )));
    }
    let k = rows.len();
    let schedule = Schedule::new(electrodes, rows)?;
    let (first, last) = (base, electrodes - 1 + base);
    said.push(format!(
        "K = {k} values a frame: {what}{}; electrodes {first} to {last}, {counted} (a scene \
         reads the file as [scan] protocol = {{ file = \"protocol.csv\"{} }})",
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
pub(super) fn currents_a(
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
