//! MATLAB `.mat` files: the version 5/7 reader's input made safe, its numeric arrays read
//! as frames, and et's own version 5 writer.

use std::path::Path;

use nalgebra::DMatrix;

use super::{FramesError, FramesFault, content, only_of_k};

mod fields;
mod structs;
pub use structs::{Numeric, StructArray};

/// A version 5/7 `.mat` as the MATLAB reader is given it: every compressed variable
/// inflated in place, each checked to inflate and all of them together to no more than the
/// data files' limit (matfile reads each to its end, without a limit: a small file could
/// expand to gigabytes), and each int32 array marked int64 (matfile 0.5 expects an int32
/// array's values stored as uint32 and refused the int32 ones scipy's `savemat` writes; as
/// int64 they are read exactly).
fn plain_mat(bytes: &[u8]) -> Result<Vec<u8>, FramesFault> {
    use std::io::Read as _;
    let order = fields::Order::of(bytes);
    let (little, word) = (order.little, |b: &[u8], at: usize| order.word(b, at));
    // An array (miMATRIX, 14) starts with its flags (miUINT32, 8 bytes), the class in the
    // flags word's low byte: int32 (12) becomes int64 (14).
    let mark_int32 = |out: &mut Vec<u8>, start: usize| {
        let class_at = start + 16 + if little { 0 } else { 3 };
        let flags = (
            word(out, start),
            word(out, start + 8),
            word(out, start + 12),
        );
        if flags == (Some(14), Some(6), Some(8))
            && let Some(class) = out.get_mut(class_at)
            && *class == 12
        {
            *class = 14;
        }
    };
    let limit = et_core::text::max_file_bytes();
    let mut out = bytes.get(..128).unwrap_or(bytes).to_vec();
    let mut at = 128;
    while let (Some(kind), Some(size)) = (word(bytes, at), word(bytes, at + 4)) {
        let size = size as usize;
        let start = out.len();
        if kind == 15 {
            let data = bytes
                .get(at + 8..(at + 8).saturating_add(size))
                .ok_or(FramesFault::CutShort)?;
            let left = limit.saturating_sub(start as u64);
            libflate::zlib::Decoder::new(data)
                .map_err(|_| FramesFault::Damaged)?
                .take(left.saturating_add(1))
                .read_to_end(&mut out)
                .map_err(|_| FramesFault::Damaged)?;
            if out.len() as u64 > limit {
                return Err(FramesFault::Inflates(limit));
            }
            at = at.saturating_add(8).saturating_add(size);
        } else {
            // Uncompressed elements are padded to 8 bytes; matfile checks them itself.
            let end = at.saturating_add(8).saturating_add(size.div_ceil(8) * 8);
            out.extend_from_slice(bytes.get(at..end.min(bytes.len())).unwrap_or_default());
            at = end;
        }
        mark_int32(&mut out, start);
    }
    out.extend_from_slice(bytes.get(at..).unwrap_or_default());
    Ok(out)
}

/// The numeric 2-D array `name` of a MATLAB file (or its only one), and what was said.
pub(super) fn mat_matrix(
    path: &Path,
    bytes: &[u8],
    name: Option<&str>,
    k: usize,
) -> Result<(DMatrix<f64>, String), FramesError> {
    if bytes.starts_with(b"MATLAB 7.3") {
        return Err(content(path, 0, FramesFault::Mat73));
    }
    // A version 5 file says its byte order at bytes 126 and 127.
    if !matches!(bytes.get(126..128), Some(b"IM" | b"MI")) {
        return Err(content(path, 0, FramesFault::NoMatHeader));
    }
    let plain = plain_mat(bytes).map_err(|fault| content(path, 0, fault))?;
    let file = parse(path, &plain)?;
    // EIDORS's stimulations, protocols whose patterns are no frames (looked for only where
    // no array is named), and the numeric variables and structs' fields (`vh.meas`) but
    // theirs, one of which is read.
    let stimulations = match name {
        None => structs::struct_arrays(&plain, &STIMULATION),
        Some(_) => Vec::new(),
    };
    let stimulations: Vec<String> = stimulations.into_iter().map(|s| s.name).collect();
    let mut fields = fields::fields(&plain);
    fields.retain(|f| !(stimulations.iter()).any(|s| is_field_of(&f.name, s)));
    // A struct array's field of one vector an element (a loop's `vi(k) = fwd_solve(...)`:
    // `vi.meas`), its vectors the columns of a matrix: its elements are parsed only where the
    // array asked for is none of the others (a file's named frames beside a model's struct
    // arrays were parsed too).
    let named_elsewhere =
        name.is_some_and(|n| file.find_by_name(n).is_some() || fields.iter().any(|f| f.name == n));
    let arrays = match named_elsewhere {
        true => Vec::new(),
        false => stacked_fields(&plain),
    };
    let names: Vec<String> = (file.arrays().iter().map(|a| a.name().to_string()))
        .chain(fields.iter().map(|f| f.name.clone()))
        .chain(arrays.iter().map(|(name, _, _)| name.clone()))
        .collect();
    // A model's nodes beside its stimulation (EIDORS's `fmdl`) read unasked, of no frame's
    // size, are said as the stimulation's file ("variable 'fmdl.nodes' read: 20 x 2 values"
    // was said); a variable of its own is frames, said by its size.
    let beside = (stimulations.first()).filter(|_| {
        name.is_none() && names.len() == 1 && fields.iter().any(|f| f.name == names[0])
    });
    let mut said_chosen = String::new();
    let chosen = match (name, names.as_slice()) {
        (Some(n), _) if names.iter().any(|m| m == n) => n.to_string(),
        (Some(n), _) => {
            let name = n.to_string();
            return Err(content(path, 0, FramesFault::NoVariable { name, names }));
        }
        (None, [only]) => only.clone(),
        (None, []) if let Some(name) = stimulations.first() => {
            return Err(stimulation(path, name));
        }
        (None, []) => {
            let kind = "numeric arrays";
            return Err(content(path, 0, FramesFault::Nothing { kind }));
        }
        // (The shapes, fields read alone, only where one is to be chosen.)
        (None, _)
            if let Some((name, said)) =
                only_of_k(&shapes_of(path, &plain, &file, &fields, &arrays), k) =>
        {
            said_chosen = said;
            name
        }
        (None, _) => {
            let fault = FramesFault::Choose {
                names,
                kind: "numeric arrays",
                path: path.into(),
                placeholder: "VARIABLE",
            };
            return Err(content(path, 0, fault));
        }
    };
    if let Some((name, n, vectors)) = (arrays.iter()).find(|(name, _, _)| *name == chosen)
        && file.find_by_name(&chosen).is_none()
    {
        let m = stacked(*n, vectors);
        let said = format!(
            "struct array '{}''s field '{}', {} elements of {} values, {said_chosen}",
            name.rsplit_once('.').map_or("", |(a, _)| a),
            name.rsplit_once('.').map_or("", |(_, f)| f),
            m.ncols(),
            m.nrows()
        );
        return Ok((m, said));
    }
    // A struct's field is read as a variable of its own, named by its dotted name.
    let field = match fields.iter().find(|f| f.name == chosen) {
        Some(f) if file.find_by_name(&chosen).is_none() => {
            let alone = fields::alone(&plain, f)
                .ok_or_else(|| content(path, 0, FramesFault::MatInconsistent))?;
            Some(parse(path, &alone)?)
        }
        _ => None,
    };
    let array = field
        .as_ref()
        .unwrap_or(&file)
        .find_by_name(&chosen)
        .ok_or_else(|| content(path, 0, FramesFault::MatInconsistent))?;
    let Some(values) = real_values(array) else {
        let fault = FramesFault::NotReal(array.name().to_string());
        return Err(content(path, 0, fault));
    };
    let m = matrix_of(path, array, &values, beside.map(|n| (n.as_str(), k)))?;
    Ok((m, format!("variable '{}', {said_chosen}", array.name())))
}

/// Each candidate array's name and shape where known: the variables', the 1 x 1 structs'
/// fields' (read from the field alone, so that the one array of K values is found beside a
/// model's `fmdl.nodes`: "name one" was asked) and the struct arrays' stacked fields'.
fn shapes_of(
    path: &Path,
    plain: &[u8],
    file: &matfile::MatFile,
    fields: &[fields::Field],
    arrays: &[Stacked],
) -> Vec<(String, Option<Vec<usize>>)> {
    let field_shape = |f: &fields::Field| {
        let alone = fields::alone(plain, f)?;
        let file = parse(path, &alone).ok()?;
        Some(file.find_by_name(&f.name)?.size().clone())
    };
    (file.arrays().iter())
        .map(|a| (a.name().to_string(), Some(a.size().clone())))
        .chain(fields.iter().map(|f| (f.name.clone(), field_shape(f))))
        .chain((arrays.iter()).map(|(name, n, v)| (name.clone(), Some(vec![*n, v.len()]))))
        .collect()
}

/// `array`'s `values` as its matrix (2-D, MATLAB's order by columns); where it was read
/// unasked beside a stimulation (its name, and K), one of no frame's size is said as the
/// stimulation's file.
fn matrix_of(
    path: &Path,
    array: &matfile::Array,
    values: &[f64],
    beside: Option<(&str, usize)>,
) -> Result<DMatrix<f64>, FramesError> {
    let (rows, cols) = match array.size().as_slice() {
        [r, c] => (*r, *c),
        other => {
            let (name, dimensions) = (array.name().to_string(), other.len());
            return Err(content(
                path,
                0,
                FramesFault::Dimensions { name, dimensions },
            ));
        }
    };
    if let Some((name, k)) = beside
        && rows != k
        && cols != k
    {
        return Err(stimulation(path, name));
    }
    if rows * cols != values.len() {
        let fault = FramesFault::Size {
            name: array.name().to_string(),
            rows,
            columns: cols,
            values: values.len(),
        };
        return Err(content(path, 0, fault));
    }
    Ok(DMatrix::from_column_slice(rows, cols, values))
}

/// Whether the dotted name `field` is a field of `array` (`stim.stim_pattern` of `stim`).
fn is_field_of(field: &str, array: &str) -> bool {
    field
        .strip_prefix(array)
        .is_some_and(|rest| rest.starts_with('.'))
}

/// `array`'s values as doubles, in MATLAB's order (by columns); None for complex values or
/// another class.
fn real_values(array: &matfile::Array) -> Option<Vec<f64>> {
    use matfile::NumericData as D;
    Some(match array.data() {
        D::Double { real, imag: None } => real.clone(),
        D::Single { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::Int8 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::UInt8 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::Int16 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::UInt16 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::Int32 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        D::UInt32 { real, imag: None } => real.iter().map(|&v| f64::from(v)).collect(),
        // Exact below 2^53 (numpy's default integers are int64).
        D::Int64 { real, imag: None } => real.iter().map(|&v| v as f64).collect(),
        D::UInt64 { real, imag: None } => real.iter().map(|&v| v as f64).collect(),
        _ => return None,
    })
}

/// The error of `path`, a file of EIDORS's stimulation `name` and no frames.
fn stimulation(path: &Path, name: &str) -> FramesError {
    let (file, name) = (path.display().to_string(), name.to_string());
    content(path, 0, FramesFault::Stimulation { file, name })
}

/// The struct array `name` of a MATLAB file having every field of `wanted` (or its only
/// one), and what was said.
pub(super) fn mat_struct_array(
    path: &Path,
    bytes: &[u8],
    name: Option<&str>,
    wanted: &[&str],
) -> Result<(StructArray, String), FramesError> {
    if bytes.starts_with(b"MATLAB 7.3") {
        return Err(content(path, 0, FramesFault::Mat73Struct));
    }
    if !matches!(bytes.get(126..128), Some(b"IM" | b"MI")) {
        // A file of another kind, or text (a protocol file, a list of pairs), said as what it
        // is: only MATLAB keeps struct arrays.
        let what = match et_core::text::binary_kind(bytes) {
            Some((what, _)) => what.to_string(),
            None if bytes.is_empty() => "an empty file".to_string(),
            // (Its first 4 KB: a character cut at their end is still text.)
            None if !bytes.iter().take(4096).any(|&b| b == 0)
                && std::str::from_utf8(bytes.get(..bytes.len().min(4096)).unwrap_or(bytes))
                    .map_or_else(|e| e.error_len().is_none(), |_| true) =>
            {
                "text".to_string()
            }
            None => return Err(content(path, 0, FramesFault::NoMatHeader)),
        };
        return Err(content(path, 0, FramesFault::NotMatStruct(what)));
    }
    let plain = plain_mat(bytes).map_err(|fault| content(path, 0, fault))?;
    let mut found = structs::struct_arrays(&plain, wanted);
    let names: Vec<String> = found.iter().map(|s| s.name.clone()).collect();
    let fields = wanted.join(" and ");
    let at = match (name, found.len()) {
        (Some(n), _) => names.iter().position(|m| m == n),
        (None, 1) => Some(0),
        (None, 0) => None,
        (None, _) => {
            let fault = FramesFault::Choose {
                names,
                kind: "struct arrays",
                path: path.into(),
                placeholder: "NAME",
            };
            return Err(content(path, 0, fault));
        }
    };
    let Some(at) = at else {
        let name = name.map(str::to_string);
        let fault = FramesFault::NoStructArray {
            name,
            fields,
            names,
        };
        return Err(content(path, 0, fault));
    };
    let array = found.swap_remove(at);
    let said = format!(
        "struct array '{}' of {} elements with {fields}",
        array.name,
        array.elements.len()
    );
    Ok((array, said))
}

/// The fields of EIDORS's stimulation struct array, a protocol's patterns.
pub(crate) const STIMULATION: [&str; 2] = ["stim_pattern", "meas_pattern"];

/// A struct array's field of a vector an element: its dotted name, n, and the vectors.
type Stacked = (String, usize, Vec<Numeric>);

/// Each field of the struct arrays of `plain` (a version 5 file, inflated) that holds a
/// vector of one length n in every element, by its dotted name (`vi.meas`): n and the
/// vectors, at most as many values in all as the file has bytes (a sparse vector's length
/// is a claim). EIDORS's stimulations' patterns are not frames, and are left out
/// (`stim.stim_pattern` was read as 16 frames).
fn stacked_fields(plain: &[u8]) -> Vec<Stacked> {
    let mut out = Vec::new();
    for array in structs::struct_arrays(plain, &[]) {
        if STIMULATION
            .iter()
            .all(|f| array.fields.iter().any(|g| g == f))
        {
            continue;
        }
        let mut columns: Vec<Vec<Option<Numeric>>> = vec![Vec::new(); array.fields.len()];
        for element in array.elements {
            for (i, value) in element.into_iter().enumerate() {
                if let Some(column) = columns.get_mut(i) {
                    column.push(value);
                }
            }
        }
        for (field, column) in array.fields.iter().zip(columns) {
            let vectors: Option<Vec<Numeric>> = (column.into_iter())
                .map(|v| v.filter(|v| v.rows == 1 || v.columns == 1))
                .collect();
            let Some(vectors) = vectors else { continue };
            let n = vectors
                .first()
                .map_or(0, |v| v.rows.saturating_mul(v.columns));
            let values = n.saturating_mul(vectors.len());
            if n == 0 || values > plain.len() || vectors.iter().any(|v| v.rows * v.columns != n) {
                continue;
            }
            out.push((format!("{}.{field}", array.name), n, vectors));
        }
    }
    out
}

/// `vectors` (each of `n` values) as the columns of a matrix.
fn stacked(n: usize, vectors: &[Numeric]) -> DMatrix<f64> {
    let mut m = DMatrix::zeros(n, vectors.len());
    for (j, v) in vectors.iter().enumerate() {
        for &(r, c, x) in &v.nonzero {
            m[(r + c, j)] = x;
        }
    }
    m
}

/// The names of `bytes`' struct arrays having every field of `wanted` (none for a file that
/// is no version 5 or 7 MATLAB file).
pub(super) fn struct_array_names(bytes: &[u8], wanted: &[&str]) -> Vec<String> {
    if !matches!(bytes.get(126..128), Some(b"IM" | b"MI")) {
        return Vec::new();
    }
    let Ok(plain) = plain_mat(bytes) else {
        return Vec::new();
    };
    (structs::struct_arrays(&plain, wanted).into_iter())
        .map(|s| s.name)
        .collect()
}

/// The MATLAB reader's reading of `bytes` (a version 5 file, compressed variables inflated).
fn parse(path: &Path, bytes: &[u8]) -> Result<matfile::MatFile, FramesError> {
    // It panics on some damaged headers (a dimension product that overflows, found by the
    // fuzzer): such a file is refused like any other it cannot read, silently for the panic
    // itself.
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let parsed = std::panic::catch_unwind(|| matfile::MatFile::parse(bytes));
    std::panic::set_hook(hook);
    match parsed {
        Ok(Ok(file)) => Ok(file),
        Ok(Err(e)) => Err(content(path, 0, FramesFault::NotMat(e))),
        Err(_) => Err(content(path, 0, FramesFault::MatInconsistent)),
    }
}

/// A MATLAB version 5 file holding the double matrix `m` as variable `name` (uncompressed;
/// MATLAB's `load`, SciPy's `loadmat` and [`read`](super::read) take it): how et writes
/// frames for MATLAB users and its tests write other systems' `.mat` files.
#[must_use]
pub fn mat_v5(name: &str, m: &DMatrix<f64>) -> Vec<u8> {
    fn element(out: &mut Vec<u8>, kind: u32, data: &[u8]) {
        out.extend(kind.to_le_bytes());
        out.extend(u32::try_from(data.len()).unwrap_or(u32::MAX).to_le_bytes());
        out.extend(data);
        out.resize(out.len().next_multiple_of(8), 0);
    }
    let (rows, cols) = m.shape();
    let mut body = Vec::new();
    // Array flags: class double (6); dimensions (int32); name (int8); real part (double).
    element(&mut body, 6, &[6, 0, 0, 0, 0, 0, 0, 0]);
    let dims: Vec<u8> = [rows, cols]
        .iter()
        .flat_map(|d| i32::try_from(*d).unwrap_or(i32::MAX).to_le_bytes())
        .collect();
    element(&mut body, 5, &dims);
    element(&mut body, 1, name.as_bytes());
    let values: Vec<u8> = m.iter().flat_map(|v| v.to_le_bytes()).collect();
    element(&mut body, 9, &values);
    let mut out =
        format!("MATLAB 5.0 MAT-file, written by et: {name} ({rows} x {cols})").into_bytes();
    out.resize(116, b' ');
    out.extend([0u8; 8]);
    out.extend(0x0100u16.to_le_bytes());
    out.extend(b"IM");
    element(&mut out, 14, &body);
    out
}
