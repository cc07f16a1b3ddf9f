//! A protocol file's header: which column is each of [`COLUMNS`], by et's names or the ones
//! other tools write for them.

use super::{COLUMNS, FileFault};
use crate::text;

/// Other names a column of [`COLUMNS`] goes by (any case): hardware logs' `I+ I- V+ V-`,
/// geophysics' `A B M N` and `C1 C2 P1 P2` (resistivity tomography's current and potential
/// electrodes), and short forms.
const ALSO: [&[&str]; 4] = [
    &["src", "i+", "inj+", "a", "c1"],
    &["snk", "i-", "inj-", "b", "c2"],
    &["pos", "plus", "v+", "meas+", "m", "p1"],
    &["neg", "minus", "v-", "meas-", "n", "p2"],
];

/// Names a column of [`COLUMNS`] may begin with, before words of its own
/// (`source_electrode(+)`, `plus_electrode`, as tank archives' pair lists name them).
const BEGINS: [&[&str]; 4] = [
    &["source"],
    &["sink"],
    &["positive", "plus"],
    &["negative", "minus"],
];

/// Which of [`COLUMNS`] a header's cell names: by et's name or another of [`ALSO`], or as
/// its first word (split at anything but letters and digits) one of [`BEGINS`].
pub fn role(cell: &str) -> Option<usize> {
    let c = cell.trim();
    let first = c
        .split(|ch: char| !ch.is_ascii_alphanumeric())
        .next()
        .unwrap_or("");
    COLUMNS
        .iter()
        .position(|n| c.eq_ignore_ascii_case(n))
        .or_else(|| {
            ALSO.iter()
                .position(|names| names.iter().any(|n| c.eq_ignore_ascii_case(n)))
        })
        .or_else(|| {
            BEGINS
                .iter()
                .position(|names| names.iter().any(|n| first.eq_ignore_ascii_case(n)))
        })
}

/// Whether the `first` record is a header, and where each of [`COLUMNS`] is: named by a
/// header (any order; a name twice, or one of the four missing, refused), or, without one, the
/// first four or five columns. A header names at least one column (a row of numbers with a typo
/// is data); a first row with no number and none of the names is a header of other names.
pub(super) fn header_columns(
    first: &csv::StringRecord,
    delimiter: text::Delimiter,
) -> Result<(bool, [Option<usize>; 5]), FileFault> {
    let header = first.iter().any(|c| role(c).is_some());
    if header {
        let find = |i: usize| first.iter().position(|c| role(c) == Some(i));
        let columns = [0, 1, 2, 3, 4].map(find);
        // A column named twice: which one is meant would be a guess (said before the column a
        // misspelt second name leaves missing).
        if let Some(name) = (0..COLUMNS.len())
            .find(|i| first.iter().filter(|c| role(c) == Some(*i)).count() > 1)
            .and_then(|i| COLUMNS.get(i))
        {
            return Err(FileFault::SameColumn(name));
        }
        // A list of injections alone (source, sink) or of measurements alone, as tank
        // archives give them apart: crossed into a protocol file by `et protocol`.
        match columns[..4] {
            [Some(_), Some(_), None, None] => return Err(FileFault::PairsOnly("injections")),
            [None, None, Some(_), Some(_)] => return Err(FileFault::PairsOnly("measurements")),
            _ => {}
        }
        if let Some(missing) = COLUMNS[..4].iter().zip(&columns).find(|(_, c)| c.is_none()) {
            return Err(FileFault::MissingColumn(missing.0));
        }
        // Other columns are ignored, but one named as a current would leave its rows driving
        // the scene's current without a word (a tank's amplitudes in mA, say).
        if let Some(other) = (first.iter()).find(|c| role(c) != Some(4) && reads_as_current(c)) {
            return Err(FileFault::OtherCurrent(other.into()));
        }
        return Ok((true, columns));
    }
    if first.len() > 1 && first.iter().all(|c| text::number(c, delimiter).is_none()) {
        // (A dataset's 200 feature names were all said.)
        let mut names = first.iter().take(6).collect::<Vec<_>>().join(", ");
        if first.len() > 6 {
            names += &format!(", ... ({} columns)", first.len());
        }
        return Err(FileFault::OtherNames(names));
    }
    if first.len() == 4 || first.len() == 5 {
        let current = (first.len() == 5).then_some(4);
        return Ok((false, [Some(0), Some(1), Some(2), Some(3), current]));
    }
    Err(FileFault::Columns(first.len()))
}

/// Whether a header's column `name` is named as a current: a word of it (split at anything
/// but letters and digits) begins with `current` or `amp` (amps, ampere, amplitude), or is a
/// unit of current (`I (mA)`, `I_uA`, `I [A]`, `I_A`, `I/A`).
#[must_use]
pub fn reads_as_current(name: &str) -> bool {
    let units = ["mA", "uA", "nA", "µA", "μA"];
    let bracketed = ["(A)", "[A]", "_A", "/A"]
        .iter()
        .any(|u| name.trim_end().ends_with(u));
    bracketed
        || name.split(|c: char| !c.is_alphanumeric()).any(|word| {
            let lower = word.to_ascii_lowercase();
            units.contains(&word) || lower.starts_with("current") || lower.starts_with("amp")
        })
}
