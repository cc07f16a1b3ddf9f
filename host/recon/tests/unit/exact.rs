use et_recon::exact::*;

/// The series converges as modes are added; current balance and reciprocity hold.
#[test]
fn the_cem_series_converges_and_is_reciprocal() {
    let l = 16;
    let angles: Vec<f64> = (0..l)
        .map(|e| 2.0 * std::f64::consts::PI * e as f64 / l as f64)
        .collect();
    let mut currents = nalgebra::DMatrix::zeros(l, 2);
    currents[(0, 0)] = 1.0;
    currents[(1, 0)] = -1.0;
    currents[(4, 1)] = 1.0;
    currents[(9, 1)] = -1.0;
    let solve = |modes| cem_disc(&angles, 0.1, 0.05, 1.0, 1.0, &currents, modes).unwrap();
    let (u1, u2, u3) = (solve(250), solve(500), solve(1000));
    let d12 = (&u1 - &u2).amax();
    let d23 = (&u2 - &u3).amax();
    println!("CEM series: |U(250) - U(500)| {d12:.2e}, |U(500) - U(1000)| {d23:.2e}");
    assert!(d23 < 0.6 * d12 && d23 < 1e-4 * u3.amax(), "{d12} {d23}");
    // Reciprocity: the potential difference 4 - 9 of pattern 0 equals 0 - 1 of pattern 1.
    let (x, y) = (u3[(4, 0)] - u3[(9, 0)], u3[(0, 1)] - u3[(1, 1)]);
    assert!((x - y).abs() < 1e-9 * x.abs(), "{x} vs {y}");
}
