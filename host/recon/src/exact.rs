//! Exact solutions of the disc, the references the finite elements are measured against
//! (never used to image): point electrodes in closed form, and the complete electrode model
//! as a Fourier series solved by Galerkin's method on the boundary.
//!
//! Both are for a disc of radius `radius` (m), uniform sheet conductivity `sigma` (S per
//! square) and electrodes at angles `angles` (rad, counter-clockwise from +x). With the
//! potential u = a_0 + sum_n r^n (a_n cos n theta + b_n sin n theta) inside (harmonic), the
//! complete electrode model's boundary conditions (docs/method.md (5.1)-(5.2)) become, on the
//! unit disc with the dimensionless contact zeta = z sigma / radius:
//!
//! ```text
//! u_r + chi (u - U_l) / zeta = 0 on electrode l, u_r = 0 between,
//! integral over electrode l of (U_l - u) / zeta = I_l / sigma,
//! ```
//!
//! tested against cos m theta and sin m theta (m = 1..N) they give a symmetric positive
//! definite system in (a_1.., b_1.., U) once a_0 = 0 grounds it (a constant shift of u and U
//! leaves the equations unchanged, and frames are differences). Every integral over an
//! electrode's arc is in closed form. The truncation error falls as N grows
//! ([`cem_disc`]'s test measures it); N = 2 000 modes is far below a finite-element error.

use et_core::protocol::{Protocol, ProtocolKind};
use faer::linalg::solvers::SolveCore;
use faer::{Mat, Side};

use crate::fem::{Electrodes, Forward};
use crate::mesh::Mesh;

/// The potential of electrode pairs on a disc with point electrodes: for a unit current in at
/// `source` and out at `sink` (points on the circle, m) on a disc of conductivity `sigma`
/// (S/sq), the potential at `x` (on the circle, not at an electrode) up to a constant:
/// u(x) = ln(|x - sink| / |x - source|) / (pi sigma).
#[must_use]
pub fn point_disc(x: [f64; 2], source: [f64; 2], sink: [f64; 2], sigma: f64) -> f64 {
    let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    (d(x, sink) / d(x, source)).ln() / (std::f64::consts::PI * sigma)
}

/// int_alpha^beta cos(k t) dt.
fn int_cos(k: f64, a: f64, b: f64) -> f64 {
    if k == 0.0 {
        b - a
    } else {
        ((k * b).sin() - (k * a).sin()) / k
    }
}

/// int_alpha^beta sin(k t) dt.
fn int_sin(k: f64, a: f64, b: f64) -> f64 {
    if k == 0.0 {
        0.0
    } else {
        ((k * a).cos() - (k * b).cos()) / k
    }
}

/// The complete electrode model on a disc: the electrode potentials (L values, V, summing to
/// 0) for each current pattern (columns of `currents`, L x m, A, each summing to 0), with
/// electrodes centred at `angles` (rad) of angular width `width` (m of arc) each, contact
/// impedance `z` (ohm m), on a disc of `radius` (m) and conductivity `sigma` (S/sq), with
/// `modes` Fourier modes. `None` if the system cannot be factorised (overlapping electrodes,
/// z <= 0).
#[must_use]
pub fn cem_disc(
    angles: &[f64],
    width: f64,
    z: f64,
    radius: f64,
    sigma: f64,
    currents: &nalgebra::DMatrix<f64>,
    modes: usize,
) -> Option<nalgebra::DMatrix<f64>> {
    let l = angles.len();
    let n = modes;
    let zeta = z * sigma / radius;
    let half = 0.5 * width / radius;
    let arcs: Vec<(f64, f64)> = angles.iter().map(|&c| (c - half, c + half)).collect();
    // Unknowns: a_1..a_N (0..N), b_1..b_N (N..2N), U_0..U_{L-1} (2N..2N+L).
    let size = 2 * n + l;
    let mut a = Mat::<f64>::zeros(size, size);
    // Which trig function each of the first 2N unknowns carries: (order, is_cos).
    let basis = |i: usize| {
        if i < n {
            (i + 1, true)
        } else {
            (i - n + 1, false)
        }
    };
    // Over all electrodes together: C[k] = sum_l int_{e_l} cos k t, S[k] likewise (k <= 2N),
    // so every product integral is a table lookup.
    let (mut cs, mut ss) = (vec![0.0; 2 * n + 2], vec![0.0; 2 * n + 2]);
    for &(s, t) in &arcs {
        for k in 0..cs.len() {
            cs[k] += int_cos(k as f64, s, t);
            ss[k] += int_sin(k as f64, s, t);
        }
    }
    let c_at = |k: i64| cs[k.unsigned_abs() as usize];
    let s_at = |k: i64| k.signum() as f64 * ss[k.unsigned_abs() as usize];
    let product = |i: usize, j: usize| {
        let ((p, ci), (q, cj)) = (basis(i), basis(j));
        let (p, q) = (p as i64, q as i64);
        match (ci, cj) {
            (true, true) => 0.5 * (c_at(p - q) + c_at(p + q)),
            (false, false) => 0.5 * (c_at(p - q) - c_at(p + q)),
            (false, true) => 0.5 * (s_at(p + q) + s_at(p - q)),
            (true, false) => 0.5 * (s_at(q + p) + s_at(q - p)),
        }
    };
    let single = |i: usize, (s, t): (f64, f64)| {
        let (p, c) = basis(i);
        if c {
            int_cos(p as f64, s, t)
        } else {
            int_sin(p as f64, s, t)
        }
    };
    for i in 0..2 * n {
        // int_0^2pi u_r phi_i = pi m (a_m or b_m).
        a[(i, i)] += std::f64::consts::PI * basis(i).0 as f64;
        for j in 0..=i {
            let v = product(i, j) / zeta;
            a[(i, j)] += v;
            if i != j {
                a[(j, i)] += v;
            }
        }
        for (e, &arc) in arcs.iter().enumerate() {
            let v = -single(i, arc) / zeta;
            a[(i, 2 * n + e)] = v;
            a[(2 * n + e, i)] = v;
        }
    }
    for (e, &(s, t)) in arcs.iter().enumerate() {
        a[(2 * n + e, 2 * n + e)] = (t - s) / zeta;
    }
    // The electrode equations' right-hand side: (int (U_l - u) / zeta) = I_l / sigma (a_0 = 0).
    let llt = a.llt(Side::Lower).ok()?;
    let m = currents.ncols();
    let mut rhs = Mat::<f64>::zeros(size, m);
    for c in 0..m {
        for e in 0..l {
            rhs[(2 * n + e, c)] = currents[(e, c)] / sigma;
        }
    }
    llt.solve_in_place_with_conj(faer::Conj::No, rhs.as_mut());
    let mut u = nalgebra::DMatrix::from_fn(l, m, |e, c| rhs[(2 * n + e, c)]);
    for mut col in u.column_iter_mut() {
        let mean = col.mean();
        col.add_scalar_mut(-mean);
    }
    u.iter().all(|v| v.is_finite()).then_some(u)
}

/// How far a finite-element frame is from the exact one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameError {
    /// The largest difference over the largest exact value.
    pub max: f64,
    /// The relative L2 error: |V_h - V| / |V| over the frame's values.
    pub l2: f64,
    /// Triangles in the mesh.
    pub triangles: usize,
}

impl FrameError {
    /// Both norms of `frame`'s difference from `exact`.
    #[must_use]
    pub fn of(frame: &[f64], exact: &[f64], triangles: usize) -> Self {
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|x| x * x).sum::<f64>().sqrt();
        let diff = || frame.iter().zip(exact).map(|(a, b)| a - b);
        let largest = |v: &mut dyn Iterator<Item = f64>| v.fold(0.0f64, |m, x| m.max(x.abs()));
        Self {
            max: largest(&mut diff()) / largest(&mut exact.iter().copied()),
            l2: norm(&mut diff()) / norm(&mut exact.iter().copied()),
            triangles,
        }
    }
}

/// The error of the adjacent frame of electrode model `model` on the unit disc (16
/// electrodes of width 0.1, contact 0.05 ohm m, sigma = 1, 1 A), meshed to about
/// `triangles`, against the exact solution (this module: the point model in closed form,
/// the complete model as a Fourier series extrapolated in its modes).
///
/// `None` if a mesh, forward model or series cannot be made (it can for the defaults).
#[must_use]
pub fn unit_disc_error(
    model: et_core::sheet::ElectrodeModel,
    triangles: usize,
) -> Option<FrameError> {
    let mut spec = et_core::sheet::Sheet::rectangle(1.0, 1.0, 16);
    spec.shape = et_core::sheet::shape::Shape::Disc { radius: 1.0 };
    spec.electrodes.width = 0.1;
    spec.sheet_resistance = 1.0;
    spec.electrodes.contact_ohm = 0.5;
    spec.electrodes.model = model;
    let mesh = Mesh::with_about(&spec, triangles).ok()?;
    let n = mesh.triangles.len();
    let centres: Vec<[f64; 2]> = spec
        .electrodes
        .arc_positions(&spec.shape)
        .iter()
        .map(|&t| spec.shape.boundary_point(t))
        .collect();
    let fwd = Forward::new(mesh, Electrodes::of_sheet(&spec).ok()?).ok()?;
    let schedule = Protocol::new(ProtocolKind::Adjacent, 16)
        .ok()?
        .schedule(1.0)
        .ok()?;
    let v = fwd.frame(&vec![1.0; n], &schedule).ok()?;
    let at = |e: u16| centres[usize::from(e)];
    let exact: Vec<f64> = match model {
        et_core::sheet::ElectrodeModel::Point => schedule
            .rows()
            .iter()
            .map(|r| {
                let (a, b) = (at(r.source), at(r.sink));
                point_disc(at(r.positive), a, b, 1.0) - point_disc(at(r.negative), a, b, 1.0)
            })
            .collect(),
        _ => {
            let angles: Vec<f64> = centres.iter().map(|c| c[1].atan2(c[0])).collect();
            let currents = Forward::injection_currents(&schedule);
            // The series converges as modes^-2 (exact.rs's test): Richardson's extrapolation
            // of 500 and 1 000 modes removes its leading error.
            let series = |m| cem_disc(&angles, 0.1, 0.05, 1.0, 1.0, &currents, m);
            let (u1, u2) = (series(500)?, series(1_000)?);
            let u = &u2 + (&u2 - &u1) / 3.0;
            let (_, of_row) = schedule.injections();
            schedule
                .rows()
                .iter()
                .zip(of_row)
                .map(|(r, i)| u[(usize::from(r.positive), i)] - u[(usize::from(r.negative), i)])
                .collect()
        }
    };
    Some(FrameError::of(&v, &exact, n))
}
