//! The record of a committed model, kept in the last [`RECORD_BYTES`] of its slot: a device
//! that restarts (a reset, a power cycle, a watchdog) finds the model it last committed and
//! the scan it was committed under, and classifies again without a host to upload it.
//!
//! | bytes of the record | field |
//! | --- | --- |
//! | 0..4 | `etMC` |
//! | 4..8 | its generation (u32 LE): one more than the commit before it |
//! | 8..12 | the blob's length in bytes (u32 LE), from the slot's start |
//! | 12..16 | the blob's CRC-32 (u32 LE) |
//! | 16 | n, the scan configuration's postcard length |
//! | 17..17 + n | the scan configuration (postcard, as `Command::Configure` carries it) |
//! | 60..64 | all ones; zeros once the model is cleared (`Command::ModelClear`) |
//!
//! It is written after the blob and the cleared word after it (offsets only grow in a slot
//! between erases); erased flash reads all ones, so a slot never committed has no record.

use super::{Active, ModelStore, verified};
use crate::config::ScanConfig;
use crate::protocol::Protocol;

/// Bytes the record takes at the end of each slot; a model blob may use the rest.
pub const RECORD_BYTES: usize = 64;

const MAGIC: [u8; 4] = *b"etMC";

/// Where the cleared word starts in the record.
pub(super) const CLEARED_AT: usize = RECORD_BYTES - 4;

/// Where the configuration starts in the record, after its length byte.
const CONFIG_AT: usize = 17;

/// One commit: the blob at the slot's start and the scan it was verified under.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Record {
    pub(super) generation: u32,
    pub(super) len: usize,
    pub(super) crc: u32,
    pub(super) config: ScanConfig,
}

impl Record {
    /// The record's bytes but its cleared word; None when the configuration does not encode
    /// in the room it has (no valid one is that long).
    pub(super) fn encode(&self) -> Option<[u8; CLEARED_AT]> {
        let mut out = [0xff; CLEARED_AT];
        let len = u32::try_from(self.len).ok()?;
        let fields = [
            MAGIC,
            self.generation.to_le_bytes(),
            len.to_le_bytes(),
            self.crc.to_le_bytes(),
        ];
        for (i, field) in fields.iter().enumerate() {
            out.get_mut(4 * i..4 * i + 4)?.copy_from_slice(field);
        }
        let used = postcard::to_slice(&self.config, out.get_mut(CONFIG_AT..)?)
            .ok()?
            .len();
        *out.get_mut(CONFIG_AT - 1)? = u8::try_from(used).ok()?;
        Some(out)
    }

    /// The record at the end of `slot` (the slot's whole bytes); None when there is none,
    /// it is damaged, or the model was cleared.
    pub(super) fn read(slot: &[u8]) -> Option<Self> {
        let at = slot.len().checked_sub(RECORD_BYTES)?;
        let record = slot.get(at..)?;
        let word = |i: usize| -> Option<[u8; 4]> { record.get(4 * i..4 * i + 4)?.try_into().ok() };
        if word(0)? != MAGIC || word(CLEARED_AT / 4)? != [0xff; 4] {
            return None;
        }
        let used = usize::from(*record.get(CONFIG_AT - 1)?);
        let config = record.get(CONFIG_AT..(CONFIG_AT + used).min(CLEARED_AT))?;
        Some(Self {
            generation: u32::from_le_bytes(word(1)?),
            len: usize::try_from(u32::from_le_bytes(word(2)?)).ok()?,
            crc: u32::from_le_bytes(word(3)?),
            config: postcard::from_bytes(config).ok()?,
        })
    }
}

/// A model found at a restart: where it is, its record, its scan's protocol, and whether it
/// is referenced.
pub(super) struct Restored {
    pub(super) active: Active,
    pub(super) record: Record,
    pub(super) protocol: Protocol,
    pub(super) referenced: bool,
}

/// Of a slot's record (a commit, not cleared), the model it names if the blob is there whole
/// and passes the checks of a commit under the record's scan.
pub(super) fn restorable<S: ModelStore>(store: &S, slot: usize) -> Option<Restored> {
    let bytes = store.read(slot);
    let record = Record::read(bytes)?;
    if record.len > store.capacity().saturating_sub(RECORD_BYTES) {
        return None;
    }
    let protocol = record.config.validate().ok()?;
    let model = verified(bytes.get(..record.len)?, record.crc, &record.config).ok()?;
    Some(Restored {
        active: Active {
            slot,
            len: record.len,
        },
        record,
        protocol,
        referenced: model.referenced(),
    })
}
