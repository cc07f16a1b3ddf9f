//! Banded Cholesky for the sheet's Laplacian: nodes numbered row by row, so every resistor
//! joins nodes at most one grid row apart and the matrix is banded with half-bandwidth about
//! one row of nodes. Factor: n b^2 flops; solve: 4 n b.

/// A symmetric positive definite band matrix, lower band stored row by row:
/// entry (i, j) with `i - b <= j <= i` at `data[i * (b + 1) + (j + b - i)]`.
#[derive(Clone, Debug)]
pub struct BandMatrix {
    n: usize,
    b: usize,
    data: Vec<f64>,
}

/// The matrix is not positive definite (a node without any path to an electrode, or a
/// conductance that is not positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NotPositiveDefinite {
    /// The row where the pivot was not positive.
    pub row: usize,
}

impl BandMatrix {
    /// An n x n zero matrix of half-bandwidth `b`.
    #[must_use]
    pub fn zeros(n: usize, b: usize) -> Self {
        Self {
            n,
            b,
            data: vec![0.0; n * (b + 1)],
        }
    }

    /// Order n.
    #[must_use]
    pub fn order(&self) -> usize {
        self.n
    }

    /// Half-bandwidth b.
    #[must_use]
    pub fn bandwidth(&self) -> usize {
        self.b
    }

    fn at(&self, i: usize, j: usize) -> usize {
        debug_assert!(j <= i && i - j <= self.b);
        i * (self.b + 1) + (j + self.b - i)
    }

    /// Adds `v` at (i, j) and, by symmetry, (j, i).
    ///
    /// # Panics
    /// If |i - j| exceeds the bandwidth.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        assert!(
            i - j <= self.b,
            "entry ({i}, {j}) outside the band {}",
            self.b
        );
        let k = self.at(i, j);
        self.data[k] += v;
    }

    /// Entry (i, j).
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (i, j) = if i >= j { (i, j) } else { (j, i) };
        if i - j > self.b {
            0.0
        } else {
            self.data[self.at(i, j)]
        }
    }

    /// Cholesky factorisation A = L L^T in place of a copy.
    ///
    /// # Errors
    /// [`NotPositiveDefinite`] at the first non-positive pivot.
    pub fn cholesky(&self) -> Result<BandCholesky, NotPositiveDefinite> {
        let (n, b) = (self.n, self.b);
        let mut l = self.clone();
        for i in 0..n {
            let lo = i.saturating_sub(b);
            for j in lo..=i {
                let klo = lo.max(j.saturating_sub(b));
                let mut s = l.data[l.at(i, j)];
                let (ri, rj) = (i * (b + 1) + b - i, j * (b + 1) + b - j);
                for k in klo..j {
                    s -= l.data[ri + k] * l.data[rj + k];
                }
                if i == j {
                    if s <= 0.0 || !s.is_finite() {
                        return Err(NotPositiveDefinite { row: i });
                    }
                    let at = l.at(i, i);
                    l.data[at] = s.sqrt();
                } else {
                    let at = l.at(i, j);
                    l.data[at] = s / l.data[l.at(j, j)];
                }
            }
        }
        Ok(BandCholesky { l })
    }
}

/// The factor L of a [`BandMatrix`].
#[derive(Clone, Debug)]
pub struct BandCholesky {
    l: BandMatrix,
}

impl BandCholesky {
    /// Solves A x = rhs in place.
    ///
    /// # Panics
    /// If `x.len()` is not the order.
    pub fn solve_mut(&self, x: &mut [f64]) {
        self.solve_from(x, 0);
    }

    /// Solves A x = rhs in place, knowing `rhs[..first] == 0` (skips that part of the forward
    /// substitution).
    ///
    /// # Panics
    /// If `x.len()` is not the order.
    pub fn solve_from(&self, x: &mut [f64], first: usize) {
        let (n, b) = (self.l.n, self.l.b);
        assert_eq!(x.len(), n);
        let d = &self.l.data;
        // (Slices zipped rather than indexed: no bounds check in the inner loops, the same
        // operations in the same order.)
        for i in first..n {
            let row = i * (b + 1) + b - i;
            let lo = i.saturating_sub(b).max(first);
            let mut s = x[i];
            for (l_ik, x_k) in d[row + lo..row + i].iter().zip(&x[lo..i]) {
                s -= l_ik * x_k;
            }
            x[i] = s / d[row + i];
        }
        for i in (0..n).rev() {
            let xi = x[i] / d[i * (b + 1) + b];
            x[i] = xi;
            let row = i * (b + 1) + b - i;
            let lo = i.saturating_sub(b);
            for (x_k, l_ik) in x[lo..i].iter_mut().zip(&d[row + lo..row + i]) {
                *x_k -= l_ik * xi;
            }
        }
    }

    /// Order n.
    #[must_use]
    pub fn order(&self) -> usize {
        self.l.n
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::DMatrix;

    #[test]
    fn solves_like_dense_cholesky() {
        // A random SPD band matrix (diagonally dominant), checked against nalgebra's dense solve.
        let (n, b) = (40, 6);
        let mut a = BandMatrix::zeros(n, b);
        let mut rng = et_core::rng::Rng::new(12345);
        let mut rnd = || rng.uniform() - 0.5;
        for i in 0..n {
            for j in i.saturating_sub(b)..i {
                a.add(i, j, rnd());
            }
            a.add(i, i, 2.0 * b as f64 + 1.0);
        }
        let dense = DMatrix::from_fn(n, n, |i, j| a.get(i, j));
        let rhs: Vec<f64> = (0..n).map(|i| (i as f64).sin()).collect();
        let want = dense
            .clone()
            .cholesky()
            .unwrap()
            .solve(&nalgebra::DVector::from_vec(rhs.clone()));
        let mut x = rhs.clone();
        a.cholesky().unwrap().solve_mut(&mut x);
        for i in 0..n {
            assert!((x[i] - want[i]).abs() < 1e-12, "{i}");
        }
        // The skipped forward part gives the same answer when the head is zero.
        let mut e = vec![0.0; n];
        e[30] = 1.0;
        let mut full = e.clone();
        let f = a.cholesky().unwrap();
        f.solve_mut(&mut full);
        f.solve_from(&mut e, 30);
        assert_eq!(full, e);
    }

    #[test]
    fn singular_is_an_error() {
        let mut a = BandMatrix::zeros(3, 1);
        a.add(0, 0, 1.0);
        a.add(1, 1, 1.0);
        a.add(1, 0, -1.0);
        a.add(0, 0, 0.0);
        assert_eq!(a.cholesky().unwrap_err(), NotPositiveDefinite { row: 1 });
    }
}
