//! The table a model learns from: features and targets of any sensor, its units, row ranges,
//! class labels and the grid that turns positions into classes.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

/// Rows `start..end` (0-based, half open) of a table; `end` None means to the last row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct RowRange {
    /// First row.
    pub start: usize,
    /// One past the last row, or None for all that follow.
    pub end: Option<usize>,
}

impl std::str::FromStr for RowRange {
    type Err = String;

    /// `A..B`, `A..` or `..B`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (a, b) = s
            .split_once("..")
            .ok_or_else(|| format!("'{s}': write A..B (0-based, B excluded), A.. or ..B"))?;
        let num = |v: &str, default: Option<usize>| -> Result<Option<usize>, String> {
            match v.trim() {
                "" => Ok(default),
                v if v.starts_with('-') => Err(format!(
                    "'{s}': '{v}': rows count from 0 at the first row (not from the end): \
                     give A..B of those numbers"
                )),
                v => v
                    .parse::<usize>()
                    .map(Some)
                    .map_err(|_| format!("'{s}': '{v}' is not a row number")),
            }
        };
        let start = num(a, Some(0))?.unwrap_or(0);
        let end = num(b, None)?;
        if let Some(end) = end.filter(|e| *e <= start) {
            // (B is excluded: A..A holds nothing, and B below A is A and B swapped?)
            let why = if end == start {
                format!(
                    "{start}..{end} holds nothing (B is excluded): {start}..{} is {start} alone",
                    start + 1
                )
            } else {
                format!("B ({end}) is below A ({start}): {end}..{start}?")
            };
            return Err(format!("'{s}': the range is empty: {why}"));
        }
        Ok(Self { start, end })
    }
}

impl std::fmt::Display for RowRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.end {
            Some(e) => write!(f, "{}..{e}", self.start),
            None => write!(f, "{}..", self.start),
        }
    }
}

/// Class labels: each row's class index into `names`, the user's own names.
#[derive(Clone, Debug, PartialEq)]
pub struct Labels {
    /// Class of each row, 0..names.len().
    pub index: Vec<u16>,
    /// Class names as written in the file (numbers in numeric order, else sorted).
    pub names: Vec<String>,
}

impl Labels {
    /// Maps labels as written to classes 0..C-1, numbers in numeric order, else sorted.
    ///
    /// # Errors
    /// [`TabularError::Usage`] for more than 65 535 classes.
    pub fn from_text(labels: &[String]) -> Result<Self, TabularError> {
        let mut names: Vec<String> = labels.to_vec();
        names.sort();
        names.dedup();
        if names.iter().all(|n| n.parse::<f64>().is_ok()) {
            names.sort_by(|a, b| {
                a.parse::<f64>()
                    .unwrap_or(0.0)
                    .total_cmp(&b.parse::<f64>().unwrap_or(0.0))
            });
        }
        if names.len() > usize::from(u16::MAX) {
            return Err(usage(Misuse::TooManyClasses(names.len())));
        }
        let lookup: BTreeMap<&str, u16> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.as_str(), i as u16))
            .collect();
        let index = labels
            .iter()
            .map(|l| lookup.get(l.as_str()).copied().unwrap_or(0))
            .collect();
        Ok(Self { index, names })
    }
}

impl Table {
    /// Rows.
    #[must_use]
    pub fn rows(&self) -> usize {
        self.x.nrows()
    }

    /// The rows of `range` only.
    ///
    /// # Errors
    /// [`TabularError::Usage`] when the range reaches past the table or holds no row.
    pub fn select(&self, range: RowRange) -> Result<Self, TabularError> {
        let n = self.rows();
        let end = range.end.unwrap_or(n);
        if end > n || range.start >= end {
            return Err(usage(Misuse::Rows { range, rows: n }));
        }
        let rows = range.start..end;
        Ok(Self {
            x: self.x.rows(rows.start, rows.len()).into_owned(),
            feature_names: self.feature_names.clone(),
            labels: self
                .labels
                .as_ref()
                .and_then(|l| l.get(rows.clone()).map(<[String]>::to_vec)),
            positions: self
                .positions
                .as_ref()
                .and_then(|p| p.get(rows.clone()).map(<[[f64; 2]]>::to_vec)),
            third: self
                .third
                .as_ref()
                .and_then(|(name, v)| v.get(rows.clone()).map(|v| (name.clone(), v.to_vec()))),
            description: self.description.clone(),
            first_row: self.first_row + range.start,
            unit: self.unit,
            groups: self
                .groups
                .as_ref()
                .and_then(|g| g.get(rows.clone()).map(<[String]>::to_vec)),
        })
    }

    /// Each row's group as an index into the distinct groups (in order of first appearance),
    /// and the groups, when the table has groups.
    #[must_use]
    pub fn group_index(&self) -> Option<(Vec<usize>, Vec<String>)> {
        let groups = self.groups.as_ref()?;
        let mut names: Vec<String> = Vec::new();
        let mut of: BTreeMap<&str, usize> = BTreeMap::new();
        let index = groups
            .iter()
            .map(|g| {
                *of.entry(g.as_str()).or_insert_with(|| {
                    names.push(g.clone());
                    names.len() - 1
                })
            })
            .collect();
        Some((index, names))
    }

    /// The features referenced to `reference`: one frame per row, one per group (in order of
    /// first appearance), or one for all rows; `(F - B) / B` or `F - B`.
    ///
    /// # Errors
    /// [`TabularError::Usage`] when `reference` has another column count or a row count that
    /// is none of those, or a ratio's reference value is 0 (naming the row and column).
    pub fn referenced(
        &self,
        reference: &DMatrix<f64>,
        how: Referencing,
        what: &str,
    ) -> Result<Self, TabularError> {
        let (n, p) = (self.rows(), self.x.ncols());
        if reference.ncols() != p {
            return Err(usage(Misuse::ReferenceColumns {
                reference: what.to_string(),
                columns: reference.ncols(),
                features: p,
            }));
        }
        let groups = self.group_index();
        let row_of: Vec<usize> = match reference.nrows() {
            r if r == n => (0..n).collect(),
            1 => vec![0; n],
            r if groups.as_ref().is_some_and(|(_, names)| names.len() == r) => {
                groups.map(|(index, _)| index).unwrap_or_default()
            }
            r => {
                return Err(usage(Misuse::ReferenceRows {
                    reference: what.to_string(),
                    rows: r,
                    features: n,
                    groups: groups.map(|(_, g)| g.len()),
                }));
            }
        };
        let mut x = self.x.clone();
        for (r, &b) in row_of.iter().enumerate() {
            for j in 0..p {
                let base = reference.get((b, j)).copied().unwrap_or(f64::NAN);
                let Some(v) = x.get_mut((r, j)) else {
                    continue;
                };
                *v = match how {
                    Referencing::Difference => *v - base,
                    Referencing::Ratio if base != 0.0 && base.is_finite() => (*v - base) / base,
                    Referencing::Ratio => {
                        return Err(usage(Misuse::ZeroReference {
                            reference: what.to_string(),
                            row: b + 1,
                            column: j + 1,
                            value: base,
                        }));
                    }
                };
            }
        }
        Ok(Self {
            x,
            description: format!(
                "{}; features {} {what}",
                self.description,
                match how {
                    Referencing::Ratio => "relative to",
                    Referencing::Difference => "minus",
                }
            ),
            ..self.clone()
        })
    }

    /// Each group's features standardised by that group's own mean and standard deviation
    /// (all rows as one group when the table has none): a session's channel offsets and gains
    /// cancel.
    ///
    /// # Errors
    /// [`TabularError::Usage`] when a group has a single row (no spread to divide by).
    pub fn standardised_per_group(&self) -> Result<Self, TabularError> {
        let n = self.rows();
        let (index, names) = self
            .group_index()
            .unwrap_or_else(|| (vec![0; n], vec!["all rows".to_string()]));
        let mut x = self.x.clone();
        for (g, name) in names.iter().enumerate() {
            let rows: Vec<usize> = (0..n).filter(|&r| index.get(r) == Some(&g)).collect();
            if rows.len() < 2 {
                return Err(usage(Misuse::SmallGroup {
                    group: name.clone(),
                    rows: rows.len(),
                }));
            }
            let (mean, scale) = super::super::fit::standardisation(&rows_of(&self.x, &rows));
            for &r in &rows {
                for (j, (m, s)) in mean.iter().zip(&scale).enumerate() {
                    if let Some(v) = x.get_mut((r, j)) {
                        *v = (*v - m) / s;
                    }
                }
            }
        }
        Ok(Self { x, ..self.clone() })
    }

    /// A note when the positions span more than any touch sheet (10 m) or less than a finger
    /// (1 mm): most likely positions in another unit than the one they were read in (mm
    /// given as m trained and scored errors of metres without a word; m read as mm, errors
    /// of micrometres).
    #[must_use]
    pub fn positions_scale_note(&self) -> Option<String> {
        let p = self.positions.as_ref()?;
        let extent = |along: fn(&[f64; 2]) -> f64| {
            let (lo, hi) = p
                .iter()
                .map(along)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                });
            hi - lo
        };
        let span = extent(|q| q[0]).max(extent(|q| q[1]));
        let (wide, narrow) = (span > 10.0, span > 0.0 && span < 1e-3);
        let ask = match (self.unit, wide, narrow) {
            (Unit::M, true, _) => {
                "are they in mm? (divide them by 1000; --unit mm on the command line)"
            }
            (Unit::Mm, _, true) => "are they in m? (give --unit m on the command line)",
            (_, true, _) | (_, _, true) => "check their unit",
            _ => return None,
        };
        Some(format!(
            "the positions span {}, {}: {ask}",
            match self.unit {
                Unit::M => format!("{span:.4} m"),
                Unit::Mm => format!("{:.4} mm", span * 1e3),
            },
            if wide {
                "more than any touch sheet (10 m)"
            } else {
                "less than a finger (1 mm)"
            }
        ))
    }

    /// Targets as (x m, y m, third or 0), when the table has positions.
    #[must_use]
    pub fn targets(&self) -> Option<Vec<Target3>> {
        let p = self.positions.as_ref()?;
        Some(
            p.iter()
                .enumerate()
                .map(|(r, q)| {
                    let third = self
                        .third
                        .as_ref()
                        .and_then(|(_, v)| v.get(r).copied())
                        .unwrap_or(0.0);
                    [q[0], q[1], third]
                })
                .collect(),
        )
    }
}

/// A class grid made from positions (`--grid RxC`): the targets' bounding box cut into
/// `rows` x `cols` cells.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// Cells along y.
    pub rows: usize,
    /// Cells along x.
    pub cols: usize,
    /// Bounding box [x0, y0, x1, y1], m (version 1 files: `bounds_mm`, converted on
    /// reading).
    #[serde(rename = "bounds_m")]
    pub bounds: [f64; 4],
}

impl Grid {
    /// The grid over the bounding box of `positions`.
    #[must_use]
    pub fn over(positions: &[[f64; 2]], rows: usize, cols: usize) -> Self {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in positions {
            b = [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ];
        }
        Self {
            rows: rows.max(1),
            cols: cols.max(1),
            bounds: b,
        }
    }

    /// The cell (row-major) of a position, clamped into the grid.
    #[must_use]
    pub fn cell(&self, p: [f64; 2]) -> usize {
        let [x0, y0, x1, y1] = self.bounds;
        let at = |v: f64, lo: f64, hi: f64, n: usize| {
            let f = if hi > lo { (v - lo) / (hi - lo) } else { 0.0 };
            // A position on a cell's edge belongs to the cell above it, whatever rounding
            // the unit's conversion left (0.01 / 0.04 * 4 is 0.999...).
            ((f * n as f64 + 1e-9).floor().max(0.0) as usize).min(n - 1)
        };
        at(p[1], y0, y1, self.rows) * self.cols + at(p[0], x0, x1, self.cols)
    }

    /// The centre of a cell, m.
    #[must_use]
    pub fn centre(&self, cell: usize) -> [f64; 2] {
        let [x0, y0, x1, y1] = self.bounds;
        let (r, c) = (cell / self.cols, cell % self.cols);
        [
            x0 + (x1 - x0) * (c as f64 + 0.5) / self.cols as f64,
            y0 + (y1 - y0) * (r as f64 + 0.5) / self.rows as f64,
        ]
    }

    /// A cell's name: `r<row>c<col>`, 1-based from the lowest x and y.
    #[must_use]
    pub fn name(&self, cell: usize) -> String {
        format!("r{}c{}", cell / self.cols + 1, cell % self.cols + 1)
    }
}

/// The features of `table` that hold one value in every row, said (at most five named, then
/// how many more), or None: they carry nothing to learn from, and they make a class's
/// covariance singular, which an unusable QDA reported as "(regularise it)" alone.
pub(super) fn constant_said(table: &Table) -> Option<String> {
    let x = &table.x;
    let constant: Vec<(usize, f64)> = (0..x.ncols())
        .filter_map(|j| {
            let first = *x.column(j).iter().next()?;
            x.column(j)
                .iter()
                .all(|v| *v == first)
                .then_some((j, first))
        })
        .collect();
    let named: Vec<String> = constant
        .iter()
        .take(5)
        .map(|&(j, v)| {
            let name = table.feature_names.get(j).map_or("?", String::as_str);
            format!("{name} ({v})")
        })
        .collect();
    let more = constant.len().saturating_sub(named.len());
    let more = if more > 0 {
        format!(" and {more} more")
    } else {
        String::new()
    };
    match constant.len() {
        0 => None,
        1 => {
            let (j, v) = constant.first().copied().unwrap_or((0, 0.0));
            let name = table.feature_names.get(j).map_or("?", String::as_str);
            Some(format!(
                "feature {name} is {v} in every row: it carries nothing to learn from (a dead \
                 channel, or a sensor not connected?); drop it"
            ))
        }
        n => Some(format!(
            "{n} features hold one value in every row: {}{more}; they carry nothing to learn \
             from (dead channels, or sensors not connected?); drop them",
            named.join(", ")
        )),
    }
}
