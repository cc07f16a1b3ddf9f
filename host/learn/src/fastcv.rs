//! Fast, exact cross-validation of QDA and LDA.
//!
//! Two ideas make k-fold cross-validation cost little more than one fit:
//!
//! 1. **Sufficient statistics.** The count, sum and sum of outer products of every (class,
//!    fold) are computed once (matrix products, in globally centred coordinates so that no
//!    precision is lost). A fold's training model, including its own feature standardisation,
//!    follows by subtraction: no pass over the data per fold.
//! 2. **Exact pruning.** QDA's quadratic form is the sum of squares of the forward
//!    substitution L_c y = z - mu_c, so its partial sums only grow: a class can be given up as
//!    soon as log pi_c - 1/2 log|Sigma_c| - 1/2 (partial sum) falls below the best complete
//!    discriminant so far. Classes are tried nearest mean first, so most observations fully
//!    evaluate one or two classes out of 49. The argmax is exactly the unpruned one.
//!
//! The folds are shared between the machine's threads. The result equals
//! [`super::cv::cross_validate_folds`] (tested).

use et_core::model::ModelKind;
use nalgebra::{DMatrix, DVector};

use super::cv::Confusion;
use super::fit::{FitError, FitOptions, Target};

/// Per (class, fold): count, sum and sum of outer products, in centred coordinates.
struct Stats {
    n: Vec<usize>,
    s: Vec<DVector<f64>>,
    q: Vec<DMatrix<f64>>,
}

/// One fold's fitted model in the centred coordinates of the data.
struct FoldModel {
    /// Per class (QDA): L_c packed by rows (row r at r(r+1)/2), in z_f = (z0 - m) .* g.
    factors: Vec<Vec<f64>>,
    means: Vec<DVector<f64>>,
    constants: Vec<f64>,
    /// Feature shift and gain from centred to the fold's standardised coordinates.
    shift: DVector<f64>,
    gain: DVector<f64>,
    /// LDA: w_c and the pooled factor is unused in evaluation.
    weights: Vec<DVector<f64>>,
}

fn stats(z0: &DMatrix<f64>, y: &[u16], fold: &[usize], classes: usize, k: usize) -> Stats {
    let p = z0.ncols();
    let mut rows: Vec<Vec<usize>> = vec![Vec::new(); classes * k];
    for (r, (&c, &f)) in y.iter().zip(fold).enumerate() {
        rows[usize::from(c) * k + f].push(r);
    }
    let mut st = Stats {
        n: Vec::new(),
        s: Vec::new(),
        q: Vec::new(),
    };
    for group in rows {
        let block = DMatrix::from_fn(group.len(), p, |i, j| z0[(group[i], j)]);
        st.s.push(DVector::from_fn(p, |j, _| block.column(j).sum()));
        st.q.push(block.transpose() * &block); // GEMM (matrixmultiply), much faster than tr_mul
        st.n.push(group.len());
    }
    st
}

#[allow(clippy::too_many_lines)]
fn fold_model(
    st: &Stats,
    f: usize,
    k: usize,
    classes: usize,
    raw_mean: &[f64],
    raw_scale: &[f64],
    opts: &FitOptions,
) -> Result<FoldModel, FitError> {
    let p = raw_mean.len();
    // Training statistics per class (all folds but f).
    let mut n_c = vec![0usize; classes];
    let mut s_c = vec![DVector::<f64>::zeros(p); classes];
    let mut q_c = vec![DMatrix::<f64>::zeros(p, p); classes];
    for c in 0..classes {
        for g in (0..k).filter(|&g| g != f) {
            let i = c * k + g;
            n_c[c] += st.n[i];
            s_c[c] += &st.s[i];
            q_c[c] += &st.q[i];
        }
        if n_c[c] == 0 {
            return Err(FitError::EmptyClass { class: c as u16 });
        }
    }
    let n: usize = n_c.iter().sum();
    // The fold's standardisation, as Fitted::fit computes it from its training rows.
    let total_s: DVector<f64> = s_c.iter().sum();
    let m = &total_s / n as f64;
    let mut gain = DVector::<f64>::zeros(p);
    for j in 0..p {
        let sumsq: f64 = q_c.iter().map(|q| q[(j, j)]).sum();
        let var = ((sumsq - n as f64 * m[j] * m[j]) / (n - 1).max(1) as f64).max(0.0);
        let sd_raw = raw_scale[j] * var.sqrt();
        let mean_raw = raw_mean[j] + raw_scale[j] * m[j];
        let floor = 1e-9 * mean_raw.abs().max(f64::MIN_POSITIVE);
        let scale = if sd_raw > floor && sd_raw.is_finite() {
            sd_raw
        } else {
            1.0
        };
        gain[j] = raw_scale[j] / scale;
    }
    // Class means and scatters in the fold's standardised coordinates.
    let mut means = Vec::with_capacity(classes);
    let mut scatters = Vec::with_capacity(classes);
    let mut pooled = DMatrix::<f64>::zeros(p, p);
    for c in 0..classes {
        let mu0 = &s_c[c] / n_c[c] as f64;
        let mut scatter = &q_c[c] - (&mu0 * mu0.transpose()) * n_c[c] as f64;
        for a in 0..p {
            for b in 0..p {
                scatter[(a, b)] *= gain[a] * gain[b];
            }
        }
        means.push((&mu0 - &m).component_mul(&gain));
        pooled += &scatter;
        scatters.push(scatter);
    }
    let pooled = pooled / (n.saturating_sub(classes).max(1)) as f64;
    let shrink = |s: &DMatrix<f64>| -> DMatrix<f64> {
        if opts.shrinkage == 0.0 {
            return s.clone();
        }
        let t = match opts.target {
            Target::Pooled => pooled.clone(),
            Target::Diagonal => {
                let nu = s.trace() / p as f64;
                DMatrix::identity(p, p) * if nu > 0.0 { nu } else { 1.0 }
            }
        };
        s * (1.0 - opts.shrinkage) + t * opts.shrinkage
    };
    let log_prior = |c: usize| (n_c[c] as f64 / n as f64).ln();
    let mut model = FoldModel {
        factors: Vec::new(),
        means: Vec::new(),
        constants: Vec::new(),
        shift: m,
        gain,
        weights: Vec::new(),
    };
    match opts.kind {
        ModelKind::Qda => {
            for (c, (mean, scatter)) in means.into_iter().zip(scatters).enumerate() {
                let sigma = shrink(&(scatter / (n_c[c].saturating_sub(1).max(1)) as f64));
                let l = sigma
                    .cholesky()
                    .ok_or(FitError::NotPositiveDefinite { class: c as u16 })?
                    .l();
                if (0..p).any(|i| !(l[(i, i)] > 0.0 && l[(i, i)].is_finite())) {
                    return Err(FitError::NotPositiveDefinite { class: c as u16 });
                }
                let log_det = 2.0 * (0..p).map(|i| l[(i, i)].ln()).sum::<f64>();
                model.constants.push(-0.5 * log_det + log_prior(c));
                model.factors.push(
                    (0..p)
                        .flat_map(|r| (0..=r).map(move |c| (r, c)))
                        .map(|(r, c)| l[(r, c)])
                        .collect(),
                );
                model.means.push(mean);
            }
        }
        ModelKind::Lda => {
            let opts_d = FitOptions {
                target: Target::Diagonal,
                ..*opts
            };
            let sigma = if opts_d.shrinkage == 0.0 {
                pooled.clone()
            } else {
                let nu = pooled.trace() / p as f64;
                &pooled * (1.0 - opts_d.shrinkage)
                    + DMatrix::identity(p, p) * (if nu > 0.0 { nu } else { 1.0 }) * opts_d.shrinkage
            };
            let chol = sigma
                .cholesky()
                .ok_or(FitError::NotPositiveDefinite { class: 0 })?;
            for (c, mean) in means.into_iter().enumerate() {
                let w = chol.solve(&mean);
                model.constants.push(-0.5 * mean.dot(&w) + log_prior(c));
                model.weights.push(w);
                model.means.push(mean);
            }
        }
    }
    Ok(model)
}

impl FoldModel {
    /// argmax_c delta_c of a centred observation, exactly, with pruning (QDA) or directly (LDA).
    fn predict(
        &self,
        z0: &[f64],
        z: &mut [f64],
        order: &mut Vec<(f64, usize)>,
        y: &mut [f64],
    ) -> u16 {
        for (j, zj) in z.iter_mut().enumerate() {
            *zj = (z0[j] - self.shift[j]) * self.gain[j];
        }
        if !self.weights.is_empty() {
            let d = |c: usize| {
                self.weights[c]
                    .iter()
                    .zip(z.iter())
                    .map(|(w, v)| w * v)
                    .sum::<f64>()
                    + self.constants[c]
            };
            return (0..self.weights.len())
                .max_by(|&a, &b| d(a).total_cmp(&d(b)))
                .unwrap_or(0) as u16;
        }
        // Nearest mean first: the usual winner, which sets a high bar for the rest.
        order.clear();
        for (c, mu) in self.means.iter().enumerate() {
            let d2: f64 = mu
                .iter()
                .zip(z.iter())
                .map(|(m, v)| (v - m) * (v - m))
                .sum();
            order.push((d2, c));
        }
        order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        let p = z.len();
        let (mut best, mut arg) = (f64::NEG_INFINITY, order[0].1);
        for &(_, c) in order.iter() {
            let (l, mu, k) = (&self.factors[c], &self.means[c], self.constants[c]);
            if k <= best {
                continue; // even a zero quadratic form cannot win
            }
            let bar = 2.0 * (k - best); // prune once the partial sum of squares exceeds this
            let mut q = 0.0;
            let mut pruned = false;
            for r in 0..p {
                let row = &l[r * (r + 1) / 2..r * (r + 1) / 2 + r + 1];
                let acc = z[r]
                    - mu[r]
                    - row[..r]
                        .iter()
                        .zip(&y[..r])
                        .map(|(a, b)| a * b)
                        .sum::<f64>();
                let v = acc / row[r];
                y[r] = v;
                q += v * v;
                if q >= bar {
                    pruned = true;
                    break;
                }
            }
            if !pruned {
                let d = k - 0.5 * q;
                if d > best {
                    best = d;
                    arg = c;
                }
            }
        }
        arg as u16
    }
}

/// Cross-validation over `fold` (values 0..k), equal to [`super::cv::cross_validate_folds`]
/// but computed from sufficient statistics with exact pruning, on all threads.
///
/// # Errors
/// [`FitError`] as a plain fit would give for the first failing fold.
pub fn cross_validate_fast(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
    opts: &FitOptions,
    fold: &[usize],
) -> Result<Confusion, FitError> {
    super::fit::check(x, y, classes)?;
    let k = super::cv::fold_count(fold, y.len())?;
    let (n, p) = (x.nrows(), x.ncols());
    // Centre and scale globally once (no precision lost in the sums of outer products).
    let raw_mean: Vec<f64> = (0..p).map(|j| x.column(j).mean()).collect();
    let raw_scale: Vec<f64> = (0..p)
        .map(|j| {
            let sd = (x.column(j).variance() * n as f64 / (n - 1).max(1) as f64).sqrt();
            if sd > 0.0 && sd.is_finite() { sd } else { 1.0 }
        })
        .collect();
    let z0 = DMatrix::from_fn(n, p, |r, j| (x[(r, j)] - raw_mean[j]) / raw_scale[j]);
    let st = stats(&z0, y, fold, classes, k);
    // Observations row-major for evaluation: one observation is one contiguous slice.
    let rows: Vec<f64> = (0..n)
        .flat_map(|r| (0..p).map(move |j| (r, j)))
        .map(|(r, j)| z0[(r, j)])
        .collect();
    let rows_of: Vec<Vec<usize>> = (0..k)
        .map(|f| (0..n).filter(|&r| fold[r] == f).collect())
        .collect();
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .min(k);
    let results: Vec<Result<Confusion, FitError>> = std::thread::scope(|scope| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let (st, rows, rows_of, raw_mean, raw_scale) =
                    (&st, &rows, &rows_of, &raw_mean, &raw_scale);
                scope.spawn(move || {
                    let mut conf = Confusion::new(classes);
                    let (mut z, mut yv, mut order) =
                        (vec![0.0; p], vec![0.0; p], Vec::with_capacity(classes));
                    for f in (t..k).step_by(threads) {
                        let model = fold_model(st, f, k, classes, raw_mean, raw_scale, opts)?;
                        for &r in &rows_of[f] {
                            let row = &rows[r * p..(r + 1) * p];
                            conf.add(y[r], model.predict(row, &mut z, &mut order, &mut yv));
                        }
                    }
                    Ok(conf)
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(FitError::Shape("worker panicked".into())))
            })
            .collect()
    });
    let mut total = Confusion::new(classes);
    for r in results {
        total.merge(&r?);
    }
    Ok(total)
}
