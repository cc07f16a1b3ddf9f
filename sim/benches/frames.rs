//! How fast the simulator makes frames, on the default 13 x 13 cm, 16-electrode scene
//! (default resolution, adjacent protocol, reference scan settings), single-threaded.
//!
//! Run: `cargo bench -p et-sim --bench frames`

use std::sync::{Arc, LazyLock};

use et_core::rng::Rng;
use et_core::{ScanConfig, Scanner};
use et_sim::frontend::{FrontendSpec, SimFrontend};
use et_sim::scene::Scene;
use et_sim::sheet::SimulatedSheet;
use et_sim::touch::Touch;

fn main() {
    divan::main();
}

static SHEET: LazyLock<Arc<SimulatedSheet>> = LazyLock::new(|| {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/square-13cm-16.toml");
    let scene = Scene::load(std::path::Path::new(path)).expect("default scene");
    Arc::new(SimulatedSheet::new(&scene.sheet, &[]).expect("sheet"))
});

fn frontend() -> SimFrontend {
    SimFrontend::new(SHEET.clone(), FrontendSpec::default(), 7).expect("frontend")
}

/// A random fingertip anywhere on the sheet, 5 to 100 kPa.
fn random_touch(rng: &mut Rng) -> Touch {
    Touch {
        position: [0.11 * (rng.uniform() - 0.5), 0.11 * (rng.uniform() - 0.5)],
        radius: 0.005 + 0.003 * rng.uniform(),
        pressure: 5e3 + 95e3 * rng.uniform(),
        footprint: Default::default(),
    }
}

/// A fresh random touch in every frame: touch update (Woodbury) + fast noisy frame.
#[divan::bench]
fn fresh_touch_every_frame(bencher: divan::Bencher) {
    let mut fe = frontend();
    let mut rng = Rng::new(1);
    bencher.bench_local(|| {
        fe.set_touches(&[random_touch(&mut rng)]).expect("touch");
        fe.fast_frame(&ScanConfig::REFERENCE).expect("frame")
    });
}

/// Noise only: the touch state stays, each frame draws new noise.
#[divan::bench]
fn noise_only_repeat(bencher: divan::Bencher) {
    let mut fe = frontend();
    fe.set_touches(&[Touch {
        position: [0.02, -0.01],
        radius: 0.0075,
        pressure: 20e3,
        footprint: Default::default(),
    }])
    .expect("touch");
    bencher.bench_local(|| fe.fast_frame(&ScanConfig::REFERENCE).expect("frame"));
}

/// Every sample through the real scan engine (10 400 samples per frame), fresh touch each frame.
#[divan::bench]
fn sample_level_fresh_touch(bencher: divan::Bencher) {
    let mut fe = frontend();
    let scanner = Scanner::new(ScanConfig::REFERENCE, &mut fe).expect("scanner");
    let mut rng = Rng::new(2);
    let mut burst = [0u16; 50];
    let mut v = vec![0.0f32; scanner.frame_len()];
    bencher.bench_local(|| {
        fe.set_touches(&[random_touch(&mut rng)]).expect("touch");
        scanner.scan(&mut fe, &mut burst, &mut v).expect("scan");
        v[0]
    });
}

/// The transfer impedance for one touch of radius `r` m (30 kPa, mid-sheet): the fast path's
/// low-rank update for small touches, a fresh solve of the touched network above
/// `et_sim::sheet::FAST_UPDATE_MAX_NODES` nodes under the touch (a palm); the threshold
/// sits where the two cost the same.
#[divan::bench(args = [0.005, 0.0075, 0.01, 0.015, 0.02, 0.03, 0.05])]
fn touch_size(bencher: divan::Bencher, r: f64) {
    let touch = Touch {
        position: [0.0, 0.0],
        radius: r,
        pressure: 30e3,
        footprint: Default::default(),
    };
    bencher.bench_local(|| SHEET.transfer(&[touch]).expect("transfer"));
}
