//! NumPy's `.npz` files, written and read without numpy: a zip archive of `.npy` arrays.
//!
//! What [`Writer`] makes is what `numpy.savez` makes: one uncompressed ("stored") zip entry
//! per array, `NAME.npy`, each a format-1.0 `.npy` file (magic, a header dictionary with
//! `descr`, `fortran_order` and `shape`, then the raw little-endian values). `numpy.load`
//! reads it without `allow_pickle`; Python's standard library reads it too (`zipfile`, then
//! `ast.literal_eval` on the header). Matrices are written in Fortran (column) order, which
//! is how `nalgebra` keeps them, so writing and reading are copies at disk speed.
//!
//! [`Npz::read`] takes back what numpy's `savez` writes as well (stored entries, C or Fortran
//! order, numbers of any common integer or float width, zip64 size fields); compressed
//! archives (`savez_compressed`), big-endian and object (pickled) arrays are refused with a
//! message saying so.
//!
//! Limits: a written archive stays under 4 GiB (no zip64 on write: about 500 million f64
//! values; more is refused with an error, never a broken file).

// Reads untrusted bytes: no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use nalgebra::DMatrix;

mod fault;

use fault::error;
pub use fault::{NpzError, NpzFault};

/// Largest offset or size a zip without zip64 holds.
const ZIP32_MAX: usize = 0xFFFF_FFFE;

/// Builds an archive in memory; [`Writer::finish`] returns its bytes.
#[derive(Default)]
#[allow(missing_debug_implementations)] // its bytes, not for printing
pub struct Writer {
    bytes: Vec<u8>,
    central: Vec<u8>,
    entries: u16,
    failed: Option<NpzError>,
}

impl Writer {
    /// An empty archive.
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `m` as a float64 array of shape (rows, cols).
    pub fn matrix(&mut self, name: &str, m: &DMatrix<f64>) {
        let mut data = Vec::with_capacity(8 * m.len());
        // nalgebra stores column-major: Fortran order is its memory as it is.
        for v in m.as_slice() {
            data.extend_from_slice(&v.to_le_bytes());
        }
        self.array(name, "<f8", true, &[m.nrows(), m.ncols()], &data);
    }

    /// Adds rows of pairs as a float64 array of shape (n, 2).
    pub fn pairs(&mut self, name: &str, rows: &[[f64; 2]]) {
        let data: Vec<u8> = rows
            .iter()
            .flatten()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        self.array(name, "<f8", false, &[rows.len(), 2], &data);
    }

    /// Adds a float64 vector.
    pub fn f64s(&mut self, name: &str, values: &[f64]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.array(name, "<f8", false, &[values.len()], &data);
    }

    /// Adds a uint16 vector.
    pub fn u16s(&mut self, name: &str, values: &[u16]) {
        let data: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        self.array(name, "<u2", false, &[values.len()], &data);
    }

    /// Adds a text as a 0-d unicode array (`str(npz[name])` in Python).
    pub fn text(&mut self, name: &str, text: &str) {
        let chars = text.chars().count().max(1);
        let mut data: Vec<u8> = text
            .chars()
            .flat_map(|c| u32::from(c).to_le_bytes())
            .collect();
        data.resize(4 * chars, 0);
        self.array(name, &format!("<U{chars}"), false, &[], &data);
    }

    fn array(&mut self, name: &str, descr: &str, fortran: bool, shape: &[usize], data: &[u8]) {
        self.entry(&format!("{name}.npy"), &npy(descr, fortran, shape, data));
    }
}

/// An `.npy` file's bytes: the header (version 1.0, padded to 64 bytes) and `data`.
fn npy(descr: &str, fortran: bool, shape: &[usize], data: &[u8]) -> Vec<u8> {
    let shape = match shape {
        [] => "()".to_string(),
        [n] => format!("({n},)"),
        _ => format!(
            "({})",
            shape
                .iter()
                .map(usize::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ),
    };
    let fortran = if fortran { "True" } else { "False" };
    let mut header =
        format!("{{'descr': '{descr}', 'fortran_order': {fortran}, 'shape': {shape}, }}");
    // Magic (6) + version (2) + header length (2) + header + '\n', to a multiple of 64.
    let unpadded = 10 + header.len() + 1;
    header.extend(std::iter::repeat_n(
        ' ',
        unpadded.next_multiple_of(64) - unpadded,
    ));
    header.push('\n');
    let mut npy = Vec::with_capacity(10 + header.len() + data.len());
    npy.extend_from_slice(b"\x93NUMPY\x01\x00");
    npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
    npy.extend_from_slice(header.as_bytes());
    npy.extend_from_slice(data);
    npy
}

/// A matrix as an `.npy` file's bytes: little-endian f64, rows in order (C order):
/// `numpy.load(path)` gives it back with its shape.
#[must_use]
pub fn npy_of_matrix(m: &DMatrix<f64>) -> Vec<u8> {
    let data: Vec<u8> = m
        .row_iter()
        .flat_map(|r| r.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<_>>())
        .collect();
    npy("<f8", false, &[m.nrows(), m.ncols()], &data)
}

/// The header of an `.npy` file of little-endian f64 values of `shape` in C order: what a
/// writer puts before values it streams.
#[must_use]
pub fn npy_header_f64(shape: &[usize]) -> Vec<u8> {
    npy("<f8", false, shape, &[])
}

/// `values` (C order) as an `.npy` file's bytes of `shape`: little-endian f64. `values.len()`
/// must be the shape's product (what is missing is written as NaN, what is over dropped).
#[must_use]
pub fn npy_of_array(values: &[f64], shape: &[usize]) -> Vec<u8> {
    let n: usize = shape.iter().product();
    let data: Vec<u8> = (0..n)
        .flat_map(|i| values.get(i).copied().unwrap_or(f64::NAN).to_le_bytes())
        .collect();
    npy("<f8", false, shape, &data)
}

impl Writer {
    fn entry(&mut self, file: &str, data: &[u8]) {
        if self.failed.is_some() {
            return;
        }
        let offset = self.bytes.len();
        if offset + data.len() + 30 + file.len() > ZIP32_MAX || self.entries == u16::MAX {
            self.failed = Some(error(None, NpzFault::TooLarge));
            return;
        }
        // crc32fast, not the wire format's `crc`: 10 to 35 times faster here (Cargo.toml says
        // by how much and how it was measured).
        let crc = crc32fast::hash(data);
        // Version 2.0, no flags, stored, time/date 0 (1980-01-01), crc, sizes, name length.
        let fixed = |signature: u32| {
            let mut h = signature.to_le_bytes().to_vec();
            if signature == 0x0201_4b50 {
                h.extend_from_slice(&20u16.to_le_bytes()); // made by
            }
            for v in [20u16, 0, 0, 0, 0x21] {
                h.extend_from_slice(&v.to_le_bytes());
            }
            h.extend_from_slice(&crc.to_le_bytes());
            for _ in 0..2 {
                h.extend_from_slice(&(data.len() as u32).to_le_bytes());
            }
            h.extend_from_slice(&(file.len() as u16).to_le_bytes());
            h.extend_from_slice(&0u16.to_le_bytes()); // extra length
            h
        };
        self.bytes.extend(fixed(0x0403_4b50));
        self.bytes.extend_from_slice(file.as_bytes());
        self.bytes.extend_from_slice(data);
        self.central.extend(fixed(0x0201_4b50));
        // Comment length, disk, internal and external attributes, local header offset.
        for v in [0u16, 0, 0] {
            self.central.extend_from_slice(&v.to_le_bytes());
        }
        self.central.extend_from_slice(&0u32.to_le_bytes());
        self.central
            .extend_from_slice(&(offset as u32).to_le_bytes());
        self.central.extend_from_slice(file.as_bytes());
        self.entries += 1;
    }

    /// The archive's bytes.
    ///
    /// # Errors
    /// When it would exceed 4 GiB (see the module docs).
    pub fn finish(mut self) -> Result<Vec<u8>, NpzError> {
        if let Some(e) = self.failed {
            return Err(e);
        }
        let start = self.bytes.len();
        if start + self.central.len() > ZIP32_MAX {
            return Err(error(None, NpzFault::TooLarge));
        }
        self.bytes.append(&mut self.central);
        let size = self.bytes.len() - start;
        self.bytes.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
        for v in [0u16, 0, self.entries, self.entries] {
            self.bytes.extend_from_slice(&v.to_le_bytes());
        }
        self.bytes.extend_from_slice(&(size as u32).to_le_bytes());
        self.bytes.extend_from_slice(&(start as u32).to_le_bytes());
        self.bytes.extend_from_slice(&0u16.to_le_bytes());
        Ok(self.bytes)
    }
}

/// One array as stored: its element type, shape and raw little-endian values.
struct Array<'a> {
    kind: Kind,
    shape: Vec<usize>,
    fortran: bool,
    data: &'a [u8],
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

    /// Indexes the archive in `bytes` (nothing is copied).
    ///
    /// # Errors
    /// When `bytes` is not a zip archive of stored `.npy` entries.
    pub fn read(bytes: Vec<u8>) -> Result<Self, NpzError> {
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
        let mut at = start;
        for _ in 0..count {
            let short = || broken("directory entry cut short");
            if bytes.get(at..at + 4) != Some(b"PK\x01\x02") {
                return Err(broken("directory entry without its signature"));
            }
            let method = u16_at(&bytes, at + 10).ok_or_else(short)?;
            let crc = u32_at(&bytes, at + 16).ok_or_else(short)?;
            let mut size = u32_at(&bytes, at + 20).ok_or_else(short)?;
            let stored_size = u32_at(&bytes, at + 24).ok_or_else(short)?;
            let name_len = u16_at(&bytes, at + 28).ok_or_else(short)?;
            let extra_len = u16_at(&bytes, at + 30).ok_or_else(short)?;
            let comment_len = u16_at(&bytes, at + 32).ok_or_else(short)?;
            let mut local = u32_at(&bytes, at + 42).ok_or_else(short)?;
            let name = bytes.get(at + 46..at + 46 + name_len).ok_or_else(short)?;
            let name = String::from_utf8_lossy(name).into_owned();
            // zip64 extra field: the 64-bit values of the fields set to 0xFFFFFFFF, in order.
            let extra = bytes
                .get(at + 46 + name_len..at + 46 + name_len + extra_len)
                .ok_or_else(short)?;
            let mut e = 0;
            while let (Some(id), Some(len)) = (u16_at(extra, e), u16_at(extra, e + 2)) {
                if id == 1 {
                    let (mut v, mut stored) = (e + 4, stored_size);
                    for field in [&mut size, &mut stored, &mut local] {
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
            if method != 0 {
                return Err(error(Some(array), NpzFault::Compressed));
            }
            let data_at = u16_at(&bytes, local + 26)
                .zip(u16_at(&bytes, local + 28))
                .filter(|_| bytes.get(local..local + 4) == Some(b"PK\x03\x04"))
                .map(|(n, x)| local + 30 + n + x)
                .ok_or_else(|| broken("local header missing"))?;
            let Some(data) = data_at
                .checked_add(size)
                .and_then(|end| bytes.get(data_at..end))
            else {
                return Err(error(Some(array), NpzFault::CutShort));
            };
            // Stored entries carry no other check: a flipped bit would be read as a value.
            if crc32fast::hash(data) as usize != crc {
                return Err(error(Some(array), NpzFault::Checksum));
            }
            if entries.iter().any(|(n, _)| n == array) {
                return Err(error(Some(array), NpzFault::Twice));
            }
            entries.push((array.to_string(), data_at..data_at + size));
        }
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
        if order == ">" {
            return Err(fault(NpzFault::BigEndian));
        }
        if !matches!(order, "<" | "|" | "=") {
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
