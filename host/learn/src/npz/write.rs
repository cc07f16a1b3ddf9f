//! What `numpy.savez` writes: an archive of stored `.npy` arrays, built in memory.

use nalgebra::DMatrix;

use super::NpzError;
use super::NpzFault;
use super::error;

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
