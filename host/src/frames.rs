//! Measured frames from other systems' files, for imaging: a CSV (one frame per row, a header
//! row optional, cells separated by `,`, `;` or tabs), a NumPy `.npy` (2-D, or 1-D for one
//! frame), an array of an `.npz` (`file.npz:NAME`, or its only array) or a MATLAB `.mat`
//! of version 5 or 7 (`file.mat:VARIABLE`, a struct's numeric field `file.mat:vi.meas` as
//! EIDORS keeps its data, or the file's only numeric array). Values in volts.
//! A matrix whose rows are the protocol's K values and whose columns are not (frames as
//! columns, as MATLAB users store them) is read as its transpose, and said so. et's own
//! recordings (`.jsonl`) are read by [`crate::recording`].

use std::path::{Path, PathBuf};

use nalgebra::DMatrix;

mod arrays;
mod csv_frames;
mod error;
mod json_frames;
mod json_objects;
mod lvm;
mod mat;
use csv_frames::csv_matrix;
pub(crate) use csv_frames::{unit_in_name, unit_words};
pub use error::said_list;
pub use error::{FramesError, FramesFault};
pub(crate) use mat::STIMULATION;
use mat::mat_matrix;
pub use mat::{Numeric, StructArray, mat_v5};

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

/// The numbers of a table's `text`, read from `path`, as a matrix of its rows, and what was
/// read in words (its header, columns left out by name, units), as frames' tables are read.
///
/// # Errors
/// [`FramesError`] naming the file and the line.
pub fn table_matrix(path: &Path, text: &str) -> Result<(DMatrix<f64>, String), FramesError> {
    match et_core::text::EtFile::of(text) {
        Some(et_core::text::EtFile::Dataset) => Err(content(path, 1, FramesFault::Dataset)),
        Some(et_core::text::EtFile::Protocol) => {
            // A hardware log's value columns beside the electrodes' (not current_a).
            let others = et_core::text::EtFile::columns_beside_protocol(text).unwrap_or(0);
            Err(content(path, 1, FramesFault::Protocol { others }))
        }
        // A JSON array (`json.dump(F.tolist())`) or an object other than et's files' (a
        // recording, a model: said as what they are by the CSV reader).
        None if text
            .trim_start_matches('\u{feff}')
            .trim_start()
            .starts_with(['[', '{']) =>
        {
            json_frames::json_matrix(path, text)
        }
        _ if lvm::is_lvm(text) => {
            let lvm = lvm::as_csv(text);
            let (matrix, said) = csv_matrix(path, &lvm.csv).map_err(|e| lvm.in_file_columns(e))?;
            if let Some(unit) = lvm.not_volts {
                let said = format!(
                    "a LabVIEW measurement file (its Y_Unit_Label '{unit}' not a unit of \
                     voltage: the values are taken as volts), {said}"
                );
                return Ok((matrix, said));
            }
            Ok((matrix, format!("a LabVIEW measurement file, {said}")))
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
/// by what it holds: a recording's first line is a JSON object naming its "format", anything
/// else is read as a table (`.dat` was read as a recording and refused for its first line);
/// one named `.json` or `.jsonl` is a table where it holds JSON arrays of frames or objects
/// other than a recording's (pandas' `to_json()`). Only a regular
/// file is read ahead; a stream (a FIFO, `/dev/stdin`) can be read once, and is taken by
/// its name. Not for outputs, whose format is their name's.
#[must_use]
pub fn reads_as_table(spec: &Path) -> bool {
    use std::io::Read as _;
    if is_table(spec) {
        return true;
    }
    let (path, _) = split_array(spec);
    if !std::fs::metadata(&path).is_ok_and(|m| m.is_file()) {
        return false;
    }
    let mut head = Vec::with_capacity(4096);
    let read = std::fs::File::open(&path).and_then(|f| f.take(4096).read_to_end(&mut head));
    let text = head.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(&head);
    let first = text.iter().find(|b| !b.is_ascii_whitespace());
    // (Unreadable or empty: the recording reader says why, as before.)
    let ext = path.extension().and_then(|e| e.to_str());
    let json =
        ext.is_some_and(|e| ["jsonl", "json", "ndjson"].contains(&e.to_ascii_lowercase().as_str()));
    // A recording's first line is an object whose first key is "format"; another object (a
    // pandas `to_json()`, `{"frames": [...]}`) holds frames, as an array does. A header
    // written without its "format" (by hand, from Python) is known by its "K" and "columns"
    // or "config" keys, and the recording reader asks for the field.
    let line = text.split(|&b| b == b'\n').next().unwrap_or(&[]);
    let key = |name: &str| {
        let quoted = format!("\"{name}\"");
        let found = |at: usize| {
            let rest = &line[at + quoted.len()..];
            rest.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b':')
        };
        (line.windows(quoted.len()).enumerate()).any(|(at, w)| w == quoted.as_bytes() && found(at))
    };
    let recording = line.windows(8).any(|w| w == b"\"format\"")
        || (key("K") && (key("columns") || key("config")));
    read.is_ok()
        && first.is_some_and(|&b| b == b'[' || (b == b'{' && !recording) || (b != b'{' && !json))
}

/// `file.npz:NAME` or `file.mat:NAME` as (file, Some(NAME)); anything else as (spec, None).
/// (`file.npy:NAME` too: a file named .npy may hold an archive or a MATLAB file.) The
/// extension in any case, as Windows tools write it (`RUN.MAT:V` was looked for as a file of
/// that name).
pub(crate) fn split_array(spec: &Path) -> (PathBuf, Option<String>) {
    let s = spec.to_string_lossy();
    // (ASCII's lower case keeps every byte's place.)
    let lower = s.to_ascii_lowercase();
    for ext in [".npz:", ".mat:", ".npy:"] {
        if let Some(at) = lower.rfind(ext)
            && at + ext.len() < s.len()
        {
            let (file, name) = (&s[..at + ext.len() - 1], &s[at + ext.len()..]);
            return (PathBuf::from(file), Some(name.to_string()));
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
    let ext = extension(&path);
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
        // (The array read where none was named: a file's only numeric array may not be the
        // frames, a model's nodes beside structs.)
        let chosen = (array.is_none() && matches!(ext.as_str(), "npz" | "mat"))
            .then(|| said.split(", ").next().unwrap_or_default().to_string())
            .filter(|c| !c.is_empty());
        let fault = FramesFault::NoK {
            chosen,
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

/// `path`'s extension in lower case (empty for none).
fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default()
}

/// The numbers of an array file (`.npy`, `.npz:NAME`, `.mat:VARIABLE`) as a matrix, rows as
/// stored, and what was read in words; None for any other name, whose text the caller reads
/// once and gives to [`table_matrix`]. For tables that are not frames (a protocol's patterns).
///
/// # Errors
/// [`FramesError`] naming the file (and the array): unreadable, or not numbers.
pub fn array_matrix(spec: &Path) -> Option<Result<(DMatrix<f64>, String), FramesError>> {
    let (path, array) = split_array(spec);
    let ext = extension(&path);
    matches!(ext.as_str(), "npy" | "npz" | "mat")
        .then(|| arrays::matrix(&path, &ext, array.as_deref(), 0))
}

/// The struct array of `spec` (`file.mat`, or `file.mat:NAME`, a dotted name for a
/// struct's field: `fmdl.stimulation`) having every field of `wanted`, each element's
/// fields as numeric matrices (dense or sparse), and what was said.
///
/// # Errors
/// [`FramesError`] naming the file: unreadable, not a version 5 or 7 MATLAB file, no such
/// struct array, or several and none named.
pub fn struct_array(spec: &Path, wanted: &[&str]) -> Result<(StructArray, String), FramesError> {
    let (path, name) = split_array(spec);
    let bytes =
        et_core::text::read_at_most(&path, et_core::text::max_file_bytes()).map_err(|source| {
            FramesError::Io {
                path: path.clone(),
                source,
            }
        })?;
    mat::mat_struct_array(&path, &bytes, name.as_deref(), wanted)
}

/// The names of the struct arrays of the MATLAB file `spec` names (its `:NAME` left aside)
/// having every field of `wanted`; none for a file that is no regular MATLAB file (a FIFO is
/// not read again).
#[must_use]
pub fn struct_array_names(spec: &Path, wanted: &[&str]) -> Vec<String> {
    let (path, _) = split_array(spec);
    if !path.metadata().is_ok_and(|m| m.is_file()) {
        return Vec::new();
    }
    et_core::text::read_at_most(&path, et_core::text::max_file_bytes())
        .map(|bytes| mat::struct_array_names(&bytes, wanted))
        .unwrap_or_default()
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
