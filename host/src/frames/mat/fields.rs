//! The numeric fields of a `.mat` file's structs, by their dotted names (`vh.meas`): EIDORS
//! keeps its data in structs (`fwd_solve` and `inv_solve` take `vh.meas`, `vi.meas`), which
//! the MATLAB reader skips. A field asked for is cut out as a variable of its own, named by
//! its dotted name, for the reader to read as it reads any other.

use std::ops::Range;

/// Nested structs followed at most this deep (a damaged file could nest without end).
pub(super) const DEPTH: usize = 8;

/// miMATRIX, the array element.
pub(super) const MATRIX: u32 = 14;
/// The struct class.
pub(super) const STRUCT: u8 = 2;

/// A numeric field of a 1 x 1 struct: its dotted name and where its array element and,
/// inside it, its (empty) name sub-element lie in the file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Field {
    /// `struct.field` (or deeper, `a.b.c`).
    pub name: String,
    /// The field's whole array element (tag included).
    element: Range<usize>,
    /// Its name sub-element (tag, name and padding).
    name_at: Range<usize>,
}

/// One element's tag: its type, its data's place and where the next element starts.
pub(super) struct Tag {
    pub kind: u32,
    pub data: Range<usize>,
    pub end: usize,
}

/// Reads words in a version 5 file's byte order (the reader's input made safe reads them too).
#[derive(Clone, Copy)]
pub(super) struct Order {
    /// Whether the file is little-endian (bytes 126 and 127 are "IM").
    pub little: bool,
}

impl Order {
    /// The byte order `file` says it is written in.
    pub fn of(file: &[u8]) -> Self {
        Self {
            little: file.get(126..128) == Some(b"IM"),
        }
    }

    /// The word at `at` of `b`, if it is all there.
    pub fn word(self, b: &[u8], at: usize) -> Option<u32> {
        let w: [u8; 4] = b.get(at..at.checked_add(4)?)?.try_into().ok()?;
        Some(if self.little {
            u32::from_le_bytes(w)
        } else {
            u32::from_be_bytes(w)
        })
    }

    fn bytes(self, w: u32) -> [u8; 4] {
        if self.little {
            w.to_le_bytes()
        } else {
            w.to_be_bytes()
        }
    }

    /// The element whose tag starts at `at` (long form: type and size words, the data
    /// padded to 8 bytes; small form: both in one word, the data in the next 4 bytes).
    pub fn tag(self, b: &[u8], at: usize) -> Option<Tag> {
        let first = self.word(b, at)?;
        let (kind, data, end) = if first >> 16 == 0 {
            let size = self.word(b, at.checked_add(4)?)? as usize;
            let start = at.checked_add(8)?;
            let end = start.checked_add(size.checked_next_multiple_of(8)?)?;
            (first, start..start.checked_add(size)?, end)
        } else {
            let size = (first >> 16) as usize;
            let start = at.checked_add(4)?;
            (first & 0xFFFF, start..start + size.min(4), start + 4)
        };
        // (A file's last element may end without its padding.)
        (data.end <= b.len()).then_some(Tag {
            kind,
            data,
            end: end.min(b.len()),
        })
    }
}

/// The numeric fields of the file's structs (`plain`: a version 5 file, its compressed
/// variables inflated), each by its dotted name, in file order.
pub(super) fn fields(plain: &[u8]) -> Vec<Field> {
    let order = Order::of(plain);
    let mut found = Vec::new();
    let mut at = 128;
    while let Some(tag) = order.tag(plain, at) {
        if tag.kind == MATRIX {
            struct_fields(plain, order, &tag, None, 0, &mut found);
        }
        at = tag.end;
    }
    found
}

/// The numeric fields of the array element `tag` when it is a 1 x 1 struct, pushed to
/// `found`: named from `name`, the struct's dotted name when it is itself a field (its own
/// name sub-element is then empty), else its own.
fn struct_fields(
    b: &[u8],
    order: Order,
    tag: &Tag,
    name: Option<&str>,
    depth: usize,
    found: &mut Vec<Field>,
) -> Option<()> {
    let flags = order.tag(b, tag.data.start)?;
    let class = order.word(b, flags.data.start)?.to_le_bytes()[0];
    let dims = order.tag(b, flags.end)?;
    let name_tag = order.tag(b, dims.end)?;
    if class != STRUCT || depth >= DEPTH {
        return None;
    }
    let name = match name {
        Some(n) => n.to_string(),
        None => std::str::from_utf8(b.get(name_tag.data.clone())?)
            .ok()?
            .to_string(),
    };
    // A 1 x 1 struct: one value of each field (a struct array's fields repeat per element).
    let mut sizes = (dims.data.start..dims.data.end).step_by(4);
    if dims.data.len() < 8 || !sizes.all(|at| order.word(b, at) == Some(1)) {
        return None;
    }
    let length = order.tag(b, name_tag.end)?;
    let width = order.word(b, length.data.start)? as usize;
    let names = order.tag(b, length.end)?;
    let mut at = names.end;
    for raw in b.get(names.data.clone())?.chunks(width.max(1)) {
        let field = order.tag(b, at)?;
        if field.kind != MATRIX || field.end > tag.end {
            return None;
        }
        let dotted = format!(
            "{name}.{}",
            std::str::from_utf8(raw).ok()?.trim_end_matches('\0')
        );
        let f_flags = order.tag(b, field.data.start)?;
        let f_class = order.word(b, f_flags.data.start)?.to_le_bytes()[0];
        let f_dims = order.tag(b, f_flags.end)?;
        let f_name = order.tag(b, f_dims.end)?;
        if f_class == STRUCT {
            struct_fields(b, order, &field, Some(&dotted), depth + 1, found);
        } else if (6..=15).contains(&f_class) {
            found.push(Field {
                name: dotted,
                element: at..field.end,
                name_at: f_dims.end..f_name.end,
            });
        }
        at = field.end;
    }
    Some(())
}

/// A version 5 file of `plain`'s header and `field` alone, its array named by the field's
/// dotted name: what the MATLAB reader reads as a variable.
pub(super) fn alone(plain: &[u8], field: &Field) -> Option<Vec<u8>> {
    let order = Order::of(plain);
    let element = plain.get(field.element.clone())?;
    let start = field.element.start;
    let (before, after) = (
        element.get(8..field.name_at.start - start)?,
        element.get(field.name_at.end - start..)?,
    );
    let mut name = Vec::new();
    name.extend(order.bytes(1)); // miINT8
    name.extend(order.bytes(u32::try_from(field.name.len()).ok()?));
    name.extend(field.name.as_bytes());
    name.resize(name.len().next_multiple_of(8), 0);
    let size = before.len() + name.len() + after.len();
    let mut out = plain.get(..128)?.to_vec();
    out.extend(order.bytes(MATRIX));
    out.extend(order.bytes(u32::try_from(size).ok()?));
    out.extend(before);
    out.extend(name);
    out.extend(after);
    Some(out)
}
