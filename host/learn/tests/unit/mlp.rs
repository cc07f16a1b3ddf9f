use et_core::rng::Rng;
use et_learn::mlp::*;
use et_learn::regress::{Target3, target_mean};
use nalgebra::DMatrix;

#[test]
fn tanh_matches_the_library_everywhere_in_f32() {
    let mut worst = 0.0f32;
    for i in -20_000..=20_000 {
        let x = i as f32 * 1e-3;
        worst = worst.max((tanh(x) - x.tanh()).abs());
    }
    // Three ulp near 1.
    assert!(worst < 4e-7, "worst {worst}");
    assert_eq!(tanh(1e30), 1.0);
    assert_eq!(tanh(-1e30), -1.0);
    assert!(tanh(f32::NAN).is_nan());
}

/// Rows of a smooth nonlinear map from 6 features to a position, and the map.
fn smooth(n: usize, seed: u64) -> (DMatrix<f64>, Vec<Target3>) {
    let mut rng = Rng::new(seed);
    let x = DMatrix::from_fn(n, 6, |_, _| 2.0 * rng.uniform() - 1.0);
    let t = (0..n)
        .map(|r| {
            let v = |j: usize| x[(r, j)];
            [
                30.0 * (v(0) + 0.5 * v(1) * v(2)),
                20.0 * (1.5 * v(3)).sin() - 10.0 * v(4),
                5.0 + v(5),
            ]
        })
        .collect();
    (x, t)
}

fn mean_error(p: &[Target3], t: &[Target3]) -> f64 {
    p.iter()
        .zip(t)
        .map(|(p, t)| (p[0] - t[0]).hypot(p[1] - t[1]))
        .sum::<f64>()
        / t.len() as f64
}

#[test]
fn learns_a_smooth_nonlinear_map_far_better_than_the_mean_and_a_line() {
    let (x, t) = smooth(1_500, 3);
    let (xv, tv) = smooth(500, 4);
    for activation in [Activation::Relu, Activation::Tanh] {
        let opts = MlpOptions {
            hidden: vec![64, 32],
            activation,
            l2: 1e-3,
            starts: 1,
            ..MlpOptions::default()
        };
        let m = Mlp::fit(&x, &t, &opts).unwrap();
        let err = mean_error(&m.predict_many(&xv), &tv);
        let mean = target_mean(&t);
        let constant = mean_error(&vec![mean; tv.len()], &tv);
        let line = et_learn::regress::Ridge::fit(&x, &t, 1e-6).unwrap();
        let linear = mean_error(&line.predict_many(&xv), &tv);
        assert!(
            err < 0.25 * linear && err < 0.1 * constant,
            "{activation:?}: {err:.2} mm against a line's {linear:.2} and the mean's {constant:.2}"
        );
        assert!(m.epochs > 5 && m.validation_loss.is_finite());
    }
}

#[test]
fn saved_layers_predict_exactly_as_the_trained_network() {
    let (x, t) = smooth(300, 5);
    let opts = MlpOptions {
        hidden: vec![16, 8],
        max_epochs: 20,
        starts: 2,
        ..MlpOptions::default()
    };
    let m = Mlp::fit(&x, &t, &opts).unwrap();
    let back = Mlp::from_dense(
        m.mean.clone(),
        m.scale.clone(),
        m.target_mean,
        m.target_scale,
        m.activation,
        &m.dense(),
    )
    .unwrap();
    assert_eq!(back.predict_many(&x), m.predict_many(&x));
    assert_eq!(m.cost(), 6 * 16 + 16 * 8 + 8 * 3);
    // A layer that does not chain is refused.
    let mut dense = m.dense();
    dense[1].weights.pop();
    assert!(
        Mlp::from_dense(
            m.mean.clone(),
            m.scale.clone(),
            m.target_mean,
            m.target_scale,
            m.activation,
            &dense
        )
        .is_err()
    );
}

#[test]
fn the_same_seed_trains_the_same_network_and_a_larger_penalty_shrinks_the_weights() {
    let (x, t) = smooth(400, 6);
    let opts = MlpOptions {
        hidden: vec![32],
        max_epochs: 80,
        starts: 1,
        ..MlpOptions::default()
    };
    let a = Mlp::fit(&x, &t, &opts).unwrap();
    let b = Mlp::fit(&x, &t, &opts).unwrap();
    assert_eq!(a.predict_many(&x), b.predict_many(&x));
    let norm = |m: &Mlp| -> f64 {
        m.dense()
            .iter()
            .flat_map(|layer| layer.weights.concat())
            .map(|v| f64::from(v).powi(2))
            .sum()
    };
    let heavy = Mlp::fit(
        &x,
        &t,
        &MlpOptions {
            l2: 30.0,
            patience: 1_000,
            ..opts.clone()
        },
    )
    .unwrap();
    let light = Mlp::fit(
        &x,
        &t,
        &MlpOptions {
            l2: 0.0,
            patience: 1_000,
            ..opts
        },
    )
    .unwrap();
    assert!(
        norm(&heavy) < 0.7 * norm(&light),
        "{} against {}",
        norm(&heavy),
        norm(&light)
    );
}

#[test]
fn bad_shapes_are_refused() {
    let (x, t) = smooth(50, 7);
    for hidden in [vec![], vec![8, 0]] {
        let opts = MlpOptions {
            hidden,
            ..MlpOptions::default()
        };
        assert!(Mlp::fit(&x, &t, &opts).is_err());
    }
    assert!(Mlp::fit(&x, &t[..10], &MlpOptions::default()).is_err());
}
