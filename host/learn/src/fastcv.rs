//! Fast, exact cross-validation of QDA and LDA.
//!
//! Three ideas make k-fold cross-validation cost little more than one fit:
//!
//! 1. **Sufficient statistics.** The count, sum and sum of outer products of every (class,
//!    fold) are computed once (matrix products, in globally centred coordinates so that no
//!    precision is lost). A fold's training model, including its own feature standardisation,
//!    follows by subtraction: no pass over the data per fold, and none per shrinkage
//!    candidate either ([`Prepared`] and [`Partition`] keep them for every cross-validation
//!    of the same data).
//! 2. **Exact pruning.** QDA's quadratic form is the sum of squares of the forward
//!    substitution L_c y = z - mu_c, so its partial sums only grow: a class can be given up as
//!    soon as log pi_c - 1/2 log|Sigma_c| - 1/2 (partial sum) falls below the best complete
//!    discriminant so far. The features are visited most discriminating first, so a wrong
//!    class passes the bar in few steps. The argmax is exactly the unpruned one.
//! 3. **Bounds for a block at once.** The first 16 steps of every class's substitution, for
//!    up to 256 observations at a time, are one matrix product; the partial sums they give
//!    bound every class's discriminant from above, so the class of the best bound is
//!    finished first and a class whose bound the best complete discriminant beats is never
//!    touched (on 49 classes, about 8 classes per observation are looked at beyond the
//!    product).
//!
//! The folds are shared between the machine's threads. The result equals
//! [`super::cv::cross_validate_folds`] (tested).

use et_core::model::ModelKind;
use nalgebra::{DMatrix, DVector};

use super::cv::Confusion;
use super::fit::{FitError, FitOptions, Target};

/// Per (class, fold): count, sum and sum of outer products, in centred coordinates.
#[allow(missing_debug_implementations)]
struct Stats {
    n: Vec<usize>,
    s: Vec<DVector<f64>>,
    q: Vec<DMatrix<f64>>,
}

/// One fold's fitted model in the centred coordinates of the data.
struct FoldModel {
    /// Per class (QDA): L_c packed by rows (row r at r(r+1)/2), in z_f = (z0 - m) .* g,
    /// with 1 / L_c[r, r] in place of each diagonal entry (a product, not a division, per
    /// step of the forward substitution).
    factors: Vec<Vec<f64>>,
    means: Vec<DVector<f64>>,
    constants: Vec<f64>,
    /// Feature shift and gain from centred to the fold's standardised coordinates.
    shift: DVector<f64>,
    gain: DVector<f64>,
    /// QDA: the order in which the forward substitution visits the features, most
    /// discriminating first (between-class over within-class variance), so that a wrong
    /// class's partial sum of squares passes the bar in few steps. The quadratic form does
    /// not depend on the order: the decisions stay exact. Identity for LDA.
    order: Vec<usize>,
    /// QDA: [W_1; ...; W_C] stacked, (C d) x d, W_c the inverse of L_c's leading d x d block
    /// (d = [`LEAD`] or p): the first d steps of every class's forward substitution, for a
    /// block of observations at once, are one matrix product.
    lead: DMatrix<f64>,
    /// QDA: W_c mu_c[..d] stacked, C d values.
    lead_shift: Vec<f64>,
    /// LDA: w_c and the pooled factor is unused in evaluation.
    weights: Vec<DVector<f64>>,
}

/// `rows`: row-major, p per observation.
fn stats(rows: &[f64], p: usize, y: &[u16], fold: &[usize], classes: usize, k: usize) -> Stats {
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); classes * k];
    for (r, (&c, &f)) in y.iter().zip(fold).enumerate() {
        groups[usize::from(c) * k + f].push(r);
    }
    let mut st = Stats {
        n: Vec::new(),
        s: Vec::new(),
        q: Vec::new(),
    };
    for group in groups {
        // p x m: the group's observations as columns (contiguous copies of their rows).
        let block = DMatrix::from_iterator(
            p,
            group.len(),
            group
                .iter()
                .flat_map(|&r| rows[r * p..(r + 1) * p].iter().copied()),
        );
        st.s.push(block.column_sum());
        st.q.push(&block * block.transpose()); // GEMM (matrixmultiply), much faster than tr_mul
        st.n.push(group.len());
    }
    st
}

/// The model of fold `f` of `k` (trained on every other fold) from the blocks' statistics
/// `st`, the features' raw standardisation (`raw_mean`, `raw_scale`, p values) and the fit's
/// options: what `Fitted::fit` would give on those rows, without going back to them.
fn fold_model(
    st: &Stats,
    f: usize,
    k: usize,
    classes: usize,
    raw_mean: &[f64],
    raw_scale: &[f64],
    opts: &FitOptions,
) -> Result<FoldModel, FitError> {
    let fold = FoldClasses::of(st, (f, k), classes, raw_mean, raw_scale)?;
    let p = raw_mean.len();
    let mut model = FoldModel {
        factors: Vec::new(),
        means: Vec::new(),
        constants: Vec::new(),
        shift: fold.shift.clone(),
        gain: fold.gain.clone(),
        order: (0..p).collect(),
        lead: DMatrix::zeros(0, 0),
        lead_shift: Vec::new(),
        weights: Vec::new(),
    };
    match opts.kind {
        ModelKind::Qda => fold.qda(opts, &mut model)?,
        ModelKind::Lda => fold.lda(opts.shrinkage, &mut model)?,
    }
    Ok(model)
}

/// A fold's training rows summed per class, in the fold's standardised coordinates.
struct FoldClasses {
    /// Rows per class.
    n_c: Vec<usize>,
    /// Each class's mean, centred on the fold's mean (p values).
    means: Vec<DVector<f64>>,
    /// Each class's scatter, sum (x - mean)(x - mean)^T (p x p).
    scatters: Vec<DMatrix<f64>>,
    /// The pooled within-class covariance (p x p).
    pooled: DMatrix<f64>,
    /// The fold's mean in the raw standardisation (p values), and each feature's gain to the
    /// fold's own standardisation.
    shift: DVector<f64>,
    gain: DVector<f64>,
}

impl FoldClasses {
    /// Fold `f` of `k` from the blocks' statistics (every class's blocks but fold f's).
    fn of(
        st: &Stats,
        (f, k): (usize, usize),
        classes: usize,
        raw_mean: &[f64],
        raw_scale: &[f64],
    ) -> Result<Self, FitError> {
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
        Ok(Self {
            n_c,
            means,
            scatters,
            pooled,
            shift: m,
            gain,
        })
    }

    /// ln of class `c`'s share of the rows.
    fn log_prior(&self, c: usize) -> f64 {
        let n: usize = self.n_c.iter().sum();
        (self.n_c[c] as f64 / n as f64).ln()
    }

    /// QDA's factors into `model`: the features ordered by between- over within-class
    /// variance, each class's shrunk covariance's Cholesky factor (its first [`LEAD`] rows
    /// inverted for the block products) and its constant.
    fn qda(self, opts: &FitOptions, model: &mut FoldModel) -> Result<(), FitError> {
        let (p, classes) = (self.gain.len(), self.n_c.len());
        let n: usize = self.n_c.iter().sum();
        // As `Fitted::fit` shrinks: toward the pooled covariance where it can be a target.
        let pooled = match opts.target {
            Target::Pooled if opts.shrinkage > 0.0 => crate::fit::pooled_target(&self.pooled),
            _ => None,
        };
        let shrink = |s: &DMatrix<f64>| -> DMatrix<f64> {
            if opts.shrinkage == 0.0 {
                return s.clone();
            }
            let t = match &pooled {
                Some(t) => t.clone(),
                None => {
                    let nu = s.trace() / p as f64;
                    DMatrix::identity(p, p) * if nu > 0.0 { nu } else { 1.0 }
                }
            };
            s * (1.0 - opts.shrinkage) + t * opts.shrinkage
        };
        // Between-class over pooled within-class variance per feature (the means are centred
        // on the fold's mean).
        let ratio: Vec<f64> = (0..p)
            .map(|j| {
                let between: f64 = (0..classes)
                    .map(|c| self.n_c[c] as f64 * self.means[c][j] * self.means[c][j])
                    .sum::<f64>()
                    / n as f64;
                between / self.pooled[(j, j)].max(f64::MIN_POSITIVE)
            })
            .collect();
        model.order.sort_by(|&a, &b| ratio[b].total_cmp(&ratio[a]));
        let order = &model.order;
        let mut leads = Vec::with_capacity(classes);
        for (c, (mean, scatter)) in self.means.iter().zip(&self.scatters).enumerate() {
            let sigma = shrink(&(scatter / (self.n_c[c].saturating_sub(1).max(1)) as f64));
            let sigma = DMatrix::from_fn(p, p, |a, b| sigma[(order[a], order[b])]);
            let mean = DVector::from_fn(p, |a, _| mean[order[a]]);
            let l = sigma
                .cholesky()
                .ok_or(FitError::NotPositiveDefinite { class: c as u16 })?
                .l();
            if (0..p).any(|i| !(l[(i, i)] > 0.0 && l[(i, i)].is_finite())) {
                return Err(FitError::NotPositiveDefinite { class: c as u16 });
            }
            let log_det = 2.0 * (0..p).map(|i| l[(i, i)].ln()).sum::<f64>();
            let d = LEAD.min(p);
            let w = l
                .view((0, 0), (d, d))
                .solve_lower_triangular(&DMatrix::identity(d, d))
                .ok_or(FitError::NotPositiveDefinite { class: c as u16 })?;
            leads.push(w);
            model.constants.push(-0.5 * log_det + self.log_prior(c));
            model.factors.push(
                (0..p)
                    .flat_map(|r| (0..=r).map(move |c| (r, c)))
                    .map(|(r, c)| if r == c { 1.0 / l[(r, c)] } else { l[(r, c)] })
                    .collect(),
            );
            model.means.push(mean);
        }
        let d = LEAD.min(p);
        model.lead = DMatrix::from_fn(classes * d, d, |r, j| leads[r / d][(r % d, j)]);
        model.lead_shift = (0..classes * d)
            .map(|r| {
                let (c, i) = (r / d, r % d);
                (0..d).map(|j| leads[c][(i, j)] * model.means[c][j]).sum()
            })
            .collect();
        Ok(())
    }

    /// LDA's weights into `model`: the pooled covariance shrunk toward its mean variance by
    /// `shrinkage` (LDA's one target), each class's weights and constant.
    fn lda(self, shrinkage: f64, model: &mut FoldModel) -> Result<(), FitError> {
        let p = self.gain.len();
        let sigma = if shrinkage == 0.0 {
            self.pooled.clone()
        } else {
            let nu = self.pooled.trace() / p as f64;
            &self.pooled * (1.0 - shrinkage)
                + DMatrix::identity(p, p) * (if nu > 0.0 { nu } else { 1.0 }) * shrinkage
        };
        let chol = sigma
            .cholesky()
            .ok_or(FitError::NotPositiveDefinite { class: 0 })?;
        for (c, mean) in self.means.iter().enumerate() {
            let w = chol.solve(mean);
            model
                .constants
                .push(-0.5 * mean.dot(&w) + self.log_prior(c));
            model.weights.push(w);
            model.means.push(mean.clone());
        }
        Ok(())
    }
}

/// Observations per block of [`FoldModel::predict_block`], at most.
const BLOCK: usize = 256;

/// Observations per block of [`FoldModel::predict_block`] among `classes` classes: [`BLOCK`],
/// fewer (down to 16) where the block's bounds ((C d) x b values) would pass 16 MiB. A
/// larger product is mapped afresh from the system for every block (glibc reuses freed
/// blocks up to 32 MB): a 50 x 50 grid's training spent 38 of its 54 s in the system so;
/// fewer than 16 rows read the class tables too often (at 10 000 classes, 3 rows a block
/// made it slower).
fn block_len(classes: usize) -> usize {
    const BOUNDS_BYTES: usize = 16 << 20;
    (BOUNDS_BYTES / (classes * LEAD * 8).max(1)).clamp(16, BLOCK)
}

/// Steps of the forward substitution done for all classes at once by a matrix product.
pub(crate) const LEAD: usize = 16;

/// Reused buffers of [`FoldModel::predict_block`].
#[derive(Default)]
struct Scratch {
    y: Vec<f64>,
    bounds: Vec<f64>,
}

impl FoldModel {
    /// argmax_c delta_c of each centred observation `rows[r]` (row-major, p per row), exactly,
    /// appended to `out`.
    ///
    /// QDA by branch and bound: the first d steps of every class's forward substitution
    /// for the whole block are one matrix product; their sum of squares q_c^d <= q_c bounds
    /// each discriminant from above, k_c - q_c^d / 2. The class with the highest bound is
    /// finished first, which sets the bar; every other class whose bound clears it is
    /// finished too, and given up as soon as its partial sum passes the bar. The argmax is
    /// exactly the unpruned one. LDA: the linear discriminants directly.
    fn predict_block(
        &self,
        rows: &[f64],
        which: &[usize],
        out: &mut Vec<u16>,
        scratch: &mut Scratch,
    ) {
        let p = self.shift.len();
        let b = which.len();
        // Standardised, in the substitution's feature order: one observation per column.
        let z = DMatrix::from_fn(p, b, |j, i| {
            let f = self.order[j];
            (rows[which[i] * p + f] - self.shift[f]) * self.gain[f]
        });
        if !self.weights.is_empty() {
            for zi in z.column_iter() {
                let d =
                    |c: usize| dot(self.weights[c].as_slice(), zi.as_slice()) + self.constants[c];
                let best = (0..self.weights.len()).max_by(|&a, &c| d(a).total_cmp(&d(c)));
                out.push(best.unwrap_or(0) as u16);
            }
            return;
        }
        let d = LEAD.min(p);
        let classes = self.means.len();
        // (C d) x b: column i holds every class's first d whitened residuals (plus shift).
        let lead = &self.lead * z.rows(0, d);
        scratch.y.resize(p, 0.0);
        for (zi, li) in z.column_iter().zip(lead.column_iter()) {
            let (zi, li) = (zi.as_slice(), li.as_slice());
            scratch.bounds.clear();
            for c in 0..classes {
                let q: f64 = (0..d)
                    .map(|i| {
                        let v = li[c * d + i] - self.lead_shift[c * d + i];
                        v * v
                    })
                    .sum();
                scratch.bounds.push(self.constants[c] - 0.5 * q);
            }
            // The class of the highest bound first (it sets the bar), then every other whose
            // bound clears the bar, in any order: the argmax is the same. Sorting them all
            // took C log C comparisons per observation, most of a 10 000-class training.
            let top = (0..classes)
                .max_by(|&a, &b| scratch.bounds[a].total_cmp(&scratch.bounds[b]))
                .unwrap_or(0);
            let (mut best, mut arg) = (f64::NEG_INFINITY, top);
            for c in std::iter::once(top).chain((0..classes).filter(|&c| c != top)) {
                if scratch.bounds[c] <= best {
                    continue; // cannot win
                }
                let (l, mu, k) = (&self.factors[c], &self.means[c], self.constants[c]);
                let bar = 2.0 * (k - best); // given up once the partial sum passes this
                let y = &mut scratch.y;
                let mut q = 0.0;
                for i in 0..d {
                    y[i] = li[c * d + i] - self.lead_shift[c * d + i];
                    q += y[i] * y[i];
                }
                let mut finished = true;
                for r in d..p {
                    let row = &l[r * (r + 1) / 2..r * (r + 1) / 2 + r + 1];
                    let v = (zi[r] - mu[r] - dot(&row[..r], &y[..r])) * row[r];
                    y[r] = v;
                    q += v * v;
                    if q >= bar {
                        finished = false;
                        break;
                    }
                }
                if finished && k - 0.5 * q > best {
                    best = k - 0.5 * q;
                    arg = c;
                }
            }
            out.push(arg as u16);
        }
    }
}

/// sum_i a_i b_i over equal-length slices, in eight independent partial sums: the
/// additions do not wait on each other, so the compiler's vector units keep busy (a single
/// running sum is bound by the adder's latency, about 8x slower on long rows).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let (ca, cb) = (a.chunks_exact(8), b.chunks_exact(8));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    let mut acc = [0.0; 8];
    for (x, y) in ca.zip(cb) {
        for i in 0..8 {
            acc[i] += x[i] * y[i];
        }
    }
    (acc[0] + acc[4]) + (acc[1] + acc[5]) + (acc[2] + acc[6]) + (acc[3] + acc[7]) + tail
}

/// The data centred and scaled once for any number of cross-validations: the folds and the
/// options vary, the data does not (a shrinkage search, then k-fold and leave-one-visit-out
/// cross-validation of the chosen model, share it).
#[derive(Debug)]
pub struct Prepared<'a> {
    y: &'a [u16],
    classes: usize,
    /// Features per observation.
    p: usize,
    /// n x p row-major (one observation is one contiguous slice): (x - mean) / scale per
    /// feature, over all rows (no precision lost in the sums of outer products).
    rows: Vec<f64>,
    raw_mean: Vec<f64>,
    raw_scale: Vec<f64>,
}

/// One way of folding the rows of a [`Prepared`] set: every (class, fold)'s sufficient
/// statistics, from which every fold's model follows by subtraction, for any options.
#[allow(missing_debug_implementations)] // matrices per (class, fold): not for printing
pub struct Partition {
    k: usize,
    stats: Stats,
    rows_of: Vec<Vec<usize>>,
}

impl<'a> Prepared<'a> {
    /// Checks and prepares `x` (n x p) with labels `y` in 0..classes.
    ///
    /// # Errors
    /// [`FitError`] for shapes, labels or values a fit refuses.
    pub fn new(x: &DMatrix<f64>, y: &'a [u16], classes: usize) -> Result<Self, FitError> {
        super::fit::check(x, y, classes)?;
        let (n, p) = (x.nrows(), x.ncols());
        let raw_mean: Vec<f64> = x.column_iter().map(|c| c.mean()).collect();
        let raw_scale: Vec<f64> = x
            .column_iter()
            .map(|c| {
                let sd = (c.variance() * n as f64 / (n - 1).max(1) as f64).sqrt();
                if sd > 0.0 && sd.is_finite() { sd } else { 1.0 }
            })
            .collect();
        let mut z0 = x.clone();
        for (mut column, (m, s)) in z0.column_iter_mut().zip(raw_mean.iter().zip(&raw_scale)) {
            column.apply(|v| *v = (*v - m) / s);
        }
        let rows = z0.transpose().as_slice().to_vec();
        Ok(Self {
            y,
            classes,
            p,
            rows,
            raw_mean,
            raw_scale,
        })
    }

    /// The sufficient statistics of `fold` (one value per row, 0..k).
    ///
    /// # Errors
    /// [`FitError::Counts`] for a fold list of another length, [`FitError::TooFewFolds`] for fewer than two folds.
    pub fn partition(&self, fold: &[usize]) -> Result<Partition, FitError> {
        let n = self.y.len();
        let k = super::cv::fold_count(fold, n)?;
        let stats = stats(&self.rows, self.p, self.y, fold, self.classes, k);
        let mut rows_of = vec![Vec::new(); k];
        for (r, &f) in fold.iter().enumerate() {
            rows_of[f].push(r);
        }
        Ok(Partition { k, stats, rows_of })
    }

    /// Cross-validation of the model `opts` describes over `part`, on all threads.
    ///
    /// # Errors
    /// [`FitError`] as a plain fit would give for the first failing fold.
    pub fn cross_validate(
        &self,
        part: &Partition,
        opts: &FitOptions,
    ) -> Result<Confusion, FitError> {
        let (k, classes, y) = (part.k, self.classes, self.y);
        let threads = std::thread::available_parallelism()
            .map_or(1, |t| t.get())
            .min(k);
        let results: Vec<Result<Confusion, FitError>> = std::thread::scope(|scope| {
            let handles: Vec<_> = (0..threads)
                .map(|t| {
                    scope.spawn(move || {
                        let mut conf = Confusion::new(classes);
                        let (mut scratch, mut predicted) = (Scratch::default(), Vec::new());
                        for f in (t..k).step_by(threads) {
                            let model = fold_model(
                                &part.stats,
                                f,
                                k,
                                classes,
                                &self.raw_mean,
                                &self.raw_scale,
                                opts,
                            )?;
                            for block in part.rows_of[f].chunks(block_len(classes)) {
                                predicted.clear();
                                model.predict_block(
                                    &self.rows,
                                    block,
                                    &mut predicted,
                                    &mut scratch,
                                );
                                for (&r, &c) in block.iter().zip(&predicted) {
                                    conf.add(y[r], c);
                                }
                            }
                        }
                        Ok(conf)
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or(Err(FitError::Panicked)))
                .collect()
        });
        let mut total = Confusion::new(classes);
        for r in results {
            total.merge(&r?);
        }
        Ok(total)
    }
}

/// Cross-validation over `fold` (values 0..k), equal to [`super::cv::cross_validate_folds`]
/// but computed from sufficient statistics with exact pruning, on all threads. To
/// cross-validate the same data several times, [`Prepared`] it once.
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
    let prepared = Prepared::new(x, y, classes)?;
    prepared.cross_validate(&prepared.partition(fold)?, opts)
}
