//! The resolution trade of the simulated sheet, measured: for the 13 x 13 cm, 16-electrode
//! sheet, each grid spacing's build time, cost per touch update, and difference from the
//! network of half the spacing (whole frame, and the touch's effect dV).
//!
//! Run: `cargo run --release -p et-sim --example resolution`

use std::time::Instant;

use et_core::protocol::{Protocol, ProtocolKind};
use et_sim::sheet::{SheetSpec, SimulatedSheet, Source, build_network, direct_transfer, frame};
use et_sim::touch::{Piezo, Touch};

fn spec(h: Option<f64>) -> SheetSpec {
    let mut spec = SheetSpec {
        resolution: h,
        ..SheetSpec::rectangle(0.13, 0.13, 16)
    };
    spec.physical.electrodes.width = 0.0052;
    spec
}

fn rel(a: &[f64], b: &[f64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum();
    (d / b.iter().map(|y| y * y).sum::<f64>()).sqrt()
}

fn main() {
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("valid");
    let (source, piezo) = (Source::default(), Piezo::default());
    let touch = Touch {
        position: [0.021, -0.013],
        radius: 0.0075,
        pressure: 20e3,
        footprint: Default::default(),
    };
    let default_h = spec(None).default_resolution();
    println!("spacing_mm  nodes  build_s  touch_update_us  frame_err_%  dV_err_%");
    for h in [0.0052, default_h, 0.0022, 0.0019, 0.0016] {
        let frames = |h: f64| {
            let net = build_network(&spec(Some(h)), &[]).expect("network");
            let v0 = frame(
                &direct_transfer(&net, &piezo, &[]).expect("solve"),
                &protocol,
                32e-6,
                &source,
            );
            let v1 = frame(
                &direct_transfer(&net, &piezo, &[touch]).expect("solve"),
                &protocol,
                32e-6,
                &source,
            );
            let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
            (v1, dv)
        };
        let ((v, dv), (v_fine, dv_fine)) = (frames(h), frames(h / 2.0));
        let t = Instant::now();
        let sheet = SimulatedSheet::new(&spec(Some(h)), &[]).expect("sheet");
        let build = t.elapsed().as_secs_f64();
        let t = Instant::now();
        for _ in 0..100 {
            let _ = sheet.transfer(&[touch]).expect("update");
        }
        let update = t.elapsed().as_secs_f64() / 100.0 * 1e6;
        println!(
            "{:10.2}  {:5}  {:7.2}  {:15.0}  {:11.2}  {:8.2}",
            h * 1e3,
            sheet.network().grid.len(),
            build,
            update,
            100.0 * rel(&v, &v_fine),
            100.0 * rel(&dv, &dv_fine)
        );
    }
}
