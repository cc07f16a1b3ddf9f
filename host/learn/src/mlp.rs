//! A multilayer perceptron for positions: a few dense layers, relu or tanh, trained in f32 on
//! the CPU by Adam on mini-batches with an L2 penalty, early stopping on a held-out part of
//! the training rows, and several random starts (the best start by its held-out loss).
//!
//! Inputs are standardised by the training rows' mean and standard deviation, targets (x, y
//! and the third) by theirs; the output layer is linear. The penalty follows scikit-learn's
//! `MLPRegressor` (`alpha`): each mini-batch of B rows adds (l2 / 2B) |W|^2 to half its mean
//! squared error, so `l2` means the same in both.
//!
//! The network learns the position (x, y) only; the third target (a press's depth or
//! pressure, often noisier) is then fitted by ridge regression on the last hidden layer's
//! outputs with the same penalty, as the output layer's third column. Learned together, the
//! third target took the network's capacity and its early stopping: on the stand-in skin
//! the position error rose from 1.26 to 2.74 mm (scikit-learn's `MLPRegressor` likewise, 1.18
//! to 2.52 mm; docs/measurements.md).
//!
//! ```text
//! z = (x - mean) / scale          (p)
//! a_1 = f(z W_1 + b_1)            (h_1)      f = relu or tanh
//! ...
//! t = (a_L W_out + b_out) * t_scale + t_mean   (3)
//! ```

use et_core::rng::Rng;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};
use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::fit::{FitError, standardisation};
use super::regress::{Target3, check, target_mean};

mod train;

use train::{shuffle, train_one};

/// Why saved layers are not a perceptron.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LayersError {
    /// Fewer than a hidden layer and the output layer.
    #[error("a perceptron needs a hidden layer and the output layer")]
    TooFew,
    /// A layer whose weights do not take the layer before's outputs.
    #[error("layer {layer}: {rows} weight rows for {inputs} inputs, or rows not {outputs} long")]
    Chain {
        /// The layer (1-based).
        layer: usize,
        /// Its weight rows.
        rows: usize,
        /// The inputs it must take.
        inputs: usize,
        /// Its outputs (its biases).
        outputs: usize,
    },
    /// A weight or bias that is not finite.
    #[error("layer {layer}: a non-finite weight")]
    NonFinite {
        /// The layer (1-based).
        layer: usize,
    },
    /// An output layer of other than 3 outputs.
    #[error("the output layer has {outputs} outputs, not 3")]
    Outputs {
        /// Its outputs.
        outputs: usize,
    },
    /// A feature or target scale that is not a positive number.
    #[error("a scale that is not a positive number")]
    Scale,
}

/// A hidden layer's nonlinearity.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    /// max(0, v).
    Relu,
    /// tanh(v).
    Tanh,
}

impl Activation {
    /// The name in files and hyperparameters.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Activation::Relu => "relu",
            Activation::Tanh => "tanh",
        }
    }

    fn apply(self, v: f32) -> f32 {
        match self {
            Activation::Relu => v.max(0.0),
            Activation::Tanh => tanh(v),
        }
    }

    /// The derivative at the pre-activation, from the activation's value `a`.
    fn slope(self, a: f32) -> f32 {
        match self {
            Activation::Relu => {
                if a > 0.0 {
                    1.0
                } else {
                    0.0
                }
            }
            Activation::Tanh => 1.0 - a * a,
        }
    }
}

/// tanh in f32 to a few ulp, by a rational function on [-7.9, 7.9] (beyond it tanh is +-1 in
/// f32). Plain arithmetic: the C library's transcendental functions run many times slower
/// once the matrix kernels' AVX code has run in the process (see `regress::exp_neg`).
#[must_use]
pub fn tanh(x: f32) -> f32 {
    // The minimax (13, 6) rational approximation of Eigen's `ptanh_float`.
    const CLAMP: f32 = 7.905_311;
    const A: [f32; 7] = [
        4.893_524_6e-3,
        6.372_619_3e-4,
        1.485_722_4e-5,
        5.122_297e-8,
        -8.604_672e-11,
        2.000_188e-13,
        -2.760_768_5e-16,
    ];
    const B: [f32; 4] = [4.893_525e-3, 2.268_434_6e-3, 1.185_347_1e-4, 1.198_258_4e-6];
    if x.is_nan() {
        return x;
    }
    let x = x.clamp(-CLAMP, CLAMP);
    let x2 = x * x;
    let p = x
        * (A[0] + x2 * (A[1] + x2 * (A[2] + x2 * (A[3] + x2 * (A[4] + x2 * (A[5] + x2 * A[6]))))));
    let q = B[0] + x2 * (B[1] + x2 * (B[2] + x2 * B[3]));
    p / q
}

/// Passes over the rows a fit is taken to run for in [`Mlp::estimate_seconds`]: early
/// stopping ends most fits after a few tens.
pub const TYPICAL_PASSES: f64 = 40.0;

/// How to train.
#[derive(Clone, Debug, PartialEq)]
pub struct MlpOptions {
    /// Widths of the hidden layers (at least one).
    pub hidden: Vec<usize>,
    /// Their nonlinearity.
    pub activation: Activation,
    /// L2 penalty (scikit-learn's `alpha`).
    pub l2: f64,
    /// Adam's step size.
    pub learning_rate: f32,
    /// Rows per mini-batch (fewer when the training rows are fewer).
    pub batch: usize,
    /// Most passes over the training rows.
    pub max_epochs: usize,
    /// Stop after more than this many passes without the held-out loss falling by `tol`.
    pub patience: usize,
    /// The fall of the held-out loss (half the mean squared standardised error) that counts
    /// as progress: 5e-5 is scikit-learn's `tol` of 1e-4 on its R² score, which is 1 - twice
    /// this loss for standardised targets.
    pub tol: f64,
    /// Share of the training rows held out for early stopping.
    pub validation_fraction: f64,
    /// Random starts; the one with the lowest held-out loss is kept.
    pub starts: usize,
    /// Seed of the starts, the hold-out and the batches.
    pub seed: u64,
}

impl Default for MlpOptions {
    /// scikit-learn's `MLPRegressor` defaults where it has them (Adam at 1e-3, batches of 200,
    /// 10 passes' patience at a tolerance of 1e-4 in R², 10 % held out), at most 2 000 passes
    /// (early stopping ends it long before), three hidden layers 300, 50, 20 with relu and an
    /// L2 of 0.1 (what won on measured skins), three starts.
    fn default() -> Self {
        Self {
            hidden: vec![300, 50, 20],
            activation: Activation::Relu,
            l2: 0.1,
            learning_rate: 1e-3,
            batch: 200,
            max_epochs: 2_000,
            patience: 10,
            tol: 5e-5,
            validation_fraction: 0.1,
            starts: 3,
            seed: 1,
        }
    }
}

/// One dense layer: out = in W + b.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Dense {
    /// Rows of W: one per input, each with a weight per output.
    pub weights: Vec<Vec<f32>>,
    /// One per output.
    pub bias: Vec<f32>,
}

/// A trained perceptron.
#[derive(Clone, Debug)]
pub struct Mlp {
    /// Features' training mean and standard deviation (p each): z = (x - mean) / scale.
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
    /// Targets' training mean and standard deviation.
    pub target_mean: Target3,
    pub target_scale: Target3,
    /// The hidden layers' nonlinearity.
    pub activation: Activation,
    /// Hidden layers, then the linear output layer (3 outputs); W as in x out.
    pub(crate) layers: Layers,
    /// Passes over the training rows of the kept start.
    pub epochs: usize,
    /// Its held-out loss (half the mean squared standardised position error), or NaN without a
    /// hold-out.
    pub validation_loss: f64,
}

impl Mlp {
    /// Trains on `x` (n x p, any units) and targets `t`.
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data, no hidden layer, a zero width, or no
    /// start that reached a finite loss.
    pub fn fit(x: &DMatrix<f64>, t: &[Target3], opts: &MlpOptions) -> Result<Self, FitError> {
        check(x, t)?;
        if opts.hidden.is_empty() || opts.hidden.contains(&0) {
            return Err(FitError::HiddenLayers(opts.hidden.clone()));
        }
        let (mean, scale) = standardisation(x);
        let target_mean = target_mean(t);
        let mut target_scale = [1.0; 3];
        let mut varies = [false; 3];
        for (k, s) in target_scale.iter_mut().enumerate() {
            let var = t
                .iter()
                .map(|r| (r[k] - target_mean[k]).powi(2))
                .sum::<f64>()
                / t.len() as f64;
            if var.sqrt() > 1e-12 * target_mean[k].abs().max(1e-300) && var > 0.0 {
                *s = var.sqrt();
                varies[k] = true;
            }
        }
        // The network's outputs: the position's targets that vary (a constant one, as a
        // single target given as (t, 0), would only dilute the held-out loss that stops it).
        let outputs: Vec<usize> = match (0..2).filter(|&k| varies[k]).collect::<Vec<_>>() {
            none if none.is_empty() => vec![0, 1],
            some => some,
        };
        let (n, p) = (x.nrows(), x.ncols());
        let z = Mat::<f32>::from_fn(n, p, |r, j| ((x[(r, j)] - mean[j]) / scale[j]) as f32);
        let y = Mat::<f32>::from_fn(n, outputs.len(), |r, c| {
            let k = outputs.get(c).copied().unwrap_or(0);
            ((t[r][k] - target_mean[k]) / target_scale[k]) as f32
        });
        let mut rng = Rng::new(opts.seed);
        // The held-out rows for early stopping (none with fewer than 20 rows: then every pass
        // runs).
        let mut order: Vec<usize> = (0..n).collect();
        shuffle(&mut order, &mut rng);
        let held = if n >= 20 {
            ((n as f64 * opts.validation_fraction).round() as usize).clamp(1, n / 2)
        } else {
            0
        };
        let (valid, train) = order.split_at(held);
        let mut best: Option<Self> = None;
        for _ in 0..opts.starts.max(1) {
            let mut start_rng = rng.fork();
            let Some((layers, epochs, loss)) =
                train_one(&z, &y, train, valid, p, opts, &mut start_rng)
            else {
                continue;
            };
            if best
                .as_ref()
                .is_none_or(|b| loss < b.validation_loss || b.validation_loss.is_nan())
            {
                best = Some(Self {
                    mean: mean.clone(),
                    scale: scale.clone(),
                    target_mean,
                    target_scale,
                    activation: opts.activation,
                    layers,
                    epochs,
                    validation_loss: loss,
                });
            }
        }
        let mut best = best.ok_or(FitError::Numerics(
            "no start of the perceptron reached a finite loss",
        ))?;
        let third: Vec<f64> = t
            .iter()
            .map(|r| (r[2] - target_mean[2]) / target_scale[2])
            .collect();
        best.fit_third(&z, &outputs, &third, opts.l2);
        Ok(best)
    }

    /// Makes the output layer's three columns: the network's `outputs` (the position's
    /// targets it learned; the other, constant, predicts its mean), then the third target's,
    /// fitted to its standardised values `third` (one per row of `z`) by ridge regression on
    /// the last hidden layer's outputs H (n x h), penalty `l2` as the network's:
    /// (Hc' Hc + l2 I) w = Hc' t with H and t centred, the bias from the means.
    fn fit_third(&mut self, z: &Mat<f32>, outputs: &[usize], third: &[f64], l2: f64) {
        let mut keep = Vec::new();
        forward(&self.layers, self.activation, z.as_ref(), &mut keep);
        let Some(h) = keep.last() else {
            return;
        };
        let (n, width) = (h.nrows(), h.ncols());
        let h_mean: Vec<f64> = (0..width)
            .map(|j| h.col(j).iter().map(|&v| f64::from(v)).sum::<f64>() / n.max(1) as f64)
            .collect();
        let t_mean = third.iter().sum::<f64>() / n.max(1) as f64;
        let hc = DMatrix::from_fn(n, width, |i, j| f64::from(h[(i, j)]) - h_mean[j]);
        let tc = nalgebra::DVector::from_iterator(n, third.iter().map(|v| v - t_mean));
        let mut gram = hc.transpose() * &hc;
        for j in 0..width {
            gram[(j, j)] += l2.max(1e-9);
        }
        let w = gram.cholesky().map_or_else(
            || nalgebra::DVector::zeros(width),
            |c| c.solve(&(hc.transpose() * tc)),
        );
        let bias = t_mean - w.iter().zip(&h_mean).map(|(a, b)| a * b).sum::<f64>();
        if let Some((out, b)) = self.layers.last_mut() {
            let learned = out.clone();
            let column = |k: usize| outputs.iter().position(|&o| o == k);
            *out = Mat::from_fn(width, 3, |i, k| match column(k) {
                Some(c) => learned[(i, c)],
                None if k == 2 => w[i] as f32,
                None => 0.0,
            });
            let learned_bias = std::mem::take(b);
            *b = (0..2)
                .map(|k| {
                    column(k)
                        .and_then(|c| learned_bias.get(c))
                        .copied()
                        .unwrap_or(0.0)
                })
                .chain([bias as f32])
                .collect();
        }
    }

    /// Seconds `fits` fits on rows like `x` (n x p) will take, each of `opts.starts` starts
    /// stopping after [`TYPICAL_PASSES`] passes (early stopping decides: a rough figure, said
    /// as one): a start's set-up and its passes timed apart, from fits of one and of three
    /// passes on as many rows as a batch (the time does not depend on the values).
    #[must_use]
    pub fn estimate_seconds(x: &DMatrix<f64>, opts: &MlpOptions, fits: usize) -> f64 {
        let (n, p) = x.shape();
        let rows = n.clamp(2, opts.batch.max(2));
        let probe = DMatrix::from_fn(rows, p, |i, j| ((i * 31 + j * 17) % 97) as f64 / 97.0);
        let t: Vec<Target3> = (0..rows)
            .map(|i| [(i % 13) as f64, (i % 7) as f64, 0.0])
            .collect();
        let timed = |passes: usize| {
            let one = MlpOptions {
                max_epochs: passes,
                patience: passes,
                starts: 1,
                ..opts.clone()
            };
            let started = std::time::Instant::now();
            let _ = Self::fit(&probe, &t, &one);
            started.elapsed().as_secs_f64()
        };
        let (one, three) = (timed(1), timed(3));
        let pass = ((three - one) / 2.0).max(0.0) * n as f64 / rows as f64;
        let set_up = (one - pass).max(0.0);
        (set_up + pass * TYPICAL_PASSES) * (opts.starts.max(1) * fits) as f64
    }

    /// Predicts every row of `x` (n x p, the training units).
    #[must_use]
    pub fn predict_many(&self, x: &DMatrix<f64>) -> Vec<Target3> {
        let z = Mat::<f32>::from_fn(x.nrows(), x.ncols(), |r, j| {
            let (m, s) = (
                self.mean.get(j).copied().unwrap_or(0.0),
                self.scale.get(j).copied().unwrap_or(1.0),
            );
            ((x[(r, j)] - m) / s) as f32
        });
        let out = forward(&self.layers, self.activation, z.as_ref(), &mut Vec::new());
        (0..x.nrows())
            .map(|r| {
                let mut t = [0.0; 3];
                for (k, v) in t.iter_mut().enumerate() {
                    *v = f64::from(out[(r, k)]) * self.target_scale[k] + self.target_mean[k];
                }
                t
            })
            .collect()
    }

    /// The layers as saved: hidden layers, then the output layer.
    #[must_use]
    pub fn dense(&self) -> Vec<Dense> {
        self.layers
            .iter()
            .map(|(w, b)| Dense {
                weights: (0..w.nrows())
                    .map(|i| (0..w.ncols()).map(|j| w[(i, j)]).collect())
                    .collect(),
                bias: b.clone(),
            })
            .collect()
    }

    /// Rebuilds a perceptron from saved layers (untrusted: a model file's).
    ///
    /// # Errors
    /// [`LayersError`] when the layers do not chain (p inputs, ..., 3 outputs) or hold a
    /// non-finite value.
    #[deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
    pub fn from_dense(
        mean: Vec<f64>,
        scale: Vec<f64>,
        target_mean: Target3,
        target_scale: Target3,
        activation: Activation,
        dense: &[Dense],
    ) -> Result<Self, LayersError> {
        let mut inputs = mean.len();
        let mut layers = Vec::with_capacity(dense.len());
        if dense.len() < 2 {
            return Err(LayersError::TooFew);
        }
        for (l, d) in dense.iter().enumerate() {
            let outputs = d.bias.len();
            if d.weights.len() != inputs
                || d.weights.iter().any(|r| r.len() != outputs)
                || outputs == 0
            {
                return Err(LayersError::Chain {
                    layer: l + 1,
                    rows: d.weights.len(),
                    inputs,
                    outputs,
                });
            }
            if d.weights
                .iter()
                .flatten()
                .chain(&d.bias)
                .any(|v| !v.is_finite())
            {
                return Err(LayersError::NonFinite { layer: l + 1 });
            }
            let w = Mat::from_fn(inputs, outputs, |i, j| {
                d.weights
                    .get(i)
                    .and_then(|r| r.get(j))
                    .copied()
                    .unwrap_or(0.0)
            });
            layers.push((w, d.bias.clone()));
            inputs = outputs;
        }
        if inputs != 3 {
            return Err(LayersError::Outputs { outputs: inputs });
        }
        if target_scale.iter().any(|s| !(s.is_finite() && *s > 0.0))
            || scale.iter().any(|s| !(s.is_finite() && *s > 0.0))
        {
            return Err(LayersError::Scale);
        }
        Ok(Self {
            mean,
            scale,
            target_mean,
            target_scale,
            activation,
            layers,
            epochs: 0,
            validation_loss: f64::NAN,
        })
    }

    /// Multiply-adds per prediction.
    #[must_use]
    pub fn cost(&self) -> usize {
        self.layers.iter().map(|(w, _)| w.nrows() * w.ncols()).sum()
    }
}

/// Each layer's weights (inputs x outputs) and biases.
type Layers = Vec<(Mat<f32>, Vec<f32>)>;

/// The network's output for the rows of `z` (n x 3); `keep` receives every hidden layer's
/// activations (for back-propagation) when it is to be filled.
fn forward(
    layers: &[(Mat<f32>, Vec<f32>)],
    activation: Activation,
    z: MatRef<'_, f32>,
    keep: &mut Vec<Mat<f32>>,
) -> Mat<f32> {
    keep.clear();
    let mut input: Option<Mat<f32>> = None;
    let last = layers.len().saturating_sub(1);
    for (l, (w, b)) in layers.iter().enumerate() {
        let a = input.as_ref().map_or(z, |m| m.as_ref());
        let mut out = Mat::<f32>::zeros(a.nrows(), w.ncols());
        matmul(out.as_mut(), Accum::Replace, a, w.as_ref(), 1.0, Par::Seq);
        for (j, col) in out.col_iter_mut().enumerate() {
            let bj = b.get(j).copied().unwrap_or(0.0);
            for v in col.iter_mut() {
                *v += bj;
                if l < last {
                    *v = activation.apply(*v);
                }
            }
        }
        if let Some(prev) = input.take() {
            keep.push(prev);
        }
        input = Some(out);
    }
    input.unwrap_or_else(|| Mat::zeros(z.nrows(), 3))
}
