//! Frames from JSON: an array of frames, each an array of numbers (Python's
//! `json.dump(F.tolist())`, MATLAB's `jsonencode(F)`, pandas' `to_json(orient="values")`) or
//! an object of named values (pandas' `orient="records"`, its columns named as no frame's
//! values skipped as a CSV's are), or one frame's array of numbers; JSON Lines of either;
//! an object holding them (`json_objects`: pandas' other orientations, a key of frames);
//! `null` (and Python's `NaN`) a value missing.

use std::fmt;
use std::path::Path;

use nalgebra::DMatrix;
use serde::Deserialize;
use serde::de::{self, IgnoredAny, MapAccess, SeqAccess, Visitor};

use super::csv_frames::{in_name, left_out_by_name, left_out_said};
use super::{FramesError, FramesFault, content};

/// One value of a frame as the file writes it.
pub(super) enum Cell {
    /// A number.
    Number(f64),
    /// `null`: a value missing.
    Missing,
    /// A string (a column's name in pandas' `orient="split"`; else not a number).
    Text(Box<str>),
    /// Anything else, as said: `true`, an array, an object.
    Other(Box<str>),
}

/// One element of the top-level array: a frame (by position or by name), or a value (the
/// file is then one frame).
pub(super) enum Item {
    /// `[v0, v1, ...]`.
    Values(Vec<Cell>),
    /// `{"v0": ..., "v1": ...}`, in the file's order.
    Named(Vec<(String, Cell)>),
    /// A value alone.
    Value(Cell),
}

impl Item {
    /// The item as one value of a frame (a frame of JSON Lines): an array in a value's place
    /// said as that.
    pub(super) fn into_cell(self) -> Cell {
        match self {
            Item::Value(cell) => cell,
            Item::Values(_) => Cell::Other("an array".into()),
            Item::Named(_) => Cell::Other("an object".into()),
        }
    }
}

/// The visitor of a [`Cell`] or an [`Item`]: `nested` says whether arrays and objects are
/// frames (an item) or values in the wrong place (a cell).
struct Visit {
    nested: bool,
}

impl<'de> Visitor<'de> for Visit {
    type Value = Item;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a frame or a value")
    }
    fn visit_f64<E>(self, v: f64) -> Result<Item, E> {
        Ok(Item::Value(Cell::Number(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Item, E> {
        Ok(Item::Value(Cell::Number(v as f64)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Item, E> {
        Ok(Item::Value(Cell::Number(v as f64)))
    }
    fn visit_unit<E>(self) -> Result<Item, E> {
        Ok(Item::Value(Cell::Missing))
    }
    fn visit_bool<E>(self, v: bool) -> Result<Item, E> {
        Ok(Item::Value(Cell::Other(v.to_string().into())))
    }
    fn visit_str<E>(self, v: &str) -> Result<Item, E> {
        Ok(Item::Value(Cell::Text(v.into())))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Item, A::Error> {
        if !self.nested {
            while seq.next_element::<IgnoredAny>()?.is_some() {}
            return Ok(Item::Value(Cell::Other("an array".into())));
        }
        let mut cells = Vec::with_capacity(seq.size_hint().unwrap_or(0));
        while let Some(CellOf(cell)) = seq.next_element()? {
            cells.push(cell);
        }
        Ok(Item::Values(cells))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Item, A::Error> {
        if !self.nested {
            while map.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
            return Ok(Item::Value(Cell::Other("an object".into())));
        }
        let mut cells = Vec::new();
        while let Some((name, CellOf(cell))) = map.next_entry::<String, CellOf>()? {
            cells.push((name, cell));
        }
        Ok(Item::Named(cells))
    }
}

/// A [`Cell`], deserialized.
struct CellOf(Cell);

impl<'de> Deserialize<'de> for CellOf {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        match d.deserialize_any(Visit { nested: false })? {
            Item::Value(cell) => Ok(Self(cell)),
            _ => Ok(Self(Cell::Other("an array".into()))),
        }
    }
}

impl<'de> Deserialize<'de> for Item {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(Visit { nested: true })
    }
}

/// A JSON value of the file's top levels: an array of frames or values, an object (of
/// arrays, objects or values, as pandas' orientations write them), or a value.
pub(super) enum Top {
    /// `[...]`: its elements as frames or values.
    Array(Vec<Item>),
    /// `{...}`, in the file's order.
    Object(Object),
    /// An object inside the top one (a column of pandas' `orient="columns"`, a row of
    /// `"index"`): its values (NaN where missing), its keys checked against the first such
    /// object's, a value not a number said in [`Object::not_number`].
    Keyed(Vec<f64>),
    /// Anything else.
    Value(Cell),
}

/// A top-level object: its entries, and the keys of the objects among them (the first's,
/// which every other's must repeat in order: a column's rows, a row's names).
pub(super) struct Object {
    /// Its entries, in the file's order.
    pub entries: Vec<(String, Top)>,
    /// The first inner object's keys.
    pub keys: Vec<String>,
    /// The first inner object whose keys differ from the first's, by its key.
    pub other_keys: Option<String>,
    /// The first value of an inner object that is not a number, said with its place.
    pub not_number: Option<String>,
}

/// The visitor of a [`Top`] at the file's top level.
struct TopVisit;

impl<'de> Visitor<'de> for TopVisit {
    type Value = Top;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("frames")
    }
    fn visit_f64<E>(self, v: f64) -> Result<Top, E> {
        Ok(Top::Value(Cell::Number(v)))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Top, E> {
        Ok(Top::Value(Cell::Number(v as f64)))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Top, E> {
        Ok(Top::Value(Cell::Number(v as f64)))
    }
    fn visit_unit<E>(self) -> Result<Top, E> {
        Ok(Top::Value(Cell::Missing))
    }
    fn visit_bool<E>(self, v: bool) -> Result<Top, E> {
        Ok(Top::Value(Cell::Other(v.to_string().into())))
    }
    fn visit_str<E>(self, v: &str) -> Result<Top, E> {
        Ok(Top::Value(Cell::Text(v.into())))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Top, A::Error> {
        let mut items = Vec::with_capacity(seq.size_hint().unwrap_or(0));
        while let Some(item) = seq.next_element::<Item>()? {
            items.push(item);
        }
        Ok(Top::Array(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Top, A::Error> {
        let mut object = Object {
            entries: Vec::new(),
            keys: Vec::new(),
            other_keys: None,
            not_number: None,
        };
        while let Some(key) = map.next_key::<String>()? {
            let value = map.next_value_seed(Entry {
                object: &mut object,
                key: &key,
            })?;
            object.entries.push((key, value));
        }
        Ok(Top::Object(object))
    }
}

impl<'de> Deserialize<'de> for Top {
    fn deserialize<D: de::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(TopVisit)
    }
}

/// One value of a top-level object: an inner object's keys checked against the first's as
/// they are read and dropped (a key a value would take more than its number).
struct Entry<'a> {
    object: &'a mut Object,
    key: &'a str,
}

impl<'de> de::DeserializeSeed<'de> for Entry<'_> {
    type Value = Top;

    fn deserialize<D: de::Deserializer<'de>>(self, d: D) -> Result<Top, D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Entry<'_> {
    type Value = Top;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a value, an array or an object")
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Top, E> {
        TopVisit.visit_f64(v)
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Top, E> {
        TopVisit.visit_i64(v)
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Top, E> {
        TopVisit.visit_u64(v)
    }
    fn visit_unit<E: de::Error>(self) -> Result<Top, E> {
        TopVisit.visit_unit()
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> Result<Top, E> {
        TopVisit.visit_bool(v)
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Top, E> {
        TopVisit.visit_str(v)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Top, A::Error> {
        TopVisit.visit_seq(seq)
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Top, A::Error> {
        let first = self.object.keys.is_empty()
            && !(self.object.entries.iter()).any(|(_, t)| matches!(t, Top::Keyed(_)));
        let mut cells = Vec::with_capacity(self.object.keys.len());
        while let Some(key) = map.next_key::<String>()? {
            let CellOf(cell) = map.next_value()?;
            let value = match cell {
                Cell::Number(v) => v,
                Cell::Missing => f64::NAN,
                // (A column left out by its name, `label`, may hold text: pandas' default
                // holds a column under its key, `orient="index"` under each row's.)
                _ if left_out_by_name(self.key) || left_out_by_name(&key) => f64::NAN,
                other => {
                    let place = format!("'{}', its '{key}'", self.key);
                    let said = numbers(&[other], |_| place.clone()).err();
                    self.object.not_number = self.object.not_number.take().or(said);
                    f64::NAN
                }
            };
            if first {
                self.object.keys.push(key);
            } else if self.object.keys.get(cells.len()) != Some(&key) {
                self.object
                    .other_keys
                    .get_or_insert_with(|| self.key.to_string());
            }
            cells.push(value);
        }
        if !first && cells.len() != self.object.keys.len() {
            self.object
                .other_keys
                .get_or_insert_with(|| self.key.to_string());
        }
        Ok(Top::Keyed(cells))
    }
}

/// The frames of a JSON array (or an object holding them), one per row, and what is said
/// of them.
pub(super) fn json_matrix(path: &Path, text: &str) -> Result<(DMatrix<f64>, String), FramesError> {
    let fault = |detail: String| content(path, 0, FramesFault::Json(detail));
    let unquoted = python_nan(text);
    // One array of frames, or JSON Lines of them: an array a line (a logger's
    // `json.dumps(frame)` each frame), each a frame; or objects (`json_objects`).
    let tops: Vec<Top> = serde_json::Deserializer::from_str(unquoted.as_deref().unwrap_or(text))
        .into_iter()
        .collect::<Result<_, _>>()
        .map_err(|e| fault(not_json(text, &e)))?;
    let super::json_objects::Found {
        items,
        mut said,
        names,
        columns,
    } = super::json_objects::items(tops).map_err(fault)?;
    if let (Some((columns, keys)), Some(names)) = (columns, &names) {
        let matrix = by_columns(columns, names, &keys);
        if matrix.is_empty() {
            return Err(content(path, 0, FramesFault::NoFrames { header: false }));
        }
        names_said(&[names.as_slice(), &keys].concat(), &mut said);
        return Ok((matrix, said));
    }
    if items.is_empty() {
        return Err(content(path, 0, FramesFault::NoFrames { header: false }));
    }
    if items.iter().all(|i| matches!(i, Item::Value(_))) {
        if said == super::json_objects::ARRAY {
            said = String::from("a JSON array of values (one frame), ");
        }
        let cells: Vec<Cell> = (items.into_iter())
            .filter_map(|i| match i {
                Item::Value(c) => Some(c),
                _ => None,
            })
            .collect();
        let values = numbers(&cells, |j| format!("value {j} (from 0)")).map_err(fault)?;
        return Ok((DMatrix::from_row_slice(1, values.len(), &values), said));
    }
    // The frames' names (given for every row, or the first record's), and each one's factor
    // to volts (None: left out by its name), worked out once.
    let by_names = |keys: Vec<String>| {
        let per = (keys.iter())
            .map(|k| (!left_out_by_name(k)).then(|| in_name(k).map_or(1.0, |u| u.1)))
            .collect();
        (keys, per)
    };
    let mut names: Option<(Vec<String>, Vec<Option<f64>>)> = names.map(by_names);
    let (mut values, mut width) = (Vec::new(), None);
    let n = items.len();
    // (Each frame's cells freed as it is read: 24 bytes a value, then 8.)
    for (r, item) in items.into_iter().enumerate() {
        let at = |j| format!("frame {r}, value {j} (from 0)");
        let row: Vec<f64> = match (&item, &names) {
            (Item::Value(_), _) => {
                let detail = format!("element {r} (from 0) is a value among frames (arrays)");
                return Err(fault(detail));
            }
            (Item::Values(cells), Some((_, per))) => named_numbers(cells.iter(), per, at),
            (Item::Values(cells), None) => numbers(cells, at),
            (Item::Named(cells), _) => {
                let (first, per) = names.get_or_insert_with(|| {
                    by_names(cells.iter().map(|(k, _)| k.clone()).collect())
                });
                if !cells.iter().map(|(k, _)| k).eq(first.iter()) {
                    let keys: Vec<&str> = cells.iter().map(|(k, _)| k.as_str()).collect();
                    let detail = format!(
                        "frame {r} (from 0) names other values than the first (its keys, in \
                         order: {})",
                        keys.join(", ")
                    );
                    return Err(fault(detail));
                }
                named_numbers(cells.iter().map(|(_, c)| c), per, at)
            }
        }
        .map_err(fault)?;
        let w = *width.get_or_insert(row.len());
        if row.len() != w {
            let detail = format!("frame {r} (from 0) has {} values, the first {w}", row.len());
            return Err(fault(detail));
        }
        values.extend(row);
    }
    if let Some((names, _)) = names {
        names_said(&names, &mut said);
    }
    let w = width.unwrap_or(0);
    if w == 0 {
        return Err(content(path, 0, FramesFault::NoFrames { header: false }));
    }
    // Row after row is a w x n column-major matrix: transposed, n x w.
    Ok((DMatrix::from_vec(w, n, values).transpose(), said))
}

/// What is said of frames' `names`: those left out, and the units read as volts.
fn names_said(names: &[String], said: &mut String) {
    let units: Vec<String> = (names.iter())
        .filter(|n| !left_out_by_name(n))
        .filter_map(|n| in_name(n))
        .filter(|(_, per)| *per != 1.0)
        .map(|(word, per)| format!("{word} x {per:e}"))
        .fold(Vec::new(), |mut all, u| {
            if !all.contains(&u) {
                all.push(u);
            }
            all
        });
    let left: Vec<&str> = (names.iter())
        .filter(|n| left_out_by_name(n))
        .map(String::as_str)
        .collect();
    if said == super::json_objects::ARRAY {
        *said = String::from("a JSON array of frames by name, ");
    }
    said.push_str(&left_out_said("its value", &left));
    if !units.is_empty() {
        said.push_str(&format!(
            "its values read as volts ({}, as their names say), ",
            units.join(", ")
        ));
    }
}

/// The matrix of `columns` (each its values by the rows, named by `names`; the rows by
/// `keys`), a column or a row left out or read as volts by its name: as pandas' default
/// `to_json()` holds them (a key a column, its rows' keys their index), read column by column
/// without turning them into rows first; `orient="index"` (a key a row, its columns' keys the
/// names) the same way round, read transposed.
fn by_columns(columns: Vec<Vec<f64>>, names: &[String], keys: &[String]) -> DMatrix<f64> {
    let per = |name: &String| (!left_out_by_name(name)).then(|| in_name(name).map_or(1.0, |u| u.1));
    let rows: Vec<Option<f64>> = keys.iter().map(per).collect();
    let height = rows.iter().flatten().count();
    let kept = names.iter().filter(|n| !left_out_by_name(n)).count();
    let mut values = Vec::with_capacity(height * kept);
    for (column, name) in columns.into_iter().zip(names) {
        if let Some(per) = per(name) {
            let kept_rows = column.into_iter().zip(&rows);
            values.extend(kept_rows.filter_map(|(v, row)| row.map(|r| v * r * per)));
        }
    }
    DMatrix::from_vec(height, kept, values)
}

/// The numbers of `cells` (NaN where missing), or what is wrong with the first that is not
/// one (`at` names it).
fn numbers(cells: &[Cell], at: impl Fn(usize) -> String) -> Result<Vec<f64>, String> {
    (cells.iter().enumerate())
        .map(|(j, c)| match c {
            Cell::Number(v) => Ok(*v),
            Cell::Missing => Ok(f64::NAN),
            Cell::Text(t) => {
                let shown: String = t.chars().take(40).collect();
                Err(format!("{}: \"{shown}\" is not a number", at(j)))
            }
            Cell::Other(o) => Err(format!("{}: {o} is not a number", at(j))),
        })
        .collect()
}

/// The numbers of named `cells` whose factor to volts `per` gives (None: left out), in
/// volts, or what is wrong with the first kept that is not one (`at` names it among the kept).
fn named_numbers<'a>(
    cells: impl Iterator<Item = &'a Cell>,
    per: &[Option<f64>],
    at: impl Fn(usize) -> String,
) -> Result<Vec<f64>, String> {
    let kept = cells
        .zip(per)
        .filter_map(|(c, per)| per.map(|per| (c, per)));
    (kept.enumerate())
        .map(|(j, (c, per))| match c {
            Cell::Number(v) => Ok(*v * per),
            Cell::Missing => Ok(f64::NAN),
            other => numbers(std::slice::from_ref(other), |_| at(j)).map(|v| v[0]),
        })
        .collect()
}

/// `text` with Python's `NaN` (which `json.dump` writes, and JSON has not) as `null` outside
/// strings; None where there is none.
fn python_nan(text: &str) -> Option<String> {
    let b = text.as_bytes();
    let (mut in_string, mut escaped, mut found) = (false, false, Vec::new());
    for i in 0..b.len() {
        match (in_string, b[i]) {
            (true, _) if escaped => escaped = false,
            (true, b'\\') => escaped = true,
            (_, b'"') => in_string = !in_string,
            // (Not inside the last one: "NaNaN" overlapped it and sliced past its end.)
            (false, b'N')
                if b[i..].starts_with(b"NaN") && found.last().is_none_or(|&l| i >= l + 3) =>
            {
                found.push(i)
            }
            _ => {}
        }
    }
    if found.is_empty() {
        return None;
    }
    let mut out = String::with_capacity(text.len() + found.len());
    let mut from = 0;
    for i in found {
        out.push_str(&text[from..i]);
        out.push_str("null");
        from = i + 3;
    }
    out.push_str(&text[from..]);
    Some(out)
}

/// What is said of a file that is not JSON where `e` stopped reading it: the line and column,
/// the text there, and Python's infinities named.
fn not_json(text: &str, e: &serde_json::Error) -> String {
    let line = text.lines().nth(e.line().saturating_sub(1)).unwrap_or("");
    let near: String = (line.chars())
        .skip(e.column().saturating_sub(1))
        .take(24)
        .collect();
    let near = near.trim();
    if e.is_eof() {
        return format!(
            "not JSON: it ends at line {} before its arrays close (a copy cut short?)",
            e.line()
        );
    }
    // JSON, but a number past a double's range: serde_json stops at its last character.
    if e.to_string().starts_with("number out of range") {
        let to: String = line.chars().take(e.column()).collect();
        let number = to.rsplit([',', '[', ' ', '\t', ':']).next().unwrap_or("");
        return format!(
            "line {}, column {}: '{number}' is past the range of a number (at most 1.8e308): \
             not volts?",
            e.line(),
            e.column()
        );
    }
    let infinite = ["Infinity", "-Infinity", "inf", "-inf"]
        .iter()
        .any(|w| near.starts_with(w));
    format!(
        "not JSON at line {}, column {} (at '{near}'){}",
        e.line(),
        e.column(),
        if infinite {
            ": an infinite value (Python's json.dump writes Infinity), which et refuses in a \
             frame: leave that frame out"
        } else {
            ""
        }
    )
}
