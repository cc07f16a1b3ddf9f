use super::assert_found_exactly;
use et_core::protocol::{Protocol, ProtocolKind};
use et_recon::fem::{Electrodes, Forward};
use et_recon::gauss_newton::*;
use et_recon::gcv::*;
use et_recon::mesh::{Mesh, MeshSize};
use et_recon::metrics::*;
use et_recon::onestep::*;
use et_recon::operator::FrameOperator;
use et_recon::pixels::*;
use et_recon::touches::*;
use et_sim::scene::Scene;
use nalgebra::{DMatrix, DVector};

use super::{scene, sim_frames};

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
    let (grid, jac) = jacobian_on(sc, protocol, amps, 32);
    Setup {
        grid,
        recon: OneStep::new(&jac, alpha, s).unwrap(),
    }
}

/// The scene's sheet meshed to about 3 000 triangles (complete electrode model), a grid
/// `pixels` across, and the dense Jacobian at the background.
fn jacobian_on(
    sc: &Scene,
    protocol: &Protocol,
    amps: f64,
    pixels: usize,
) -> (PixelGrid, DMatrix<f64>) {
    let sheet = &sc.sheet.physical;
    let mesh = Mesh::of_sheet(sheet, MeshSize::for_count(sheet, 3_000)).unwrap();
    let z = vec![sheet.electrodes.contact_ohm * sheet.electrodes.width; mesh.electrodes.len()];
    let grid = PixelGrid::new(&mesh, pixels);
    let n = mesh.triangles.len();
    let fwd = Forward::new(mesh, Electrodes::Complete(z)).unwrap();
    let (_, jac) = fwd
        .jacobian(
            &vec![1.0 / sheet.sheet_resistance; n],
            &protocol.schedule(amps).unwrap(),
        )
        .unwrap();
    (grid, jac)
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
    // docs/method.md §6: f = 0.05 for PP-PP.
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
            Err(ReconError::OutOfRange { .. })
        ));
    }
    assert_eq!(
        OneStep::new(&DMatrix::zeros(4, 6), 1.0, 0.5).unwrap_err(),
        ReconError::Singular
    );
    // Alpha from 1e-8 to 1e4: finite matrices.
    for alpha in [1e-8, 1e-3, 1.0, 1e4] {
        let r = OneStep::new(&jac, alpha, 1.0).unwrap();
        assert!(r.matrix().iter().all(|v| v.is_finite()), "alpha {alpha}");
        let d = r.reconstruct(&[1.0, -1.0, 0.5, 0.0]).unwrap();
        assert!(d.iter().all(|v| v.is_finite()));
    }
    let r = OneStep::new(&jac, 0.5, 0.5).unwrap();
    assert!(matches!(
        r.reconstruct(&[1.0; 3]),
        Err(ReconError::FrameLength { got: 3, k: 4, .. })
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
    let mut rng = et_core::rng::Rng::new(4);
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
        Err(ReconError::FrameLength { got: 5, .. })
    ));
}

/// The touch at x = 0.5 of the 22 cm disc, adjacent protocol at 32 uA: the scene, protocol,
/// current and the simulator's noiseless dV.
fn x050_adjacent() -> (Scene, Protocol, f64, Vec<f64>) {
    let sc = scene("disc-ref-x050.toml");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let amps = 32e-6;
    let (v0, v1) = sim_frames(&sc, &protocol, amps);
    let dv = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
    (sc, protocol, amps, dv)
}

#[test]
fn iterative_gauss_newton_fits_the_data_better_than_one_step() {
    // Data from the simulator's resistor network (not these finite elements).
    let (sc, protocol, amps, dv) = x050_adjacent();
    let mesh = Mesh::with_about(&sc.sheet.physical, 2_000).unwrap();
    let e = &sc.sheet.physical.electrodes;
    let n = mesh.triangles.len();
    let grid = PixelGrid::new(&mesh, 32);
    let fwd = Forward::new(
        mesh,
        Electrodes::Complete(vec![e.contact_ohm * e.width; 16]),
    )
    .unwrap();
    let sigma_0 = vec![1.0 / sc.sheet.physical.sheet_resistance; n];
    let opts = GaussNewton {
        alpha: 0.03,
        s: 0.5,
        iterations: 4,
    };
    let fit = gauss_newton(
        &fwd,
        &protocol.schedule(amps).unwrap(),
        &sigma_0,
        Data::Difference(&dv),
        opts,
        &[],
    )
    .unwrap();
    let its = &fit.iterates;
    let norms: Vec<f64> = its.iter().map(|i| i.residual).collect();
    let bvc = et_core::stats::bvc_dv(&dv);
    println!("residual norms {norms:?} of |dV| = {bvc:.3e}");
    assert!(
        norms[0] < 0.5 * bvc,
        "the first step explains most of dV: {norms:?}"
    );
    assert!(norms[3] < norms[0], "iterating fits better: {norms:?}");
    // The touch is still where it is, and every conductivity finite and positive.
    let last = &its[3].sigma;
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
    assert!(
        gauss_newton(
            &fwd,
            &protocol.schedule(amps).unwrap(),
            &sigma_0,
            Data::Difference(&dv),
            bad,
            &[]
        )
        .is_err()
    );
    assert!(
        gauss_newton(
            &fwd,
            &protocol.schedule(amps).unwrap(),
            &sigma_0,
            Data::Difference(&dv[..5]),
            opts,
            &[]
        )
        .is_err()
    );
}

#[test]
fn dynamic_selection_on_the_reference_scenes() {
    use et_recon::select::{Selector, Settings};
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

/// A `w` x `h` grid of 1 mm pixels (origin at 0) with every pixel on the sheet.
fn plain_grid(w: usize, h: usize) -> PixelGrid {
    PixelGrid {
        width: w,
        height: h,
        origin: [0.0, 0.0],
        size: 1e-3,
        triangle: vec![Some(0); w * h],
    }
}

/// Gaussian bumps (centre in pixels, height, sigma in pixels) plus `ripple` x cos along x.
fn bumps(g: &PixelGrid, list: &[([f64; 2], f64, f64)], ripple: f64) -> Vec<Option<f64>> {
    (0..g.width * g.height)
        .map(|p| {
            let (i, j) = ((p % g.width) as f64, (p / g.width) as f64);
            let v: f64 = list
                .iter()
                .map(|&(c, a, s)| {
                    a * (-((i - c[0]).powi(2) + (j - c[1]).powi(2)) / (2.0 * s * s)).exp()
                })
                .sum();
            Some(v + ripple * (std::f64::consts::TAU * i / 5.0).cos())
        })
        .collect()
}

#[test]
fn touches_split_two_peaks_over_a_high_saddle_and_keep_one_peak_whole() {
    let g = plain_grid(40, 20);
    // Two bumps 10 px apart, sigma 3 px: the saddle is at about half the peaks, far above
    // f max, so the threshold alone sees one region.
    let two = bumps(
        &g,
        &[([15.0, 10.0], 1.0, 3.0), ([25.0, 10.0], 0.9, 3.0)],
        0.0,
    );
    assert_eq!(regions(&g, &two, 0.05).len(), 1);
    let t = touches(&g, &two, &[], 0.05, PROMINENCE);
    assert_eq!(t.len(), 2, "{t:?}");
    for (r, x) in t.iter().zip([15.5e-3, 25.5e-3]) {
        assert!((r.centroid[0] - x).abs() < 1.5e-3, "{t:?}");
        assert!((r.centroid[1] - 10.5e-3).abs() < 0.5e-3, "{t:?}");
    }
    assert!((t[0].peak - 1.0).abs() < 0.01 && (t[1].peak - 0.9).abs() < 0.01);
    // Every pixel of the region of interest goes to one of the two.
    let area: f64 = t.iter().map(|r| r.area).sum();
    assert!((area - regions(&g, &two, 0.05)[0].area).abs() < 1e-12);
    // Closer together the dip is too shallow: one touch.
    let close = bumps(
        &g,
        &[([18.0, 10.0], 1.0, 3.0), ([23.0, 10.0], 0.9, 3.0)],
        0.0,
    );
    assert_eq!(touches(&g, &close, &[], 0.05, PROMINENCE).len(), 1);
    // One peak: the threshold's region (its centroid from the half-peak core, here the
    // same by symmetry).
    let one = bumps(&g, &[([20.0, 10.0], 1.0, 4.0)], 0.0);
    let (t, r) = (
        touches(&g, &one, &[], 0.1, PROMINENCE),
        regions(&g, &one, 0.1),
    );
    assert_eq!(t.len(), 1);
    assert_eq!(
        (t[0].area, t[0].peak, t[0].peak_pixel),
        (r[0].area, r[0].peak, r[0].peak_pixel)
    );
    assert!((0..2).all(|d| (t[0].centroid[d] - r[0].centroid[d]).abs() < 1e-9));
    // One peak with a ripple: the ripple's little peaks on the touch's flank stay part of it
    // (those far out, where the ripple is most of the value, are at most specks).
    let rippled = bumps(&g, &[([20.0, 10.0], 1.0, 4.0)], 0.02);
    let t = touches(&g, &rippled, &[], 0.1, PROMINENCE);
    let strong: Vec<_> = t.iter().filter(|r| r.peak >= 0.5 * t[0].peak).collect();
    assert_eq!(strong.len(), 1, "{t:?}");
    assert!(
        strong[0].area > 0.8 * regions(&g, &one, 0.1)[0].area,
        "{t:?}"
    );
    // Nothing positive, nothing found; missing pixels are skipped.
    assert!(touches(&g, &vec![Some(-1.0); 800], &[], 0.1, PROMINENCE).is_empty());
    let mut holes = two.clone();
    for p in (0..800).step_by(7) {
        holes[p] = None;
    }
    assert!(!touches(&g, &holes, &[], 0.05, PROMINENCE).is_empty());
}

#[test]
fn two_touches_under_noise_are_two_peaks_at_the_alpha_gcv_picks() {
    // The simulator's calibrated noise, V_0 from 10 frames, alpha by GCV: the two touches
    // stand as two peaks above their noise. (On the earlier simulator, 0.5 mV in every frame,
    // GCV's alpha smoothed them into one region above the threshold and only the peaks told
    // them apart; at the calibrated noise the threshold separates them too.)
    let sc = scene("disc-ref-two.toml");
    let config = sc.scan_config().unwrap();
    let protocol = config.validate().unwrap();
    let amps = f64::from(config.current_amps());
    let frames = et_sim::still::scene_frames(&sc, &config, 10).unwrap();
    let dv = frames.dv();
    let (grid, jac) = jacobian_on(&sc, &protocol, amps, 48);
    let candidates: Vec<f64> = (0..=25)
        .map(|i| 10f64.powf(-4.0 + 0.2 * f64::from(i)))
        .collect();
    let (alpha, _) = gcv_alpha(&jac, 0.5, &dv, &candidates).unwrap();
    let recon = OneStep::new(&jac, alpha, 0.5).unwrap();
    let image = grid.image(&recon.reconstruct(&dv).unwrap());
    let sd = grid.image(&recon.noise_sd(&frames.var).unwrap());
    let f = default_threshold(ProtocolKind::PpPp);
    let rois = regions(&grid, &image, f);
    let found = touches(&grid, &image, &sd, f, PROMINENCE);
    let counted = above_noise(&found, TOUCH_Z);
    println!("alpha {alpha}: regions {rois:?}\ntouches {found:?}\nabove noise {counted:?}");
    assert_eq!(
        rois.iter().filter(|r| r.peak >= 0.5 * rois[0].peak).count(),
        2,
        "two strong regions: {rois:?}"
    );
    assert_eq!(counted.len(), 2, "{counted:?}");
    // The other peaks in the image are noise.
    assert!(found.len() > 2, "{found:?}");
    for (c, r) in &frames.truth {
        assert!(
            counted
                .iter()
                .any(|g| (g.centroid[0] - c[0]).hypot(g.centroid[1] - c[1]) < *r),
            "no touch found within {r} m of {c:?}: {counted:?}"
        );
    }
}

#[test]
fn noise_of_an_image_by_hand_and_by_sampling() {
    // (The variance of dV itself is et_core::stats::dv_variance, tested there.)
    // noise_sd: sqrt(sum_k R_tk^2 var_k), and it matches the spread of R n over samples.
    let jac = DMatrix::from_fn(5, 7, |r, c| ((r * 7 + c) as f64 * 0.37).sin() + 0.1);
    let recon = OneStep::new(&jac, 0.3, 0.5).unwrap();
    let var_dv: Vec<f64> = (0..5).map(|k| 1e-6 * (k + 1) as f64).collect();
    let sd = recon.noise_sd(&var_dv).unwrap();
    let m = recon.matrix();
    for t in 0..7 {
        let by_hand: f64 = (0..5)
            .map(|k| m[(t, k)].powi(2) * var_dv[k])
            .sum::<f64>()
            .sqrt();
        assert!((sd[t] - by_hand).abs() <= 1e-12 * by_hand);
    }
    let mut rng = et_core::rng::Rng::new(5);
    let samples = 20_000;
    let mut sum_sq = [0.0; 7];
    for _ in 0..samples {
        let n: Vec<f64> = var_dv.iter().map(|v| v.sqrt() * rng.normal()).collect();
        for (s, x) in sum_sq.iter_mut().zip(recon.reconstruct(&n).unwrap()) {
            *s += x * x / samples as f64;
        }
    }
    for t in 0..7 {
        assert!((sum_sq[t].sqrt() / sd[t] - 1.0).abs() < 0.03, "{t}");
    }
    assert!(recon.noise_sd(&var_dv[..4]).is_err());
    // Some triangles only, in any order, repeated: the same values.
    let some = recon.noise_sd_of(&var_dv, &[6, 2, 2, 0]).unwrap();
    for (s, t) in some.iter().zip([6, 2, 2, 0]) {
        assert!((s - sd[t]).abs() <= 1e-12 * sd[t], "{t}");
    }
    assert!(matches!(
        recon.noise_sd_of(&var_dv, &[7]),
        Err(ReconError::Size { got: 7, .. })
    ));
    // Touches are given their largest value over noise; unknown noise keeps a region.
    let g = plain_grid(4, 1);
    let image = vec![Some(1.0), Some(6.0), Some(1.0), Some(4.0)];
    let sd_img = vec![Some(1.0), Some(2.0), None, Some(0.5)];
    let t = touches(&g, &image, &sd_img, 0.1, PROMINENCE);
    assert_eq!(t.len(), 2, "{t:?}");
    // The peak at 6 has z = 3 there, but its neighbour 1 / 1 is less: z = 3; the peak at 4
    // has z = 8.
    assert_eq!((t[0].z, t[1].z), (Some(3.0), Some(8.0)));
    assert_eq!(above_noise(&t, TOUCH_Z).len(), 1);
    let unknown = touches(&g, &image, &[], 0.1, PROMINENCE);
    assert!(unknown.iter().all(|r| r.z.is_none()));
    assert_eq!(above_noise(&unknown, TOUCH_Z).len(), 2);
}

/// Pixel counts are bounded before anything is allocated (`--pixels 100000` was an
/// allocation abort: 10^10 cells).
#[test]
fn pixel_counts_outside_the_documented_range_are_refused() {
    let sheet = et_core::sheet::Sheet::rectangle(0.13, 0.13, 16);
    let mesh = Mesh::with_about(&sheet, 500).unwrap();
    for pixels in [0, 3, et_recon::imager::MAX_PIXELS + 1, 100_000] {
        let e = et_recon::Imager::new(&sheet, mesh.clone(), pixels).unwrap_err();
        assert!(
            matches!(&e, et_recon::fem::FemError::Pixels { pixels: p, .. } if *p == pixels)
                && e.to_string().contains("4 to 512"),
            "{pixels}: {e}"
        );
    }
    assert!(et_recon::Imager::new(&sheet, mesh, 4).is_ok());
}

/// The data-space matrix (BLAS-3, Cholesky of the K x K system) equals the primal form
/// (J^T J + lambda P)^-1 J^T solved in the T x T space, and GCV from A's eigendecomposition
/// equals K |(I - J R) dv|^2 / tr(I - J R)^2 computed from that matrix.
#[test]
fn the_data_space_matrix_equals_the_primal_form_and_gcv_its_definition() {
    let mut rng = et_core::rng::Rng::new(11);
    let (k, t) = (23, 57);
    let jac = DMatrix::from_fn(k, t, |r, c| {
        (-(r as f64 / k as f64 - c as f64 / t as f64).powi(2) * 20.0).exp() + 0.05 * rng.normal()
    });
    let dv: Vec<f64> = (0..k).map(|_| rng.normal()).collect();
    for (alpha, s) in [(0.01, 0.5), (0.3, 1.0), (2.0, 0.0)] {
        let space = DataSpace::new(&jac, s).unwrap();
        let r = space.one_step(alpha).unwrap().matrix();
        let p = DVector::from_fn(t, |c, _| jac.column(c).norm_squared().powf(s));
        let a = jac.transpose() * &jac;
        let trace: f64 = (0..t).map(|c| jac.column(c).norm_squared() / p[c]).sum();
        let lambda = alpha * alpha * trace / k as f64;
        let primal = (a + DMatrix::from_diagonal(&(p * lambda)))
            .cholesky()
            .unwrap()
            .solve(&jac.transpose());
        let scale = primal.amax();
        assert!(
            (&r - &primal).amax() < 1e-9 * scale,
            "alpha {alpha}, s {s}: {:e}",
            (&r - &primal).amax() / scale
        );
        let influence = DMatrix::identity(k, k) - &jac * &r;
        let res = &influence * DVector::from_column_slice(&dv);
        let by_definition = k as f64 * res.norm_squared() / influence.trace().powi(2);
        let (_, scores) = space.gcv(&dv, &[alpha]).unwrap();
        assert!(
            (scores[0].1 - by_definition).abs() < 1e-9 * by_definition,
            "{} vs {by_definition}",
            scores[0].1
        );
    }
}

/// Too little regularisation (alpha 1e-6) made full Gauss-Newton steps diverge (residual
/// 1.05e2 V against |dV| = 7e-3 V after 5 iterations): the line search keeps every iterate's
/// objective below the one before, so the residual stays below |dV|; every iterate carries
/// its noise, so touches can be scored.
#[test]
fn iterative_gauss_newton_does_not_diverge_and_scores_its_noise() {
    let (sc, protocol, amps, dv) = x050_adjacent();
    let mesh = Mesh::with_about(&sc.sheet.physical, 2_000).unwrap();
    let n = mesh.triangles.len();
    let fwd = Forward::new(mesh, Electrodes::of_sheet(&sc.sheet.physical).unwrap()).unwrap();
    let sigma_0 = vec![1.0 / sc.sheet.physical.sheet_resistance; n];
    let bvc = et_core::stats::bvc_dv(&dv);
    let var = vec![(1e-3 * bvc).powi(2) / dv.len() as f64; dv.len()];
    for alpha in [1e-6, 0.03] {
        let opts = GaussNewton {
            alpha,
            s: 0.5,
            iterations: 5,
        };
        let fit = gauss_newton(
            &fwd,
            &protocol.schedule(amps).unwrap(),
            &sigma_0,
            Data::Difference(&dv),
            opts,
            &var,
        )
        .unwrap();
        let summary: Vec<(f64, f64, f64)> = fit
            .iterates
            .iter()
            .map(|i| (i.residual, i.objective, i.step))
            .collect();
        println!(
            "alpha {alpha}: (residual, objective, step) {summary:?}, {:?}",
            fit.stop
        );
        assert!(!fit.iterates.is_empty());
        for w in fit.iterates.windows(2) {
            assert!(w[1].objective < w[0].objective, "{summary:?}");
        }
        for i in &fit.iterates {
            assert!(i.residual < bvc, "{summary:?} against |dV| = {bvc:e}");
            assert_eq!(i.noise_sd.len(), n);
            assert!(i.noise_sd.iter().all(|v| v.is_finite() && *v > 0.0));
            assert!(i.sigma.iter().all(|v| v.is_finite() && *v > 0.0));
        }
    }
}

/// Frames without noise (the simulator's resistor network, noiseless): GCV alone runs to the
/// smallest alpha and the model's mismatch images into a ring of spurious peaks; with the
/// model's error counted as noise (`imaging_variance`) and the discrepancy floor
/// (`choose_alpha`), exactly the true touches are found, each within its radius.
#[test]
fn noise_free_frames_find_exactly_the_true_touches() {
    for (name, kind) in [
        ("disc-ref-x050.toml", ProtocolKind::Adjacent),
        ("disc-ref-x075.toml", ProtocolKind::Adjacent),
        ("disc-ref-two.toml", ProtocolKind::PpPp),
    ] {
        let sc = scene(name);
        let protocol = Protocol::new(kind, 16).unwrap();
        let amps = 32e-6;
        let (v0, v1) = sim_frames(&sc, &protocol, amps);
        let dv: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let mesh = Mesh::with_about(&sc.sheet.physical, 4_000).unwrap();
        let grid = PixelGrid::new(&mesh, 64);
        let n = mesh.triangles.len();
        let fwd = Forward::new(mesh, Electrodes::of_sheet(&sc.sheet.physical).unwrap()).unwrap();
        let (_, jac) = fwd
            .jacobian(
                &vec![1.0 / sc.sheet.physical.sheet_resistance; n],
                &protocol.schedule(amps).unwrap(),
            )
            .unwrap();
        let space = DataSpace::new(&jac, 0.5).unwrap();
        let var = imaging_variance(&vec![0.0; dv.len()], &dv);
        let alpha = space
            .choose_alpha(&dv, &var, &et_recon::gcv::default_alphas())
            .unwrap();
        let (gcv_only, _) = space.gcv(&dv, &et_recon::gcv::default_alphas()).unwrap();
        let recon = space.one_step(alpha).unwrap();
        let image = grid.image(&recon.reconstruct(&dv).unwrap());
        let sd = grid.image(&recon.noise_sd(&var).unwrap());
        let f = default_threshold(kind);
        let found = above_noise(&touches(&grid, &image, &sd, f, PROMINENCE), TOUCH_Z);
        let at: Vec<[f64; 2]> = found.iter().map(|r| r.centroid).collect();
        println!("{name}: alpha {alpha:.3} (GCV alone {gcv_only:.1e}), touches at {at:?}");
        // Each true touch matched to its own found touch, PE within the touch's radius.
        let truth: Vec<([f64; 2], f64)> =
            sc.touches.iter().map(|t| (t.position, t.radius)).collect();
        let matches = assert_found_exactly(name, &grid, &found, &truth);
        let extent = grid.width.max(grid.height) as f64 * grid.size;
        for (m, t) in matches.iter().zip(&sc.touches) {
            // (SE is not bounded here: the one-step image is blurred, and a touch split off
            // a region keeps its half of the region.)
            assert!(
                m.pe * extent < t.radius && (0.0..=1.0).contains(&m.se),
                "{name}: {m:?}"
            );
        }
    }
}

/// The factored data space (J = M G over the transfer impedances) gives the same one-step
/// matrix, noise and GCV as the dense Jacobian, for complete and point electrodes and a
/// protocol whose K exceeds r (PP-PP) and one whose K is below it (opposite at L = 8).
#[test]
fn the_factored_data_space_equals_the_dense_one() {
    use et_core::sheet::ElectrodeModel;
    for (model, kind) in [
        (ElectrodeModel::Complete, ProtocolKind::Adjacent),
        (ElectrodeModel::Complete, ProtocolKind::PpPp),
        (ElectrodeModel::Point, ProtocolKind::Opposite),
    ] {
        let mut spec = et_core::sheet::Sheet::rectangle(0.13, 0.13, 8);
        spec.electrodes.model = model;
        let mesh = Mesh::with_about(&spec, 600).unwrap();
        let n = mesh.triangles.len();
        let fwd = Forward::new(mesh, Electrodes::of_sheet(&spec).unwrap()).unwrap();
        let protocol = Protocol::new(kind, 8).unwrap();
        let sigma: Vec<f64> = (0..n)
            .map(|t| 1e-4 * (1.0 + 0.3 * ((t % 7) as f64)))
            .collect();
        let tj = fwd
            .transfer_jacobian(&sigma, &protocol.schedule(1e-4).unwrap())
            .unwrap();
        assert_eq!(tj.pairs(), 28);
        let dense = tj.dense();
        let frame = fwd
            .frame(&sigma, &protocol.schedule(1e-4).unwrap())
            .unwrap();
        let scale = frame.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in tj.frame.iter().zip(&frame) {
            assert!((a - b).abs() < 1e-10 * scale, "{a} vs {b}");
        }
        let (f, d) = (
            DataSpace::factored(&tj, 0.5).unwrap(),
            DataSpace::new(&dense, 0.5).unwrap(),
        );
        let (rf, rd) = (
            f.one_step(0.05).unwrap().matrix(),
            d.one_step(0.05).unwrap().matrix(),
        );
        let amax = rd.amax();
        assert!(
            (&rf - &rd).amax() < 1e-7 * amax,
            "{kind:?}: {:e}",
            (&rf - &rd).amax() / amax
        );
        let dv: Vec<f64> = (0..frame.len())
            .map(|k| (k as f64 * 0.7).sin() * 1e-5)
            .collect();
        let var = vec![1e-14; frame.len()];
        let (a1, s1) = f.gcv(&dv, &et_recon::gcv::default_alphas()).unwrap();
        let (a2, s2) = d.gcv(&dv, &et_recon::gcv::default_alphas()).unwrap();
        assert_eq!(a1, a2);
        for (x, y) in s1.iter().zip(&s2) {
            assert!((x.1 - y.1).abs() <= 1e-7 * y.1, "{x:?} {y:?}");
        }
        let (nf, nd) = (
            f.one_step(0.05).unwrap().noise_sd(&var).unwrap(),
            d.one_step(0.05).unwrap().noise_sd(&var).unwrap(),
        );
        for (x, y) in nf.iter().zip(&nd) {
            assert!((x - y).abs() <= 1e-7 * y.max(1e-30), "{x} vs {y}");
        }
    }
}

/// The pixel operator's thin factors multiply out to R's pixel rows, keep exactly P's
/// numerical rank (an SVD of the dense rows: K / 2 independent values for adjacent by
/// reciprocity, fewer than r), image a frame as the dense product does, carry each pixel's
/// noise as its definition, and refuse wrong lengths.
#[test]
fn the_pixel_operator_equals_the_dense_pixel_rows_at_their_rank() {
    let mut sc = scene("disc-ref-x050.toml");
    for (kind, electrodes) in [
        (ProtocolKind::Adjacent, 16),
        (ProtocolKind::Opposite, 16),
        // K = 1 824 > 2 r: the operator keeps C' and M^T.
        (ProtocolKind::PpPp, 32),
    ] {
        sc.sheet.physical.electrodes.count = electrodes;
        let r_max = usize::from(electrodes) * (usize::from(electrodes) - 1) / 2;
        let protocol = Protocol::new(kind, electrodes).unwrap();
        let Setup { grid, recon } = setup(&sc, &protocol, 32e-6);
        let op = grid.project(&recon);
        let r = recon.matrix();
        let inside: Vec<usize> = grid.triangle.iter().filter_map(|t| *t).collect();
        let p = DMatrix::from_fn(inside.len(), r.ncols(), |i, k| r[(inside[i], k)]);
        let top = p.amax();
        let dense = op.dense();
        let worst = p
            .iter()
            .zip(dense.iter())
            .map(|(a, b)| (a - f64::from(*b)).abs())
            .fold(0.0, f64::max);
        println!(
            "{kind:?}: the factors multiply out within {:.1e} of the largest entry",
            worst / top
        );
        assert!(worst < 1e-4 * top, "{kind:?}: {worst:e} of {top:e}");
        let sv = p.singular_values();
        let rank = sv.iter().filter(|&&s| s > 1e-7 * sv.max()).count();
        println!(
            "{kind:?}: rank {} of K = {}, r = {r_max}",
            op.rank(),
            p.ncols()
        );
        assert_eq!(op.rank(), rank, "{kind:?}");
        assert!(op.rank() <= r_max && op.rank() < p.ncols(), "{kind:?}");
        // A frame, and the noise of each pixel.
        let k = p.ncols();
        let dv: Vec<f64> = (0..k)
            .map(|i| ((i * 37 % 11) as f64 - 5.0) * 1e-4)
            .collect();
        let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
        let mut out = vec![0.0f32; op.rows()];
        op.apply(&dv32, &mut out).unwrap();
        let want = &p * DVector::from_column_slice(&dv);
        for (a, b) in want.iter().zip(&out) {
            assert!((a - f64::from(*b)).abs() < 1e-4 * want.amax(), "{kind:?}");
        }
        let var: Vec<f64> = (0..k).map(|i| 1e-8 * (1.0 + (i % 5) as f64)).collect();
        let var32: Vec<f32> = var.iter().map(|&v| v as f32).collect();
        let sd = op.noise_sd(&var).unwrap();
        // The same noise a row at a time from the squared rows (the live pipeline's, f32).
        let squares = et_recon::SquaredRows::of(&op);
        for (row, s) in sd.iter().enumerate() {
            let want: f64 = (0..k)
                .map(|c| p[(row, c)].powi(2) * var[c])
                .sum::<f64>()
                .sqrt();
            assert!(
                (s - want).abs() <= 1e-4 * want,
                "{kind:?} pixel {row}: {s} vs {want}"
            );
            let one = squares.sd(row, &var32).unwrap();
            assert!(
                (one - want).abs() <= 1e-4 * want,
                "{kind:?} pixel {row}, squared row: {one} vs {want}"
            );
        }
        assert!(op.apply(&dv32[1..], &mut out).is_err());
        assert!(op.apply(&dv32, &mut out[1..]).is_err());
        assert!(op.noise_sd(&var[1..]).is_err());
        assert_eq!(squares.sd(0, &var32[1..]), None);
        assert_eq!(squares.sd(op.rows(), &var32), None);
    }
}

/// Frames through the packed thin factors (f32 arithmetic, the tall factor stored in 16-bit
/// fixed point per row: what `et reconstruct`, the live pipeline and GREIT apply) against the
/// f64 product of the one-step matrix's factors: within 1e-4 of the image's largest value, onto about 8 000 triangles and onto 64 x 64 pixels, for 16
/// electrodes adjacent (K = 208) and 32 electrodes PP-PP (K = 1 824), on a simulated touch's
/// dV (the simulator's resistor network) and on noise alone.
#[test]
fn frames_are_the_f64_images_within_1e_4_of_their_peak() {
    use et_core::sheet::Sheet;
    for (name, electrodes, kind) in [
        ("disc-ref-x050.toml", 16, ProtocolKind::Adjacent),
        ("disc-ref-two.toml", 32, ProtocolKind::PpPp),
    ] {
        let mut sc = scene(name);
        sc.sheet.physical.electrodes.count = electrodes;
        let sheet: &Sheet = &sc.sheet.physical;
        let protocol = Protocol::new(kind, electrodes).unwrap();
        let mesh = Mesh::with_about(sheet, 8_000).unwrap();
        let imager = et_recon::Imager::new(sheet, mesh, 64).unwrap();
        let jac = imager
            .transfer_jacobian(&protocol.schedule(32e-6).unwrap())
            .unwrap();
        let r = DataSpace::factored(&jac, 0.5)
            .and_then(|d| d.one_step(0.03))
            .unwrap();
        let (v0, v1) = sim_frames(&sc, &protocol, 32e-6);
        let touch: Vec<f64> = v1.iter().zip(&v0).map(|(a, b)| a - b).collect();
        let scale = touch.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let noise: Vec<f64> = (0..touch.len())
            .map(|k| scale * 1e-2 * (((k * 7919) % 1000) as f64 / 500.0 - 1.0))
            .collect();
        let operators = [
            ("triangles", FrameOperator::of(&r), None),
            (
                "64 x 64 pixels",
                imager.grid.project(&r),
                Some(
                    imager
                        .grid
                        .triangle
                        .iter()
                        .filter_map(|t| *t)
                        .collect::<Vec<_>>(),
                ),
            ),
        ];
        for (what, dv) in [("touch", &touch), ("noise", &noise)] {
            let exact = r.reconstruct(dv).unwrap();
            let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
            for (onto, op, rows) in &operators {
                let mut out = vec![0.0f32; op.rows()];
                op.apply(&dv32, &mut out).unwrap();
                let want: Vec<f64> = match rows {
                    Some(rows) => rows.iter().map(|&t| exact[t]).collect(),
                    None => exact.clone(),
                };
                let peak = want.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                let worst = want
                    .iter()
                    .zip(&out)
                    .map(|(a, b)| (a - f64::from(*b)).abs())
                    .fold(0.0, f64::max);
                println!(
                    "{electrodes} electrodes {kind:?}, {what} onto {onto}: largest error {:.1e} \
                     of the peak (rank {})",
                    worst / peak,
                    op.rank()
                );
                assert!(out.iter().all(|v| v.is_finite()), "{name} {what} {onto}");
                assert!(peak > 0.0 && worst <= 1e-4 * peak, "{name} {what} {onto}");
            }
        }
    }
}
