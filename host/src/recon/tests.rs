use super::*;
use crate::fem::{Electrodes, Forward};
use crate::mesh::{Mesh, MeshSize};
use et_core::protocol::{Protocol, ProtocolKind};
use et_sim::frontend::SimFrontend;
use et_sim::scene::Scene;
use et_sim::sheet::Sheet;
use et_sim::touch::Touch;
use std::sync::Arc;

fn scene(name: &str) -> Scene {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../sim/scenes");
    Scene::load(&root.join(name)).unwrap()
}

/// Noiseless simulator frames (resistor network, not these finite elements) without and with
/// the scene's touches.
fn sim_frames(sc: &Scene, protocol: &Protocol, amps: f64) -> (Vec<f64>, Vec<f64>) {
    let sheet = Arc::new(Sheet::new(&sc.sheet, &[]).unwrap());
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

struct Setup {
    grid: PixelGrid,
    recon: OneStep,
}

fn setup(sc: &Scene, protocol: &Protocol, amps: f64) -> Setup {
    // alpha = 0.1 (this module's normalisation) merges the two PP-PP touches of the
    // reference scene into one central blob; 0.03 and below separates them.
    setup_with(sc, protocol, amps, 0.03, 0.5)
}

fn setup_with(sc: &Scene, protocol: &Protocol, amps: f64, alpha: f64, s: f64) -> Setup {
    let mesh = Mesh::of_sheet(&sc.sheet, MeshSize::for_count(&sc.sheet, 3_000)).unwrap();
    let z =
        vec![sc.sheet.electrodes.contact_ohm * sc.sheet.electrodes.width; mesh.electrodes.len()];
    let grid = PixelGrid::new(&mesh, 32);
    let n = mesh.triangles.len();
    let fwd = Forward::new(mesh, Electrodes::Complete(z)).unwrap();
    let (_, jac) = fwd
        .jacobian(&vec![1.0 / sc.sheet.sheet_resistance; n], protocol, amps)
        .unwrap();
    Setup {
        grid,
        recon: OneStep::new(&jac, alpha, s).unwrap(),
    }
}

#[test]
fn a_single_touch_is_found_within_its_radius() {
    let amps = 32e-6;
    for kind in [ProtocolKind::Adjacent, ProtocolKind::Opposite] {
        let protocol = Protocol::new(kind, 16).unwrap();
        let mut st: Option<Setup> = None;
        for name in [
            "disc-ref-x000.toml",
            "disc-ref-x025.toml",
            "disc-ref-x050.toml",
            "disc-ref-x075.toml",
        ] {
            let sc = scene(name);
            let s = st.get_or_insert_with(|| setup(&sc, &protocol, amps));
            let (v0, v1) = sim_frames(&sc, &protocol, amps);
            let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
            let image = s.grid.image(&s.recon.reconstruct(&dv).unwrap());
            let rois = regions(&s.grid, &image, 0.1);
            let t = &sc.touches[0];
            let c = rois[0].centroid;
            let off = (c[0] - t.position[0]).hypot(c[1] - t.position[1]);
            println!(
                "{kind:?} {name}: ROI centroid {c:.4?}, {:.1} mm from the touch (radius {:.1} mm), {} regions",
                off * 1e3,
                t.radius * 1e3,
                rois.len()
            );
            assert!(
                off < t.radius,
                "{kind:?} {name}: centroid {c:?} is {off} m off"
            );
            let m = metrics(
                &s.grid,
                &image,
                0.1,
                &dv,
                t.position,
                std::f64::consts::PI * t.radius * t.radius,
            );
            assert!(
                m.pe < 0.1 && m.bvc > 0.0 && m.se.is_finite() && m.rng.is_finite(),
                "{m:?}"
            );
        }
    }
}

#[test]
fn two_touches_are_two_regions_with_pp_pp() {
    let sc = scene("disc-ref-two.toml");
    let protocol = Protocol::new(ProtocolKind::PpPp, 16).unwrap();
    let (v0, v1) = sim_frames(&sc, &protocol, 32e-6);
    let s = setup(&sc, &protocol, 32e-6);
    let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
    let image = s.grid.image(&s.recon.reconstruct(&dv).unwrap());
    // SPEC §6: f = 0.05 for PP-PP.
    let rois = regions(&s.grid, &image, 0.05);
    println!("PP-PP, two touches: {rois:?}");
    assert!(rois.len() >= 2, "{rois:?}");
    // The two strongest regions sit one on each touch.
    for t in &sc.touches {
        let near = rois[..2].iter().any(|r| {
            (r.centroid[0] - t.position[0]).hypot(r.centroid[1] - t.position[1]) < t.radius
        });
        assert!(near, "no region on the touch at {:?}: {rois:?}", t.position);
    }
}

#[test]
fn parameters_and_frames_are_checked() {
    let jac = DMatrix::from_fn(4, 6, |r, c| {
        ((r + 2 * c) as f64).sin() + if r == c { 2.0 } else { 0.0 }
    });
    for (alpha, s) in [(0.0, 0.5), (f64::NAN, 0.5), (1.0, 1.5), (1.0, -0.1)] {
        assert!(matches!(
            OneStep::new(&jac, alpha, s),
            Err(ReconError::Parameter(_))
        ));
    }
    assert_eq!(
        OneStep::new(&DMatrix::zeros(4, 6), 1.0, 0.5).unwrap_err(),
        ReconError::Singular
    );
    // Alpha from 1e-8 to 1e4: finite matrices.
    for alpha in [1e-8, 1e-3, 1.0, 1e4] {
        let r = OneStep::new(&jac, alpha, 1.0).unwrap();
        assert!(r.matrix.iter().all(|v| v.is_finite()), "alpha {alpha}");
        let d = r.reconstruct(&[1.0, -1.0, 0.5, 0.0]).unwrap();
        assert!(d.iter().all(|v| v.is_finite()));
    }
    let r = OneStep::new(&jac, 0.5, 0.5).unwrap();
    assert!(matches!(
        r.reconstruct(&[1.0; 3]),
        Err(ReconError::Parameter(_))
    ));
    assert_eq!(
        r.reconstruct(&[1.0, f64::NAN, 0.0, 0.0]),
        Err(ReconError::NonFinite)
    );
    // Small alpha approaches the minimum-norm solution: J R dv = dv for K < T.
    let r = OneStep::new(&jac, 1e-6, 0.0).unwrap();
    let dv = [0.3, -0.2, 0.1, 0.4];
    let back = &jac * DVector::from_vec(r.reconstruct(&dv).unwrap());
    for (a, b) in back.iter().zip(dv) {
        assert!((a - b).abs() < 1e-6, "{a} vs {b}");
    }
}

#[test]
fn gcv_prefers_little_regularisation_for_clean_data_and_much_for_noise() {
    let mut rng = et_sim::rng::Rng::new(4);
    let (k, t) = (30, 80);
    // A smoothing operator: singular values decaying like a tomography Jacobian's.
    let jac = DMatrix::from_fn(k, t, |r, c| {
        let (x, y) = (r as f64 / k as f64, c as f64 / t as f64);
        (-(x - y).powi(2) * 40.0).exp() * (1.0 + 0.1 * rng.normal())
    });
    let truth = DVector::from_fn(t, |c, _| if (30..40).contains(&c) { 1.0 } else { 0.0 });
    let clean: Vec<f64> = (&jac * &truth).iter().copied().collect();
    let candidates: Vec<f64> = (0..=20)
        .map(|i| 10f64.powf(-5.0 + 0.3 * f64::from(i)))
        .collect();
    let (a_clean, _) = gcv_alpha(&jac, 0.5, &clean, &candidates).unwrap();
    let noise: Vec<f64> = (0..k).map(|_| rng.normal()).collect();
    let (a_noise, scores) = gcv_alpha(&jac, 0.5, &noise, &candidates).unwrap();
    assert!(
        a_clean < a_noise,
        "clean {a_clean}, noise {a_noise}: {scores:?}"
    );
    assert_eq!(a_noise, *candidates.last().unwrap(), "{scores:?}");
    // Mixed: an interior choice.
    let mixed: Vec<f64> = clean.iter().zip(&noise).map(|(c, n)| c + 0.3 * n).collect();
    let (a_mixed, _) = gcv_alpha(&jac, 0.5, &mixed, &candidates).unwrap();
    assert!(
        a_mixed > a_clean && a_mixed < a_noise,
        "{a_clean} {a_mixed} {a_noise}"
    );
    assert!(matches!(
        gcv_alpha(&jac, 0.5, &clean[..5], &candidates),
        Err(ReconError::Parameter(_))
    ));
}

#[test]
fn iterative_gauss_newton_fits_the_data_better_than_one_step() {
    // Data from the simulator's resistor network (not these finite elements).
    let sc = scene("disc-ref-x050.toml");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let amps = 32e-6;
    let (v0, v1) = sim_frames(&sc, &protocol, amps);
    let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
    let mesh = Mesh::with_about(&sc.sheet, 2_000).unwrap();
    let e = &sc.sheet.electrodes;
    let n = mesh.triangles.len();
    let grid = PixelGrid::new(&mesh, 32);
    let fwd = Forward::new(
        mesh,
        Electrodes::Complete(vec![e.contact_ohm * e.width; 16]),
    )
    .unwrap();
    let sigma_0 = vec![1.0 / sc.sheet.sheet_resistance; n];
    let opts = GaussNewton {
        alpha: 0.03,
        s: 0.5,
        iterations: 4,
    };
    let its = gauss_newton(&fwd, &protocol, amps, &sigma_0, Data::Difference(&dv), opts).unwrap();
    let norms: Vec<f64> = its.iter().map(|i| i.1).collect();
    let bvc = dv.iter().map(|v| v * v).sum::<f64>().sqrt();
    println!("residual norms {norms:?} of |dV| = {bvc:.3e}");
    assert!(
        norms[0] < 0.5 * bvc,
        "the first step explains most of dV: {norms:?}"
    );
    assert!(norms[3] < norms[0], "iterating fits better: {norms:?}");
    // The touch is still where it is, and every conductivity finite and positive.
    let last = &its[3].0;
    assert!(last.iter().all(|v| v.is_finite() && *v > 0.0));
    let d: Vec<f64> = last.iter().zip(&sigma_0).map(|(a, b)| a - b).collect();
    let rois = regions(&grid, &grid.image(&d), 0.1);
    let t = &sc.touches[0];
    let off = (rois[0].centroid[0] - t.position[0]).hypot(rois[0].centroid[1] - t.position[1]);
    assert!(off < t.radius, "{:?}", rois[0]);
    let bad = GaussNewton {
        alpha: -1.0,
        ..opts
    };
    assert!(gauss_newton(&fwd, &protocol, amps, &sigma_0, Data::Difference(&dv), bad).is_err());
    assert!(
        gauss_newton(
            &fwd,
            &protocol,
            amps,
            &sigma_0,
            Data::Difference(&dv[..5]),
            opts
        )
        .is_err()
    );
}

#[test]
fn dynamic_selection_on_the_reference_scenes() {
    use crate::dynamic::{Selector, Settings};
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let first = scene("disc-ref-x000.toml");
    let s = setup(&first, &protocol, 32e-6);
    // d_c: the 22 cm disc's centre-to-electrode distance.
    let settings = Settings::new([0.0, 0.0], 0.11);
    for (name, expect) in [
        ("disc-ref-x000.toml", Some(ProtocolKind::PseudoPolar)),
        ("disc-ref-x025.toml", Some(ProtocolKind::PseudoPolar)),
        ("disc-ref-x075.toml", None),
        ("disc-ref-two.toml", Some(ProtocolKind::PpPp)),
    ] {
        let sc = scene(name);
        let (v0, v1) = sim_frames(&sc, &protocol, 32e-6);
        let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let image = s.grid.image(&s.recon.reconstruct(&dv).unwrap());
        let rois = regions(&s.grid, &image, 0.1);
        let mut sel = Selector::new(settings);
        let switched: Vec<ProtocolKind> = (0..3).filter_map(|_| sel.step(&rois)).collect();
        println!("{name}: {} regions, switches {switched:?}", rois.len());
        assert_eq!(switched.first().copied(), expect, "{name}: {rois:?}");
    }
}
