//! Iterative Gauss-Newton, for when accuracy matters more than speed
//! (docs/method.md §6.4).

use nalgebra::DVector;

use crate::onestep::{DataSpace, ReconError, check_alpha, check_s, noser_inverse};

/// Iterative Gauss-Newton for when accuracy matters more than speed. Minimises
/// Phi(sigma) = |r(sigma)|^2 + lambda |sigma - sigma_0|^2_P, with the prior P = diag(J_0^T
/// J_0)^s and lambda (normalised by alpha as [`crate::onestep`]) both of the background's
/// Jacobian J_0, so every iterate lowers one and the same objective; with the residual r = dV - (F(sigma) - F(sigma_0)) for difference data (`dv` =
/// V_1 - V_0: model errors common to both frames cancel) or r = V - F(sigma) for absolute
/// data ([`Data::Absolute`]). Each step, in data-space form with d = sigma - sigma_0:
/// sigma_full = sigma_0 + P^-1 J^T (J P^-1 J^T + lambda I)^-1 (r + J d), the conductivity kept
/// above 1e-3 sigma_0; then a backtracking line search takes the longest of the steps 1, 1/2,
/// 1/4, ... (at most [`LINE_SEARCH_HALVINGS`] halvings) towards sigma_full that lowers Phi, so
/// the objective never grows. When none does the fit stops ([`Stop::NoDescent`]) with the
/// iterates so far.
///
/// With `var_dv` (each channel's noise variance, V^2; empty when unknown) every iterate
/// carries the noise of each triangle's value, linearised at the step that made it
/// ([`OneStep::noise_sd`](crate::OneStep::noise_sd) of that step's reconstruction matrix).
///
/// # Errors
/// [`ReconError`] for bad parameters or a failed forward solve; [`ReconError::NoDescent`]
/// when even the first step cannot lower the objective (nothing was fitted).
pub fn gauss_newton(
    forward: &crate::fem::Forward,
    schedule: &et_core::schedule::Schedule,
    sigma_0: &[f64],
    data: Data<'_>,
    options: GaussNewton,
    var_dv: &[f64],
) -> Result<Fit, ReconError> {
    let GaussNewton {
        alpha,
        s,
        iterations,
    } = options;
    check_alpha(alpha)?;
    check_s(s)?;
    // One factorisation per iterate: the Jacobian solve also gives the frame.
    let (v0, jac0) = forward.jacobian(sigma_0, schedule)?;
    let target: Vec<f64> = match data {
        Data::Difference(dv) => dv.iter().zip(&v0).map(|(d, v)| d + v).collect(),
        Data::Absolute(v) => v.to_vec(),
    };
    if target.len() != v0.len() {
        return Err(ReconError::FrameLength {
            what: "the data",
            got: target.len(),
            k: v0.len(),
        });
    }
    if target.iter().any(|v| !v.is_finite()) {
        return Err(ReconError::NonFinite);
    }
    let residual = |v: &[f64]| -> Vec<f64> { target.iter().zip(v).map(|(t, v)| t - v).collect() };
    let norm2 = |r: &[f64]| r.iter().map(|x| x * x).sum::<f64>();
    // For difference data the model is F(sigma) - F(sigma_0) + V_0(measured); the
    // target above already is V_0(model) + dV, so both cases compare F(sigma) with target.
    let mut sigma = sigma_0.to_vec();
    let mut iterates = Vec::with_capacity(iterations);
    let (mut v, mut jac) = (v0, jac0);
    let mut stop = Stop::Iterations;
    // The background's prior and lambda, kept for every iterate.
    let p_inv = noser_inverse(&jac, s).ok_or(ReconError::Singular)?;
    // lambda = alpha^2 tr(J_0 P^-1 J_0^T) / K, the normalisation of `crate::onestep`.
    let trace: f64 = (0..jac.ncols())
        .map(|c| jac.column(c).norm_squared() * p_inv[c])
        .sum();
    let lambda = alpha * alpha * trace / jac.nrows() as f64;
    let prior = |sg: &[f64]| -> f64 {
        sg.iter()
            .zip(sigma_0)
            .zip(&p_inv)
            .map(|((a, b), w)| (a - b).powi(2) / w)
            .sum::<f64>()
    };
    for it in 0..iterations {
        let r = residual(&v);
        let d: Vec<f64> = sigma.iter().zip(sigma_0).map(|(a, b)| a - b).collect();
        if jac.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::Singular);
        }
        let space = DataSpace::with_prior(&jac, s, &p_inv);
        let phi_now = norm2(&r) + lambda * prior(&sigma);
        let rhs = DVector::from_vec(r) + &jac * DVector::from_column_slice(&d);
        let y = space.solve(lambda, rhs.as_slice())?;
        let full: Vec<f64> = space
            .back_project(&y)
            .iter()
            .zip(sigma_0)
            .map(|(st, s0)| (s0 + st).max(1e-3 * s0))
            .collect();
        // Backtracking: the longest step towards `full` that lowers Phi.
        let mut accepted = None;
        let mut t = 1.0;
        for _ in 0..=LINE_SEARCH_HALVINGS {
            let trial: Vec<f64> = sigma
                .iter()
                .zip(&full)
                .map(|(a, b)| a + t * (b - a))
                .collect();
            let v_trial = forward.frame(&trial, schedule)?;
            let phi = norm2(&residual(&v_trial)) + lambda * prior(&trial);
            if phi < phi_now {
                accepted = Some((trial, v_trial, phi));
                break;
            }
            t *= 0.5;
        }
        let Some((trial, v_trial, phi)) = accepted else {
            if it == 0 {
                return Err(ReconError::NoDescent { iteration: 0 });
            }
            stop = Stop::NoDescent { iteration: it };
            break;
        };
        let noise_sd = if var_dv.is_empty() {
            Vec::new()
        } else {
            space.at_lambda(lambda, alpha)?.noise_sd(var_dv)?
        };
        sigma = trial;
        v = v_trial;
        iterates.push(Iterate {
            residual: norm2(&residual(&v)).sqrt(),
            objective: phi,
            step: t,
            sigma: sigma.clone(),
            noise_sd,
        });
        // The next step needs the Jacobian here.
        if it + 1 < iterations {
            (v, jac) = forward.jacobian(&sigma, schedule)?;
        }
    }
    Ok(Fit { iterates, stop })
}

/// How many times the line search halves the step before it gives up.
pub const LINE_SEARCH_HALVINGS: usize = 12;

/// One iterate of [`gauss_newton`].
#[derive(Clone, Debug)]
pub struct Iterate {
    /// Conductivity per triangle, S per square.
    pub sigma: Vec<f64>,
    /// |target - F(sigma)|, V.
    pub residual: f64,
    /// Phi(sigma), V^2 (the background's prior and lambda: comparable across iterates).
    pub objective: f64,
    /// The step length the line search took (1: the full Gauss-Newton step).
    pub step: f64,
    /// Each triangle's noise, S per square (empty without noise variances).
    pub noise_sd: Vec<f64>,
}

/// Why [`gauss_newton`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stop {
    /// It ran the iterations asked for.
    Iterations,
    /// No step towards the next Gauss-Newton point lowered the objective at this iteration
    /// (0-based): the iterates so far are returned, the last the best.
    NoDescent {
        /// The iteration that found no descent.
        iteration: usize,
    },
}

/// The iterates of [`gauss_newton`] and why it stopped.
#[derive(Clone, Debug)]
pub struct Fit {
    /// One per completed iteration, each with a lower objective than the one before.
    pub iterates: Vec<Iterate>,
    /// Why it stopped.
    pub stop: Stop,
}

/// Settings of [`gauss_newton`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaussNewton {
    /// Regularisation, normalised as [`OneStep`]'s.
    pub alpha: f64,
    /// NOSER exponent in [0, 1].
    pub s: f64,
    /// Iterations.
    pub iterations: usize,
}

/// The data an iterative reconstruction fits.
#[derive(Clone, Copy, Debug)]
pub enum Data<'a> {
    /// V_1 - V_0 (difference imaging).
    Difference(&'a [f64]),
    /// V (absolute imaging: the model must match the hardware's absolute voltages).
    Absolute(&'a [f64]),
}
