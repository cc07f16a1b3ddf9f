//! Beyond classes (docs/method.md §11): continuous touch position (x, y) and touch intensity (pressure)
//! by regression from the (referenced) features, and several methods to compare:
//!
//! - [`Ridge`]: linear ridge regression, (x, y, p) = W z + b. Tiny (3 p weights) and trivially
//!   cheap on the chip.
//! - [`KernelRidge`]: Gaussian-kernel ridge regression on m training observations. Smooth and
//!   non-linear; its cost is m kernel evaluations of p features per frame.
//! - [`posterior_centre`]: the class centres weighted by a classifier's posteriors (softmax of
//!   the discriminants), so a class model interpolates between its grid cells.
//!
//! Targets are positions in m and a third value (pressure in kPa, or a table's third target);
//! the learners are equivariant to the targets' units. Features are volts (standardised
//! inside each model).

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::SolveCore;
use faer::{Accum, Mat, Par, Side};
use nalgebra::DMatrix;

use super::fit::{FitError, Fitted, standardisation};
pub use kernel_exp::{exp_neg, exp_neg_scaled};

/// Targets per observation: x (m), y (m), a third value (pressure in kPa, a z in m, ...).
pub type Target3 = [f64; 3];

/// `x` (n x p) standardised column by column: (x - mean) / scale.
#[must_use]
pub fn standardise(x: &DMatrix<f64>, mean: &[f64], scale: &[f64]) -> DMatrix<f64> {
    DMatrix::from_fn(x.nrows(), x.ncols(), |r, j| {
        (x[(r, j)] - mean[j]) / scale[j]
    })
}

/// The rows of `x` (n x p) in z-space, as faer's matrix for the kernel products.
pub(crate) fn z_space(x: &DMatrix<f64>, mean: &[f64], scale: &[f64]) -> Mat<f64> {
    Mat::from_fn(x.nrows(), x.ncols(), |r, j| {
        (x[(r, j)] - mean[j]) / scale[j]
    })
}

pub(crate) fn check(x: &DMatrix<f64>, t: &[Target3]) -> Result<(), FitError> {
    if x.nrows() != t.len() || x.nrows() < 2 || x.ncols() == 0 {
        return Err(FitError::Counts {
            what: "targets",
            got: t.len(),
            expected: x.nrows(),
            of: "observations",
        });
    }
    for (r, row) in x.row_iter().enumerate() {
        if let Some(j) = row.iter().position(|v| !v.is_finite()) {
            return Err(FitError::NonFinite { row: r, feature: j });
        }
        if t[r].iter().any(|v| !v.is_finite()) {
            return Err(FitError::NonFiniteTarget { row: r });
        }
    }
    Ok(())
}

/// The mean of the targets, per component.
#[must_use]
pub fn target_mean(t: &[Target3]) -> Target3 {
    let mut m = [0.0; 3];
    for row in t {
        for k in 0..3 {
            m[k] += row[k] / t.len() as f64;
        }
    }
    m
}

/// Linear ridge regression in z-space.
#[derive(Clone, Debug)]
pub struct Ridge {
    pub(crate) mean: Vec<f64>,
    pub(crate) scale: Vec<f64>,
    /// p x 3 weights.
    pub weights: DMatrix<f64>,
    pub(crate) intercept: Target3,
}

impl Ridge {
    /// Fits (Z^T Z + lambda n I) W = Z^T (T - mean T); with more features than rows, in the
    /// dual: W = Z^T (Z Z^T + lambda n I)^-1 (T - mean T), the same weights from an n x n
    /// system instead of a p x p one (360 rows of 10 000 features: a 360 x 360 Cholesky).
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data, or a system that is not positive
    /// definite (lambda = 0 with collinear features).
    pub fn fit(x: &DMatrix<f64>, t: &[Target3], lambda: f64) -> Result<Self, FitError> {
        Self::fit_path(x, t, &[lambda])?
            .pop()
            .flatten()
            .ok_or(FitError::NotPositiveDefinite { class: 0 })
    }

    /// [`fit`](Self::fit) at each of `lambdas` from one Gram matrix (Z^T Z, or Z Z^T when
    /// there are more features than rows; the cost of one fit plus a Cholesky per lambda): a
    /// ridge path for cross-validation. A lambda whose system is not positive definite gives
    /// `None`.
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data.
    pub fn fit_path(
        x: &DMatrix<f64>,
        t: &[Target3],
        lambdas: &[f64],
    ) -> Result<Vec<Option<Self>>, FitError> {
        check(x, t)?;
        let (mean, scale) = standardisation(x);
        let z = standardise(x, &mean, &scale);
        let intercept = target_mean(t);
        let tc = DMatrix::from_fn(t.len(), 3, |r, k| t[r][k] - intercept[k]);
        let (n, p) = (z.nrows(), z.ncols());
        let dual = p > n;
        let zf = Mat::from_fn(n, p, |r, j| z[(r, j)]);
        let side = if dual { n } else { p };
        let mut gram = Mat::<f64>::zeros(side, side);
        let (a, b) = if dual {
            (zf.as_ref(), zf.transpose())
        } else {
            (zf.transpose(), zf.as_ref())
        };
        matmul(gram.as_mut(), Accum::Replace, a, b, 1.0, Par::Seq);
        let zt = if dual {
            tc.clone()
        } else {
            z.transpose() * &tc
        };
        Ok(lambdas
            .iter()
            .map(|&lambda| {
                let a = DMatrix::from_fn(side, side, |i, j| {
                    gram[(i, j)] + if i == j { lambda * n as f64 } else { 0.0 }
                });
                let solved = a.cholesky()?.solve(&zt);
                let weights = if dual { z.transpose() * solved } else { solved };
                weights.iter().all(|v| v.is_finite()).then(|| Self {
                    mean: mean.clone(),
                    scale: scale.clone(),
                    weights,
                    intercept,
                })
            })
            .collect())
    }

    /// The p rows of 3 weights.
    pub(crate) fn weight_rows(&self) -> Vec<[f64; 3]> {
        self.weights
            .row_iter()
            .map(|w| [w[0], w[1], w[2]])
            .collect()
    }

    /// Predicts every row of `x` (n x p, volts).
    #[must_use]
    pub fn predict_many(&self, x: &DMatrix<f64>) -> Vec<Target3> {
        let mut row = vec![0.0; x.ncols()];
        (0..x.nrows())
            .map(|r| {
                for (j, v) in row.iter_mut().enumerate() {
                    *v = x[(r, j)];
                }
                self.predict(&row)
            })
            .collect()
    }

    /// Predicts one observation (p features, volts).
    #[must_use]
    pub fn predict(&self, x: &[f64]) -> Target3 {
        let mut out = self.intercept;
        for (j, &v) in x.iter().enumerate() {
            let z = (v - self.mean[j]) / self.scale[j];
            for (k, o) in out.iter_mut().enumerate() {
                *o += z * self.weights[(j, k)];
            }
        }
        out
    }

    /// Multiply-adds per prediction.
    #[must_use]
    pub fn cost(&self) -> usize {
        3 * self.weights.nrows()
    }
}

/// The rows of an m x 3 matrix.
pub(crate) fn rows3(m: &Mat<f64>) -> Vec<[f64; 3]> {
    (0..m.nrows())
        .map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]])
        .collect()
}

/// The rows of a matrix.
pub(crate) fn rows_of(m: &Mat<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
        .collect()
}

/// The median of the squared distances `d2` (m x m) between the first 400 rows, the scale
/// kernel widths are measured in (at least 1e-12).
pub(crate) fn median_pair(d2: &Mat<f64>) -> f64 {
    let first = d2.nrows().min(400);
    let mut pairs: Vec<f64> = (0..first)
        .flat_map(|a| ((a + 1)..first).map(move |b| (a, b)))
        .map(|(a, b)| d2[(a, b)])
        .collect();
    pairs.sort_by(f64::total_cmp);
    pairs
        .get(pairs.len() / 2)
        .copied()
        .unwrap_or(1.0)
        .max(1e-12)
}

/// Squared distances between the rows of `a` (m x p) and of `b` (n x p), m x n:
/// |a_i|^2 + |b_j|^2 - 2 a_i . b_j, the cross term one matrix product (one core), clamped at 0
/// against rounding.
/// The most memory a block of rows' distances to a support takes, bytes.
const BLOCK_BYTES: usize = 64 << 20;

/// `n` rows as blocks (start, rows) whose distances to a support of `m` rows (f64, and a copy
/// as the kernel) take at most [`BLOCK_BYTES`]: memory bounded whatever the table's length.
pub fn row_blocks(n: usize, m: usize) -> impl Iterator<Item = (usize, usize)> {
    let block = (BLOCK_BYTES / (16 * m.max(1))).max(1);
    (0..n)
        .step_by(block)
        .map(move |start| (start, block.min(n - start)))
}

pub(crate) fn squared_distances(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let (na, nb) = (squared_norms(a), squared_norms(b));
    let mut d = Mat::<f64>::zeros(a.nrows(), b.nrows());
    matmul(
        d.as_mut(),
        Accum::Replace,
        a.as_ref(),
        b.transpose(),
        -2.0,
        Par::Seq,
    );
    for j in 0..b.nrows() {
        for (i, v) in d.col_mut(j).iter_mut().enumerate() {
            *v = (*v + na[i] + nb[j]).max(0.0);
        }
    }
    d
}

/// The Gaussian kernel from squared distances, in place: each d2 becomes e^(-`gamma` d2).
pub(crate) fn gaussian_in_place(d2: &mut Mat<f64>, gamma: f64) {
    for j in 0..d2.ncols() {
        // An owned matrix's columns are contiguous.
        if let Some(c) = d2.col_mut(j).try_as_col_major_mut() {
            exp_neg_scaled(c.as_slice_mut(), gamma);
        } else {
            d2.col_mut(j)
                .iter_mut()
                .for_each(|v| *v = exp_neg(gamma * *v));
        }
    }
}

/// |row|^2 of each row of `m`.
fn squared_norms(m: &Mat<f64>) -> Vec<f64> {
    (0..m.nrows())
        .map(|i| (0..m.ncols()).map(|j| m[(i, j)] * m[(i, j)]).sum())
        .collect()
}

/// [`squared_distances`] for the nearest neighbours: the product in f32, at twice the speed.
/// The distances' absolute error is about 1e-7 |z|^2 (4e-5 for 192 standardised channels):
/// only neighbours that close to each other can swap, and a 1/distance weight moves by a
/// relative 1e-7 |z|^2 / d^2. Kernel models keep f64: their weights can be large and of both
/// signs, which would magnify the error.
pub(crate) fn squared_distances_f32(a: &Mat<f64>, b: &Mat<f64>) -> Mat<f64> {
    let single = |m: &Mat<f64>| Mat::<f32>::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)] as f32);
    let (na, nb) = (squared_norms(a), squared_norms(b));
    let mut dot = Mat::<f32>::zeros(a.nrows(), b.nrows());
    matmul(
        dot.as_mut(),
        Accum::Replace,
        single(a).as_ref(),
        single(b).transpose(),
        -2.0,
        Par::Seq,
    );
    Mat::from_fn(a.nrows(), b.nrows(), |i, j| {
        (f64::from(dot[(i, j)]) + na[i] + nb[j]).max(0.0)
    })
}

/// Gaussian-kernel ridge regression: f(z) = mean T + sum_i alpha_i exp(-gamma |z - z_i|^2).
#[derive(Clone, Debug)]
pub struct KernelRidge {
    pub(crate) mean: Vec<f64>,
    pub(crate) scale: Vec<f64>,
    /// m x p training observations in z-space.
    pub(crate) support: Mat<f64>,
    /// m x 3.
    pub(crate) alpha: Mat<f64>,
    pub(crate) gamma: f64,
    pub(crate) intercept: Target3,
}

impl KernelRidge {
    /// Fits on at most `m` observations spread evenly over the rows, with kernel width from
    /// the median squared distance between the first 400 of them (gamma = `width` / median)
    /// and ridge `lambda`: (K + lambda I) alpha = T - mean T, K from one matrix product and
    /// solved by its Cholesky factor (faer, one core).
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data, or a singular system.
    pub fn fit(
        x: &DMatrix<f64>,
        t: &[Target3],
        m: usize,
        width: f64,
        lambda: f64,
    ) -> Result<Self, FitError> {
        Self::fit_grid(x, t, m, &[width], &[lambda])?
            .pop()
            .flatten()
            .ok_or(FitError::NotPositiveDefinite { class: 0 })
    }

    /// [`fit`](Self::fit) at every (width, lambda) of `widths` x `lambdas` (width-major), the
    /// distances computed once: a grid for cross-validation. A pair whose system is singular
    /// gives `None`.
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data.
    pub fn fit_grid(
        x: &DMatrix<f64>,
        t: &[Target3],
        m: usize,
        widths: &[f64],
        lambdas: &[f64],
    ) -> Result<Vec<Option<Self>>, FitError> {
        check(x, t)?;
        let n = x.nrows();
        let m = m.clamp(2, n);
        let rows: Vec<usize> = (0..m).map(|i| i * n / m).collect();
        let (mean, scale) = standardisation(x);
        let support = z_space(&x.select_rows(&rows), &mean, &scale);
        let d2 = squared_distances(&support, &support);
        let median = median_pair(&d2);
        let ts: Vec<Target3> = rows.iter().map(|&r| t[r]).collect();
        let intercept = target_mean(&ts);
        let mut fits = Vec::with_capacity(widths.len() * lambdas.len());
        for &width in widths {
            let gamma = width / median;
            let mut kernel = d2.clone();
            gaussian_in_place(&mut kernel, gamma);
            for &lambda in lambdas {
                let mut k = kernel.clone();
                for i in 0..m {
                    k[(i, i)] += lambda;
                }
                let mut alpha = Mat::from_fn(m, 3, |r, c| ts[r][c] - intercept[c]);
                let solved = match k.llt(Side::Lower) {
                    Ok(llt) => {
                        llt.solve_in_place_with_conj(faer::Conj::No, alpha.as_mut());
                        (0..m).all(|r| (0..3).all(|c| alpha[(r, c)].is_finite()))
                    }
                    Err(_) => false,
                };
                fits.push(solved.then(|| Self {
                    mean: mean.clone(),
                    scale: scale.clone(),
                    support: support.clone(),
                    alpha,
                    gamma,
                    intercept,
                }));
            }
        }
        Ok(fits)
    }

    /// Predicts one observation (p features, volts).
    #[must_use]
    pub fn predict(&self, x: &[f64]) -> Target3 {
        let z: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(j, &v)| (v - self.mean[j]) / self.scale[j])
            .collect();
        let mut out = self.intercept;
        for i in 0..self.support.nrows() {
            let d2: f64 = z
                .iter()
                .enumerate()
                .map(|(j, b)| (self.support[(i, j)] - b).powi(2))
                .sum();
            let w = exp_neg(self.gamma * d2);
            for (k, o) in out.iter_mut().enumerate() {
                *o += w * self.alpha[(i, k)];
            }
        }
        out
    }

    /// Predicts every row of `x` (n x p, volts): the distances to the support as matrix
    /// products, then the kernel times alpha as another (one core), a block of rows at a time
    /// ([`row_blocks`]: the n x m kernel at once took 48 kB a row).
    #[must_use]
    pub fn predict_many(&self, x: &DMatrix<f64>) -> Vec<Target3> {
        let mut out = Vec::with_capacity(x.nrows());
        for (start, rows) in row_blocks(x.nrows(), self.support.nrows()) {
            let mut k = self.distances(&x.rows(start, rows).into_owned());
            gaussian_in_place(&mut k, self.gamma);
            out.extend(self.kernel_times_alpha(&k));
        }
        out
    }

    /// The rows of the support (m).
    #[must_use]
    pub fn support_rows(&self) -> usize {
        self.support.nrows()
    }

    /// Squared z-space distances from the rows of `x` (n x p, volts) to the support, n x m.
    /// Every fit of [`fit_grid`](Self::fit_grid) shares them: compute once, predict many.
    pub(crate) fn distances(&self, x: &DMatrix<f64>) -> Mat<f64> {
        squared_distances(&z_space(x, &self.mean, &self.scale), &self.support)
    }

    /// Predictions from [`distances`](Self::distances).
    pub(crate) fn predict_from_distances(&self, d2: &Mat<f64>) -> Vec<Target3> {
        let mut k = d2.clone();
        gaussian_in_place(&mut k, self.gamma);
        self.kernel_times_alpha(&k)
    }

    /// The predictions from the kernel matrix k (n x m) between n rows and the support.
    fn kernel_times_alpha(&self, k: &Mat<f64>) -> Vec<Target3> {
        let mut out = Mat::<f64>::zeros(k.nrows(), 3);
        matmul(
            out.as_mut(),
            Accum::Replace,
            k.as_ref(),
            self.alpha.as_ref(),
            1.0,
            Par::Seq,
        );
        (0..k.nrows())
            .map(|r| std::array::from_fn(|c| out[(r, c)] + self.intercept[c]))
            .collect()
    }

    /// Multiply-adds per prediction (distances, then the weighted sum), ignoring the exp.
    #[must_use]
    pub fn cost(&self) -> usize {
        self.support.nrows() * (self.support.ncols() + 3)
    }
}

/// Posterior-weighted class centre: sum_c w_c centre_c with w the softmax of the model's
/// discriminants divided by `temperature` (1 = the posteriors P(c | x); larger spreads the
/// weight over neighbouring cells), in the units of `centres`.
#[must_use]
pub fn posterior_centre(
    model: &Fitted,
    x: &[f64],
    centres: &[[f64; 2]],
    temperature: f64,
) -> [f64; 2] {
    let d = model.discriminants(x);
    let top = d.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let t = if temperature > 0.0 { temperature } else { 1.0 };
    let w: Vec<f64> = d.iter().map(|v| ((v - top) / t).exp()).collect();
    let total: f64 = w.iter().sum();
    let mut p = [0.0; 2];
    for (wc, c) in w.iter().zip(centres) {
        p[0] += wc / total * c[0];
        p[1] += wc / total * c[1];
    }
    p
}

/// The temperature of [`posterior_centre`] with the smallest mean position error on a
/// validation set (`x` rows, true positions in the centres' units), from `candidates`. Choose it on data the
/// test never sees.
#[must_use]
pub fn choose_temperature(
    model: &Fitted,
    x: &DMatrix<f64>,
    truth: &[[f64; 2]],
    centres: &[[f64; 2]],
    candidates: &[f64],
) -> f64 {
    let rows: Vec<Vec<f64>> = x.row_iter().map(|r| r.iter().copied().collect()).collect();
    let err = |t: f64| {
        rows.iter()
            .zip(truth)
            .map(|(r, p)| {
                let q = posterior_centre(model, r, centres, t);
                (q[0] - p[0]).hypot(q[1] - p[1])
            })
            .sum::<f64>()
    };
    candidates
        .iter()
        .copied()
        .map(|t| (t, err(t)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(1.0, |(t, _)| t)
}

/// Touch intensity from the size of the touch's signature, calibrated per class: pressure
/// (kPa) = a_c + b_c u + c_c u^2 with u = ln |x| (x referenced features, volts), fitted by
/// least squares on each class's observations. Three numbers per class on the chip.
#[derive(Clone, Debug)]
pub struct IntensityByClass {
    /// Per class (a, b, c).
    pub coefficients: Vec<[f64; 3]>,
}

impl IntensityByClass {
    /// Fits per class; a class with fewer than 3 observations, or a singular fit, takes the
    /// pooled fit.
    ///
    /// # Errors
    /// [`FitError::Counts`] for mismatched lengths, [`FitError::Label`] for a label out of range, [`FitError::NotPositiveDefinite`]
    /// when even the pooled fit is singular (all signatures the same size).
    pub fn fit(
        x: &DMatrix<f64>,
        y: &[u16],
        pressure_kpa: &[f64],
        classes: usize,
    ) -> Result<Self, FitError> {
        for (what, got) in [("labels", y.len()), ("pressures", pressure_kpa.len())] {
            if got != x.nrows() {
                return Err(FitError::Counts {
                    what,
                    got,
                    expected: x.nrows(),
                    of: "rows",
                });
            }
        }
        let u: Vec<f64> = x.row_iter().map(|r| r.norm().max(1e-300).ln()).collect();
        let solve = |rows: &[usize]| -> Option<[f64; 3]> {
            let mut a = nalgebra::Matrix3::<f64>::zeros();
            let mut b = nalgebra::Vector3::<f64>::zeros();
            for &r in rows {
                let f = nalgebra::Vector3::new(1.0, u[r], u[r] * u[r]);
                a += f * f.transpose();
                b += f * pressure_kpa[r];
            }
            let s = a.cholesky()?.solve(&b);
            s.iter().all(|v| v.is_finite()).then(|| [s[0], s[1], s[2]])
        };
        let all: Vec<usize> = (0..y.len()).collect();
        let pooled = solve(&all).ok_or(FitError::NotPositiveDefinite { class: 0 })?;
        let mut coefficients = vec![pooled; classes];
        for (c, k) in coefficients.iter_mut().enumerate() {
            let rows: Vec<usize> = all
                .iter()
                .copied()
                .filter(|&r| usize::from(y[r]) == c)
                .collect();
            if rows.len() >= 3
                && let Some(s) = solve(&rows)
            {
                *k = s;
            }
        }
        if let Some(r) = y.iter().position(|&c| usize::from(c) >= classes) {
            return Err(FitError::Label {
                row: r,
                label: usize::from(y[r]),
                classes,
            });
        }
        Ok(Self { coefficients })
    }

    /// Pressure (kPa) of referenced features `x` pressed at class `class`.
    #[must_use]
    pub fn predict(&self, x: &[f64], class: u16) -> f64 {
        let u = x.iter().map(|v| v * v).sum::<f64>().sqrt().max(1e-300).ln();
        let [a, b, c] = self.coefficients[usize::from(class).min(self.coefficients.len() - 1)];
        a + b * u + c * u * u
    }
}

mod kernel_cost;
mod kernel_exp;
mod knn;
mod summary;
pub use knn::*;
pub use summary::*;
