//! Columns of a sensor's table that are not measurements, known by their names: the rows'
//! numbers and times, and the sessions they were recorded in.
//!
//! Taken as features they give the model the row's place in the recording, not the sheet's
//! state: in a table recorded position after position the row's number predicts the
//! position, and cross-validation reports a fraction of the error the voltages alone give,
//! for a model that reads the row number and fails on the next recording.

use std::path::Path;

use super::super::table::Csv;
use super::super::{DatasetError, DatasetFault, content};

/// What a column holds that is no measurement, by its name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Role {
    /// The row's number or name (`id`, `index`, `sample`, `frame`, `sample_id`).
    Identifier,
    /// When the row was recorded (`time`, `t`, `timestamp`, `time_s`, `time (ms)`).
    Time,
    /// The session it was recorded in (`session`, `visit`, `subject`, `day`, `run`, `group`).
    Session,
}

impl Role {
    fn said(self) -> &'static str {
        match self {
            Role::Identifier => "the rows' numbers",
            Role::Time => "the rows' times",
            Role::Session => "sessions",
        }
    }
}

/// The role of a column named `name` (any case): a stem alone, or with a suffix that names
/// the same thing (`sample_id`, `session no`, `subject-name`) or, for a time, its unit
/// (`time_ms`, `Time (s)`); any name ending in `_id`. None for every other name: a stem
/// numbered as channels are (`sample_1`, `t 2`) or with another word after it
/// (`sample_rate`, `run_avg`: measurements, or a feature of the run).
pub(super) fn role(name: &str) -> Option<Role> {
    let name = name.trim().to_ascii_lowercase();
    let separators = ['_', ' ', '(', '[', '-', '.', ')', ']'];
    let stem = name.split(separators).next().unwrap_or_default();
    let rest = name.get(stem.len()..).unwrap_or_default();
    let rest = rest.trim_matches(separators);
    let names_it = matches!(
        rest,
        "" | "id" | "no" | "nr" | "num" | "number" | "name" | "#"
    );
    let a_unit = matches!(
        rest,
        "" | "s" | "ms" | "us" | "µs" | "ns" | "sec" | "secs" | "seconds" | "min" | "h" | "utc"
    );
    match stem {
        "session" | "visit" | "subject" | "participant" | "day" | "run" | "group" if names_it => {
            Some(Role::Session)
        }
        "id" | "index" | "idx" | "row" | "sample" | "seq" | "sequence" | "frame" | "#"
            if names_it =>
        {
            Some(Role::Identifier)
        }
        "time" | "t" | "timestamp" | "datetime" | "date" | "elapsed" if a_unit => Some(Role::Time),
        _ if name.ends_with("_id") || name.ends_with(" id") => Some(Role::Identifier),
        _ => None,
    }
}

/// The names of `table`'s columns of `wanted` role (none without a header).
pub(super) fn named(table: &Csv, wanted: Role) -> Vec<&str> {
    (table.names.iter())
        .filter(|n| table.header && role(n) == Some(wanted))
        .map(String::as_str)
        .collect()
}

/// The session column the groups come from when none is given: the one column named as
/// sessions, or None when there is none.
///
/// # Errors
/// [`DatasetFault::Sessions`] when several are (which sessions a model must hold across is
/// the user's choice).
pub(super) fn session_column(path: &Path, table: &Csv) -> Result<Option<String>, DatasetError> {
    match named(table, Role::Session).as_slice() {
        [] => Ok(None),
        [one] => Ok(Some((*one).to_string())),
        several => {
            let names = several.iter().map(|n| (*n).to_string()).collect();
            Err(content(path, 0, None, DatasetFault::Sessions(names)))
        }
    }
}

/// What the read line says of the columns left out of the features by their names
/// (`group`, the column the groups were taken from, aside); empty when none were.
pub(super) fn left_out(table: &Csv, group: Option<&str>) -> String {
    let said: Vec<String> = [Role::Identifier, Role::Time, Role::Session]
        .into_iter()
        .filter_map(|r| {
            let names: Vec<String> = (named(table, r).into_iter())
                .filter(|n| group.is_none_or(|g| !g.eq_ignore_ascii_case(n)))
                .map(|n| format!("'{n}'"))
                .collect();
            (!names.is_empty()).then(|| format!("{} ({})", names.join(", "), r.said()))
        })
        .collect();
    if said.is_empty() {
        String::new()
    } else {
        format!("; not features: {}", said.join(", "))
    }
}

/// Checks that a targets file (`targets`, `side`) pairs with the features file (`features`,
/// `main`) row for row where both carry a column of the rows' numbers or times by one name:
/// rows are paired by their order, and the same `id` in another order pairs each row's
/// features with another row's targets.
///
/// # Errors
/// [`DatasetFault::RowsDiffer`] at the first row where the two columns differ.
pub(super) fn check_paired(
    features: &Path,
    main: &Csv,
    targets: &Path,
    side: &Csv,
) -> Result<(), DatasetError> {
    for (c, name) in main.names.iter().enumerate() {
        if !main.header || !matches!(role(name), Some(Role::Identifier | Role::Time)) {
            continue;
        }
        let Some(t) = (side.header)
            .then(|| side.names.iter().position(|n| n.eq_ignore_ascii_case(name)))
            .flatten()
        else {
            continue;
        };
        let (ours, theirs) = (
            main.text_column(features, c)?,
            side.text_column(targets, t)?,
        );
        let differs = ours.iter().zip(&theirs).position(|(a, b)| !same_cell(a, b));
        if let Some(i) = differs {
            let line = |table: &Csv| table.rows.get(i).map_or(0, |r| r.0);
            let fault = DatasetFault::RowsDiffer {
                here: ours.get(i).cloned().unwrap_or_default(),
                there: theirs.get(i).cloned().unwrap_or_default(),
                targets: targets.into(),
                line: line(side),
            };
            return Err(content(features, line(main), Some(name.clone()), fault));
        }
    }
    Ok(())
}

/// Whether two cells say one thing: as written, or as numbers (`7` and `7.0`).
fn same_cell(a: &str, b: &str) -> bool {
    a.trim() == b.trim()
        || matches!(
            (a.trim().parse::<f64>(), b.trim().parse::<f64>()),
            (Ok(x), Ok(y)) if x == y
        )
}
