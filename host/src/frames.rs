//! Measured frames from other systems' files, for imaging: a CSV (one frame per row, a header
//! row optional, cells separated by `,`, `;` or tabs), a NumPy `.npy` (2-D, or 1-D for one
//! frame), an array of an `.npz` (`file.npz:NAME`, or its only array) or a MATLAB `.mat`
//! of version 5 or 7 (`file.mat:VARIABLE`, a struct's numeric field `file.mat:vi.meas` as
//! EIDORS keeps its data, or the file's only numeric array). Values in volts.
//! A matrix whose rows are the protocol's K values and whose columns are not (frames as
//! columns, as MATLAB users store them) is read as its transpose, and said so. et's own
//! recordings (`.jsonl`) are read by [`crate::recording`].

use std::path::{Path, PathBuf};

use et_learn::npz::NpzError;
use nalgebra::DMatrix;

mod arrays;
mod csv_frames;
mod mat;
use csv_frames::csv_matrix;
use mat::mat_matrix;
pub use mat::mat_v5;

/// Frames read from a file, each of K values, V.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// The frames, in file order.
    pub frames: Vec<Vec<f32>>,
    /// The frames (from 0) with values missing, NaN in them (an empty or NaN cell, a NaN in an
    /// array: a value the system did not send): kept in their place, and taken by no image.
    pub gaps: Vec<usize>,
    /// What was read, in words (the file, the shape, the orientation).
    pub description: String,
}

impl Frames {
    /// The first of `frames` (indices from 0) with values missing, and its values' columns
    /// (from 0), said as an error of the file at `path`: "choose other frames with `how`".
    ///
    /// # Errors
    /// [`FramesError::Content`] naming that frame.
    pub fn check_whole(
        &self,
        path: &Path,
        frames: std::ops::Range<usize>,
        how: &str,
    ) -> Result<(), FramesError> {
        let Some(&frame) = self.gaps.iter().find(|i| frames.contains(i)) else {
            return Ok(());
        };
        let columns = (self.frames.get(frame))
            .map_or_else(Vec::new, |f| crate::recording::invalid_columns(f));
        let fault = FramesFault::Missing {
            frame,
            columns,
            how: how.to_string(),
        };
        Err(content(path, 0, fault))
    }
}

/// Why frames could not be read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FramesError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The content is not frames of this protocol.
    #[error("{}{}: {fault}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Content {
        /// The file.
        path: PathBuf,
        /// 1-based line of a CSV (0: not about one line).
        line: usize,
        /// What is wrong.
        fault: FramesFault,
    },
    /// The `.npy`/`.npz` could not be read.
    #[error("{}: {error}", path.display())]
    Npz {
        /// The file.
        path: PathBuf,
        /// Why.
        error: NpzError,
    },
}

/// What is wrong inside a file of frames.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FramesFault {
    /// The rows could not be read as CSV.
    #[error(transparent)]
    Records(#[from] et_core::text::RecordFault),
    /// A row of another length than the first.
    #[error(
        "{found} values, the first frame has {first}{}",
        if *last { " (the file's last row: a copy cut short?)" } else { "" }
    )]
    RowLength {
        /// The row's values.
        found: usize,
        /// The first row's.
        first: usize,
        /// Whether it is the file's last row, short of values (a file cut short).
        last: bool,
    },
    /// A cell that is not a number (column from 1).
    #[error(
        "column {column}: '{cell}' is not a number{}",
        if csv_frames::complex(cell) {
            " but a complex one: et images real voltages, so write the real parts (NumPy: \
             np.savetxt(f, V.real); from magnitude and phase, magnitude * cos(phase))"
        } else if *first_row && et_core::text::fortran_said(cell).is_empty() {
            " (a header of more lines than one, as some loggers write? et reads one row of \
             names above the numbers: write # before the others)"
        } else {
            et_core::text::fortran_said(cell)
        }
    )]
    NotNumber {
        /// The column, from 1.
        column: usize,
        /// The cell as written.
        cell: String,
        /// Whether it is on the row after a header, before any frame.
        first_row: bool,
    },
    /// Every column named as no frame's values.
    #[error(
        "no values: its columns {} are named as the rows' numbers, times, sessions or targets, \
         which frames are read without",
        .0.join(", ")
    )]
    NoValues(Vec<String>),
    /// No rows of numbers (under a header, or none).
    #[error("no frames{}", if *header { " (a header row alone)" } else { "" })]
    NoFrames {
        /// Whether a header was read.
        header: bool,
    },
    /// A cell of a CSV that is a number but not a voltage et takes: NaN, infinite, or past
    /// single precision (column from 1).
    #[error("column {column}: '{cell}' {}", if value.is_finite() {
        "is past single precision (at most 3.4e38), in which et takes frames: not volts?"
    } else {
        "is not finite (a value the system did not send? leave that frame out)"
    })]
    NotVolts {
        /// The column, from 1.
        column: usize,
        /// The cell as written.
        cell: String,
        /// Its value.
        value: f64,
    },
    /// A frame asked for with values missing (NaN; from 0).
    #[error(
        "frame {frame} (from 0) has values missing (empty or NaN cells: values the system did \
         not send) in column{} {} (from 0): choose other frames with {how}",
        if columns.len() == 1 { "" } else { "s" },
        said_list(columns)
    )]
    Missing {
        /// The frame.
        frame: usize,
        /// Its values missing.
        columns: Vec<usize>,
        /// How other frames are chosen.
        how: String,
    },
    /// A value that is not finite (row and column from 0).
    #[error(
        "value {value} at row {row}, column {column} (counted from 0) is not finite (a value \
         the system did not send? leave that frame out)"
    )]
    NotFinite {
        /// The value.
        value: f64,
        /// Its row.
        row: usize,
        /// Its column.
        column: usize,
    },
    /// Values that single precision, in which et takes frames, cannot hold ([`Single`]; the
    /// row and column from 0 of a value past its range, in an array).
    #[error("{}", match fault {
        Single::Past(_) => format!("row {row}, column {column}: {fault}"),
        Single::Below => fault.to_string(),
    })]
    NotSingle {
        /// What single precision cannot hold.
        fault: Single,
        /// The row of the value past its range.
        row: usize,
        /// Its column.
        column: usize,
    },
    /// Neither dimension is the protocol's K.
    #[error(
        "{rows} x {columns} values: the protocol has K = {k} values per frame, so one dimension \
         must be {k} ({})",
        if *rows == k + 1 || *columns == k + 1 {
            "one more than K: a first column or row of frame numbers or times? write the file \
             without it, or name its column time or frame in a header, which et leaves out"
                .to_string()
        } else if *rows == 2 * k || *columns == 2 * k {
            "twice K: real and imaginary parts, or magnitudes and phases, side by side? et \
             images real voltages: write the real parts alone (magnitude * cos(phase))".to_string()
        } else {
            other_protocol(*rows, *columns, *k)
        }
    )]
    NoK {
        /// Rows.
        rows: usize,
        /// Columns.
        columns: usize,
        /// The protocol's values per frame.
        k: usize,
    },
    /// Several arrays and none named.
    #[error(
        "{} {kind} ({}): name one as {}:{placeholder}",
        names.len(), names.join(", "), path.display()
    )]
    Choose {
        /// The arrays there are.
        names: Vec<String>,
        /// "arrays", "numeric arrays".
        kind: &'static str,
        /// The file.
        path: PathBuf,
        /// NAME, VARIABLE.
        placeholder: &'static str,
    },
    /// A file of another kind named as an array file (a picture, a spreadsheet, HDF5).
    #[error("{what}, though named .{ext}: {fix}")]
    OtherKind {
        /// What it is.
        what: String,
        /// Its name's ending.
        ext: String,
        /// How to write frames from it.
        fix: String,
    },
    /// An array named in a `.npy`, which holds one.
    #[error("a .npy holds one array, not one named '{0}': give the file alone")]
    NpyName(String),
    /// A MATLAB 7.3 file.
    #[error("a MATLAB 7.3 file (HDF5): save it with save(..., '-v7') or as CSV")]
    Mat73,
    /// A file without a version 5 header: MATLAB's version 4 format, or not MATLAB's.
    #[error(
        "not a MATLAB version 5 or 7 file (no such header: a version 4 file, from save -v4 \
         or scipy's format='4'?): save it with save(..., '-v7') or as CSV"
    )]
    NoMatHeader,
    /// A file holding no array of numbers.
    #[error(
        "no {kind}: cell arrays, structs, sparse matrices and text are not frames; store \
         them as a matrix of numbers, one frame per row or column"
    )]
    Nothing {
        /// "numeric arrays" or "arrays".
        kind: &'static str,
    },
    /// An array of booleans.
    #[error("array '{0}' holds booleans (True, False), not voltages")]
    Booleans(String),
    /// An et dataset (observations with their labels), not frames.
    #[error(
        "an et dataset (`et collect`'s observations with their classes and positions), not \
         frames: train and evaluate with it (et train --data, et eval --data; Python's \
         read_dataset)"
    )]
    Dataset,
    /// A protocol file (its rows of electrodes were read as frames, one per column), or a
    /// hardware log of each value's electrodes beside `others` columns of values.
    #[error("{}", protocol_said(*others))]
    Protocol {
        /// Columns beside the electrodes' and the current's.
        others: usize,
    },
    /// A compressed MATLAB variable that ends early.
    #[error("a compressed variable is cut short")]
    CutShort,
    /// A compressed MATLAB variable that does not inflate.
    #[error("a compressed variable is damaged")]
    Damaged,
    /// A compressed MATLAB variable that inflates past the data files' limit.
    #[error("its compressed variables inflate past {0} bytes together: not frames et reads")]
    Inflates(u64),
    /// The MATLAB reader refused the file.
    #[error("not a MATLAB version 5 or 7 file: {0}")]
    NotMat(matfile::Error),
    /// The MATLAB reader stopped on inconsistent headers.
    #[error("not a MATLAB file et can read: its variables' headers are inconsistent")]
    MatInconsistent,
    /// No numeric array of the name.
    #[error("no numeric array '{name}' (it has: {})", names.join(", "))]
    NoVariable {
        /// The name asked for.
        name: String,
        /// The ones there are.
        names: Vec<String>,
    },
    /// A variable that is not real doubles, singles or 8 to 32-bit integers.
    #[error("'{0}' is complex or 64-bit integer: store the frames' real voltages as double")]
    NotReal(String),
    /// A variable of other than 2 dimensions.
    #[error("'{name}' has {dimensions} dimensions: frames are a 2-D matrix")]
    Dimensions {
        /// The variable.
        name: String,
        /// Its dimensions.
        dimensions: usize,
    },
    /// A variable whose size and values disagree.
    #[error("'{name}': {rows} x {columns} but {values} values")]
    Size {
        /// The variable.
        name: String,
        /// Its rows.
        rows: usize,
        /// Its columns.
        columns: usize,
        /// Its values.
        values: usize,
    },
}

/// What is said of a protocol file given as frames, or of a hardware log (each value's four
/// electrodes, then `others` columns of values).
fn protocol_said(others: usize) -> String {
    let scene = "a scene names it as [scan] protocol = { file = \"FILE\" }";
    match others {
        0 => format!(
            "a protocol file (et protocol --csv), not frames: {scene}, and the frames measured \
             under it go to --frames"
        ),
        n => format!(
            "each row's four electrodes (source, sink, positive, negative) and {n} more \
             column{}: a hardware log? et reads them apart: the four electrodes' columns as \
             a protocol file ({scene}), the values alone, one frame a column, as --frames",
            if n == 1 { "" } else { "s" }
        ),
    }
}

fn content(path: &Path, line: usize, fault: FramesFault) -> FramesError {
    FramesError::Content {
        path: path.into(),
        line,
        fault,
    }
}

/// The matrix of a table of text and what is said of it: et's other files refused as what they are (its comments
/// and header skipped and its columns read as a frame's values, a protocol file's 5 columns
/// were 5 frames).
fn text_matrix(path: &Path) -> Result<(DMatrix<f64>, String), FramesError> {
    let text = et_core::text::read_text_at_most(path, et_core::text::max_file_bytes()).map_err(
        |source| FramesError::Io {
            path: path.into(),
            source,
        },
    )?;
    table_matrix(path, &text)
}

/// [`text_matrix`] of the `text` read from `path`.
fn table_matrix(path: &Path, text: &str) -> Result<(DMatrix<f64>, String), FramesError> {
    match et_core::text::EtFile::of(text) {
        Some(et_core::text::EtFile::Dataset) => Err(content(path, 1, FramesFault::Dataset)),
        Some(et_core::text::EtFile::Protocol) => {
            // A hardware log's value columns beside the electrodes' (not current_a).
            let others = et_core::text::EtFile::columns_beside_protocol(text).unwrap_or(0);
            Err(content(path, 1, FramesFault::Protocol { others }))
        }
        _ => csv_matrix(path, text),
    }
}

/// Of a file's several arrays, unnamed by the user, the one of `k` values along a dimension
/// (`np.savez(f, frames=F, t=t)`), where it is the only one and every array's shape is known;
/// what is said of the choice with it.
fn only_of_k(shapes: &[(String, Option<Vec<usize>>)], k: usize) -> Option<(String, String)> {
    if shapes.iter().any(|(_, s)| s.is_none()) {
        return None;
    }
    let mut fit = shapes
        .iter()
        .filter(|(_, s)| s.as_ref().is_some_and(|s| s.len() <= 2 && s.contains(&k)));
    let (name, _) = fit.next()?;
    if fit.next().is_some() {
        return None;
    }
    let others: Vec<&str> = (shapes.iter().map(|(n, _)| n.as_str()))
        .filter(|n| n != name)
        .collect();
    let said = format!(
        "the only one of its arrays with K = {k} values a frame (the others: {}), ",
        others.join(", ")
    );
    Some((name.clone(), said))
}

/// Whether `spec` names a table of frames this module reads (by its extension), rather than
/// an et recording.
#[must_use]
pub fn is_table(spec: &Path) -> bool {
    let (path, _) = split_array(spec);
    matches!(
        path.extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref(),
        Some("csv" | "txt" | "tsv" | "npy" | "npz" | "mat")
    )
}

/// Whether the frames given as `spec` are read as a table rather than as an et recording: by
/// name ([`is_table`]), and a file named otherwise (a DAQ's `.dat` or `.log`, no extension)
/// by what it holds: a recording's first line is a JSON object, anything else is read as a
/// table (`.dat` was read as a recording and refused for its first line). Only a regular
/// file is read ahead; a stream (a FIFO, `/dev/stdin`) can be read once, and is taken by
/// its name. Not for outputs, whose format is their name's.
#[must_use]
pub fn reads_as_table(spec: &Path) -> bool {
    use std::io::Read as _;
    if is_table(spec) {
        return true;
    }
    let (path, _) = split_array(spec);
    let ext = path.extension().and_then(|e| e.to_str());
    if ext.is_some_and(|e| ["jsonl", "json", "ndjson"].contains(&e.to_ascii_lowercase().as_str()))
        || !std::fs::metadata(&path).is_ok_and(|m| m.is_file())
    {
        return false;
    }
    let mut head = Vec::with_capacity(4096);
    let read = std::fs::File::open(&path).and_then(|f| f.take(4096).read_to_end(&mut head));
    let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&head);
    let first = text.iter().find(|b| !b.is_ascii_whitespace());
    // (Unreadable or empty: the recording reader says why, as before.)
    read.is_ok() && first.is_some_and(|&b| b != b'{')
}

/// `file.npz:NAME` or `file.mat:NAME` as (file, Some(NAME)); anything else as (spec, None).
/// (`file.npy:NAME` too: a file named .npy may hold an archive or a MATLAB file.)
fn split_array(spec: &Path) -> (PathBuf, Option<String>) {
    let s = spec.to_string_lossy();
    for ext in [".npz:", ".mat:", ".npy:"] {
        if let Some((file, name)) = s.rsplit_once(ext)
            && !name.is_empty()
        {
            return (
                PathBuf::from(format!("{file}{}", &ext[..4])),
                Some(name.to_string()),
            );
        }
    }
    (spec.to_path_buf(), None)
}

/// Whether frames of `rows` or `columns` values are of another protocol than the scene's
/// (`k` values), with what they may be ([`et_core::schedule::other_frame_len`]).
fn other_protocol(rows: usize, columns: usize, k: usize) -> String {
    let asked = "is it the scene's protocol?";
    [columns, rows]
        .into_iter()
        .find_map(|n| et_core::schedule::other_frame_len(n, k))
        .map_or_else(|| asked.to_string(), |may| format!("{asked} {may}"))
}

/// Reads the frames of `spec` for a protocol of `k` values per frame.
///
/// # Errors
/// [`FramesError`] naming the file (and the line or array): unreadable, not numbers, a
/// non-finite value, or no dimension of K values.
pub fn read(spec: &Path, k: usize) -> Result<Frames, FramesError> {
    let (path, array) = split_array(spec);
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    let (matrix, said) = match ext.as_str() {
        "npy" | "npz" | "mat" => arrays::matrix(&path, &ext, array.as_deref(), k)?,
        _ => text_matrix(&path)?,
    };
    let (rows, cols) = matrix.shape();
    // (NaN is a value not measured, its frame kept: see `gaps`.)
    if let Some((i, v)) = matrix.iter().enumerate().find(|(_, v)| v.is_infinite()) {
        let (value, row, column) = (*v, i % rows, i / rows);
        return Err(content(
            &path,
            0,
            FramesFault::NotFinite { value, row, column },
        ));
    }
    if let Some((i, fault)) = Single::check(matrix.as_slice()) {
        let (row, column) = (i % rows.max(1), i / rows.max(1));
        let fault = FramesFault::NotSingle { fault, row, column };
        return Err(content(&path, 0, fault));
    }
    // A square matrix (K frames of K values, K of 8 or more) reads either way round: a
    // recording's frames are far more alike than its values across the channels, so the
    // frames are the way whose lines are clearly alike (read by rows, MATLAB's columns of
    // frames were taken as rows).
    let square = rows == k && cols == k && k >= 8;
    let by_rows = cols == k && !(square && columns_alike(&matrix));
    let by_columns = !by_rows && rows == k;
    if !by_rows && !by_columns {
        let fault = FramesFault::NoK {
            rows,
            columns: cols,
            k,
        };
        return Err(content(&path, 0, fault));
    }
    let frames: Vec<Vec<f32>> = if by_rows {
        matrix
            .row_iter()
            .map(|r| r.iter().map(|&v| v as f32).collect())
            .collect()
    } else {
        matrix
            .column_iter()
            .map(|c| c.iter().map(|&v| v as f32).collect())
            .collect()
    };
    let gaps: Vec<usize> = (frames.iter().enumerate())
        .filter(|(_, f)| f.iter().any(|v| v.is_nan()))
        .map(|(i, _)| i)
        .collect();
    let description = format!(
        "{}: {said}{} frame{} of {k} values{}{}",
        path.display(),
        frames.len(),
        if frames.len() == 1 { "" } else { "s" },
        match (by_columns, square) {
            (true, false) => " (one per column: read transposed)",
            (true, true) => {
                " (one per column, read transposed: a K x K matrix, whose columns are alike as \
                 a recording's frames are)"
            }
            (false, true) => {
                " (one per row: a K x K matrix, whose rows are alike as a recording's frames \
                 are)"
            }
            (false, false) => "",
        },
        match gaps.as_slice() {
            [] => String::new(),
            [one] => format!(" (frame {one}, from 0, with values missing: empty or NaN)"),
            many => format!(
                " ({} with values missing, empty or NaN: frames {}, from 0)",
                many.len(),
                said_list(many)
            ),
        }
    );
    Ok(Frames {
        frames,
        gaps,
        description,
    })
}

/// Indices as a list, the first eight and how many more.
fn said_list(indices: &[usize]) -> String {
    let shown: Vec<String> = indices.iter().take(8).map(ToString::to_string).collect();
    match indices.len() {
        n if n > 8 => format!("{}, ... ({n} in all)", shown.join(", ")),
        _ => shown.join(", "),
    }
}

/// Voltages single precision cannot hold: et takes frames in it (the board's, and every
/// reader's), and such values are not volts (a unit or a column mistaken).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Single {
    /// A finite value past its range: it would become infinite.
    #[error(
        "{0:e} is past single precision (at most 3.4e38), in which et takes frames: not volts?"
    )]
    Past(f64),
    /// Every value below its normal range, one at least not zero: they would become zeros (or
    /// keep a few bits).
    #[error(
        "every value is below 1.2e-38, the least of single precision, in which et takes frames: \
         not volts?"
    )]
    Below,
}

impl Single {
    /// The first fault of `values` and the index of the value it is in (0 for
    /// [`Single::Below`]), or None when single precision holds them. NaN and infinity pass:
    /// they are said where values are checked for being finite.
    #[must_use]
    pub fn check(values: &[f64]) -> Option<(usize, Self)> {
        let largest = f64::from(f32::MAX);
        if let Some((i, &value)) =
            (values.iter().enumerate()).find(|(_, v)| v.is_finite() && v.abs() > largest)
        {
            return Some((i, Self::Past(value)));
        }
        let least = f64::from(f32::MIN_POSITIVE);
        (values.iter().any(|v| *v != 0.0) && values.iter().all(|v| v.abs() < least))
            .then_some((0, Self::Below))
    }
}

/// Whether the columns of `m` are clearly more alike than its rows: the squares of each
/// entry's distance from its row's mean under a quarter of those from its column's mean
/// (frames of a recording differ by a few per cent, its channels by their whole size; what is
/// not clear stays read by rows, NumPy's way).
fn columns_alike(m: &DMatrix<f64>) -> bool {
    let (row_means, column_means) = (m.column_mean(), m.row_mean());
    let (mut about_rows, mut about_columns) = (0.0, 0.0);
    for ((r, c), v) in m
        .iter()
        .enumerate()
        .map(|(i, v)| ((i % m.nrows(), i / m.nrows()), v))
    {
        about_rows += (v - row_means[r]).powi(2);
        about_columns += (v - column_means[c]).powi(2);
    }
    4.0 * about_rows < about_columns
}
