//! A struct array's numeric fields, dense or sparse, by element: EIDORS keeps a forward
//! model's protocol as one (`fwd_model.stimulation`, what `mk_stim_patterns` returns: a
//! struct an injection, its `stim_pattern` and `meas_pattern` sparse matrices), which the
//! MATLAB reader skips (it reads neither struct arrays nor sparse matrices).

use super::fields::{DEPTH, MATRIX, Order, STRUCT, Tag};

/// A numeric field's value: its shape and its entries other than 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Numeric {
    /// Its rows.
    pub rows: usize,
    /// Its columns.
    pub columns: usize,
    /// (row, column, value) of each entry other than 0, by columns (as MATLAB stores them).
    pub nonzero: Vec<(usize, usize, f64)>,
}

/// A struct array of a file: its name and, for each of its elements, the fields read.
#[derive(Clone, Debug, PartialEq)]
pub struct StructArray {
    /// Its name (dotted where it is a field of a 1 x 1 struct: `fmdl.stimulation`).
    pub name: String,
    /// The fields read, in order (those asked for, or every one).
    pub fields: Vec<String>,
    /// Each element's fields read, in `fields`' order: None where the field is not a real
    /// numeric matrix (text, a cell, a complex or empty value).
    pub elements: Vec<Vec<Option<Numeric>>>,
}

/// The struct arrays of a version 5 file (`plain`: its compressed variables inflated) that
/// have every field of `wanted`, in file order: variables, and fields of 1 x 1 structs
/// (`fmdl.stimulation`, `imdl.fwd_model.stimulation`); with none wanted, every struct array
/// of other than one element, with all its fields.
pub(super) fn struct_arrays(plain: &[u8], wanted: &[&str]) -> Vec<StructArray> {
    let order = Order::of(plain);
    let mut found = Vec::new();
    let mut at = 128;
    while let Some(tag) = order.tag(plain, at) {
        if tag.kind == MATRIX {
            walk(plain, order, &tag, None, 0, wanted, &mut found);
        }
        at = tag.end;
    }
    found
}

/// The struct array element `tag`, when it has every field of `wanted`, pushed to `found`;
/// a 1 x 1 struct's struct fields followed. `name`: its dotted name when it is a field.
fn walk(
    b: &[u8],
    order: Order,
    tag: &Tag,
    name: Option<&str>,
    depth: usize,
    wanted: &[&str],
    found: &mut Vec<StructArray>,
) -> Option<()> {
    let head = Head::of(b, order, tag)?;
    if head.class != STRUCT || depth >= DEPTH {
        return None;
    }
    let name = match name {
        Some(n) => n.to_string(),
        None => std::str::from_utf8(b.get(head.name.clone())?)
            .ok()?
            .to_string(),
    };
    let count = head
        .dims
        .iter()
        .try_fold(1_usize, |n, d| n.checked_mul(*d))?;
    let length = order.tag(b, head.after)?;
    let width = order.word(b, length.data.start)? as usize;
    let names_tag = order.tag(b, length.end)?;
    let names: Vec<String> = (b.get(names_tag.data.clone())?.chunks(width.max(1)))
        .map(|raw| {
            String::from_utf8_lossy(raw)
                .trim_end_matches('\0')
                .to_string()
        })
        .collect();
    if names.is_empty() || width == 0 {
        return None;
    }
    let mut at = names_tag.end;
    let mut field = || -> Option<Tag> {
        let field = order.tag(b, at)?;
        at = field.end;
        (field.kind == MATRIX && field.end <= tag.end).then_some(field)
    };
    // No field asked for: every field of every struct array but a 1 x 1 struct (whose
    // fields are followed, as `fields.rs` reads them).
    let every = wanted.is_empty();
    let places: Vec<Option<usize>> = match every {
        true => (0..names.len()).map(Some).collect(),
        false => (wanted.iter())
            .map(|w| names.iter().position(|n| n == w))
            .collect(),
    };
    if (every && count != 1) || (!every && places.iter().all(Option::is_some)) {
        // Every element's fields, one after another; each tag takes 8 bytes at least, so the
        // loop ends with the element's bytes whatever the dimensions claim.
        let mut elements = Vec::new();
        for _ in 0..count {
            let values: Vec<Tag> = (0..names.len()).map(|_| field()).collect::<Option<_>>()?;
            elements.push(
                (places.iter().flatten())
                    .map(|&i| numeric(b, order, &values[i]))
                    .collect(),
            );
        }
        let fields = places.iter().flatten().map(|&i| names[i].clone()).collect();
        found.push(StructArray {
            name,
            fields,
            elements,
        });
    } else if count == 1 {
        for n in &names {
            let value = field()?;
            walk(
                b,
                order,
                &value,
                Some(&format!("{name}.{n}")),
                depth + 1,
                wanted,
                found,
            );
        }
    }
    Some(())
}

/// An array element's header: its class, dimensions, name and where its data begins.
struct Head {
    class: u8,
    /// The array's flags word's complex bit.
    complex: bool,
    dims: Vec<usize>,
    name: std::ops::Range<usize>,
    /// Where the name's element ends: the class's sub-elements follow.
    after: usize,
}

impl Head {
    fn of(b: &[u8], order: Order, tag: &Tag) -> Option<Self> {
        // (An empty value is an array element of no bytes.)
        let flags = order
            .tag(b, tag.data.start)
            .filter(|_| !tag.data.is_empty())?;
        let word = order.word(b, flags.data.start)?;
        let dims = order.tag(b, flags.end)?;
        let name = order.tag(b, dims.end)?;
        let dims = (numbers(b, order, &dims)?.into_iter())
            .map(|d| (d >= 0.0 && d <= f64::from(u32::MAX)).then_some(d as usize))
            .collect::<Option<_>>()?;
        Some(Self {
            class: (word & 0xFF) as u8,
            complex: word & 0x0800 != 0,
            dims,
            name: name.data,
            after: name.end,
        })
    }
}

/// The numeric array element `tag`, dense or sparse, as its shape and entries other than 0;
/// None for any other class, a complex one, or one whose sizes disagree.
fn numeric(b: &[u8], order: Order, tag: &Tag) -> Option<Numeric> {
    /// The sparse class (its sub-elements: row indices, column starts, values).
    const SPARSE: u8 = 5;
    let head = Head::of(b, order, tag)?;
    let [rows, columns] = head.dims[..] else {
        return None;
    };
    if head.complex {
        return None;
    }
    let sub = |at: usize| order.tag(b, at).filter(|t| t.end <= tag.end);
    let first = sub(head.after)?;
    let mut nonzero = Vec::new();
    match head.class {
        SPARSE => {
            let starts = sub(first.end)?;
            let values = sub(starts.end)?;
            let index = |v: f64| (v >= 0.0 && v.fract() == 0.0).then_some(v as usize);
            let rows_of = (numbers(b, order, &first)?.into_iter())
                .map(index)
                .collect::<Option<Vec<usize>>>()?;
            let starts = (numbers(b, order, &starts)?.into_iter())
                .map(index)
                .collect::<Option<Vec<usize>>>()?;
            let values = numbers(b, order, &values)?;
            if starts.len() != columns.checked_add(1)?
                || starts.windows(2).any(|w| w[0] > w[1])
                || starts[columns] > rows_of.len().min(values.len())
            {
                return None;
            }
            for c in 0..columns {
                for i in starts[c]..starts[c + 1] {
                    let (r, v) = (rows_of[i], values[i]);
                    if r >= rows {
                        return None;
                    }
                    if v != 0.0 {
                        nonzero.push((r, c, v));
                    }
                }
            }
        }
        6..=15 => {
            let values = numbers(b, order, &first)?;
            if Some(values.len()) != rows.checked_mul(columns) || rows == 0 && columns == 0 {
                return None;
            }
            let by_columns = values.iter().enumerate().filter(|(_, v)| **v != 0.0);
            nonzero.extend(by_columns.map(|(i, &v)| (i % rows, i / rows, v)));
        }
        _ => return None,
    }
    Some(Numeric {
        rows,
        columns,
        nonzero,
    })
}

/// The values of a numeric data element (MATLAB stores an array's values in the smallest
/// type that holds them: an int8 element for a double array of small integers).
fn numbers(b: &[u8], order: Order, tag: &Tag) -> Option<Vec<f64>> {
    let data = b.get(tag.data.clone())?;
    let size = match tag.kind {
        1 | 2 => 1,
        3 | 4 => 2,
        5..=7 => 4,
        9 | 12 | 13 => 8,
        _ => return None,
    };
    if data.len() % size != 0 {
        return None;
    }
    let bytes = |c: &[u8]| -> [u8; 8] {
        let mut w = [0u8; 8];
        if order.little {
            w[..size].copy_from_slice(c);
        } else {
            w[8 - size..].copy_from_slice(c);
        }
        w
    };
    let value = |c: &[u8]| -> f64 {
        let w = bytes(c);
        let (le, be) = (u64::from_le_bytes(w), u64::from_be_bytes(w));
        let raw = if order.little { le } else { be };
        match tag.kind {
            1 => f64::from(raw as u8 as i8),
            2 => f64::from(raw as u8),
            3 => f64::from(raw as u16 as i16),
            4 => f64::from(raw as u16),
            5 => f64::from(raw as u32 as i32),
            6 => f64::from(raw as u32),
            7 => f64::from(f32::from_bits(raw as u32)),
            9 => f64::from_bits(raw),
            12 => raw as i64 as f64,
            _ => raw as f64,
        }
    };
    Some(data.chunks_exact(size).map(value).collect())
}
