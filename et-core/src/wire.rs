//! The wire format between firmware and host.
//!
//! Device to host: [`Uplink`] ([`Frame`]s of V_m and [`Event`]s). Host to device: [`Command`].
//! Every message travels as one packet:
//!
//! ```text
//! 0x00 | COBS( WIRE_VERSION | postcard(message) | CRC-32(version | postcard) as u32 LE ) | 0x00
//! ```
//!
//! COBS removes every 0x00 from the packet, so 0x00 always delimits: after garbage, a
//! truncated packet or a flipped bit, the reader drops what it has and starts again at the
//! next 0x00, losing only the damaged packet. The CRC-32 (ISO-HDLC, as in zlib) catches what
//! postcard alone would decode into a wrong but valid message; the version byte lets a reader
//! refuse a peer it does not understand instead of misreading it.
//!
//! The golden byte vectors in this module's tests are the compatibility contract between
//! firmware and host: change them only together with [`WIRE_VERSION`].

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use heapless::Vec;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::config::ScanConfig;
use crate::protocol::K_MAX;
use crate::scan::ScanReport;
use crate::time::Micros;

/// Version of the packet format and of every message type in it.
pub const WIRE_VERSION: u8 = 1;
/// Bytes of model blob in one [`Command::ModelChunk`].
pub const MODEL_CHUNK: usize = 256;
/// Largest postcard body of any message (a frame of K_MAX f32 plus its header, with room).
pub const BODY_MAX: usize = 4 * K_MAX + 64;
/// Largest packet on the wire, delimiters included: body + version + CRC, COBS overhead, two 0x00.
pub const PACKET_MAX: usize = cobs_max_len(BODY_MAX + 5) + 2;
/// Largest command packet (the firmware's receive buffer).
pub const COMMAND_PACKET_MAX: usize = cobs_max_len(MODEL_CHUNK + 32) + 2;

/// The packets' CRC-32: slice-by-16 tables on the host (16 KB, about 0.2 ns a byte, which a
/// 32-electrode frame's 7 KB wants at tens of thousands of frames a second), one 1 KB table on
/// the board (its flash is small, its frames few).
#[cfg(feature = "std")]
const CRC32: crc::Crc<u32, crc::Table<16>> =
    crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISO_HDLC);
#[cfg(not(feature = "std"))]
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Frame flag: at least one measurement had samples on an ADC rail.
pub const FLAG_RAIL: u8 = 1 << 0;
/// Frame flag: one or more frames before this one were dropped (sequence gap is real).
pub const FLAG_DROPPED_BEFORE: u8 = 1 << 1;
/// Frame flag: V_m holds sub-section observations rather than a full-scan median.
pub const FLAG_SUBSECTION: u8 = 1 << 2;
/// Frame flag: the current source was in compliance for at least one measurement (its load
/// too high for the set current: a contact come loose, a dry electrode), so V_m is smaller
/// than the protocol expects.
pub const FLAG_COMPLIANCE: u8 = 1 << 3;

/// One scan: the frame vector V_m and everything needed to interpret it (docs/design.md: a frame
/// always says which protocol, electrode count and settings produced it).
///
/// `V` holds the voltages: a fixed [`K_MAX`] buffer on the board; on the host a heap vector
/// ([`HostFrame`]), the same bytes on the wire, so that decoding a frame moves a pointer
/// rather than the whole buffer (8 KB) from call to call.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frame<V = Vec<f32, K_MAX>> {
    /// Sequence number, +1 per frame produced (gaps = frames lost).
    pub seq: u32,
    /// When the scan started, device clock.
    pub timestamp: Micros,
    /// Protocol, L and scan settings that produced V_m.
    pub config: ScanConfig,
    /// `FLAG_*` bits.
    pub flags: u8,
    /// Number of measurements with rail samples (0 unless [`FLAG_RAIL`]).
    pub rail_count: u16,
    /// V_m in volts, K values in protocol step order (208 for AD at L = 16).
    pub voltages: V,
}

/// The host's [`Frame`]: its voltages on the heap.
#[cfg(feature = "std")]
pub type HostFrame = Frame<std::vec::Vec<f32>>;

/// The host's [`Uplink`]: what [`decode`] gives the host from the same packets the board
/// writes (a frame's voltages on the heap; [`HostUplink::fits`] checks their count).
#[cfg(feature = "std")]
pub type HostUplink = Uplink<std::vec::Vec<f32>>;

#[cfg(feature = "std")]
impl HostUplink {
    /// Whether a frame holds at most [`K_MAX`] values, as every frame the board can send
    /// does (a heap vector reads any count the packet holds).
    #[must_use]
    pub fn fits(&self) -> bool {
        match self {
            Uplink::Frame(f) => f.voltages.len() <= K_MAX,
            Uplink::Event(_) => true,
        }
    }
}

#[cfg(feature = "std")]
impl From<Frame> for HostFrame {
    fn from(f: Frame) -> Self {
        Self {
            seq: f.seq,
            timestamp: f.timestamp,
            config: f.config,
            flags: f.flags,
            rail_count: f.rail_count,
            voltages: f.voltages.to_vec(),
        }
    }
}

#[cfg(feature = "std")]
impl From<Uplink> for HostUplink {
    fn from(u: Uplink) -> Self {
        match u {
            Uplink::Frame(f) => Uplink::Frame(f.into()),
            Uplink::Event(e) => Uplink::Event(e),
        }
    }
}

impl Frame {
    /// The frame of one scan: V_m from `voltages` (K values), the rail flag and count and the
    /// compliance flag from `report`. `flags` are extra `FLAG_*` bits (e.g. [`FLAG_SUBSECTION`]).
    ///
    /// # Errors
    /// [`WireError::BufferFull`] if `voltages` is longer than [`K_MAX`].
    pub fn from_scan(
        seq: u32,
        timestamp: Micros,
        config: ScanConfig,
        report: &ScanReport,
        flags: u8,
        voltages: &[f32],
    ) -> Result<Self, WireError> {
        let rail_count = report.rail.count() as u16;
        let rail = if rail_count > 0 { FLAG_RAIL } else { 0 };
        let compliance = if report.compliance_steps > 0 {
            FLAG_COMPLIANCE
        } else {
            0
        };
        Ok(Self {
            seq,
            timestamp,
            config,
            flags: flags | rail | compliance,
            rail_count,
            voltages: Vec::from_slice(voltages).map_err(|_| WireError::BufferFull)?,
        })
    }
}

/// What the device reports besides frames.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// The on-chip classifier's answer for frame `seq` (docs/method.md §9).
    Touch {
        /// The frame classified.
        seq: u32,
        /// Winning class (index into the model's classes).
        class: u16,
        /// Discriminant of the winner minus the runner-up's (>= 0; larger = surer).
        margin: f32,
    },
    /// Periodic health report.
    Status(Status),
    /// Answer to [`Command::Ping`].
    Pong {
        /// The nonce of the ping.
        nonce: u32,
    },
    /// A command was carried out.
    Ack {
        /// Which command.
        command: CommandTag,
    },
    /// A command was refused; the device goes on as before.
    Refused {
        /// Which command (or [`CommandTag::Unknown`] when it could not be decoded).
        command: CommandTag,
        /// Why.
        reason: Refusal,
    },
    /// Something went wrong on the device while scanning or sending.
    Fault(Fault),
}

/// A device-side error, reported as [`Event::Fault`] when it happens (the counters in
/// [`Status`] keep the totals).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The front end failed during scan `seq`; that frame was not sent.
    Frontend {
        /// The scan that failed.
        seq: u32,
    },
    /// Frame `seq` had `measurements` measurements with samples on an ADC rail.
    Saturated {
        /// The frame.
        seq: u32,
        /// How many of its measurements.
        measurements: u16,
    },
    /// Electrode `electrode` looks disconnected or shorted.
    Electrode {
        /// The electrode.
        electrode: u8,
    },
    /// The link could not keep up: `dropped` frames were not sent since the last report.
    Overflow {
        /// Frames lost.
        dropped: u32,
    },
}

/// Device health, sent periodically as [`Event::Status`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Device clock now.
    pub uptime: Micros,
    /// Frames produced since boot.
    pub frames: u32,
    /// Frames dropped because the link was busy.
    pub dropped: u32,
    /// Frames with rail samples.
    pub rail_frames: u32,
    /// Packets received that failed to decode.
    pub bad_commands: u32,
    /// Bit e set = electrode e is suspected faulty (disconnected or shorted).
    pub suspect_electrodes: u32,
    /// Scanning now.
    pub scanning: bool,
    /// A validated model is loaded and classifying.
    pub model_loaded: bool,
}

/// Host to device.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(clippy::large_enum_variant)] // ModelChunk's inline buffer; boxing needs alloc.
pub enum Command {
    /// Use this scan configuration from the next scan on (validated before it is applied).
    Configure(ScanConfig),
    /// Start continuous scanning.
    Start,
    /// Stop scanning.
    Stop,
    /// Liveness check, answered with [`Event::Pong`].
    Ping {
        /// Echoed back.
        nonce: u32,
    },
    /// Begin a model upload of `len` bytes whose CRC-32 is `crc`.
    ModelBegin {
        /// Total blob length in bytes.
        len: u32,
        /// CRC-32 (ISO-HDLC) of the whole blob.
        crc: u32,
    },
    /// One chunk of the upload, at byte `offset`.
    ModelChunk {
        /// Offset of `data` in the blob.
        offset: u32,
        /// Up to [`MODEL_CHUNK`] bytes.
        data: Vec<u8, MODEL_CHUNK>,
    },
    /// Verify the uploaded blob (length, CRC, model validation) and switch to it; the old model
    /// stays in use if verification fails.
    ModelCommit,
    /// Stop classifying and forget the model.
    ModelClear,
    /// Take the next frame as the untouched frame V_0 that a referenced model subtracts (the
    /// sheet must not be touched while it is taken). Acknowledged once V_0 is stored.
    Tare,
}

impl Command {
    /// This command's tag, for [`Event::Ack`] and [`Event::Refused`].
    #[must_use]
    pub fn tag(&self) -> CommandTag {
        match self {
            Command::Configure(_) => CommandTag::Configure,
            Command::Start => CommandTag::Start,
            Command::Stop => CommandTag::Stop,
            Command::Ping { .. } => CommandTag::Ping,
            Command::ModelBegin { .. } => CommandTag::ModelBegin,
            Command::ModelChunk { .. } => CommandTag::ModelChunk,
            Command::ModelCommit => CommandTag::ModelCommit,
            Command::ModelClear => CommandTag::ModelClear,
            Command::Tare => CommandTag::Tare,
        }
    }
}

/// Names a [`Command`] without its data.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[allow(missing_docs)]
pub enum CommandTag {
    Configure,
    Start,
    Stop,
    Ping,
    ModelBegin,
    ModelChunk,
    ModelCommit,
    ModelClear,
    /// The packet did not decode to any command.
    Unknown,
    Tare,
}

/// Why the device refused a command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Refusal {
    /// The packet failed to decode (see [`WireError`]).
    Malformed(WireError),
    /// The configuration is invalid.
    BadConfig,
    /// A model command out of order (chunk before begin, commit before all bytes came, ...).
    UploadOrder,
    /// The blob does not fit the device's model storage.
    TooLarge,
    /// The uploaded blob failed its CRC or model validation; the old model is kept.
    BadModel,
    /// The model does not match the current scan configuration.
    ModelMismatch,
    /// The model storage failed (erase or write); the old model is kept.
    Storage,
}

/// Device to host.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[allow(clippy::large_enum_variant)] // a Frame is the common case; boxing needs alloc.
pub enum Uplink<V = Vec<f32, K_MAX>> {
    /// A scan.
    Frame(Frame<V>),
    /// Anything else.
    Event(Event),
}

/// Why a packet could not be encoded or decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum WireError {
    /// The output buffer is too small for the packet.
    #[error("output buffer too small for the packet")]
    BufferFull,
    /// The packet is not valid COBS.
    #[error("packet is not valid COBS")]
    Cobs,
    /// Shorter than version + CRC.
    #[error("packet too short")]
    Short,
    /// The CRC does not match: the packet was damaged.
    #[error("CRC mismatch (damaged packet)")]
    Crc,
    /// A version this reader does not understand.
    #[error("wire version {got}, this build speaks {WIRE_VERSION}")]
    Version {
        /// The version byte received.
        got: u8,
    },
    /// The CRC matched but the body is not a valid message.
    #[error("CRC ok but the body is not a valid message")]
    Body,
    /// The packet grew past the reader's buffer before its delimiter; it was dropped.
    #[error("packet longer than the receive buffer")]
    Overflow,
}

/// Largest postcard encoding of a [`Frame`]'s fields other than its voltages, with the
/// [`Uplink`] tag and the voltage count (varints at their widest).
pub const FRAME_HEADER_MAX: usize = 48;

/// Largest packet of a frame with `k` voltages, delimiters included (bytes on the wire).
#[must_use]
pub const fn frame_packet_max(k: usize) -> usize {
    // version byte + header + k f32 + CRC-32, COBS-encoded, between two 0x00.
    cobs_max_len(1 + FRAME_HEADER_MAX + 4 * k + 4) + 2
}

/// Bytes on the wire per frame besides the frame: one [`Event::Touch`] (at most 16 bytes as a
/// packet) when a model classifies, and a share of the status events.
pub const EVENTS_PER_FRAME_MAX: usize = 24;

/// The link's load under `config` at `baud` (8N1: 10 bits per byte): bytes per second that
/// frames and their events need at the configuration's frame rate, over the bytes per second
/// the line carries. Above 1 the device drops frames (and counts them).
#[must_use]
pub fn link_load(config: &ScanConfig, baud: u32) -> Option<f32> {
    let k = config.validate().ok()?.frame_len();
    let per_frame = (frame_packet_max(k) + EVENTS_PER_FRAME_MAX) as f32;
    Some(per_frame * config.frame_rate_hz() / (baud as f32 / 10.0))
}

/// Upper bound of COBS-encoding `n` bytes: one code byte per started run of 254.
#[must_use]
pub const fn cobs_max_len(n: usize) -> usize {
    n + n / 254 + 1
}

/// Encodes `message` as one packet (both delimiters included) into `out`; returns its length.
///
/// # Errors
/// [`WireError::BufferFull`] if `out` is too small (nothing useful is left in `out`).
// Writes our own message into `out`, whose length is checked before each index; nothing here
// comes from the wire (the property tests encode every message shape).
#[allow(clippy::indexing_slicing)]
pub fn encode<T: Serialize>(message: &T, out: &mut [u8]) -> Result<usize, WireError> {
    // Serialise at the back of `out`, leaving room in front for the COBS overhead and the
    // leading delimiter, then COBS-encode forward in place (the write position never passes
    // the read position).
    let n = out.len();
    let head = 2 + n / 254 + 1;
    if n < head + 6 {
        return Err(WireError::BufferFull);
    }
    let body_start = head;
    out[body_start] = WIRE_VERSION;
    let used = postcard::to_slice(message, &mut out[body_start + 1..n - 4])
        .map_err(|_| WireError::BufferFull)?
        .len();
    let body_end = body_start + 1 + used;
    let crc = CRC32.checksum(&out[body_start..body_end]);
    out[body_end..body_end + 4].copy_from_slice(&crc.to_le_bytes());
    let raw_len = 1 + used + 4;
    out[0] = 0;
    let encoded = cobs_encode_forward(out, body_start, raw_len, 1)?;
    let end = 1 + encoded;
    if end >= n {
        return Err(WireError::BufferFull);
    }
    out[end] = 0;
    Ok(end + 1)
}

/// COBS-encodes `buf[src..src + len]` into `buf[dst..]`, `dst < src`, returning the encoded
/// length. Safe in place because a block's code byte is written only after its data moved.
// Our own bytes, in bounds that `encode` checked (and the write position never passes the
// read position, checked per byte).
#[allow(clippy::indexing_slicing)]
fn cobs_encode_forward(
    buf: &mut [u8],
    src: usize,
    len: usize,
    dst: usize,
) -> Result<usize, WireError> {
    let mut w = dst; // next write position
    let mut code_pos = w;
    w += 1;
    let mut code: u8 = 1;
    for r in src..src + len {
        if w > r {
            return Err(WireError::BufferFull);
        }
        let byte = buf[r];
        if byte == 0 {
            buf[code_pos] = code;
            code_pos = w;
            w += 1;
            code = 1;
        } else {
            buf[w] = byte;
            w += 1;
            code += 1;
            if code == 0xFF {
                buf[code_pos] = code;
                code_pos = w;
                w += 1;
                code = 1;
            }
        }
    }
    if code_pos >= buf.len() {
        return Err(WireError::BufferFull);
    }
    buf[code_pos] = code;
    Ok(w - dst)
}

/// Decodes COBS in place (no delimiters in `buf`); returns the decoded length.
fn cobs_decode_in_place(buf: &mut [u8]) -> Result<usize, WireError> {
    // The write position w never passes the read position r.
    let (mut r, mut w) = (0, 0);
    while let Some(&code) = buf.get(r) {
        if code == 0 {
            return Err(WireError::Cobs);
        }
        r += 1;
        let end = r + usize::from(code) - 1;
        // The block's data: no zero inside, moved down to w (w < r) as one copy.
        if buf.get(r..end).is_none_or(|block| block.contains(&0)) {
            return Err(WireError::Cobs);
        }
        buf.copy_within(r..end, w);
        w += end - r;
        r = end;
        // A code below 0xFF ends with an implied zero, unless it ends the packet.
        if code != 0xFF && r < buf.len() {
            *buf.get_mut(w).ok_or(WireError::Cobs)? = 0;
            w += 1;
        }
    }
    Ok(w)
}

/// Decodes one packet's content (the bytes between two 0x00 delimiters, excluded), in place.
///
/// Never panics, whatever the bytes.
///
/// # Errors
/// [`WireError::Cobs`], [`WireError::Short`], [`WireError::Crc`], [`WireError::Version`] or
/// [`WireError::Body`], checked in that order.
pub fn decode<T: DeserializeOwned>(packet: &mut [u8]) -> Result<T, WireError> {
    let n = cobs_decode_in_place(packet)?;
    let raw = packet.get(..n).ok_or(WireError::Cobs)?;
    let Some((body, crc)) = raw.split_last_chunk::<4>() else {
        return Err(WireError::Short);
    };
    let [version, content @ ..] = body else {
        return Err(WireError::Short);
    };
    if CRC32.checksum(body) != u32::from_le_bytes(*crc) {
        return Err(WireError::Crc);
    }
    if *version != WIRE_VERSION {
        return Err(WireError::Version { got: *version });
    }
    match postcard::take_from_bytes::<T>(content) {
        Ok((message, [])) => Ok(message),
        _ => Err(WireError::Body),
    }
}

/// CRC-32 (ISO-HDLC) of `bytes`: the checksum of packets, model uploads and model blobs.
#[must_use]
pub fn crc32(bytes: &[u8]) -> u32 {
    CRC32.checksum(bytes)
}

mod accumulator;
pub use accumulator::Accumulator;

mod words;

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests;
