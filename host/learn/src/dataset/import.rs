//! Data from other sensors: a CSV of features with its targets (see [`import_csv`]).

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;

use nalgebra::DMatrix;

use super::table::{Table, parse_table, text_lines};
use super::{DatasetError, content};

/// Data imported from other sensors.
#[derive(Clone, Debug)]
pub struct Imported {
    /// n x p features.
    pub x: DMatrix<f64>,
    /// Feature column names (column numbers, 1-based, without a header row).
    pub feature_names: Vec<String>,
    /// Class labels as written (any text: `3`, `left-palm`), if a label column was given.
    pub labels: Option<Vec<String>>,
    /// Positions, if `x` and `y` columns were given (the files' units).
    pub positions: Option<Vec<[f64; 2]>>,
    /// A third target beside x and y (z, force, pressure: the column after y in a headerless
    /// targets file, or a column named `z`, `force` or `pressure`), with its name.
    pub third: Option<(String, Vec<f64>)>,
    /// Which columns were taken as what, in words (for the user to check).
    pub description: String,
}

/// Names a third target column may have, besides the column after y in a headerless file.
const THIRD_NAMES: [&str; 4] = ["z", "force", "pressure", "pressure_kpa"];

/// Imports CSV from any sensor. A header row is optional (a first row with a cell that is not
/// a number is one); a UTF-8 byte-order mark, CRLF line ends and blank lines are allowed.
/// Columns named `label`, `x`, `y` and `z`, `force` or `pressure` (any case) are targets, all
/// others features (any count). Targets may instead come from `targets`, a second CSV with the
/// same number of rows: named as above, or without a header one column (a label) or two and
/// more (x, y, then a third target such as z or force; further columns unused). Labels may be
/// any text.
///
/// # Errors
/// [`DatasetError`] naming the file, the line and the column: non-numbers, NaN or infinite
/// values, rows of the wrong length, mismatched row counts, no features, no target (a file
/// without a header and no targets file has none).
pub fn import_csv(features: &Path, targets: Option<&Path>) -> Result<Imported, DatasetError> {
    let read = |p: &Path| {
        std::fs::read_to_string(p).map_err(|source| DatasetError::Io {
            path: p.into(),
            source,
        })
    };
    let label_text = |name: &str, _: usize| name.eq_ignore_ascii_case("label");
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
    let feature_cols: Vec<usize> = (0..main.names.len())
        .filter(|&c| !main.header || main.names.get(c).is_some_and(|n| !is_target(n)))
        .collect();
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
    let positions = match (x_col, y_col) {
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
    let header_note = |t: &Table| {
        if t.header {
            "header row"
        } else {
            "no header row"
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
    Ok(Imported {
        description,
        x,
        feature_names: feature_cols
            .iter()
            .filter_map(|&c| main.names.get(c).cloned())
            .collect(),
        labels,
        positions,
        third,
    })
}
