//! The one-step reconstruction as a matrix: built from the Jacobian, applied to a frame, and the
//! image's noise from the frames' variance.

use super::*;

/// The one-step Gauss-Newton reconstruction R = P^-1 J^T (A + lambda I)^-1 (T x K) of one
/// (mesh, protocol, alpha, s), kept as its factors R = (G P^-1)^T X^T: a frame costs r (T + K)
/// instead of T K, and [`OneStep::matrix`] multiplies it out when a caller wants R itself.
#[derive(Clone, Debug)]
pub struct OneStep {
    /// G P^-1, r x T (shared with the data space it was made from, [`DataSpace`]).
    pub(crate) gp: std::sync::Arc<Mat<f64>>,
    /// X^T = M^T (A + lambda I)^-1, r x K.
    pub(crate) xt: Mat<f64>,
    /// (N H + lambda I)^-1 on N's range, r x r: X^T = `inverse` M^T.
    pub(crate) inverse: Mat<f64>,
    /// M's rows: frame value k is the sum of c z_p over `combination[k]`'s (p, c), z the r
    /// transfer impedances.
    pub(crate) combination: Vec<Vec<(usize, f64)>>,
    /// The alpha it was built with.
    pub alpha: f64,
    /// The NOSER exponent s.
    pub s: f64,
    /// R's rows of the triangles a noise image was asked for twice, squared entrywise
    /// ([`OneStep::noise_sd_of`]).
    pub(crate) squared: NoiseRows,
}

/// The rows of R (T x K) some frames' noise images need, squared entrywise (rows x K, f32),
/// made the second time the same rows' noise is asked for: a frame's noise is then
/// sqrt(S var) (to f32's precision), rows K multiply-adds, where the factors' way costs r^2
/// rows a frame (r the transfer impedances; 9 ms at 8 000 triangles and 16 electrodes). One
/// image of a frame never pays to make it.
#[derive(Clone, Debug, Default)]
pub(crate) struct NoiseRows {
    asked: std::sync::OnceLock<Vec<usize>>,
    made: std::sync::OnceLock<Mat<f32>>,
}

impl OneStep {
    /// Builds R from the dense Jacobian `jac` (K x T): [`DataSpace::new`] then
    /// [`DataSpace::one_step`] (use those to choose alpha by GCV on the same data space).
    ///
    /// # Errors
    /// [`ReconError::OutOfRange`] for alpha not in (0, inf) or s not in [0, 1];
    /// [`ReconError::Singular`] when the system cannot be factorised.
    pub fn new(jac: &DMatrix<f64>, alpha: f64, s: f64) -> Result<Self, ReconError> {
        check_alpha(alpha)?;
        DataSpace::new(jac, s)?.one_step(alpha)
    }

    /// This reconstruction with G P^-1 replaced by `gp` (r x N): R = gp^T X^T, whose N
    /// "triangles" are gp's columns (GREIT's pixels, [`crate::greit`]).
    pub(crate) fn with_columns(self, gp: Mat<f64>) -> OneStep {
        debug_assert_eq!(gp.nrows(), self.gp.nrows());
        OneStep {
            gp: std::sync::Arc::new(gp),
            squared: NoiseRows::default(),
            ..self
        }
    }

    /// K, the frame length.
    #[must_use]
    pub fn frame_len(&self) -> usize {
        self.xt.ncols()
    }

    /// T, the triangles.
    #[must_use]
    pub fn triangles(&self) -> usize {
        self.gp.ncols()
    }

    /// R (T x K) multiplied out.
    #[must_use]
    pub fn matrix(&self) -> DMatrix<f64> {
        let (t, k) = (self.triangles(), self.frame_len());
        let mut m = DMatrix::<f64>::zeros(t, k);
        matmul(
            MatMut::from_column_major_slice_mut(m.as_mut_slice(), t, k),
            Accum::Replace,
            self.gp.transpose(),
            self.xt.as_ref(),
            1.0,
            Par::Seq,
        );
        m
    }

    /// d_sigma on the mesh's triangles for the frame difference `dv` = V_1 - V_0 (K values).
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a wrong length, [`ReconError::NonFinite`] for NaN/inf.
    pub fn reconstruct(&self, dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        self.check_len(dv.len(), "values")?;
        if dv.iter().any(|v| !v.is_finite()) {
            return Err(ReconError::NonFinite);
        }
        // y = X^T dv (r), then the image (G P^-1)^T y (T): two matrix-vector products.
        let dv = MatRef::from_column_major_slice(dv, dv.len(), 1);
        let y = product(self.xt.as_ref(), dv);
        let mut image = vec![0.0; self.triangles()];
        matmul(
            MatMut::from_column_major_slice_mut(&mut image, self.triangles(), 1),
            Accum::Replace,
            self.gp.transpose(),
            y.as_ref(),
            1.0,
            Par::Seq,
        );
        Ok(image)
    }

    fn check_len(&self, n: usize, what: &'static str) -> Result<(), ReconError> {
        if n == self.frame_len() {
            Ok(())
        } else {
            Err(ReconError::FrameLength {
                what,
                got: n,
                k: self.frame_len(),
            })
        }
    }

    /// The standard deviation of each triangle's value when dV carries independent noise of
    /// variance `var_dv` per channel (V^2): sqrt(sum_k R_tk^2 var_k) = |W g_t| with W =
    /// diag(sqrt var) X (K x r) and g_t triangle t's column of G P^-1, computed as |R_W g_t|
    /// through W's QR factor R_W (r x r: the cost is r^2 T, not K r T, and a norm of a vector
    /// keeps its accuracy). Same units as an image.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a wrong length.
    pub fn noise_sd(&self, var_dv: &[f64]) -> Result<Vec<f64>, ReconError> {
        let all: Vec<usize> = (0..self.triangles()).collect();
        self.noise_sd_of(var_dv, &all)
    }

    /// [`OneStep::noise_sd`] of the triangles `rows` only (each < T), in their order: an
    /// image drawn on pixels needs only the triangles under them.
    ///
    /// # Errors
    /// [`ReconError::FrameLength`] for a wrong length, [`ReconError::Size`] for a triangle out of range.
    pub fn noise_sd_of(&self, var_dv: &[f64], rows: &[usize]) -> Result<Vec<f64>, ReconError> {
        self.check_len(var_dv.len(), "variances")?;
        if let Some(t) = rows.iter().find(|&&t| t >= self.triangles()) {
            return Err(ReconError::Size {
                what: "a triangle's index",
                got: *t,
                expected: self.triangles(),
            });
        }
        if let Some(s) = self.squared_rows(rows) {
            // f32: the rows are read once a frame (62 MB in f64 for 3 300 pixels and K = 2 356),
            // and a sum of positive terms keeps f32's relative precision (a noise figure
            // needs no more).
            let var = Mat::from_fn(var_dv.len(), 1, |k, _| var_dv[k].max(0.0) as f32);
            let mut sd2 = Mat::<f32>::zeros(rows.len(), 1);
            matmul(
                sd2.as_mut(),
                Accum::Replace,
                s.as_ref(),
                var.as_ref(),
                1.0,
                Par::Seq,
            );
            return Ok((0..rows.len())
                .map(|t| f64::from(sd2[(t, 0)].max(0.0)).sqrt())
                .collect());
        }
        let r = self.xt.nrows();
        let w = Mat::from_fn(self.frame_len(), r, |k, j| {
            self.xt[(j, k)] * var_dv[k].max(0.0).sqrt()
        });
        let qr = w.qr();
        let thin = qr.thin_R();
        let upper = Mat::from_fn(
            thin.nrows(),
            r,
            |i, j| if i <= j { thin[(i, j)] } else { 0.0 },
        );
        let g = Mat::from_fn(r, rows.len(), |i, t| self.gp[(i, rows[t])]);
        let mut y = Mat::<f64>::zeros(upper.nrows(), rows.len());
        // R_W is upper triangular (thin.nrows() = min(K, r) rows): half the products.
        faer::linalg::matmul::triangular::matmul(
            y.as_mut(),
            BlockStructure::Rectangular,
            Accum::Replace,
            upper.as_ref(),
            if upper.nrows() == r {
                BlockStructure::TriangularUpper
            } else {
                BlockStructure::Rectangular
            },
            g.as_ref(),
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        Ok((0..rows.len())
            .map(|t| y.col(t).iter().map(|v| v * v).sum::<f64>().sqrt())
            .collect())
    }

    /// R's rows `rows` squared entrywise (rows x K), when these rows were asked for before
    /// ([`NoiseRows`]); None the first time, or for other rows than the first asked.
    fn squared_rows(&self, rows: &[usize]) -> Option<&Mat<f32>> {
        if let Some(s) = self.squared.made.get() {
            return (self.squared.asked.get().map(Vec::as_slice) == Some(rows)).then_some(s);
        }
        match self.squared.asked.get() {
            None => {
                // The first time: remember the rows, image by the factors.
                let _ = self.squared.asked.set(rows.to_vec());
                None
            }
            Some(asked) if asked.as_slice() == rows => Some(self.squared.made.get_or_init(|| {
                let g = Mat::from_fn(self.gp.nrows(), rows.len(), |i, t| self.gp[(i, rows[t])]);
                let r = product(g.transpose(), self.xt.as_ref());
                Mat::from_fn(r.nrows(), r.ncols(), |i, k| (r[(i, k)] * r[(i, k)]) as f32)
            })),
            Some(_) => None,
        }
    }
}

/// The forward model's relative error against a real sheet, as a share of each channel's
/// change: the finite elements and the simulator's resistor network (two independent models
/// of one sheet) agree within 3.7 % on the 22 cm disc and 2.7 % on the 13 cm square
/// (`finite_elements_and_the_simulators_resistor_network_agree`); a real fabric is no closer.
pub const MODEL_ERROR: f64 = 0.03;

/// Each channel's variance of dV as imaging sees it, V^2: the frames' noise `var_dv` plus the
/// model's error (`MODEL_ERROR` x dV_k)^2. The model's error is not noise (it repeats from
/// frame to frame), but to an image it is the same: a misfit that images into peaks where
/// there is no touch. It sets the images' noise (a touch's or object's z) and the iterative
/// fit's weights; alpha's floor counts less of it ([`floor_variance`]).
#[must_use]
pub fn imaging_variance(var_dv: &[f64], dv: &[f64]) -> Vec<f64> {
    var_dv
        .iter()
        .zip(dv)
        .map(|(v, d)| v.max(0.0) + (MODEL_ERROR * d).powi(2))
        .collect()
}

/// The share of each channel's change alpha's floor counts as the model's error (a third of
/// [`MODEL_ERROR`]).
pub const FLOOR_MODEL_ERROR: f64 = 0.01;

/// Each channel's variance of dV that alpha must not fit below ([`DataSpace::choose_alpha`]),
/// V^2: the frames' noise `var_dv` plus ([`FLOOR_MODEL_ERROR`] x dV_k)^2. Even noiseless
/// frames carry the model's mismatch, and a floor of the noise alone then lets GCV run to the
/// smallest alpha, where the image rings; counting all of [`MODEL_ERROR`] smooths strong
/// objects and moves them towards the centre. Measured on two simulated tanks of another
/// system's protocols, noiseless and noisy (`cargo run --release -p et-host --example
/// defaults_sweep`, docs/measurements.md): with 0 % the noiseless frames show no object at
/// all, with 3 % the strongest object lies 5 to 5.5 mm from its rod (median), with 1 % 3 to 4.5
/// mm.
#[must_use]
pub fn floor_variance(var_dv: &[f64], dv: &[f64]) -> Vec<f64> {
    var_dv
        .iter()
        .zip(dv)
        .map(|(v, d)| v.max(0.0) + (FLOOR_MODEL_ERROR * d).powi(2))
        .collect()
}
