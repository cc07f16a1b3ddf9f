use et_core::wire::{
    self, Accumulator, Command, CommandTag, Event, HostFrame, HostUplink, PACKET_MAX, Refusal,
    Uplink,
};
use serde::Serialize;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::ScanReport;
use et_core::device::{Device, RamStore};
use et_core::wire::{COMMAND_PACKET_MAX, Frame};
use serialport::{SerialPort, TTYPort};

use et_host::link::*;

fn packet<T: Serialize>(m: &T) -> Vec<u8> {
    let mut buf = vec![0u8; PACKET_MAX];
    let n = wire::encode(m, &mut buf).unwrap();
    buf.truncate(n);
    buf
}

fn frame(seq: u32) -> Uplink {
    Uplink::Frame(Frame {
        seq,
        timestamp: et_core::Micros(seq * 1000),
        config: ScanConfig::REFERENCE,
        flags: 0,
        rail_count: 0,
        voltages: heapless::Vec::from_slice(&[0.25, -0.5, f32::from(seq as u16)]).unwrap(),
    })
}

#[test]
fn decoder_resyncs_counts_damage_and_sequence_gaps() {
    let mut stream = Vec::new();
    stream.extend(b"boot garbage \x01\x02");
    stream.extend(packet(&frame(0)));
    let mut flipped = packet(&frame(1));
    flipped[6] ^= 0x01;
    stream.extend(flipped);
    let truncated = packet(&frame(2));
    stream.extend(&truncated[..truncated.len() / 2]);
    stream.extend(packet(&frame(3)));
    stream.extend(packet(&HostUplink::Event(Event::Pong { nonce: 9 })));
    // Another wire version: valid COBS and CRC, version byte 2.
    let mut other = vec![2u8, 1, 2];
    let crc = wire::crc32(&other);
    other.extend(crc.to_le_bytes());
    let mut cobs = Vec::new();
    cobs.push(0u8);
    cobs.push((other.len() + 1) as u8);
    cobs.extend(&other);
    cobs.push(0);
    assert!(!other.contains(&0));
    stream.extend(cobs);
    stream.extend(packet(&frame(7)));

    // Fed in awkward pieces: the result does not depend on how reads split the stream.
    for piece in [1usize, 3, 64, stream.len()] {
        let mut d = Decoder::new();
        let mut out = Vec::new();
        for chunk in stream.chunks(piece) {
            d.feed(chunk, &mut out);
        }
        let seqs: Vec<u32> = out
            .iter()
            .filter_map(|m| match m {
                Uplink::Frame(f) => Some(f.seq),
                Uplink::Event(_) => None,
            })
            .collect();
        assert_eq!(seqs, [0, 3, 7], "piece {piece}");
        assert_eq!(
            out[1..3],
            [
                HostUplink::from(frame(3)),
                HostUplink::Event(Event::Pong { nonce: 9 })
            ]
        );
        let c = d.counters();
        // The flipped frame; the truncated frame ran into frame 3's leading 0x00 and died
        // with it as one damaged packet. The bytes before the first 0x00 are not counted:
        // they are the end of a packet sent before the port was opened (a clean link said
        // "1 damaged packets dropped" when joined mid-packet).
        assert_eq!((c.corrupt, c.wrong_version), (2, 1), "piece {piece}: {c:?}");
        assert_eq!((c.frames, c.events, c.lost_frames), (3, 1, 2 + 3));
        assert_eq!(c.bytes, stream.len() as u64);
    }
}

/// The host reads a frame's voltages into a heap vector, which would take any count a packet
/// holds: a frame longer than any board sends (K_MAX + 1 values, which still fit a packet)
/// is refused as damaged, and the frames around it are read.
#[test]
fn a_frame_longer_than_k_max_is_refused() {
    let Uplink::Frame(f) = frame(1) else {
        unreachable!()
    };
    let long = HostUplink::Frame(HostFrame {
        voltages: vec![0.5; et_core::protocol::K_MAX + 1],
        ..HostFrame::from(f)
    });
    let mut stream = packet(&frame(0));
    let mut buf = vec![0u8; PACKET_MAX];
    let n = wire::encode(&long, &mut buf).expect("K_MAX + 1 values fit a packet");
    stream.extend(&buf[..n]);
    stream.extend(packet(&frame(2)));
    let mut d = Decoder::new();
    let mut out = Vec::new();
    d.feed(&stream, &mut out);
    assert_eq!(
        out,
        [HostUplink::from(frame(0)), HostUplink::from(frame(2))]
    );
    assert_eq!(d.counters().corrupt, 1);
}

/// A device on the master side of a pty: the real `et_core::device::Device` answering
/// commands, booting on adjacent, and a frame of its configuration every 2 ms while started (each passed through `mangle` first: a
/// faulty board).
struct FakeDevice {
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<TTYPort>>,
}

impl FakeDevice {
    fn start(master: TTYPort) -> Self {
        Self::start_mangling(master, |_| {})
    }

    fn start_mangling(mut master: TTYPort, mangle: fn(&mut Frame)) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let flag = Arc::clone(&stop);
        let thread = thread::spawn(move || {
            master.set_timeout(Duration::from_millis(2)).unwrap();
            let mut device = Device::new(RamStore::<4096>::new(), ScanConfig::REFERENCE).unwrap();
            let mut packets = Box::new(Accumulator::<COMMAND_PACKET_MAX>::new());
            let mut buf = [0u8; 512];
            while !flag.load(Ordering::Relaxed) {
                if let Ok(n) = master.read(&mut buf) {
                    for &b in &buf[..n] {
                        if let Some(d) = packets.feed::<Command>(b)
                            && let Some(reply) = device.handle_decoded(d)
                        {
                            let _ = master.write_all(&packet(&HostUplink::Event(reply)));
                        }
                    }
                }
                if device.scanning() {
                    // The scan it is configured for (a real board's scan task rebuilds its
                    // scanner when the configuration changes).
                    let config = *device.config();
                    let v_m = vec![0.01f32; config.validate().unwrap().frame_len()];
                    let mut out = device
                        .frame(&config, et_core::Micros(0), &ScanReport::default(), &v_m, 0)
                        .unwrap();
                    mangle(&mut out.frame);
                    let _ = master.write_all(&packet(&Uplink::Frame(out.frame)));
                }
            }
            master
        });
        Self {
            stop,
            thread: Some(thread),
        }
    }

    /// Stops the device and gives its end of the cable back.
    fn stop(mut self) -> TTYPort {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.take().unwrap().join().unwrap()
    }
}

/// A pty pair reached through a stable symlink in `dir` (as /dev/serial/by-id is).
fn cable(dir: &Path) -> (TTYPort, PathBuf) {
    let (master, slave) = TTYPort::pair().unwrap();
    let target = slave.name().unwrap();
    // The slave end must stay open until the link has opened it, or the pty hangs up.
    std::mem::forget(slave);
    let link = dir.join("et-device");
    let _ = std::fs::remove_file(&link);
    std::os::unix::fs::symlink(target, &link).unwrap();
    (master, link)
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("et-link-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn frames(link: &mut Link, n: usize) -> Vec<HostFrame> {
    let mut out = Vec::new();
    let deadline = Instant::now() + Duration::from_secs(10);
    while out.len() < n && Instant::now() < deadline {
        if let Ok(Uplink::Frame(f)) = link.next(Duration::from_millis(100)) {
            out.push(f);
        }
    }
    assert_eq!(out.len(), n, "frames within 10 s");
    out
}

/// A path that is no port is said as what it is, with what to do: no path, a file (a
/// recording given as the port), a folder, a device that is no terminal, nothing there (the
/// system's "Not a typewriter", "Is a directory" and "No such file or directory" were all they
/// said).
#[test]
fn a_path_that_is_no_port_is_said_as_what_it_is() {
    let dir = temp_dir("noport");
    let file = dir.join("r.jsonl");
    std::fs::write(&file, "{}\n").unwrap();
    let (file, folder) = (file.display().to_string(), dir.display().to_string());
    let missing = dir.join("ttyACM9").display().to_string();
    for (path, said) in [
        (
            "",
            "no serial port given: give the board's port (`et ports` lists the ports)",
        ),
        (
            file.as_str(),
            "a file, not a port (a recording is played with --replay",
        ),
        (folder.as_str(), "a folder, not a port"),
        ("/dev/null", "not a serial port"),
        (
            missing.as_str(),
            "no such port: is the board plugged in, and the path right?",
        ),
    ] {
        let e = Link::open(path, 115_200).unwrap_err().to_string();
        assert!(
            e.contains(said) && e.ends_with("(`et ports` lists the ports)"),
            "{path}: {e}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Frames a board sent while no one read them, waiting in the port, are dropped when a link
/// opens it: its first frame is one the board sends now (they were taken, and the gap from
/// them to the board's frames now counted as frames lost: the viewer's "lost" on connecting).
#[test]
fn frames_left_in_the_port_from_before_are_not_this_links() {
    let dir = temp_dir("left");
    let (mut master, path) = cable(&dir);
    for seq in 0..3 {
        master.write_all(&packet(&frame(seq))).unwrap();
    }
    let mut link = Link::open(path.to_str().unwrap(), 115_200).unwrap();
    for seq in 40..43 {
        master.write_all(&packet(&frame(seq))).unwrap();
    }
    let seqs: Vec<u32> = frames(&mut link, 3).iter().map(|f| f.seq).collect();
    assert_eq!(seqs, [40, 41, 42]);
    assert_eq!(link.counters().lost_frames, 0);
    drop(link);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn commands_get_their_replies_over_a_pty() {
    let dir = temp_dir("commands");
    let (master, path) = cable(&dir);
    let device = FakeDevice::start(master);
    let mut link = Link::open(path.to_str().unwrap(), et_core::board::BAUD).unwrap();
    let t = Duration::from_secs(2);
    assert_eq!(
        link.request(&Command::Ping { nonce: 42 }, t).unwrap(),
        Event::Pong { nonce: 42 }
    );
    let bad = ScanConfig {
        electrodes: 3,
        ..ScanConfig::REFERENCE
    };
    match link.request(&Command::Configure(bad), t) {
        Err(LinkError::Refused { reason, .. }) => assert_eq!(reason, Refusal::BadConfig),
        other => panic!("{other:?}"),
    }
    // Garbage into the device's input is refused, and the link goes on.
    link.send_bytes(&[0, 1, 2, 3, 0]).unwrap();
    assert!(matches!(
        link.next(t),
        Ok(Uplink::Event(Event::Refused {
            command: CommandTag::Unknown,
            ..
        }))
    ));
    link.request(&Command::Start, t).unwrap();
    let got = frames(&mut link, 20);
    assert!(got.windows(2).all(|w| w[1].seq == w[0].seq + 1));
    // A request while frames stream: they are kept, not lost.
    link.request(&Command::Ping { nonce: 1 }, t).unwrap();
    let more = frames(&mut link, 5);
    assert_eq!(
        more[0].seq,
        got[19].seq + 1,
        "no frame lost around the request"
    );
    // An upload the device refuses (not a model) reports the refusal.
    match link.upload_model(&[1, 2, 3, 4, 5, 6, 7, 8], t, t) {
        Err(LinkError::Refused { command, reason }) => {
            assert_eq!(
                (command, reason),
                (CommandTag::ModelCommit, Refusal::BadModel)
            );
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(link.counters().corrupt, 0);
    assert_eq!(link.counters().lost_frames, 0);
    drop(link);
    device.stop();
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_pulled_cable_is_reconnected_and_frames_flow_again() {
    let dir = temp_dir("pulled");
    let (master, path) = cable(&dir);
    let device = FakeDevice::start(master);
    let mut link = Link::open(path.to_str().unwrap(), et_core::board::BAUD).unwrap();
    let t = Duration::from_secs(2);
    link.request(&Command::Start, t).unwrap();
    let before = frames(&mut link, 10);
    // Pull: the device's end goes away.
    drop(device.stop());
    thread::sleep(Duration::from_millis(300));
    assert!(matches!(
        link.send(&Command::Stop),
        Err(LinkError::Disconnected | LinkError::Write(_))
    ));
    // Plug back in (a new pty behind the same name): the link reopens it by itself.
    let (master, _) = cable(&dir);
    let device = FakeDevice::start(master);
    let deadline = Instant::now() + Duration::from_secs(5);
    while link.counters().reconnects == 0 && Instant::now() < deadline {
        thread::sleep(Duration::from_millis(50));
    }
    assert_eq!(link.counters().reconnects, 1);
    link.request(&Command::Start, t).unwrap();
    // First what the old device sent before the pull (kept, in order), then the new one's
    // frames from seq 0.
    let after = frames(&mut link, 60);
    let restart = after
        .iter()
        .position(|f| f.seq == 0)
        .expect("the new device's first frame");
    let seqs: Vec<u32> = before
        .iter()
        .chain(&after[..restart])
        .map(|f| f.seq)
        .collect();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "nothing lost before the pull"
    );
    assert!(
        after[restart..]
            .windows(2)
            .all(|w| w[1].seq == w[0].seq + 1)
    );
    drop(link);
    device.stop();
    let _ = std::fs::remove_dir_all(dir);
}

/// A board that restarts (here: the cable pulled and a board just booted plugged in) scans
/// adjacent, or its stored model's configuration, and waits; `et stream` and `et view` ask it
/// for the scan they set again before Start (they used to send Start only, and went on with
/// the board's scan without a word: a host model's classes lost).
#[test]
fn a_board_that_restarts_is_asked_for_the_scan_it_was_given() {
    use et_core::protocol::ProtocolKind;
    use et_host::live::{Source, SourceSpec, open_source};
    let dir = temp_dir("rescan");
    let (master, path) = cable(&dir);
    let device = FakeDevice::start(master);
    let spec = SourceSpec::Port(path.to_str().unwrap().into(), et_core::board::BAUD);
    let (mut source, _) = open_source(&spec, None).unwrap();
    let opposite = ScanConfig {
        protocol: ProtocolKind::Opposite,
        ..ScanConfig::REFERENCE
    };
    source.configure(opposite).unwrap();
    // The configurations and sequence numbers of the next `n` frames numbered up to `below`
    // (those of a board before waiting may follow: a new board numbers from 0 again), and the
    // link's changes.
    let next = |source: &mut Source, n: usize, below: u32| {
        let (mut frames, mut changes) = (Vec::new(), Vec::new());
        let deadline = Instant::now() + Duration::from_secs(10);
        while frames.len() < n && Instant::now() < deadline {
            for f in source.poll(64, true).unwrap() {
                if f.seq < below && frames.len() < n {
                    frames.push((f.config, f.seq));
                }
            }
            changes.extend(source.link_changes());
            thread::sleep(Duration::from_millis(5));
        }
        assert_eq!(frames.len(), n, "frames within 10 s; changes {changes:?}");
        (frames, changes)
    };
    let (frames, _) = next(&mut source, 40, u32::MAX);
    assert_eq!(frames[39].0, opposite);
    drop(device.stop());
    thread::sleep(Duration::from_millis(300));
    let (master, _) = cable(&dir);
    let device = FakeDevice::start(master);
    let (frames, changes) = next(&mut source, 20, frames[39].1);
    assert!(
        frames.iter().all(|(c, _)| *c == opposite),
        "the restarted board's frames: {:?}",
        frames
            .iter()
            .map(|(c, _)| c.protocol.name())
            .collect::<Vec<_>>()
    );
    assert!(changes.contains(&LinkChange::Back), "{changes:?}");
    drop(source);
    device.stop();
    let _ = std::fs::remove_dir_all(dir);
}

/// A board whose front end cannot scan its configuration sends its fault and no frames:
/// `et record` says the board's words (it waited without one; its events were dropped).
#[test]
fn a_recording_says_what_the_board_reports() {
    use et_host::recorder::{Notice, Plan, record};
    let dir = temp_dir("faulty");
    let (mut master, path) = cable(&dir);
    let stop = Arc::new(AtomicBool::new(false));
    let flag = Arc::clone(&stop);
    let board = thread::spawn(move || {
        let fault = HostUplink::Event(Event::Fault(et_core::wire::Fault::Frontend { seq: 7 }));
        while !flag.load(Ordering::Relaxed) {
            let _ = master.write_all(&packet(&fault));
            thread::sleep(Duration::from_millis(50));
        }
    });
    let mut link = Link::open(path.to_str().unwrap(), et_core::board::BAUD).unwrap();
    let plan = Plan {
        out: dir.join("r.jsonl"),
        frames: Some(1),
        duration: Some(Duration::from_millis(600)),
        send_start: false,
        force: false,
    };
    let mut notices = Vec::new();
    let tally = record(&mut link, &plan, |n| notices.push(n)).unwrap();
    stop.store(true, Ordering::Relaxed);
    board.join().unwrap();
    assert_eq!(tally.written, 0);
    let said = notices.iter().find_map(|n| match n {
        Notice::Board(s) => Some(s.clone()),
        _ => None,
    });
    assert!(
        said.as_deref()
            .is_some_and(|s| s.contains("the front end failed at scan 7")),
        "{notices:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `et record` through a faulty board and a pulled cable: a frame with the wrong value count
/// is skipped and counted (it used to end the recording), a NaN is kept and flagged (it used
/// to make the file unreadable), and a board that comes back idle after the replug is sent
/// Start again (the recording used to stall forever).
#[test]
fn a_recording_rides_out_bad_frames_and_a_replug_to_an_idle_board() {
    use et_host::link::LinkChange;
    use et_host::recorder::{Notice, Plan, record};
    let dir = temp_dir("record");
    let (master, path) = cable(&dir);
    let mangle: fn(&mut Frame) = |f| match f.seq {
        3 => f.voltages.truncate(100),
        5 => f.voltages[2] = f32::NAN,
        // The board's own flag: a reading with samples on an ADC rail.
        7 | 8 => {
            f.flags |= wire::FLAG_RAIL;
            f.rail_count = 1;
        }
        _ => {}
    };
    let device = FakeDevice::start_mangling(master, mangle);
    let mut link = Link::open(path.to_str().unwrap(), et_core::board::BAUD).unwrap();
    link.request(&Command::Start, Duration::from_secs(2))
        .unwrap();
    let out = dir.join("session.jsonl");
    let plan = Plan {
        out: out.clone(),
        frames: Some(400),
        duration: Some(Duration::from_secs(20)),
        send_start: true,
        force: false,
    };
    let recorder = thread::spawn(move || {
        let mut notices = Vec::new();
        let tally = record(&mut link, &plan, |n| notices.push(n)).unwrap();
        (tally, notices)
    });
    // Pull the cable after ~100 frames; plug in a board that has just booted (not scanning).
    thread::sleep(Duration::from_millis(200));
    drop(device.stop());
    thread::sleep(Duration::from_millis(600));
    let (master, _) = cable(&dir);
    let device = FakeDevice::start_mangling(master, mangle);
    let (tally, notices) = recorder.join().unwrap();
    device.stop();
    assert_eq!(tally.written, 400, "{tally}");
    assert_eq!((tally.skipped, tally.flagged), (2, 2), "{tally}");
    // Frames 7 and 8 of each board flagged, said once (the first), and counted.
    assert_eq!(tally.board_flagged, 4, "{tally}");
    let said: Vec<_> = (notices.iter())
        .filter_map(|n| match n {
            Notice::Flagged { seq, said } => Some((*seq, said.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(said.len(), 1, "{said:?}");
    assert_eq!(said[0].0, 7);
    assert!(said[0].1.contains("on an ADC rail"), "{said:?}");
    assert_eq!(tally.link.reconnects, 1);
    for change in [LinkChange::Vanished, LinkChange::Back] {
        assert!(
            notices.contains(&Notice::Link(change)),
            "{change:?}: {notices:?}"
        );
    }
    assert!(notices.contains(&Notice::Skipped {
        seq: 3,
        got: 100,
        expected: 208
    }));
    // One part, every frame readable, the NaN flagged.
    let rec = et_host::recording::read(&out).unwrap();
    assert_eq!(rec.records.len(), 400);
    assert_eq!(rec.records.iter().filter(|r| r.invalid == [2]).count(), 2);
    assert!(!dir.join("session-2.jsonl").exists());
    // Recording onto it again is refused before anything is sent.
    let (master, _) = cable(&dir);
    let device = FakeDevice::start(master);
    let mut link = Link::open(path.to_str().unwrap(), et_core::board::BAUD).unwrap();
    let again = Plan {
        out: out.clone(),
        frames: Some(1),
        duration: None,
        send_start: false,
        force: false,
    };
    let e = record(&mut link, &again, |_| {}).unwrap_err().to_string();
    assert!(e.contains("already exists"), "{e}");
    assert_eq!(et_host::recording::read(&out).unwrap().records.len(), 400);
    drop(link);
    device.stop();
    let _ = std::fs::remove_dir_all(dir);
}

fn uplink_packets() -> Vec<(Uplink, Vec<u8>)> {
    let mut v = vec![
        frame(5),
        frame(6),
        Uplink::Event(Event::Pong { nonce: 77 }),
        Uplink::Event(Event::Touch {
            seq: 6,
            class: 3,
            margin: 1.5,
        }),
        Uplink::Event(Event::Refused {
            command: CommandTag::ModelCommit,
            reason: Refusal::BadModel,
        }),
    ];
    let mut big = frame(7);
    if let Uplink::Frame(f) = &mut big {
        f.voltages = (0..208).map(|i| i as f32 * 1e-3).collect();
    }
    v.push(big);
    v.into_iter()
        .map(|m| {
            let p = packet(&m);
            (m, p)
        })
        .collect()
}

proptest::proptest! {
    // Cases from PROPTEST_CASES (256 by default). The fuzzing run of the README:
    // PROPTEST_CASES=1000000 cargo test --release -p et-host fuzz_
    /// The host's frame decoder on damaged streams: never panics, and whatever it decodes is
    /// one of the messages that were sent (a damaged packet is dropped, never misread).
    #[test]
    fn fuzz_frame_decoder(
        picks in proptest::collection::vec(0usize..6, 0..10),
        flips in proptest::collection::vec((0usize..8192, 0u8..8), 0..6),
        cuts in proptest::collection::vec(0usize..8192, 0..3),
        garbage in proptest::collection::vec(proptest::num::u8::ANY, 0..64),
        at in 0usize..8192,
        piece in 1usize..300,
    ) {
        let packets = uplink_packets();
        let mut stream: Vec<u8> = picks.iter().flat_map(|&i| packets[i].1.clone()).collect();
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
        let mut d = Decoder::new();
        let mut out = Vec::new();
        for chunk in stream.chunks(piece) {
            d.feed(chunk, &mut out);
        }
        for m in &out {
            proptest::prop_assert!(packets.iter().any(|(sent, _)| HostUplink::from(sent.clone()) == *m), "misread {:?}", m);
        }
        let c = d.counters();
        proptest::prop_assert_eq!(c.frames + c.events, out.len() as u64);
    }
}
