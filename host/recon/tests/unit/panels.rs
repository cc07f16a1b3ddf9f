use et_recon::operator::*;

const FULL_SCALE: f64 = i16::MAX as f64;

/// The product against a plain f64 sum of the stored entries, for shapes around the panel
/// width (empty, one row, a partial last panel, several panels), on both paths; and every
/// stored entry within half a step (1 / 65 534 of its row's largest in i16) or f32's
/// rounding of the entry given.
#[test]
fn the_packed_product_is_the_matrix_vector_product_of_the_rounded_matrix() {
    product_of_the_rounded_matrix::<i16>(0.5 / FULL_SCALE);
    product_of_the_rounded_matrix::<f32>(f64::from(f32::EPSILON) / 2.0);
}

fn product_of_the_rounded_matrix<T: Stored>(step: f64) {
    for (rows, cols) in [
        (0, 3),
        (1, 1),
        (5, 0),
        (7, 3),
        (64, 5),
        (65, 17),
        (300, 120),
    ] {
        // Rows of very different sizes, from 1e-30 to 1e30, and one of zeros.
        let size = |i: usize| {
            if i % 11 == 3 {
                0.0
            } else {
                10f64.powi((i % 7) as i32 * 10 - 30)
            }
        };
        let entry = |i: usize, j: usize| size(i) * (((i * 31 + j * 17) % 23) as f64 / 7.0 - 1.5);
        let a = Panels::<T>::from_fn(rows, cols, entry);
        assert_eq!((a.rows(), a.cols()), (rows, cols));
        let x: Vec<f32> = (0..cols).map(|j| (j as f32 * 0.37).sin()).collect();
        let (mut out, mut plain) = (vec![f32::NAN; rows], vec![f32::NAN; rows]);
        a.apply(&x, &mut out);
        a.apply_plain(&x, &mut plain);
        for i in 0..rows {
            let largest = (0..cols).map(|j| entry(i, j).abs()).fold(0.0, f64::max);
            for j in 0..cols {
                let stored = f64::from(a.get(i, j));
                assert!(
                    (stored - entry(i, j)).abs() <= largest * step * (1.0 + 1e-6),
                    "{rows} x {cols}, ({i}, {j}): {stored} for {}",
                    entry(i, j)
                );
            }
            let exact: f64 = (0..cols)
                .map(|j| f64::from(a.get(i, j)) * f64::from(x[j]))
                .sum();
            let scale: f64 = (0..cols)
                .map(|j| (f64::from(a.get(i, j)) * f64::from(x[j])).abs())
                .sum::<f64>();
            for got in [out[i], plain[i]] {
                assert!(
                    (f64::from(got) - exact).abs() <= 1e-6 * scale,
                    "{rows} x {cols}, row {i}: {got} against {exact}"
                );
            }
        }
    }
}

/// A row with a value that is not finite gives NaN, as in floating point; the other rows
/// are unaffected.
#[test]
fn a_row_that_is_not_finite_stays_not_finite() {
    let entry = |i, j| if i == 1 && j == 0 { f64::INFINITY } else { 1.0 };
    let (a, b) = (
        Panels::<i16>::from_fn(3, 2, entry),
        Panels::<f32>::from_fn(3, 2, entry),
    );
    for out in [image_of(&a, &[1.0, 2.0]), image_of(&b, &[1.0, 2.0])] {
        assert!(out[1].is_nan());
        assert_eq!((out[0], out[2]), (3.0, 3.0));
    }
}

fn image_of<T: Stored>(a: &Panels<T>, x: &[f32]) -> Vec<f32> {
    let mut out = vec![0.0; a.rows()];
    a.apply(x, &mut out);
    out
}
