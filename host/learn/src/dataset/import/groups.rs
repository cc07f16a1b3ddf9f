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
