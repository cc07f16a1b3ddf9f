//! The live pipeline end to end on one core, as a board's frames meet it: each frame's wire
//! bytes decoded (COBS, CRC, postcard: `et_host::link::Decoder`), referenced against V_0,
//! imaged onto the pixels, searched for touches and, when touched, its event written as a
//! JSON line. Frames from the simulator's swipe scene (the 13 x 13 cm sheet, a finger moving
//! across it), encoded once before timing; the pipeline's defaults (`live::Settings`): 16
//! electrodes adjacent (K = 208) and 32 electrodes PP-PP (K = 1 824). divan reports the
//! median time a frame and frames per second.
//!
//! Run: `cargo bench -p et-host --bench live`

use std::sync::LazyLock;

use et_core::ScanConfig;
use et_core::protocol::ProtocolKind;
use et_core::sheet::Sheet;
use et_core::wire::{self, Uplink};
use et_host::link::Decoder;
use et_host::live::{LiveFrame, Processor, Settings, SimSource, Source};
use et_sim::scene::Scene;

fn main() {
    divan::main();
}

/// Frames simulated and encoded per configuration (the pipeline cycles through them).
const FRAMES: usize = 400;

/// The swipe scene's sheet with `electrodes` electrodes scanned by `protocol`, and FRAMES of
/// its frames as wire packets (the first LEAD_FRAMES untouched).
fn packets(electrodes: u8, protocol: ProtocolKind) -> (Sheet, Vec<Vec<u8>>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../sim/scenes/square-13cm-16-swipe.toml"
    );
    let mut scene = Scene::load(std::path::Path::new(path)).expect("scene");
    scene.sheet.physical.electrodes.count = electrodes;
    let sheet = scene.sheet.physical.clone();
    let mut source = Source::Sim(Box::new(SimSource::new(&scene, "swipe").expect("sheet")));
    source
        .configure(ScanConfig {
            electrodes,
            protocol,
            ..ScanConfig::REFERENCE
        })
        .expect("configuration");
    let Source::Sim(sim) = &mut source else {
        unreachable!()
    };
    let mut buffer = vec![0u8; wire::PACKET_MAX];
    let packets = (0..FRAMES)
        .map(|_| {
            let f = sim.next_frame().expect("frame");
            let frame: wire::Frame = wire::Frame {
                seq: f.seq,
                timestamp: et_core::Micros(f.t_us),
                config: f.config,
                flags: f.flags,
                rail_count: 0,
                voltages: heapless::Vec::from_slice(&f.voltages).expect("K_MAX"),
            };
            let n = wire::encode(&Uplink::Frame(frame), &mut buffer).expect("encode");
            buffer[..n].to_vec()
        })
        .collect();
    (sheet, packets)
}

static L16: LazyLock<(Sheet, Vec<Vec<u8>>)> = LazyLock::new(|| packets(16, ProtocolKind::Adjacent));
static L32: LazyLock<(Sheet, Vec<Vec<u8>>)> = LazyLock::new(|| packets(32, ProtocolKind::PpPp));

/// One frame through the whole pipeline, bytes in, event out, for 16 electrodes adjacent
/// (arg 16) and 32 electrodes PP-PP (arg 32).
#[divan::bench(args = [16, 32], sample_count = 200, sample_size = 20)]
fn live_pipeline(bencher: divan::Bencher, electrodes: u8) {
    let (sheet, packets) = if electrodes == 16 { &*L16 } else { &*L32 };
    let mut processor = Processor::new(sheet, Settings::default()).expect("set-up");
    let mut decoder = Decoder::new();
    let (mut messages, mut sink) = (Vec::new(), Vec::<u8>::new());
    let mut next = 0;
    let mut one = |packet: &[u8]| {
        decoder.feed(packet, &mut messages);
        for message in messages.drain(..) {
            if let Uplink::Frame(f) = message {
                let out = processor.process(LiveFrame::from(f)).expect("frame");
                if let Some(event) = out.event {
                    serde_json::to_writer(&mut sink, &event).expect("json");
                    sink.push(b'\n');
                }
            }
        }
        sink.clear();
    };
    // The reference frames, and the reconstruction set up for this configuration.
    for packet in &packets[..SimSource::LEAD_FRAMES as usize] {
        one(packet);
    }
    bencher
        .counter(divan::counter::ItemsCount::new(1usize))
        .bench_local(|| {
            let packet = &packets[SimSource::LEAD_FRAMES as usize + next];
            next = (next + 1) % (packets.len() - SimSource::LEAD_FRAMES as usize);
            one(divan::black_box(packet));
        });
}

/// The first stage alone: a frame's wire bytes decoded into a frame (16 and 32 electrodes).
#[divan::bench(args = [16, 32], sample_count = 200, sample_size = 20)]
fn decode_only(bencher: divan::Bencher, electrodes: u8) {
    let (_, packets) = if electrodes == 16 { &*L16 } else { &*L32 };
    let mut decoder = Decoder::new();
    let mut messages = Vec::new();
    let mut next = 0;
    bencher
        .counter(divan::counter::ItemsCount::new(1usize))
        .bench_local(|| {
            decoder.feed(divan::black_box(&packets[next]), &mut messages);
            next = (next + 1) % packets.len();
            messages.drain(..).count()
        });
}
