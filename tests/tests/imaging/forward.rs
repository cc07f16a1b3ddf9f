//! The finite elements against the simulator's resistor network: two independent models of
//! one sheet.

use et_core::protocol::{Protocol, ProtocolKind};
use et_recon::fem::{Electrodes, Forward};
use et_recon::mesh::Mesh;

#[test]
fn finite_elements_and_the_simulators_resistor_network_agree() {
    // Two independent models of the same untouched sheet (scene file): the simulator's
    // resistor network and these finite elements.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes");
    for name in ["disc-22cm-16.toml", "square-13cm-16.toml"] {
        let sc = et_sim::scene::Scene::load(&root.join(name)).unwrap();
        let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
        let sheet =
            std::sync::Arc::new(et_sim::sheet::SimulatedSheet::new(&sc.sheet, &[]).unwrap());
        let sim = et_sim::frontend::SimFrontend::new(sheet, sc.frontend, 1).unwrap();
        let v_sim = sim.ideal_frame(&protocol, 32e-6);
        let mesh = Mesh::with_about(&sc.sheet.physical, 20_000).unwrap();
        let n = mesh.triangles.len();
        let e = &sc.sheet.physical.electrodes;
        let fwd = Forward::new(
            mesh,
            Electrodes::Complete(vec![e.contact_ohm * e.width; 16]),
        )
        .unwrap();
        let v_fem = fwd
            .frame(
                &vec![1.0 / sc.sheet.physical.sheet_resistance; n],
                &protocol.schedule(32e-6).unwrap(),
            )
            .unwrap();
        let scale = v_fem.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let worst = v_fem
            .iter()
            .zip(&v_sim)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        println!(
            "{name}: largest difference {:.2} % of the largest voltage",
            100.0 * worst / scale
        );
        assert!(worst < 0.05 * scale, "{name}: {worst} of {scale}");
    }
}
