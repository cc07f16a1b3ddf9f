//! Datasets on disk: CSV that Python and MATLAB read as they are, or the same content as a
//! NumPy `.npz` archive that loads at disk speed ([`save_npz`], [`load_npz`]; [`save`] and
//! [`load`] choose by the file's extension).
//!
//! ```text
//! # et-dataset 2
//! # units: SI: features and untouched in V, positions and centres in m, pressure in Pa
//! # config: {"electrodes":16,"protocol":"Opposite",...}      (scan settings, JSON)
//! # feature_index: 0 1 2 4 ...                                (frame index of each feature)
//! # centres_m: 0.0093 0.0093; 0.0279 0.0093; ...              (class centres)
//! # electrodes_m: 0.0041 0; 0.0122 0; ...                     (optional: nominal electrode centres)
//! # untouched: 0.0121 ...; 0.0119 ...                        (optional: each visit's untouched frame, V)
//! # provenance: sim sheet 13 x 13 cm, seed 1, T=6 S_num=20 S_sub=20
//! f0,f1,...,f95,label,x_m,y_m,visit,pressure_pa               (pressure_pa optional)
//! 0.0123,...,3,0.0271,0.0088,0,23500
//! ```
//!
//! Every number in the file is in SI units, as in the `.npz` and the recordings (mm and kPa
//! are for what people read: plots, reports, printed positions). Version 1 files (`x_mm`,
//! `y_mm`, `pressure_kpa`, `centres_mm`, `electrodes_mm`) are read as well, converted.
//!
//! Python: `numpy.loadtxt(path, delimiter=",", comments="#", skiprows=...)` or the `csv`
//! module skipping `#` lines; MATLAB: `readmatrix(path, "CommentStyle", "#")`.
//!
//! [`import_csv`] brings data from other sensors: any channel count, a header row or none,
//! a UTF-8 byte-order mark, CRLF line ends; the columns named `label` (class, any text) or `x`
//! and `y` (position, and `z`, `force` or `pressure` as a third target) are targets and all
//! others are features; targets may also come from a second file with the same rows (without
//! a header: one column is a label, two or more are x, y and a third target, e.g. z or force;
//! further columns unused).

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::{Path, PathBuf};

use et_core::ScanConfig;
use nalgebra::DMatrix;

use super::collect::Dataset;
use super::npz;

/// Why a dataset file could not be read or written.
#[derive(Debug)]
#[non_exhaustive]
pub enum DatasetError {
    /// The file could not be read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// Something in the file is wrong.
    Content {
        /// The file.
        path: PathBuf,
        /// 1-based line (0 when not about one line).
        line: usize,
        /// Column name or number, where it is about one.
        column: Option<String>,
        /// What is wrong.
        message: String,
    },
}

impl std::fmt::Display for DatasetError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DatasetError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            DatasetError::Content {
                path,
                line,
                column,
                message,
            } => {
                write!(f, "{}", path.display())?;
                if *line > 0 {
                    write!(f, ":{line}")?;
                }
                if let Some(c) = column {
                    write!(f, ", column {c}")?;
                }
                write!(f, ": {message}")
            }
        }
    }
}

impl std::error::Error for DatasetError {}

fn content(
    path: &Path,
    line: usize,
    column: Option<String>,
    message: impl Into<String>,
) -> DatasetError {
    DatasetError::Content {
        path: path.into(),
        line,
        column,
        message: message.into(),
    }
}

/// Writes `data` as CSV (see the module docs), with a free-text `provenance` line.
///
/// # Errors
/// [`DatasetError::Io`].
pub fn save_csv(data: &Dataset, path: &Path, provenance: &str) -> Result<(), DatasetError> {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(s, "{FORMAT_2}");
    let _ = writeln!(s, "{UNITS}");
    let _ = writeln!(
        s,
        "# config: {}",
        serde_json::to_string(&data.config).unwrap_or_default()
    );
    let idx: Vec<String> = data.feature_index.iter().map(u16::to_string).collect();
    let _ = writeln!(s, "# feature_index: {}", idx.join(" "));
    let centres: Vec<String> = data
        .centres
        .iter()
        .map(|c| format!("{} {}", c[0], c[1]))
        .collect();
    let _ = writeln!(s, "# centres_m: {}", centres.join("; "));
    if !data.electrodes.is_empty() {
        let e: Vec<String> = data
            .electrodes
            .iter()
            .map(|c| format!("{} {}", c[0], c[1]))
            .collect();
        let _ = writeln!(s, "# electrodes_m: {}", e.join("; "));
    }
    if data.baselines.nrows() > 0 {
        let frames: Vec<String> = data
            .baselines
            .row_iter()
            .map(|r| r.iter().map(f64::to_string).collect::<Vec<_>>().join(" "))
            .collect();
        let _ = writeln!(s, "# untouched: {}", frames.join("; "));
    }
    let _ = writeln!(s, "# provenance: {}", provenance.replace('\n', " "));
    let mut header: Vec<String> = (0..data.x.ncols()).map(|j| format!("f{j}")).collect();
    header.extend(["label", "x_m", "y_m", "visit"].map(String::from));
    let with_pressure = data.pressure.len() == data.x.nrows();
    if with_pressure {
        header.push("pressure_pa".into());
    }
    let _ = writeln!(s, "{}", header.join(","));
    let rows = data
        .x
        .row_iter()
        .zip(&data.positions)
        .zip(data.y.iter().zip(&data.visit));
    for (r, ((features, p), (label, visit))) in rows.enumerate() {
        for v in &features {
            let _ = write!(s, "{v},");
        }
        let _ = write!(s, "{label},{},{},{visit}", p[0], p[1]);
        if let Some(pa) = data.pressure.get(r).filter(|_| with_pressure) {
            let _ = write!(s, ",{pa}");
        }
        s.push('\n');
    }
    std::fs::write(path, s).map_err(|source| DatasetError::Io {
        path: path.into(),
        source,
    })
}

/// Parses whitespace-separated finite numbers of a `field`.
fn numbers(path: &Path, line: usize, field: &str, text: &str) -> Result<Vec<f64>, DatasetError> {
    text.split_whitespace()
        .map(|v| {
            v.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    content(
                        path,
                        line,
                        None,
                        format!("{field}: '{v}' is not a finite number"),
                    )
                })
        })
        .collect()
}

/// The first line of a dataset file: the format and its version.
const FORMAT_2: &str = "# et-dataset 2";
/// Version 1: positions in mm and pressure in kPa (still read).
const FORMAT_1: &str = "# et-dataset 1";
/// The second line: what the numbers are in.
const UNITS: &str =
    "# units: SI: features and untouched in V, positions and centres in m, pressure in Pa";

/// Parses `x y; x y; ...` (finite numbers) into metres, `per_unit` metres to the file's unit.
fn points(
    path: &Path,
    line: usize,
    field: &str,
    list: &str,
    per_unit: f64,
) -> Result<Vec<[f64; 2]>, DatasetError> {
    list.split(';')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| match numbers(path, line, field, pair)?[..] {
            [x, y] => Ok([x * per_unit, y * per_unit]),
            _ => Err(content(
                path,
                line,
                None,
                format!("{field}: each point is 'x y'"),
            )),
        })
        .collect()
}

/// Reads a dataset written by [`save_csv`].
///
/// # Errors
/// [`DatasetError`] naming the file, line and column.
pub fn load_csv(path: &Path) -> Result<Dataset, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|source| DatasetError::Io {
        path: path.into(),
        source,
    })?;
    let mut config: Option<ScanConfig> = None;
    let mut feature_index = Vec::new();
    let mut centres = Vec::new();
    let mut untouched: Vec<Vec<f64>> = Vec::new();
    let mut electrodes = Vec::new();
    let mut lines = text.lines().enumerate().peekable();
    match lines.next() {
        Some((_, l)) if [FORMAT_1, FORMAT_2].contains(&l.trim()) => {}
        _ => {
            return Err(content(
                path,
                1,
                None,
                format!("not an et dataset (expected '{FORMAT_2}', or version 1)"),
            ));
        }
    }
    while let Some((i, l)) = lines.peek().copied() {
        let Some(meta) = l.strip_prefix('#') else {
            break;
        };
        lines.next();
        let meta = meta.trim();
        if let Some(json) = meta.strip_prefix("config:") {
            config = Some(
                serde_json::from_str(json.trim())
                    .map_err(|e| content(path, i + 1, None, format!("config: {e}")))?,
            );
        } else if let Some(list) = meta.strip_prefix("feature_index:") {
            feature_index = list
                .split_whitespace()
                .map(|v| {
                    v.parse::<u16>()
                        .map_err(|e| content(path, i + 1, None, format!("feature_index: {e}")))
                })
                .collect::<Result<_, _>>()?;
        } else if let Some(list) = meta.strip_prefix("untouched:") {
            for frame in list.split(';').filter(|p| !p.trim().is_empty()) {
                untouched.push(numbers(path, i + 1, "untouched", frame)?);
            }
        } else if let Some(list) = meta.strip_prefix("electrodes_m:") {
            electrodes = points(path, i + 1, "electrodes_m", list, 1.0)?;
        } else if let Some(list) = meta.strip_prefix("centres_m:") {
            centres = points(path, i + 1, "centres_m", list, 1.0)?;
        } else if let Some(list) = meta.strip_prefix("electrodes_mm:") {
            electrodes = points(path, i + 1, "electrodes_mm", list, 1e-3)?;
        } else if let Some(list) = meta.strip_prefix("centres_mm:") {
            centres = points(path, i + 1, "centres_mm", list, 1e-3)?;
        }
    }
    let config = config.ok_or_else(|| content(path, 0, None, "no '# config:' line"))?;
    let rest: Vec<(usize, &str)> = lines.collect();
    let table = parse_table(path, &rest, &|_, _| false)?;
    let col = |name: &str| {
        table
            .names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| content(path, 0, Some(name.into()), "column missing"))
    };
    // SI columns, or version 1's mm and kPa (metres and pascals per the file's unit).
    let either = |si: &str, old: &str, per_unit: f64| match col(si) {
        Ok(c) => Ok((c, 1.0)),
        Err(e) => col(old).map(|c| (c, per_unit)).map_err(|_| e),
    };
    let (label, visit) = (col("label")?, col("visit")?);
    let ((xc, x_unit), (yc, y_unit)) = (either("x_m", "x_mm", 1e-3)?, either("y_m", "y_mm", 1e-3)?);
    let pressure = either("pressure_pa", "pressure_kpa", 1e3).ok();
    let pressure_col = pressure.map(|p| p.0);
    let features: Vec<usize> = (0..table.names.len())
        .filter(|&c| ![label, xc, yc, visit].contains(&c) && Some(c) != pressure_col)
        .collect();
    if feature_index.len() != features.len() {
        return Err(content(
            path,
            0,
            None,
            format!(
                "{} feature columns, {} in feature_index",
                features.len(),
                feature_index.len()
            ),
        ));
    }
    if let Some((bad, u)) = untouched
        .iter()
        .enumerate()
        .find(|(_, u)| u.len() != features.len())
    {
        return Err(content(
            path,
            0,
            None,
            format!(
                "untouched frame {bad} has {} values, the data {} features",
                u.len(),
                features.len()
            ),
        ));
    }
    let p = features.len();
    let baselines =
        DMatrix::from_row_iterator(untouched.len(), p, untouched.iter().flatten().copied());
    let column = |c| table.column(path, c);
    let x = table.matrix(path, &features)?;
    let y = table.whole(path, label)?;
    let visit = table.whole(path, visit)?;
    let positions = column(xc)?
        .into_iter()
        .zip(column(yc)?)
        .map(|(x, y)| [x * x_unit, y * y_unit])
        .collect();
    let pressure = match pressure {
        Some((c, unit)) => column(c)?.into_iter().map(|p| p * unit).collect(),
        None => Vec::new(),
    };
    Ok(Dataset {
        x,
        y,
        positions,
        pressure,
        electrodes,
        centres,
        visit,
        baselines,
        feature_index,
        config,
    })
}

/// Writes `data` as a NumPy `.npz` archive with the same content as [`save_csv`], in SI units
/// (the names say so) and at disk speed:
///
/// | array | shape, type | content |
/// | --- | --- | --- |
/// | `format` | text | `et-dataset 1` (the `.npz` was SI from the start) |
/// | `x` | n x p, float64 | features, volts |
/// | `label` | n, uint16 | class |
/// | `position_m` | n x 2, float64 | where the finger pressed, m |
/// | `visit` | n, uint16 | visit (session) of each row |
/// | `pressure_pa` | n or 0, float64 | pressure of each touch, Pa (empty when unknown) |
/// | `feature_index` | p, uint16 | frame index of each feature |
/// | `centres_m` | C x 2, float64 | class centres, m |
/// | `electrodes_m` | L x 2, float64 | nominal electrode centres, m (0 rows when unknown) |
/// | `untouched` | T x p, float64 | each visit's untouched frame, volts |
/// | `config` | text | the scan settings, JSON |
/// | `provenance` | text | what made it |
///
/// Python: `d = numpy.load(path); d["x"], d["label"], json.loads(str(d["config"]))`.
///
/// # Errors
/// [`DatasetError::Io`], or [`DatasetError::Content`] for a set over 4 GiB.
pub fn save_npz(data: &Dataset, path: &Path, provenance: &str) -> Result<(), DatasetError> {
    let mut w = npz::Writer::new();
    w.text("format", "et-dataset 1");
    w.matrix("x", &data.x);
    w.u16s("label", &data.y);
    w.pairs("position_m", &data.positions);
    w.u16s("visit", &data.visit);
    w.f64s("pressure_pa", &data.pressure);
    w.u16s("feature_index", &data.feature_index);
    w.pairs("centres_m", &data.centres);
    w.pairs("electrodes_m", &data.electrodes);
    w.matrix("untouched", &data.baselines);
    w.text(
        "config",
        &serde_json::to_string(&data.config).unwrap_or_default(),
    );
    w.text("provenance", provenance);
    let bytes = w
        .finish()
        .map_err(|e| content(path, 0, None, e.to_string()))?;
    std::fs::write(path, bytes).map_err(|source| DatasetError::Io {
        path: path.into(),
        source,
    })
}

/// Reads a dataset written by [`save_npz`] (or by numpy with the same arrays).
///
/// # Errors
/// [`DatasetError`] naming the file and the array at fault.
pub fn load_npz(path: &Path) -> Result<Dataset, DatasetError> {
    let bytes = std::fs::read(path).map_err(|source| DatasetError::Io {
        path: path.into(),
        source,
    })?;
    let bad = |e: npz::NpzError| content(path, 0, None, e.to_string());
    let z = npz::Npz::read(bytes).map_err(bad)?;
    let fault = |array: &str, message: String| {
        content(path, 0, None, format!("array '{array}': {message}"))
    };
    if z.text("format").map_err(bad)? != "et-dataset 1" {
        return Err(fault("format", "not an et dataset ('et-dataset 1')".into()));
    }
    let config: ScanConfig = serde_json::from_str(&z.text("config").map_err(bad)?)
        .map_err(|e| fault("config", e.to_string()))?;
    let x = z.matrix("x").map_err(bad)?;
    let (n, p) = x.shape();
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(fault(
            "x",
            format!("row {}, column {} is not a finite number", i % n, i / n),
        ));
    }
    let pairs = |name: &str, rows: Option<usize>| {
        let m = z.matrix(name).map_err(bad)?;
        if m.ncols() != 2 || rows.is_some_and(|r| r != m.nrows()) {
            return Err(fault(
                name,
                format!(
                    "shape {} x {}, expected {} x 2",
                    m.nrows(),
                    m.ncols(),
                    rows.map_or("any".into(), |r| r.to_string())
                ),
            ));
        }
        if m.iter().any(|v| !v.is_finite()) {
            return Err(fault(
                name,
                "holds a value that is not a finite number".into(),
            ));
        }
        Ok(m.column(0)
            .iter()
            .zip(m.column(1).iter())
            .map(|(&x, &y)| [x, y])
            .collect::<Vec<_>>())
    };
    let rows = |name: &str, len: usize, want: usize| {
        if len == want {
            Ok(())
        } else {
            Err(fault(name, format!("{len} values, x has {want} rows")))
        }
    };
    let y = z.whole("label").map_err(bad)?;
    rows("label", y.len(), n)?;
    let visit = z.whole("visit").map_err(bad)?;
    rows("visit", visit.len(), n)?;
    let pressure = z.vector("pressure_pa").map_err(bad)?;
    if !pressure.is_empty() {
        rows("pressure_pa", pressure.len(), n)?;
    }
    let feature_index = z.whole("feature_index").map_err(bad)?;
    if feature_index.len() != p {
        return Err(fault(
            "feature_index",
            format!("{} values, x has {p} columns", feature_index.len()),
        ));
    }
    let baselines = z.matrix("untouched").map_err(bad)?;
    if baselines.nrows() > 0 && baselines.ncols() != p {
        return Err(fault(
            "untouched",
            format!("{} columns, x has {p}", baselines.ncols()),
        ));
    }
    Ok(Dataset {
        positions: pairs("position_m", Some(n))?,
        centres: pairs("centres_m", None)?,
        electrodes: pairs("electrodes_m", None)?,
        x,
        y,
        pressure,
        visit,
        baselines,
        feature_index,
        config,
    })
}

/// Whether `path` names an `.npz` dataset (else CSV).
fn is_npz(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("npz"))
}

/// Writes `data` as `.npz` when `path` ends so ([`save_npz`]), else as CSV ([`save_csv`]).
///
/// # Errors
/// As those.
pub fn save(data: &Dataset, path: &Path, provenance: &str) -> Result<(), DatasetError> {
    if is_npz(path) {
        save_npz(data, path, provenance)
    } else {
        save_csv(data, path, provenance)
    }
}

/// Reads an `.npz` dataset when `path` ends so ([`load_npz`]), else CSV ([`load_csv`]).
///
/// # Errors
/// As those.
pub fn load(path: &Path) -> Result<Dataset, DatasetError> {
    if is_npz(path) {
        load_npz(path)
    } else {
        load_csv(path)
    }
}

struct Table {
    names: Vec<String>,
    /// Whether the names came from a header row (else they are the column numbers, 1-based).
    header: bool,
    /// (1-based line, values): every row has a value for every name (`parse_table` checks);
    /// NaN in a text column.
    rows: Vec<(usize, Vec<f64>)>,
    /// Per column: its cells as written, for the columns that may hold text (class labels).
    text: Vec<Option<Vec<String>>>,
}

impl Table {
    /// Column `c` of every row.
    fn column(&self, path: &Path, c: usize) -> Result<Vec<f64>, DatasetError> {
        self.rows
            .iter()
            .map(|(line, v)| {
                v.get(c).copied().filter(|v| v.is_finite()).ok_or_else(|| {
                    content(
                        path,
                        *line,
                        self.names.get(c).cloned(),
                        "missing or not a finite number",
                    )
                })
            })
            .collect()
    }

    /// Column `c` as written (labels: any text, numbers as their text).
    fn text_column(&self, path: &Path, c: usize) -> Result<Vec<String>, DatasetError> {
        match self.text.get(c) {
            Some(Some(t)) => Ok(t.clone()),
            _ => Err(content(
                path,
                0,
                self.names.get(c).cloned(),
                "not kept as text",
            )),
        }
    }

    /// Columns `cols`, as an n x cols.len() matrix.
    fn matrix(&self, path: &Path, cols: &[usize]) -> Result<DMatrix<f64>, DatasetError> {
        let mut x = DMatrix::zeros(self.rows.len(), cols.len());
        for (j, &c) in cols.iter().enumerate() {
            x.set_column(j, &nalgebra::DVector::from_vec(self.column(path, c)?));
        }
        Ok(x)
    }

    /// Column `c` as whole numbers 0..=65535 (class labels, visits).
    fn whole(&self, path: &Path, c: usize) -> Result<Vec<u16>, DatasetError> {
        self.column(path, c)?
            .into_iter()
            .zip(&self.rows)
            .map(|(v, (line, _))| {
                if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u16::MAX) {
                    Ok(v as u16)
                } else {
                    Err(content(
                        path,
                        *line,
                        self.names.get(c).cloned(),
                        format!("{v} is not a whole number from 0 to 65535"),
                    ))
                }
            })
            .collect()
    }
}

/// Whether a cell reads as a number.
fn is_number(cell: &str) -> bool {
    cell.trim().parse::<f64>().is_ok()
}

/// An optional header row, then numeric rows; blank and `#` lines skipped; every value finite.
/// The first row is a header when it has a cell that is not a number, unless the second row
/// has text in exactly the same columns (a headerless file with text labels). `text_ok(name,
/// columns)` says which columns may hold text (kept as written besides their numbers).
fn parse_table(
    path: &Path,
    lines: &[(usize, &str)],
    text_ok: &dyn Fn(&str, usize) -> bool,
) -> Result<Table, DatasetError> {
    let mut it = lines
        .iter()
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .peekable();
    let &&(hl, first) = it.peek().ok_or_else(|| content(path, 0, None, "no rows"))?;
    let texts = |l: &str| -> Vec<bool> { l.split(',').map(|c| !is_number(c)).collect() };
    let first_text = texts(first);
    let second_text = it.clone().nth(1).map(|&(_, l)| texts(l));
    let header =
        first_text.iter().any(|&t| t) && second_text.is_none_or(|second| second != first_text);
    let names: Vec<String> = if header {
        it.next();
        first.split(',').map(|s| s.trim().to_string()).collect()
    } else {
        (1..=first.split(',').count())
            .map(|c| c.to_string())
            .collect()
    };
    if names.iter().any(String::is_empty) {
        return Err(content(
            path,
            hl + 1,
            None,
            "empty column name in the header",
        ));
    }
    let keep_text: Vec<bool> = names.iter().map(|n| text_ok(n, names.len())).collect();
    let mut text: Vec<Option<Vec<String>>> = keep_text.iter().map(|&k| k.then(Vec::new)).collect();
    let mut rows = Vec::new();
    for &(i, l) in it {
        let cells: Vec<&str> = l.split(',').collect();
        if cells.len() != names.len() {
            return Err(content(
                path,
                i + 1,
                None,
                format!(
                    "{} values, {} has {} columns",
                    cells.len(),
                    if header {
                        "the header"
                    } else {
                        "the first row"
                    },
                    names.len()
                ),
            ));
        }
        let mut values = Vec::with_capacity(cells.len());
        for ((c, name), t) in cells.iter().zip(&names).zip(text.iter_mut()) {
            let cell = c.trim();
            if let Some(t) = t {
                if cell.is_empty() {
                    return Err(content(path, i + 1, Some(name.clone()), "empty label"));
                }
                t.push(cell.to_string());
                values.push(cell.parse::<f64>().unwrap_or(f64::NAN));
                continue;
            }
            values.push(match cell.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                Ok(v) => {
                    return Err(content(
                        path,
                        i + 1,
                        Some(name.clone()),
                        format!("{v} is not a finite number"),
                    ));
                }
                Err(_) => {
                    return Err(content(
                        path,
                        i + 1,
                        Some(name.clone()),
                        format!("'{cell}' is not a number"),
                    ));
                }
            });
        }
        rows.push((i + 1, values));
    }
    if rows.is_empty() {
        return Err(content(path, 0, None, "no data rows"));
    }
    Ok(Table {
        names,
        header,
        rows,
        text,
    })
}

/// The lines of `text`, without a leading UTF-8 byte-order mark (CRLF ends are handled by
/// `lines`).
fn text_lines(text: &str) -> Vec<(usize, &str)> {
    text.strip_prefix('\u{feff}')
        .unwrap_or(text)
        .lines()
        .enumerate()
        .collect()
}

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
