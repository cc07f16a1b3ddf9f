//! Discriminant analysis on the device (docs/method.md §9): QDA and LDA evaluated straight from a model
//! blob, a byte slice the caller owns (in flash on the board), validated once before use.
//!
//! Features are picked from V_m by index, then standardised: z_j = (V_m\[idx_j] - mean_j) /
//! scale_j. The model lives in z-space. Discriminants (docs/method.md §9, [5.6]-[5.7] as corrected there):
//!
//! ```text
//! QDA: delta_c(z) = -1/2 |L_c^-1 (z - mu_c)|^2 - 1/2 log|Sigma_c| + log pi_c,  Sigma_c = L_c L_c^T
//! LDA: delta_c(z) = z^T w_c - 1/2 mu_c^T Sigma^-1 mu_c + log pi_c,            w_c = Sigma^-1 mu_c
//! ```
//!
//! The prediction is argmax_c delta_c, with the margin to the runner-up as a confidence.
//!
//! A *referenced* model ([`FLAG_REFERENCED`]) was trained on V_m minus the untouched frame
//! V_0 taken when the sheet was put down (a "tare", as difference imaging does, docs/method.md §6):
//! this cancels what electrode movement between sessions does to the standing voltages. It is
//! evaluated with [`Model::evaluate_referenced`], which subtracts V_0 before standardising.
//!
//! # Blob layout (little-endian, version 1)
//!
//! | bytes | field |
//! | --- | --- |
//! | 0..4 | magic `ETDA` |
//! | 4..6 | version (u16) = [`MODEL_VERSION`] |
//! | 6 | kind: 0 QDA, 1 LDA |
//! | 7 | precision of the large tables: 0 f32, 1 f16 |
//! | 8..10, 10..12, 12..14 | classes C, features p, frame length K the model expects (u16) |
//! | 14 | electrodes L |
//! | 15, 16, 18..22 | protocol tag (0 AD, 1 PP, 2 PP-PP, 3 opposite, 4 custom), drive skip, measure skip mask (u32) |
//! | 17 | flags: bit 0 [`FLAG_REFERENCED`], other bits zero |
//! | 22..32 | reserved, zero |
//! | then | feature index (u16 x p, zero-padded to 4 bytes); mean, scale (f32 x p each); class positions in mm (f32 x 2C: x, y); log prior (f32 x C); constant (f32 x C: -1/2 log det Sigma_c for QDA, -1/2 mu_c^T Sigma^-1 mu_c for LDA) |
//! | then | QDA: class means mu_c (C x p), Cholesky factors L_c (C x p(p+1)/2, lower triangle packed by rows); LDA: weights w_c (C x p). In the stored precision, zero-padded to 4 bytes. |
//! | last 4 | CRC-32 (ISO-HDLC) of everything before it |
//!
//! A full-covariance QDA with C = 49, p = 96 takes 931 KB in f32 and 466 KB in f16
//! ([`model_len`]).

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use crate::config::ScanConfig;
use crate::precision::{f16_to_f32, f32_to_f16};
use crate::protocol::{Pattern, Protocol, ProtocolError, ProtocolKind, SkipSet};
use crate::wire::crc32;

/// The blob's first four bytes.
pub const MODEL_MAGIC: [u8; 4] = *b"ETDA";
/// The blob format version this build reads and writes.
pub const MODEL_VERSION: u16 = 1;
/// Header flag (byte 17, bit 0): features are V_m - V_0, the frame minus the untouched frame.
pub const FLAG_REFERENCED: u8 = 1;
/// Header length in bytes.
pub const HEADER_LEN: usize = 32;
/// Smallest allowed ratio of the smallest to the largest Cholesky diagonal entry of a class:
/// below it (condition number of Sigma_c above 1e10) f32 evaluation loses all precision, so
/// the blob is refused at load time instead of giving meaningless discriminants.
pub const MIN_PIVOT_RATIO: f32 = 1e-5;

/// Quadratic or linear discriminant analysis: the one name of a discriminant model's kind, in
/// the blob, in model files (`"qda"` or `"lda"`) and on the host.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ModelKind {
    /// One covariance per class [5.6].
    Qda,
    /// One pooled covariance [5.7].
    Lda,
}

impl ModelKind {
    /// The name in files and on the command line: `qda` or `lda`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ModelKind::Qda => "qda",
            ModelKind::Lda => "lda",
        }
    }
}

/// Storage precision of the large tables (class means, factors, weights).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
pub enum Precision {
    /// 4 bytes per value.
    F32,
    /// 2 bytes per value (IEEE binary16): half the flash, about 3 significant digits.
    F16,
}

impl Precision {
    fn bytes(self) -> usize {
        match self {
            Precision::F32 => 4,
            Precision::F16 => 2,
        }
    }
}

/// Why a model does not fit a scan configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mismatch {
    /// Different electrode count.
    Electrodes,
    /// Different protocol.
    Protocol,
}

/// The classifier's answer.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Decision {
    /// argmax_c delta_c.
    pub class: u16,
    /// delta of the winner.
    pub discriminant: f32,
    /// delta of the winner minus delta of the runner-up (>= 0).
    pub margin: f32,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Layout {
    feature_index: usize,
    mean: usize,
    scale: usize,
    positions: usize,
    log_prior: usize,
    constant: usize,
    vectors: usize,
    factors: usize,
    crc: usize,
}

fn packed_len(p: usize) -> usize {
    p * (p + 1) / 2
}

/// The tables' offsets for C = `classes` and p = `features`, or None when the blob would not
/// be addressable with `usize_max` as the largest address (`usize::MAX`; the tests pass
/// `u32::MAX` to check the board's 32-bit arithmetic on a 64-bit host). The sizes are summed
/// in u64, where no u16 C and p can overflow (at most about 2^49), so a crafted header can
/// never wrap the length into something that looks valid.
fn layout_within(
    kind: ModelKind,
    precision: Precision,
    classes: usize,
    features: usize,
    usize_max: u64,
) -> Option<Layout> {
    let (c, p) = (u64::try_from(classes).ok()?, u64::try_from(features).ok()?);
    if c > u64::from(u16::MAX) || p > u64::from(u16::MAX) {
        return None;
    }
    let pad4 = |n: u64| n.div_ceil(4) * 4;
    let b = precision.bytes() as u64;
    let feature_index = HEADER_LEN as u64;
    let mean = feature_index + pad4(2 * p);
    let scale = mean + 4 * p;
    let positions = scale + 4 * p;
    let log_prior = positions + 8 * c;
    let constant = log_prior + 4 * c;
    let vectors = constant + 4 * c;
    let factors = vectors + b * c * p;
    let end = match kind {
        ModelKind::Qda => factors + b * c * (p * (p + 1) / 2),
        ModelKind::Lda => factors,
    };
    let crc = pad4(end);
    // The CRC's 4 bytes must be addressable too.
    if crc + 4 > usize_max {
        return None;
    }
    let at = |n: u64| usize::try_from(n).ok();
    Some(Layout {
        feature_index: at(feature_index)?,
        mean: at(mean)?,
        scale: at(scale)?,
        positions: at(positions)?,
        log_prior: at(log_prior)?,
        constant: at(constant)?,
        vectors: at(vectors)?,
        factors: at(factors)?,
        crc: at(crc)?,
    })
}

fn layout(kind: ModelKind, precision: Precision, classes: usize, p: usize) -> Option<Layout> {
    layout_within(kind, precision, classes, p, usize::MAX as u64)
}

/// Bytes of a blob with these dimensions (header, tables and CRC); `usize::MAX` when C or p
/// exceed the format's u16 fields or the blob could not be addressed, so it never fits.
#[must_use]
pub fn model_len(kind: ModelKind, precision: Precision, classes: usize, features: usize) -> usize {
    layout(kind, precision, classes, features).map_or(usize::MAX, |l| l.crc + 4)
}

/// The u16 at `at`, or 0 past the end (a blob that passed `Model::parse` has every table).
fn rd_u16(b: &[u8], at: usize) -> u16 {
    b.get(at..)
        .and_then(<[u8]>::first_chunk)
        .map_or(0, |c| u16::from_le_bytes(*c))
}

/// The f32 at `at`, or NaN past the end (which every check refuses).
fn rd_f32(b: &[u8], at: usize) -> f32 {
    b.get(at..)
        .and_then(<[u8]>::first_chunk)
        .map_or(f32::NAN, |c| f32::from_le_bytes(*c))
}

fn protocol_tag(kind: ProtocolKind) -> (u8, Pattern) {
    let tag = match kind {
        ProtocolKind::Adjacent => 0,
        ProtocolKind::PseudoPolar => 1,
        ProtocolKind::PpPp => 2,
        ProtocolKind::Opposite => 3,
        ProtocolKind::Custom(_) => 4,
    };
    let pattern = match kind {
        ProtocolKind::Custom(p) => p,
        _ => Pattern {
            drive_skip: 0,
            measure_skips: SkipSet(0),
        },
    };
    (tag, pattern)
}

/// A validated model blob, evaluated in place (nothing copied out of `bytes`).
#[derive(Debug, Clone, Copy)]
pub struct Model<'a> {
    bytes: &'a [u8],
    kind: ModelKind,
    precision: Precision,
    classes: usize,
    features: usize,
    frame_len: usize,
    protocol: Protocol,
    layout: Layout,
    referenced: bool,
}

impl<'a> Model<'a> {
    /// Validates `bytes` completely (header, length, CRC, indices, finiteness, positive scales,
    /// positive and well-conditioned Cholesky diagonals) and wraps them.
    ///
    /// # Errors
    /// The first [`ModelError`] found; nothing of a refused blob is ever used.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, ModelError> {
        let model = Self::parse_header(bytes)?;
        // parse_header checked the length: the CRC is the last 4 bytes.
        let (body, stored_crc) = bytes.split_last_chunk::<4>().ok_or(ModelError::Checksum)?;
        if crc32(body) != u32::from_le_bytes(*stored_crc) {
            return Err(ModelError::Checksum);
        }
        model.check_tables()?;
        Ok(model)
    }

    /// Re-opens a blob that already passed [`parse`](Self::parse) and has not changed since,
    /// checking only its header (magic, version, kind, dimensions, protocol, length): O(1)
    /// instead of a pass over every table. The firmware uses it per frame on the model it
    /// verified at upload, which lives in storage it never writes while the model is active.
    /// Evaluation stays memory-safe on any bytes; only a blob that skipped `parse` could give
    /// wrong classes or a panic on an out-of-range feature index.
    ///
    /// # Errors
    /// The header's [`ModelError`]s.
    pub fn parse_header(bytes: &'a [u8]) -> Result<Self, ModelError> {
        let too_short = ModelError::Length {
            expected: 0,
            got: bytes.len(),
        };
        if bytes.len() < HEADER_LEN + 4 {
            return Err(too_short);
        }
        // The header as a fixed array: every index below is checked at compile time.
        let h: &[u8; HEADER_LEN] = bytes.first_chunk().ok_or(too_short)?;
        if h[..4] != MODEL_MAGIC {
            return Err(ModelError::Magic);
        }
        let version = rd_u16(h, 4);
        if version != MODEL_VERSION {
            return Err(ModelError::Version { got: version });
        }
        let kind = match h[6] {
            0 => ModelKind::Qda,
            1 => ModelKind::Lda,
            _ => return Err(ModelError::Header),
        };
        let precision = match h[7] {
            0 => Precision::F32,
            1 => Precision::F16,
            _ => return Err(ModelError::Header),
        };
        if h[17] & !FLAG_REFERENCED != 0 || h[22..32].iter().any(|&b| b != 0) {
            return Err(ModelError::Header);
        }
        let classes = usize::from(rd_u16(h, 8));
        let features = usize::from(rd_u16(h, 10));
        let frame_len = rd_u16(h, 12);
        // Dimensions before any arithmetic on them.
        if classes < 2 || features == 0 || features > usize::from(frame_len) {
            return Err(ModelError::Dimensions);
        }
        let layout = layout(kind, precision, classes, features).ok_or(ModelError::Dimensions)?;
        if bytes.len() != layout.crc + 4 {
            return Err(ModelError::Length {
                expected: layout.crc + 4,
                got: bytes.len(),
            });
        }
        let electrodes = h[14];
        let pattern = Pattern {
            drive_skip: h[16],
            measure_skips: SkipSet(u32::from_le_bytes([h[18], h[19], h[20], h[21]])),
        };
        let protocol_kind = match h[15] {
            0 => ProtocolKind::Adjacent,
            1 => ProtocolKind::PseudoPolar,
            2 => ProtocolKind::PpPp,
            3 => ProtocolKind::Opposite,
            4 => ProtocolKind::Custom(pattern),
            _ => return Err(ModelError::Header),
        };
        let protocol = Protocol::new(protocol_kind, electrodes).map_err(ModelError::Protocol)?;
        if usize::from(frame_len) != protocol.frame_len() {
            return Err(ModelError::FrameLength {
                expected: protocol.frame_len() as u16,
                got: frame_len,
            });
        }
        Ok(Self {
            bytes,
            kind,
            precision,
            classes,
            features,
            frame_len: usize::from(frame_len),
            protocol,
            layout,
            referenced: h[17] & FLAG_REFERENCED != 0,
        })
    }

    fn check_tables(&self) -> Result<(), ModelError> {
        let mut previous = None;
        for j in 0..self.features {
            let index = self.feature_index(j);
            if usize::from(index) >= self.frame_len {
                return Err(ModelError::FeatureIndex { feature: j as u16 });
            }
            if previous.is_some_and(|before| index <= before) {
                return Err(ModelError::FeatureOrder { feature: j as u16 });
            }
            previous = Some(index);
        }
        check_class_tables(self)
    }

    /// QDA or LDA.
    #[must_use]
    pub fn kind(&self) -> ModelKind {
        self.kind
    }

    /// Whether the model classifies V_m - V_0 (see the module docs): evaluate it with
    /// [`evaluate_referenced`](Self::evaluate_referenced).
    #[must_use]
    pub fn referenced(&self) -> bool {
        self.referenced
    }

    /// Storage precision of the large tables.
    #[must_use]
    pub fn precision(&self) -> Precision {
        self.precision
    }

    /// Number of classes C.
    #[must_use]
    pub fn classes(&self) -> usize {
        self.classes
    }

    /// Number of features p.
    #[must_use]
    pub fn features(&self) -> usize {
        self.features
    }

    /// The frame length K the model expects.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.frame_len
    }

    /// The protocol the model was trained on.
    #[must_use]
    pub fn protocol(&self) -> &Protocol {
        &self.protocol
    }

    /// Scratch length [`evaluate`](Self::evaluate) needs: 2p.
    #[must_use]
    pub fn scratch_len(&self) -> usize {
        2 * self.features
    }

    /// The blob's bytes.
    #[must_use]
    pub fn bytes(&self) -> &'a [u8] {
        self.bytes
    }

    /// Whether frames of `config` can be classified by this model.
    ///
    /// # Errors
    /// Which of electrode count or protocol differs.
    pub fn check_config(&self, config: &ScanConfig) -> Result<(), Mismatch> {
        if config.electrodes != self.protocol.electrodes() {
            return Err(Mismatch::Electrodes);
        }
        let theirs = config.protocol.pattern(config.electrodes);
        if theirs != self.protocol.pattern() {
            return Err(Mismatch::Protocol);
        }
        Ok(())
    }

    /// Frame index of feature `j`.
    #[must_use]
    pub fn feature_index(&self, j: usize) -> u16 {
        rd_u16(self.bytes, self.layout.feature_index + 2 * j)
    }

    fn mean(&self, j: usize) -> f32 {
        rd_f32(self.bytes, self.layout.mean + 4 * j)
    }

    fn scale(&self, j: usize) -> f32 {
        rd_f32(self.bytes, self.layout.scale + 4 * j)
    }

    /// Position of class `c`'s centre on the sheet, in mm.
    #[must_use]
    pub fn position_mm(&self, c: u16) -> [f32; 2] {
        let at = self.layout.positions + 8 * usize::from(c);
        [rd_f32(self.bytes, at), rd_f32(self.bytes, at + 4)]
    }

    fn log_prior(&self, c: usize) -> f32 {
        rd_f32(self.bytes, self.layout.log_prior + 4 * c)
    }

    fn constant(&self, c: usize) -> f32 {
        rd_f32(self.bytes, self.layout.constant + 4 * c)
    }

    fn stored(&self, at: usize, i: usize) -> f32 {
        match self.precision {
            Precision::F32 => rd_f32(self.bytes, at + 4 * i),
            Precision::F16 => f16_to_f32(rd_u16(self.bytes, at + 2 * i)),
        }
    }

    /// mu_c (QDA) or w_c (LDA), component j.
    fn vector(&self, c: usize, j: usize) -> f32 {
        self.stored(self.layout.vectors, c * self.features + j)
    }

    /// Packed lower-triangular L_c, entry i (row r, column q at i = r(r+1)/2 + q).
    fn factor(&self, c: usize, i: usize) -> f32 {
        self.stored(self.layout.factors, c * packed_len(self.features) + i)
    }
}

mod check;
mod error;
mod evaluate;
mod write;

pub use check::{ClassTables, check_class_tables};
pub use error::{EvalError, ModelError};
pub use write::{ModelTables, write_model};

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests;
