use et_core::rng::Rng;
use et_recon::onestep::*;
use nalgebra::DMatrix;

/// The factored diagonal equals J^T J's with J = M G made whole, for a column count that
/// is not a multiple of the tile's (the last tile part empty).
#[test]
fn the_factored_diagonal_is_jtjs() {
    let (k, r, t) = (23, 9, 37);
    let mut rng = Rng::new(3);
    let combination: Vec<Vec<(usize, f64)>> = (0..k)
        .map(|i| vec![(i % r, rng.normal()), ((3 * i + 1) % r, rng.normal())])
        .collect();
    let g = DMatrix::from_fn(r, t, |_, _| rng.normal());
    let m = DMatrix::from_fn(k, r, |i, p| {
        combination[i]
            .iter()
            .filter(|(q, _)| *q == p)
            .map(|(_, c)| c)
            .sum::<f64>()
    });
    let j = &m * &g;
    let diag = jtj_diagonal(&combination, &g);
    for (c, d) in diag.iter().enumerate() {
        let whole = j.column(c).norm_squared();
        assert!(
            (d - whole).abs() <= 1e-12 * whole,
            "column {c}: {d} against {whole}"
        );
    }
}
