//! Each row's group (session) of a sensor's table: a named column, or a file of its own.

use std::path::Path;

use super::super::table::Csv;
use super::super::{DatasetError, DatasetFault, content};
use super::{GroupsFrom, beside};

/// Each row's group: a named column of the features file (`main`) or else of the targets
/// file (`side`), or a file of one column with its row count.
pub(super) fn group_values(
    groups: &GroupsFrom,
    features: &Path,
    main: &Csv,
    side: Option<&(&Path, Csv)>,
) -> Result<Vec<String>, DatasetError> {
    match groups {
        GroupsFrom::Column(name) => {
            let in_side = side.and_then(|(p, t)| {
                let c = t.names.iter().position(|n| n.eq_ignore_ascii_case(name));
                c.filter(|_| t.header).map(|c| (*p, t, c))
            });
            let in_main = main.names.iter().any(|n| n.eq_ignore_ascii_case(name));
            if let (Some((p, t, c)), false) = (in_side, in_main && main.header) {
                return t.text_column(p, c);
            }
            let c = main
                .names
                .iter()
                .position(|n| n.eq_ignore_ascii_case(name))
                .filter(|_| main.header)
                .ok_or_else(|| {
                    let names = main
                        .header
                        .then(|| main.names.iter().take(8).cloned().collect());
                    let name = name.clone();
                    content(
                        features,
                        0,
                        None,
                        DatasetFault::NoGroupColumn { name, names },
                    )
                })?;
            main.text_column(features, c)
        }
        GroupsFrom::File(p) => {
            let one = |_: &str, _: usize| true;
            beside(p, features, main, &one, "rows of groups")?.text_column(p, 0)
        }
    }
}

/// The groups when none are given: a column named as sessions (an et dataset's `visit`,
/// another's `session`) of the features file (`main`), else of the targets file (`side`).
/// As a feature it was the session's number among the voltages.
///
/// # Errors
/// As [`roles::session_column`](super::roles::session_column): several such columns in one
/// file.
pub(super) fn sessions_as_groups(
    features: &Path,
    main: &Csv,
    side: Option<&(&Path, Csv)>,
) -> Result<Option<GroupsFrom>, DatasetError> {
    let column = match super::roles::session_column(features, main)? {
        Some(column) => Some(column),
        None => side
            .map(|(p, t)| super::roles::session_column(p, t))
            .transpose()?
            .flatten(),
    };
    Ok(column.map(GroupsFrom::Column))
}

/// What the read line says of the groups (`values`, one per row): how many, and where they
/// came from when taken without being given (`sessions`; an et dataset's visits when
/// `from_dataset`). Empty without groups.
pub(super) fn groups_said(
    values: Option<&[String]>,
    sessions: Option<&GroupsFrom>,
    from_dataset: bool,
) -> String {
    let Some(values) = values else {
        return String::new();
    };
    let distinct: std::collections::BTreeSet<&String> = values.iter().collect();
    let n = distinct.len();
    let whence = match (sessions, from_dataset) {
        (Some(_), true) => " (an et dataset's visits)".to_string(),
        (Some(GroupsFrom::Column(c)), false) => format!(" (its '{c}' column)"),
        _ => String::new(),
    };
    format!("; {n} group{}{whence}", if n == 1 { "" } else { "s" })
}
