//! Each row's group (session) of a sensor's table: a named column, or a file of its own.

use std::path::Path;

use et_core::text::lines as text_lines;

use super::super::table::{Csv, parse_table};
use super::super::{DatasetError, DatasetFault, content};
use super::{GroupsFrom, read};

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
            let mut g = parse_table(p, &text_lines(&read(p)?), &one)?;
            g.first_row_as_header(main.rows.len(), main.header);
            if g.rows.len() != main.rows.len() {
                let fault = DatasetFault::RowCount {
                    rows: g.rows.len(),
                    what: "rows of groups",
                    features: features.into(),
                    features_rows: main.rows.len(),
                };
                return Err(content(p, 0, None, fault));
            }
            g.text_column(p, 0)
        }
    }
}
