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
        // Trained nearer convergence than the default's early stop, whose tolerance is set
        // for noisy data: this map is noise-free, and its error still falls after it.
        let opts = MlpOptions {
            hidden: vec![64, 32],
            activation,
            l2: 1e-3,
            starts: 1,
            tol: 1e-6,
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

/// The network learns the position alone: a third target, however noisy, leaves the predicted
/// positions exactly as without it (it neither takes the network's capacity nor stops its
/// training), and a third target that follows the position is read off the last hidden layer
/// far better than its mean would guess it.
#[test]
fn the_third_target_neither_steers_nor_stops_the_position() {
    let (x, t) = smooth(800, 5);
    let (xv, tv) = smooth(300, 6);
    let mut rng = Rng::new(9);
    let noisy: Vec<Target3> = t.iter().map(|r| [r[0], r[1], 1e3 * rng.normal()]).collect();
    let follows = |t: &[Target3]| -> Vec<Target3> {
        t.iter()
            .map(|r| [r[0], r[1], 0.5 * r[0] - 0.3 * r[1]])
            .collect()
    };
    let opts = MlpOptions {
        hidden: vec![32, 16],
        starts: 1,
        ..MlpOptions::default()
    };
    let with_noise = Mlp::fit(&x, &noisy, &opts).unwrap().predict_many(&xv);
    let trained = Mlp::fit(&x, &follows(&t), &opts).unwrap();
    let predicted = trained.predict_many(&xv);
    for (a, b) in with_noise.iter().zip(&predicted) {
        assert_eq!((a[0], a[1]), (b[0], b[1]));
    }
    let truth = follows(&tv);
    let mean = target_mean(&follows(&t))[2];
    let third_error = |p: &[Target3]| -> f64 {
        p.iter()
            .zip(&truth)
            .map(|(p, t)| (p[2] - t[2]).abs())
            .sum::<f64>()
            / truth.len() as f64
    };
    let guess = third_error(&vec![[0.0, 0.0, mean]; truth.len()]);
    assert!(
        third_error(&predicted) < 0.2 * guess,
        "third target {:.2} against the mean's {guess:.2}",
        third_error(&predicted)
    );
}
