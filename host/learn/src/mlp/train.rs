//! Training one random start of the perceptron: Glorot-uniform weights, then Adam on
//! shuffled mini-batches with scikit-learn's squared loss and L2 term, early stopping on the
//! held-out rows.

use et_core::rng::Rng;
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatRef, Par};

use super::{Layers, MlpOptions, forward};

/// Adam's state for one parameter array.
struct Moments {
    m: Vec<f32>,
    v: Vec<f32>,
}

impl Moments {
    fn new(len: usize) -> Self {
        Self {
            m: vec![0.0; len],
            v: vec![0.0; len],
        }
    }

    /// One Adam step of `params` along `grad` (step t from 1), both in the same order.
    fn step<'a>(
        &mut self,
        params: impl Iterator<Item = &'a mut f32>,
        grad: impl Iterator<Item = f32>,
        lr: f32,
        t: i32,
    ) {
        const B1: f32 = 0.9;
        const B2: f32 = 0.999;
        const EPS: f32 = 1e-8;
        let lr_t = lr * (1.0 - B2.powi(t)).sqrt() / (1.0 - B1.powi(t));
        for (((p, g), m), v) in params.zip(grad).zip(&mut self.m).zip(&mut self.v) {
            *m = B1 * *m + (1.0 - B1) * g;
            *v = B2 * *v + (1.0 - B2) * g * g;
            *p -= lr_t * *m / (v.sqrt() + EPS);
        }
    }
}

/// The values of a matrix, column by column (its storage order).
fn values(m: &Mat<f32>) -> impl Iterator<Item = f32> + '_ {
    m.col_iter().flat_map(|c| c.iter().copied())
}

/// Fisher-Yates.
pub(super) fn shuffle(v: &mut [usize], rng: &mut Rng) {
    for i in (1..v.len()).rev() {
        let j = (rng.next_u64() % (i as u64 + 1)) as usize;
        v.swap(i, j);
    }
}

/// Rows `rows` of `m`.
fn gather(m: &Mat<f32>, rows: &[usize]) -> Mat<f32> {
    Mat::from_fn(rows.len(), m.ncols(), |i, j| {
        rows.get(i).map_or(0.0, |&r| m[(r, j)])
    })
}

/// Half the mean squared error over rows and outputs (scikit-learn's squared loss).
fn loss(out: &Mat<f32>, y: &Mat<f32>) -> f64 {
    let mut s = 0.0f64;
    for j in 0..out.ncols() {
        for i in 0..out.nrows() {
            let d = f64::from(out[(i, j)] - y[(i, j)]);
            s += d * d;
        }
    }
    0.5 * s / (out.nrows() * out.ncols()).max(1) as f64
}

/// Glorot-uniform weights and biases for layers of `widths` (the input's first): each drawn
/// from +-sqrt(6 / (fan in + fan out)).
fn glorot(widths: &[usize], rng: &mut Rng) -> Layers {
    widths
        .windows(2)
        .map(|w| {
            let (fan_in, fan_out) = (
                w.first().copied().unwrap_or(1),
                w.get(1).copied().unwrap_or(1),
            );
            let bound = (6.0 / (fan_in + fan_out) as f64).sqrt();
            let mut u = || ((2.0 * rng.uniform() - 1.0) * bound) as f32;
            (
                Mat::from_fn(fan_in, fan_out, |_, _| u()),
                (0..fan_out).map(|_| u()).collect(),
            )
        })
        .collect()
}

/// Adam's state for every layer: its weights' and biases' moments, and the steps taken.
struct Adam {
    moments: Vec<(Moments, Moments)>,
    step: i32,
}

impl Adam {
    fn new(layers: &Layers) -> Self {
        Self {
            moments: layers
                .iter()
                .map(|(w, b)| (Moments::new(w.nrows() * w.ncols()), Moments::new(b.len())))
                .collect(),
            step: 0,
        }
    }

    /// One mini-batch's step: the gradient of scikit-learn's squared loss (with its L2 term)
    /// of `out`, the forward pass of `zb` through `layers` (`keep`: its hidden layers'
    /// outputs), against the targets `yb`, back-propagated layer by layer, each layer moved by
    /// Adam before the one below.
    fn descend(
        &mut self,
        layers: &mut Layers,
        (zb, yb): (MatRef<'_, f32>, &Mat<f32>),
        out: &Mat<f32>,
        keep: &[Mat<f32>],
        opts: &MlpOptions,
    ) -> Option<()> {
        let b = out.nrows() as f32;
        // d(loss)/d(out) for scikit-learn's loss: (out - y) / B (the 1/2 and the mean over
        // outputs folded as it does: per row, per output).
        let mut delta = Mat::<f32>::from_fn(out.nrows(), out.ncols(), |i, j| {
            (out[(i, j)] - yb[(i, j)]) / b
        });
        self.step = self.step.saturating_add(1);
        for l in (0..layers.len()).rev() {
            let input = if l == 0 {
                zb
            } else {
                keep.get(l - 1).map_or(zb, |m| m.as_ref())
            };
            let (w, bias) = layers.get_mut(l)?;
            let mut gw = Mat::<f32>::zeros(w.nrows(), w.ncols());
            matmul(
                gw.as_mut(),
                Accum::Replace,
                input.transpose(),
                delta.as_ref(),
                1.0,
                Par::Seq,
            );
            let penalty = (opts.l2 / f64::from(b)) as f32;
            for j in 0..w.ncols() {
                for i in 0..w.nrows() {
                    gw[(i, j)] += penalty * w[(i, j)];
                }
            }
            let gb: Vec<f32> = delta.col_iter().map(|c| c.iter().sum()).collect();
            // The delta of the layer below, before this layer's weights change.
            let below = (l > 0).then(|| {
                let mut d = Mat::<f32>::zeros(delta.nrows(), w.nrows());
                matmul(
                    d.as_mut(),
                    Accum::Replace,
                    delta.as_ref(),
                    w.transpose(),
                    1.0,
                    Par::Seq,
                );
                for j in 0..d.ncols() {
                    for i in 0..d.nrows() {
                        d[(i, j)] *= opts.activation.slope(input[(i, j)]);
                    }
                }
                d
            });
            let (mw, mb) = self.moments.get_mut(l)?;
            let (lr, t) = (opts.learning_rate, self.step);
            mw.step(
                w.col_iter_mut().flat_map(|c| c.iter_mut()),
                values(&gw),
                lr,
                t,
            );
            mb.step(bias.iter_mut(), gb.iter().copied(), lr, t);
            if let Some(d) = below {
                delta = d;
            }
        }
        Some(())
    }
}

/// One random start: Glorot-uniform weights, Adam on shuffled mini-batches of `train`, the
/// weights of the pass with the lowest loss on `valid` kept. (layers, passes, held-out loss).
pub(super) fn train_one(
    z: &Mat<f32>,
    y: &Mat<f32>,
    train: &[usize],
    valid: &[usize],
    p: usize,
    opts: &MlpOptions,
    rng: &mut Rng,
) -> Option<(Layers, usize, f64)> {
    let widths: Vec<usize> = std::iter::once(p)
        .chain(opts.hidden.iter().copied())
        .chain([y.ncols()])
        .collect();
    let mut layers = glorot(&widths, rng);
    let mut adam = Adam::new(&layers);
    let (zv, yv) = (gather(z, valid), gather(y, valid));
    let batch = opts.batch.clamp(1, train.len().max(1));
    let mut order = train.to_vec();
    let mut keep = Vec::new();
    let mut best: Option<(Layers, usize, f64)> = None;
    let mut since_best = 0;
    for epoch in 1..=opts.max_epochs.max(1) {
        shuffle(&mut order, rng);
        let mut train_loss = 0.0;
        for rows in order.chunks(batch) {
            let (zb, yb) = (gather(z, rows), gather(y, rows));
            let out = forward(&layers, opts.activation, zb.as_ref(), &mut keep);
            train_loss += loss(&out, &yb) * rows.len() as f64;
            adam.descend(&mut layers, (zb.as_ref(), &yb), &out, &keep, opts)?;
        }
        let score = if valid.is_empty() {
            train_loss / order.len().max(1) as f64
        } else {
            loss(
                &forward(&layers, opts.activation, zv.as_ref(), &mut Vec::new()),
                &yv,
            )
        };
        if !score.is_finite() {
            break;
        }
        // scikit-learn's rule: the best weights kept at any improvement, the patience
        // restarting only at an improvement of more than `tol`.
        let best_score = best.as_ref().map_or(f64::INFINITY, |b| b.2);
        if score < best_score {
            best = Some((layers.clone(), epoch, score));
        }
        if score < best_score - opts.tol {
            since_best = 0;
        } else {
            since_best += 1;
            if since_best > opts.patience {
                break;
            }
        }
    }
    best.map(|(l, e, s)| (l, e, if valid.is_empty() { f64::NAN } else { s }))
}
