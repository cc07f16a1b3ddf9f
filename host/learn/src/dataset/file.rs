//! Datasets on disk: CSV that Python and MATLAB read as they are, or the same content as a
//! NumPy `.npz` archive that loads at disk speed (see the parent module for the format).

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::path::Path;

use et_core::ScanConfig;
use nalgebra::DMatrix;

use super::check::consistent;
use super::table::parse_table;
use super::{Dataset, DatasetError, DatasetFault, content};
use crate::npz;

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
fn numbers(
    path: &Path,
    line: usize,
    field: &'static str,
    text: &str,
) -> Result<Vec<f64>, DatasetError> {
    text.split_whitespace()
        .map(|v| {
            v.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    let cell = v.to_string();
                    content(path, line, None, DatasetFault::HeaderNumber { field, cell })
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
    field: &'static str,
    list: &str,
    per_unit: f64,
) -> Result<Vec<[f64; 2]>, DatasetError> {
    list.split(';')
        .filter(|p| !p.trim().is_empty())
        .map(|pair| match numbers(path, line, field, pair)?[..] {
            [x, y] => Ok([x * per_unit, y * per_unit]),
            _ => Err(content(path, line, None, DatasetFault::NotPoint(field))),
        })
        .collect()
}

/// The `#` lines after a CSV dataset's first line: its scan, features, class centres,
/// untouched frames and electrodes.
struct Header {
    config: ScanConfig,
    feature_index: Vec<u16>,
    centres: Vec<[f64; 2]>,
    untouched: Vec<Vec<f64>>,
    electrodes: Vec<[f64; 2]>,
    /// The `# units:` line's text and its line (1-based), where there is one.
    units: Option<(usize, String)>,
}

impl Header {
    /// Reads the `#` lines from `lines` (0-based numbers), leaving it at the first other line.
    fn read<'t>(
        path: &Path,
        lines: &mut std::iter::Peekable<impl Iterator<Item = (usize, &'t str)>>,
    ) -> Result<Self, DatasetError> {
        let mut config: Option<ScanConfig> = None;
        let mut feature_index = Vec::new();
        let mut centres = Vec::new();
        let mut untouched: Vec<Vec<f64>> = Vec::new();
        let mut electrodes = Vec::new();
        let mut units = None;
        while let Some((i, l)) = lines.peek().copied() {
            let Some(meta) = l.strip_prefix('#') else {
                break;
            };
            lines.next();
            let meta = meta.trim();
            if meta.starts_with("units:") {
                units = Some((i + 1, meta.to_string()));
            }
            if let Some(json) = meta.strip_prefix("config:") {
                // Parsed, then read with each field's name in its error.
                config = Some(
                    serde_json::from_str(json.trim())
                        .and_then(crate::model_file::from_value_named)
                        .map_err(|e| content(path, i + 1, None, DatasetFault::Config(e)))?,
                );
            } else if let Some(list) = meta.strip_prefix("feature_index:") {
                feature_index = list
                    .split_whitespace()
                    .map(|v| {
                        v.parse::<u16>().map_err(|_| {
                            content(path, i + 1, None, DatasetFault::FeatureIndex(v.into()))
                        })
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
        let config = config.ok_or_else(|| content(path, 0, None, DatasetFault::NoConfig))?;
        Ok(Self {
            config,
            feature_index,
            centres,
            untouched,
            electrodes,
            units,
        })
    }
}

/// Reads a dataset written by [`save_csv`].
///
/// # Errors
/// [`DatasetError`] naming the file, line and column.
pub fn load_csv(path: &Path) -> Result<Dataset, DatasetError> {
    // An et dataset is a document of et's own: a file of another kind is said as what it is,
    // not told how to write a table (a .npy given was told to use numpy.savetxt).
    let text = et_core::text::read_document_at_most(path, et_core::text::max_file_bytes())
        .map_err(|source| DatasetError::Io {
            path: path.into(),
            source,
        })?;
    let mut lines = text.lines().enumerate().peekable();
    let version_2 = match lines.next() {
        Some((_, l)) if [FORMAT_1, FORMAT_2].contains(&l.trim()) => l.trim() == FORMAT_2,
        Some((_, l)) if l.trim().starts_with("# et-dataset ") => {
            let version = l.trim()["# et-dataset ".len()..].chars().take(40).collect();
            return Err(content(
                path,
                1,
                None,
                DatasetFault::DatasetVersion(version),
            ));
        }
        other => {
            // JSON naming its format (a recording's header, a model file's first line).
            let format = other
                .and_then(|(_, l)| serde_json::from_str::<serde_json::Value>(l).ok())
                .and_then(|v| Some(v.get("format")?.as_str()?.chars().take(40).collect()));
            return Err(content(path, 1, None, DatasetFault::NotDataset(format)));
        }
    };
    let Header {
        config,
        feature_index,
        centres,
        untouched,
        electrodes,
        units,
    } = Header::read(path, &mut lines)?;
    // A version 2 file's values are in SI, as its units line says: a line edited to say
    // other units would be read as SI all the same.
    if let Some((line, said)) = units.filter(|(_, u)| version_2 && *u != UNITS[2..]) {
        return Err(content(path, line, None, DatasetFault::Units(said)));
    }
    let rest: Vec<(usize, &str)> = lines.collect();
    let table = parse_table(path, &rest, &|_, _| false)?;
    let col = |name: &str| {
        table
            .names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| content(path, 0, Some(name.into()), DatasetFault::ColumnMissing))
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
        let (features, index) = (features.len(), feature_index.len());
        return Err(content(
            path,
            0,
            None,
            DatasetFault::FeatureCount { features, index },
        ));
    }
    if let Some((bad, u)) = untouched
        .iter()
        .enumerate()
        .find(|(_, u)| u.len() != features.len())
    {
        let fault = DatasetFault::UntouchedLength {
            frame: bad,
            values: u.len(),
            features: features.len(),
        };
        return Err(content(path, 0, None, fault));
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
    let bytes = npz_bytes(data, provenance).map_err(|source| DatasetError::Npz {
        path: path.into(),
        source,
    })?;
    std::fs::write(path, bytes).map_err(|source| DatasetError::Io {
        path: path.into(),
        source,
    })
}

/// The `.npz` [`save_npz`] writes, as bytes (how Python pickles a dataset).
///
/// # Errors
/// [`npz::NpzError`] for a set over 4 GiB.
pub fn npz_bytes(data: &Dataset, provenance: &str) -> Result<Vec<u8>, npz::NpzError> {
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
    w.finish()
}

/// Reads a dataset written by [`save_npz`] (or by numpy with the same arrays).
///
/// # Errors
/// [`DatasetError`] naming the file and the array at fault.
pub fn load_npz(path: &Path) -> Result<Dataset, DatasetError> {
    let bytes =
        et_core::text::read_at_most(path, et_core::text::max_file_bytes()).map_err(|source| {
            DatasetError::Io {
                path: path.into(),
                source,
            }
        })?;
    from_npz_bytes(bytes, path)
}

/// A dataset from the bytes of an `.npz` [`save_npz`] writes, checked as [`load_npz`] checks
/// a file; `path` names them in errors (a file, or where the bytes came from).
///
/// # Errors
/// As [`load_npz`].
pub fn from_npz_bytes(bytes: Vec<u8>, path: &Path) -> Result<Dataset, DatasetError> {
    let bad = |source: npz::NpzError| DatasetError::Npz {
        path: path.into(),
        source,
    };
    let z = npz::Npz::read(bytes).map_err(bad)?;
    let fault = |fault| content(path, 0, None, fault);
    if !z.names().any(|n| n == "format") {
        let names = z.names().map(str::to_string).collect();
        return Err(fault(DatasetFault::NotEtNpz(names)));
    }
    if z.text("format").map_err(bad)? != "et-dataset 1" {
        return Err(fault(DatasetFault::NotNpzDataset));
    }
    let config: ScanConfig = serde_json::from_str(&z.text("config").map_err(bad)?)
        .and_then(crate::model_file::from_value_named)
        .map_err(|source| DatasetError::Json {
            path: path.into(),
            array: "config",
            source,
        })?;
    let x = z.matrix("x").map_err(bad)?;
    let (n, p) = x.shape();
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        let (row, column) = (i % n, i / n);
        return Err(fault(DatasetFault::ArrayNotFinite {
            array: "x",
            row,
            column,
        }));
    }
    let pairs = |array: &'static str, want: Option<usize>| {
        let m = z.matrix(array).map_err(bad)?;
        if m.ncols() != 2 || want.is_some_and(|r| r != m.nrows()) {
            let (rows, columns) = m.shape();
            return Err(fault(DatasetFault::ArrayShape {
                array,
                rows,
                columns,
                want,
            }));
        }
        if let Some(i) = m.iter().position(|v| !v.is_finite()) {
            let (row, column) = (i % m.nrows(), i / m.nrows());
            return Err(fault(DatasetFault::ArrayNotFinite { array, row, column }));
        }
        Ok(m.column(0)
            .iter()
            .zip(m.column(1).iter())
            .map(|(&x, &y)| [x, y])
            .collect::<Vec<_>>())
    };
    let rows = |array: &'static str, len: usize, want: usize| {
        if len == want {
            Ok(())
        } else {
            Err(fault(DatasetFault::ArrayLength { array, len, want }))
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
        let (array, len) = ("feature_index", feature_index.len());
        return Err(fault(DatasetFault::ArrayColumns {
            array,
            len,
            want: p,
        }));
    }
    let baselines = z.matrix("untouched").map_err(bad)?;
    if baselines.nrows() > 0 && baselines.ncols() != p {
        let (array, len) = ("untouched", baselines.ncols());
        return Err(fault(DatasetFault::ArrayColumns {
            array,
            len,
            want: p,
        }));
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
    let data = if is_npz(path) {
        load_npz(path)?
    } else {
        load_csv(path)?
    };
    consistent(path, &data)?;
    Ok(data)
}
