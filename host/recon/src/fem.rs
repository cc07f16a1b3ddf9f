//! The forward model (docs/method.md §5): P1 finite elements on a [`Mesh`] with the complete electrode
//! model, or point electrodes, for a piecewise-constant sheet conductivity.
//!
//! Complete electrode model, unknowns u (nodes) and U (electrodes), with sheet conductivity
//! sigma (S per square, one value per triangle) and contact impedance z_l (ohm m, i.e. a
//! contact resistance R_l spread over the electrode's width w_l has z_l = R_l w_l):
//!
//! ```text
//! [ A_M + A_Z   A_W ] [u]   [0]     A_M[i,j] = sum_T sigma_T int_T grad phi_i . grad phi_j
//! [ A_W^T       A_D ] [U] = [I]     A_Z[i,j] = sum_l 1/z_l int_{e_l} phi_i phi_j
//!                                   A_W[i,l] = -1/z_l int_{e_l} phi_i,  A_D[l,l] = |e_l| / z_l
//! ```
//!
//! The last electrode is grounded (U_{L-1} = 0) to make the system positive definite, then all
//! potentials are shifted so that sum_l U_l = 0 (docs/method.md §5's reference). The point model injects
//! each electrode's current at its centre node and reads the potential there (ground: the
//! last electrode's node). One sparse Cholesky factorisation (faer, AMD ordering) serves every
//! injection. The sparsity pattern, its ordering and the symbolic factorisation are made once
//! in [`Forward::new`]; a solve at a new conductivity only fills in the values and redoes the
//! numeric factorisation (docs/design.md: "keep the symbolic step").

use et_core::schedule::Schedule;
use faer::Side;
use faer::linalg::solvers::SolveCore;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{Argsort, Pair, SparseColMat, SymbolicSparseColMat};
use nalgebra::DMatrix;

use crate::mesh::{Mesh, dist};
use et_core::sheet::ElectrodeModel;

mod error;
pub use error::FemError;

/// How electrodes meet the sheet.
#[derive(Clone, Debug, PartialEq)]
pub enum Electrodes {
    /// The complete electrode model with these contact impedances z_l, ohm m (one per
    /// electrode, > 0).
    Complete(Vec<f64>),
    /// Point electrodes at the electrodes' centre nodes.
    Point,
    /// The shunt model: perfectly conducting electrodes without contact resistance (every
    /// node under electrode l is at its potential U_l; current enters through the sheet at the
    /// electrode's edges). The complete model's limit z -> 0.
    Shunt,
}

impl Electrodes {
    /// The model a sheet asks for (`sheet.electrodes.model`), with the complete model's
    /// contact impedances z_l = contact resistance x width (ohm m).
    ///
    /// # Errors
    /// [`FemError::ContactTooSmall`] when the complete model's contact resistance is under
    /// [`MIN_CONTACT_RATIO`] of the sheet resistance: its system cannot be factorised
    /// accurately in f64 (the shunt model is that limit).
    pub fn of_sheet(spec: &et_core::sheet::Sheet) -> Result<Self, FemError> {
        let e = &spec.electrodes;
        Ok(match e.model {
            ElectrodeModel::Point => Electrodes::Point,
            ElectrodeModel::Shunt => Electrodes::Shunt,
            ElectrodeModel::Complete => {
                let ratio = e.contact_ohm / spec.sheet_resistance;
                if ratio.is_nan() || ratio < MIN_CONTACT_RATIO {
                    return Err(FemError::ContactTooSmall {
                        contact_ohm: e.contact_ohm,
                        sheet_ohm: spec.sheet_resistance,
                    });
                }
                Electrodes::Complete(vec![e.contact_ohm * e.width; usize::from(e.count)])
            }
        })
    }
}

/// The smallest contact resistance the complete electrode model takes, as a fraction of the
/// sheet resistance (ohm per square). There its frames differ from the shunt model's (the
/// limit of zero contact) by about 1e-7 of their size; below it the contact terms (1/z) swamp
/// the sheet's in the system matrix and round-off grows (1e-6 at 1e-9, a failed
/// factorisation at 1e-15: `the_shunt_model_is_the_complete_models_limit`), so the shunt
/// model is the accurate choice.
pub const MIN_CONTACT_RATIO: f64 = 1e-6;

/// Refuses contact impedances `z` unless there is one per electrode (`l`), each finite and
/// positive.
fn check_contacts(z: &[f64], l: usize) -> Result<(), FemError> {
    if z.len() != l {
        return Err(FemError::Count {
            what: "contact impedances",
            got: z.len(),
            expected: l,
            of: "electrodes",
        });
    }
    positive("contact impedance of electrode", z)
}

/// The index and value of the first of `values` that is not finite and positive.
pub(crate) fn first_not_positive(values: &[f64]) -> Option<(usize, f64)> {
    values
        .iter()
        .enumerate()
        .find(|(_, v)| !(v.is_finite() && **v > 0.0))
        .map(|(i, v)| (i, *v))
}

/// [`FemError::NotPositive`] for the first of `values` not finite and positive.
fn positive(what: &'static str, values: &[f64]) -> Result<(), FemError> {
    match first_not_positive(values) {
        Some((index, value)) => Err(FemError::NotPositive { what, index, value }),
        None => Ok(()),
    }
}

/// A failed factorisation, in words: the factoriser's own error is internal (a pivot's
/// index).
fn fail(_: impl std::fmt::Debug) -> FemError {
    FemError::Factorisation
}

/// Potentials for several current patterns.
#[derive(Clone, Debug)]
pub struct Solution {
    /// n x m node potentials, V (one column per pattern).
    pub nodes: DMatrix<f64>,
    /// L x m electrode potentials, V (sum over electrodes 0 in each column).
    pub electrodes: DMatrix<f64>,
}

/// Where one entry of the system matrix comes from.
#[derive(Clone, Copy, Debug)]
enum Entry {
    /// sigma_t times entry k of triangle t's unit stiffness.
    Stiffness { t: usize, k: usize },
    /// A contact term of electrode `e` (independent of sigma): `weight` / z_e, `weight` in m
    /// (its share of the electrode's edge length).
    Contact { e: usize, weight: f64 },
}

/// The system's sparsity, fixed per mesh and electrode model: its entries, their order in CSC
/// storage, and the symbolic Cholesky factorisation (AMD ordering, elimination tree).
#[derive(Clone, Debug)]
struct Pattern {
    entries: Vec<Entry>,
    symbolic: SymbolicSparseColMat<usize>,
    argsort: Argsort<usize>,
    llt: SymbolicLlt<usize>,
}

/// The forward operator of one mesh and electrode model.
#[derive(Clone, Debug)]
pub struct Forward {
    mesh: Mesh,
    electrodes: Electrodes,
    /// The grounded system's unknown of each node, then each electrode ([`unknowns`]).
    unknown: Vec<Option<usize>>,
    /// Unknowns of the grounded system.
    size: usize,
    /// Per triangle, the 3 x 3 stiffness of unit conductivity (row-major).
    local: Vec<[f64; 9]>,
    pattern: Pattern,
}

/// The unknown of each full index (nodes 0..n, then electrodes n..n+L) in the grounded
/// system, `None` for the grounded one, and the system's size. Complete model: every node and
/// electrode its own unknown, the last electrode grounded. Point model: an electrode is its
/// centre node's unknown, the last one grounded. Shunt model: the nodes under electrode l
/// are electrode l's unknown, the last electrode grounded.
fn unknowns(mesh: &Mesh, electrodes: &Electrodes) -> Result<(Vec<Option<usize>>, usize), FemError> {
    let (n, l) = (mesh.nodes.len(), mesh.electrodes.len());
    let mut owner: Vec<Option<usize>> = vec![None; n]; // electrode of a node (point, shunt)
    for e in 0..l {
        let nodes: Vec<usize> = match electrodes {
            Electrodes::Complete(_) => continue,
            Electrodes::Point => vec![mesh.centre_nodes[e]],
            Electrodes::Shunt => mesh.electrodes[e].iter().flatten().copied().collect(),
        };
        for i in nodes {
            match owner[i] {
                Some(other) if other != e => {
                    return Err(FemError::SharedNode {
                        node: i,
                        electrodes: [other, e],
                    });
                }
                _ => owner[i] = Some(e),
            }
        }
    }
    let mut map = vec![None; n + l];
    let mut next = 0;
    for (i, slot) in map.iter_mut().enumerate().take(n) {
        if owner[i].is_none() {
            *slot = Some(next);
            next += 1;
        }
    }
    for e in 0..l - 1 {
        map[n + e] = Some(next + e);
    }
    let size = next + l - 1;
    for i in 0..n {
        if let Some(e) = owner[i] {
            map[i] = map[n + e];
        }
    }
    Ok((map, size))
}

/// Every entry of the system matrix with its place, then the pattern and its symbolic
/// factorisation.
fn make_pattern(
    mesh: &Mesh,
    electrodes: &Electrodes,
    unknown: &[Option<usize>],
    size: usize,
) -> Result<Pattern, FemError> {
    let n = mesh.nodes.len();
    let mut places: Vec<Pair<usize, usize>> = Vec::with_capacity(9 * mesh.triangles.len());
    let mut entries = Vec::with_capacity(places.capacity());
    let mut put = |i: usize, j: usize, entry: Entry| {
        if let (Some(a), Some(b)) = (unknown[i], unknown[j]) {
            places.push(Pair::new(a, b));
            entries.push(entry);
        }
    };
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for i in 0..3 {
            for j in 0..3 {
                put(tri[i], tri[j], Entry::Stiffness { t, k: 3 * i + j });
            }
        }
    }
    if let Electrodes::Complete(_) = electrodes {
        for (e, edges) in mesh.electrodes.iter().enumerate() {
            for &[a, b] in edges {
                let len = dist(mesh.nodes[a], mesh.nodes[b]);
                let contact = |weight: f64| Entry::Contact { e, weight };
                put(a, a, contact(len / 3.0));
                put(b, b, contact(len / 3.0));
                put(a, b, contact(len / 6.0));
                put(b, a, contact(len / 6.0));
                for v in [a, b] {
                    put(v, n + e, contact(-len / 2.0));
                    put(n + e, v, contact(-len / 2.0));
                }
                put(n + e, n + e, contact(len));
            }
        }
    }
    let (symbolic, argsort) =
        SymbolicSparseColMat::try_new_from_indices(size, size, &places).map_err(fail)?;
    let llt = SymbolicLlt::try_new(symbolic.as_ref(), Side::Lower).map_err(fail)?;
    Ok(Pattern {
        entries,
        symbolic,
        argsort,
        llt,
    })
}

impl Forward {
    /// Prepares the forward model.
    ///
    /// # Errors
    /// [`FemError::Count`] or [`FemError::NotPositive`] for impedances of the wrong count or
    /// not finite and positive, [`FemError::Degenerate`] for a mesh with a degenerate
    /// triangle, and the electrodes' faults.
    pub fn new(mesh: Mesh, electrodes: Electrodes) -> Result<Self, FemError> {
        let l = mesh.electrodes.len();
        if let Electrodes::Complete(z) = &electrodes {
            check_contacts(z, l)?;
        }
        if l < 2 {
            return Err(FemError::TooFewElectrodes);
        }
        if !matches!(electrodes, Electrodes::Point)
            && let Some(e) = mesh.electrodes.iter().position(Vec::is_empty)
        {
            return Err(FemError::PointElectrode { electrode: e });
        }
        let local = (0..mesh.triangles.len())
            .map(|t| {
                let [a, b, c] = mesh.triangles[t].map(|i| mesh.nodes[i]);
                let area2 = mesh.double_area(t);
                if !(area2.is_finite() && area2 > 0.0) {
                    return Err(FemError::Degenerate { triangle: t });
                }
                // grad phi_k = (y_{k+1} - y_{k+2}, x_{k+2} - x_{k+1}) / (2 area).
                let p = [a, b, c];
                let g: Vec<[f64; 2]> = (0..3)
                    .map(|k| {
                        let (q, r) = (p[(k + 1) % 3], p[(k + 2) % 3]);
                        [(q[1] - r[1]) / area2, (r[0] - q[0]) / area2]
                    })
                    .collect();
                let mut m = [0.0; 9];
                for i in 0..3 {
                    for j in 0..3 {
                        m[3 * i + j] = 0.5 * area2 * (g[i][0] * g[j][0] + g[i][1] * g[j][1]);
                    }
                }
                Ok(m)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (unknown, size) = unknowns(&mesh, &electrodes)?;
        let pattern = make_pattern(&mesh, &electrodes, &unknown, size)?;
        Ok(Self {
            mesh,
            electrodes,
            unknown,
            size,
            local,
            pattern,
        })
    }

    /// Other contact impedances z_l (ohm m) for the complete model, keeping the mesh, the
    /// system's pattern and its symbolic factorisation (a background fit's search over the
    /// contact solves at many).
    ///
    /// # Errors
    /// [`FemError::NotComplete`] for another electrode model, [`FemError::Count`] or
    /// [`FemError::NotPositive`] for impedances of the wrong count or not finite and positive.
    pub fn set_contacts(&mut self, z: Vec<f64>) -> Result<(), FemError> {
        let l = self.mesh.electrodes.len();
        match &mut self.electrodes {
            Electrodes::Complete(old) => {
                check_contacts(&z, l)?;
                *old = z;
                Ok(())
            }
            _ => Err(FemError::NotComplete),
        }
    }

    /// The mesh.
    #[must_use]
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The electrode model.
    #[must_use]
    pub fn electrodes(&self) -> &Electrodes {
        &self.electrodes
    }

    /// Solves for the current patterns `currents` (L x m, A, each column summing to 0) at
    /// sheet conductivity `sigma` (S per square, one per triangle).
    ///
    /// # Errors
    /// [`FemError`] for bad input or a failed factorisation.
    pub fn solve(&self, sigma: &[f64], currents: &DMatrix<f64>) -> Result<Solution, FemError> {
        let (n, l) = (self.mesh.nodes.len(), self.mesh.electrodes.len());
        if sigma.len() != self.mesh.triangles.len() {
            return Err(FemError::Count {
                what: "conductivities",
                got: sigma.len(),
                expected: self.mesh.triangles.len(),
                of: "triangles",
            });
        }
        positive("conductivity of triangle", sigma)?;
        if currents.nrows() != l {
            return Err(FemError::Count {
                what: "rows of currents",
                got: currents.nrows(),
                expected: l,
                of: "electrodes",
            });
        }
        if currents.iter().any(|v| !v.is_finite()) {
            return Err(FemError::NonFiniteCurrent);
        }
        for (c, col) in currents.column_iter().enumerate() {
            let scale = col.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if col.sum().abs() > 1e-9 * scale.max(f64::MIN_POSITIVE) {
                return Err(FemError::Unbalanced { pattern: c });
            }
        }
        let size = self.size;
        let idx = |full: usize| self.unknown[full];
        let z: &[f64] = match &self.electrodes {
            Electrodes::Complete(z) => z,
            _ => &[],
        };
        let values: Vec<f64> = self
            .pattern
            .entries
            .iter()
            .map(|e| match *e {
                Entry::Stiffness { t, k } => sigma[t] * self.local[t][k],
                Entry::Contact { e, weight } => weight / z[e],
            })
            .collect();
        let a = SparseColMat::new_from_argsort(
            self.pattern.symbolic.clone(),
            &self.pattern.argsort,
            &values,
        )
        .map_err(fail)?;
        let llt = Llt::try_new_with_symbolic(self.pattern.llt.clone(), a.as_ref(), Side::Lower)
            .map_err(fail)?;
        let m = currents.ncols();
        let mut rhs = faer::Mat::<f64>::zeros(size, m);
        for c in 0..m {
            for e in 0..l {
                if let Some(i) = idx(n + e) {
                    rhs[(i, c)] += currents[(e, c)];
                }
            }
        }
        llt.solve_in_place_with_conj(faer::Conj::No, rhs.as_mut());
        let value = |full: usize, c: usize| idx(full).map_or(0.0, |i| rhs[(i, c)]);
        let mut nodes = DMatrix::from_fn(n, m, &value);
        let mut electrodes = DMatrix::from_fn(l, m, |e, c| value(n + e, c));
        for c in 0..m {
            let mean = electrodes.column(c).mean();
            electrodes.column_mut(c).add_scalar_mut(-mean);
            nodes.column_mut(c).add_scalar_mut(-mean);
        }
        if nodes
            .iter()
            .chain(electrodes.iter())
            .any(|v| !v.is_finite())
        {
            return Err(FemError::NonFinitePotentials);
        }
        Ok(Solution { nodes, electrodes })
    }

    /// The L x I current patterns of `schedule`'s distinct injections (each its current from
    /// source to sink, A), in the order of [`Schedule::injections`].
    #[must_use]
    pub fn injection_currents(schedule: &Schedule) -> DMatrix<f64> {
        let (injections, _) = schedule.injections();
        let mut c = DMatrix::zeros(schedule.electrodes(), injections.len());
        for (i, &(source, sink, amps)) in injections.iter().enumerate() {
            c[(usize::from(source), i)] += amps;
            c[(usize::from(sink), i)] -= amps;
        }
        c
    }

    /// Refuses a schedule for another electrode count, or one that measures on a drive
    /// electrode where the electrodes are points (a point reads the node the current enters
    /// by: its potential is the model's singularity, not a measurement).
    fn check(&self, schedule: &Schedule) -> Result<(), FemError> {
        let l = self.mesh.electrodes.len();
        if schedule.electrodes() != l {
            return Err(FemError::Count {
                what: "electrodes in the protocol",
                got: schedule.electrodes(),
                expected: l,
                of: "in the mesh",
            });
        }
        if let (Electrodes::Point, Some((k, e))) = (&self.electrodes, schedule.first_on_drive()) {
            return Err(FemError::MeasuresOnDrive {
                value: k,
                electrode: usize::from(e),
            });
        }
        Ok(())
    }

    /// The frame V_m (K values, V) of `schedule` at conductivity `sigma`: U_positive -
    /// U_negative of each row, under its injection's current.
    ///
    /// # Errors
    /// [`FemError`] as [`Forward::solve`], a schedule for another electrode count, or one
    /// measuring on a drive electrode with point electrodes.
    pub fn frame(&self, sigma: &[f64], schedule: &Schedule) -> Result<Vec<f64>, FemError> {
        self.check(schedule)?;
        let currents = Self::injection_currents(schedule);
        let l = currents.nrows();
        // More injections than the L - 1 independent patterns: solve for those (+1 A into
        // electrode c, out of the last) and combine them, as every injection's currents sum
        // to 0 (I = sum_{c < L-1} I_c (e_c - e_{L-1})).
        let u = if currents.ncols() > l - 1 {
            let basis = DMatrix::from_fn(l, l - 1, |e, c| {
                if e == c {
                    1.0
                } else if e == l - 1 {
                    -1.0
                } else {
                    0.0
                }
            });
            self.solve(sigma, &basis)?.electrodes * currents.rows(0, l - 1)
        } else {
            self.solve(sigma, &currents)?.electrodes
        };
        let (_, of_row) = schedule.injections();
        Ok(schedule
            .rows()
            .iter()
            .zip(of_row)
            .map(|(r, i)| u[(usize::from(r.positive), i)] - u[(usize::from(r.negative), i)])
            .collect())
    }
}

mod jacobian;
pub use jacobian::*;
