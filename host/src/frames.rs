//! Measured frames from other systems' files, for imaging: a CSV (one frame per row, a header
//! row optional, cells separated by `,`, `;` or tabs), a NumPy `.npy` (2-D, or 1-D for one
//! frame) or an array of an `.npz` (`file.npz:NAME`, or its only array). Values in volts.
//! A matrix whose rows are the protocol's K values and whose columns are not (frames as
//! columns, as MATLAB users store them) is read as its transpose, and said so. et's own
//! recordings (`.jsonl`) are read by [`crate::recording`].

use std::path::{Path, PathBuf};

use et_core::text::{self, Delimiter};
use et_learn::npz::{Npz, NpzError};
use nalgebra::DMatrix;

/// Frames read from a file, each of K values, V.
#[derive(Clone, Debug, PartialEq)]
pub struct Frames {
    /// The frames, in file order.
    pub frames: Vec<Vec<f32>>,
    /// What was read, in words (the file, the shape, the orientation).
    pub description: String,
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
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Content {
        /// The file.
        path: PathBuf,
        /// 1-based line of a CSV (0: not about one line).
        line: usize,
        /// What is wrong.
        message: String,
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

fn content(path: &Path, line: usize, message: impl Into<String>) -> FramesError {
    FramesError::Content {
        path: path.into(),
        line,
        message: message.into(),
    }
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
        Some("csv" | "txt" | "tsv" | "npy" | "npz")
    )
}

/// `file.npz:NAME` as (file, Some(NAME)); anything else as (spec, None).
fn split_array(spec: &Path) -> (PathBuf, Option<String>) {
    let s = spec.to_string_lossy();
    match s.rsplit_once(".npz:") {
        Some((file, name)) if !name.is_empty() => {
            (PathBuf::from(format!("{file}.npz")), Some(name.to_string()))
        }
        _ => (spec.to_path_buf(), None),
    }
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
    let io = |source| FramesError::Io {
        path: path.clone(),
        source,
    };
    let npz = |error| FramesError::Npz {
        path: path.clone(),
        error,
    };
    let (matrix, said) = match ext.as_str() {
        "npy" => {
            let bytes = std::fs::read(&path).map_err(io)?;
            (
                npy_matrix(&Npz::from_npy(bytes), "array").map_err(npz)?,
                String::new(),
            )
        }
        "npz" => {
            let archive = Npz::read(std::fs::read(&path).map_err(io)?).map_err(npz)?;
            let names: Vec<&str> = archive.names().collect();
            let name = match (&array, names.as_slice()) {
                (Some(n), _) => n.clone(),
                (None, [only]) => (*only).to_string(),
                (None, _) => {
                    return Err(content(
                        &path,
                        0,
                        format!(
                            "{} arrays ({}): name one as {}:NAME",
                            names.len(),
                            names.join(", "),
                            path.display()
                        ),
                    ));
                }
            };
            let m = npy_matrix(&archive, &name).map_err(npz)?;
            (m, format!("array '{name}', "))
        }
        _ => {
            let text = std::fs::read_to_string(&path).map_err(io)?;
            csv_matrix(&path, &text)?
        }
    };
    let (rows, cols) = matrix.shape();
    if let Some((i, v)) = matrix.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(content(
            &path,
            0,
            format!(
                "value {v} at row {}, column {} is not finite",
                i % rows,
                i / rows
            ),
        ));
    }
    let by_rows = cols == k;
    let by_columns = !by_rows && rows == k;
    if !by_rows && !by_columns {
        return Err(content(
            &path,
            0,
            format!(
                "{rows} x {cols} values: the protocol has K = {k} values per frame, so one \
                 dimension must be {k} (is it the scene's protocol?)"
            ),
        ));
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
    let description = format!(
        "{}: {said}{} frames of {k} values{}",
        path.display(),
        frames.len(),
        if by_columns {
            " (one per column: read transposed)"
        } else {
            ""
        }
    );
    Ok(Frames {
        frames,
        description,
    })
}

/// A 1-D array as one row, a 2-D one as it is.
fn npy_matrix(archive: &Npz, name: &str) -> Result<DMatrix<f64>, NpzError> {
    archive
        .matrix(name)
        .or_else(|e| match archive.vector(name) {
            Ok(v) => Ok(DMatrix::from_row_slice(1, v.len(), &v)),
            Err(_) => Err(e),
        })
}

/// A CSV of numbers, a header row skipped; its matrix and what was said of the delimiter.
fn csv_matrix(path: &Path, text: &str) -> Result<(DMatrix<f64>, String), FramesError> {
    let records =
        text::read_records(&text::lines(text)).map_err(|(line, m)| content(path, line, m))?;
    let delimiter = records.delimiter;
    let mut rows = records.rows.iter().peekable();
    let header = rows
        .peek()
        .is_some_and(|(_, r)| r.iter().any(|c| text::number(c, delimiter).is_none()));
    if header {
        rows.next();
    }
    let mut values = Vec::new();
    let mut width = None;
    let mut n = 0;
    for (line, cells) in rows {
        let w = *width.get_or_insert(cells.len());
        if cells.len() != w {
            return Err(content(
                path,
                *line,
                format!("{} values, the first frame has {w}", cells.len()),
            ));
        }
        for (c, cell) in cells.iter().enumerate() {
            values.push(text::number(cell, delimiter).ok_or_else(|| {
                content(
                    path,
                    *line,
                    format!("column {}: '{cell}' is not a number", c + 1),
                )
            })?);
        }
        n += 1;
    }
    let w = width.ok_or_else(|| content(path, 0, "no frames"))?;
    let said = match delimiter {
        Delimiter::Comma => String::new(),
        d => format!("{}, ", d.said()),
    };
    Ok((DMatrix::from_row_slice(n, w, &values), said))
}

#[cfg(test)]
mod tests;
