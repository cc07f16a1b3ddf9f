use et_core::protocol::{Protocol, ProtocolKind};
use et_core::rng::Rng;
use et_core::sheet::Sheet;
use et_recon::imager::Imager;
use et_recon::mesh::Mesh;
use et_recon::redundancy::*;
use faer::Mat;

/// A 22 cm disc of 16 electrodes under `kind`: its imager, schedule and redundancy.
fn disc(kind: ProtocolKind) -> (Imager, et_core::schedule::Schedule, Redundancy) {
    let sheet = Sheet::disc(0.11, 16);
    let mesh = Mesh::with_about(&sheet, 600).unwrap();
    let imager = Imager::new(&sheet, mesh, 16).unwrap();
    let schedule = Protocol::new(kind, 16).unwrap().schedule(1e-3).unwrap();
    let jac = imager.transfer_jacobian(&schedule).unwrap();
    let redundancy = Redundancy::of(&jac).unwrap();
    (imager, schedule, redundancy)
}

/// Adjacent drive on L electrodes measures L (L - 3) / 2 independent values (the
/// reciprocal pairs and the frame's sums account for the rest): 104 of 208 for 16.
#[test]
fn adjacent_drive_has_as_many_redundant_values_as_reciprocity_says() {
    let (_, schedule, redundancy) = disc(ProtocolKind::Adjacent);
    assert_eq!(schedule.frame_len(), 208);
    assert_eq!(redundancy.dof(), 208 - 16 * 13 / 2);
}

/// What a conductivity change (the forward model's own, not linearised) or a gain drift
/// makes has no redundant part; white noise's variance is found within its sampling error.
#[test]
fn a_change_has_no_redundant_part_and_white_noise_is_measured() {
    let (imager, schedule, redundancy) = disc(ProtocolKind::Adjacent);
    let sigma0 = imager.background();
    let v0 = imager.forward.frame(&sigma0, &schedule).unwrap();
    let mut touched = sigma0.clone();
    for s in touched.iter_mut().step_by(7) {
        *s *= 3.0;
    }
    let v1 = imager.forward.frame(&touched, &schedule).unwrap();
    let norm2 = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>();
    for dv in [
        v1.iter().zip(&v0).map(|(a, b)| a - b).collect::<Vec<_>>(),
        v0.iter().map(|v| 2e-3 * v).collect(),
    ] {
        let n = redundancy.noise(&dv).unwrap();
        assert!(
            n.variance * n.dof as f64 <= 1e-12 * norm2(&dv),
            "{n:?} for |dv|^2 = {}",
            norm2(&dv)
        );
    }
    let mut rng = Rng::new(3);
    let sd = 1e-5;
    let draws = 40;
    let mut mean = 0.0;
    for _ in 0..draws {
        let dv: Vec<f64> = v1
            .iter()
            .zip(&v0)
            .map(|(a, b)| a - b + sd * rng.normal())
            .collect();
        mean += redundancy.noise(&dv).unwrap().variance / draws as f64;
    }
    // 40 draws of 104 degrees of freedom: the mean's relative sd is sqrt(2 / 4160) = 2 %.
    assert!(
        (mean / (sd * sd) - 1.0).abs() < 0.08,
        "{mean} vs {}",
        sd * sd
    );
}

/// Too little redundancy, a wrong length or a non-finite value: no estimate.
#[test]
fn no_estimate_without_redundancy_or_from_bad_frames() {
    let (_, _, redundancy) = disc(ProtocolKind::Adjacent);
    assert!(redundancy.noise(&[0.0; 207]).is_none());
    let mut dv = vec![1e-3; 208];
    dv[5] = f64::NAN;
    assert!(redundancy.noise(&dv).is_none());
    let few = Redundancy {
        combination: vec![vec![(0, 1.0)]; MIN_REDUNDANCY],
        basis: Mat::from_fn(1, 1, |_, _| 1.0),
    };
    assert_eq!(few.dof(), MIN_REDUNDANCY - 1);
    assert!(few.noise(&[1.0; MIN_REDUNDANCY]).is_none());
}
