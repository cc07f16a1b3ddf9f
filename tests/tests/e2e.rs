//! Scan, wire, upload, classify: everything `et-core` does, wired end to end.

use et_core::device::{self, RamStore};
use et_core::model::{Model, ModelKind, ModelTables, Precision, model_len, write_model};
use et_core::protocol::{Halving, ProtocolKind};
use et_core::wire::{
    self, Accumulator, COMMAND_PACKET_MAX, Command, Event, FLAG_SUBSECTION, Frame, MODEL_CHUNK,
    PACKET_MAX, Uplink,
};
use et_core::{Micros, ScanConfig, ScanReport, Scanner};
use et_tests::ScriptedSheet;

const CLASSES: u16 = 4;

fn config() -> ScanConfig {
    ScanConfig {
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        samples_per_step: 60,
        settle_samples: 20,
        ..ScanConfig::REFERENCE
    }
}

fn packet<T: serde::Serialize>(m: &T) -> Vec<u8> {
    let mut buf = vec![0u8; PACKET_MAX];
    let n = wire::encode(m, &mut buf).expect("fits");
    buf.truncate(n);
    buf
}

/// The device side as the firmware wires it: the scan engine on a scripted sheet, and
/// `et_core::device::Device` for commands, frames, model upload and on-chip classes.
struct Device {
    sheet: ScriptedSheet,
    scanner: Scanner,
    device: Box<device::Device<RamStore<16384>>>,
    commands: Box<Accumulator<COMMAND_PACKET_MAX>>,
}

impl Device {
    fn new() -> Self {
        let mut sheet = ScriptedSheet::new(0xfeed);
        let scanner = Scanner::new(config(), &mut sheet).expect("valid config");
        let device = Box::new(device::Device::new(RamStore::new(), config()).expect("valid"));
        Self {
            sheet,
            scanner,
            device,
            commands: Box::default(),
        }
    }

    /// Training mode: one scan cut into `subsections` observations, each sent as a frame.
    fn training_frames(&mut self, subsections: usize) -> Vec<u8> {
        let k = self.scanner.frame_len();
        let mut burst = vec![0u16; 60];
        let mut scratch = vec![
            et_core::extract::Extracted {
                median_code: 0.0,
                rail_samples: 0
            };
            subsections
        ];
        let mut obs = vec![0.0f32; subsections * k];
        let report = self
            .scanner
            .scan_subsections(
                &mut self.sheet,
                &mut burst,
                subsections,
                &mut scratch,
                &mut obs,
            )
            .expect("scan");
        let mut out = Vec::new();
        for o in obs.chunks(k) {
            out.extend(self.frame(&report, FLAG_SUBSECTION, o));
        }
        out
    }

    /// The frame's packet and its events' packets.
    fn frame(&mut self, report: &ScanReport, flags: u8, v_m: &[f32]) -> Vec<u8> {
        let t = Micros(self.device.next_seq() * 12_800);
        let out = self
            .device
            .frame(self.scanner.config(), t, report, v_m, flags)
            .expect("K <= K_MAX");
        let mut bytes = packet(&Uplink::Frame(out.frame));
        for e in out.events {
            bytes.extend(packet(&Uplink::<()>::Event(e)));
        }
        bytes
    }

    /// Live mode: one scan, its frame, and the on-chip class as a Touch event.
    fn live(&mut self) -> Vec<u8> {
        let k = self.scanner.frame_len();
        let mut burst = vec![0u16; 60];
        let mut v_m = vec![0.0f32; k];
        let report = self
            .scanner
            .scan(&mut self.sheet, &mut burst, &mut v_m)
            .expect("scan");
        assert_eq!(report.rail.count(), 0);
        self.frame(&report, 0, &v_m)
    }

    /// Feeds command bytes; returns reply packets.
    fn receive(&mut self, bytes: &[u8]) -> Vec<u8> {
        let mut replies = Vec::new();
        for &b in bytes {
            if let Some(result) = self.commands.feed::<Command>(b)
                && let Some(reply) = self.device.handle_decoded(result)
            {
                replies.extend(packet(&Uplink::<()>::Event(reply)));
            }
        }
        replies
    }
}

/// Host side: decode everything in a byte stream.
fn host_decode(acc: &mut Accumulator<PACKET_MAX>, bytes: &[u8]) -> (Vec<Frame>, Vec<Event>, usize) {
    let (mut frames, mut events, mut errors) = (Vec::new(), Vec::new(), 0);
    for &b in bytes {
        match acc.feed::<Uplink>(b) {
            Some(Ok(Uplink::Frame(f))) => frames.push(f),
            Some(Ok(Uplink::Event(e))) => events.push(e),
            Some(Err(_)) => errors += 1,
            None => {}
        }
    }
    (frames, events, errors)
}

/// Nearest-class-mean in z-space as a QDA blob with identity covariances (Sigma_c = I): the
/// simplest model the blob can carry, enough to test the plumbing (learning proper is the
/// host's `learn` module).
fn fit(frames_by_class: &[Vec<Frame>]) -> Vec<u8> {
    let protocol = config().validate().unwrap();
    let features: Vec<u16> = protocol
        .features(Halving::Reciprocity)
        .map(|k| k as u16)
        .collect();
    let p = features.len();
    let all: Vec<&Frame> = frames_by_class.iter().flatten().collect();
    let n = all.len() as f64;
    let value = |f: &Frame, j: usize| f64::from(f.voltages[usize::from(features[j])]);
    let mean: Vec<f64> = (0..p)
        .map(|j| all.iter().map(|f| value(f, j)).sum::<f64>() / n)
        .collect();
    let scale: Vec<f64> = (0..p)
        .map(|j| {
            (all.iter()
                .map(|f| (value(f, j) - mean[j]).powi(2))
                .sum::<f64>()
                / (n - 1.0))
                .sqrt()
        })
        .collect();
    let mut mu = Vec::new();
    for frames in frames_by_class {
        for j in 0..p {
            let m = frames
                .iter()
                .map(|f| (value(f, j) - mean[j]) / scale[j])
                .sum::<f64>()
                / frames.len() as f64;
            mu.push(m as f32);
        }
    }
    let identity: Vec<f32> = (0..p)
        .flat_map(|r| (0..=r).map(move |c| if r == c { 1.0 } else { 0.0 }))
        .collect();
    let c_n = frames_by_class.len();
    let tables = ModelTables {
        kind: ModelKind::Qda,
        precision: Precision::F32,
        referenced: false,
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        feature_index: &features,
        mean: &mean.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        scale: &scale.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        positions_mm: &(0..c_n).map(|c| [20.0 * c as f32, 0.0]).collect::<Vec<_>>(),
        log_prior: &vec![-(c_n as f32).ln(); c_n],
        constant: &vec![0.0; c_n],
        vectors: &mu,
        factors: &identity.repeat(c_n),
    };
    let mut blob = vec![0u8; model_len(ModelKind::Qda, Precision::F32, c_n, p)];
    write_model(&tables, &mut blob).expect("valid tables");
    blob
}

#[test]
fn scan_stream_upload_and_classify_on_device() {
    let mut device = Device::new();
    let mut host: Box<Accumulator<PACKET_MAX>> = Box::default();

    // 1. Training data: each class touched, scanned, cut into sub-section observations and
    //    streamed; the stream carries line noise between some packets.
    let mut frames_by_class = Vec::new();
    for class in 0..CLASSES {
        device.sheet.touch = Some(class);
        let mut stream = Vec::new();
        for scan in 0..6 {
            stream.extend(device.training_frames(5));
            if scan % 2 == 0 {
                stream.extend([0x13, 0x37, 0xff, 0x42]); // garbage, no delimiter
            }
        }
        let (frames, events, errors) = host_decode(&mut host, &stream);
        assert!(events.is_empty());
        assert!(errors <= 3, "only the garbage is lost, {errors} errors");
        assert_eq!(frames.len(), 30, "every frame of class {class} arrives");
        assert!(
            frames
                .iter()
                .all(|f| f.flags & FLAG_SUBSECTION != 0 && f.voltages.len() == 32)
        );
        frames_by_class.push(frames);
    }

    // 2. The host fits and uploads the model in chunks; one chunk is corrupted in flight
    //    (refused, then sent again).
    let blob = fit(&frames_by_class);
    let mut commands = vec![Command::ModelBegin {
        len: blob.len() as u32,
        crc: wire::crc32(&blob),
    }];
    for (i, chunk) in blob.chunks(MODEL_CHUNK).enumerate() {
        commands.push(Command::ModelChunk {
            offset: (i * MODEL_CHUNK) as u32,
            data: heapless::Vec::from_slice(chunk).unwrap(),
        });
    }
    commands.push(Command::ModelCommit);
    let mut replies = Vec::new();
    for (i, cmd) in commands.iter().enumerate() {
        let mut bytes = packet(cmd);
        if i == 2 {
            let mut damaged = bytes.clone();
            damaged[10] ^= 0x04;
            replies.extend(device.receive(&damaged));
        }
        replies.extend(device.receive(&bytes));
        bytes.clear();
    }
    let (_, events, errors) = host_decode(&mut host, &replies);
    assert_eq!(errors, 0);
    let refused = events
        .iter()
        .filter(|e| matches!(e, Event::Refused { .. }))
        .count();
    assert_eq!(refused, 1, "the damaged chunk is refused: {events:?}");
    assert_eq!(
        events.last(),
        Some(&Event::Ack {
            command: wire::CommandTag::ModelCommit
        })
    );
    assert_eq!(
        device.device.model().map(|m| m.bytes()),
        Some(&blob[..]),
        "the device holds exactly the host's blob"
    );

    // 3. Live: the device classifies every frame; the host classifies the same frames with the
    //    same blob and must agree; the scripted classes are well apart, so both are right.
    let host_model = Model::parse(&blob).unwrap();
    let mut scratch = vec![0.0; host_model.scratch_len()];
    for class in 0..CLASSES {
        device.sheet.touch = Some(class);
        for _ in 0..5 {
            let (frames, events, _) = host_decode(&mut host, &device.live());
            let [frame] = &frames[..] else {
                panic!("one frame per scan")
            };
            let [
                Event::Touch {
                    seq,
                    class: on_chip,
                    margin,
                },
            ] = events[..]
            else {
                panic!("{events:?}")
            };
            assert_eq!(seq, frame.seq);
            let on_host = host_model.evaluate(&frame.voltages, &mut scratch).unwrap();
            assert_eq!(on_chip, on_host.class, "device and host agree");
            assert_eq!(on_chip, class, "and are right");
            assert!(margin > 0.0 && (margin - on_host.margin).abs() < 1e-3);
        }
    }
}

#[test]
fn a_model_for_another_protocol_is_refused() {
    let mut device = Device::new();
    // A valid blob, but for adjacent frames at L = 8 (K = 40): the device must refuse it.
    let features: Vec<u16> = (0..4).collect();
    let tables = ModelTables {
        kind: ModelKind::Lda,
        precision: Precision::F32,
        referenced: false,
        electrodes: 8,
        protocol: ProtocolKind::Adjacent,
        feature_index: &features,
        mean: &[0.0; 4],
        scale: &[1.0; 4],
        positions_mm: &[[0.0, 0.0]; 2],
        log_prior: &[-0.69; 2],
        constant: &[0.0; 2],
        vectors: &[0.1; 8],
        factors: &[],
    };
    let mut blob = vec![0u8; model_len(ModelKind::Lda, Precision::F32, 2, 4)];
    write_model(&tables, &mut blob).unwrap();
    let mut bytes = packet(&Command::ModelBegin {
        len: blob.len() as u32,
        crc: wire::crc32(&blob),
    });
    bytes.extend(packet(&Command::ModelChunk {
        offset: 0,
        data: heapless::Vec::from_slice(&blob).unwrap(),
    }));
    bytes.extend(packet(&Command::ModelCommit));
    let mut host: Box<Accumulator<PACKET_MAX>> = Box::default();
    let (_, events, _) = host_decode(&mut host, &device.receive(&bytes));
    assert_eq!(
        events.last(),
        Some(&Event::Refused {
            command: wire::CommandTag::ModelCommit,
            reason: wire::Refusal::ModelMismatch
        })
    );
    assert!(device.device.model().is_none());
}
