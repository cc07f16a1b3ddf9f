//! The firmware image in QEMU, end to end (issue: "the test that proves the image works").
//!
//! Builds the `qemu` image (`cd firmware && cargo build --profile qemu --features qemu`), boots
//! it on QEMU's netduinoplus2 with USART1 on a pty, attaches `et_host::link::Link` to the pty
//! and checks, against the simulator's resistor network (`et_sim::emulated::QemuSheet`):
//!
//! 1. frames decode, in sequence, and match the sheet's noiseless voltages within the noise;
//! 2. a model trained on the host and uploaded in chunks classifies on the chip, and the chip's
//!    classes equal the host's for the same frames;
//! 3. reconfiguring the protocol takes effect on the next frames (and the adjacent-protocol
//!    model then stays silent rather than misclassify);
//! 4. garbage and a damaged command into the firmware's input are refused and scanning goes
//!    on without a gap.
//!
//! QEMU runs under `timeout` and is killed when the test ends, pass or fail.

use std::io::{BufRead, BufReader, Write};
use std::path::{Path, PathBuf};
use std::process::{Child, ChildStdin, Command as Process, Stdio};
use std::time::Duration;

use et_core::ScanConfig;
use et_core::board::BAUD;
use et_core::model::{Model, Precision};
use et_core::protocol::{Halving, Protocol, ProtocolKind};
use et_core::rng::Rng;
use et_core::wire::{self, Command, CommandTag, Event, HostFrame, Refusal, Uplink};
use et_host::link::{Link, LinkError};
use et_learn::fit::{FitOptions, Fitted, fisher_ranking};
use et_sim::emulated::QemuSheet;
use nalgebra::DMatrix;

/// Seconds QEMU may live: `timeout` kills it even if this test hangs.
const QEMU_LIFETIME_S: u32 = 180;
const REPLY: Duration = Duration::from_secs(5);
/// The wait for the booted board's first status event: QEMU's boot shares the cores with the
/// other test binaries, and 5 s ran out once while both were busy.
const BOOT: Duration = Duration::from_secs(30);

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Why the QEMU tests cannot run on this machine (the thumbv7em target or qemu-system-arm
/// missing), or None when they can.
fn missing_tools() -> Option<String> {
    let sysroot = Process::new("rustc")
        .args(["--print", "sysroot"])
        .output()
        .ok()?;
    let sysroot = String::from_utf8_lossy(&sysroot.stdout).trim().to_string();
    let target = Path::new(&sysroot).join("lib/rustlib/thumbv7em-none-eabihf");
    if !target.exists() {
        return Some("the thumbv7em-none-eabihf target is not installed".into());
    }
    let qemu = Process::new("qemu-system-arm").arg("--version").output();
    if !qemu.is_ok_and(|o| o.status.success()) {
        return Some("qemu-system-arm is not installed".into());
    }
    None
}

/// Builds the QEMU image and returns its path, or None (with a message) when this machine
/// lacks the tools. `ET_REQUIRE_QEMU=1` (set by `scripts/test.sh`, which installs them) makes
/// a missing tool a failure instead.
fn image_or_skip(test: &str) -> Option<PathBuf> {
    if let Some(why) = missing_tools() {
        assert!(
            std::env::var_os("ET_REQUIRE_QEMU").is_none(),
            "{test}: {why} (ET_REQUIRE_QEMU is set)"
        );
        eprintln!("skipped {test}: {why}; ./scripts/test.sh installs it and runs this test");
        return None;
    }
    Some(build_image())
}

/// Builds the QEMU image and returns its path; `$ET_QEMU_IMAGE` when set (scripts/test.sh
/// builds the image before the tests, with the board image's compiled dependencies).
fn build_image() -> PathBuf {
    if let Some(image) = std::env::var_os("ET_QEMU_IMAGE") {
        let image = PathBuf::from(image);
        assert!(
            image.is_file(),
            "ET_QEMU_IMAGE: {} is not a file",
            image.display()
        );
        return image;
    }
    let status = Process::new(env!("CARGO"))
        .args(["build", "--profile", "qemu", "--features", "qemu"])
        .current_dir(repo().join("firmware"))
        .status()
        .expect("run cargo for the firmware");
    assert!(status.success(), "the QEMU firmware image did not build");
    repo().join("target/thumbv7em-none-eabihf/qemu/et-firmware")
}

/// QEMU, paused, with its monitor on stdin/stdout and USART1 (the first serial port) on a pty.
struct Qemu {
    child: Child,
    monitor: ChildStdin,
    pty: String,
}

impl Qemu {
    fn boot(image: &Path) -> Self {
        let mut child = Process::new("timeout")
            .arg(QEMU_LIFETIME_S.to_string())
            .args(["qemu-system-arm", "-M", "netduinoplus2", "-display", "none"])
            .args(["-monitor", "stdio", "-serial", "pty", "-S"])
            .arg("-kernel")
            .arg(image)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("qemu-system-arm (./scripts/test.sh installs it)");
        let mut monitor = child.stdin.take().unwrap();
        // Ask the monitor where the pty is (its own "redirected to" notice is buffered).
        writeln!(monitor, "info chardev").unwrap();
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let mut pty = None;
        let mut line = String::new();
        while pty.is_none() {
            line.clear();
            assert!(out.read_line(&mut line).unwrap() > 0, "QEMU exited early");
            // "serial0: filename=pty:/dev/pts/3"
            if let Some(rest) = line.trim().strip_prefix("serial0: filename=pty:") {
                pty = Some(rest.to_string());
            }
        }
        // Keep draining the monitor's output so QEMU never blocks on it.
        std::thread::spawn(move || {
            let mut sink = String::new();
            while out.read_line(&mut sink).is_ok_and(|n| n > 0) {
                sink.clear();
            }
        });
        Self {
            child,
            monitor,
            pty: pty.unwrap(),
        }
    }

    /// Starts the CPU (QEMU drops serial output until a reader is attached, so the link
    /// opens the pty first).
    fn run(&mut self) {
        writeln!(self.monitor, "cont").unwrap();
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = writeln!(self.monitor, "quit");
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The next `n` frames, and every event that came with them.
fn collect(link: &mut Link, n: usize) -> (Vec<HostFrame>, Vec<Event>) {
    let (mut frames, mut events) = (Vec::new(), Vec::new());
    while frames.len() < n {
        match link.next(REPLY) {
            Ok(Uplink::Frame(f)) => frames.push(f),
            Ok(Uplink::Event(e)) => events.push(e),
            Err(e) => panic!("after {} frames: {e}", frames.len()),
        }
    }
    (frames, events)
}

/// Largest and rms difference between a frame and the sheet's noiseless one, V.
fn deviation(frame: &HostFrame, ideal: &[f64]) -> (f64, f64) {
    assert_eq!(frame.voltages.len(), ideal.len());
    let d: Vec<f64> = frame
        .voltages
        .iter()
        .zip(ideal)
        .map(|(&v, &w)| f64::from(v) - w)
        .collect();
    let max = d.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let rms = (d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64).sqrt();
    (max, rms)
}

/// Checks every frame against its state's noiseless frame: within a few ADC codes (the image adds
/// the calibrated 49 uV per sample and quantises at gain 1, a 153 uV code), and nearer its own
/// state than any other.
fn check_against_sheet(sheet: &QemuSheet, frames: &[HostFrame], config: &ScanConfig) {
    let protocol = config.validate().unwrap();
    let amps = f64::from(config.current_amps());
    let ideals: Vec<Vec<f64>> = (0..sheet.transfers.len())
        .map(|s| sheet.ideal_frame(s, &protocol, amps))
        .collect();
    for f in frames {
        assert_eq!(&f.config, config, "frame {}", f.seq);
        let state = sheet.state_of(f.seq);
        let (max, rms) = deviation(f, &ideals[state]);
        assert!(
            max < 2.5e-3 && rms < 0.8e-3,
            "frame {}: max {max} rms {rms}",
            f.seq
        );
        for (other, ideal) in ideals.iter().enumerate() {
            if other != state {
                assert!(
                    deviation(f, ideal).1 > 2.0 * rms,
                    "frame {} vs state {other}",
                    f.seq
                );
            }
        }
    }
}

/// A QDA on the host from noisy copies of each state's noiseless adjacent frame (one class
/// per touch state), with the 16 Fisher-best reciprocity-halved features.
fn train(sheet: &QemuSheet, config: &ScanConfig) -> (Fitted, Vec<u16>, Vec<u8>) {
    let protocol = config.validate().unwrap();
    let amps = f64::from(config.current_amps());
    let features: Vec<usize> = protocol.features(Halving::Reciprocity).collect();
    let classes = sheet.transfers.len();
    let per_class = 80;
    let mut rng = Rng::new(11);
    let mut rows = Vec::new();
    let mut y = Vec::new();
    for c in 0..classes {
        let ideal = sheet.ideal_frame(c, &protocol, amps);
        for _ in 0..per_class {
            rows.extend(features.iter().map(|&k| ideal[k] + 0.5e-3 * rng.normal()));
            y.push(c as u16);
        }
    }
    let x = DMatrix::from_row_slice(y.len(), features.len(), &rows);
    let mut best: Vec<usize> = fisher_ranking(&x, &y, classes)
        .into_iter()
        .take(16)
        .collect();
    // A blob lists its features in frame order (as `et train` keeps them).
    best.sort_unstable();
    let x = x.select_columns(&best);
    let index: Vec<u16> = best.iter().map(|&j| features[j] as u16).collect();
    let opts = FitOptions {
        shrinkage: 0.1,
        ..FitOptions::default()
    };
    let fitted = Fitted::fit(&x, &y, classes, &opts).unwrap();
    let positions: Vec<[f32; 2]> = (0..classes).map(|c| [c as f32, 0.0]).collect();
    let blob = fitted
        .to_blob(
            config.electrodes,
            config.protocol,
            &index,
            &positions,
            Precision::F32,
            false,
        )
        .unwrap();
    (fitted, index, blob)
}

/// Blobs of a model for the board's reference configuration and of one for pseudo-polar
/// frames, which the board must refuse.
fn right_and_wrong_blobs(sheet: &QemuSheet) -> (Vec<u8>, Vec<u8>) {
    let reference = ScanConfig::REFERENCE;
    let pp = ScanConfig {
        protocol: ProtocolKind::PseudoPolar,
        ..reference
    };
    (train(sheet, &reference).2, train(sheet, &pp).2)
}

#[test]
fn the_firmware_image_scans_classifies_and_obeys_in_qemu() {
    let sheet = QemuSheet::new().unwrap();
    let Some(image) = image_or_skip("the_firmware_image_scans_classifies_and_obeys_in_qemu") else {
        return;
    };
    let mut qemu = Qemu::boot(&image);
    let mut link = Link::open(&qemu.pty, BAUD).unwrap();
    qemu.run();

    // Booted: the first status event says the USART is up (bytes sent before that are lost).
    loop {
        if let Uplink::Event(Event::Status(s)) = link.next(BOOT).expect("a status event") {
            assert!(!s.scanning && !s.model_loaded);
            break;
        }
    }
    // Alive, and answering.
    assert_eq!(
        link.request(&Command::Ping { nonce: 0xe7 }, REPLY).unwrap(),
        Event::Pong { nonce: 0xe7 }
    );

    // 1. Frames against the sheet.
    let reference = ScanConfig::REFERENCE;
    link.request(&Command::Start, REPLY).unwrap();
    let (frames, _) = collect(&mut link, 30);
    assert!(
        frames.windows(2).all(|w| w[1].seq == w[0].seq + 1),
        "in sequence"
    );
    check_against_sheet(&sheet, &frames, &reference);

    // 2. A host-trained model, uploaded and classifying on the chip.
    let (fitted, index, blob) = train(&sheet, &reference);
    link.upload_model(&blob, REPLY, REPLY).unwrap();
    let host_model = Model::parse(&blob).unwrap();
    let mut scratch = vec![0.0; host_model.scratch_len()];
    let (frames, events) = collect(&mut link, 120);
    let mut chip = std::collections::HashMap::new();
    for e in &events {
        if let Event::Touch { seq, class, .. } = e {
            chip.insert(*seq, *class);
        }
    }
    let (mut agree_f64, mut right) = (0, 0);
    let mut classified = 0;
    for f in &frames {
        // The Touch event follows its frame; the last frame's may still be in flight.
        let Some(&class) = chip.get(&f.seq) else {
            continue;
        };
        classified += 1;
        let host = host_model.evaluate(&f.voltages, &mut scratch).unwrap();
        assert_eq!(
            class, host.class,
            "frame {}: chip and host (same blob) differ",
            f.seq
        );
        let x: Vec<f64> = index
            .iter()
            .map(|&k| f64::from(f.voltages[usize::from(k)]))
            .collect();
        agree_f64 += usize::from(fitted.predict(&x) == class);
        right += usize::from(usize::from(class) == sheet.state_of(f.seq));
    }
    // Frames queued before the commit's acknowledgement came in unclassified; from the first
    // classified one on, every frame has its class.
    let first = *chip.keys().min().expect("touch events");
    let after_commit = frames.iter().filter(|f| f.seq >= first).count();
    assert!(
        after_commit >= 20,
        "only {after_commit} frames after the upload"
    );
    assert!(
        classified >= after_commit - 1,
        "{classified} of {after_commit} classified"
    );
    assert!(
        agree_f64 * 100 >= classified * 98,
        "f64 host model agrees on {agree_f64}/{classified}"
    );
    assert!(right * 100 >= classified * 95, "{right}/{classified} right");

    // 3. Reconfigure: pseudo-polar frames from the next scan on, no classes from the adjacent
    //    model, and back.
    let pp = ScanConfig {
        protocol: ProtocolKind::PseudoPolar,
        ..reference
    };
    link.request(&Command::Configure(pp), REPLY).unwrap();
    // What came before the acknowledgement was sent before the board took the command (as
    // many as the host was slow to read: 3 on a loaded machine): the change is counted from it.
    for _ in 0..link.kept() {
        link.next(REPLY).unwrap();
    }
    let (frames, events) = collect(&mut link, 40);
    let first_pp = frames
        .iter()
        .position(|f| f.config == pp)
        .expect("pseudo-polar frames");
    assert!(first_pp <= 2, "the change took {first_pp} frames");
    let pp_frames = &frames[first_pp..];
    assert_eq!(
        pp_frames[0].voltages.len(),
        Protocol::new(ProtocolKind::PseudoPolar, 16)
            .unwrap()
            .frame_len()
    );
    check_against_sheet(&sheet, pp_frames, &pp);
    let touches_on_pp = events
        .iter()
        .filter(|e| matches!(e, Event::Touch { seq, .. } if *seq >= pp_frames[0].seq))
        .count();
    assert_eq!(
        touches_on_pp, 0,
        "an adjacent model must not classify pseudo-polar frames"
    );
    link.request(&Command::Configure(reference), REPLY).unwrap();

    // 4. Garbage and a damaged command: refused, scanning goes on without a gap.
    let (before, _) = collect(&mut link, 3);
    link.send_bytes(&[0x00, 0x13, 0x37, 0xff, 0x42, 0x00])
        .unwrap();
    let mut ping = vec![0u8; 32];
    let n = wire::encode(&Command::Ping { nonce: 5 }, &mut ping).unwrap();
    ping.truncate(n);
    ping[4] ^= 0x20;
    link.send_bytes(&ping).unwrap();
    let (after, events) = collect(&mut link, 20);
    let refusals = events
        .iter()
        .filter(|e| {
            matches!(
                e,
                Event::Refused {
                    command: CommandTag::Unknown,
                    reason: Refusal::Malformed(_)
                }
            )
        })
        .count();
    assert_eq!(refusals, 2, "{events:?}");
    assert!(
        !events.iter().any(|e| matches!(e, Event::Pong { .. })),
        "a damaged ping is not answered"
    );
    let seqs: Vec<u32> = before.iter().chain(&after).map(|f| f.seq).collect();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "no frame lost: {seqs:?}"
    );
    // A bad configuration is refused and the old one stays.
    let bad = ScanConfig {
        settle_samples: 50,
        ..reference
    };
    match link.request(&Command::Configure(bad), REPLY) {
        Err(LinkError::Refused { reason, .. }) => assert_eq!(reason, Refusal::BadConfig),
        other => panic!("{other:?}"),
    }
    let (frames, _) = collect(&mut link, 5);
    assert!(frames.iter().all(|f| f.config == reference));
    // A configuration et scans but this front end cannot (8 electrodes on its 16): accepted,
    // then no frames, and the front end's fault said at once and again every 2 s (a host
    // that connected later waited without a word: `et record` on such a board).
    let eight = ScanConfig {
        electrodes: 8,
        ..reference
    };
    link.request(&Command::Configure(eight), REPLY).unwrap();
    let (mut faults, mut frames) = (0, 0);
    let until = std::time::Instant::now() + Duration::from_millis(3500);
    while std::time::Instant::now() < until {
        match link.next(Duration::from_millis(100)) {
            Ok(Uplink::Event(Event::Fault(wire::Fault::Frontend { .. }))) => faults += 1,
            // (A frame of the old configuration may be in flight past the reply.)
            Ok(Uplink::Frame(f)) if f.config == eight => frames += 1,
            _ => {}
        }
    }
    assert!(
        faults >= 2 && frames == 0,
        "{faults} faults, {frames} frames"
    );
    link.request(&Command::Configure(reference), REPLY).unwrap();
    let (frames, _) = collect(&mut link, 3);
    assert!(frames.iter().all(|f| f.config == reference));

    // Health: the device counted the refusals; the link lost nothing.
    let status = loop {
        if let Ok(Uplink::Event(Event::Status(s))) = link.next(REPLY) {
            break s;
        }
    };
    assert!(status.scanning && status.model_loaded);
    assert_eq!(status.bad_commands, 3);
    let counters = link.counters();
    assert_eq!(
        (counters.corrupt, counters.lost_frames),
        (0, 0),
        "{counters:?}"
    );
}

/// Builds `et` and returns its path.
/// A blob whose header sizes wrap the board's 32-bit arithmetic into a length it holds,
/// with a valid CRC: the board must refuse it and keep answering (before the layout was
/// checked it read past the blob and halted).
#[test]
fn the_board_refuses_a_blob_whose_sizes_wrap_32_bit_arithmetic() {
    let Some(image) = image_or_skip("the_board_refuses_a_blob_whose_sizes_wrap_32_bit_arithmetic")
    else {
        return;
    };
    let blob = et_tests::wrapping_qda_blob(16 * 1024);
    let mut qemu = Qemu::boot(&image);
    let mut link = Link::open(&qemu.pty, BAUD).unwrap();
    qemu.run();
    assert_eq!(
        link.request(&Command::Ping { nonce: 1 }, BOOT).unwrap(),
        Event::Pong { nonce: 1 }
    );
    let refused = link.upload_model(&blob, REPLY, REPLY);
    assert!(
        matches!(refused, Err(LinkError::Refused { .. })),
        "{refused:?}"
    );
    assert_eq!(
        link.request(&Command::Ping { nonce: 2 }, REPLY).unwrap(),
        Event::Pong { nonce: 2 },
        "the board still answers"
    );
    // A blob past the image's slot is refused at its start, said with its size and what
    // makes it smaller (a 3 x 3 QDA from the viewer's wizard was "does not fit its model
    // storage" alone).
    let big = vec![0u8; et_core::board::QEMU_MODEL_SLOT_BYTES + 1];
    let refused = link.upload_model(&big, REPLY, REPLY).unwrap_err();
    assert!(
        matches!(refused, LinkError::TooLarge { bytes } if bytes == big.len())
            && refused.to_string().contains("et train --keep"),
        "{refused}"
    );
}

/// The `et` command: `$ET_BIN` when set, else built with `cargo build -p et-host`. The test
/// command (scripts/test.sh) names the `et` its own `cargo test --workspace` built beside the
/// tests: building it here again would compile et and half its dependencies a second time (the
/// features differ from the workspace's), minutes on CI.
fn build_et() -> PathBuf {
    if let Some(et) = std::env::var_os("ET_BIN") {
        return PathBuf::from(et);
    }
    let status = Process::new(env!("CARGO"))
        .args(["build", "-p", "et-host", "--bin", "et"])
        .current_dir(repo())
        .status()
        .expect("run cargo for et");
    assert!(status.success(), "et did not build");
    let profile = if cfg!(debug_assertions) {
        "debug"
    } else {
        "release"
    };
    repo().join("target").join(profile).join("et")
}

/// `et record` from the QEMU board, killed with SIGKILL mid-stream: every frame in the file
/// before the kill is whole and in sequence (at most the frame in flight is lost).
#[test]
fn a_killed_recorder_loses_at_most_the_frame_in_flight() {
    let Some(image) = image_or_skip("a_killed_recorder_loses_at_most_the_frame_in_flight") else {
        return;
    };
    let et = build_et();
    let dir = std::env::temp_dir().join(format!("et-qemu-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("session.jsonl");
    let mut qemu = Qemu::boot(&image);
    let mut recorder = Process::new(et)
        .args(["record", "--port", &qemu.pty, "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    // Let the recorder open the port before the CPU runs.
    std::thread::sleep(Duration::from_millis(300));
    qemu.run();
    let lines = |p: &Path| std::fs::read_to_string(p).map_or(0, |t| t.lines().count());
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    while lines(&out) < 60 {
        assert!(
            std::time::Instant::now() < deadline,
            "the recorder wrote {} lines",
            lines(&out)
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    recorder.kill().unwrap(); // SIGKILL: no chance to flush anything more
    recorder.wait().unwrap();
    let recording = et_host::recording::read(&out).unwrap();
    assert_eq!(recording.header.config, ScanConfig::REFERENCE);
    assert!(recording.records.len() >= 59);
    let seqs: Vec<u32> = recording.records.iter().map(|r| r.seq).collect();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "every frame before the kill is there: {seqs:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// `et upload` to the QEMU board: a model for another protocol is refused (and the command
/// says so), the right one is verified and classifies.
#[test]
fn et_upload_sends_a_model_the_board_verifies() {
    let sheet = QemuSheet::new().unwrap();
    let Some(image) = image_or_skip("et_upload_sends_a_model_the_board_verifies") else {
        return;
    };
    let et = build_et();
    let dir = std::env::temp_dir().join(format!("et-qemu-upload-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (blob, wrong) = right_and_wrong_blobs(&sheet);
    let (good, bad) = (dir.join("model.bin"), dir.join("pp.bin"));
    std::fs::write(&good, &blob).unwrap();
    std::fs::write(&bad, &wrong).unwrap();
    let mut qemu = Qemu::boot(&image);
    let pty = qemu.pty.clone();
    let upload = |path: &Path| {
        Process::new(&et)
            .args(["upload", "--port", &pty, "--blob"])
            .arg(path)
            .output()
            .unwrap()
    };
    qemu.run();
    let refused = upload(&bad);
    assert!(!refused.status.success());
    let message = String::from_utf8_lossy(&refused.stderr);
    assert!(
        message.contains("the model was trained for pseudo-polar at L = 16")
            && message.contains("et upload --model model.json"),
        "{message}"
    );
    let accepted = upload(&good);
    assert!(
        accepted.status.success(),
        "{}",
        String::from_utf8_lossy(&accepted.stderr)
    );
    assert!(String::from_utf8_lossy(&accepted.stdout).contains("the board verified it"));
    let mut link = Link::open(&qemu.pty, BAUD).unwrap();
    link.request(&Command::Start, REPLY).unwrap();
    let (frames, events) = collect(&mut link, 20);
    let touches = events
        .iter()
        .filter(|e| matches!(e, Event::Touch { .. }))
        .count();
    assert!(
        touches >= frames.len() - 2,
        "{touches} classes for {} frames",
        frames.len()
    );
    drop(link);
    // The same model as the file `et train` writes: the board is first set to its scan,
    // then takes it (a model of et collect's opposite scan could not be put on a fresh board
    // at all).
    let pp = ScanConfig {
        protocol: ProtocolKind::PseudoPolar,
        ..ScanConfig::REFERENCE
    };
    let (fitted, index, _) = train(&sheet, &pp);
    let centres = (0..sheet.transfers.len())
        .map(|c| [c as f64 * 1e-3, 0.0])
        .collect();
    let file = et_learn::model_file::ModelFile::new(&fitted, 0.1, pp, index, centres, false);
    let json = dir.join("pp.json");
    file.save(&json).unwrap();
    let by_file = Process::new(&et)
        .args(["upload", "--port", &pty, "--model"])
        .arg(&json)
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&by_file.stdout);
    assert!(
        by_file.status.success()
            && said.contains(
                "set the board to the scan the model was trained on: L = 16, pseudo-polar"
            ),
        "{said}{}",
        String::from_utf8_lossy(&by_file.stderr)
    );
    // Cleared: the board says so in its status and classifies no frame.
    let cleared = Process::new(&et)
        .args(["upload", "--port", &pty, "--clear"])
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&cleared.stdout);
    assert!(
        cleared.status.success() && said.contains("cleared the board's model"),
        "{said}{}",
        String::from_utf8_lossy(&cleared.stderr)
    );
    let mut link = Link::open(&qemu.pty, BAUD).unwrap();
    link.request(&Command::Start, REPLY).unwrap();
    // (Over a second of frames: a status comes twice a second.)
    let (frames, events) = collect(&mut link, 100);
    assert!(!frames.is_empty());
    assert!(
        !events.iter().any(|e| matches!(e, Event::Touch { .. })),
        "{events:?}"
    );
    assert!(
        events
            .iter()
            .any(|e| matches!(e, Event::Status(s) if !s.model_loaded)),
        "{events:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// The viewer's board source (`live::Source::Port`): the wizard's "Export to the board" goes
/// through `PortSource::install_model`; a model for another protocol is refused with the
/// board's reason, the right one is verified, and the frames the source delivers carry the
/// chip's classes, which name the sheet's state.
#[test]
fn the_live_board_source_installs_a_model_and_delivers_the_chips_classes() {
    use et_host::live::{LiveError, PortSource, Source};
    let sheet = QemuSheet::new().unwrap();
    let Some(image) =
        image_or_skip("the_live_board_source_installs_a_model_and_delivers_the_chips_classes")
    else {
        return;
    };
    let (blob, wrong) = right_and_wrong_blobs(&sheet);
    let mut qemu = Qemu::boot(&image);
    qemu.run();
    let mut port = PortSource::open(&qemu.pty, BAUD).unwrap();
    let refused = port.install_model(&wrong).unwrap_err();
    assert!(
        matches!(refused, LiveError::Link { .. })
            && refused.to_string().contains("trained for another scan"),
        "{refused}"
    );
    assert!(port.install_model(&blob[..blob.len() / 2]).is_err());
    let done = port.install_model(&blob).unwrap();
    assert!(done.contains("verified"), "{done}");
    let mut source = Source::Port(Box::new(port));
    let (mut frames, started) = (Vec::new(), std::time::Instant::now());
    // The frames that queued up during the upload come first.
    let classified = |frames: &[et_host::live::LiveFrame]| {
        frames.iter().filter(|f| f.chip_class.is_some()).count()
    };
    while classified(&frames) < 30 && started.elapsed() < Duration::from_secs(60) {
        frames.extend(source.poll(256, false).unwrap());
        std::thread::sleep(Duration::from_millis(20));
    }
    // Frames queued before the commit's acknowledgement come unclassified; after the first
    // classified one, every frame has its class, and the class is the sheet's state.
    let first = frames
        .iter()
        .position(|f| f.chip_class.is_some())
        .expect("classified frames");
    let after = &frames[first..];
    assert!(
        after.len() >= 20,
        "only {} frames after the upload",
        after.len()
    );
    let classified = classified(after);
    assert!(
        classified >= after.len() - 1,
        "{classified} of {}",
        after.len()
    );
    let right = after
        .iter()
        .filter(|f| {
            f.chip_class
                .is_some_and(|c| usize::from(c.class) == sheet.state_of(f.seq))
        })
        .count();
    assert!(right * 100 >= classified * 95, "{right}/{classified} right");
}

/// `et stream --model` of a model trained on another sheet (8 electrodes) than the QEMU
/// board's (16): the board's front end refuses the model's scan, the board says so and goes
/// back to the scan it made before, and the stream ends with the reason (it said the fault
/// every second without end, and the board kept the scan it could not make until reset).
#[test]
fn a_stream_whose_model_the_board_cannot_scan_ends_with_the_reason() {
    let Some(image) =
        image_or_skip("a_stream_whose_model_the_board_cannot_scan_ends_with_the_reason")
    else {
        return;
    };
    let et = build_et();
    let dir = std::env::temp_dir().join(format!("et-qemu-unscanned-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = repo().join("sim/scenes/square-13cm-8.toml");
    let (data, model) = (dir.join("d8.npz"), dir.join("m8.json"));
    for args in [
        vec![
            "collect",
            "--scene",
            scene.to_str().unwrap(),
            "--grid",
            "2x2",
            "--visits",
            "1",
        ],
        vec![
            "train",
            "--data",
            data.to_str().unwrap(),
            "--out",
            model.to_str().unwrap(),
        ],
    ] {
        let mut args = args;
        if args[0] == "collect" {
            args.extend([
                "--scans",
                "3",
                "--subsections",
                "3",
                "--out",
                data.to_str().unwrap(),
            ]);
        }
        let done = Process::new(&et).args(&args).output().unwrap();
        assert!(
            done.status.success(),
            "{}",
            String::from_utf8_lossy(&done.stderr)
        );
    }
    let mut qemu = Qemu::boot(&image);
    qemu.run();
    let mut stream = Process::new(&et)
        .args(["stream", "--port", &qemu.pty, "--reference", "2", "--scene"])
        .arg(&scene)
        .arg("--model")
        .arg(&model)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = stream.stderr.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut said = String::new();
        let _ = std::io::Read::read_to_string(&mut stderr, &mut said);
        said
    });
    let deadline = std::time::Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(status) = stream.try_wait().unwrap() {
            break Some(status);
        }
        if std::time::Instant::now() > deadline {
            stream.kill().unwrap();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let said = reader.join().unwrap();
    let Some(status) = status else {
        panic!("the stream was still running after 60 s: {said}");
    };
    assert!(!status.success(), "{said}");
    assert!(
        said.contains(
            "the board reported a fault and scans 16 electrodes, adjacent, not the model's scan \
             (8 electrodes, opposite)"
        ),
        "{said}"
    );
    // The board went back to the scan it made before (it stayed on the one it cannot make
    // until reset, and every stream after it got no frames).
    let after = Process::new(&et)
        .args([
            "stream",
            "--port",
            &qemu.pty,
            "--reference",
            "2",
            "--frames",
            "6",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(
        after.status.success() && String::from_utf8_lossy(&after.stdout).lines().count() > 0,
        "{}",
        String::from_utf8_lossy(&after.stderr)
    );
    let _ = std::fs::remove_dir_all(dir);
}
