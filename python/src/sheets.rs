//! Sheets and protocols from Python: built-in protocols and scene files as tables, and each
//! checked where it is made, as a Reconstructor takes it.

use numpy::{PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;

use et_core::protocol::{Protocol, ProtocolKind};
use et_core::schedule::{Row, Schedule};
use et_core::sheet::Sheet;

use crate::{array2, json, refused, usage};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(protocol_table, m)?)?;
    m.add_function(wrap_pyfunction!(scene_parts, m)?)?;
    m.add_function(wrap_pyfunction!(check_sheet, m)?)?;
    m.add_function(wrap_pyfunction!(check_protocol, m)?)?;
    Ok(())
}

/// The schedule of a built-in protocol, or of rows (source, sink, positive, negative,
/// 0-based) and their currents (A).
pub(crate) fn schedule(
    electrodes: u64,
    protocol: Option<&str>,
    current_a: f64,
    rows: Option<PyReadonlyArray2<'_, i64>>,
    currents: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<Schedule> {
    if let Some(name) = protocol {
        let kind = ProtocolKind::from_name(name).ok_or_else(|| {
            usage(format!(
                "protocol '{name}': adjacent, pseudo-polar, pp-pp, opposite, or a table of \
                 rows (Protocol.from_rows)"
            ))
        })?;
        let electrodes = u8::try_from(electrodes).map_err(|_| {
            usage(format!(
                "electrodes = {electrodes}: an even whole number from {} to {}",
                et_core::protocol::L_MIN,
                et_core::protocol::L_MAX
            ))
        })?;
        let p = Protocol::new(kind, electrodes).map_err(|e| refused(&e))?;
        return Schedule::of_protocol(&p, current_a).map_err(|e| refused(&e));
    }
    let (Some(rows), Some(currents)) = (rows, currents) else {
        return Err(usage(
            "a protocol: a built-in one's name, or rows and currents",
        ));
    };
    let (table, currents) = (rows.as_array(), currents.as_array());
    if table.shape()[1] != 4 || currents.len() != table.shape()[0] {
        return Err(usage(format!(
            "protocol rows: {} x {} with {} currents; give K x 4 (source, sink, positive, \
             negative) and K currents",
            table.shape()[0],
            table.shape()[1],
            currents.len()
        )));
    }
    let electrode = |row: usize, v: i64| {
        u16::try_from(v).map_err(|_| usage(format!("row {row}: electrode {v} is not 0 to 65535")))
    };
    let rows = (0..table.shape()[0])
        .map(|k| {
            Ok(Row {
                source: electrode(k, table[[k, 0]])?,
                sink: electrode(k, table[[k, 1]])?,
                positive: electrode(k, table[[k, 2]])?,
                negative: electrode(k, table[[k, 3]])?,
                current_a: currents[k],
            })
        })
        .collect::<PyResult<Vec<Row>>>()?;
    let electrodes = u16::try_from(electrodes)
        .map_err(|_| usage(format!("{electrodes} electrodes: at most 65535")))?;
    Schedule::new(electrodes, rows).map_err(|e| refused(&e))
}

/// A protocol as arrays: rows (K x 4) and currents (K, A).
pub(crate) type Table<'py> = (Bound<'py, PyArray2<i64>>, Bound<'py, PyArray1<f64>>);

/// A schedule's rows (K x 4: source, sink, positive, negative) and currents (K, A).
pub(crate) fn schedule_table<'py>(py: Python<'py>, schedule: &Schedule) -> PyResult<Table<'py>> {
    let rows = schedule.rows();
    let table = rows
        .iter()
        .flat_map(|r| [r.source, r.sink, r.positive, r.negative].map(i64::from))
        .collect();
    let currents = rows.iter().map(|r| r.current_a).collect();
    Ok((
        array2(py, table, rows.len(), 4)?,
        PyArray1::from_vec(py, currents),
    ))
}

/// A built-in protocol's rows (K x 4) and currents (K, A).
#[pyfunction]
fn protocol_table<'py>(
    py: Python<'py>,
    name: &str,
    electrodes: u64,
    current_a: f64,
) -> PyResult<Table<'py>> {
    schedule_table(
        py,
        &schedule(electrodes, Some(name), current_a, None, None)?,
    )
}

/// A scene file's sheet (JSON), its protocol's name (None for a protocol file), electrode
/// count, current (A), and the schedule's rows and currents.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn scene_parts<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
) -> PyResult<(
    String,
    Option<String>,
    u16,
    f64,
    Bound<'py, PyArray2<i64>>,
    Bound<'py, PyArray1<f64>>,
)> {
    let scene = et_sim::scene::Scene::load(&path).map_err(|e| refused(&e))?;
    let schedule = scene.schedule().map_err(|e| refused(&e))?;
    let (rows, currents) = schedule_table(py, &schedule)?;
    Ok((
        json(&scene.sheet.physical)?,
        schedule.kind().map(|k| k.name().to_string()),
        u16::from(scene.sheet.physical.electrodes.count),
        scene.scan.current_ua * 1e-6,
        rows,
        currents,
    ))
}

/// A sheet's spec (JSON the module wrote) read and checked as a scene's `[sheet]` is.
pub(crate) fn sheet_of(sheet_json: &str) -> PyResult<Sheet> {
    // Each field named by its place (`electrodes.direction: unknown variant ...`), not by a
    // column of the JSON the module wrote.
    let sheet: Sheet = serde_json::from_str(sheet_json)
        .and_then(et_learn::model_file::from_value_named)
        .map_err(|e| {
            usage(format!(
                "sheet: {}",
                et_learn::model_file::json_said(&e, false)
            ))
        })?;
    sheet.validate().map_err(|e| refused(&e))?;
    Ok(sheet)
}

/// Checks a protocol where it is made (`Protocol.from_rows`, `from_pyeit`, `Protocol(...)`),
/// as a Reconstructor would take it, not first where it is used.
#[pyfunction]
#[pyo3(signature = (electrodes, protocol, current_a, rows, currents))]
fn check_protocol(
    electrodes: u64,
    protocol: Option<&str>,
    current_a: f64,
    rows: Option<PyReadonlyArray2<'_, i64>>,
    currents: Option<PyReadonlyArray1<'_, f64>>,
) -> PyResult<()> {
    schedule(electrodes, protocol, current_a, rows, currents).map(|_| ())
}

/// Checks a sheet where it is made (`et.disc`, `et.Sheet(spec)`), not first where it is used.
#[pyfunction]
fn check_sheet(sheet_json: &str) -> PyResult<()> {
    sheet_of(sheet_json).map(|_| ())
}
