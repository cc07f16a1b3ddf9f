//! The device's logic, apart from its hardware: what the firmware does with each command and
//! each scan. The firmware only moves bytes and samples; everything that decides lives here,
//! where it is tested on the host.
//!
//! [`Device`] holds the scan configuration, the run state, the model upload and the active
//! model, the untouched frame V_0 of a referenced model, and the health counters of
//! [`Status`]. Per received packet the firmware calls [`Device::handle_packet`] and sends the
//! reply; per scan it calls [`Device::frame`] and sends the frame and, when a model is active,
//! the [`Event::Touch`] of the on-chip classification (docs/method.md §9).
//!
//! Models are uploaded into one of two slots of a [`ModelStore`] (flash on the board, RAM under
//! QEMU): the upload always goes to the slot that is not active, and only a blob that passes
//! its CRC-32, [`Model::parse`] and matches the scan configuration replaces the old model. A
//! failed or abandoned upload leaves the old model classifying. A commit is recorded at the
//! slot's end ([`commit`]), so a device that restarts classifies with its last model, under
//! the scan it was committed with, until it is cleared.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use heapless::Vec;

mod commit;

pub use commit::RECORD_BYTES;
use commit::{CLEARED_AT, Record, restorable};

use crate::config::ScanConfig;
use crate::model::Model;
use crate::protocol::{K_MAX, L_MAX, Protocol};
use crate::scan::ScanReport;
use crate::time::Micros;
use crate::wire::{
    self, Command, CommandTag, Event, FLAG_DROPPED_BEFORE, Fault, Frame, Refusal, Status, WireError,
};

/// Where model blobs are kept: two slots of [`capacity`](ModelStore::capacity) bytes.
pub trait ModelStore {
    /// What the storage can fail with.
    type Error: core::fmt::Debug;
    /// Bytes one slot holds (the largest model this device accepts).
    fn capacity(&self) -> usize;
    /// Makes slot `slot` (0 or 1) writable from offset 0 (flash: erases its sectors).
    ///
    /// # Errors
    /// When the storage fails.
    fn erase(&mut self, slot: usize) -> Result<(), Self::Error>;
    /// Writes `data` at byte `offset` of slot `slot`; offsets only grow between erases.
    ///
    /// # Errors
    /// When the storage fails.
    fn write(&mut self, slot: usize, offset: usize, data: &[u8]) -> Result<(), Self::Error>;
    /// The whole of slot `slot` (`capacity` bytes).
    fn read(&self, slot: usize) -> &[u8];
}

impl<S: ModelStore + ?Sized> ModelStore for &mut S {
    type Error = S::Error;
    fn capacity(&self) -> usize {
        (**self).capacity()
    }
    fn erase(&mut self, slot: usize) -> Result<(), Self::Error> {
        (**self).erase(slot)
    }
    fn write(&mut self, slot: usize, offset: usize, data: &[u8]) -> Result<(), Self::Error> {
        (**self).write(slot, offset, data)
    }
    fn read(&self, slot: usize) -> &[u8] {
        (**self).read(slot)
    }
}

/// A [`ModelStore`] in RAM: two slots of `N` bytes (the QEMU image and host tests).
#[derive(Debug, Clone)]
pub struct RamStore<const N: usize> {
    slots: [[u8; N]; 2],
}

impl<const N: usize> RamStore<N> {
    /// Two empty slots.
    #[must_use]
    pub const fn new() -> Self {
        Self {
            slots: [[0xff; N]; 2],
        }
    }
}

impl<const N: usize> Default for RamStore<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// A write outside a slot of a [`RamStore`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutOfRange;

impl<const N: usize> ModelStore for RamStore<N> {
    type Error = OutOfRange;
    fn capacity(&self) -> usize {
        N
    }
    fn erase(&mut self, slot: usize) -> Result<(), OutOfRange> {
        self.slots.get_mut(slot).ok_or(OutOfRange)?.fill(0xff);
        Ok(())
    }
    fn write(&mut self, slot: usize, offset: usize, data: &[u8]) -> Result<(), OutOfRange> {
        let end = offset.checked_add(data.len()).ok_or(OutOfRange)?;
        let slot = self.slots.get_mut(slot).ok_or(OutOfRange)?;
        slot.get_mut(offset..end)
            .ok_or(OutOfRange)?
            .copy_from_slice(data);
        Ok(())
    }
    fn read(&self, slot: usize) -> &[u8] {
        self.slots.get(slot).map_or(&[], |s| &s[..])
    }
}

/// An upload in progress.
#[derive(Debug, Clone, Copy)]
struct Upload {
    slot: usize,
    len: usize,
    crc: u32,
    received: usize,
    /// Length of the last chunk written (a resent chunk is acknowledged again).
    last_chunk: usize,
}

/// A model that passed verification: `len` bytes at the start of `slot`.
#[derive(Debug, Clone, Copy)]
struct Active {
    slot: usize,
    len: usize,
}

/// The verified model in `active`'s slot, reopened by its header only (it passed
/// [`Model::parse`] at commit and its slot is not written while it is active).
fn active_model<S: ModelStore>(store: &S, active: Option<Active>) -> Option<Model<'_>> {
    let a = active?;
    Model::parse_header(store.read(a.slot).get(..a.len)?).ok()
}

/// `blob` as a model the device takes under `config`: its CRC-32 is `crc`, it parses, its
/// features fit the evaluation's scratch, and it classifies frames of `config` (checked at
/// commit, and again at a restart before it is restored).
fn verified<'b>(blob: &'b [u8], crc: u32, config: &ScanConfig) -> Result<Model<'b>, Refusal> {
    if wire::crc32(blob) != crc {
        return Err(Refusal::BadModel);
    }
    let model = Model::parse(blob).map_err(|_| Refusal::BadModel)?;
    if model.features() > FEATURES_MAX {
        return Err(Refusal::TooLarge);
    }
    if model.check_config(config).is_err() {
        return Err(Refusal::ModelMismatch);
    }
    Ok(model)
}

/// Most features an on-chip model may use (its evaluation scratch is 2 p values).
pub const FEATURES_MAX: usize = 512;

/// A rail hit on at least this share of the measurements that probe an electrode makes it a
/// suspect (disconnected), in percent. An open probe rails every measurement it takes part in;
/// its neighbours share half of theirs with it, so the threshold sits well above one half.
pub const SUSPECT_RAIL_PERCENT: usize = 90;

/// The device's state machine (see the module docs).
#[derive(Debug)]
pub struct Device<S> {
    store: S,
    config: ScanConfig,
    protocol: Protocol,
    /// The scan task has not yet picked up `config`.
    reconfigure: bool,
    /// The configuration of the last frame scanned, which the device goes back to when the
    /// front end refuses a new one ([`Device::front_end_refused`]).
    last_scanned: Option<ScanConfig>,
    scanning: bool,
    upload: Option<Upload>,
    active: Option<Active>,
    /// The generation of the last commit recorded ([`commit`]).
    generation: u32,
    /// V_0 for referenced models (empty until tared).
    reference: Vec<f32, K_MAX>,
    tare_pending: bool,
    /// The pending tare is a restored referenced model's, which no host asked for (its
    /// V_0 is taken unacknowledged).
    tare_unasked: bool,
    seq: u32,
    dropped_since_last: bool,
    status: Status,
    scratch: [f32; 2 * FEATURES_MAX],
}

/// What one scan produces for the link: the frame and, with a model active, its class.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The frame to send.
    pub frame: Frame,
    /// [`Event::Touch`] from the on-chip classifier, [`Event::Fault`] for a newly suspected
    /// electrode, or an [`Event::Ack`] of [`Command::Tare`] once V_0 is stored.
    pub events: Vec<Event, 3>,
}

impl<S: ModelStore> Device<S> {
    /// A stopped device with `config` (which must be valid: it is the firmware's default), or,
    /// when `store` holds a committed model that was not cleared, with that model active
    /// under the scan it was committed with (the latest commit of the two slots; a referenced
    /// model takes V_0 from the first frame it scans).
    ///
    /// # Errors
    /// The configuration's error if it is invalid.
    pub fn new(store: S, config: ScanConfig) -> Result<Self, crate::config::ConfigError> {
        let protocol = config.validate()?;
        let mut device = Self {
            store,
            config,
            protocol,
            reconfigure: true,
            last_scanned: None,
            scanning: false,
            upload: None,
            active: None,
            generation: 0,
            reference: Vec::new(),
            tare_pending: false,
            tare_unasked: false,
            seq: 0,
            dropped_since_last: false,
            status: Status::default(),
            scratch: [0.0; 2 * FEATURES_MAX],
        };
        let latest = (0..2)
            .filter_map(|slot| restorable(&device.store, slot))
            .max_by_key(|r| r.record.generation);
        if let Some(r) = latest {
            device.active = Some(r.active);
            device.generation = r.record.generation;
            device.config = r.record.config;
            device.protocol = r.protocol;
            device.tare_pending = r.referenced;
            device.tare_unasked = r.referenced;
        }
        Ok(device)
    }

    /// The configuration scans use.
    #[must_use]
    pub fn config(&self) -> &ScanConfig {
        &self.config
    }

    /// Whether the scan task should scan.
    #[must_use]
    pub fn scanning(&self) -> bool {
        self.scanning
    }

    /// The new configuration, once, after it changed (the scan task rebuilds its
    /// [`Scanner`](crate::Scanner) with it); `None` when nothing changed.
    pub fn take_reconfigure(&mut self) -> Option<ScanConfig> {
        core::mem::take(&mut self.reconfigure).then_some(self.config)
    }

    /// The front end refused the configuration [`Device::take_reconfigure`] gave (the scan
    /// task could not build its scanner: another electrode count than the sheet it emulates,
    /// a gain it lacks): the device goes back to the configuration of the last frame it
    /// scanned, which the scan task picks up next, and returns it; None when it has scanned
    /// none or that one was refused (it stayed on a scan it could not make until reset, and
    /// every host after it got no frames).
    pub fn front_end_refused(&mut self) -> Option<ScanConfig> {
        let last = self.last_scanned.filter(|last| *last != self.config)?;
        self.protocol = last.validate().ok()?;
        self.config = last;
        self.reference.clear();
        self.status.suspect_electrodes = 0;
        self.reconfigure = true;
        Some(last)
    }

    /// The sequence number the next frame will carry.
    #[must_use]
    pub fn next_seq(&self) -> u32 {
        self.seq
    }

    /// The health report as of `uptime`.
    #[must_use]
    pub fn status(&self, uptime: Micros) -> Status {
        Status {
            uptime,
            scanning: self.scanning,
            model_loaded: self.active.is_some(),
            ..self.status
        }
    }

    /// The active model, if any.
    #[must_use]
    pub fn model(&self) -> Option<Model<'_>> {
        active_model(&self.store, self.active)
    }

    /// The model storage.
    #[must_use]
    pub fn store(&self) -> &S {
        &self.store
    }

    /// Decodes one received packet (delimiters stripped, decoded in place) and handles it; the
    /// reply is always an event to send (a refusal for a packet that does not decode).
    pub fn handle_packet(&mut self, packet: &mut [u8]) -> Option<Event> {
        self.handle_decoded(wire::decode(packet))
    }

    /// Handles the outcome of decoding one packet (from [`wire::Accumulator::feed`]). Returns
    /// the reply, or `None` for [`Command::Tare`], whose acknowledgement comes with the frame
    /// that becomes V_0.
    pub fn handle_decoded(&mut self, packet: Result<Command, WireError>) -> Option<Event> {
        match packet {
            Ok(command) => self.handle(command),
            Err(e) => {
                self.status.bad_commands = self.status.bad_commands.saturating_add(1);
                Some(Event::Refused {
                    command: CommandTag::Unknown,
                    reason: Refusal::Malformed(e),
                })
            }
        }
    }

    /// Carries out `command`; returns the reply (see [`handle_decoded`](Self::handle_decoded)).
    pub fn handle(&mut self, command: Command) -> Option<Event> {
        let tag = command.tag();
        let outcome = match command {
            Command::Configure(config) => self.configure(config),
            Command::Start => {
                self.scanning = true;
                Ok(())
            }
            Command::Stop => {
                self.scanning = false;
                Ok(())
            }
            Command::Ping { nonce } => return Some(Event::Pong { nonce }),
            Command::ModelBegin { len, crc } => self.begin(len as usize, crc),
            Command::ModelChunk { offset, data } => self.chunk(offset as usize, &data),
            Command::ModelCommit => self.commit(),
            Command::ModelClear => self.clear(),
            Command::Tare => {
                self.tare_pending = true;
                self.tare_unasked = false;
                return None;
            }
        };
        Some(match outcome {
            Ok(()) => Event::Ack { command: tag },
            Err(reason) => {
                self.status.bad_commands = self.status.bad_commands.saturating_add(1);
                Event::Refused {
                    command: tag,
                    reason,
                }
            }
        })
    }

    fn configure(&mut self, config: ScanConfig) -> Result<(), Refusal> {
        self.protocol = config.validate().map_err(|_| Refusal::BadConfig)?;
        if config != self.config {
            // V_0 belongs to the old configuration; suspicions are re-earned under the new one.
            self.reference.clear();
            self.status.suspect_electrodes = 0;
        }
        self.config = config;
        self.reconfigure = true;
        Ok(())
    }

    fn begin(&mut self, len: usize, crc: u32) -> Result<(), Refusal> {
        self.upload = None;
        if len > self.store.capacity().saturating_sub(RECORD_BYTES) {
            return Err(Refusal::TooLarge);
        }
        let slot = self.active.map_or(0, |a| 1 - a.slot);
        self.store.erase(slot).map_err(|_| Refusal::Storage)?;
        self.upload = Some(Upload {
            slot,
            len,
            crc,
            received: 0,
            last_chunk: 0,
        });
        Ok(())
    }

    fn chunk(&mut self, offset: usize, data: &[u8]) -> Result<(), Refusal> {
        let up = self.upload.as_mut().ok_or(Refusal::UploadOrder)?;
        // The previous chunk again (its acknowledgement was lost): accept it if it is the same.
        if up.last_chunk > 0 && offset + up.last_chunk == up.received && data.len() == up.last_chunk
        {
            let written = self.store.read(up.slot).get(offset..up.received);
            return if written == Some(data) {
                Ok(())
            } else {
                Err(Refusal::UploadOrder)
            };
        }
        if offset != up.received || data.is_empty() {
            return Err(Refusal::UploadOrder);
        }
        if offset + data.len() > up.len {
            return Err(Refusal::TooLarge);
        }
        if self.store.write(up.slot, offset, data).is_err() {
            self.upload = None;
            return Err(Refusal::Storage);
        }
        up.received += data.len();
        up.last_chunk = data.len();
        Ok(())
    }

    fn commit(&mut self) -> Result<(), Refusal> {
        let up = self.upload.ok_or(Refusal::UploadOrder)?;
        if up.received != up.len {
            return Err(Refusal::UploadOrder);
        }
        self.upload = None;
        let bytes = self
            .store
            .read(up.slot)
            .get(..up.len)
            .ok_or(Refusal::BadModel)?;
        verified(bytes, up.crc, &self.config)?;
        // Recorded, so that a restart finds it; a model that cannot be is not taken.
        let record = Record {
            generation: self.generation.wrapping_add(1),
            len: up.len,
            crc: up.crc,
            config: self.config,
        };
        let at = self.store.capacity().saturating_sub(RECORD_BYTES);
        let bytes = record.encode().ok_or(Refusal::Storage)?;
        self.store
            .write(up.slot, at, &bytes)
            .map_err(|_| Refusal::Storage)?;
        self.generation = record.generation;
        self.active = Some(Active {
            slot: up.slot,
            len: up.len,
        });
        Ok(())
    }

    /// No model from now on, nor after a restart: both slots' records marked cleared (an
    /// upload in progress is abandoned: its slot is erased again when the next begins).
    fn clear(&mut self) -> Result<(), Refusal> {
        self.active = None;
        self.upload = None;
        let at = self.store.capacity().saturating_sub(RECORD_BYTES) + CLEARED_AT;
        let mut written = Ok(());
        for slot in 0..2 {
            if self.store.read(slot).get(at..at + 4) != Some(&[0; 4]) {
                written = written.and(self.store.write(slot, at, &[0; 4]));
            }
        }
        written.map_err(|_| Refusal::Storage)
    }

    /// Records that a frame was produced but could not be sent (the link was busy): it counts
    /// in [`Status::dropped`] and the next frame carries [`FLAG_DROPPED_BEFORE`].
    pub fn dropped(&mut self) {
        self.status.dropped = self.status.dropped.saturating_add(1);
        self.dropped_since_last = true;
    }

    /// Turns one scan made under `config` into the frame to send, and classifies it with the
    /// active model. `v_m` holds the scan's K voltages; `flags` are extra frame flags (e.g.
    /// [`wire::FLAG_SUBSECTION`]). A scan under a configuration that has changed since it
    /// started (a `Configure` arrived meanwhile) is sent as what it is, without classification
    /// or tare.
    ///
    /// # Errors
    /// [`WireError::BufferFull`] if `v_m` is longer than [`K_MAX`].
    pub fn frame(
        &mut self,
        config: &ScanConfig,
        timestamp: Micros,
        report: &ScanReport,
        v_m: &[f32],
        flags: u8,
    ) -> Result<Output, WireError> {
        let seq = self.seq;
        self.seq = self.seq.wrapping_add(1);
        let dropped = if core::mem::take(&mut self.dropped_since_last) {
            FLAG_DROPPED_BEFORE
        } else {
            0
        };
        let frame = Frame::from_scan(seq, timestamp, *config, report, flags | dropped, v_m)?;
        self.last_scanned = Some(*config);
        let current = *config == self.config;
        self.status.frames = self.status.frames.saturating_add(1);
        let mut events = Vec::new();
        if frame.rail_count > 0 {
            self.status.rail_frames = self.status.rail_frames.saturating_add(1);
            let suspects = self.suspects(report);
            let new = suspects & !self.status.suspect_electrodes;
            self.status.suspect_electrodes |= suspects;
            if new != 0 {
                let electrode = new.trailing_zeros() as u8;
                let _ = events.push(Event::Fault(Fault::Electrode { electrode }));
            }
        }
        if !current {
            return Ok(Output { frame, events });
        }
        if self.tare_pending && v_m.len() == self.protocol.frame_len() {
            self.tare_pending = false;
            self.reference.clear();
            let _ = self.reference.extend_from_slice(v_m);
            if !core::mem::take(&mut self.tare_unasked) {
                let _ = events.push(Event::Ack {
                    command: CommandTag::Tare,
                });
            }
        }
        if let Some(touch) = self.classify(seq, v_m) {
            let _ = events.push(touch);
        }
        Ok(Output { frame, events })
    }

    fn classify(&mut self, seq: u32, v_m: &[f32]) -> Option<Event> {
        // Borrows only the store, so the scratch below stays free to borrow mutably.
        let model = active_model(&self.store, self.active)?;
        model.check_config(&self.config).ok()?;
        let v_0 = match model.referenced() {
            // A referenced model waits for Command::Tare.
            true if self.reference.is_empty() => return None,
            true => Some(&self.reference[..]),
            false => None,
        };
        let decision = model
            .evaluate_referenced(v_m, v_0, &mut self.scratch)
            .ok()?;
        Some(Event::Touch {
            seq,
            class: decision.class,
            margin: decision.margin,
        })
    }

    /// Electrodes whose measurements hit a rail on at least [`SUSPECT_RAIL_PERCENT`] of the
    /// steps that probe them (an open probe floats to a rail). Bit e = electrode e.
    fn suspects(&self, report: &ScanReport) -> u32 {
        let mut probed = [0u16; L_MAX as usize];
        let mut railed = [0u16; L_MAX as usize];
        for step in self.protocol.steps() {
            let hit = report.rail.get(usize::from(step.k));
            for e in [step.measurement.positive.0, step.measurement.negative.0] {
                let e = usize::from(e);
                if let (Some(p), Some(r)) = (probed.get_mut(e), railed.get_mut(e)) {
                    *p += 1;
                    *r += u16::from(hit);
                }
            }
        }
        let mut bits = 0u32;
        let electrodes = usize::from(self.protocol.electrodes());
        for (e, (&p, &r)) in probed.iter().zip(&railed).enumerate().take(electrodes) {
            if p > 0 && usize::from(r) * 100 >= SUSPECT_RAIL_PERCENT * usize::from(p) {
                bits |= 1 << e;
            }
        }
        bits
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests;
