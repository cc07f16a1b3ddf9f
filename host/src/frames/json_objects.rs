//! JSON objects that hold frames, as other tools write them: pandas' `to_json()` in its
//! default orientation (`"columns"`: a key a column, each an object of the rows by index),
//! `"index"` (a key a row), `"split"` (`columns`, `index`, `data`) and `"table"` (`schema`,
//! `data` as records), a Series (one object of values: one frame), `lines=True` (an object a
//! line, a record a frame), and an object whose one array holds the frames (MATLAB's
//! `jsonencode(struct("frames", F))`, `{"frames": [...]}`) or, a line each, a logger's
//! `{"t": 0.1, "v": [...]}`; each turned into the frames `json_frames` reads.

use super::json_frames::{Cell, Item, Object, Top};

/// What is said of one array of frames.
pub(super) const ARRAY: &str = "a JSON array of frames, ";

/// The frames found in a file's top-level values.
pub(super) struct Found {
    /// A row each: an array, a record of named values, or the one frame's values.
    pub items: Vec<Item>,
    /// How they were found, in words.
    pub said: String,
    /// Every row's names, where the rows are arrays of named columns (pandas' `"split"` and
    /// `"columns"`): each name once, not once a value.
    pub names: Option<Vec<String>>,
    /// The frames' columns instead of rows, each named by `names` (pandas' `"columns"`):
    /// their values (NaN where missing), and their rows' keys.
    pub columns: Option<(Vec<Vec<f64>>, Vec<String>)>,
}

impl Found {
    fn new(items: Vec<Item>, said: impl Into<String>) -> Self {
        Self {
            items,
            said: said.into(),
            names: None,
            columns: None,
        }
    }
}

/// The frames of a file's top-level values, and how they were found; or what is wrong.
pub(super) fn items(mut tops: Vec<Top>) -> Result<Found, String> {
    if tops.len() == 1 {
        return match tops.remove(0) {
            Top::Array(items) => Ok(Found::new(items, ARRAY)),
            Top::Object(object) => self::object(object),
            Top::Value(_) | Top::Keyed(_) => Err("a value alone, not frames".into()),
        };
    }
    // JSON Lines: an array a line, or an object a line (pandas' `lines=True` records, or a
    // logger's record holding its frame's array).
    let mut items = Vec::with_capacity(tops.len());
    let mut key: Option<String> = None;
    // A logger's lines of frames (an object holding one array) among its other records (`{"event":
    // "start"}`, a status): those hold no array, and are skipped and said (the first was read
    // as a frame of named values, "\"start\" is not a number").
    let arrays = |o: &Object| {
        (o.entries.iter())
            .filter(|(_, t)| matches!(t, Top::Array(_)))
            .count()
    };
    let logger = (tops.iter()).any(|t| matches!(t, Top::Object(o) if arrays(o) == 1));
    let mut skipped: Vec<usize> = Vec::new();
    for (n, top) in tops.into_iter().enumerate() {
        let item = match top {
            Top::Object(object) if logger && arrays(&object) == 0 => {
                skipped.push(n + 1);
                continue;
            }
            Top::Array(cells) => Item::Values(cells.into_iter().map(Item::into_cell).collect()),
            Top::Object(object) => match line_record(object.entries) {
                Ok((item, k)) => {
                    key = key.or(k);
                    item
                }
                Err(why) => return Err(format!("JSON line {} (from 1): {why}", n + 1)),
            },
            Top::Value(_) | Top::Keyed(_) => {
                return Err(format!(
                    "JSON line {} (from 1) is a value alone, where each line is a frame",
                    n + 1
                ));
            }
        };
        items.push(item);
    }
    let said = match (&key, items.first()) {
        (Some(k), _) if !skipped.is_empty() => {
            let first: Vec<String> = skipped.iter().take(5).map(usize::to_string).collect();
            format!(
                "JSON Lines, each frame its line's '{k}', its other keys skipped, and {} line{} \
                 without '{k}' (line{} {}{}, from 1: a logger's other records), ",
                skipped.len(),
                if skipped.len() == 1 { "" } else { "s" },
                if skipped.len() == 1 { "" } else { "s" },
                first.join(", "),
                if skipped.len() > 5 { ", ..." } else { "" }
            )
        }
        (Some(k), _) => {
            format!("JSON Lines, each frame its line's '{k}', its other keys skipped, ")
        }
        (None, Some(Item::Named(_))) => {
            "JSON Lines, an object a frame (pandas' orient=\"records\", lines=True), ".into()
        }
        _ => "JSON Lines, an array a frame, ".into(),
    };
    Ok(Found::new(items, said))
}

/// A line's object as a frame: its one array of values (a logger's record, the others
/// skipped, with its key), else its values by name (a record).
fn line_record(entries: Vec<(String, Top)>) -> Result<(Item, Option<String>), String> {
    let arrays = entries
        .iter()
        .filter(|(_, t)| matches!(t, Top::Array(_)))
        .count();
    if arrays > 1 {
        return Err(several_arrays(&entries));
    }
    if arrays == 1 {
        let (key, cells) = (entries.into_iter())
            .find_map(|(k, t)| match t {
                Top::Array(cells) => Some((k, cells)),
                _ => None,
            })
            .ok_or("no array")?;
        let cells = cells.into_iter().map(Item::into_cell).collect();
        return Ok((Item::Values(cells), Some(key)));
    }
    Ok((Item::Named(as_cells(entries)), None))
}

/// An object's entries as named values (a nested one said as what it is, not a number).
fn as_cells(entries: Vec<(String, Top)>) -> Vec<(String, Cell)> {
    (entries.into_iter())
        .map(|(k, t)| {
            let cell = match t {
                Top::Value(c) => c,
                Top::Array(_) => Cell::Other("an array".into()),
                Top::Object(_) | Top::Keyed(_) => Cell::Other("an object".into()),
            };
            (k, cell)
        })
        .collect()
}

/// What is said of an object of several arrays.
fn several_arrays(entries: &[(String, Top)]) -> String {
    let keys: Vec<&str> = (entries.iter())
        .filter(|(_, t)| matches!(t, Top::Array(_)))
        .map(|(k, _)| k.as_str())
        .collect();
    format!(
        "an object of {} arrays ({}): et reads frames from an object of one (its key said), \
         an array, or pandas' orientations; save the frames alone (json.dump(F.tolist()))",
        keys.len(),
        keys.join(", ")
    )
}

/// One top-level object's frames: pandas' orientations by their keys, one array held, or
/// an object of values (one frame).
fn object(object: Object) -> Result<Found, String> {
    let entries = &object.entries;
    let has = |k: &str| entries.iter().any(|(key, _)| key == k);
    if has("columns") && has("data") {
        return split(object.entries);
    }
    if has("schema") && has("data") {
        let data = (object.entries.into_iter()).find_map(|(k, t)| (k == "data").then_some(t));
        return match data {
            Some(Top::Array(items)) => Ok(Found::new(
                items,
                "pandas' orient=\"table\" (its records, the index by name skipped), ",
            )),
            _ => Err("its \"data\" (pandas' orient=\"table\") is not an array of records".into()),
        };
    }
    if entries.is_empty() {
        return Err("an empty object, no frames".into());
    }
    if entries.iter().all(|(_, t)| matches!(t, Top::Keyed(_))) {
        return columns(object);
    }
    if entries.iter().all(|(_, t)| matches!(t, Top::Value(_))) {
        let said = "a JSON object of values (one frame, as a pandas Series writes it), ";
        return Ok(Found::new(
            vec![Item::Named(as_cells(object.entries))],
            said,
        ));
    }
    let arrays = entries
        .iter()
        .filter(|(_, t)| matches!(t, Top::Array(_)))
        .count();
    if arrays > 1 {
        return Err(several_arrays(entries));
    }
    if arrays == 0 {
        return Err(
            "an object of objects and values, which no frames' layout is (an array of \
                    frames, or pandas' orientations)"
                .into(),
        );
    }
    let (key, items) = (object.entries.into_iter())
        .find_map(|(k, t)| match t {
            Top::Array(items) => Some((k, items)),
            _ => None,
        })
        .ok_or("no array")?;
    Ok(Found::new(
        items,
        format!("its key '{key}' (its other keys skipped), "),
    ))
}

/// pandas' `orient="split"`: its `data` rows named by its `columns`, its `index` skipped.
fn split(entries: Vec<(String, Top)>) -> Result<Found, String> {
    let (mut names, mut data) = (None, None);
    for (k, t) in entries {
        match (k.as_str(), t) {
            ("columns", Top::Array(items)) => names = Some(items),
            ("data", Top::Array(items)) => data = Some(items),
            _ => {}
        }
    }
    let (Some(names), Some(data)) = (names, data) else {
        return Err(
            "its \"columns\" and \"data\" (pandas' orient=\"split\") are not arrays".into(),
        );
    };
    let names: Vec<String> = (names.into_iter())
        .map(|item| match item {
            Item::Value(Cell::Text(t)) => t.to_string(),
            Item::Value(Cell::Number(v)) => format!("{v}"),
            _ => String::new(),
        })
        .collect();
    for (r, item) in data.iter().enumerate() {
        match item {
            Item::Values(cells) if cells.len() == names.len() => {}
            Item::Values(cells) => {
                return Err(format!(
                    "its \"data\" row {r} (from 0) has {} values for its {} columns",
                    cells.len(),
                    names.len()
                ));
            }
            _ => {
                return Err(format!(
                    "its \"data\" row {r} (from 0) is not an array of values"
                ));
            }
        }
    }
    Ok(Found {
        items: data,
        said: "pandas' orient=\"split\" (its columns by name, its index skipped), ".into(),
        names: Some(names),
        columns: None,
    })
}

/// pandas' default `orient="columns"`: a key a column, each an object of its values by the
/// rows' index (the same keys in each), kept as columns; a row a frame. (`orient="index"`, a key a
/// row, reads as its transpose, which the frames' reader turns back by K.)
fn columns(object: Object) -> Result<Found, String> {
    if let Some(name) = object.other_keys {
        return Err(format!(
            "its column '{name}' has other rows than its first (pandas writes each column's \
             rows by one index)"
        ));
    }
    if let Some(said) = object.not_number {
        return Err(said);
    }
    let (names, columns) = (object.entries.into_iter())
        .map(|(name, top)| match top {
            Top::Keyed(values) => (name, values),
            _ => (name, Vec::new()),
        })
        .unzip();
    Ok(Found {
        items: Vec::new(),
        said: "an object of objects, a key a column (pandas' to_json() default, \
               orient=\"columns\"; orient=\"index\" reads transposed), "
            .into(),
        names: Some(names),
        columns: Some((columns, object.keys)),
    })
}
