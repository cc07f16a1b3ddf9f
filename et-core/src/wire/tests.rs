//! Wire tests: a hand-derived packet, golden bytes for every message type (the firmware-host
//! contract), round trips, and a decoder that never panics and resynchronises.

use super::*;
use crate::protocol::{Pattern, ProtocolKind, SkipSet};
use proptest::prelude::*;
use std::vec;
use std::vec::Vec as StdVec;

/// Bitwise CRC-32 (reflected, polynomial 0xEDB88320): independent of the `crc` crate.
fn crc32_bitwise(data: &[u8]) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// Textbook COBS into a fresh Vec: independent of the in-place encoder.
fn cobs_reference(data: &[u8]) -> StdVec<u8> {
    let mut out = StdVec::new();
    let mut block = StdVec::new();
    for &b in data {
        if b == 0 {
            out.push(block.len() as u8 + 1);
            out.append(&mut block);
        } else {
            block.push(b);
            if block.len() == 254 {
                out.push(255);
                out.append(&mut block);
            }
        }
    }
    out.push(block.len() as u8 + 1);
    out.extend(block);
    out
}

fn encode_vec<T: Serialize>(m: &T) -> StdVec<u8> {
    let mut buf = vec![0u8; PACKET_MAX];
    let n = encode(m, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// Decodes a whole packet (with delimiters) through the accumulator.
fn decode_packet<T: DeserializeOwned>(packet: &[u8]) -> StdVec<Result<T, WireError>> {
    let mut acc: std::boxed::Box<Accumulator<PACKET_MAX>> = std::boxed::Box::default();
    packet.iter().filter_map(|&b| acc.feed(b)).collect()
}

#[test]
fn ping_packet_matches_a_hand_derivation() {
    // Derived by hand: version 1; postcard: variant index 3 (Configure, Start, Stop, Ping),
    // nonce 0x01020304 as LEB128 varint 84 86 88 08; CRC-32 of those six bytes, LE; COBS; 0x00
    // delimiters. The same bytes come from Python's zlib.crc32 and a textbook COBS.
    let raw = [1u8, 3, 0x84, 0x86, 0x88, 0x08];
    let mut with_crc = raw.to_vec();
    with_crc.extend(crc32_bitwise(&raw).to_le_bytes());
    let mut want = vec![0u8];
    want.extend(cobs_reference(&with_crc));
    want.push(0);
    assert_eq!(want, PING_BYTES);
    assert_eq!(encode_vec(&Command::Ping { nonce: 0x0102_0304 }), want);
    assert_eq!(crc32(&raw), crc32_bitwise(&raw));
}

fn sample_config() -> ScanConfig {
    ScanConfig {
        electrodes: 4,
        ..ScanConfig::REFERENCE
    }
}

fn sample_frame() -> Frame {
    Frame {
        seq: 7,
        timestamp: Micros(123_456),
        config: sample_config(),
        flags: FLAG_RAIL,
        rail_count: 1,
        voltages: Vec::from_slice(&[0.5, -0.25, 1.0, 0.0]).unwrap(),
    }
}

fn uplinks() -> StdVec<(&'static str, Uplink)> {
    vec![
        ("frame", Uplink::Frame(sample_frame())),
        (
            "touch",
            Uplink::Event(Event::Touch {
                seq: 7,
                class: 12,
                margin: 3.5,
            }),
        ),
        (
            "status",
            Uplink::Event(Event::Status(Status {
                uptime: Micros(1_000_000),
                frames: 78,
                dropped: 1,
                rail_frames: 2,
                bad_commands: 3,
                suspect_electrodes: 1 << 5,
                scanning: true,
                model_loaded: false,
            })),
        ),
        ("pong", Uplink::Event(Event::Pong { nonce: 42 })),
        (
            "ack",
            Uplink::Event(Event::Ack {
                command: CommandTag::ModelCommit,
            }),
        ),
        (
            "refused",
            Uplink::Event(Event::Refused {
                command: CommandTag::Unknown,
                reason: Refusal::Malformed(WireError::Crc),
            }),
        ),
        (
            "fault",
            Uplink::Event(Event::Fault(Fault::Saturated {
                seq: 9,
                measurements: 3,
            })),
        ),
    ]
}

fn commands() -> StdVec<(&'static str, Command)> {
    let custom = ProtocolKind::Custom(Pattern {
        drive_skip: 2,
        measure_skips: SkipSet(0b101),
    });
    vec![
        (
            "configure",
            Command::Configure(ScanConfig {
                protocol: custom,
                ..ScanConfig::REFERENCE
            }),
        ),
        ("start", Command::Start),
        ("stop", Command::Stop),
        ("ping", Command::Ping { nonce: 0x0102_0304 }),
        (
            "model_begin",
            Command::ModelBegin {
                len: 931_440,
                crc: 0xdead_beef,
            },
        ),
        (
            "model_chunk",
            Command::ModelChunk {
                offset: 256,
                data: Vec::from_slice(&[1, 2, 3, 0, 255]).unwrap(),
            },
        ),
        ("model_commit", Command::ModelCommit),
        ("model_clear", Command::ModelClear),
        ("tare", Command::Tare),
    ]
}

const PING_BYTES: [u8; 13] = [
    0x00, 0x0b, 0x01, 0x03, 0x84, 0x86, 0x88, 0x08, 0xf9, 0xd4, 0x3c, 0x47, 0x00,
];

/// Golden packets, one per message type. Frozen: a change here is a wire-format change and
/// needs a new WIRE_VERSION and a firmware release.
const GOLDEN: &[(&str, &[u8])] = &[
    (
        "frame",
        &[
            0, 2, 1, 6, 7, 192, 196, 7, 4, 13, 50, 25, 128, 250, 1, 164, 232, 3, 1, 1, 1, 4, 1, 1,
            2, 63, 1, 3, 128, 190, 1, 3, 128, 63, 1, 1, 1, 5, 130, 212, 192, 64, 0,
        ],
    ),
    (
        "touch",
        &[0, 3, 1, 1, 3, 7, 12, 1, 7, 96, 64, 253, 247, 12, 246, 0],
    ),
    (
        "status",
        &[
            0, 13, 1, 1, 1, 192, 132, 61, 78, 1, 2, 3, 32, 1, 5, 72, 67, 76, 67, 0,
        ],
    ),
    ("pong", &[0, 9, 1, 1, 2, 42, 26, 121, 183, 113, 0]),
    ("ack", &[0, 9, 1, 1, 3, 6, 184, 36, 116, 90, 0]),
    ("refused", &[0, 5, 1, 1, 4, 8, 6, 3, 227, 204, 134, 95, 0]),
    ("fault", &[0, 11, 1, 1, 5, 1, 9, 3, 64, 43, 41, 57, 0]),
    (
        "configure",
        &[
            0, 2, 1, 18, 16, 4, 2, 5, 50, 25, 128, 250, 1, 164, 232, 3, 1, 89, 96, 242, 60, 0,
        ],
    ),
    ("start", &[0, 7, 1, 1, 40, 19, 197, 47, 0]),
    ("stop", &[0, 7, 1, 2, 146, 66, 204, 182, 0]),
    (
        "ping",
        &[0, 11, 1, 3, 132, 134, 136, 8, 249, 212, 60, 71, 0],
    ),
    (
        "model_begin",
        &[
            0, 15, 1, 4, 240, 236, 56, 239, 253, 182, 245, 13, 62, 122, 199, 138, 0,
        ],
    ),
    (
        "model_chunk",
        &[
            0, 9, 1, 5, 128, 2, 5, 1, 2, 3, 6, 255, 168, 243, 155, 106, 0,
        ],
    ),
    ("model_commit", &[0, 7, 1, 6, 139, 134, 161, 177, 0]),
    ("model_clear", &[0, 7, 1, 7, 29, 182, 166, 198, 0]),
    // Added in place without a version change: a new variant at the end leaves every older
    // packet's bytes as they were (derived with Python's zlib.crc32 and a COBS by hand).
    ("tare", &[0, 7, 1, 8, 140, 171, 25, 86, 0]),
];

#[test]
fn golden_bytes_encode_and_decode() {
    let ups = uplinks();
    let cmds = commands();
    assert_eq!(
        GOLDEN.len(),
        ups.len() + cmds.len(),
        "one golden packet per message type"
    );
    for (name, m) in &ups {
        let golden = GOLDEN.iter().find(|(n, _)| n == name).unwrap().1;
        assert_eq!(encode_vec(m), golden, "encode {name}");
        assert_eq!(
            decode_packet::<Uplink>(golden),
            vec![Ok(m.clone())],
            "decode {name}"
        );
    }
    for (name, m) in &cmds {
        let golden = GOLDEN.iter().find(|(n, _)| n == name).unwrap().1;
        assert_eq!(encode_vec(m), golden, "encode {name}");
        assert_eq!(
            decode_packet::<Command>(golden),
            vec![Ok(m.clone())],
            "decode {name}"
        );
    }
}

#[test]
fn every_command_fits_the_device_receive_buffer() {
    let biggest = Command::ModelChunk {
        offset: u32::MAX,
        data: Vec::from_slice(&[0xff; MODEL_CHUNK]).unwrap(),
    };
    assert!(encode_vec(&biggest).len() <= COMMAND_PACKET_MAX);
    let mut acc = Accumulator::<COMMAND_PACKET_MAX>::new();
    let got: StdVec<_> = encode_vec(&biggest)
        .iter()
        .filter_map(|&b| acc.feed::<Command>(b))
        .collect();
    assert_eq!(got, vec![Ok(biggest)]);
}

#[test]
fn largest_frame_fits_packet_max_and_reference_frame_size_is_known() {
    let big: Frame = Frame {
        seq: u32::MAX,
        timestamp: Micros(u32::MAX),
        config: ScanConfig {
            current_na: u32::MAX,
            sample_rate_hz: u32::MAX,
            ..ScanConfig::REFERENCE
        },
        flags: 0xff,
        rail_count: u16::MAX,
        voltages: core::iter::repeat_n(-1.0e-3, K_MAX).collect(),
    };
    let packet = encode_vec(&Uplink::Frame(big.clone()));
    assert!(packet.len() <= PACKET_MAX);
    assert!(
        packet.len() <= frame_packet_max(K_MAX),
        "FRAME_HEADER_MAX is an upper bound"
    );
    let mut custom = big.clone();
    custom.config.protocol = ProtocolKind::Custom(Pattern {
        drive_skip: u8::MAX,
        measure_skips: SkipSet(u32::MAX),
    });
    custom.voltages.truncate(3);
    assert!(encode_vec(&Uplink::Frame(custom)).len() <= frame_packet_max(3));
    assert_eq!(
        decode_packet::<Uplink>(&packet),
        vec![Ok(Uplink::Frame(big))]
    );
    // AD at L = 16: 208 f32 = 832 bytes of voltages plus a header of at most 32 bytes.
    let reference = Frame {
        voltages: core::iter::repeat_n(0.0123, 208).collect(),
        config: ScanConfig::REFERENCE,
        ..sample_frame()
    };
    let n = encode_vec(&Uplink::Frame(reference)).len();
    assert!((832..832 + 32).contains(&n), "{n}");
}

#[test]
fn encode_refuses_a_small_buffer() {
    let m = Uplink::Frame(sample_frame());
    let need = encode_vec(&m).len();
    for n in 0..need {
        let mut buf = vec![0u8; n];
        assert_eq!(
            encode(&m, &mut buf),
            Err(WireError::BufferFull),
            "buffer of {n}"
        );
    }
}

#[test]
fn bad_packets_give_typed_errors() {
    // Wrong version with a correct CRC.
    let raw = [2u8, 1];
    let mut with_crc = raw.to_vec();
    with_crc.extend(crc32_bitwise(&raw).to_le_bytes());
    let mut p = cobs_reference(&with_crc);
    assert_eq!(
        decode::<Command>(&mut p),
        Err(WireError::Version { got: 2 })
    );
    // Right version and CRC, but not a Command (variant 200).
    let raw = [1u8, 200];
    let mut with_crc = raw.to_vec();
    with_crc.extend(crc32_bitwise(&raw).to_le_bytes());
    assert_eq!(
        decode::<Command>(&mut cobs_reference(&with_crc)),
        Err(WireError::Body)
    );
    // Trailing bytes after a valid message are refused too.
    let raw = [1u8, 1, 9];
    let mut with_crc = raw.to_vec();
    with_crc.extend(crc32_bitwise(&raw).to_le_bytes());
    assert_eq!(
        decode::<Command>(&mut cobs_reference(&with_crc)),
        Err(WireError::Body)
    );
    assert_eq!(decode::<Command>(&mut [2, 1]), Err(WireError::Short));
    assert_eq!(decode::<Command>(&mut [5, 1]), Err(WireError::Cobs));
    let mut golden = GOLDEN[1].1[1..GOLDEN[1].1.len() - 1].to_vec();
    golden[4] ^= 0x10;
    assert_eq!(decode::<Uplink>(&mut golden), Err(WireError::Crc));
}

#[test]
fn accumulator_drops_an_overflowing_packet_and_carries_on() {
    let mut acc = Accumulator::<64>::new();
    let mut out = StdVec::new();
    for _ in 0..100 {
        out.extend(acc.feed::<Command>(0x55));
    }
    out.extend(acc.feed::<Command>(0));
    for &b in &PING_BYTES {
        out.extend(acc.feed::<Command>(b));
    }
    assert_eq!(
        out,
        vec![
            Err(WireError::Overflow),
            Ok(Command::Ping { nonce: 0x0102_0304 })
        ]
    );
}

fn arb_config() -> impl Strategy<Value = ScanConfig> {
    (
        (2u8..=16).prop_map(|h| 2 * h),
        0usize..5,
        any::<u16>(),
        any::<u16>(),
        any::<u32>(),
        any::<u32>(),
        any::<u8>(),
        (any::<u8>(), any::<u32>()),
    )
        .prop_map(
            |(electrodes, kind, spp, settle, current_na, rate, gain, (d, m))| ScanConfig {
                electrodes,
                protocol: match kind {
                    0..4 => ProtocolKind::NAMED[kind],
                    _ => ProtocolKind::Custom(Pattern {
                        drive_skip: d,
                        measure_skips: SkipSet(m),
                    }),
                },
                samples_per_step: spp,
                settle_samples: settle,
                current_na,
                sample_rate_hz: rate,
                gain,
            },
        )
}

fn arb_frame() -> impl Strategy<Value = Frame> {
    (
        any::<u32>(),
        any::<u32>(),
        arb_config(),
        any::<u8>(),
        any::<u16>(),
        proptest::collection::vec(any::<f32>(), 0..300),
    )
        .prop_map(|(seq, t, config, flags, rail_count, v)| Frame {
            seq,
            timestamp: Micros(t),
            config,
            flags,
            rail_count,
            voltages: v.into_iter().collect(),
        })
}

/// Equality that treats NaN payloads as equal bit patterns (f32 NaN != NaN).
fn same_bits(a: &Uplink, b: &Uplink) -> bool {
    match (a, b) {
        (Uplink::Frame(x), Uplink::Frame(y)) => {
            x.seq == y.seq
                && x.timestamp == y.timestamp
                && x.config == y.config
                && x.flags == y.flags
                && x.rail_count == y.rail_count
                && x.voltages
                    .iter()
                    .map(|v| v.to_bits())
                    .eq(y.voltages.iter().map(|v| v.to_bits()))
        }
        _ => a == b,
    }
}

/// What happens to one packet on its way.
#[derive(Debug, Clone)]
enum Damage {
    None,
    /// Random bytes (no 0x00) before the packet.
    GarbageBefore(StdVec<u8>),
    /// The packet is cut after this many bytes (its trailing delimiter lost).
    Truncate(usize),
    /// One bit flipped at this byte (never a delimiter).
    Flip(usize, u8),
}

fn arb_damage() -> impl Strategy<Value = Damage> {
    prop_oneof![
        3 => Just(Damage::None),
        1 => proptest::collection::vec(1u8..=255, 1..40).prop_map(Damage::GarbageBefore),
        1 => any::<usize>().prop_map(Damage::Truncate),
        1 => (any::<usize>(), 0u8..8).prop_map(|(i, b)| Damage::Flip(i, b)),
    ]
}

// Cases from PROPTEST_CASES (256 by default), like every property test of the workspace.
proptest! {

    #[test]
    fn frames_round_trip(frame in arb_frame()) {
        let m = Uplink::Frame(frame);
        let got = decode_packet::<Uplink>(&encode_vec(&m));
        prop_assert_eq!(got.len(), 1);
        prop_assert!(same_bits(got[0].as_ref().unwrap(), &m));
    }

    #[test]
    fn cobs_in_place_matches_the_textbook(data in proptest::collection::vec(any::<u8>(), 0..1200)) {
        let mut buf = vec![0u8; 8 + data.len() + data.len() / 254 + 4];
        let src = buf.len() - data.len();
        buf[src..].copy_from_slice(&data);
        let n = cobs_encode_forward(&mut buf, src, data.len(), 1).unwrap();
        prop_assert_eq!(&buf[1..1 + n], &cobs_reference(&data)[..]);
        let mut enc = buf[1..1 + n].to_vec();
        let m = cobs_decode_in_place(&mut enc).unwrap();
        prop_assert_eq!(&enc[..m], &data[..]);
    }

    #[test]
    fn decoding_random_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..2000)) {
        let mut acc: std::boxed::Box<Accumulator<PACKET_MAX>> = std::boxed::Box::default();
        let mut small = Accumulator::<COMMAND_PACKET_MAX>::new();
        for &b in &bytes {
            let _ = acc.feed::<Uplink>(b);
            let _ = small.feed::<Command>(b);
        }
        let mut copy = bytes.clone();
        let _ = decode::<Uplink>(&mut copy);
    }

    #[test]
    fn stream_resynchronises_after_damage(
        items in proptest::collection::vec((arb_frame(), arb_damage()), 1..12)
    ) {
        let mut stream = StdVec::new();
        let mut intact = StdVec::new();
        for (frame, damage) in &items {
            let m = Uplink::Frame(frame.clone());
            let mut packet = encode_vec(&m);
            match damage {
                Damage::None => intact.push(m),
                Damage::GarbageBefore(g) => {
                    stream.extend(g);
                    intact.push(m);
                }
                Damage::Truncate(at) => {
                    let at = 1 + at % (packet.len() - 2);
                    packet.truncate(at);
                }
                Damage::Flip(at, bit) => {
                    let at = 1 + at % (packet.len() - 2);
                    // A flip that would make a 0x00 (a split, not damage) flips a neighbour bit too.
                    let mut flip = 1u8 << bit;
                    if packet[at] ^ flip == 0 {
                        flip |= 1 << ((bit + 1) % 8);
                    }
                    packet[at] ^= flip;
                }
            }
            stream.extend(packet);
        }
        let got: StdVec<Result<Uplink, WireError>> = decode_packet(&stream);
        let ok: StdVec<&Uplink> = got.iter().filter_map(|r| r.as_ref().ok()).collect();
        prop_assert_eq!(ok.len(), intact.len(), "exactly the undamaged packets decode: {:?}", got);
        for (a, b) in ok.iter().zip(&intact) {
            prop_assert!(same_bits(a, b));
        }
    }

    /// Fed in chunks of any size (a serial port's reads), as blocks, the accumulator gives the
    /// same results in the same order as byte by byte: good packets, damaged ones, overflows.
    #[test]
    fn feeding_blocks_is_feeding_bytes(
        items in proptest::collection::vec((arb_frame(), arb_damage()), 1..8),
        cuts in proptest::collection::vec(0usize..3000, 0..12),
        overflow in proptest::collection::vec(1u8..=255, 0..200),
    ) {
        let mut stream = StdVec::new();
        for (frame, damage) in &items {
            let mut packet = encode_vec(&Uplink::Frame(frame.clone()));
            match damage {
                Damage::GarbageBefore(g) => stream.extend(g),
                Damage::Truncate(at) => packet.truncate(1 + at % (packet.len() - 2)),
                Damage::Flip(at, bit) => {
                    let at = 1 + at % (packet.len() - 2);
                    packet[at] ^= 1 << bit;
                }
                Damage::None => {}
            }
            stream.extend(packet);
        }
        // A run of bytes longer than a small accumulator holds, then a delimiter.
        stream.extend(&overflow);
        stream.push(0);
        let mut cuts: StdVec<usize> = cuts.into_iter().map(|c| c % (stream.len() + 1)).collect();
        cuts.sort_unstable();
        let (mut bytewise, mut blockwise) = (StdVec::new(), StdVec::new());
        let mut one: std::boxed::Box<Accumulator<PACKET_MAX>> = std::boxed::Box::default();
        for &b in &stream {
            if let Some(r) = one.feed::<Uplink>(b) {
                bytewise.push(r);
            }
        }
        let mut other: std::boxed::Box<Accumulator<PACKET_MAX>> = std::boxed::Box::default();
        let mut start = 0;
        for end in cuts.into_iter().chain([stream.len()]) {
            other.feed_slice::<Uplink>(&stream[start..end], |r| blockwise.push(r));
            start = end;
        }
        prop_assert_eq!(bytewise.len(), blockwise.len());
        for (a, b) in bytewise.iter().zip(&blockwise) {
            match (a, b) {
                (Ok(a), Ok(b)) => prop_assert!(same_bits(a, b)),
                (a, b) => prop_assert_eq!(a.as_ref().err(), b.as_ref().err()),
            }
        }
        // The small accumulator overflows on the long frames and on the run alike.
        let (mut small_bytes, mut small_blocks) = (StdVec::new(), StdVec::new());
        let mut small = Accumulator::<COMMAND_PACKET_MAX>::new();
        for &b in &stream {
            if let Some(r) = small.feed::<Command>(b) {
                small_bytes.push(r.err());
            }
        }
        let mut small = Accumulator::<COMMAND_PACKET_MAX>::new();
        small.feed_slice::<Command>(&stream, |r| small_blocks.push(r.err()));
        prop_assert_eq!(small_bytes, small_blocks);
    }
}

#[test]
fn every_single_bit_flip_of_every_golden_packet_is_refused() {
    let uplink_names: StdVec<&str> = uplinks().iter().map(|(n, _)| *n).collect();
    for (name, golden) in GOLDEN {
        let inner = &golden[1..golden.len() - 1];
        for at in 0..inner.len() {
            for bit in 0..8 {
                let mut p = inner.to_vec();
                p[at] ^= 1 << bit;
                if p[at] == 0 {
                    continue; // the flip made a delimiter: a split, covered by the resync test
                }
                let refused = if uplink_names.contains(name) {
                    decode::<Uplink>(&mut p).is_err()
                } else {
                    decode::<Command>(&mut p).is_err()
                };
                assert!(refused, "{name}: flip of bit {bit} at byte {at} accepted");
            }
        }
    }
}

#[test]
fn frames_from_a_scan_carry_its_rail_flags() {
    let mut report = ScanReport::default();
    let clean = Frame::from_scan(1, Micros(5), sample_config(), &report, 0, &[0.1; 4]).unwrap();
    assert_eq!((clean.flags, clean.rail_count), (0, 0));
    report.rail.set(2);
    report.rail.set(3);
    let f = Frame::from_scan(
        2,
        Micros(6),
        sample_config(),
        &report,
        FLAG_SUBSECTION,
        &[0.1; 4],
    )
    .unwrap();
    assert_eq!((f.flags, f.rail_count), (FLAG_RAIL | FLAG_SUBSECTION, 2));
    let too_long = [0.0; K_MAX + 1];
    assert_eq!(
        Frame::from_scan(3, Micros(7), sample_config(), &report, 0, &too_long),
        Err(WireError::BufferFull)
    );
}
