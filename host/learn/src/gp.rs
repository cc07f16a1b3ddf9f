//! Gaussian-process regression with one learned length scale per feature (automatic relevance
//! determination): the non-linear regressor that learns its features' weights from the data.
//!
//! The prior on the map from standardised features z (p of them) to a target is a Gaussian
//! process with covariance
//!
//! ```text
//! k(z, z') = s² exp(-½ Σ_l (z_l - z'_l)² / ℓ_l²) + σ² δ(z, z')
//! ```
//!
//! The p length scales ℓ_l, the signal variance s² and the noise variance σ² are found by
//! maximising the log marginal likelihood of the training positions (x and y, each
//! standardised; both share the kernel) with L-BFGS on their logarithms. A feature whose
//! length scale grows large stops mattering: that is the learning of features the isotropic
//! [`KernelRidge`] cannot do. The prediction is then the posterior mean, which is kernel ridge
//! in the length-scaled space, so the fitted model *is* a [`KernelRidge`] (per-feature
//! scales, gamma = ½, alpha times s²) and predicts exactly as fast.
//!
//! Costs on n learning rows and p features, per likelihood evaluation: the Cholesky factor
//! (n³/3), the inverse (n³) and two n x n x p products. The learning runs on at most
//! [`GpOptions::learn_rows`] rows spread evenly over the training rows; the final fit on at
//! most [`GpOptions::support`].
//!
//! Reference: C. E. Rasmussen and C. K. I. Williams, *Gaussian Processes for Machine Learning*,
//! MIT Press 2006, §5.4 (the marginal likelihood and its gradient, eq. 5.9).

use faer::linalg::matmul::matmul;
use faer::linalg::solvers::{DenseSolveCore, SolveCore};
use faer::{Accum, Mat, Par, Side};
use nalgebra::DMatrix;

use super::fit::{FitError, standardisation};
use super::regress::{
    KernelRidge, Target3, check, gaussian_in_place, median_pair, squared_distances, target_mean,
    z_space,
};

/// How much work the Gaussian process does.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpOptions {
    /// Rows the hyperparameters are learned on (spread evenly over the training rows).
    pub learn_rows: usize,
    /// Rows the final model keeps as its support.
    pub support: usize,
    /// L-BFGS iterations at most.
    pub iterations: usize,
}

impl GpOptions {
    /// 1 000 learning rows, 60 iterations and a support of 3 000: on the 2 000 x 192 stand-in,
    /// the middle of the budgets measured (docs/measurements.md, example `gp_budget`): more
    /// learning rows help a little at three times the time.
    pub const DEFAULT: Self = Self {
        learn_rows: 1_000,
        support: 3_000,
        iterations: 60,
    };
}

impl Default for GpOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// A fitted Gaussian process.
#[derive(Clone, Debug)]
pub struct Gp {
    /// ℓ_l per feature, in standardised units (one is a feature's standard deviation).
    pub length_scales: Vec<f64>,
    /// s², in units of the standardised positions' variance.
    pub signal_variance: f64,
    /// σ², likewise.
    pub noise_variance: f64,
    /// The negative log marginal likelihood reached (per learning row, up to a constant).
    pub nll_per_row: f64,
    /// L-BFGS iterations taken.
    pub iterations: usize,
    /// The posterior mean as kernel ridge in the length-scaled space.
    pub predictor: KernelRidge,
}

impl Gp {
    /// Learns the hyperparameters on the rows of `x` (n x p, any units) and their targets,
    /// then fits the posterior mean. `progress(done, of)` is called after every iteration.
    ///
    /// # Errors
    /// [`FitError`] for mismatched or non-finite data, or when no kernel matrix could be
    /// factored (the data has fewer than two distinct rows).
    pub fn fit(
        x: &DMatrix<f64>,
        t: &[Target3],
        opts: &GpOptions,
        progress: &mut dyn FnMut(usize, usize),
    ) -> Result<Self, FitError> {
        check(x, t)?;
        let (n, p) = (x.nrows(), x.ncols());
        let (mean, scale) = standardisation(x);
        let spread = |m: usize| -> Vec<usize> {
            let m = m.clamp(2, n);
            (0..m).map(|i| i * n / m).collect()
        };
        // The learning rows and their standardised positions (x, y: the third target, often
        // a noisy pressure, would inflate the shared noise variance and blur the positions).
        let rows = spread(opts.learn_rows);
        let z = z_space(&x.select_rows(&rows), &mean, &scale);
        let ts: Vec<Target3> = rows.iter().map(|&r| t[r]).collect();
        let centre = target_mean(&ts);
        let spread_of = |c: usize| {
            let v = ts.iter().map(|r| (r[c] - centre[c]).powi(2)).sum::<f64>() / ts.len() as f64;
            if v.sqrt() > 1e-12 { v.sqrt() } else { 1.0 }
        };
        let sd = [spread_of(0), spread_of(1)];
        let u = Mat::from_fn(rows.len(), 2, |r, c| (ts[r][c] - centre[c]) / sd[c]);

        // Start isotropic at kernel ridge's middle width (exp(-d²/median)), s² = 1, σ² = 1e-2.
        let median = median_pair(&squared_distances(&z, &z));
        let mut theta = vec![0.5 * (median / 2.0).ln(); p];
        theta.extend([0.0, (1e-2f64).ln()]);
        let (mut lo, mut hi) = (vec![-3.0; p], vec![12.0; p]);
        lo.extend([-7.0, -14.0]);
        hi.extend([5.0, 1.0]);
        let objective = |th: &[f64]| nll_and_gradient(&z, &u, th);
        let (theta, nll, iterations) =
            minimise(objective, theta, &lo, &hi, opts.iterations, progress).ok_or(
                FitError::Numerics("no kernel matrix of these rows could be factored"),
            )?;

        let length_scales: Vec<f64> = theta[..p].iter().map(|v| v.exp()).collect();
        let (signal_variance, noise_variance) = (theta[p].exp(), theta[p + 1].exp());
        // The posterior mean on the support rows, in the targets' own units.
        let rows = spread(opts.support);
        let scaled: Vec<f64> = scale
            .iter()
            .zip(&length_scales)
            .map(|(s, l)| s * l)
            .collect();
        let support = z_space(&x.select_rows(&rows), &mean, &scaled);
        let ts: Vec<Target3> = rows.iter().map(|&r| t[r]).collect();
        let intercept = target_mean(&ts);
        let m = rows.len();
        let mut k = squared_distances(&support, &support);
        gaussian_in_place(&mut k, 0.5);
        scale_in_place(&mut k, signal_variance);
        for i in 0..m {
            k[(i, i)] += noise_variance;
        }
        let mut alpha = Mat::from_fn(m, 3, |r, c| ts[r][c] - intercept[c]);
        let llt = k.llt(Side::Lower).map_err(|_| {
            FitError::Numerics("the learned kernel matrix is not positive definite")
        })?;
        llt.solve_in_place_with_conj(faer::Conj::No, alpha.as_mut());
        for v in alpha.col_iter_mut().flat_map(|c| c.iter_mut()) {
            *v *= signal_variance;
        }
        if (0..m).any(|r| (0..3).any(|c| !alpha[(r, c)].is_finite())) {
            return Err(FitError::Numerics("the posterior mean is not finite"));
        }
        Ok(Self {
            length_scales,
            signal_variance,
            noise_variance,
            nll_per_row: nll / rows.len().max(1) as f64,
            iterations,
            predictor: KernelRidge {
                mean,
                scale: scaled,
                support,
                alpha,
                gamma: 0.5,
                intercept,
            },
        })
    }

    /// Seconds `fits` fits on rows like `x` (n x p) will take, from one timed likelihood
    /// evaluation on as many learning rows (the time does not depend on the values): each
    /// iteration costs about 1.2 evaluations.
    #[must_use]
    pub fn estimate_seconds(x: &DMatrix<f64>, opts: &GpOptions, fits: usize) -> f64 {
        let (n, p) = (opts.learn_rows.clamp(2, x.nrows().max(2)), x.ncols());
        let z = Mat::from_fn(n, p, |i, j| ((i * 31 + j * 17) % 97) as f64 / 97.0);
        let u = Mat::from_fn(n, 2, |i, c| ((i * 7 + c) % 13) as f64 / 13.0);
        let mut theta = vec![0.5 * (p as f64).ln(); p];
        theta.extend([0.0, (1e-2f64).ln()]);
        let started = std::time::Instant::now();
        let _ = nll_and_gradient(&z, &u, &theta);
        started.elapsed().as_secs_f64() * 1.2 * opts.iterations as f64 * fits as f64
    }

    /// Predicts every row of `x` (n x p, the training units).
    #[must_use]
    pub fn predict_many(&self, x: &DMatrix<f64>) -> Vec<Target3> {
        self.predictor.predict_many(x)
    }
}

/// The negative log marginal likelihood of the standardised targets `u` (n x q, independent
/// outputs sharing the kernel) given rows `z` (n x p) and θ = (ln ℓ_1..p, ln s², ln σ²), up
/// to the constant, and its gradient in θ; `None` when the kernel matrix cannot be factored.
///
/// With K = K_f + σ² I, α = K⁻¹ u and W = α αᵀ - q K⁻¹ (Rasmussen & Williams eq. 5.9):
/// nll = ½ tr(uᵀ α) + q Σ ln L_ii, and ∂nll/∂θ = -½ tr(W ∂K/∂θ), where ∂K/∂ln ℓ_l =
/// K_f ∘ D_l with D_l,ij = (a_il - a_jl)² in the length-scaled rows a = z / ℓ, so that with
/// M = W ∘ K_f the p traces are 2 Σ_i a_il² (M 1)_i - 2 Σ_i a_il (M a)_il: two products.
#[must_use]
pub fn nll_and_gradient(z: &Mat<f64>, u: &Mat<f64>, theta: &[f64]) -> Option<(f64, Vec<f64>)> {
    let (n, p, q) = (z.nrows(), z.ncols(), u.ncols());
    let (s2, noise) = (theta[p].exp(), theta[p + 1].exp());
    let a = Mat::from_fn(n, p, |i, l| z[(i, l)] / theta[l].exp());
    let mut kf = squared_distances(&a, &a);
    gaussian_in_place(&mut kf, 0.5);
    scale_in_place(&mut kf, s2);
    let mut k = kf.clone();
    for i in 0..n {
        k[(i, i)] += noise;
    }
    let llt = k.llt(Side::Lower).ok()?;
    let mut alpha = u.clone();
    llt.solve_in_place_with_conj(faer::Conj::No, alpha.as_mut());
    let l = llt.L();
    let log_det: f64 = (0..n).map(|i| l[(i, i)].ln()).sum();
    let fit: f64 = (0..q)
        .map(|c| (0..n).map(|i| u[(i, c)] * alpha[(i, c)]).sum::<f64>())
        .sum();
    let nll = 0.5 * fit + q as f64 * log_det;
    // W = α αᵀ - q K⁻¹, then M = W ∘ K_f.
    let mut w = llt.inverse();
    for v in w.col_iter_mut().flat_map(|c| c.iter_mut()) {
        *v *= -(q as f64);
    }
    matmul(
        w.as_mut(),
        Accum::Add,
        alpha.as_ref(),
        alpha.transpose(),
        1.0,
        Par::Seq,
    );
    let trace_w: f64 = (0..n).map(|i| w[(i, i)]).sum();
    let m = Mat::from_fn(n, n, |i, j| w[(i, j)] * kf[(i, j)]);
    let sum_wk: f64 = m.col_iter().flat_map(|c| c.iter().copied()).sum();
    let mut ma = Mat::<f64>::zeros(n, p);
    matmul(
        ma.as_mut(),
        Accum::Replace,
        m.as_ref(),
        a.as_ref(),
        1.0,
        Par::Seq,
    );
    let row_sums: Vec<f64> = (0..n).map(|i| (0..n).map(|j| m[(i, j)]).sum()).collect();
    let mut gradient: Vec<f64> = (0..p)
        .map(|l| {
            let t: f64 = (0..n)
                .map(|i| a[(i, l)] * (a[(i, l)] * row_sums[i] - ma[(i, l)]))
                .sum();
            -t
        })
        .collect();
    gradient.push(-0.5 * sum_wk);
    gradient.push(-0.5 * noise * trace_w);
    (nll.is_finite() && gradient.iter().all(|g| g.is_finite())).then_some((nll, gradient))
}

/// Minimises `f` (value and gradient, `None` where undefined) from `x` inside the box
/// [`lo`, `hi`] with L-BFGS (ten correction pairs, backtracking line search, steps projected
/// onto the box). Returns the point, its value and the iterations taken; `None` when `f` is
/// undefined at the start.
pub fn minimise(
    mut f: impl FnMut(&[f64]) -> Option<(f64, Vec<f64>)>,
    mut x: Vec<f64>,
    lo: &[f64],
    hi: &[f64],
    iterations: usize,
    progress: &mut dyn FnMut(usize, usize),
) -> Option<(Vec<f64>, f64, usize)> {
    const MEMORY: usize = 10;
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(u, v)| u * v).sum::<f64>();
    let project = |v: &mut Vec<f64>| {
        for ((x, l), h) in v.iter_mut().zip(lo).zip(hi) {
            *x = x.clamp(*l, *h);
        }
    };
    project(&mut x);
    let (mut fx, mut g) = f(&x)?;
    let mut pairs: std::collections::VecDeque<(Vec<f64>, Vec<f64>, f64)> =
        std::collections::VecDeque::new();
    let mut taken = 0;
    progress(0, iterations);
    while taken < iterations {
        // Coordinates held at a bound by their gradient stay out of the step.
        let free: Vec<bool> = (0..x.len())
            .map(|i| !((x[i] <= lo[i] && g[i] > 0.0) || (x[i] >= hi[i] && g[i] < 0.0)))
            .collect();
        let free_gradient: Vec<f64> = g
            .iter()
            .zip(&free)
            .map(|(v, &f)| if f { *v } else { 0.0 })
            .collect();
        // The two-loop recursion: d = -H g on the free coordinates.
        let mut d: Vec<f64> = free_gradient.iter().map(|v| -v).collect();
        let mut coefficients = Vec::with_capacity(pairs.len());
        for (s, y, rho) in pairs.iter().rev() {
            let c = rho * dot(s, &d);
            for (di, yi) in d.iter_mut().zip(y) {
                *di -= c * yi;
            }
            coefficients.push(c);
        }
        let gamma = pairs
            .back()
            .map_or(1.0 / dot(&g, &g).sqrt().max(1e-12), |(s, y, _)| {
                dot(s, y) / dot(y, y)
            });
        for v in &mut d {
            *v *= gamma;
        }
        for ((s, y, rho), c) in pairs.iter().zip(coefficients.iter().rev()) {
            let b = rho * dot(y, &d);
            for (di, si) in d.iter_mut().zip(s) {
                *di += (c - b) * si;
            }
        }
        for (di, &f) in d.iter_mut().zip(&free) {
            if !f {
                *di = 0.0;
            }
        }
        if dot(&d, &g) >= 0.0 {
            // Not a descent direction (curvature lost): restart from steepest descent.
            pairs.clear();
            d = free_gradient.iter().map(|v| -v).collect();
        }
        // Backtracking with the projected step.
        let mut step = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let mut trial: Vec<f64> = x.iter().zip(&d).map(|(a, b)| a + step * b).collect();
            project(&mut trial);
            let moved: Vec<f64> = trial.iter().zip(&x).map(|(a, b)| a - b).collect();
            if let Some((ft, gt)) = f(&trial)
                && ft <= fx + 1e-4 * dot(&g, &moved)
            {
                accepted = Some((trial, ft, gt, moved));
                break;
            }
            step *= 0.5;
        }
        let Some((trial, ft, gt, moved)) = accepted else {
            break;
        };
        let y: Vec<f64> = gt.iter().zip(&g).map(|(a, b)| a - b).collect();
        let sy = dot(&moved, &y);
        if sy > 1e-10 {
            if pairs.len() == MEMORY {
                pairs.pop_front();
            }
            pairs.push_back((moved, y, 1.0 / sy));
        }
        let decrease = fx - ft;
        x = trial;
        fx = ft;
        g = gt;
        taken += 1;
        progress(taken, iterations);
        if decrease.abs() <= 1e-10 * fx.abs().max(1.0) {
            break;
        }
    }
    progress(iterations, iterations);
    Some((x, fx, taken))
}

/// Every entry of `m` times `s`.
fn scale_in_place(m: &mut Mat<f64>, s: f64) {
    for j in 0..m.ncols() {
        m.col_mut(j).iter_mut().for_each(|v| *v *= s);
    }
}
