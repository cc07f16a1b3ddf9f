//! The Jacobian of the boundary voltages with respect to the element conductivities, dense and in
//! the factored transfer form (one row per electrode pair).

use super::*;

/// A schedule's Jacobian in factored form J = M G (docs/method.md §5): by reciprocity every
/// frame value is a combination of the transfer impedances Z_ij (i <= j < L - 1: the
/// potential at electrode i, against electrode L - 1, of a unit current into electrode j and
/// out of electrode L - 1), so J (K x T) is a sparse K x r combination M of the r = L (L - 1) / 2
/// rows G = dZ / dsigma (r x T). For 16 electrodes r = 120 against K = 208 (adjacent); for 32
/// electrodes PP-PP r = 496 against K = 1 824: the data-space products cost r, not K.
#[derive(Clone, Debug)]
pub struct TransferJacobian {
    /// The frame V_m at the conductivity, V (K values).
    pub frame: Vec<f64>,
    /// M, K rows of (pair index, coefficient in A): frame value k = sum over its entries of
    /// coefficient x Z_pair. At most four entries a row.
    pub combination: Vec<Vec<(usize, f64)>>,
    /// G = dZ_ij / dsigma_t, r x T (ohm per S/sq), pairs (i, j), i <= j, in [`pair_index`]
    /// order.
    pub g: DMatrix<f64>,
}

impl TransferJacobian {
    /// r, the number of transfer impedances.
    #[must_use]
    pub fn pairs(&self) -> usize {
        self.g.nrows()
    }

    /// The dense Jacobian J = M G, K x T (V per S/sq).
    #[must_use]
    pub fn dense(&self) -> DMatrix<f64> {
        let t_n = self.g.ncols();
        let mut jac = DMatrix::zeros(self.combination.len(), t_n);
        for t in 0..t_n {
            let g = self.g.column(t);
            for (k, row) in self.combination.iter().enumerate() {
                jac[(k, t)] = row.iter().map(|&(p, c)| c * g[p]).sum();
            }
        }
        jac
    }
}

/// Index of the transfer impedance Z_ij (i <= j < L - 1) among the r = L (L - 1) / 2 pairs:
/// row-major upper triangle.
#[must_use]
pub fn pair_index(l: usize, i: usize, j: usize) -> usize {
    let (i, j) = (i.min(j), i.max(j));
    let n = l - 1;
    i * n - i * (i + 1) / 2 + j
}

impl Forward {
    /// The frame of `schedule` and its Jacobian with respect to each triangle's conductivity
    /// (K x T, V per S/sq): [`Forward::transfer_jacobian`] multiplied out.
    ///
    /// # Errors
    /// As [`Forward::frame`].
    pub fn jacobian(
        &self,
        sigma: &[f64],
        schedule: &Schedule,
    ) -> Result<(Vec<f64>, DMatrix<f64>), FemError> {
        let tj = self.transfer_jacobian(sigma, schedule)?;
        let jac = tj.dense();
        Ok((tj.frame, jac))
    }

    /// The frame of `schedule` and its Jacobian in factored form, by the adjoint method on
    /// the transfer impedances: with u_i the potentials of a unit current from electrode i to
    /// electrode L - 1, dZ_ij / dsigma_t = -int_T grad u_i . grad u_j = -|T| grad u_i . grad
    /// u_j (P1: gradients constant on a triangle). L - 1 solves of one factorisation serve
    /// every injection and measurement; no inverse is formed.
    ///
    /// # Errors
    /// As [`Forward::frame`].
    pub fn transfer_jacobian(
        &self,
        sigma: &[f64],
        schedule: &Schedule,
    ) -> Result<TransferJacobian, FemError> {
        self.check(schedule)?;
        let l = self.mesh.electrodes.len();
        let n = l - 1;
        let r = l * n / 2;
        let mut currents = DMatrix::zeros(l, n);
        for i in 0..n {
            currents[(i, i)] = 1.0;
            currents[(n, i)] = -1.0;
        }
        let sol = self.solve(sigma, &currents)?;
        // Z_ij = U_i - U_{L-1} for pattern j.
        let z = |i: usize, j: usize| sol.electrodes[(i, j)] - sol.electrodes[(n, j)];
        // Electrode x as a vector of the grounded basis: e_x (x < L - 1), 0 for x = L - 1.
        let basis = |x: usize| (x < n).then_some(x);
        let mut frame = Vec::with_capacity(schedule.frame_len());
        let mut combination = Vec::with_capacity(schedule.frame_len());
        for s in schedule.rows() {
            let amps = s.current_a;
            let terms =
                |a: u16, b: u16| [(basis(usize::from(a)), 1.0), (basis(usize::from(b)), -1.0)];
            let inj = terms(s.source, s.sink);
            let meas = terms(s.positive, s.negative);
            let mut row: Vec<(usize, f64)> = Vec::with_capacity(4);
            let mut value = 0.0;
            for &(p, cp) in &meas {
                for &(q, cq) in &inj {
                    if let (Some(p), Some(q)) = (p, q) {
                        let c = amps * cp * cq;
                        value += c * z(p, q);
                        let at = pair_index(l, p, q);
                        match row.iter_mut().find(|e| e.0 == at) {
                            Some(e) => e.1 += c,
                            None => row.push((at, c)),
                        }
                    }
                }
            }
            frame.push(value);
            combination.push(row);
        }
        // Per triangle: grad u_i for every pattern, then -|T| grad u_i . grad u_j.
        let t_n = self.mesh.triangles.len();
        let mut g = DMatrix::zeros(r, t_n);
        let mut grads = vec![[0.0f64; 2]; n];
        for (t, tri) in self.mesh.triangles.iter().enumerate() {
            let p = tri.map(|a| self.mesh.nodes[a]);
            let area2 = self.mesh.double_area(t);
            let dphi: [[f64; 2]; 3] = std::array::from_fn(|k| {
                let (q, w) = (p[(k + 1) % 3], p[(k + 2) % 3]);
                [(q[1] - w[1]) / area2, (w[0] - q[0]) / area2]
            });
            for (i, grad) in grads.iter_mut().enumerate() {
                *grad = [0.0, 0.0];
                for (k, &a) in tri.iter().enumerate() {
                    let u = sol.nodes[(a, i)];
                    grad[0] += u * dphi[k][0];
                    grad[1] += u * dphi[k][1];
                }
            }
            let area = 0.5 * area2;
            let mut col = g.column_mut(t);
            let mut at = 0;
            for i in 0..n {
                for j in i..n {
                    col[at] = -area * (grads[i][0] * grads[j][0] + grads[i][1] * grads[j][1]);
                    at += 1;
                }
            }
        }
        Ok(TransferJacobian {
            frame,
            combination,
            g,
        })
    }
}
