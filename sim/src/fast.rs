//! The fast path: electrode transfer impedances for any touch state without refactoring.
//!
//! The untouched network is solved once, and the rows of the inverse of its banded block A
//! are solved as touches first need them (n each, kept). A touch changes the conductance of the few resistors under it; with S the nodes
//! they join and dG their change of the network matrix, the Woodbury identity gives
//!
//! ```text
//! Z' = Z - K_ES (I + dG K_SS)^-1 dG K_SE
//! ```
//!
//! where K is the inverse of the whole (grounded) network matrix, K_SS = A^-1_SS +
//! W_S Z W_S^T and K_SE = -W_S Z. The cost is that of a dense |S| x |S| solve (about 100
//! nodes for a fingertip at the default resolution) instead of a factorisation of the whole
//! sheet. [`Network::solve`] computes the same thing directly and is the oracle in the tests.

use std::sync::OnceLock;

use nalgebra::DMatrix;

use crate::band::BandCholesky;
use crate::network::{Conductor, Network, NetworkError, Transfer};

/// A network prepared for fast touch updates.
#[derive(Debug)]
pub struct FastNetwork {
    n: usize,
    electrodes: usize,
    /// The Cholesky factor of the untouched network's banded block A.
    factor: BandCholesky,
    /// The rows of A^-1 (symmetric: row j is column j), each n long, solved the first time a
    /// touch's nodes include j. A collection's presses cover part of the sheet, so most
    /// sheets never pay for all n.
    ainv: Vec<OnceLock<Box<[f64]>>>,
    /// W = A^-1 B, n x (L-1) column-major.
    w: Vec<f64>,
    /// Untouched transfer impedance.
    base: Transfer,
    /// Untouched conductance of every edge, S.
    g0: Vec<f64>,
    /// Edge endpoints.
    ends: Vec<(u32, u32)>,
}

impl FastNetwork {
    /// Solves `network` with edge conductances `g0` (S) and stores what touch updates need.
    /// A^-1's rows come later, as touches need them: up to n^2 doubles (for n = 2 800 nodes,
    /// 63 MB) and about 1.5 n^2 b flops when every node has been touched.
    ///
    /// # Errors
    /// As [`Network::solve`].
    pub fn new(network: &Network, g0: Vec<f64>) -> Result<Self, NetworkError> {
        let solved = network.solve(&g0)?;
        let n = network.grid.len();
        Ok(Self {
            n,
            electrodes: network.electrodes(),
            factor: solved.factor().clone(),
            ainv: (0..n).map(|_| OnceLock::new()).collect(),
            w: solved.w().to_vec(),
            base: solved.transfer.clone(),
            g0,
            ends: network.grid.edges.iter().map(|e| (e.u, e.v)).collect(),
        })
    }

    /// The untouched transfer impedance.
    #[must_use]
    pub fn base(&self) -> &Transfer {
        &self.base
    }

    /// Row j of A^-1 (= column j: A is symmetric), solved the first time it is asked for.
    fn ainv_row(&self, j: usize) -> &[f64] {
        self.ainv[j].get_or_init(|| {
            let mut col = vec![0.0; self.n];
            col[j] = 1.0;
            // A e_j's right-hand side is zero above j: the forward substitution starts there.
            self.factor.solve_from(&mut col, j);
            col.into_boxed_slice()
        })
    }

    /// How many nodes the changed edges join (the size of the update's dense solve).
    #[must_use]
    pub fn touched_nodes(&self, changes: &[(usize, f64)]) -> usize {
        let mut nodes: Vec<u32> = changes
            .iter()
            .filter_map(|&(k, _)| self.ends.get(k))
            .flat_map(|&(u, v)| [u, v])
            .collect();
        nodes.sort_unstable();
        nodes.dedup();
        nodes.len()
    }

    /// The transfer impedance with edge `k`'s conductance multiplied by `m` for every
    /// `(k, m)` in `changes` (from [`crate::touch::edge_multipliers`]).
    ///
    /// # Errors
    /// [`NetworkError::Conductance`] if a multiplier is not finite and positive,
    /// [`NetworkError::Singular`] if the update
    /// is singular (cannot happen for positive multipliers on a connected sheet).
    pub fn transfer(&self, changes: &[(usize, f64)]) -> Result<Transfer, NetworkError> {
        if changes.is_empty() {
            return Ok(self.base.clone());
        }
        if let Some(&(k, m)) = changes
            .iter()
            .find(|(k, m)| !(m.is_finite() && *m > 0.0) || *k >= self.g0.len())
        {
            return Err(NetworkError::Conductance {
                of: Conductor::Multiplier(k),
                value: m,
            });
        }
        let (n, l) = (self.n, self.electrodes);
        let m = l - 1;
        // S: the nodes the changed edges join, and each one's local index.
        let mut s_nodes: Vec<u32> = changes
            .iter()
            .flat_map(|&(k, _)| [self.ends[k].0, self.ends[k].1])
            .collect();
        s_nodes.sort_unstable();
        s_nodes.dedup();
        let s = s_nodes.len();
        let local = |node: u32| s_nodes.binary_search(&node).unwrap_or(0);
        // dG over S.
        let mut dg = DMatrix::<f64>::zeros(s, s);
        for &(k, mult) in changes {
            let d = self.g0[k] * (mult - 1.0);
            let (i, j) = (local(self.ends[k].0), local(self.ends[k].1));
            dg[(i, i)] += d;
            dg[(j, j)] += d;
            dg[(i, j)] -= d;
            dg[(j, i)] -= d;
        }
        // P = W_S Z_EE (s x m); K_SE = -P; K_SS = A^-1_SS + P W_S^T.
        let ws = DMatrix::from_fn(s, m, |i, e| self.w[e * n + s_nodes[i] as usize]);
        let z = DMatrix::from_fn(m, m, |e, f| self.base.at(e + 1, f + 1));
        let p = &ws * &z;
        let mut kss = &p * ws.transpose();
        for (i, &a) in s_nodes.iter().enumerate() {
            let row = self.ainv_row(a as usize);
            for (j, &b) in s_nodes.iter().enumerate() {
                kss[(i, j)] += row[b as usize];
            }
        }
        let mut big_m = &dg * &kss;
        for i in 0..s {
            big_m[(i, i)] += 1.0;
        }
        let r = -(&dg * &p);
        let x = big_m
            .lu()
            .solve(&r)
            .ok_or(NetworkError::Singular("touch update is singular"))?;
        // Z' = Z - K_ES X = Z + P^T X.
        let dz = p.transpose() * x;
        let mut out = self.base.clone();
        for e in 1..l {
            for f in 1..l {
                out.z[e * l + f] += dz[(e - 1, f - 1)];
            }
        }
        if out.z.iter().any(|v| !v.is_finite()) {
            return Err(NetworkError::Singular(
                "touch update produced a non-finite impedance",
            ));
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::network::{Grid, place_contacts};
    use crate::touch::{Inclusion, edge_multipliers};
    use et_core::sheet::shape::Shape;

    const RS: f64 = 30e3;

    fn square(h: f64) -> Network {
        let shape = Shape::Rectangle {
            width: 0.13,
            height: 0.13,
        };
        let grid = Grid::new(&shape, h);
        let pos: Vec<f64> = (0..16).map(|e| (e as f64 + 0.5) / 16.0).collect();
        let contacts = place_contacts(&shape, &grid, &pos, 0.006, &[500.0; 16], RS);
        Network::new(grid, contacts, 1.0 / RS).unwrap()
    }

    #[test]
    fn woodbury_update_equals_a_direct_solve_at_every_contrast() {
        let net = square(0.005);
        let fast = FastNetwork::new(&net, net.conductances(None)).unwrap();
        for contrast in [1e-3, 0.5, 2.0, 5.0, 1e3] {
            let incs = [
                Inclusion {
                    position: [0.02, -0.01],
                    radius: 0.012,
                    multiplier: contrast,
                    footprint: Default::default(),
                },
                Inclusion {
                    position: [-0.04, 0.03],
                    radius: 0.008,
                    multiplier: contrast.sqrt(),
                    footprint: Default::default(),
                },
            ];
            let changes = edge_multipliers(&net.grid, &incs);
            assert!(!changes.is_empty());
            let quick = fast.transfer(&changes).unwrap();
            let mut mult = vec![1.0; net.grid.edges.len()];
            for &(k, m) in &changes {
                mult[k] = m;
            }
            let direct = net.solve(&net.conductances(Some(&mult))).unwrap().transfer;
            let scale = direct.z.iter().fold(0.0f64, |a, b| a.max(b.abs()));
            for (a, b) in quick.z.iter().zip(&direct.z) {
                assert!(
                    (a - b).abs() <= 1e-8 * scale,
                    "contrast {contrast}: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn bad_multipliers_are_refused() {
        let net = square(0.01);
        let fast = FastNetwork::new(&net, net.conductances(None)).unwrap();
        assert!(fast.transfer(&[(3, 0.0)]).is_err());
        assert!(fast.transfer(&[(3, f64::NAN)]).is_err());
        assert!(fast.transfer(&[(usize::MAX, 2.0)]).is_err());
        assert_eq!(fast.transfer(&[]).unwrap(), *fast.base());
    }
}
