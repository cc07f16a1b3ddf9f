//! Imaging (et-recon) on the simulator's frames: the reconstruction and the simulator share no
//! model (finite elements against a resistor network), so these tests do not commit the
//! inverse crime. Tests of et-recon that need no simulator live beside its code.

mod forward;
mod greit;
mod onestep;

use std::sync::Arc;

use et_core::protocol::Protocol;
use et_sim::frontend::SimFrontend;
use et_sim::scene::Scene;
use et_sim::sheet::SimulatedSheet;
use et_sim::touch::Touch;

/// A scene of `sim/scenes`.
pub(crate) fn scene(name: &str) -> Scene {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes");
    Scene::load(&root.join(name)).unwrap()
}

/// Noiseless simulator frames (its resistor network, not et-recon's finite elements) without
/// and with the scene's touches, V.
pub(crate) fn sim_frames(sc: &Scene, protocol: &Protocol, amps: f64) -> (Vec<f64>, Vec<f64>) {
    let sheet = Arc::new(SimulatedSheet::new(&sc.sheet, &[]).unwrap());
    let mut fe = SimFrontend::new(sheet, sc.frontend, 1).unwrap();
    let v0 = fe.ideal_frame(protocol, amps);
    let touches: Vec<Touch> = sc
        .touches
        .iter()
        .map(et_sim::scene::TouchEvent::touch)
        .collect();
    fe.set_touches(&touches).unwrap();
    (v0, fe.ideal_frame(protocol, amps))
}

/// For tests: `found` holds exactly one touch per true touch (`truth`: centre and radius, m),
/// each true touch matched to a touch of its own, and a found centroid within each true
/// touch's radius. Returns the matches.
pub(crate) fn assert_found_exactly(
    name: &str,
    grid: &et_recon::PixelGrid,
    found: &[et_recon::Region],
    truth: &[([f64; 2], f64)],
) -> Vec<et_recon::TouchMatch> {
    let at: Vec<[f64; 2]> = found.iter().map(|r| r.centroid).collect();
    assert_eq!(found.len(), truth.len(), "{name}: {at:?}");
    let matches = et_recon::match_touches(grid, found, truth);
    let mut which: Vec<usize> = matches.iter().filter_map(|m| m.found).collect();
    which.sort_unstable();
    which.dedup();
    assert_eq!(which.len(), truth.len(), "{name}: {matches:?}");
    for (centre, radius) in truth {
        let near = at
            .iter()
            .map(|c| (c[0] - centre[0]).hypot(c[1] - centre[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(near < *radius, "{name}: {near} from {centre:?}");
    }
    matches
}
