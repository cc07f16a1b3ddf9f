use et_learn::gp::*;
use et_learn::regress::{KernelRidge, Target3};
use faer::Mat;
use nalgebra::DMatrix;

fn rows(n: usize, p: usize, seed: u64) -> DMatrix<f64> {
    let mut rng = et_core::rng::Rng::new(seed);
    DMatrix::from_fn(n, p, |_, _| rng.normal())
}

#[test]
fn the_likelihood_gradient_matches_finite_differences() {
    let (n, p) = (40, 5);
    let x = rows(n, p, 3);
    let z = Mat::from_fn(n, p, |i, j| x[(i, j)]);
    let u = Mat::from_fn(n, 2, |i, c| (x[(i, c)] * 1.3).sin() + 0.1 * x[(i, 4)]);
    let mut theta: Vec<f64> = (0..p).map(|l| 0.2 * l as f64 - 0.1).collect();
    theta.extend([0.3, -2.5]);
    let (_, g) = nll_and_gradient(&z, &u, &theta).unwrap();
    for i in 0..theta.len() {
        let h = 1e-5;
        let mut up = theta.clone();
        up[i] += h;
        let mut down = theta.clone();
        down[i] -= h;
        let fd = (nll_and_gradient(&z, &u, &up).unwrap().0
            - nll_and_gradient(&z, &u, &down).unwrap().0)
            / (2.0 * h);
        assert!(
            (fd - g[i]).abs() < 1e-6 * fd.abs().max(1.0),
            "θ_{i}: analytic {} vs finite difference {fd}",
            g[i]
        );
    }
}

#[test]
fn an_irrelevant_feature_gets_a_long_length_scale_and_the_fit_beats_isotropic() {
    // The target depends on features 0 and 1 only; 2..6 are noise the isotropic kernel
    // cannot ignore.
    let (n, p) = (300, 6);
    let x = rows(n + 200, p, 11);
    let truth =
        |r: usize| -> Target3 { [20.0 * x[(r, 0)].sin(), 15.0 * (x[(r, 1)] * 0.8).tanh(), 1.0] };
    let train = x.rows(0, n).into_owned();
    let t: Vec<Target3> = (0..n).map(truth).collect();
    let gp = Gp::fit(&train, &t, &GpOptions::default(), &mut |_, _| {}).unwrap();
    let relevant = gp.length_scales[0].max(gp.length_scales[1]);
    let ignored = gp.length_scales[2..]
        .iter()
        .copied()
        .fold(f64::INFINITY, f64::min);
    assert!(
        ignored > 5.0 * relevant,
        "length scales {:?}",
        gp.length_scales
    );
    let test = x.rows(n, 200).into_owned();
    let error = |pred: &[Target3]| {
        pred.iter()
            .enumerate()
            .map(|(i, q)| {
                let r = truth(n + i);
                (q[0] - r[0]).hypot(q[1] - r[1])
            })
            .sum::<f64>()
            / pred.len() as f64
    };
    let iso = KernelRidge::fit(&train, &t, n, 1.0, 1e-3).unwrap();
    let (e_gp, e_iso) = (
        error(&gp.predict_many(&test)),
        error(&iso.predict_many(&test)),
    );
    assert!(e_gp < 0.5 * e_iso, "gp {e_gp} mm vs isotropic {e_iso} mm");
    // The third target (constant) comes back as itself.
    assert!(
        gp.predict_many(&test)
            .iter()
            .all(|q| (q[2] - 1.0).abs() < 1e-6)
    );
}

#[test]
fn minimise_finds_a_box_constrained_quadratic_minimum() {
    // f = Σ c_i (x_i - 2)², with x_0 boxed below 1: the minimum is (1, 2, 2).
    let c = [1.0, 10.0, 100.0];
    let f = |x: &[f64]| {
        let v = x.iter().zip(c).map(|(x, c)| c * (x - 2.0).powi(2)).sum();
        let g = x.iter().zip(c).map(|(x, c)| 2.0 * c * (x - 2.0)).collect();
        Some((v, g))
    };
    let (x, _, _) = minimise(
        f,
        vec![0.0; 3],
        &[-5.0; 3],
        &[1.0, 5.0, 5.0],
        100,
        &mut |_, _| {},
    )
    .unwrap();
    assert!(
        (x[0] - 1.0).abs() < 1e-9 && (x[1] - 2.0).abs() < 1e-6 && (x[2] - 2.0).abs() < 1e-6,
        "{x:?}"
    );
}

#[test]
fn duplicate_rows_and_bad_data_are_refused_or_fitted_never_panic() {
    let x = DMatrix::from_element(10, 3, 1.0);
    let t = vec![[1.0, 2.0, 0.0]; 10];
    // Identical rows: the noise variance keeps K positive definite; the prediction is the
    // (constant) target.
    let gp = Gp::fit(&x, &t, &GpOptions::default(), &mut |_, _| {}).unwrap();
    let p = gp.predict_many(&x);
    assert!(
        p.iter()
            .all(|q| (q[0] - 1.0).abs() < 1e-6 && (q[1] - 2.0).abs() < 1e-6)
    );
    let mut bad = rows(10, 3, 1);
    bad[(4, 1)] = f64::NAN;
    assert!(Gp::fit(&bad, &t, &GpOptions::default(), &mut |_, _| {}).is_err());
    assert!(Gp::fit(&rows(9, 3, 1), &t, &GpOptions::default(), &mut |_, _| {}).is_err());
}
