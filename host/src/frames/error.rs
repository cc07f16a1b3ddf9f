//! Why frames could not be read, in words that name the file, the line or array, and the fix.

use std::path::PathBuf;

use et_learn::npz::NpzError;

use super::{Single, csv_frames, other_protocol};

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
    /// A JSON file that is not an array of frames (what is wrong, where).
    #[error("{0}")]
    Json(String),
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
        "{}{rows} x {columns} values: the protocol has K = {k} values per frame, so one \
         dimension must be {k} ({})",
        chosen.as_ref().map(|c| format!("{c} read: ")).unwrap_or_default(),
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
        /// The array read where the file has several and none was named (`variable 'v'`).
        chosen: Option<String>,
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
    /// A MATLAB 7.3 file where a struct array is read.
    #[error(
        "a MATLAB 7.3 file (HDF5), which et does not read: save the struct array with \
         save('stim.mat', 'stim', '-v7')"
    )]
    Mat73Struct,
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
    /// EIDORS's stimulation struct array alone: a protocol, not frames.
    #[error(
        "holds EIDORS's stimulation '{name}' (what mk_stim_patterns returns), a protocol, \
         and no frames: et protocol --stimulation {file}:{name} > protocol.csv writes it as \
         the protocol file a scene names ([scan] protocol = {{ file = \"protocol.csv\" }}); \
         the frames measured under it are another array (EIDORS's data: vi.meas, a frame a \
         column)"
    )]
    Stimulation {
        /// The file, as given.
        file: String,
        /// The struct array.
        name: String,
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
    /// A file of another kind, or text, where a MATLAB file's struct array is read.
    #[error(
        "{0}, not a MATLAB .mat file: EIDORS's stimulation is read from the struct array saved \
         from MATLAB (save('stim.mat', 'stim')); lists or patterns of pairs go to --injections \
         and --measurements, and a protocol file to a scene as it is"
    )]
    NotMatStruct(String),
    /// No struct array of the name, or none with the fields asked for.
    #[error(
        "no struct array {}with the fields {fields}{}",
        name.as_ref().map(|n| format!("'{n}' ")).unwrap_or_default(),
        if names.is_empty() {
            " (EIDORS's fwd_model.stimulation, what mk_stim_patterns returns: save it with \
             save('stim.mat', 'stim'), or the forward model with its name)"
                .to_string()
        } else {
            format!(" (it has: {})", names.join(", "))
        }
    )]
    NoStructArray {
        /// The name asked for.
        name: Option<String>,
        /// The fields asked for, in words.
        fields: String,
        /// The ones there are with those fields.
        names: Vec<String>,
    },
    /// A variable of complex values.
    #[error(
        "'{0}' holds complex values: save the real voltages, the part you mean: the real part \
         (real(V)), the magnitude (abs(V)) or the quadrature (imag(V))"
    )]
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

/// Indices as a list, the first eight and how many more.
pub fn said_list(indices: &[usize]) -> String {
    let shown: Vec<String> = indices.iter().take(8).map(ToString::to_string).collect();
    match indices.len() {
        n if n > 8 => format!("{}, ... ({n} in all)", shown.join(", ")),
        _ => shown.join(", "),
    }
}
