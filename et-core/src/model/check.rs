//! The checks every discriminant model's class tables pass, wherever they are stored: the
//! board's blob ([`Model::parse`]) and the host's fitted tables (model files of either kind)
//! run this one function, so they accept and refuse the same tables.

use super::*;

/// Read access to a discriminant model's tables (values as the board evaluates them, f32).
pub trait ClassTables {
    /// QDA or LDA.
    fn kind(&self) -> ModelKind;
    /// Class count C.
    fn classes(&self) -> usize;
    /// Feature count p.
    fn features(&self) -> usize;
    /// Feature `j`'s mean.
    fn mean(&self, j: usize) -> f32;
    /// Feature `j`'s scale (> 0).
    fn scale(&self, j: usize) -> f32;
    /// Class `c`'s position, mm.
    fn position_mm(&self, c: usize) -> [f32; 2];
    /// log pi_c.
    fn log_prior(&self, c: usize) -> f32;
    /// QDA: -1/2 log|Sigma_c|; LDA: -1/2 mu_c^T Sigma^-1 mu_c.
    fn constant(&self, c: usize) -> f32;
    /// QDA: mu_c; LDA: w_c, component `j`.
    fn vector(&self, c: usize, j: usize) -> f32;
    /// QDA: the Cholesky factor L_c's entry at row `r`, column `q <= r`.
    fn factor(&self, c: usize, r: usize, q: usize) -> f32;
}

/// Checks the tables: at least 2 classes and 1 feature; every value finite; every scale
/// positive; each QDA factor's diagonal positive (else the covariance is singular) and no
/// smaller than [`MIN_PIVOT_RATIO`] of its largest (else f32 evaluation loses all precision).
///
/// # Errors
/// The first [`ModelError`] found.
pub fn check_class_tables(t: &impl ClassTables) -> Result<(), ModelError> {
    let (c_n, p) = (t.classes(), t.features());
    if c_n < 2 || p == 0 {
        return Err(ModelError::Dimensions);
    }
    for j in 0..p {
        if !t.mean(j).is_finite() || !t.scale(j).is_finite() {
            return Err(ModelError::NonFiniteFeature { feature: j as u16 });
        }
        if t.scale(j) <= 0.0 {
            return Err(ModelError::Scale { feature: j as u16 });
        }
    }
    for c in 0..c_n {
        let [x, y] = t.position_mm(c);
        let finite = [x, y, t.log_prior(c), t.constant(c)]
            .iter()
            .all(|v| v.is_finite());
        if !finite || (0..p).any(|j| !t.vector(c, j).is_finite()) {
            return Err(ModelError::NonFinite { class: c as u16 });
        }
        if t.kind() == ModelKind::Qda {
            if (0..p).any(|r| (0..=r).any(|q| !t.factor(c, r, q).is_finite())) {
                return Err(ModelError::NonFinite { class: c as u16 });
            }
            let (mut lo, mut hi) = (f32::INFINITY, 0.0f32);
            for r in 0..p {
                let d = t.factor(c, r, r);
                if d <= 0.0 {
                    return Err(ModelError::Singular { class: c as u16 });
                }
                lo = lo.min(d);
                hi = hi.max(d);
            }
            if lo < MIN_PIVOT_RATIO * hi {
                return Err(ModelError::IllConditioned { class: c as u16 });
            }
        }
    }
    Ok(())
}

impl ClassTables for Model<'_> {
    fn kind(&self) -> ModelKind {
        self.kind
    }
    fn classes(&self) -> usize {
        self.classes
    }
    fn features(&self) -> usize {
        self.features
    }
    fn mean(&self, j: usize) -> f32 {
        Model::mean(self, j)
    }
    fn scale(&self, j: usize) -> f32 {
        Model::scale(self, j)
    }
    fn position_mm(&self, c: usize) -> [f32; 2] {
        Model::position_mm(self, c as u16)
    }
    fn log_prior(&self, c: usize) -> f32 {
        Model::log_prior(self, c)
    }
    fn constant(&self, c: usize) -> f32 {
        Model::constant(self, c)
    }
    fn vector(&self, c: usize, j: usize) -> f32 {
        Model::vector(self, c, j)
    }
    fn factor(&self, c: usize, r: usize, q: usize) -> f32 {
        Model::factor(self, c, packed_len(r) + q)
    }
}
