//! NumPy's `.npz` files, written and read without numpy: a zip archive of `.npy` arrays.
//!
//! What [`Writer`] makes is what `numpy.savez` makes: one uncompressed ("stored") zip entry
//! per array, `NAME.npy`, each a format-1.0 `.npy` file (magic, a header dictionary with
//! `descr`, `fortran_order` and `shape`, then the raw little-endian values). `numpy.load`
//! reads it without `allow_pickle`; Python's standard library reads it too (`zipfile`, then
//! `ast.literal_eval` on the header). Matrices are written in Fortran (column) order, which
//! is how `nalgebra` keeps them, so writing and reading are copies at disk speed.
//!
//! [`Npz::read`] takes back what numpy's `savez` and `savez_compressed` write as well
//! (stored or deflated entries, C or Fortran order, numbers of any common integer or float
//! width in either byte order, zip64 size fields); complex and object (pickled) arrays are
//! refused with a message saying what to save instead.
//!
//! Limits: a written archive stays under 4 GiB (no zip64 on write: about 500 million f64
//! values; more is refused with an error, never a broken file).

// Reads untrusted bytes: no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use nalgebra::DMatrix;

mod fault;
mod write;

use fault::error;
pub use fault::{NpzError, NpzFault};
pub use write::{Writer, npy_header_f64, npy_of_array, npy_of_matrix};

/// One array as stored: its element type, shape and raw values, little-endian.
struct Array<'a> {
    kind: Kind,
    shape: Vec<usize>,
    fortran: bool,
    data: std::borrow::Cow<'a, [u8]>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Float(usize),
    Int(usize),
    Uint(usize),
    Bool,
    /// UTF-32 characters per element.
    Unicode(usize),
}

impl Kind {
    fn size(self) -> usize {
        match self {
            Kind::Float(s) | Kind::Int(s) | Kind::Uint(s) => s,
            Kind::Bool => 1,
            Kind::Unicode(n) => 4 * n,
        }
    }
}

/// An archive read into memory: arrays by name.
pub struct Npz {
    bytes: Vec<u8>,
    /// (array name without `.npy`, byte range of its `.npy` file in `bytes`).
    entries: Vec<(String, std::ops::Range<usize>)>,
}

impl std::fmt::Debug for Npz {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Npz")
            .field("bytes", &self.bytes.len())
            .field("entries", &self.entries)
            .finish()
    }
}

fn u16_at(b: &[u8], at: usize) -> Option<usize> {
    Some(usize::from(u16::from_le_bytes(
        b.get(at..at + 2)?.try_into().ok()?,
    )))
}

fn u32_at(b: &[u8], at: usize) -> Option<usize> {
    usize::try_from(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?)).ok()
}

fn u64_at(b: &[u8], at: usize) -> Option<usize> {
    usize::try_from(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?)).ok()
}

/// Inflates the raw deflate stream `packed` onto `out`: exactly `size` bytes, as the
/// archive's directory states (more or fewer is a damaged entry).
fn inflate(packed: &[u8], size: usize, out: &mut Vec<u8>) -> Result<(), NpzFault> {
    use std::io::Read as _;
    let from = out.len();
    libflate::deflate::Decoder::new(packed)
        .take(size as u64 + 1)
        .read_to_end(out)
        .map_err(|_| NpzFault::Inflate)?;
    if out.len() - from != size {
        return Err(NpzFault::Inflate);
    }
    Ok(())
}

impl Npz {
    /// One `.npy` file's bytes as an archive holding one array named `array` (nothing is
    /// copied; the array is checked when read).
    #[must_use]
    pub fn from_npy(bytes: Vec<u8>) -> Self {
        let range = 0..bytes.len();
        Self {
            bytes,
            entries: vec![("array".to_string(), range)],
        }
    }

    /// Each array's name (without `.npy`) and where its `.npy` file lies in the archive's bytes.
    #[must_use]
    pub fn entries(&self) -> &[(String, std::ops::Range<usize>)] {
        &self.entries
    }

    /// Indexes the archive in `bytes` (stored entries are not copied; deflated ones, as
    /// `numpy.savez_compressed` writes them, are inflated once, to no more than
    /// [`max_file_bytes`](et_core::text::max_file_bytes) together).
    ///
    /// # Errors
    /// When `bytes` is not a zip archive of stored or deflated `.npy` entries, or one is
    /// damaged.
    pub fn read(mut bytes: Vec<u8>) -> Result<Self, NpzError> {
        let broken = |what| error(None, NpzFault::Broken(what));
        // The end-of-central-directory record: 22 bytes, then a comment of at most 64 KiB.
        let lowest = bytes.len().saturating_sub(22 + 0xFFFF);
        let eocd = (lowest..=bytes.len().saturating_sub(22))
            .rev()
            .find(|&i| bytes.get(i..i + 4) == Some(b"PK\x05\x06"))
            .ok_or_else(|| broken("no zip directory (is it a zip archive?)"))?;
        let field = |at| u32_at(&bytes, eocd + at).ok_or_else(|| broken("short directory"));
        let mut count = u16_at(&bytes, eocd + 10).ok_or_else(|| broken("short directory"))?;
        let mut start = field(16)?;
        if start == 0xFFFF_FFFF || count == 0xFFFF {
            // zip64: its locator sits just before the record and points at the zip64 record.
            let locator = eocd
                .checked_sub(20)
                .filter(|&l| bytes.get(l..l + 4) == Some(b"PK\x06\x07"))
                .ok_or_else(|| broken("zip64 locator missing"))?;
            let record =
                u64_at(&bytes, locator + 8).ok_or_else(|| broken("zip64 locator short"))?;
            if bytes.get(record..record + 4) != Some(b"PK\x06\x06") {
                return Err(broken("zip64 directory missing"));
            }
            count = u64_at(&bytes, record + 32).ok_or_else(|| broken("zip64 record short"))?;
            start = u64_at(&bytes, record + 48).ok_or_else(|| broken("zip64 record short"))?;
        }
        let mut entries = Vec::new();
        // Compressed entries inflated, appended to `bytes` once the directory is read; their
        // ranges point past the archive's own bytes. Their total is bounded by the data files'
        // limit (a small archive could inflate to gigabytes).
        let (mut inflated, base, limit) =
            (Vec::new(), bytes.len(), et_core::text::max_file_bytes());
        let mut at = start;
        for _ in 0..count {
            let short = || broken("directory entry cut short");
            if bytes.get(at..at + 4) != Some(b"PK\x01\x02") {
                return Err(broken("directory entry without its signature"));
            }
            let method = u16_at(&bytes, at + 10).ok_or_else(short)?;
            let crc = u32_at(&bytes, at + 16).ok_or_else(short)?;
            let mut packed = u32_at(&bytes, at + 20).ok_or_else(short)?;
            let mut size = u32_at(&bytes, at + 24).ok_or_else(short)?;
            let name_len = u16_at(&bytes, at + 28).ok_or_else(short)?;
            let extra_len = u16_at(&bytes, at + 30).ok_or_else(short)?;
            let comment_len = u16_at(&bytes, at + 32).ok_or_else(short)?;
            let mut local = u32_at(&bytes, at + 42).ok_or_else(short)?;
            let name = bytes.get(at + 46..at + 46 + name_len).ok_or_else(short)?;
            let name = String::from_utf8_lossy(name).into_owned();
            // zip64 extra field: the 64-bit values of the fields set to 0xFFFFFFFF, in the
            // order size, packed size, local header offset.
            let extra = bytes
                .get(at + 46 + name_len..at + 46 + name_len + extra_len)
                .ok_or_else(short)?;
            let mut e = 0;
            while let (Some(id), Some(len)) = (u16_at(extra, e), u16_at(extra, e + 2)) {
                if id == 1 {
                    let mut v = e + 4;
                    for field in [&mut size, &mut packed, &mut local] {
                        if *field == 0xFFFF_FFFF {
                            *field = u64_at(extra, v).ok_or_else(short)?;
                            v += 8;
                        }
                    }
                }
                e += 4 + len;
            }
            at += 46 + name_len + extra_len + comment_len;
            let Some(array) = name.strip_suffix(".npy") else {
                continue;
            };
            if entries.iter().any(|(n, _)| n == array) {
                return Err(error(Some(array), NpzFault::Twice));
            }
            let data_at = u16_at(&bytes, local + 26)
                .zip(u16_at(&bytes, local + 28))
                .filter(|_| bytes.get(local..local + 4) == Some(b"PK\x03\x04"))
                .map(|(n, x)| local + 30 + n + x)
                .ok_or_else(|| broken("local header missing"))?;
            let Some(data) = data_at
                .checked_add(packed)
                .and_then(|end| bytes.get(data_at..end))
            else {
                return Err(error(Some(array), NpzFault::CutShort));
            };
            let range = match method {
                0 => data_at..data_at + data.len(),
                // Deflated (numpy.savez_compressed), to no more than its stated size.
                8 => {
                    let from = inflated.len();
                    if (from as u64).saturating_add(size as u64) > limit {
                        return Err(error(Some(array), NpzFault::Inflates(limit)));
                    }
                    inflate(data, size, &mut inflated).map_err(|f| error(Some(array), f))?;
                    base + from..base + inflated.len()
                }
                _ => return Err(error(Some(array), NpzFault::Method(method))),
            };
            // Stored entries carry no other check: a flipped bit would be read as a value.
            let entry = if range.start < base {
                bytes.get(range.clone())
            } else {
                inflated.get(range.start - base..)
            };
            if crc32fast::hash(entry.unwrap_or_default()) as usize != crc {
                return Err(error(Some(array), NpzFault::Checksum));
            }
            entries.push((array.to_string(), range));
        }
        bytes.append(&mut inflated);
        Ok(Self { bytes, entries })
    }

    /// The arrays' names, as stored.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.entries.iter().map(|(n, _)| n.as_str())
    }

    /// Whether the archive holds `name`.
    #[must_use]
    pub fn has(&self, name: &str) -> bool {
        self.entries.iter().any(|(n, _)| n == name)
    }

    /// Whether `name` is an array of booleans (numpy's `|b1`): read as 0 and 1 by
    /// [`Npz::matrix`], which suits labels but not measurements.
    #[must_use]
    pub fn is_boolean(&self, name: &str) -> bool {
        self.array(name).is_ok_and(|a| a.kind == Kind::Bool)
    }

    /// The shape of the array `name` as its header says it, and whether it holds numbers
    /// (not booleans or text); None where it does not read.
    #[must_use]
    pub fn shape(&self, name: &str) -> Option<(Vec<usize>, bool)> {
        let a = self.array(name).ok()?;
        let numbers = !matches!(a.kind, Kind::Bool | Kind::Unicode(_));
        Some((a.shape, numbers))
    }

    fn array(&self, name: &str) -> Result<Array<'_>, NpzError> {
        let fault = |f| error(Some(name), f);
        let bad = |m| fault(NpzFault::Npy(m));
        let range = self
            .entries
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, r)| r.clone())
            .ok_or_else(|| {
                let held = self.names().collect::<Vec<_>>().join(", ");
                fault(NpzFault::Missing {
                    held: if held.is_empty() {
                        "no array".into()
                    } else {
                        held
                    },
                })
            })?;
        let npy = self
            .bytes
            .get(range)
            .ok_or_else(|| bad("outside the file"))?;
        if npy.get(..6) != Some(b"\x93NUMPY") {
            return Err(bad("not an .npy array (no magic)"));
        }
        let (len, at) = match npy.get(6) {
            Some(1) => (u16_at(npy, 8), 10),
            Some(2 | 3) => (u32_at(npy, 8), 12),
            _ => return Err(bad("unknown .npy version")),
        };
        let len = len.ok_or_else(|| bad("header cut short"))?;
        let header = npy
            .get(at..at + len)
            .and_then(|h| std::str::from_utf8(h).ok())
            .ok_or_else(|| bad("header cut short or not text"))?;
        let value = |key: &'static str| {
            let k = header
                .find(&format!("'{key}'"))
                .ok_or_else(|| fault(NpzFault::NoKey(key)))?;
            let rest = header.get(k + key.len() + 2..).unwrap_or_default();
            Ok::<&str, NpzError>(rest.trim_start().trim_start_matches(':').trim_start())
        };
        let descr = value("descr")?;
        let descr = descr
            .strip_prefix('\'')
            .and_then(|d| d.split('\'').next())
            .ok_or_else(|| bad("descr is not a simple type (a structured or object array?)"))?;
        // The byte order is the first character, whatever it is (a damaged header may start
        // with one of several bytes: splitting at byte 1 inside it panicked).
        let first = descr.chars().next().map_or(0, char::len_utf8);
        let (order, code) = descr.split_at(first);
        if !matches!(order, "<" | "|" | "=" | ">") {
            return Err(fault(NpzFault::Type(descr.to_string())));
        }
        let width = code.get(1..).and_then(|w| w.parse::<usize>().ok());
        let kind = match (code.get(..1), width) {
            (Some("f"), Some(s @ (2 | 4 | 8))) => Kind::Float(s),
            (Some("i"), Some(s @ (1 | 2 | 4 | 8))) => Kind::Int(s),
            (Some("u"), Some(s @ (1 | 2 | 4 | 8))) => Kind::Uint(s),
            (Some("b"), Some(1)) => Kind::Bool,
            (Some("U"), Some(n)) => Kind::Unicode(n),
            (Some("c"), _) => return Err(fault(NpzFault::Complex(descr.to_string()))),
            (Some("O"), _) => return Err(fault(NpzFault::Objects)),
            _ => return Err(fault(NpzFault::Type(descr.to_string()))),
        };
        let fortran = value("fortran_order")?.starts_with("True");
        let shape = value("shape")?;
        let shape = shape
            .strip_prefix('(')
            .and_then(|s| s.split(')').next())
            .ok_or_else(|| bad("shape is not a tuple"))?;
        let shape = shape
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(|s| s.trim_end_matches('L').parse::<usize>())
            .collect::<Result<Vec<_>, _>>()
            .map_err(|_| bad("shape is not a tuple of sizes"))?;
        let count = shape
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .and_then(|c| c.checked_mul(kind.size()))
            .ok_or_else(|| bad("shape too large"))?;
        let data = npy
            .get(at + len..)
            .and_then(|d| d.get(..count))
            .ok_or_else(|| bad("fewer values than its shape says"))?;
        // Big-endian values (`>f8`, as a big-endian machine or `astype('>f8')` saves them)
        // are turned round once, to the little-endian order the readers take.
        let data = if order == ">" {
            let width = match kind {
                Kind::Unicode(_) => 4,
                _ => kind.size(),
            };
            let mut turned = data.to_vec();
            turned
                .chunks_exact_mut(width.max(1))
                .for_each(<[u8]>::reverse);
            std::borrow::Cow::Owned(turned)
        } else {
            std::borrow::Cow::Borrowed(data)
        };
        Ok(Array {
            kind,
            shape,
            fortran,
            data,
        })
    }

    /// Every value of a numeric array as f64, in storage order, with its shape and order.
    fn numbers(&self, name: &str) -> Result<(Vec<f64>, Vec<usize>, bool), NpzError> {
        let a = self.array(name)?;
        let size = a.kind.size();
        let convert: fn(&[u8]) -> f64 = match a.kind {
            Kind::Float(8) => |b| f64::from_le_bytes(b.try_into().unwrap_or_default()),
            Kind::Float(2) => |b| {
                let h = u16::from_le_bytes(b.try_into().unwrap_or_default());
                f64::from(et_core::precision::f16_to_f32(h))
            },
            Kind::Float(_) => |b| f64::from(f32::from_le_bytes(b.try_into().unwrap_or_default())),
            Kind::Int(1) => |b| f64::from(b.first().map_or(0, |&v| v as i8)),
            Kind::Int(2) => |b| f64::from(i16::from_le_bytes(b.try_into().unwrap_or_default())),
            Kind::Int(4) => |b| f64::from(i32::from_le_bytes(b.try_into().unwrap_or_default())),
            Kind::Int(_) => |b| i64::from_le_bytes(b.try_into().unwrap_or_default()) as f64,
            Kind::Uint(1) | Kind::Bool => |b| f64::from(b.first().copied().unwrap_or(0)),
            Kind::Uint(2) => |b| f64::from(u16::from_le_bytes(b.try_into().unwrap_or_default())),
            Kind::Uint(4) => |b| f64::from(u32::from_le_bytes(b.try_into().unwrap_or_default())),
            Kind::Uint(_) => |b| u64::from_le_bytes(b.try_into().unwrap_or_default()) as f64,
            Kind::Unicode(_) => return Err(error(Some(name), NpzFault::TextNotNumbers)),
        };
        let values = a.data.chunks_exact(size).map(convert).collect();
        Ok((values, a.shape, a.fortran))
    }

    /// A 2-d numeric array as a matrix (any order, any numeric type; converted to f64).
    ///
    /// # Errors
    /// When it is missing, not 2-d, or not numbers.
    pub fn matrix(&self, name: &str) -> Result<DMatrix<f64>, NpzError> {
        let (values, shape, fortran) = self.numbers(name)?;
        let &[rows, cols] = shape.as_slice() else {
            let (found, want) = (shape.len(), 2);
            return Err(error(Some(name), NpzFault::Dimensions { found, want }));
        };
        Ok(if fortran {
            DMatrix::from_vec(rows, cols, values)
        } else {
            DMatrix::from_row_slice(rows, cols, &values)
        })
    }

    /// A 1-d numeric array as f64.
    ///
    /// # Errors
    /// When it is missing, not 1-d, or not numbers.
    pub fn vector(&self, name: &str) -> Result<Vec<f64>, NpzError> {
        let (values, shape, _) = self.numbers(name)?;
        if shape.len() != 1 {
            let (found, want) = (shape.len(), 1);
            return Err(error(Some(name), NpzFault::Dimensions { found, want }));
        }
        Ok(values)
    }

    /// A 1-d array of whole numbers in 0..=65535.
    ///
    /// # Errors
    /// As [`Npz::vector`], or for a value that is not such a number (naming its index).
    pub fn whole(&self, name: &str) -> Result<Vec<u16>, NpzError> {
        self.vector(name)?
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                (v.fract() == 0.0 && (0.0..=65535.0).contains(&v))
                    .then_some(v as u16)
                    .ok_or_else(|| error(Some(name), NpzFault::NotWhole { index: i, value: v }))
            })
            .collect()
    }

    /// A 0-d (or single-element) unicode array as text.
    ///
    /// # Errors
    /// When it is missing or not one text.
    pub fn text(&self, name: &str) -> Result<String, NpzError> {
        let a = self.array(name)?;
        if a.shape.iter().product::<usize>() != 1 || !matches!(a.kind, Kind::Unicode(_)) {
            return Err(error(Some(name), NpzFault::NotText));
        }
        a.data
            .chunks_exact(4)
            .map(|b| u32::from_le_bytes(b.try_into().unwrap_or_default()))
            .take_while(|&c| c != 0)
            .map(|c| char::from_u32(c).ok_or_else(|| error(Some(name), NpzFault::InvalidText)))
            .collect()
    }
}
