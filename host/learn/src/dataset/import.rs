//! Data from other sensors: a CSV of features with its targets, read into a [`Table`] (see
//! [`Table::import`]).

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use et_core::text::lines as text_lines;

use super::table::{Csv, parse_table};
use super::{DatasetError, content};

/// The unit of positions in the files.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Metres.
    M,
    /// Millimetres.
    #[default]
    Mm,
}

impl Unit {
    /// Millimetres per unit.
    #[must_use]
    pub fn to_mm(self) -> f64 {
        match self {
            Unit::M => 1e3,
            Unit::Mm => 1.0,
        }
    }
}

/// A table of features and targets from any sensor.
#[derive(Clone, Debug)]
pub struct Table {
    /// n x p features, in the file's units (volts, board codes, ...).
    pub x: DMatrix<f64>,
    /// The feature columns' names.
    pub feature_names: Vec<String>,
    /// Class labels as written, when the data has them.
    pub labels: Option<Vec<String>>,
    /// Positions in mm, when the data has them.
    pub positions_mm: Option<Vec<[f64; 2]>>,
    /// A third target (name; values: a length in mm when named z, else as written).
    pub third: Option<(String, Vec<f64>)>,
    /// Which columns were taken as what, and the unit.
    pub description: String,
    /// The first row's index in the file (after `--rows`).
    pub first_row: usize,
    /// The unit the files' positions were written in (they are held in mm).
    pub unit: Unit,
    /// The session (or visit, or subject) of each row as written, when given: rows of one
    /// group share their drift, and cross-validation leaves one group out.
    pub groups: Option<Vec<String>>,
}

/// Where the rows' groups (sessions) come from.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GroupsFrom {
    /// A CSV with one column (a header row optional), a group per row of the features.
    File(std::path::PathBuf),
    /// A named column of the features file (not then a feature).
    Column(String),
}

/// Reads a CSV of numbers only (a header row optional; the same dialects as
/// [`Table::import`]): reference frames, one per row or per session.
///
/// # Errors
/// [`DatasetError`] naming the file, line and column of a cell that is not a finite number.
pub fn read_matrix(path: &Path) -> Result<DMatrix<f64>, DatasetError> {
    let text = et_core::text::read_text_at_most(path, et_core::text::MAX_FILE_BYTES).map_err(
        |source| DatasetError::Io {
            path: path.into(),
            source,
        },
    )?;
    let none = |_: &str, _: usize| false;
    let csv = parse_table(path, &text_lines(&text), &none)?;
    let cols: Vec<usize> = (0..csv.names.len()).collect();
    csv.matrix(path, &cols)
}

/// Names a third target column may have, besides the column after y in a headerless file.
const THIRD_NAMES: [&str; 4] = ["z", "force", "pressure", "pressure_kpa"];

impl Table {
    /// Imports CSV from any sensor. A header row is optional (a first row with a cell that is not
    /// a number is one); a UTF-8 byte-order mark, CRLF line ends and blank lines are allowed.
    /// Columns named `label`, `x`, `y` and `z`, `force` or `pressure` (any case) are targets, all
    /// others features (any count). Targets may instead come from `targets`, a second CSV with the
    /// same number of rows: named as above, or without a header one column (a label) or two and
    /// more (x, y, then a third target such as z or force; further columns unused). Labels may be
    /// any text. Cells may be quoted, and separated by `,`, `;` (then `1,5` is a decimal comma) or
    /// tabs: detected, and said in [`Table::description`]. Positions (and a third target named z)
    /// are in `unit`.
    ///
    /// # Errors
    /// [`DatasetError`] naming the file, the line and the column: non-numbers, NaN or infinite
    /// values, rows of the wrong length, mismatched row counts, no features, no target (a file
    /// without a header and no targets file has none).
    pub fn import(
        features: &Path,
        targets: Option<&Path>,
        unit: Unit,
    ) -> Result<Self, DatasetError> {
        Self::import_grouped(features, targets, unit, None)
    }

    /// [`Table::import`], and each row's group from `groups`: a file with one column, or a
    /// named column of the features file (then not a feature). Groups may be any text.
    ///
    /// # Errors
    /// As [`Table::import`]; and a groups file with another row count, or a column the
    /// features file does not have, named.
    pub fn import_grouped(
        features: &Path,
        targets: Option<&Path>,
        unit: Unit,
        groups: Option<&GroupsFrom>,
    ) -> Result<Self, DatasetError> {
        let group_column = match groups {
            Some(GroupsFrom::Column(name)) => Some(name.as_str()),
            _ => None,
        };
        let read = |p: &Path| {
            et_core::text::read_text_at_most(p, et_core::text::MAX_FILE_BYTES).map_err(|source| {
                DatasetError::Io {
                    path: p.into(),
                    source,
                }
            })
        };
        let label_text = |name: &str, _: usize| {
            name.eq_ignore_ascii_case("label")
                || group_column.is_some_and(|g| g.eq_ignore_ascii_case(name))
        };
        let text = read(features)?;
        let main = parse_table(features, &text_lines(&text), &label_text)?;
        let target_text = targets.map(read).transpose()?;
        let side = match (targets, &target_text) {
            (Some(p), Some(t)) => {
                // Without a header, one column is a label and may be text.
                let label_or_only = |name: &str, columns: usize| {
                    name.eq_ignore_ascii_case("label") || (columns == 1 && name == "1")
                };
                let table = parse_table(p, &text_lines(t), &label_or_only)?;
                if table.rows.len() != main.rows.len() {
                    return Err(content(
                        p,
                        0,
                        None,
                        format!(
                            "{} rows, {} has {}",
                            table.rows.len(),
                            features.display(),
                            main.rows.len()
                        ),
                    ));
                }
                Some((p, table))
            }
            _ => None,
        };
        let is_target = |n: &str| {
            let n = n.to_ascii_lowercase();
            ["label", "x", "y"].contains(&n.as_str()) || THIRD_NAMES.contains(&n.as_str())
        };
        // Without a header every column of the features file is a feature.
        let is_group = |n: &str| group_column.is_some_and(|g| g.eq_ignore_ascii_case(n));
        let feature_cols: Vec<usize> = (0..main.names.len())
            .filter(|&c| {
                !main.header
                    || main
                        .names
                        .get(c)
                        .is_some_and(|n| !is_target(n) && !is_group(n))
            })
            .collect();
        let group_values = match groups {
            None => None,
            Some(GroupsFrom::Column(name)) => {
                let c = main
                    .names
                    .iter()
                    .position(|n| n.eq_ignore_ascii_case(name))
                    .filter(|_| main.header)
                    .ok_or_else(|| {
                        content(
                            features,
                            0,
                            None,
                            format!(
                                "--groups {name}: no such column (the header has {}); give a \
                                 column name or a file with one group per row",
                                if main.header {
                                    main.names
                                        .iter()
                                        .take(8)
                                        .cloned()
                                        .collect::<Vec<_>>()
                                        .join(", ")
                                } else {
                                    "no names: the file has no header row".into()
                                }
                            ),
                        )
                    })?;
                Some(main.text_column(features, c)?)
            }
            Some(GroupsFrom::File(p)) => {
                let text = read(p)?;
                let one = |_: &str, _: usize| true;
                let g = parse_table(p, &text_lines(&text), &one)?;
                if g.rows.len() != main.rows.len() {
                    return Err(content(
                        p,
                        0,
                        None,
                        format!(
                            "{} rows of groups, {} has {}",
                            g.rows.len(),
                            features.display(),
                            main.rows.len()
                        ),
                    ));
                }
                Some(g.text_column(p, 0)?)
            }
        };
        if feature_cols.is_empty() {
            return Err(content(features, 0, None, "no feature columns"));
        }
        let x = main.matrix(features, &feature_cols)?;
        let (tpath, ttable) = side.as_ref().map_or((features, &main), |(p, t)| (*p, t));
        let named = |name: &str| {
            ttable
                .names
                .iter()
                .position(|c| c.eq_ignore_ascii_case(name))
        };
        // A targets file without a header: one column is a label, more are x, y, (z), ...
        let (label_col, x_col, y_col, third_col) =
            match (side.is_some(), ttable.header, ttable.names.len()) {
                (true, false, 1) => (Some(0), None, None, None),
                (true, false, n) => (None, Some(0), Some(1), (n > 2).then_some(2)),
                _ => (
                    named("label"),
                    named("x"),
                    named("y"),
                    THIRD_NAMES.iter().find_map(|n| named(n)),
                ),
            };
        let labels = label_col
            .map(|c| ttable.text_column(tpath, c))
            .transpose()?;
        let positions: Option<Vec<[f64; 2]>> = match (x_col, y_col) {
            (Some(cx), Some(cy)) => Some(
                ttable
                    .column(tpath, cx)?
                    .into_iter()
                    .zip(ttable.column(tpath, cy)?)
                    .map(|(x, y)| [x, y])
                    .collect(),
            ),
            (None, None) => None,
            _ => {
                return Err(content(
                    tpath,
                    0,
                    None,
                    "give both x and y columns, or neither",
                ));
            }
        };
        let third = match third_col {
            Some(c) if positions.is_some() => Some((
                ttable
                    .names
                    .get(c)
                    .filter(|_| ttable.header)
                    .cloned()
                    .unwrap_or_else(|| "z".into()),
                ttable.column(tpath, c)?,
            )),
            _ => None,
        };
        if labels.is_none() && positions.is_none() {
            return Err(content(
                tpath,
                0,
                None,
                if ttable.header {
                    "no target: add a 'label' column or 'x' and 'y' columns"
                } else {
                    "no target: without a header row every column is a feature; name the targets \
                 (label, or x and y) in a header row, or give them in a second file"
                },
            ));
        }
        let file = |p: &Path| {
            p.file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
        };
        let header_note = |t: &Csv| {
            let header = if t.header {
                "header row"
            } else {
                "no header row"
            };
            match t.delimiter.said() {
                "" => header.to_string(),
                said => format!("{header}, {said}"),
            }
        };
        let mut description = format!(
            "{}: {} rows, {} feature columns ({}), {}",
            file(features),
            main.rows.len(),
            feature_cols.len(),
            match (feature_cols.first(), feature_cols.last()) {
                (Some(&a), Some(&b)) if !main.header => format!("columns {} to {}", a + 1, b + 1),
                _ =>
                    feature_cols
                        .iter()
                        .filter_map(|&c| main.names.get(c).cloned())
                        .take(3)
                        .collect::<Vec<_>>()
                        .join(", ")
                        + if feature_cols.len() > 3 { ", ..." } else { "" },
            },
            header_note(&main)
        );
        let third_name = third.as_ref().map(|(n, _)| n.as_str());
        let taken: Vec<String> = [
            ("label", label_col),
            ("x", x_col),
            ("y", y_col),
            (
                third_name.unwrap_or("z"),
                third_col.filter(|_| third.is_some()),
            ),
        ]
        .iter()
        .filter_map(|&(what, c)| c.map(|c| format!("{what} from column {}", c + 1)))
        .collect();
        let used = taken.len();
        description += &format!(
            "; targets in {} ({}): {}",
            file(tpath),
            header_note(ttable),
            taken.join(", ")
        );
        if side.is_some() && ttable.names.len() > used {
            description += &format!(" ({} more columns not used)", ttable.names.len() - used);
        }
        let mm = unit.to_mm();
        let third = third.map(|(name, v)| {
            let length = name.eq_ignore_ascii_case("z");
            let v = if length {
                v.iter().map(|z| z * mm).collect()
            } else {
                v
            };
            (name, v)
        });
        description += &format!(
            "; positions in {}",
            match unit {
                Unit::M => "m (read as mm x 1000)",
                Unit::Mm => "mm",
            }
        );
        // Positions in metres read as mm span less than a millimetre: say so.
        if let (Unit::Mm, Some(p)) = (unit, &positions) {
            let span = |i: usize| {
                let (lo, hi) = p
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), q| {
                        let v = q.get(i).copied().unwrap_or(0.0);
                        (l.min(v), h.max(v))
                    });
                hi - lo
            };
            let widest = span(0).max(span(1));
            if widest > 0.0 && widest < 1.0 {
                description.push_str(&format!(
                    "; note: the positions span only {widest:.3} mm: if they are in metres, \
                 give --unit m"
                ));
            }
        }
        Ok(Self {
            x,
            feature_names: feature_cols
                .iter()
                .filter_map(|&c| main.names.get(c).cloned())
                .collect(),
            labels,
            positions_mm: positions.map(|p| p.iter().map(|q| [q[0] * mm, q[1] * mm]).collect()),
            third,
            description: match &group_values {
                Some(g) => {
                    let mut distinct = g.clone();
                    distinct.sort();
                    distinct.dedup();
                    format!("{description}; {} groups", distinct.len())
                }
                None => description,
            },
            first_row: 0,
            unit,
            groups: group_values,
        })
    }
}
