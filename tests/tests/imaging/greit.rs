use super::assert_found_exactly;
use et_core::protocol::{Protocol, ProtocolKind};
use et_recon::fem::TransferJacobian;
use et_recon::greit::*;
use et_recon::imager::Imager;
use et_recon::mesh::Mesh;
use et_recon::metrics::merit;
use et_recon::onestep::imaging_variance;
use et_recon::touches::{PROMINENCE, TOUCH_Z, above_noise, default_threshold, touches};
use et_recon::{PixelGrid, ReconError};
use et_sim::scene::Scene;
use nalgebra::{DMatrix, DVector};

use super::{scene, sim_frames};

/// Noiseless simulator frames: dV of the scene's touches.
fn sim_dv(sc: &Scene, protocol: &Protocol, amps: f64) -> Vec<f64> {
    let (v0, v1) = sim_frames(sc, protocol, amps);
    v1.iter().zip(&v0).map(|(a, b)| a - b).collect()
}

fn small(kind: ProtocolKind) -> (Imager, TransferJacobian) {
    let sc = scene("disc-ref-x050.toml");
    let mesh = Mesh::with_about(&sc.sheet.physical, 600).unwrap();
    let imager = Imager::new(&sc.sheet.physical, mesh, 24).unwrap();
    let protocol = Protocol::new(kind, 16).unwrap();
    let jac = imager
        .transfer_jacobian(&protocol.schedule(32e-6).unwrap())
        .unwrap();
    (imager, jac)
}

/// GREIT's definition written out densely: D Sigma_x J^T (J Sigma_x J^T + lambda I)^-1,
/// with D from its formula (area_t ramp(d) / (pi r^2)), on the pixels inside.
fn dense_r(imager: &Imager, jac: &TransferJacobian, radius: f64, lambda: f64) -> DMatrix<f64> {
    let mesh = imager.forward.mesh();
    let grid = &imager.grid;
    let t_n = mesh.triangles.len();
    let j = jac.dense();
    let area: Vec<f64> = (0..t_n).map(|t| 0.5 * mesh.double_area(t)).collect();
    let inside: Vec<usize> = (0..grid.triangle.len())
        .filter(|&p| grid.triangle[p].is_some())
        .collect();
    let h = grid.size;
    let ramp = |x: [f64; 2], c: [f64; 2]| {
        ((radius - (x[0] - c[0]).hypot(x[1] - c[1])) / h + 0.5).clamp(0.0, 1.0)
    };
    // Each triangle's ramp summed over the whole lattice of pixel centres (a wide window).
    let reach = (radius / h).ceil() as i64 + 2;
    let norm: Vec<f64> = (0..t_n)
        .map(|t| {
            let c = mesh.centroid(t);
            let i0 = ((c[0] - grid.origin[0]) / h).floor() as i64;
            let j0 = ((c[1] - grid.origin[1]) / h).floor() as i64;
            let mut sum = 0.0;
            for j in j0 - reach..=j0 + reach {
                for i in i0 - reach..=i0 + reach {
                    let x = [
                        grid.origin[0] + (i as f64 + 0.5) * h,
                        grid.origin[1] + (j as f64 + 0.5) * h,
                    ];
                    sum += ramp(x, c) * h * h;
                }
            }
            sum
        })
        .collect();
    let d = DMatrix::from_fn(inside.len(), t_n, |row, t| {
        area[t] * ramp(grid.centre(inside[row]), mesh.centroid(t)) / norm[t]
    });
    let sx_jt = DMatrix::from_fn(t_n, j.nrows(), |t, k| area[t] * j[(k, t)]);
    let mut a = &j * &sx_jt;
    for k in 0..a.nrows() {
        a[(k, k)] += lambda;
    }
    let inv = a.try_inverse().unwrap();
    d * sx_jt * inv
}

/// The factored, spectral computation equals GREIT's formula, for a protocol whose K
/// exceeds r (PP-PP) and one below it (opposite); the image and each pixel's noise too.
#[test]
fn greit_equals_its_dense_formula() {
    for kind in [
        ProtocolKind::Adjacent,
        ProtocolKind::PpPp,
        ProtocolKind::Opposite,
    ] {
        let (imager, jac) = small(kind);
        let g = Greit::new(
            &imager,
            &jac,
            &GreitOptions {
                radius: Some(0.02),
                regularisation: Regularisation::Alpha(0.1),
            },
        )
        .unwrap();
        let r = dense_r(&imager, &jac, g.radius, g.lambda);
        let p = g.projection().dense();
        let top = r.amax();
        let worst = r
            .iter()
            .zip(p.iter())
            .map(|(a, b)| (a - f64::from(*b)).abs())
            .fold(0.0, f64::max);
        println!("{kind:?}: |R - dense| {:.2e} of max {top:.3e}", worst / top);
        // The tall factor is stored in 16-bit fixed point per row: within 1e-4 of the largest.
        assert!(worst < 1e-4 * top, "{kind:?}: {worst} against {top}");
        // A frame and the noise of each pixel against R dv and sqrt(sum_k R_pk^2 var_k).
        let k = jac.combination.len();
        let dv: Vec<f64> = (0..k)
            .map(|i| ((i * 37 % 11) as f64 - 5.0) * 1e-4)
            .collect();
        let var: Vec<f64> = (0..k).map(|i| 1e-8 * (1.0 + (i % 5) as f64)).collect();
        let want = &r * DVector::from_column_slice(&dv);
        let got: Vec<f64> = g.image(&dv).unwrap().into_iter().flatten().collect();
        let sd: Vec<f64> = g.noise_sd(&var).unwrap().into_iter().flatten().collect();
        for (row, (a, b)) in want.iter().zip(&got).enumerate() {
            // The image is applied through the packed thin factors: within 1e-4 of its peak.
            assert!((a - b).abs() <= 1e-4 * want.amax(), "{kind:?} pixel {row}");
            let s: f64 = (0..k)
                .map(|c| r[(row, c)].powi(2) * var[c])
                .sum::<f64>()
                .sqrt();
            // The noise figure's search asked for these rows already, so they come from R's
            // squared rows in f32 (`NoiseRows`): within f32's relative precision.
            assert!(
                (s - sd[row]).abs() <= 1e-6 * s.max(1e-300),
                "{kind:?} sd {row}: {} against {s}",
                sd[row]
            );
        }
    }
}

/// The noise figure asked for is the one met, by its definition (SNR_in / SNR_out of a
/// centred target under white noise, computed here from the dense R), and it falls as
/// lambda grows.
#[test]
fn the_noise_figure_asked_for_is_met() {
    let (imager, jac) = small(ProtocolKind::Adjacent);
    let mesh = imager.forward.mesh();
    let mut last_lambda = 0.0;
    for nf in [1.0, 0.5, 0.3] {
        let options = GreitOptions {
            radius: None,
            regularisation: Regularisation::NoiseFigure(nf),
        };
        let g = Greit::new(&imager, &jac, &options).unwrap();
        let r = dense_r(&imager, &jac, g.radius, g.lambda);
        // The target: triangles within the radius of the centre of area.
        let t_n = mesh.triangles.len();
        let area: Vec<f64> = (0..t_n).map(|t| 0.5 * mesh.double_area(t)).collect();
        let total: f64 = area.iter().sum();
        let mut centre = [0.0; 2];
        for t in 0..t_n {
            let c = mesh.centroid(t);
            centre[0] += c[0] * area[t] / total;
            centre[1] += c[1] * area[t] / total;
        }
        let x = DVector::from_fn(t_n, |t, _| {
            let c = mesh.centroid(t);
            f64::from(u8::from(
                (c[0] - centre[0]).hypot(c[1] - centre[1]) <= g.radius,
            ))
        });
        let h = jac.dense() * x;
        // EIDORS' calc_noise_figure: SNR_z = sum z^2 / tr(Sigma_n), SNR_x = sum x^2 /
        // tr(R Sigma_n R^T), pixels of equal area, Sigma_n = I.
        let img = &r * &h;
        let snr_in = h.norm_squared() / h.len() as f64;
        let snr_out = img.norm_squared() / r.norm_squared();
        let measured = snr_in / snr_out;
        println!(
            "NF {nf}: alpha {:.3e}, met {:.4}, by definition {measured:.4}",
            g.alpha, g.noise_figure
        );
        assert!(
            (g.noise_figure - nf).abs() < 1e-3 * nf,
            "{}",
            g.noise_figure
        );
        assert!((measured - g.noise_figure).abs() < 1e-9 * nf, "{measured}");
        assert!(
            g.lambda > last_lambda,
            "a smaller noise figure needs a larger lambda"
        );
        last_lambda = g.lambda;
    }
}

/// Noise-free frames of the simulator's resistor network: GREIT's image at the consensus
/// noise figure finds exactly the true touches, each within its radius.
#[test]
fn greit_finds_exactly_the_true_touches_on_noise_free_frames() {
    for (name, kind) in [
        ("disc-ref-x000.toml", ProtocolKind::Adjacent),
        ("disc-ref-x050.toml", ProtocolKind::Adjacent),
        ("disc-ref-x075.toml", ProtocolKind::Adjacent),
        ("disc-ref-two.toml", ProtocolKind::PpPp),
    ] {
        let sc = scene(name);
        let protocol = Protocol::new(kind, 16).unwrap();
        let dv = sim_dv(&sc, &protocol, 32e-6);
        let mesh = Mesh::with_about(&sc.sheet.physical, 3_000).unwrap();
        let imager = Imager::new(&sc.sheet.physical, mesh, 64).unwrap();
        let jac = imager
            .transfer_jacobian(&protocol.schedule(32e-6).unwrap())
            .unwrap();
        let g = Greit::new(&imager, &jac, &GreitOptions::default()).unwrap();
        let var = imaging_variance(&vec![0.0; dv.len()], &dv);
        let image = g.image(&dv).unwrap();
        let sd = g.noise_sd(&var).unwrap();
        let found = above_noise(
            &touches(
                &imager.grid,
                &image,
                &sd,
                default_threshold(kind),
                PROMINENCE,
            ),
            TOUCH_Z,
        );
        let truth: Vec<([f64; 2], f64)> =
            sc.touches.iter().map(|t| (t.position, t.radius)).collect();
        let at: Vec<[f64; 2]> = found.iter().map(|r| r.centroid).collect();
        println!("{name}: alpha {:.3e}, touches at {at:.4?}", g.alpha);
        assert_found_exactly(name, &imager.grid, &found, &truth);
    }
}

#[test]
fn bad_settings_and_frames_are_refused() {
    let (imager, jac) = small(ProtocolKind::Adjacent);
    for options in [
        GreitOptions {
            radius: Some(0.0),
            ..GreitOptions::default()
        },
        GreitOptions {
            radius: Some(f64::NAN),
            ..GreitOptions::default()
        },
        GreitOptions {
            radius: None,
            regularisation: Regularisation::NoiseFigure(-1.0),
        },
        GreitOptions {
            radius: None,
            regularisation: Regularisation::Alpha(f64::INFINITY),
        },
    ] {
        assert!(
            matches!(
                Greit::new(&imager, &jac, &options),
                Err(ReconError::OutOfRange { .. } | ReconError::RadiusTooLarge { .. })
            ),
            "{options:?}"
        );
    }
    let g = Greit::new(&imager, &jac, &GreitOptions::default()).unwrap();
    let k = g.frame_len();
    assert!(matches!(
        g.image(&vec![0.0; k - 1]),
        Err(ReconError::FrameLength { .. })
    ));
    let mut nan = vec![0.0; k];
    nan[3] = f64::NAN;
    assert_eq!(g.image(&nan), Err(ReconError::NonFinite));
    assert!(matches!(
        g.noise_sd(&[1.0]),
        Err(ReconError::FrameLength { got: 1, .. })
    ));
    // A Jacobian of another mesh.
    let (other, _) = {
        let sc = scene("disc-ref-x050.toml");
        let mesh = Mesh::with_about(&sc.sheet.physical, 300).unwrap();
        (Imager::new(&sc.sheet.physical, mesh, 24).unwrap(), ())
    };
    assert!(matches!(
        Greit::new(&other, &jac, &GreitOptions::default()),
        Err(ReconError::Size { .. })
    ));
}

/// The figures of merit of an ideal image (the target itself, pixelated) are the ideal ones:
/// amplitude 1, no position error, resolution sqrt(target / sheet), no ringing.
#[test]
fn figures_of_merit_of_an_ideal_image() {
    let (imager, _) = small(ProtocolKind::Adjacent);
    let grid = PixelGrid::new(imager.forward.mesh(), 128);
    let (centre, radius, contrast) = ([0.03, -0.02], 0.015, 2.0);
    let image: Vec<Option<f64>> = (0..grid.triangle.len())
        .map(|p| {
            grid.triangle[p].map(|_| {
                let x = grid.centre(p);
                if (x[0] - centre[0]).hypot(x[1] - centre[1]) <= radius {
                    contrast
                } else {
                    0.0
                }
            })
        })
        .collect();
    let area = std::f64::consts::PI * radius * radius;
    let m = merit(&grid, &image, centre, contrast, area).unwrap();
    let sheet = image.iter().flatten().count() as f64 * grid.size * grid.size;
    println!("{m:?}");
    assert!((m.amplitude - 1.0).abs() < 0.03, "{m:?}");
    assert!(m.position_error < 0.5 * grid.size, "{m:?}");
    assert!(
        (m.resolution - (area / sheet).sqrt()).abs() < 0.02 * m.resolution,
        "{m:?}"
    );
    assert!(m.shape_deformation < 0.1 && m.ringing == 0.0, "{m:?}");
    // No positive value: no figures.
    let flat: Vec<Option<f64>> = image.iter().map(|v| v.map(|_| -1.0)).collect();
    assert_eq!(merit(&grid, &flat, centre, contrast, area), None);
}
