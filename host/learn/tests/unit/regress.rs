#[test]
fn the_kernel_exponential_matches_the_library_one_to_two_ulp() {
    // Over the whole range a kernel weight takes, with both ends and the underflow edge.
    let mut worst = 0.0f64;
    for i in 0..=200_000 {
        let a = f64::from(i) * 708.0 / 200_000.0;
        let (ours, exact) = (et_learn::regress::exp_neg(a), (-a).exp());
        worst = worst.max((ours - exact).abs() / exact);
    }
    assert!(worst < 4.5e-16, "worst relative error {worst:e}");
    assert_eq!(et_learn::regress::exp_neg(0.0), 1.0);
    assert_eq!(et_learn::regress::exp_neg(709.0), 0.0);
    assert_eq!(et_learn::regress::exp_neg(f64::INFINITY), 0.0);
    assert!(et_learn::regress::exp_neg(f64::NAN).is_nan());
    // Negative arguments (never a kernel weight, but not wrong either).
    let e = et_learn::regress::exp_neg(-3.5);
    assert!((e - 3.5f64.exp()).abs() < 1e-15 * e);
}

use et_learn::fit::{FitError, standardisation};
use et_learn::regress::*;
use nalgebra::DMatrix;

/// A smooth non-linear map from 2-D positions to 6 "voltages", like a sheet's.
fn data(n: usize, seed: u64) -> (DMatrix<f64>, Vec<Target3>) {
    let mut rng = et_core::rng::Rng::new(seed);
    let mut t = Vec::new();
    let x = DMatrix::from_fn(n, 6, |_, _| 0.0);
    let mut x = x;
    for r in 0..n {
        let (a, b, p) = (rng.uniform(), rng.uniform(), 5.0 + 50.0 * rng.uniform());
        t.push([100.0 * a, 100.0 * b, p]);
        let s = p / 55.0;
        let f = [a, b, (a * b), (3.0 * a).sin(), (2.0 * b).cos(), a * a];
        for j in 0..6 {
            x[(r, j)] = s * f[j] + 1e-4 * rng.normal();
        }
    }
    (x, t)
}

#[test]
fn ridge_recovers_a_linear_map_exactly() {
    let mut rng = et_core::rng::Rng::new(5);
    let x = DMatrix::from_fn(200, 4, |_, _| rng.normal());
    let t: Vec<Target3> = (0..200)
        .map(|r| {
            let v = x.row(r);
            [2.0 * v[0] - v[1] + 3.0, v[2] * 0.5, 10.0 + v[3]]
        })
        .collect();
    let m = Ridge::fit(&x, &t, 0.0).unwrap();
    for r in 0..200 {
        let row: Vec<f64> = x.row(r).iter().copied().collect();
        let p = m.predict(&row);
        for k in 0..3 {
            assert!((p[k] - t[r][k]).abs() < 1e-9, "{p:?} {:?}", t[r]);
        }
    }
    assert_eq!(m.cost(), 12);
}

#[test]
fn kernel_ridge_beats_linear_on_a_non_linear_map() {
    let (x, t) = data(1500, 1);
    let (xt, tt) = data(300, 2);
    let rows = |x: &DMatrix<f64>| -> Vec<Vec<f64>> {
        x.row_iter().map(|r| r.iter().copied().collect()).collect()
    };
    let lin = Ridge::fit(&x, &t, 1e-6).unwrap();
    let krr = KernelRidge::fit(&x, &t, 800, 1.0, 1e-3).unwrap();
    let pl: Vec<Target3> = rows(&xt).iter().map(|r| lin.predict(r)).collect();
    let pk: Vec<Target3> = rows(&xt).iter().map(|r| krr.predict(r)).collect();
    let (sl, sk) = (summarise(&pl, &tt, true), summarise(&pk, &tt, true));
    assert!(sk.mean_mm < 0.5 * sl.mean_mm, "kernel {sk:?} linear {sl:?}");
    assert!(sk.pressure_r > 0.9, "{sk:?}");
}

/// The kernel matrix from one product and faer's Cholesky factor give the predictions of
/// the textbook formula (pairwise distances, nalgebra's Cholesky) to 1e-9, and predicting
/// many rows at once equals predicting each.
#[test]
fn kernel_ridge_equals_the_textbook_formula() {
    let (x, t) = data(300, 5);
    let (width, lambda) = (0.5, 1e-3);
    let krr = KernelRidge::fit(&x, &t, 300, width, lambda).unwrap();
    // The textbook: standardise, K_ab = exp(-gamma |z_a - z_b|^2), (K + lambda I) a = t.
    let (mean, scale) = standardisation(&x);
    let z = standardise(&x, &mean, &scale);
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(u, v)| (u - v).powi(2)).sum::<f64>();
    let rows: Vec<Vec<f64>> = z.row_iter().map(|r| r.iter().copied().collect()).collect();
    let mut pairs: Vec<f64> = (0..300)
        .flat_map(|a| ((a + 1)..300).map(move |b| (a, b)))
        .map(|(a, b)| d2(&rows[a], &rows[b]))
        .collect();
    pairs.sort_by(f64::total_cmp);
    let gamma = width / pairs[pairs.len() / 2];
    let k = DMatrix::from_fn(300, 300, |a, b| {
        (-gamma * d2(&rows[a], &rows[b])).exp() + if a == b { lambda } else { 0.0 }
    });
    let mean_t = target_mean(&t);
    let tc = DMatrix::from_fn(300, 3, |r, c| t[r][c] - mean_t[c]);
    let alpha = k.cholesky().unwrap().solve(&tc);
    let (test_x, _) = data(50, 6);
    let many = krr.predict_many(&test_x);
    for (r, row) in test_x.row_iter().enumerate() {
        let v: Vec<f64> = row.iter().copied().collect();
        let zr: Vec<f64> = v
            .iter()
            .enumerate()
            .map(|(j, x)| (x - mean[j]) / scale[j])
            .collect();
        let want: Vec<f64> = (0..3)
            .map(|c| {
                mean_t[c]
                    + (0..300)
                        .map(|i| (-gamma * d2(&zr, &rows[i])).exp() * alpha[(i, c)])
                        .sum::<f64>()
            })
            .collect();
        let one = krr.predict(&v);
        for c in 0..3 {
            let tol = 1e-9 * (1.0 + want[c].abs());
            assert!(
                (one[c] - want[c]).abs() < tol,
                "row {r}: {one:?} vs {want:?}"
            );
            assert!(
                (many[r][c] - one[c]).abs() < tol,
                "row {r}: {:?} vs {one:?}",
                many[r]
            );
        }
    }
}

#[test]
fn intensity_by_class_recovers_each_class_calibration() {
    // Class c: pressure = (1 + c) + 2 u + 0.5 u^2 with u = ln |x|.
    let mut rng = et_core::rng::Rng::new(3);
    let (mut rows, mut y, mut kpa) = (Vec::new(), Vec::new(), Vec::new());
    for r in 0..60 {
        let c = (r % 3) as u16;
        let u: f64 = -6.0 + 2.0 * rng.uniform();
        let dir = [0.6, 0.8];
        rows.extend(dir.iter().map(|d| d * u.exp()));
        y.push(c);
        kpa.push(f64::from(c) + 1.0 + 2.0 * u + 0.5 * u * u);
    }
    let x = DMatrix::from_row_slice(60, 2, &rows);
    let m = IntensityByClass::fit(&x, &y, &kpa, 3).unwrap();
    for (r, &c) in y.iter().enumerate() {
        let row: Vec<f64> = x.row(r).iter().copied().collect();
        assert!((m.predict(&row, c) - kpa[r]).abs() < 1e-6);
    }
    assert!(matches!(
        IntensityByClass::fit(&x, &y[..5], &kpa, 3),
        Err(FitError::Counts {
            what: "labels",
            got: 5,
            ..
        })
    ));
}

#[test]
fn bad_input_is_refused() {
    let x = DMatrix::from_element(3, 2, 1.0);
    assert!(matches!(
        Ridge::fit(&x, &[[0.0; 3]; 2], 0.1),
        Err(FitError::Counts {
            what: "targets",
            got: 2,
            expected: 3,
            ..
        })
    ));
    let mut y = x.clone();
    y[(1, 1)] = f64::NAN;
    assert!(matches!(
        KernelRidge::fit(&y, &[[0.0; 3]; 3], 3, 1.0, 0.1),
        Err(FitError::NonFinite { row: 1, feature: 1 })
    ));
    // Positions in m, summarised in mm.
    let s = summarise(
        &[[0.0, 0.0, 1.0], [0.003, 0.004, 2.0]],
        &[[0.0; 3], [0.0; 3]],
        false,
    );
    assert!((s.mean_mm - 2.5).abs() < 1e-12 && (s.p90_mm - 5.0).abs() < 1e-12);
    assert_eq!(s.pressure_r, 0.0);
}

/// With more features than rows the ridge solves in the dual (an n x n system); its weights
/// are the primal's, (Z^T Z + lambda n I)^-1 Z^T T, computed here the textbook way.
#[test]
fn ridge_on_wide_data_solves_in_the_dual_with_the_primal_weights() {
    let mut rng = et_core::rng::Rng::new(12);
    let (n, p) = (15, 40);
    let x = DMatrix::from_fn(n, p, |_, _| rng.normal());
    let t: Vec<Target3> = (0..n)
        .map(|r| [x[(r, 0)] - 2.0 * x[(r, 5)], x[(r, 7)], 0.5 * x[(r, 3)]])
        .collect();
    let lambda = 0.3;
    let m = Ridge::fit(&x, &t, lambda).unwrap();
    let (mean, scale) = standardisation(&x);
    let z = standardise(&x, &mean, &scale);
    let centre = target_mean(&t);
    let tc = DMatrix::from_fn(n, 3, |r, k| t[r][k] - centre[k]);
    let a = z.transpose() * &z + DMatrix::identity(p, p) * (lambda * n as f64);
    let primal = a.lu().solve(&(z.transpose() * tc)).unwrap();
    let worst = (&m.weights - &primal).abs().max();
    assert!(
        worst < 1e-10 * primal.abs().max(),
        "largest difference {worst:e}"
    );
    // And a path gives each lambda's fit.
    let path = Ridge::fit_path(&x, &t, &[lambda, 10.0]).unwrap();
    assert_eq!(path[0].as_ref().unwrap().weights, m.weights);
    assert!(path[1].is_some());
}
