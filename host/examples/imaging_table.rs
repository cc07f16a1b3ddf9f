//! The speed/accuracy table of imaging: mesh size against forward error, position error (PE)
//! and set-up time; one-step against iterative Gauss-Newton. 22 cm disc, 16 electrodes,
//! adjacent protocol, complete electrode model; the touch is SPEC §7's at x = 0.5 (noiseless
//! frames from the simulator's resistor network, so the reconstruction never sees its own
//! model's data).
//!
//! Run: `cargo run --release -p et-host --example imaging_table`

use std::sync::Arc;
use std::time::Instant;

use et_core::protocol::{Protocol, ProtocolKind};
use et_host::fem::{Electrodes, Forward};
use et_host::mesh::Mesh;
use et_host::recon::{Data, GaussNewton, OneStep, PixelGrid, gauss_newton, regions};
use et_sim::frontend::SimFrontend;
use et_sim::scene::Scene;
use et_sim::sheet::Sheet;
use et_sim::touch::Touch;

fn main() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes");
    let sc = Scene::load(&root.join("disc-ref-x050.toml")).expect("scene");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    let amps = 32e-6;
    let sigma0 = 1.0 / sc.sheet.sheet_resistance;
    let e = &sc.sheet.electrodes;
    let z = vec![e.contact_ohm * e.width; 16];
    let t = &sc.touches[0];
    // Simulator frames.
    let sheet = Arc::new(Sheet::new(&sc.sheet, &[]).expect("sheet"));
    let mut sim = SimFrontend::new(sheet, sc.frontend, 1).expect("sim");
    let v0 = sim.ideal_frame(&protocol, amps);
    sim.set_touches(&[Touch {
        position: t.position,
        radius: t.radius,
        pressure: t.pressure,
    }])
    .expect("touch");
    let dv: Vec<f64> = sim
        .ideal_frame(&protocol, amps)
        .iter()
        .zip(&v0)
        .map(|(a, b)| a - b)
        .collect();
    // The finest mesh's untouched frame is the reference of the forward error.
    let fine = Mesh::with_about(&sc.sheet, 128_000).expect("mesh");
    let n_fine = fine.triangles.len();
    let v_ref = Forward::new(fine, Electrodes::Complete(z.clone()))
        .expect("forward")
        .frame(&vec![sigma0; n_fine], &protocol, amps)
        .expect("frame");
    let scale = v_ref.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let extent = 2.0 * 0.11;
    println!("Reference: {n_fine} triangles.\n");
    println!(
        "| triangles | forward error | set-up (mesh + Jacobian + one-step matrix) | PE one-step | iterative GN, 4 steps: PE, time |"
    );
    println!("| --- | --- | --- | --- | --- |");
    for target in [1_000, 2_000, 4_000, 8_000, 16_000, 32_000] {
        let started = Instant::now();
        let mesh = Mesh::with_about(&sc.sheet, target).expect("mesh");
        let n = mesh.triangles.len();
        let grid = PixelGrid::new(&mesh, 64);
        let fwd = Forward::new(mesh, Electrodes::Complete(z.clone())).expect("forward");
        let sigma = vec![sigma0; n];
        let (v, jac) = fwd.jacobian(&sigma, &protocol, amps).expect("jacobian");
        let r = OneStep::new(&jac, 0.03, 0.5).expect("one-step");
        let setup = started.elapsed().as_secs_f64();
        let err = v
            .iter()
            .zip(&v_ref)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
            / scale;
        let pe = |d: &[f64]| {
            let rois = regions(&grid, &grid.image(d), 0.1);
            rois.first().map_or(1.0, |r| {
                (r.centroid[0] - t.position[0]).hypot(r.centroid[1] - t.position[1]) / extent
            })
        };
        let pe1 = pe(&r.reconstruct(&dv).expect("image"));
        let (pe_it, t_it) = if n <= 8_500 {
            let started = Instant::now();
            let its = gauss_newton(
                &fwd,
                &protocol,
                amps,
                &sigma,
                Data::Difference(&dv),
                GaussNewton {
                    alpha: 0.03,
                    s: 0.5,
                    iterations: 4,
                },
            )
            .expect("gauss-newton");
            let d: Vec<f64> = its[3].0.iter().map(|v| v - sigma0).collect();
            (
                format!("{:.3}", pe(&d)),
                format!("{:.2} s", started.elapsed().as_secs_f64()),
            )
        } else {
            ("-".into(), "-".into())
        };
        println!(
            "| {n} | {:.2} % | {:.3} s | {pe1:.3} | {pe_it}, {t_it} |",
            100.0 * err,
            setup
        );
    }
}
