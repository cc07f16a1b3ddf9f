//! The binary arrays frames come in (NumPy's `.npy` and `.npz`, MATLAB's `.mat`), each read
//! by what its first bytes say it is: a file named for one of them and holding another
//! (`scipy.io.savemat('frames.npy', ...)`, a renamed file) is read as what it holds and said
//! so, and one holding text is read as a table; another kind of file is named as what it is.

use std::path::Path;

use et_learn::npz::{Npz, NpzError};
use nalgebra::DMatrix;

use super::{FramesError, FramesFault, content, mat_matrix, only_of_k, table_matrix};

/// The array format `bytes` hold by their first bytes: "npy", "npz" (a zip archive; an Excel
/// workbook is one too, and is named when its arrays are not found) or "mat" (a MATLAB
/// version 5 or 7 header, or 7.3's, which is refused by name).
fn format(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x93NUMPY") {
        Some("npy")
    } else if bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06") {
        Some("npz")
    } else if matches!(bytes.get(126..128), Some(b"IM" | b"MI")) || bytes.starts_with(b"MATLAB 7.3")
    {
        Some("mat")
    } else {
        None
    }
}

/// Whether `bytes` begin as text does: a byte-order mark, or UTF-8 without a NUL byte in
/// their first kilobyte (a character cut at its end allowed).
fn is_text(bytes: &[u8]) -> bool {
    let head = &bytes[..bytes.len().min(1024)];
    if head.starts_with(b"\xEF\xBB\xBF")
        || head.starts_with(b"\xFF\xFE")
        || head.starts_with(b"\xFE\xFF")
    {
        return true;
    }
    // (A character cut at the kilobyte's end is no error in its bytes.)
    let utf8 = std::str::from_utf8(head).map_or_else(|e| e.error_len().is_none(), |_| true);
    !head.is_empty() && !head.contains(&0) && utf8
}

/// The matrix of the array file at `path`, named `.{ext}`, and what is said of it: the array
/// `array` (an `.npz`'s or a `.mat`'s; its only one when None, or its only one of `k`
/// values a frame).
pub(super) fn matrix(
    path: &Path,
    ext: &str,
    array: Option<&str>,
    k: usize,
) -> Result<(DMatrix<f64>, String), FramesError> {
    let bytes =
        et_core::text::read_at_most(path, et_core::text::max_file_bytes()).map_err(|source| {
            FramesError::Io {
                path: path.into(),
                source,
            }
        })?;
    let held = match format(&bytes) {
        Some(held) => held,
        None if is_text(&bytes) => {
            // (From the bytes read: a FIFO is read once.)
            let text = et_core::text::table_text_of(bytes).map_err(|source| FramesError::Io {
                path: path.into(),
                source,
            })?;
            let (matrix, said) = table_matrix(path, &text)?;
            return Ok((
                matrix,
                format!("text, though named .{ext}, read as a table; {said}"),
            ));
        }
        None => {
            if let Some((what, fix)) = et_core::text::binary_kind(&bytes) {
                let (what, fix) = (what.to_string(), fix.to_string());
                let ext = ext.to_string();
                return Err(content(path, 0, FramesFault::OtherKind { what, ext, fix }));
            }
            // Said by the reader of its name (no .npy magic, no MATLAB header).
            ext
        }
    };
    let named = if held == ext {
        String::new()
    } else {
        let what = match held {
            "npy" => "a NumPy .npy array",
            "npz" => "a NumPy .npz archive",
            _ => "a MATLAB .mat file",
        };
        format!("{what} by its first bytes, though named .{ext}; ")
    };
    let npz = |error| FramesError::Npz {
        path: path.into(),
        error,
    };
    let (matrix, said) = match held {
        "npy" => {
            if let Some(name) = array {
                return Err(content(path, 0, FramesFault::NpyName(name.into())));
            }
            let archive = Npz::from_npy(bytes);
            if archive.is_boolean("array") {
                let fault = FramesFault::Booleans("array".into());
                return Err(content(path, 0, fault));
            }
            (npy_matrix(&archive, "array").map_err(npz)?, String::new())
        }
        "npz" => {
            // An Office document is a zip archive too (its parts, no .npy among them).
            let office = bytes.windows(19).any(|w| w == b"[Content_Types].xml");
            let archive = Npz::read(bytes).map_err(npz)?;
            if office && archive.names().next().is_none() {
                let fault = FramesFault::OtherKind {
                    what: "an Excel .xlsx workbook (a zip archive of no arrays)".into(),
                    ext: ext.into(),
                    fix: "save its sheet as CSV (\"CSV UTF-8\")".into(),
                };
                return Err(content(path, 0, fault));
            }
            npz_matrix(path, &archive, array, k)?
        }
        _ => mat_matrix(path, &bytes, array, k)?,
    };
    Ok((matrix, format!("{named}{said}")))
}

/// The array `name` of an `.npz` (or its only one) as a matrix, and what was said of it.
fn npz_matrix(
    path: &Path,
    archive: &Npz,
    name: Option<&str>,
    k: usize,
) -> Result<(DMatrix<f64>, String), FramesError> {
    let names: Vec<&str> = archive.names().collect();
    let shapes: Vec<_> = (names.iter())
        .map(|n| {
            // (Booleans and text are known, and hold no frames.)
            let shape = archive
                .shape(n)
                .map(|(s, numbers)| if numbers { s } else { vec![] });
            ((*n).to_string(), shape)
        })
        .collect();
    let mut chosen = String::new();
    let name = match (name, names.as_slice()) {
        (Some(n), _) => n.to_string(),
        (None, [only]) => (*only).to_string(),
        (None, []) => return Err(content(path, 0, FramesFault::Nothing { kind: "arrays" })),
        (None, _) if let Some((name, said)) = only_of_k(&shapes, k) => {
            chosen = said;
            name
        }
        (None, _) => {
            let fault = FramesFault::Choose {
                names: names.iter().map(|n| (*n).to_string()).collect(),
                kind: "arrays",
                path: path.into(),
                placeholder: "NAME",
            };
            return Err(content(path, 0, fault));
        }
    };
    if archive.is_boolean(&name) {
        return Err(content(path, 0, FramesFault::Booleans(name)));
    }
    let m = npy_matrix(archive, &name).map_err(|error| FramesError::Npz {
        path: path.into(),
        error,
    })?;
    Ok((m, format!("array '{name}', {chosen}")))
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
