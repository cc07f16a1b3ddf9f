//! Calibrates the simulated front end's noise to the reference hardware (docs/method.md §3): the
//! adjacent protocol on the 13 x 13 cm, 16-electrode sheet reads about 55 dB SNR and 0.5 mV
//! MAD at 32 uA, and 49 dB and 0.4 mV at 10 uA.
//!
//! Noise model (per sample at the amplifier input): white noise sigma_w, mains hum of
//! amplitude A, and a relative jitter sigma_I of the current from one injection to the next.
//! After the median of the 25 kept samples, a frame value carries
//! sigma_k^2 = (sqrt(pi/2) sigma_w / 5)^2 + A^2 / 2 + (sigma_I V_k)^2: a floor that does not
//! depend on the current, and a part that grows with the signal.
//!
//! The two reference figures cannot both hold for this sheet: at 32 uA a 30 kohm/sq, 13 cm
//! sheet gives adjacent differential voltages whose dB-average is about 17 mV, so 0.5 mV of
//! frame noise means about 30 dB, not 55 dB (55 dB at that noise needs channels 20 times
//! larger). We calibrate to the noise the reference states (MAD 0.5 / 0.4 mV) and report the
//! SNR that follows: the conservative choice, since results on the simulator are then
//! pessimistic rather than flattering. The program grid-searches (sigma_w, sigma_I) with
//! A = 0.3 mV, scoring |dMAD| / 0.05 mV at both currents, and prints the best fit.
//!
//! Run: `cargo run --release -p et-sim --example calibrate`

use std::sync::Arc;

use et_core::ScanConfig;
use et_core::stats::{mad, snr};
use et_sim::frontend::{FrontendSpec, SimFrontend};
use et_sim::sheet::{Sheet, SheetSpec};

const FRAMES: usize = 400;

fn measure(sheet: &Arc<Sheet>, spec: FrontendSpec, current_na: u32) -> (f32, f32) {
    let config = ScanConfig {
        current_na,
        ..ScanConfig::REFERENCE
    };
    let mut fe = SimFrontend::new(sheet.clone(), spec, 42).expect("valid spec");
    let k = config.validate().expect("valid").frame_len();
    let mut frames = Vec::with_capacity(FRAMES * k);
    for _ in 0..FRAMES {
        frames.extend(fe.fast_frame(&config).expect("frame"));
    }
    (
        snr(&frames, k).expect("snr").mean_db,
        mad(&frames, k).expect("mad") * 1e3,
    )
}

fn main() {
    let sheet_spec = SheetSpec::rectangle(0.13, 0.13, 16);
    let sheet = Arc::new(Sheet::new(&sheet_spec, &[]).expect("sheet"));
    let targets = [(32_000, 55.0f32, 0.5f32), (10_000, 49.0, 0.4)];
    let score = |spec: FrontendSpec| -> (f32, Vec<(f32, f32)>) {
        let got: Vec<(f32, f32)> = targets
            .iter()
            .map(|&(i, _, _)| measure(&sheet, spec, i))
            .collect();
        let s = targets
            .iter()
            .zip(&got)
            .map(|(&(_, _, mad_t), &(_, mad_g))| (mad_g - mad_t).abs() / 0.05)
            .sum();
        (s, got)
    };
    let now = FrontendSpec::default();
    let (s, got) = score(now);
    println!(
        "defaults: white {:.2} mV, jitter {:.2} %, mains {:.2} mV -> 32 uA {:.1} dB {:.3} mV, 10 uA {:.1} dB {:.3} mV (score {s:.2})",
        now.white_noise_v * 1e3,
        now.current_noise * 100.0,
        now.mains_v * 1e3,
        got[0].0,
        got[0].1,
        got[1].0,
        got[1].1
    );
    let mut best = (f32::INFINITY, now, got);
    for w in (10..=40).map(|i| f64::from(i) * 0.1e-3) {
        for j in (0..=40).map(|i| f64::from(i) * 0.5e-3) {
            let spec = FrontendSpec {
                white_noise_v: w,
                current_noise: j,
                mains_v: 0.3e-3,
                ..now
            };
            let (s, got) = score(spec);
            if s < best.0 {
                best = (s, spec, got);
            }
        }
    }
    let (s, spec, got) = best;
    println!(
        "best:     white {:.2} mV, jitter {:.2} %, mains {:.2} mV -> 32 uA {:.1} dB {:.3} mV, 10 uA {:.1} dB {:.3} mV (score {s:.2})",
        spec.white_noise_v * 1e3,
        spec.current_noise * 100.0,
        spec.mains_v * 1e3,
        got[0].0,
        got[0].1,
        got[1].0,
        got[1].1
    );
}
