//! Data from other sensors: a CSV of features with its targets, read into a [`Table`] (see
//! [`Table::import`]).

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use et_core::text::lines as text_lines;

use super::table::{Csv, parse_table};
use super::{DatasetError, DatasetFault, content};

mod groups;
mod roles;

use groups::{group_values, groups_said, sessions_as_groups};

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
    /// Metres per unit.
    #[must_use]
    pub fn metres(self) -> f64 {
        match self {
            Unit::M => 1.0,
            Unit::Mm => 1e-3,
        }
    }
}

/// Whether a third target named `name` is a length (z: held in m like x and y), rather than
/// a value kept as written (a force).
#[must_use]
pub fn is_length(name: &str) -> bool {
    position_name(name).is_some_and(|(axis, _)| axis == 'z')
}

/// A position column's axis (`x`, `y` or `z`) and the unit its name gives: bare (`x`, the
/// unit `--unit` says), or with the unit it is written in (`x_mm`, `y_m`, any case), as et's
/// own files and most loggers name them (`x_mm` was taken as a feature: the target itself
/// among the features, a cross-validated error of 0.00 mm), or as spreadsheets do (`x (mm)`,
/// `y [m]`). `Err` holds a length unit et does not read (`x_cm`); `None` for any other name
/// (`x_offset` is a feature).
fn position_name(name: &str) -> Option<(char, Result<Option<Unit>, String>)> {
    let n = name.trim().to_ascii_lowercase();
    let bracketed = (n.strip_suffix(')').and_then(|s| s.split_once('(')))
        .or_else(|| n.strip_suffix(']').and_then(|s| s.split_once('[')));
    let (axis, unit) = match bracketed {
        Some((axis, unit)) => (axis.trim_end(), unit.trim()),
        None => n.split_once('_').unwrap_or((n.as_str(), "")),
    };
    let axis = match axis {
        "x" => 'x',
        "y" => 'y',
        "z" => 'z',
        _ => return None,
    };
    let unit = match unit {
        "" => Ok(None),
        "mm" => Ok(Some(Unit::Mm)),
        "m" => Ok(Some(Unit::M)),
        "cm" | "um" | "nm" | "km" | "in" | "inch" | "ft" => Err(unit.to_string()),
        _ => return None,
    };
    Some((axis, unit))
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
    /// Positions in m, when the data has them.
    pub positions: Option<Vec<[f64; 2]>>,
    /// A third target (name; values: a length in m when named z, else as written).
    pub third: Option<(String, Vec<f64>)>,
    /// Which columns were taken as what, and the unit.
    pub description: String,
    /// The first row's index in the file (after `--rows`).
    pub first_row: usize,
    /// The unit the files' positions were written in (they are held in m).
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

/// Reference features (a CSV of numbers only, a header row optional; the same dialects as
/// [`Table::import`]: one frame per row or per session), its columns paired with `features`
/// (the features' names, in order): by name when both have a header (a reference whose columns are in
/// another order is read in the features' order; one without a feature's column is
/// refused, naming it), by position when either has none.
///
/// # Errors
/// [`DatasetError`] naming the file, line and column of a cell that is not a finite number;
/// [`DatasetFault::NoReferenceColumn`] for a feature the reference's
/// header does not name.
pub fn read_reference(path: &Path, features: &[String]) -> Result<DMatrix<f64>, DatasetError> {
    let text = read(path)?;
    // The rows' numbers, times and sessions may be text, as in the features' file.
    let text_cells = |name: &str, _: usize| roles::role(name).is_some();
    let csv = parse_table(path, &text_lines(&text), &text_cells)?;
    // Without a header a table's features are named by their column numbers.
    let named = features
        .iter()
        .enumerate()
        .any(|(i, n)| *n != (i + 1).to_string());
    let cols: Vec<usize> = if csv.header && named {
        features
            .iter()
            .map(|f| {
                csv.names
                    .iter()
                    .position(|n| n.eq_ignore_ascii_case(f))
                    .ok_or_else(|| {
                        let fault = DatasetFault::NoReferenceColumn {
                            feature: f.clone(),
                            names: csv.names.iter().take(8).cloned().collect(),
                        };
                        content(path, 0, None, fault)
                    })
            })
            .collect::<Result<_, _>>()?
    } else {
        (0..csv.names.len()).collect()
    };
    csv.matrix(path, &cols)
}

/// Names a third target column may have besides z (any [`position_name`] of it), and the
/// column after y in a headerless file.
const THIRD_NAMES: [&str; 4] = ["force", "pressure", "pressure_kpa", "pressure_pa"];

/// Whether a column named `name` holds the rows' numbers, times or sessions (`id`,
/// `time_ms`, `session`), which a table's import leaves out of the features.
#[must_use]
pub fn not_a_feature(name: &str) -> bool {
    roles::role(name).is_some()
}

/// A target column's name (label, x, y or a third target's, bare or with a unit), in any case.
#[must_use]
pub fn is_target_name(name: &str) -> bool {
    let n = name.to_ascii_lowercase();
    n == "label" || position_name(&n).is_some() || THIRD_NAMES.contains(&n.as_str())
}

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
        let text = read(features)?;
        let from_dataset = text.starts_with("# et-dataset");
        // A target column is no session (every position would be a group of its own).
        if let Some(GroupsFrom::Column(name)) = groups
            && is_target_name(name)
        {
            let fault = DatasetFault::GroupIsTarget(name.clone());
            return Err(content(features, 0, Some(name.clone()), fault));
        }
        let given = match groups {
            Some(GroupsFrom::Column(name)) => Some(name.as_str()),
            _ => None,
        };
        // Labels, groups and the columns of rows' numbers, times and sessions may be text.
        let text_cells = |name: &str, _: usize| {
            name.eq_ignore_ascii_case("label")
                || given.is_some_and(|g| g.eq_ignore_ascii_case(name))
                || roles::role(name).is_some()
        };
        let main = parse_table(features, &text_lines(&text), &text_cells)?;
        drop(text);
        let side = targets
            .map(|p| targets_file(p, features, &main))
            .transpose()?;
        let sessions = match groups {
            Some(_) => None,
            None => sessions_as_groups(features, &main, side.as_ref())?,
        };
        let groups = groups.or(sessions.as_ref());
        let group_column = match groups {
            Some(GroupsFrom::Column(name)) => Some(name.as_str()),
            _ => None,
        };
        let is_group = |n: &str| group_column.is_some_and(|g| g.eq_ignore_ascii_case(n));
        if let Some((p, t)) = &side {
            roles::check_paired(features, &main, p, t)?;
        }
        // Without a header every column of the features file is a feature; with one, neither
        // the targets, the groups nor the rows' numbers, times and sessions are.
        let feature_cols: Vec<usize> = (0..main.names.len())
            .filter(|&c| {
                !main.header
                    || main.names.get(c).is_some_and(|n| {
                        !is_target_name(n) && !is_group(n) && roles::role(n).is_none()
                    })
            })
            .collect();
        let group_values = groups
            .map(|g| group_values(g, features, &main, side.as_ref()))
            .transpose()?;
        if feature_cols.is_empty() {
            return Err(content(features, 0, None, DatasetFault::NoFeatures));
        }
        let x = main.matrix(features, &feature_cols)?;
        let (tpath, ttable) = side.as_ref().map_or((features, &main), |(p, t)| (*p, t));
        let found = Targets::read(tpath, ttable, side.is_some())?;
        let mut description = describe(features, &main, &feature_cols, tpath, ttable, &found);
        description += &roles::left_out(&main, group_column);
        if side.is_some() && ttable.names.len() > found.taken() {
            description += &format!(
                " ({} more columns not used)",
                ttable.names.len() - found.taken()
            );
        }
        // Columns that name their unit (x_mm) are read in it; --unit beside them is the
        // caller's to compare (the table says the unit it read).
        let unit = found.unit.unwrap_or(unit);
        let m = unit.metres();
        let third = found.third.map(|(name, v)| {
            let length = is_length(&name);
            let v = if length {
                v.iter().map(|z| z * m).collect()
            } else {
                v
            };
            (name, v)
        });
        description += &positions_note(unit, found.positions.as_deref());
        let positions = found.positions;
        let labels = found.labels;
        Ok(Self {
            x,
            feature_names: feature_cols
                .iter()
                .filter_map(|&c| main.names.get(c).cloned())
                .collect(),
            labels,
            positions: positions.map(|p| p.iter().map(|q| [q[0] * m, q[1] * m]).collect()),
            third,
            description: description
                + &groups_said(group_values.as_deref(), sessions.as_ref(), from_dataset),
            first_row: 0,
            unit,
            groups: group_values,
        })
    }
}

/// A file's text, at most et's file limit (a read error names the file).
pub(super) fn read(p: &Path) -> Result<String, DatasetError> {
    et_core::text::read_text_at_most(p, et_core::text::max_file_bytes()).map_err(|source| {
        DatasetError::Io {
            path: p.into(),
            source,
        }
    })
}

/// The targets file `p`, with the features file's row count. Without a header, its one column
/// is a label and may be text; under one, every column but the positions and a third target
/// may be (a label, the groups, an operator's name: the targets' unused columns were refused
/// as "not a number").
fn targets_file<'p>(
    p: &'p Path,
    features: &Path,
    main: &Csv,
) -> Result<(&'p Path, Csv), DatasetError> {
    let label_or_only = |name: &str, columns: usize| {
        let headed = name.parse::<usize>().is_err();
        name.eq_ignore_ascii_case("label")
            || (columns == 1 && name == "1")
            || (headed && (!is_target_name(name) || roles::role(name).is_some()))
    };
    Ok((p, beside(p, features, main, &label_or_only, "rows")?))
}

/// A file beside the features (`main`, from `features`) with a row for each of theirs, read
/// with `text` saying which columns may hold text: a targets or a groups file. A first row
/// that is a header after all is taken as one ([`Csv::first_row_as_header`]).
///
/// # Errors
/// As [`parse_table`]; [`DatasetFault::RowCount`] naming `what` when its rows are not the
/// features'.
fn beside(
    p: &Path,
    features: &Path,
    main: &Csv,
    text: &dyn Fn(&str, usize) -> bool,
    what: &'static str,
) -> Result<Csv, DatasetError> {
    let mut table = parse_table(p, &text_lines(&read(p)?), text)?;
    table.first_row_as_header(main.rows.len(), main.header);
    if table.rows.len() != main.rows.len() {
        let fault = DatasetFault::RowCount {
            rows: table.rows.len(),
            what,
            features: features.into(),
            features_rows: main.rows.len(),
            // (Beside headerless features, which file has the row too many is a guess.)
            header_like: table.header_like(main.rows.len()).map(String::from),
        };
        return Err(content(p, 0, None, fault));
    }
    Ok(table)
}

/// The targets a table holds and the columns they came from.
struct Targets {
    /// Class labels, as written.
    labels: Option<Vec<String>>,
    /// (x, y), in the file's unit.
    positions: Option<Vec<[f64; 2]>>,
    /// The third target's name and values (a length in the file's unit when named z).
    third: Option<(String, Vec<f64>)>,
    /// The columns of the label, x, y and the third target.
    columns: [Option<usize>; 4],
    /// The unit the position columns' names give (`x_mm`), when they give one.
    unit: Option<Unit>,
}

impl Targets {
    /// The targets of `table` (`path`): by name in a header; without one, in a targets file
    /// (`side`), its one column is a label, more are x, y, (z), ...
    fn read(path: &Path, table: &Csv, side: bool) -> Result<Self, DatasetError> {
        let named = |name: &str| {
            table
                .names
                .iter()
                .position(|c| c.eq_ignore_ascii_case(name))
        };
        let axis = |a: char| {
            (table.names.iter())
                .position(|c| position_name(c).is_some_and(|(b, _)| a == b))
                .filter(|_| table.header)
        };
        let position = axis('x').or(axis('y')).is_some();
        let (label_col, x_col, y_col, third_col) = match (side, table.header, table.names.len()) {
            // A targets file's one column is a label, whatever its header calls it.
            (true, false, 1) => (Some(0), None, None, None),
            (true, true, 1) if !position => (Some(0), None, None, None),
            (true, false, n) => (None, Some(0), Some(1), (n > 2).then_some(2)),
            _ => (
                named("label"),
                axis('x'),
                axis('y'),
                axis('z').or_else(|| THIRD_NAMES.iter().find_map(|n| named(n))),
            ),
        };
        let unit = position_unit(path, table, [x_col, y_col, third_col])?;
        let labels = label_col.map(|c| table.text_column(path, c)).transpose()?;
        let positions: Option<Vec<[f64; 2]>> = match (x_col, y_col) {
            (Some(cx), Some(cy)) => Some(
                table
                    .column(path, cx)?
                    .into_iter()
                    .zip(table.column(path, cy)?)
                    .map(|(x, y)| [x, y])
                    .collect(),
            ),
            (None, None) => None,
            _ => {
                return Err(content(path, 0, None, DatasetFault::HalfPosition));
            }
        };
        let third = match third_col {
            Some(c) if positions.is_some() => Some((
                table
                    .names
                    .get(c)
                    .filter(|n| table.header && !is_length(n))
                    .cloned()
                    .unwrap_or_else(|| "z".into()),
                table.column(path, c)?,
            )),
            _ => None,
        };
        if labels.is_none() && positions.is_none() {
            let header = table.header;
            return Err(content(path, 0, None, DatasetFault::NoTarget { header }));
        }
        let third_col = third_col.filter(|_| third.is_some());
        Ok(Self {
            labels,
            positions,
            third,
            columns: [label_col, x_col, y_col, third_col],
            unit,
        })
    }

    /// How many target columns were taken.
    fn taken(&self) -> usize {
        self.columns.iter().flatten().count()
    }
}

/// The unit the position columns' names give (`x_mm`, `y_mm`), if any: refused when they give
/// two, or one et does not read (`x_cm`).
fn position_unit(
    path: &Path,
    table: &Csv,
    columns: [Option<usize>; 3],
) -> Result<Option<Unit>, DatasetError> {
    let mut found: Option<(&str, Unit)> = None;
    for name in columns.iter().flatten().filter_map(|&c| table.names.get(c)) {
        let Some((axis, unit)) = position_name(name).filter(|_| table.header) else {
            continue;
        };
        let fault = match (unit, found) {
            (Err(unit), _) => DatasetFault::PositionUnit {
                column: name.clone(),
                unit,
                axis,
            },
            (Ok(Some(u)), Some((first, f))) if u != f => DatasetFault::PositionUnits {
                first: first.into(),
                second: name.clone(),
            },
            (Ok(Some(u)), None) => {
                found = Some((name, u));
                continue;
            }
            (Ok(_), _) => continue,
        };
        return Err(content(path, 0, None, fault));
    }
    Ok(found.map(|(_, u)| u))
}

/// What was read from where, as `et train` prints it: the features' file, rows and columns,
/// and the targets' file and columns.
fn describe(
    features: &Path,
    main: &Csv,
    feature_cols: &[usize],
    tpath: &Path,
    ttable: &Csv,
    found: &Targets,
) -> String {
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
        header_note(main)
    );
    let third_name = found.third.as_ref().map_or("z", |(n, _)| n.as_str());
    let [label_col, x_col, y_col, third_col] = found.columns;
    let taken: Vec<String> = [
        ("label", label_col),
        ("x", x_col),
        ("y", y_col),
        (third_name, third_col),
    ]
    .iter()
    .filter_map(|&(what, c)| c.map(|c| format!("{what} from column {}", c + 1)))
    .collect();
    description += &format!(
        "; targets in {} ({}): {}",
        file(tpath),
        header_note(ttable),
        taken.join(", ")
    );
    description
}

/// The unit the positions were read in (nothing without positions; a span no sheet has is
/// said by [`Table::positions_scale_note`] when the table is trained on).
fn positions_note(unit: Unit, positions: Option<&[[f64; 2]]>) -> String {
    // Class labels alone have no unit to say.
    match (positions, unit) {
        (None, _) => String::new(),
        (Some(_), Unit::M) => "; positions in m".into(),
        (Some(_), Unit::Mm) => "; positions in mm".into(),
    }
}
