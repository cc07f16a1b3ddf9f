use std::vec::Vec as StdVec;

use super::*;
use crate::model::{FLAG_REFERENCED, ModelKind, ModelTables, Precision, model_len, write_model};
use crate::protocol::ProtocolKind;
use crate::wire::{MODEL_CHUNK, encode};

/// L = 8, opposite protocol (K = 32).
fn config() -> ScanConfig {
    ScanConfig {
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        ..ScanConfig::REFERENCE
    }
}

const K: usize = 32;
/// Upload chunk: smaller than the test blobs, so an upload takes several.
const CHUNK: usize = 64;

fn device() -> Device<RamStore<4096>> {
    Device::new(RamStore::new(), config()).unwrap()
}

/// An LDA over features 0, 1, 2 of V_m with w_c = e_c: class c wins when V_m[c] is the
/// largest of the three (z = V_m[j] with mean 0, scale 1).
fn blob(referenced: bool, protocol: ProtocolKind) -> StdVec<u8> {
    let eye = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let tables = ModelTables {
        kind: ModelKind::Lda,
        precision: Precision::F32,
        referenced,
        electrodes: 8,
        protocol,
        feature_index: &[0, 1, 2],
        mean: &[0.0; 3],
        scale: &[1.0; 3],
        positions_mm: &[[0.0, 0.0], [10.0, 0.0], [20.0, 0.0]],
        log_prior: &[0.0; 3],
        constant: &[0.0; 3],
        vectors: &eye,
        factors: &[],
    };
    let mut out = vec![0u8; model_len(ModelKind::Lda, Precision::F32, 3, 3)];
    let n = write_model(&tables, &mut out).unwrap();
    out.truncate(n);
    out
}

/// Sends `blob` as an upload and returns the replies (begin, chunks, commit).
fn upload<S: ModelStore>(d: &mut Device<S>, blob: &[u8], crc: u32) -> StdVec<Option<Event>> {
    let mut replies = vec![d.handle(Command::ModelBegin {
        len: blob.len() as u32,
        crc,
    })];
    for (i, chunk) in blob.chunks(CHUNK).enumerate() {
        replies.push(d.handle(Command::ModelChunk {
            offset: (i * CHUNK) as u32,
            data: Vec::from_slice(chunk).unwrap(),
        }));
    }
    replies.push(d.handle(Command::ModelCommit));
    replies
}

fn ack(command: CommandTag) -> Option<Event> {
    Some(Event::Ack { command })
}

fn refused(command: CommandTag, reason: Refusal) -> Option<Event> {
    Some(Event::Refused { command, reason })
}

/// A frame whose class (under [`blob`]) is `class`.
fn frame_of(class: usize) -> StdVec<f32> {
    let mut v = vec![0.1; K];
    v[class] = 1.0;
    v
}

fn touches(out: &Output) -> StdVec<u16> {
    out.events
        .iter()
        .filter_map(|e| match e {
            Event::Touch { class, .. } => Some(*class),
            _ => None,
        })
        .collect()
}

#[test]
fn ping_start_stop_and_configure() {
    assert_eq!(config().validate().unwrap().frame_len(), K);
    let mut d = device();
    assert_eq!(
        d.take_reconfigure(),
        Some(config()),
        "the default is picked up once"
    );
    assert_eq!(d.take_reconfigure(), None);
    assert_eq!(
        d.handle(Command::Ping { nonce: 7 }),
        Some(Event::Pong { nonce: 7 })
    );
    assert!(!d.scanning());
    assert_eq!(d.handle(Command::Start), ack(CommandTag::Start));
    assert!(d.scanning() && d.status(Micros(5)).scanning);
    assert_eq!(d.handle(Command::Stop), ack(CommandTag::Stop));
    assert!(!d.scanning());

    let bad = ScanConfig {
        electrodes: 7,
        ..config()
    };
    assert_eq!(
        d.handle(Command::Configure(bad)),
        refused(CommandTag::Configure, Refusal::BadConfig)
    );
    assert_eq!(
        d.config(),
        &config(),
        "a refused configuration changes nothing"
    );
    assert_eq!(d.take_reconfigure(), None);
    assert_eq!(d.status(Micros(0)).bad_commands, 1);

    let pp = ScanConfig {
        protocol: ProtocolKind::PseudoPolar,
        ..config()
    };
    assert_eq!(d.handle(Command::Configure(pp)), ack(CommandTag::Configure));
    assert_eq!(d.take_reconfigure(), Some(pp));
}

#[test]
fn damaged_packets_are_refused_and_counted() {
    let mut d = device();
    let mut buf = [0u8; 64];
    let n = encode(&Command::Ping { nonce: 1 }, &mut buf).unwrap();
    // Without the delimiters, as the accumulator hands it over.
    let mut good = buf[1..n - 1].to_vec();
    assert_eq!(
        d.handle_packet(&mut good.clone()),
        Some(Event::Pong { nonce: 1 })
    );
    good[3] ^= 0x10;
    assert_eq!(
        d.handle_packet(&mut good),
        refused(CommandTag::Unknown, Refusal::Malformed(WireError::Crc))
    );
    assert_eq!(
        d.handle_packet(&mut [7, 7, 7]),
        refused(CommandTag::Unknown, Refusal::Malformed(WireError::Cobs))
    );
    assert_eq!(d.status(Micros(0)).bad_commands, 2);
}

#[test]
fn an_uploaded_model_classifies_every_frame() {
    let mut d = device();
    let b = blob(false, ProtocolKind::Opposite);
    let replies = upload(&mut d, &b, wire::crc32(&b));
    assert!(
        replies[..replies.len() - 1]
            .iter()
            .all(|r| matches!(r, Some(Event::Ack { .. })))
    );
    assert_eq!(replies.last().unwrap(), &ack(CommandTag::ModelCommit));
    assert!(d.status(Micros(0)).model_loaded);
    let report = ScanReport::default();
    for class in [2, 0, 1] {
        let out = d
            .frame(&config(), Micros(1), &report, &frame_of(class), 0)
            .unwrap();
        assert_eq!(touches(&out), [class as u16]);
    }
    assert_eq!(d.status(Micros(0)).frames, 3);

    // Clearing stops classification.
    assert_eq!(d.handle(Command::ModelClear), ack(CommandTag::ModelClear));
    let out = d
        .frame(&config(), Micros(1), &report, &frame_of(1), 0)
        .unwrap();
    assert!(touches(&out).is_empty());
}

#[test]
fn a_bad_upload_keeps_the_old_model() {
    let mut d = device();
    let b = blob(false, ProtocolKind::Opposite);
    upload(&mut d, &b, wire::crc32(&b));
    let report = ScanReport::default();

    // One flipped bit, sent with the CRC of the damaged bytes (so only the blob's own CRC
    // catches it): refused, the first model goes on.
    let mut damaged = b.clone();
    damaged[40] ^= 0x04;
    let replies = upload(&mut d, &damaged, wire::crc32(&damaged));
    assert_eq!(
        replies.last().unwrap(),
        &refused(CommandTag::ModelCommit, Refusal::BadModel)
    );
    // Upload CRC wrong.
    let replies = upload(&mut d, &b, wire::crc32(&b) ^ 1);
    assert_eq!(
        replies.last().unwrap(),
        &refused(CommandTag::ModelCommit, Refusal::BadModel)
    );
    // A model for another protocol.
    let pp = blob(false, ProtocolKind::PseudoPolar);
    let replies = upload(&mut d, &pp, wire::crc32(&pp));
    assert_eq!(
        replies.last().unwrap(),
        &refused(CommandTag::ModelCommit, Refusal::ModelMismatch)
    );
    let out = d
        .frame(&config(), Micros(1), &report, &frame_of(2), 0)
        .unwrap();
    assert_eq!(touches(&out), [2], "the first model still classifies");

    // Out of order and oversized.
    assert_eq!(
        d.handle(Command::ModelCommit),
        refused(CommandTag::ModelCommit, Refusal::UploadOrder)
    );
    assert_eq!(
        d.handle(Command::ModelChunk {
            offset: 0,
            data: Vec::from_slice(&[1]).unwrap()
        }),
        refused(CommandTag::ModelChunk, Refusal::UploadOrder)
    );
    assert_eq!(
        d.handle(Command::ModelBegin {
            len: (4096 - RECORD_BYTES + 1) as u32,
            crc: 0
        }),
        refused(CommandTag::ModelBegin, Refusal::TooLarge)
    );
    // Commit before the last byte.
    d.handle(Command::ModelBegin {
        len: b.len() as u32,
        crc: wire::crc32(&b),
    });
    d.handle(Command::ModelChunk {
        offset: 0,
        data: Vec::from_slice(&b[..CHUNK]).unwrap(),
    });
    // The same chunk again (a lost acknowledgement) is fine; a different one at that place not.
    assert_eq!(
        d.handle(Command::ModelChunk {
            offset: 0,
            data: Vec::from_slice(&b[..CHUNK]).unwrap(),
        }),
        ack(CommandTag::ModelChunk)
    );
    assert_eq!(
        d.handle(Command::ModelChunk {
            offset: 0,
            data: Vec::from_slice(&b[1..CHUNK + 1]).unwrap(),
        }),
        refused(CommandTag::ModelChunk, Refusal::UploadOrder)
    );
    assert_eq!(
        d.handle(Command::ModelCommit),
        refused(CommandTag::ModelCommit, Refusal::UploadOrder)
    );
    let out = d
        .frame(&config(), Micros(1), &report, &frame_of(0), 0)
        .unwrap();
    assert_eq!(touches(&out), [0], "the first model survived all of it");
}

#[test]
fn uploads_alternate_slots_so_the_active_model_is_never_overwritten() {
    let mut d = device();
    let b = blob(false, ProtocolKind::Opposite);
    upload(&mut d, &b, wire::crc32(&b));
    let first = d.active.unwrap().slot;
    // Begin a second upload and write garbage into it: the active slot's bytes do not move.
    d.handle(Command::ModelBegin {
        len: b.len() as u32,
        crc: 0,
    });
    d.handle(Command::ModelChunk {
        offset: 0,
        data: Vec::from_slice(&[0x55; MODEL_CHUNK]).unwrap(),
    });
    assert_eq!(&d.store().read(first)[..b.len()], &b[..]);
    upload(&mut d, &b, wire::crc32(&b));
    assert_ne!(d.active.unwrap().slot, first);
}

#[test]
fn a_referenced_model_waits_for_the_tare() {
    let mut d = device();
    let b = blob(true, ProtocolKind::Opposite);
    assert_eq!(b[17], FLAG_REFERENCED);
    upload(&mut d, &b, wire::crc32(&b));
    let report = ScanReport::default();
    // V_0 has a large standing voltage on feature 1: raw, frame_of(0) would read as class 1.
    let mut v_0 = vec![0.0; K];
    v_0[1] = 5.0;
    let out = d.frame(&config(), Micros(1), &report, &v_0, 0).unwrap();
    assert!(out.events.is_empty(), "no class before the tare");
    assert_eq!(d.handle(Command::Tare), None, "acknowledged with a frame");
    let out = d.frame(&config(), Micros(2), &report, &v_0, 0).unwrap();
    assert_eq!(out.events[0], ack(CommandTag::Tare).unwrap());
    let v: StdVec<f32> = frame_of(0).iter().zip(&v_0).map(|(a, b)| a + b).collect();
    let out = d.frame(&config(), Micros(3), &report, &v, 0).unwrap();
    assert_eq!(touches(&out), [0]);
    // A new configuration forgets V_0 (it was taken under the old one).
    let pp = ScanConfig {
        samples_per_step: 60,
        ..config()
    };
    d.handle(Command::Configure(pp));
    let out = d.frame(&pp, Micros(4), &report, &v, 0).unwrap();
    assert!(touches(&out).is_empty());
}

#[test]
fn a_scan_under_a_superseded_configuration_is_sent_but_not_classified() {
    let mut d = device();
    let b = blob(false, ProtocolKind::Opposite);
    upload(&mut d, &b, wire::crc32(&b));
    let report = ScanReport::default();
    let slower = ScanConfig {
        samples_per_step: 80,
        ..config()
    };
    // The scan started under config(); Configure(slower) arrived while it ran.
    d.handle(Command::Configure(slower));
    let out = d
        .frame(&config(), Micros(1), &report, &frame_of(1), 0)
        .unwrap();
    assert_eq!(
        out.frame.config,
        config(),
        "labelled with what it was scanned under"
    );
    assert!(touches(&out).is_empty());
    // The model matches the new configuration too (same protocol): the next scan classifies.
    let out = d
        .frame(&slower, Micros(2), &report, &frame_of(1), 0)
        .unwrap();
    assert_eq!(touches(&out), [1]);
}

#[test]
fn sequence_numbers_and_dropped_frames() {
    let mut d = device();
    let report = ScanReport::default();
    let v = frame_of(0);
    let a = d.frame(&config(), Micros(1), &report, &v, 0).unwrap().frame;
    d.dropped();
    let b = d.frame(&config(), Micros(2), &report, &v, 0).unwrap().frame;
    let c = d.frame(&config(), Micros(3), &report, &v, 0).unwrap().frame;
    assert_eq!((a.seq, b.seq, c.seq), (0, 1, 2));
    assert_eq!(a.flags & FLAG_DROPPED_BEFORE, 0);
    assert_ne!(b.flags & FLAG_DROPPED_BEFORE, 0);
    assert_eq!(c.flags & FLAG_DROPPED_BEFORE, 0);
    assert_eq!(d.status(Micros(0)).dropped, 1);
    assert_eq!(a.config, config());
    assert!(
        d.frame(&config(), Micros(4), &report, &[0.0; K_MAX + 1], 0)
            .is_err()
    );
}

#[test]
fn an_open_probe_electrode_is_suspected_and_its_neighbours_are_not() {
    let mut d = device();
    let protocol = config().validate().unwrap();
    for open in 0..8u8 {
        let mut d2 = device();
        let mut report = ScanReport::default();
        for step in protocol.steps() {
            if step.measurement.positive.0 == open || step.measurement.negative.0 == open {
                report.rail.set(usize::from(step.k));
            }
        }
        let out = d2
            .frame(&config(), Micros(1), &report, &[0.0; K], 0)
            .unwrap();
        assert_eq!(
            out.events.as_slice(),
            &[Event::Fault(Fault::Electrode { electrode: open })]
        );
        assert_eq!(d2.status(Micros(0)).suspect_electrodes, 1 << open);
        // Reported once, counted every frame.
        let out = d2
            .frame(&config(), Micros(2), &report, &[0.0; K], 0)
            .unwrap();
        assert!(out.events.is_empty());
        assert_eq!(d2.status(Micros(0)).rail_frames, 2);
    }
    // One saturated measurement is a rail frame, not a suspect.
    let mut report = ScanReport::default();
    report.rail.set(3);
    let out = d
        .frame(&config(), Micros(1), &report, &[0.0; K], 0)
        .unwrap();
    assert!(out.events.is_empty());
    assert_eq!(out.frame.rail_count, 1);
    assert_eq!(d.status(Micros(0)).suspect_electrodes, 0);
}

/// Valid command packets to mutate: every kind, with the delimiters.
fn command_packets() -> StdVec<StdVec<u8>> {
    let b = blob(false, ProtocolKind::Opposite);
    let commands = [
        Command::Ping { nonce: 3 },
        Command::Start,
        Command::Stop,
        Command::Configure(config()),
        Command::ModelBegin {
            len: b.len() as u32,
            crc: wire::crc32(&b),
        },
        Command::ModelChunk {
            offset: 0,
            data: Vec::from_slice(&b[..CHUNK]).unwrap(),
        },
        Command::ModelCommit,
        Command::ModelClear,
        Command::Tare,
    ];
    commands
        .iter()
        .map(|c| {
            let mut buf = [0u8; wire::COMMAND_PACKET_MAX];
            let n = encode(c, &mut buf).unwrap();
            buf[..n].to_vec()
        })
        .collect()
}

proptest::proptest! {
    // Cases from PROPTEST_CASES (256 by default). The fuzzing run of the README:
    // PROPTEST_CASES=1000000 cargo test --release -p et-core fuzz_

    /// The firmware's command path (accumulator, decoder, device) on damaged streams: valid
    /// packets with bit flips, cuts and garbage between them. It never panics, every reply is
    /// an answer to a command or a refusal, and a scan afterwards still makes a frame.
    #[test]
    fn fuzz_command_decoder(
        picks in proptest::collection::vec(0usize..9, 0..12),
        flips in proptest::collection::vec((0usize..4096, 0u8..8), 0..6),
        cuts in proptest::collection::vec(0usize..4096, 0..3),
        garbage in proptest::collection::vec(proptest::num::u8::ANY, 0..64),
        at in 0usize..4096,
    ) {
        let packets = command_packets();
        let mut stream: StdVec<u8> = picks.iter().flat_map(|&i| packets[i].clone()).collect();
        if !stream.is_empty() {
            for (i, bit) in &flips {
                let i = i % stream.len();
                stream[i] ^= 1 << bit;
            }
            for c in &cuts {
                let c = c % stream.len();
                stream.remove(c);
                if stream.is_empty() {
                    break;
                }
            }
        }
        let at = if stream.is_empty() { 0 } else { at % stream.len() };
        stream.splice(at..at, garbage);
        let mut d = device();
        let mut packets_in = wire::Accumulator::<{ wire::COMMAND_PACKET_MAX }>::new();
        for b in stream {
            if let Some(decoded) = packets_in.feed::<Command>(b)
                && let Some(reply) = d.handle_decoded(decoded)
            {
                let answer = matches!(
                    reply,
                    Event::Ack { .. } | Event::Refused { .. } | Event::Pong { .. }
                );
                proptest::prop_assert!(answer, "unexpected reply {:?}", reply);
            }
        }
        let config = *d.config();
        let k = config.validate().unwrap().frame_len();
        let out = d.frame(&config, Micros(0), &ScanReport::default(), &vec![0.0; k], 0).unwrap();
        proptest::prop_assert_eq!(out.frame.voltages.len(), k);
    }
}

/// A configuration the front end refuses (the scan task could not build its scanner) sends
/// the device back to the configuration of the last frame it scanned, which the scan task
/// picks up next (the board stayed on a scan it could not make until reset); before any frame
/// there is nothing to go back to.
#[test]
fn a_configuration_the_front_end_refuses_goes_back_to_the_last_scanned() {
    let mut d = device();
    assert_eq!(d.take_reconfigure(), Some(config()));
    assert_eq!(d.front_end_refused(), None, "no frame scanned yet");
    let v = vec![0.0; K];
    d.frame(&config(), Micros(1), &ScanReport::default(), &v, 0)
        .unwrap();
    let sixteen = ScanConfig {
        electrodes: 16,
        ..config()
    };
    assert_eq!(
        d.handle(Command::Configure(sixteen)),
        ack(CommandTag::Configure)
    );
    assert_eq!(d.take_reconfigure(), Some(sixteen));
    assert_eq!(d.front_end_refused(), Some(config()));
    assert_eq!(d.config(), &config());
    assert_eq!(d.take_reconfigure(), Some(config()));
    // Refused again (the last frame's is the configuration now): nothing more to go back to.
    assert_eq!(d.front_end_refused(), None);
}

/// The firmware's default at a restart, other than [`config`] (the scan models are committed
/// under here).
fn default_at_restart() -> ScanConfig {
    ScanConfig {
        electrodes: 8,
        protocol: ProtocolKind::Adjacent,
        ..ScanConfig::REFERENCE
    }
}

/// A device restarted on the store of the last (a reset, a power cycle): the model committed
/// classifies again under the scan it was committed with, not the firmware's default, and is
/// what `model()` and the status report; a referenced one takes V_0 from its first frame,
/// unacknowledged (no host asked).
#[test]
fn a_committed_model_survives_a_restart() {
    for referenced in [false, true] {
        let mut store = RamStore::<4096>::new();
        let b = blob(referenced, ProtocolKind::Opposite);
        let mut d = Device::new(&mut store, config()).unwrap();
        assert_eq!(
            upload(&mut d, &b, wire::crc32(&b)).last().unwrap(),
            &ack(CommandTag::ModelCommit)
        );
        drop(d);
        let mut d = Device::new(&mut store, default_at_restart()).unwrap();
        assert_eq!(*d.config(), config());
        assert_eq!(d.take_reconfigure(), Some(config()));
        assert!(d.status(Micros(0)).model_loaded);
        assert_eq!(d.model().unwrap().referenced(), referenced);
        let report = ScanReport::default();
        let mut v_0 = vec![0.0; K];
        v_0[1] = 5.0;
        let out = d.frame(&config(), Micros(1), &report, &v_0, 0).unwrap();
        assert!(
            !out.events.contains(&ack(CommandTag::Tare).unwrap()),
            "{:?}",
            out.events
        );
        let v: StdVec<f32> = frame_of(0).iter().zip(&v_0).map(|(a, b)| a + b).collect();
        let out = d.frame(&config(), Micros(2), &report, &v, 0).unwrap();
        // Referenced: V_0 taken from the first frame, so class 0; raw, feature 1's 5 V wins.
        assert_eq!(touches(&out), [if referenced { 0 } else { 1 }]);
        // A Tare asked for after it is acknowledged as before.
        assert_eq!(d.handle(Command::Tare), None);
        let out = d.frame(&config(), Micros(3), &report, &v_0, 0).unwrap();
        assert!(out.events.contains(&ack(CommandTag::Tare).unwrap()));
    }
}

/// Two commits, then a restart: the latest is restored (the two slots both hold a record);
/// cleared, neither comes back at the next restart, and the firmware's default is scanned.
/// A new upload after the clear is restored again.
#[test]
fn the_latest_commit_is_restored_and_a_cleared_model_stays_cleared() {
    let mut store = RamStore::<4096>::new();
    let (plain, referenced) = (
        blob(false, ProtocolKind::Opposite),
        blob(true, ProtocolKind::Opposite),
    );
    let mut d = Device::new(&mut store, config()).unwrap();
    upload(&mut d, &plain, wire::crc32(&plain));
    upload(&mut d, &referenced, wire::crc32(&referenced));
    drop(d);
    let mut d = Device::new(&mut store, default_at_restart()).unwrap();
    assert!(d.model().unwrap().referenced());
    assert_eq!(d.handle(Command::ModelClear), ack(CommandTag::ModelClear));
    assert!(d.model().is_none());
    drop(d);
    let mut d = Device::new(&mut store, default_at_restart()).unwrap();
    assert!(d.model().is_none() && !d.status(Micros(0)).model_loaded);
    assert_eq!(*d.config(), default_at_restart());
    d.handle(Command::Configure(config()));
    upload(&mut d, &plain, wire::crc32(&plain));
    drop(d);
    let d = Device::new(&mut store, default_at_restart()).unwrap();
    assert!(!d.model().unwrap().referenced());
    assert_eq!(*d.config(), config());
}

/// Nothing is restored from a damaged slot (a byte of the blob, or the record's mark,
/// changed) nor from an upload a restart cut short; an upload cut short leaves the model
/// before it restored.
#[test]
fn a_damaged_slot_or_an_unfinished_upload_restores_nothing_of_it() {
    let b = blob(false, ProtocolKind::Opposite);
    for damage in [5, 4096 - RECORD_BYTES] {
        let mut store = RamStore::<4096>::new();
        let mut d = Device::new(&mut store, config()).unwrap();
        upload(&mut d, &b, wire::crc32(&b));
        let slot = d.active.unwrap().slot;
        drop(d);
        let byte = store.read(slot)[damage];
        store.write(slot, damage, &[byte ^ 0x10]).unwrap();
        let d = Device::new(&mut store, default_at_restart()).unwrap();
        assert!(d.model().is_none(), "damaged at {damage}");
        assert_eq!(*d.config(), default_at_restart());
    }
    let mut store = RamStore::<4096>::new();
    let mut d = Device::new(&mut store, config()).unwrap();
    upload(&mut d, &b, wire::crc32(&b));
    let first = d.active.unwrap().slot;
    let referenced = blob(true, ProtocolKind::Opposite);
    d.handle(Command::ModelBegin {
        len: referenced.len() as u32,
        crc: wire::crc32(&referenced),
    });
    d.handle(Command::ModelChunk {
        offset: 0,
        data: Vec::from_slice(&referenced[..CHUNK]).unwrap(),
    });
    drop(d);
    let d = Device::new(&mut store, default_at_restart()).unwrap();
    assert_eq!(d.active.unwrap().slot, first);
    assert!(!d.model().unwrap().referenced());
}
