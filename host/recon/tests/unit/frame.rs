use et_core::sheet::Sheet;
use et_recon::reconstructor::*;

/// The model's own frame of a bump of `scale` x sigma_0 near (3, 2) cm on a 10 cm disc
/// of 16 electrodes (pairs adjacent, drive electrodes measured too), imaged at alpha 0.1:
/// the linearisation's misfit at that image.
fn misfit_at(recon: &mut Reconstructor, scale: f64) -> f64 {
    let sigma0 = recon.imager().background();
    let mesh = recon.imager().forward.mesh().clone();
    let sigma: Vec<f64> = (0..sigma0.len())
        .map(|t| {
            let [x, y] = mesh.centroid(t);
            let r2 = (x - 0.03).powi(2) + (y - 0.02).powi(2);
            sigma0[t] * (1.0 + scale * (-r2 / (2.0 * 0.015f64.powi(2))).exp())
        })
        .collect();
    let schedule = recon.schedule().clone();
    let forward = &recon.imager().forward;
    let f32s = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect::<Vec<f32>>();
    let v0 = f32s(forward.frame(&sigma0, &schedule).unwrap());
    let v = f32s(forward.frame(&sigma, &schedule).unwrap());
    let reference = Reference::from_frames(&[v0]).unwrap();
    let image = recon.image(&v, &reference).unwrap();
    recon.linearisation_misfit(&image).unwrap().unwrap()
}

#[test]
fn the_linearisation_misfit_is_of_second_order() {
    // F(sigma_0 + d) - F(sigma_0) - J d is O(|d|^2) while dV is O(|d|): the misfit's share
    // halves as the change halves, and vanishes with it.
    let sheet = Sheet::disc(0.1, 16);
    let pairs: Vec<(u16, u16)> = (0..16).map(|i| (i, (i + 1) % 16)).collect();
    let schedule = et_core::schedule::Schedule::adjacent_pairs_under(16, &pairs, 1e-3).unwrap();
    let mut recon = Spec {
        mesh: MeshPlan::About {
            triangles: 600,
            refine: Vec::new(),
        },
        alpha: AlphaRule::Fixed(0.1),
        ..Spec::new(sheet, schedule)
    }
    .set_up()
    .unwrap();
    let (large, small) = (misfit_at(&mut recon, 0.4), misfit_at(&mut recon, 0.1));
    assert!(small < 0.05, "at a 10 % bump: {small}");
    let ratio = large / small;
    assert!(
        (2.5..6.0).contains(&ratio),
        "4 times the change, {ratio:.2} times the misfit's share ({large:.4} against {small:.4})"
    );
}
