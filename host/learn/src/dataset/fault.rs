//! What can be wrong inside a dataset or a table of features and targets: the faults a
//! [`super::DatasetError::Content`] names, with the file, line and column beside them.

use std::path::PathBuf;

/// What is wrong in a dataset or table file (where: the error's file, line and column).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DatasetFault {
    /// The rows could not be read as CSV.
    #[error(transparent)]
    Records(#[from] et_core::text::RecordFault),
    /// No rows at all.
    #[error("no rows")]
    NoRows,
    /// A header and no rows under it.
    #[error("no data rows")]
    NoDataRows,
    /// A header cell left empty: pandas' row index (or R's row names) when it is the first,
    /// a delimiter ending the line when it is the last.
    #[error(
        "column {column} of the header has no name{}",
        if *column == 1 {
            " (pandas' row index or R's row names? write the file with to_csv(..., \
             index=False) or write.csv(..., row.names = FALSE))"
        } else if *column == *columns {
            " (a delimiter at the end of the line?)"
        } else {
            ""
        }
    )]
    EmptyName {
        /// The column, from 1.
        column: usize,
        /// The header's columns.
        columns: usize,
    },
    /// Two columns of one name (letter case aside).
    #[error("columns {first} and {second} are both named '{name}': give each column its own name")]
    SameName {
        /// The first column, from 1.
        first: usize,
        /// The second, from 1.
        second: usize,
        /// The name.
        name: String,
    },
    /// A row of another length than the header (or the first row).
    #[error(
        "{found} values, {} has {columns} columns{}",
        if *header { "the header" } else { "the first row" },
        if *last { " (the file's last row: a copy cut short?)" } else { "" }
    )]
    RowLength {
        /// The row's values.
        found: usize,
        /// The columns.
        columns: usize,
        /// Whether the file has a header row.
        header: bool,
        /// Whether it is the file's last row, short of values (a file cut short).
        last: bool,
    },
    /// A label cell left empty.
    #[error("empty label")]
    EmptyLabel,
    /// A number that is not finite (`inf`, `nan`).
    #[error("{0} is not a finite number")]
    NotFinite(f64),
    /// A cell that is not a number (a word: said how a column of text is read).
    #[error("'{cell}' is not a number{hint}", cell = .0, hint = text_hint(.0))]
    NotNumber(String),
    /// A number needed where a label's text is.
    #[error("missing or not a finite number")]
    Missing,
    /// A column asked for as text that was read as numbers only.
    #[error("not kept as text")]
    NotText,
    /// A class or visit that is not 0 to 65 535.
    #[error("{0} is not a whole number from 0 to 65535")]
    NotWhole(f64),
    /// A header line's value that is not a finite number.
    #[error("{field}: '{cell}' is not a finite number")]
    HeaderNumber {
        /// The header line's key.
        field: &'static str,
        /// What is written.
        cell: String,
    },
    /// A header line's point that is not two numbers.
    #[error("{0}: each point is 'x y'")]
    NotPoint(&'static str),
    /// The configuration line is not the scan settings' JSON.
    #[error("config: {}", crate::model_file::json_said(.0, true))]
    Config(serde_json::Error),
    /// The configuration is not one et scans (an electrode count, a gain of 0, ...).
    #[error("config: {0} (check the dataset's header)")]
    ConfigInvalid(et_core::config::ConfigError),
    /// A class with no centre in the header's `centres_m`.
    #[error(
        "class {class}, but centres_m lists {centres} class centre(s): is the header's \
         centres_m line missing or cut?"
    )]
    NoCentre {
        /// The class.
        class: u16,
        /// The centres listed.
        centres: usize,
    },
    /// Electrode centres listed for another number of electrodes than the scan's.
    #[error(
        "{given} electrode centres for a scan of {scan} electrodes: one centre per electrode, \
         in the scan's order"
    )]
    ElectrodeCount {
        /// The centres listed.
        given: usize,
        /// The scan's electrodes.
        scan: usize,
    },
    /// The feature index line holds something that is not a frame index.
    #[error(
        "feature_index: '{0}' is not a frame value's index (whole numbers from 0 to 65535, \
         separated by spaces)"
    )]
    FeatureIndex(String),
    /// The header has no configuration line.
    #[error("no '# config:' line")]
    NoConfig,
    /// The first line is not an et dataset's; the format it names, if it is JSON that names
    /// one (an et recording's, a model file's).
    #[error("not an et dataset (expected '# et-dataset 2', or version 1){}", other_format(.0.as_deref()))]
    NotDataset(Option<String>),
    /// JSON given as a table: the format its first line names, if it names one (an et
    /// recording's, a model file's).
    #[error("{}", not_table(.0.as_deref()))]
    NotTable(Option<String>),
    /// A protocol file given as a table.
    #[error(
        "a protocol file (et protocol --csv), not a table of a sensor's values: a scene names \
         it as [scan] protocol = {{ file = \"FILE\" }}"
    )]
    ProtocolTable,
    /// An et dataset of a version this et does not read.
    #[error(
        "et-dataset version '{0}': this et reads versions 1 and 2 (a later one is a newer et's)"
    )]
    DatasetVersion(String),
    /// A column the format needs.
    #[error("column missing")]
    ColumnMissing,
    /// The features and the feature index disagree.
    #[error("{features} feature columns, {index} in feature_index")]
    FeatureCount {
        /// Feature columns.
        features: usize,
        /// Entries of the feature index.
        index: usize,
    },
    /// An untouched frame of another length than the features.
    #[error("untouched frame {frame} has {values} values, the data {features} features")]
    UntouchedLength {
        /// The frame, from 0.
        frame: usize,
        /// Its values.
        values: usize,
        /// The features.
        features: usize,
    },
    /// An `.npz` without a `format` array: not one `et collect` wrote (a user's own `X`
    /// and `y`, most often).
    #[error(
        "not an et dataset: `et collect` writes its .npz with a 'format' array, and this one \
         holds {}; a sensor's own features and targets train as tables (--features F.csv \
         --targets T.csv; numpy.savetxt writes them) or in Python (et.train(X, y))",
        .0.join(", ")
    )]
    NotEtNpz(Vec<String>),
    /// An `.npz` whose `format` array is not an et dataset's.
    #[error("array 'format': not an et dataset ('et-dataset 1')")]
    NotNpzDataset,
    /// A value of an `.npz` array (row, column from 0) that is not finite.
    #[error("array '{array}': row {row}, column {column} is not a finite number")]
    ArrayNotFinite {
        /// The array.
        array: &'static str,
        /// Its row.
        row: usize,
        /// Its column.
        column: usize,
    },
    /// An `.npz` array of another shape.
    #[error(
        "array '{array}': shape {rows} x {columns}, expected {} x 2",
        want.map_or("any".into(), |r| r.to_string())
    )]
    ArrayShape {
        /// The array.
        array: &'static str,
        /// Its rows.
        rows: usize,
        /// Its columns.
        columns: usize,
        /// The rows expected, if any number.
        want: Option<usize>,
    },
    /// An `.npz` array of another length than `x`'s rows.
    #[error("array '{array}': {len} values, x has {want} rows")]
    ArrayLength {
        /// The array.
        array: &'static str,
        /// Its length.
        len: usize,
        /// `x`'s rows.
        want: usize,
    },
    /// An `.npz` array across the features of another length than `x`'s columns.
    #[error("array '{array}': {len} values, x has {want} columns")]
    ArrayColumns {
        /// The array.
        array: &'static str,
        /// Its length (or columns).
        len: usize,
        /// `x`'s columns.
        want: usize,
    },
    /// The `index`-th value (from 1) of the column is not finite.
    #[error("value {0} is not a finite number")]
    ValueNotFinite(usize),
    /// A touch's pressure below 0 (row from 1).
    #[error("row {0}: a pressure below 0 Pa")]
    NegativePressure(usize),
    /// A units line other than the SI et writes (its text).
    #[error(
        "'{0}': et datasets of version 2 hold SI values (features in V, positions in m, \
         pressure in Pa); convert the values and keep the line et wrote"
    )]
    Units(String),
    /// The features' frame indices out of order.
    #[error(
        "feature {feature} reads frame value {index} after {before}: each frame value once, in \
         frame order"
    )]
    FeatureOrder {
        /// The feature, from 1.
        feature: usize,
        /// Its frame value.
        index: u16,
        /// The previous feature's.
        before: u16,
    },
    /// A feature's frame value past the frame.
    #[error("frame value {index} in a frame of {frame_len} values")]
    PastFrame {
        /// The frame value.
        index: u16,
        /// The frame's length.
        frame_len: usize,
    },
    /// A visit number above the rows.
    #[error("visit {visit} in a set of {rows} rows: visits are numbered from 0")]
    VisitPast {
        /// The visit.
        visit: u16,
        /// The rows.
        rows: usize,
    },
    /// A visit with no rows below the last.
    #[error("visits run to {last} but visit {missing} has no rows: number them 0 to T - 1")]
    VisitMissing {
        /// The last visit.
        last: usize,
        /// The one without rows.
        missing: usize,
    },
    /// A table with no feature columns.
    #[error("no feature columns")]
    NoFeatures,
    /// A second file (targets, groups) of other rows than the features'.
    #[error(
        "{rows} {what}, {} has {features_rows}{}",
        features.display(),
        header_like.as_ref().map_or(String::new(), |h| format!(
            ": its first row, '{h}', reads as a header above the rest, but {} has no header \
             row, so whether that or a row of the features is missing would be a guess: give \
             {} a header row of its column names, or take this file's off",
            features.display(),
            features.display()
        ))
    )]
    RowCount {
        /// This file's rows.
        rows: usize,
        /// "rows", "rows of groups".
        what: &'static str,
        /// The features file.
        features: PathBuf,
        /// Its rows.
        features_rows: usize,
        /// This file's first cell when it reads as a header and the features have none
        /// (the table reader's `header_like`).
        header_like: Option<String>,
    },
    /// `--groups NAME` that is no column.
    #[error(
        "--groups {name}: no such column (the header has {}); give a column name or a file with \
         one group per row",
        names.as_ref().map_or("no names: the file has no header row".into(), |n| n.join(", "))
    )]
    NoGroupColumn {
        /// The name given.
        name: String,
        /// The header's first names (none: no header).
        names: Option<Vec<String>>,
    },
    /// Reference features whose header does not name a feature.
    #[error(
        "no column '{feature}' (the header names {}): reference features are paired with the \
         features by name; name its columns as the features' header does, or leave out its \
         header to pair them by position",
        names.join(", ")
    )]
    NoReferenceColumn {
        /// The feature without a column.
        feature: String,
        /// The reference header's first names.
        names: Vec<String>,
    },
    /// `--groups NAME` naming a target column (label, x, y, z, force, pressure).
    #[error(
        "--groups {0}: that column is a target, not a session; give the column (or a file) \
         that says which session each row was recorded in"
    )]
    GroupIsTarget(String),
    /// Several columns named as sessions (`subject` and `session`), none chosen.
    #[error(
        "columns {} name sessions: choose the one a model must hold across with --groups \
         NAME (Python: groups=...); none of them is a feature",
        .0.iter().map(|n| format!("'{n}'")).collect::<Vec<_>>().join(", ")
    )]
    Sessions(Vec<String>),
    /// A column of the rows' numbers or times that differs between the features and the
    /// targets file: their rows are paired by order, and these are not.
    #[error(
        "'{here}' here and '{there}' in {} (line {line}): rows are paired by their order, and \
         these files' rows are in different orders: sort both by this column",
        .targets.display()
    )]
    RowsDiffer {
        /// The features file's cell.
        here: String,
        /// The targets file's cell.
        there: String,
        /// The targets file.
        targets: PathBuf,
        /// Its line.
        line: usize,
    },
    /// A position column named in a length unit et does not read (`x_cm`).
    #[error(
        "{column}: positions in {unit}; et reads them in mm or m: convert the column and name \
         it {axis}_mm or {axis}_m"
    )]
    PositionUnit {
        /// The column's name.
        column: String,
        /// The unit its name gives.
        unit: String,
        /// Its axis: x, y or z.
        axis: char,
    },
    /// Position columns naming two units (`x_mm` beside `y_m`).
    #[error("{first} and {second} name two units: give the positions in one (mm or m)")]
    PositionUnits {
        /// The first column's name.
        first: String,
        /// The other's.
        second: String,
    },
    /// x without y or y without x.
    #[error("give both x and y columns, or neither")]
    HalfPosition,
    /// Neither labels nor positions.
    #[error(
        "{}",
        if *header {
            "no target: add a 'label' column or 'x' and 'y' columns"
        } else {
            "no target: without a header row every column is a feature; name the targets (label, \
             or x and y) in a header row, or give them in a second file"
        }
    )]
    NoTarget {
        /// Whether the file has a header row.
        header: bool,
    },
}

/// For a cell of words where a number belongs: how a table reads a column of text (`class`
/// of `left`, `right` was said only as "'right' is not a number").
fn text_hint(cell: &str) -> &'static str {
    if et_core::text::says_missing(cell) {
        " but a value missing: every row needs each of its features; leave the row out (as \
         pandas' df.dropna() does) or fill the value in"
    } else if et_core::text::fortran_exponent(cell) {
        et_core::text::fortran_said(cell)
    } else if cell.chars().any(char::is_alphabetic) {
        " (a column of text is read as the class when it is named 'label', or as the session \
         with --groups NAME)"
    } else {
        ""
    }
}

/// What is said of JSON given as a table, whose first line names `format`.
fn not_table(format: Option<&str>) -> String {
    match format {
        Some("et-recording") => "an et recording (et sim, et record), not a table: `et \
                                 reconstruct --frames FILE` images its frames, and `et stream \
                                 --replay FILE --model MODEL` classifies them"
            .into(),
        Some("et-model" | "et-table-model") => {
            "a model file (et train), not a table: give it as --model".into()
        }
        Some(other) => format!("JSON naming the format '{other}', not a table of numbers"),
        None => "JSON, not a table of numbers (a CSV: a header row, then a row of numbers per \
                 observation)"
            .into(),
    }
}

/// What is said of a file given as a dataset whose first line names `format`.
fn other_format(format: Option<&str>) -> String {
    match format {
        None => String::new(),
        Some("et-recording") => ": it is an et recording (et sim, et record); `et stream \
                                 --replay FILE --model MODEL` classifies its frames, and et \
                                 collect writes datasets"
            .into(),
        Some("et-model" | "et-table-model") => ": it is a model file (et train); give it as \
                                                  --model, and the dataset as --data"
            .into(),
        Some(other) => format!(": its first line names the format '{other}'"),
    }
}
