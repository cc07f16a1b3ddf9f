//! The sheet as a resistor network (docs/method.md §1: "a fine resistor network is a faithful model").
//!
//! Nodes sit on a rectangular grid (spacing hx, hy) inside the outline. Neighbouring nodes are
//! joined by a resistor whose conductance is the sheet conductance 1/R_s times the length of
//! the finite-volume face between them that lies inside the outline, over their distance: a
//! uniform sheet is then modelled exactly by its 5-point Laplacian in the interior, with the
//! boundary cut cells at first order. Each electrode is one more node, joined to the boundary
//! nodes under it by its contact resistance (shared equally among them).
//!
//! Unknowns: node potentials phi (n) and electrode potentials V (L), with electrode 0 grounded
//! (V_0 = 0). The system is `[[A, B], [B^T, C]] [phi; V] = [0; I]`; A is banded (row-major
//! grid numbering), so we factor it once, form W = A^-1 B and the L x L Schur complement
//! S = C - B^T W, whose inverse is the electrodes' transfer impedance Z (V = Z I).
//!
//! This is deliberately not the host's finite-element model: tests on the simulator never
//! commit the inverse crime.

use crate::band::{BandCholesky, BandMatrix};
use et_core::sheet::shape::Shape;

/// A resistor between two nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// First node.
    pub u: u32,
    /// Second node (u < v).
    pub v: u32,
    /// Conductance of this resistor in units of the sheet conductance 1/R_s
    /// (face length inside the outline over node distance; 1 in the interior of a square grid).
    pub weight: f64,
}

/// The grid of nodes over the outline.
#[derive(Clone, Debug)]
pub struct Grid {
    /// Node positions `[x, y]`, m, row-major (y outer, x inner).
    pub nodes: Vec<[f64; 2]>,
    /// Resistors.
    pub edges: Vec<Edge>,
    /// Whether a node lies on the outline (fewer than four full faces).
    pub boundary: Vec<bool>,
    /// Grid spacing along x and y, m.
    pub spacing: [f64; 2],
    /// Largest index distance of any edge (the band of the Laplacian).
    pub bandwidth: usize,
}

impl Grid {
    /// Lays a grid of spacing about `h` metres over `shape` (the exact spacing divides the
    /// bounding box evenly, so a rectangle's sides carry nodes).
    ///
    /// # Panics
    /// If `h` is not positive and finite.
    #[must_use]
    pub fn new(shape: &Shape, h: f64) -> Self {
        assert!(h.is_finite() && h > 0.0, "grid spacing must be positive");
        let [x0, y0, x1, y1] = shape.bounds();
        let nx = (((x1 - x0) / h).round() as usize).max(1) + 1;
        let ny = (((y1 - y0) / h).round() as usize).max(1) + 1;
        let (hx, hy) = ((x1 - x0) / (nx - 1) as f64, (y1 - y0) / (ny - 1) as f64);
        let tol = 1e-9 * shape.size();
        // Candidate nodes: every grid point whose dual cell (hx x hy around it) can meet the
        // outline. Edges then carry the fraction of their face inside the outline, and nodes
        // left without any edge are dropped: a cut-cell finite-volume scheme, so the modelled
        // sheet ends where the outline does, not on a staircase.
        let reach = 0.5 * hx.hypot(hy) + tol;
        let candidate =
            |i: usize, j: usize| shape.contains([x0 + i as f64 * hx, y0 + j as f64 * hy], reach);
        // Fraction of a face (segment from a to b) inside the outline, by the midpoint rule.
        const SAMPLES: usize = 16;
        let inside = |a: [f64; 2], b: [f64; 2]| {
            (0..SAMPLES)
                .filter(|&s| {
                    let t = (s as f64 + 0.5) / SAMPLES as f64;
                    shape.contains([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])], tol)
                })
                .count() as f64
                / SAMPLES as f64
        };
        // Edges between grid points (flat index j * nx + i), before numbering the nodes.
        let mut raw: Vec<(usize, usize, f64)> = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                if !candidate(i, j) {
                    continue;
                }
                let p = [x0 + i as f64 * hx, y0 + j as f64 * hy];
                if i + 1 < nx && candidate(i + 1, j) {
                    let mx = p[0] + hx / 2.0;
                    let f = inside([mx, p[1] - hy / 2.0], [mx, p[1] + hy / 2.0]);
                    if f > 0.0 {
                        raw.push((j * nx + i, j * nx + i + 1, f * hy / hx));
                    }
                }
                if j + 1 < ny && candidate(i, j + 1) {
                    let my = p[1] + hy / 2.0;
                    let f = inside([p[0] - hx / 2.0, my], [p[0] + hx / 2.0, my]);
                    if f > 0.0 {
                        raw.push((j * nx + i, (j + 1) * nx + i, f * hx / hy));
                    }
                }
            }
        }
        let mut index = vec![u32::MAX; nx * ny];
        for &(a, b, _) in &raw {
            index[a] = 0;
            index[b] = 0;
        }
        let mut nodes = Vec::new();
        for (flat, slot) in index.iter_mut().enumerate() {
            if *slot == 0 {
                *slot = nodes.len() as u32;
                nodes.push([x0 + (flat % nx) as f64 * hx, y0 + (flat / nx) as f64 * hy]);
            }
        }
        let edges: Vec<Edge> = raw
            .iter()
            .map(|&(a, b, weight)| Edge {
                u: index[a],
                v: index[b],
                weight,
            })
            .collect();
        let mut full_faces = vec![0u8; nodes.len()];
        for e in &edges {
            let full = (e.weight - hy / hx).abs() < 1e-12 || (e.weight - hx / hy).abs() < 1e-12;
            if full {
                full_faces[e.u as usize] += 1;
                full_faces[e.v as usize] += 1;
            }
        }
        let bandwidth = edges
            .iter()
            .map(|e| (e.v - e.u) as usize)
            .max()
            .unwrap_or(0);
        let boundary = full_faces.iter().map(|&f| f < 4).collect();
        Self {
            nodes,
            edges,
            boundary,
            spacing: [hx, hy],
            bandwidth,
        }
    }

    /// Number of nodes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the grid has no node.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// An electrode as the network sees it: the boundary nodes it touches and the contact
/// conductance to each (S).
#[derive(Clone, Debug, PartialEq)]
pub struct Contact {
    /// (node, conductance in S) pairs.
    pub nodes: Vec<(u32, f64)>,
}

/// Why a network cannot be built or solved.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NetworkError {
    /// Fewer than 2 electrodes.
    #[error("electrodes: need at least 2")]
    TooFewElectrodes,
    /// An electrode that touches no node.
    #[error("electrodes: electrode {0} touches no node")]
    NoContact(usize),
    /// An electrode's node that is not on the grid.
    #[error("electrodes: electrode {electrode}: node {node} is not on the grid")]
    OffGrid {
        /// The electrode.
        electrode: usize,
        /// The node.
        node: u32,
    },
    /// A short between electrodes that do not exist, or of an electrode with itself.
    #[error("electrodes: cannot short electrodes {0} and {1}")]
    Short(usize, usize),
    /// Two electrodes share a node at this resolution.
    #[error(
        "electrodes {a} and {b} touch the same node at this resolution: refine the grid or narrow them"
    )]
    Overlap {
        /// First electrode.
        a: usize,
        /// Second electrode.
        b: usize,
    },
    /// A conductance (S) that is not finite and positive (an edge's: non-negative), or an
    /// edge multiplier that is not finite and positive.
    #[error("the network cannot be solved: {of} {value}")]
    Conductance {
        /// Whose.
        of: Conductor,
        /// Its value.
        value: f64,
    },
    /// A node with no path to an electrode.
    #[error("the network cannot be solved: node {0} has no path to an electrode")]
    Unreached(usize),
    /// An electrode with no path through the sheet to electrode 0.
    #[error(
        "the network cannot be solved: electrode {0} has no path through the sheet to electrode 0"
    )]
    Isolated(usize),
    /// A matrix that could not be inverted, or gave a non-finite impedance: which.
    #[error("the network cannot be solved: {0}")]
    Singular(&'static str),
}

/// Whose conductance (or multiplier) a [`NetworkError::Conductance`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Conductor {
    /// The sheet's, S.
    Sheet,
    /// An electrode's contact, S.
    Contact(usize),
    /// An edge's, S.
    Edge,
    /// An edge's multiplier (a touch's), dimensionless.
    Multiplier(usize),
}

impl std::fmt::Display for Conductor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Conductor::Sheet => f.write_str("sheet conductance (S)"),
            Conductor::Contact(e) => write!(f, "electrode {e} contact conductance (S)"),
            Conductor::Edge => f.write_str("edge conductance (S)"),
            Conductor::Multiplier(k) => write!(f, "edge {k} multiplier"),
        }
    }
}

/// Potentials of every electrode per unit current at every electrode: V = Z I, in ohms, with
/// electrode 0 grounded (row and column 0 are zero). Symmetric (reciprocity).
#[derive(Clone, Debug, PartialEq)]
pub struct Transfer {
    /// Electrode count L.
    pub electrodes: usize,
    /// Z, L x L row-major, ohms.
    pub z: Vec<f64>,
}

impl Transfer {
    /// Z\[e]\[f].
    #[must_use]
    pub fn at(&self, e: usize, f: usize) -> f64 {
        self.z[e * self.electrodes + f]
    }

    /// Voltage phi(p) - phi(q) for current `i` amps entering at `a` and leaving at `b`.
    #[must_use]
    pub fn voltage(&self, a: usize, b: usize, p: usize, q: usize, i: f64) -> f64 {
        i * (self.at(p, a) - self.at(p, b) - self.at(q, a) + self.at(q, b))
    }

    /// The ideal frame of any system's `schedule`: each row's voltage under its current
    /// (the contact's drop included where a row measures on a drive electrode), V; None for
    /// a schedule of another electrode count.
    #[must_use]
    pub fn frame_of(&self, schedule: &et_core::schedule::Schedule) -> Option<Vec<f64>> {
        if schedule.electrodes() != self.electrodes {
            return None;
        }
        let frame = schedule
            .rows()
            .iter()
            .map(|r| {
                let e = |x: u16| usize::from(x);
                self.voltage(
                    e(r.source),
                    e(r.sink),
                    e(r.positive),
                    e(r.negative),
                    r.current_a,
                )
            })
            .collect();
        Some(frame)
    }

    /// Resistance seen between electrodes a and b, ohms (the current source's load).
    #[must_use]
    pub fn load(&self, a: usize, b: usize) -> f64 {
        self.at(a, a) - self.at(a, b) - self.at(b, a) + self.at(b, b)
    }
}

/// The sheet's resistor network with its electrodes, for a given conductance of every edge.
#[derive(Clone, Debug)]
pub struct Network {
    /// The grid.
    pub grid: Grid,
    /// Electrode contacts, electrode 0 first.
    pub contacts: Vec<Contact>,
    /// Sheet conductance 1/R_s, S.
    pub sheet_conductance: f64,
    /// Per-edge conductance multipliers of the untouched sheet (bending strain, ...); all 1
    /// unless set with [`Network::with_base`].
    pub base: Vec<f64>,
    /// Pairs of electrodes shorted together (a fault), joined by [`CONTACT_MIN_RELATIVE`] R_s.
    pub shorts: Vec<(usize, usize)>,
}

/// A factored network: everything needed for electrode potentials and node potentials.
#[derive(Debug)]
pub struct Solved {
    factor: BandCholesky,
    /// W = A^-1 B, n x (L-1) column-major (one column per electrode 1..L).
    w: Vec<f64>,
    /// The transfer impedance.
    pub transfer: Transfer,
}

impl Network {
    /// Attaches `contacts` to `grid`.
    ///
    /// # Errors
    /// [`NetworkError`] for fewer than 2 electrodes, an electrode without contact nodes, a
    /// contact conductance that is not finite and positive, or two electrodes sharing a node.
    pub fn new(
        grid: Grid,
        contacts: Vec<Contact>,
        sheet_conductance: f64,
    ) -> Result<Self, NetworkError> {
        if contacts.len() < 2 {
            return Err(NetworkError::TooFewElectrodes);
        }
        if !(sheet_conductance.is_finite() && sheet_conductance > 0.0) {
            return Err(NetworkError::Conductance {
                of: Conductor::Sheet,
                value: sheet_conductance,
            });
        }
        let mut owner = vec![usize::MAX; grid.len()];
        for (e, c) in contacts.iter().enumerate() {
            if c.nodes.is_empty() {
                return Err(NetworkError::NoContact(e));
            }
            for &(n, g) in &c.nodes {
                if !(g.is_finite() && g > 0.0) {
                    return Err(NetworkError::Conductance {
                        of: Conductor::Contact(e),
                        value: g,
                    });
                }
                let slot = owner.get_mut(n as usize).ok_or(NetworkError::OffGrid {
                    electrode: e,
                    node: n,
                })?;
                if *slot != usize::MAX && *slot != e {
                    return Err(NetworkError::Overlap { a: *slot, b: e });
                }
                *slot = e;
            }
        }
        let base = vec![1.0; grid.edges.len()];
        Ok(Self {
            grid,
            contacts,
            sheet_conductance,
            base,
            shorts: Vec::new(),
        })
    }

    /// The same network with per-edge multipliers of the untouched sheet (one per edge).
    ///
    /// # Errors
    /// [`NetworkError::Singular`] for a wrong count or a multiplier that is not finite and
    /// positive.
    pub fn with_base(mut self, base: Vec<f64>) -> Result<Self, NetworkError> {
        if base.len() != self.grid.edges.len() || base.iter().any(|m| !(m.is_finite() && *m > 0.0))
        {
            return Err(NetworkError::Singular(
                "base multipliers: one finite positive value per edge",
            ));
        }
        self.base = base;
        Ok(self)
    }

    /// The same network with electrodes `a` and `b` shorted together.
    ///
    /// # Errors
    /// [`NetworkError::Short`] for an electrode that does not exist or a == b.
    pub fn with_short(mut self, a: usize, b: usize) -> Result<Self, NetworkError> {
        let l = self.contacts.len();
        if a >= l || b >= l || a == b {
            return Err(NetworkError::Short(a, b));
        }
        self.shorts.push((a, b));
        Ok(self)
    }

    /// Electrode count L.
    #[must_use]
    pub fn electrodes(&self) -> usize {
        self.contacts.len()
    }

    /// Conductance of every edge (S) for per-edge multipliers on top of the base ones (`None` =
    /// the untouched sheet).
    #[must_use]
    pub fn conductances(&self, multiplier: Option<&[f64]>) -> Vec<f64> {
        self.grid
            .edges
            .iter()
            .enumerate()
            .map(|(k, e)| {
                self.sheet_conductance * e.weight * self.base[k] * multiplier.map_or(1.0, |m| m[k])
            })
            .collect()
    }

    /// The banded block A (sheet Laplacian plus contact conductances on the diagonal) for
    /// edge conductances `g`.
    fn assemble(&self, g: &[f64]) -> BandMatrix {
        let mut a = BandMatrix::zeros(self.grid.len(), self.grid.bandwidth);
        for (e, &ge) in self.grid.edges.iter().zip(g) {
            let (u, v) = (e.u as usize, e.v as usize);
            a.add(u, u, ge);
            a.add(v, v, ge);
            a.add(v, u, -ge);
        }
        for c in &self.contacts {
            for &(n, gc) in &c.nodes {
                a.add(n as usize, n as usize, gc);
            }
        }
        a
    }

    /// Factors the network for edge conductances `g` (S, one per edge) and computes the
    /// transfer impedance. Cost: n b^2 + 4 n b L flops.
    ///
    /// # Errors
    /// [`NetworkError::Conductance`] for a non-finite or negative conductance,
    /// [`NetworkError::Unreached`] or [`NetworkError::Isolated`] for a part of the sheet cut off
    /// from every electrode.
    pub fn solve(&self, g: &[f64]) -> Result<Solved, NetworkError> {
        if let Some(bad) = g.iter().find(|x| !(x.is_finite() && **x >= 0.0)) {
            return Err(NetworkError::Conductance {
                of: Conductor::Edge,
                value: *bad,
            });
        }
        let n = self.grid.len();
        let l = self.electrodes();
        let factor = self
            .assemble(g)
            .cholesky()
            .map_err(|e| NetworkError::Unreached(e.row))?;
        // W = A^-1 B for electrodes 1..L (column e-1), B[node][e] = -g_contact.
        let mut w = vec![0.0; n * (l - 1)];
        for e in 1..l {
            let col = &mut w[(e - 1) * n..e * n];
            let mut first = n;
            for &(node, gc) in &self.contacts[e].nodes {
                col[node as usize] = -gc;
                first = first.min(node as usize);
            }
            factor.solve_from(col, first);
        }
        // S = C - B^T W over electrodes 1..L.
        let m = l - 1;
        let mut s = nalgebra::DMatrix::<f64>::zeros(m, m);
        for e in 1..l {
            let c_ee: f64 = self.contacts[e].nodes.iter().map(|&(_, gc)| gc).sum();
            s[(e - 1, e - 1)] += c_ee;
            for f in 1..l {
                let wf = &w[(f - 1) * n..f * n];
                let bw: f64 = self.contacts[e]
                    .nodes
                    .iter()
                    .map(|&(node, gc)| -gc * wf[node as usize])
                    .sum();
                s[(e - 1, f - 1)] -= bw;
            }
        }
        // A short is a near-zero resistance between two electrode nodes: it adds to S like a
        // resistor (electrode 0 is ground, so a short to it only adds to the other's diagonal).
        let g_short = self.sheet_conductance / CONTACT_MIN_RELATIVE;
        for &(a, b) in &self.shorts {
            for (x, y) in [(a, b), (b, a)] {
                if x > 0 {
                    s[(x - 1, x - 1)] += g_short;
                    if y > 0 {
                        s[(x - 1, y - 1)] -= g_short;
                    }
                }
            }
        }
        // An electrode with no path to electrode 0 has S_ee at round-off level (the true value
        // is 0): refuse it rather than return an absurd Z. Connected electrodes have S_ee of
        // the order of the sheet's conductance, far above 1e-12 of their contact's.
        for e in 1..l {
            let c_ee: f64 = self.contacts[e].nodes.iter().map(|&(_, gc)| gc).sum();
            let pivot = s[(e - 1, e - 1)];
            if pivot.is_nan() || pivot <= 1e-12 * c_ee {
                return Err(NetworkError::Isolated(e));
            }
        }
        // Not symmetrised on purpose: the reciprocity test checks that Z comes out symmetric.
        let zinv = s.lu().try_inverse().ok_or(NetworkError::Singular(
            "electrode Schur complement is singular",
        ))?;
        let mut z = vec![0.0; l * l];
        for e in 1..l {
            for f in 1..l {
                z[e * l + f] = zinv[(e - 1, f - 1)];
            }
        }
        Ok(Solved {
            factor,
            w,
            transfer: Transfer { electrodes: l, z },
        })
    }
}

/// Smallest contact resistance used, relative to the sheet resistance: a contact of 0 ohm
/// (a perfect electrode) is modelled as R_s * 1e-6, far below anything the sheet can resolve.
pub const CONTACT_MIN_RELATIVE: f64 = 1e-6;

impl Solved {
    /// The Cholesky factor of the banded block A.
    #[must_use]
    pub fn factor(&self) -> &BandCholesky {
        &self.factor
    }

    /// W = A^-1 B, n x (L-1) column-major (column e-1 for electrode e).
    #[must_use]
    pub fn w(&self) -> &[f64] {
        &self.w
    }

    /// Node potentials (V, n values) for current `i` amps entering at electrode `a` and
    /// leaving at `b` (electrode 0 grounded): phi = -W V_E with V_E = Z I.
    #[must_use]
    pub fn potentials(&self, a: usize, b: usize, i: f64) -> (Vec<f64>, Vec<f64>) {
        let t = &self.transfer;
        let l = t.electrodes;
        let n = self.factor.order();
        let v: Vec<f64> = (0..l).map(|e| i * (t.at(e, a) - t.at(e, b))).collect();
        let mut phi = vec![0.0; n];
        for e in 1..l {
            let we = &self.w[(e - 1) * n..e * n];
            for (p, wv) in phi.iter_mut().zip(we) {
                *p -= wv * v[e];
            }
        }
        (phi, v)
    }
}

mod contacts;
pub use contacts::*;

#[cfg(test)]
mod tests;
