//! Iterative Gauss-Newton, for when accuracy matters more than speed
//! (docs/method.md §6.4).

use nalgebra::DVector;

use crate::onestep::{DataSpace, ReconError};

/// Iterative Gauss-Newton for when accuracy matters more than speed. Minimises
/// |r(sigma)|^2 + lambda |sigma - sigma_0|^2_P, P = diag(J^T J)^s at each iterate, with the
/// residual r = dV - (F(sigma) - F(sigma_0)) for difference data (`dv` = V_1 - V_0: model
/// errors common to both frames cancel) or r = V - F(sigma) for absolute data
/// ([`Data::Absolute`]). Each step, in data-space form with d = sigma - sigma_0:
/// sigma += P^-1 J^T (J P^-1 J^T + lambda I)^-1 (r + J d) - d, the conductivity kept above
/// 1e-3 sigma_0. Returns the iterates' conductivities (per triangle) and residual norms.
///
/// # Errors
/// [`ReconError`] for bad parameters, or a failed forward solve.
pub fn gauss_newton(
    forward: &crate::fem::Forward,
    protocol: &et_core::protocol::Protocol,
    amps: f64,
    sigma_0: &[f64],
    data: Data<'_>,
    options: GaussNewton,
) -> Result<Vec<(Vec<f64>, f64)>, ReconError> {
    let GaussNewton {
        alpha,
        s,
        iterations,
    } = options;
    if !(alpha.is_finite() && alpha > 0.0 && (0.0..=1.0).contains(&s)) {
        return Err(ReconError::Parameter(format!(
            "alpha = {alpha} (> 0), s = {s} (in [0, 1])"
        )));
    }
    let fem = |e: crate::fem::FemError| ReconError::Parameter(e.to_string());
    // One factorisation per iterate: the Jacobian solve also gives the frame.
    let (v0, jac0) = forward.jacobian(sigma_0, protocol, amps).map_err(fem)?;
    let target: Vec<f64> = match data {
        Data::Difference(dv) => dv.iter().zip(&v0).map(|(d, v)| d + v).collect(),
        Data::Absolute(v) => v.to_vec(),
    };
    if target.len() != v0.len() {
        return Err(ReconError::Parameter(format!(
            "{} values, K = {}",
            target.len(),
            v0.len()
        )));
    }
    if target.iter().any(|v| !v.is_finite()) {
        return Err(ReconError::NonFinite);
    }
    // For difference data the model is F(sigma) - F(sigma_0) + V_0(measured); the
    // target above already is V_0(model) + dV, so both cases compare F(sigma) with target.
    let mut sigma = sigma_0.to_vec();
    let mut out = Vec::with_capacity(iterations);
    let (mut v, mut jac) = (v0, jac0);
    for it in 0..iterations {
        let r: Vec<f64> = target.iter().zip(&v).map(|(t, v)| t - v).collect();
        let d: Vec<f64> = sigma.iter().zip(sigma_0).map(|(a, b)| a - b).collect();
        let space = DataSpace::new(&jac, s)?;
        let rhs = DVector::from_vec(r) + &jac * DVector::from_column_slice(&d);
        let y = space.solve(alpha, rhs.as_slice())?;
        let step = space.back_project(&y);
        for (i, sg) in sigma.iter_mut().enumerate() {
            *sg = (sigma_0[i] + step[i]).max(1e-3 * sigma_0[i]);
        }
        // The next step needs the Jacobian here; the last one only the frame.
        if it + 1 < iterations {
            (v, jac) = forward.jacobian(&sigma, protocol, amps).map_err(fem)?;
        } else {
            v = forward.frame(&sigma, protocol, amps).map_err(fem)?;
        }
        let norm = target
            .iter()
            .zip(&v)
            .map(|(t, v)| (t - v).powi(2))
            .sum::<f64>()
            .sqrt();
        out.push((sigma.clone(), norm));
    }
    Ok(out)
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
