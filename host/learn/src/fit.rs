//! Fitting QDA and LDA (docs/method.md §9) on the host, in f64, and exporting to the et-core model blob.
//!
//! Observations are standardised with the training set's mean and standard deviation per
//! feature; the model lives in that z-space (as the blob does). Class covariances can be shrunk
//! toward a target so that the fit keeps working when a class has fewer observations than
//! features, or features are constant or duplicated (a dead electrode):
//! Sigma_c(lambda) = (1 - lambda) S_c + lambda T, with T the pooled covariance or nu I
//! (nu = trace(S_c) / p, or 1 where that is 0).

use et_core::model::{ModelKind, ModelTables, Precision, model_len, write_model};
use et_core::protocol::ProtocolKind;
use nalgebra::{DMatrix, DVector};

/// What a class covariance is shrunk toward.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Target {
    /// The pooled (LDA) covariance.
    Pooled,
    /// A multiple of the identity with the same average variance.
    Diagonal,
}

/// How to fit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FitOptions {
    /// QDA (one covariance per class) or LDA (pooled) [5.6-5.7].
    pub kind: ModelKind,
    /// Shrinkage lambda in [0, 1]; 0 = the plain docs/method.md §9 estimate.
    pub shrinkage: f64,
    /// What to shrink toward.
    pub target: Target,
}

impl Default for FitOptions {
    /// Plain QDA, as docs/method.md §9.
    fn default() -> Self {
        Self {
            kind: ModelKind::Qda,
            shrinkage: 0.0,
            target: Target::Diagonal,
        }
    }
}

/// Why a fit failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FitError {
    /// No observations or no features.
    #[error("training data: no observations or no features")]
    Empty,
    /// Tables that must be as long as each other are not (labels per row, targets per
    /// observation, predictions per label, ...).
    #[error("training data: {got} {what} for {expected} {of}")]
    Counts {
        /// What was counted.
        what: &'static str,
        /// How many.
        got: usize,
        /// How many there must be.
        expected: usize,
        /// What they are counted against.
        of: &'static str,
    },
    /// Observations of another feature count than the model's.
    #[error("training data: {got} features for a model of {expected}")]
    FeatureCount {
        /// The observations' features.
        got: usize,
        /// The model's.
        expected: usize,
    },
    /// A label (class) outside the model's classes.
    #[error("training data: observation {row} has class {label}, the model has {classes}")]
    Label {
        /// The observation.
        row: usize,
        /// Its class.
        label: usize,
        /// The model's classes.
        classes: usize,
    },
    /// A target that is NaN or infinite.
    #[error("training data: observation {row}: non-finite target")]
    NonFiniteTarget {
        /// The observation.
        row: usize,
    },
    /// Cross-validation with fewer than 2 folds.
    #[error("cross-validation needs at least 2 folds ({0} given)")]
    TooFewFolds(usize),
    /// Nothing to choose from, or nothing fitted: which.
    #[error("{0}")]
    NoCandidates(&'static str),
    /// A perceptron with no hidden layer or a layer of no width.
    #[error("hidden layers {0:?}: at least one, each at least 1 wide")]
    HiddenLayers(Vec<usize>),
    /// k nearest neighbours with k = 0.
    #[error("k = 0 neighbours")]
    NoNeighbours,
    /// The fit's numbers failed (a kernel matrix not factored, a loss not finite): which.
    #[error("fit: {0}")]
    Numerics(&'static str),
    /// A model's tables that disagree in length: which.
    #[error("model tables: {0}")]
    Tables(&'static str),
    /// A fit's worker panicked (a bug in et).
    #[error("the fit panicked (a bug in et: please report it)")]
    Panicked,
    /// Discriminants that are not finite from finite features: they are far beyond the
    /// training's (another unit), or the tables overflow.
    #[error(
        "observation {row}: its discriminants are not finite: its features are far beyond \
         those the model was trained on (frames in another unit?), or the model's tables \
         overflow (an edited value?)"
    )]
    Discriminants {
        /// Row of the observation (0-based).
        row: usize,
    },
    /// A value is NaN or infinite.
    #[error("observation {row}, feature {feature} is NaN or infinite")]
    NonFinite {
        /// Row of the observation.
        row: usize,
        /// Feature.
        feature: usize,
    },
    /// A class has no observation.
    #[error("class {class} has no observation")]
    EmptyClass {
        /// The class.
        class: u16,
    },
    /// A covariance is not positive definite: too few observations, constant or duplicated
    /// features. Use shrinkage (FitOptions::shrinkage > 0).
    #[error(
        "class {class}: covariance not positive definite (too few observations or constant/duplicated features); fit with shrinkage"
    )]
    NotPositiveDefinite {
        /// The class (LDA: 0).
        class: u16,
    },
    /// Shrinkage outside [0, 1].
    #[error("shrinkage {0} is not in [0, 1]")]
    Shrinkage(f64),
    /// Too many classes or features for the board's blob.
    #[error(
        "model export: {classes} classes x {features} features do not fit the blob format (at \
         most 65 535 each)"
    )]
    BlobSize {
        /// The classes.
        classes: usize,
        /// The features.
        features: usize,
    },
    /// The blob could not be written.
    #[error("model export: {0}")]
    Export(#[source] et_core::model::ModelError),
    /// The tables fail the checks the board makes on a model (et-core's `Model::parse` on
    /// the f32 blob: a value not finite in f32, a scale not positive, a singular or
    /// ill-conditioned class covariance, a feature outside the frame).
    #[error("not a usable model: {0}")]
    Invalid(et_core::model::ModelError),
    /// A board model file's fingerprint of a training observation that is not one.
    #[error(transparent)]
    Seen(#[from] crate::fingerprint::SeenError),
}

/// Per-feature mean and standard deviation of the rows of `x` (n x p), the z-space every
/// model here works in. A constant feature (a dead electrode) keeps unit scale rather than
/// blow round-off up into a feature. The deviations are summed as multiples of the largest,
/// so features of any magnitude f64 holds keep their spread (squared as they are, values
/// of 1e-300 underflowed to a spread of 0 and values of 1e200 overflowed to infinity: both
/// were kept at unit scale, and a classifier on them guessed).
#[must_use]
pub fn standardisation(x: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>) {
    let (n, p) = (x.nrows(), x.ncols());
    let feature_mean: Vec<f64> = (0..p).map(|j| x.column(j).mean()).collect();
    let feature_scale: Vec<f64> = (0..p)
        .map(|j| {
            let m = feature_mean[j];
            let largest = x
                .column(j)
                .iter()
                .fold(0.0_f64, |a, v| a.max((v - m).abs()));
            let sd = if n > 1 && largest > 0.0 && largest.is_finite() {
                let sum: f64 = x
                    .column(j)
                    .iter()
                    .map(|v| ((v - m) / largest).powi(2))
                    .sum();
                largest * (sum / (n - 1) as f64).sqrt()
            } else {
                0.0
            };
            // A constant feature (a dead electrode) has a round-off-sized spread: keep it
            // at unit scale rather than blow round-off up into a feature.
            let floor = 1e-9 * feature_mean[j].abs().max(f64::MIN_POSITIVE);
            if sd > floor && sd.is_finite() {
                sd
            } else {
                1.0
            }
        })
        .collect();
    (feature_mean, feature_scale)
}

/// Features ranked by their Fisher ratio (variance of the class means over the mean
/// within-class variance), best first: a feature-reduced model keeps the first p'.
#[must_use]
pub fn fisher_ranking(x: &DMatrix<f64>, y: &[u16], classes: usize) -> Vec<usize> {
    let p = x.ncols();
    let mut count = vec![0usize; classes];
    let mut sum = DMatrix::<f64>::zeros(classes, p);
    let mut sq = DMatrix::<f64>::zeros(classes, p);
    for (r, &c) in y.iter().enumerate() {
        let c = usize::from(c);
        if c >= classes {
            continue;
        }
        count[c] += 1;
        for j in 0..p {
            sum[(c, j)] += x[(r, j)];
            sq[(c, j)] += x[(r, j)] * x[(r, j)];
        }
    }
    let used: Vec<usize> = (0..classes).filter(|&c| count[c] > 0).collect();
    let ratio = |j: usize| {
        let means: Vec<f64> = used
            .iter()
            .map(|&c| sum[(c, j)] / count[c] as f64)
            .collect();
        let grand = means.iter().sum::<f64>() / means.len().max(1) as f64;
        let between = means.iter().map(|m| (m - grand).powi(2)).sum::<f64>();
        let within = used
            .iter()
            .zip(&means)
            .map(|(&c, m)| (sq[(c, j)] / count[c] as f64 - m * m).max(0.0))
            .sum::<f64>();
        if within > 0.0 { between / within } else { 0.0 }
    };
    let mut order: Vec<(usize, f64)> = (0..p).map(|j| (j, ratio(j))).collect();
    order.sort_by(|a, b| b.1.total_cmp(&a.1));
    order.into_iter().map(|(j, _)| j).collect()
}

/// One class of a fitted model, in z-space.
#[derive(Clone, Debug)]
pub struct ClassFit {
    /// Observations.
    pub count: usize,
    /// Mean mu_c.
    pub mean: DVector<f64>,
    /// log pi_c = log(n_c / n) [5.5].
    pub log_prior: f64,
    /// QDA: lower Cholesky factor of Sigma_c. LDA: empty.
    pub factor: DMatrix<f64>,
    /// QDA: log |Sigma_c|. LDA: mu_c^T Sigma^-1 mu_c.
    pub log_det_or_quad: f64,
    /// LDA: w_c = Sigma^-1 mu_c. QDA: empty.
    pub weights: DVector<f64>,
}

/// A fitted discriminant model.
#[derive(Clone, Debug)]
pub struct Fitted {
    /// QDA or LDA.
    pub kind: ModelKind,
    /// Feature means of the training set.
    pub feature_mean: Vec<f64>,
    /// Feature standard deviations of the training set (1 for a constant feature).
    pub feature_scale: Vec<f64>,
    /// Per class.
    pub classes: Vec<ClassFit>,
}

pub(crate) fn check(
    x: &DMatrix<f64>,
    y: &[u16],
    classes: usize,
) -> Result<Vec<Vec<usize>>, FitError> {
    if x.nrows() == 0 || x.ncols() == 0 {
        return Err(FitError::Empty);
    }
    if x.nrows() != y.len() {
        return Err(FitError::Counts {
            what: "labels",
            got: y.len(),
            expected: x.nrows(),
            of: "rows",
        });
    }
    for r in 0..x.nrows() {
        for c in 0..x.ncols() {
            if !x[(r, c)].is_finite() {
                return Err(FitError::NonFinite { row: r, feature: c });
            }
        }
    }
    let mut members = vec![Vec::new(); classes];
    for (r, &label) in y.iter().enumerate() {
        members
            .get_mut(usize::from(label))
            .ok_or_else(|| FitError::Label {
                row: r,
                label: usize::from(label),
                classes,
            })?
            .push(r);
    }
    if let Some(c) = members.iter().position(Vec::is_empty) {
        return Err(FitError::EmptyClass { class: c as u16 });
    }
    Ok(members)
}

/// The pooled covariance as a shrinkage target, when it can be one: a feature constant in
/// every class (a dead electrode, a column of one value) has no pooled variance, so unit
/// variance (the z-space's total) takes its place, which costs nothing as its z is 0 in
/// every row and class mean; a pooled covariance still singular (more features than rows
/// to pool, or features that repeat each other) is no target (None: the caller shrinks
/// toward the diagonal instead, where every shrinkage failed before).
#[must_use]
pub(crate) fn pooled_target(pooled: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let mut t = pooled.clone();
    for i in 0..t.nrows() {
        if t[(i, i)] <= 0.0 {
            t[(i, i)] = 1.0;
        }
    }
    let l = t.clone().cholesky()?.l();
    (0..l.nrows())
        .all(|i| l[(i, i)] > 0.0 && l[(i, i)].is_finite())
        .then_some(t)
}

/// `s` shrunk by `lambda` toward `pooled` ([`pooled_target`]), or toward the identity times
/// its own mean variance when `pooled` is None.
fn shrink(s: &DMatrix<f64>, lambda: f64, pooled: Option<&DMatrix<f64>>) -> DMatrix<f64> {
    if lambda == 0.0 {
        return s.clone();
    }
    let p = s.nrows();
    let t = match pooled {
        Some(pooled) => pooled.clone(),
        None => {
            let nu = s.trace() / p as f64;
            DMatrix::identity(p, p) * if nu > 0.0 { nu } else { 1.0 }
        }
    };
    s * (1.0 - lambda) + t * lambda
}

impl Fitted {
    /// Fits a model to observations `x` (n x p, raw features such as volts) with labels `y`
    /// (0..classes).
    ///
    /// # Errors
    /// [`FitError`]: bad shapes, non-finite values, empty classes, or a covariance that is
    /// not positive definite without enough shrinkage.
    pub fn fit(
        x: &DMatrix<f64>,
        y: &[u16],
        classes: usize,
        opts: &FitOptions,
    ) -> Result<Self, FitError> {
        if !(0.0..=1.0).contains(&opts.shrinkage) {
            return Err(FitError::Shrinkage(opts.shrinkage));
        }
        let members = check(x, y, classes)?;
        let (n, p) = (x.nrows(), x.ncols());
        let (feature_mean, feature_scale) = standardisation(x);
        let mut z = x.clone();
        for j in 0..p {
            let (m, s) = (feature_mean[j], feature_scale[j]);
            z.column_mut(j).apply(|v| *v = (*v - m) / s);
        }
        // Class means and scatter matrices.
        let mut means = Vec::with_capacity(classes);
        let mut scatters = Vec::with_capacity(classes);
        let mut pooled = DMatrix::<f64>::zeros(p, p);
        for rows in &members {
            let zc = DMatrix::from_fn(rows.len(), p, |i, j| z[(rows[i], j)]);
            let mean = DVector::from_fn(p, |j, _| zc.column(j).mean());
            let mut centred = zc;
            for mut row in centred.row_iter_mut() {
                row -= mean.transpose();
            }
            let scatter = centred.transpose() * &centred;
            pooled += &scatter;
            means.push(mean);
            scatters.push(scatter);
        }
        let dof = n.saturating_sub(classes).max(1);
        let pooled = pooled / dof as f64; // [5.3]
        let log_prior = |count: usize| (count as f64 / n as f64).ln(); // [5.5]
        let target = match (opts.kind, opts.target) {
            (ModelKind::Qda, Target::Pooled) if opts.shrinkage > 0.0 => pooled_target(&pooled),
            _ => None,
        };
        let classes_fit = match opts.kind {
            ModelKind::Qda => members
                .iter()
                .zip(means)
                .zip(scatters)
                .enumerate()
                .map(|(c, ((rows, mean), scatter))| {
                    let s = scatter / (rows.len().saturating_sub(1).max(1)) as f64;
                    let sigma = shrink(&s, opts.shrinkage, target.as_ref());
                    let chol = sigma
                        .cholesky()
                        .ok_or(FitError::NotPositiveDefinite { class: c as u16 })?;
                    let factor = chol.l();
                    if (0..p).any(|i| factor[(i, i)] <= 0.0 || !factor[(i, i)].is_finite()) {
                        return Err(FitError::NotPositiveDefinite { class: c as u16 });
                    }
                    let log_det = 2.0 * (0..p).map(|i| factor[(i, i)].ln()).sum::<f64>();
                    Ok(ClassFit {
                        count: rows.len(),
                        mean,
                        log_prior: log_prior(rows.len()),
                        factor,
                        log_det_or_quad: log_det,
                        weights: DVector::zeros(0),
                    })
                })
                .collect::<Result<Vec<_>, _>>()?,
            ModelKind::Lda => {
                let sigma = shrink(&pooled, opts.shrinkage, None);
                let chol = sigma
                    .cholesky()
                    .ok_or(FitError::NotPositiveDefinite { class: 0 })?;
                members
                    .iter()
                    .zip(means)
                    .map(|(rows, mean)| {
                        let w = chol.solve(&mean);
                        let quad = mean.dot(&w);
                        ClassFit {
                            count: rows.len(),
                            mean,
                            log_prior: log_prior(rows.len()),
                            factor: DMatrix::zeros(0, 0),
                            log_det_or_quad: quad,
                            weights: w,
                        }
                    })
                    .collect()
            }
        };
        Ok(Self {
            kind: opts.kind,
            feature_mean,
            feature_scale,
            classes: classes_fit,
        })
    }

    /// Feature count p.
    #[must_use]
    pub fn features(&self) -> usize {
        self.feature_mean.len()
    }

    /// delta_c for every class of one raw observation (p values) [5.6-5.7].
    ///
    /// # Panics
    /// If `x.len()` is not p.
    #[must_use]
    pub fn discriminants(&self, x: &[f64]) -> Vec<f64> {
        assert_eq!(x.len(), self.features());
        let z = DVector::from_iterator(
            x.len(),
            x.iter()
                .zip(&self.feature_mean)
                .zip(&self.feature_scale)
                .map(|((v, m), s)| (v - m) / s),
        );
        self.classes
            .iter()
            .map(|c| match self.kind {
                ModelKind::Qda => {
                    let d = &z - &c.mean;
                    let y = c
                        .factor
                        .solve_lower_triangular(&d)
                        .unwrap_or_else(|| DVector::from_element(d.len(), f64::INFINITY));
                    -0.5 * y.norm_squared() - 0.5 * c.log_det_or_quad + c.log_prior
                }
                ModelKind::Lda => z.dot(&c.weights) - 0.5 * c.log_det_or_quad + c.log_prior,
            })
            .collect()
    }

    /// argmax_c delta_c.
    ///
    /// # Panics
    /// If `x.len()` is not p.
    #[must_use]
    pub fn predict(&self, x: &[f64]) -> u16 {
        argmax(&self.discriminants(x))
    }

    /// argmax_c delta_c when every delta_c is finite; None when one is not: a feature NaN or
    /// infinite, or so far beyond the training's that its square overflows, where the argmax
    /// names whichever class comes last (NaN frames were class 8 of 9).
    ///
    /// # Panics
    /// If `x.len()` is not p.
    #[must_use]
    pub fn predict_finite(&self, x: &[f64]) -> Option<u16> {
        let d = self.discriminants(x);
        d.iter().all(|v| v.is_finite()).then(|| argmax(&d))
    }

    /// Exports to the et-core model blob the firmware evaluates. `feature_index` says which
    /// frame value each feature is (p entries); `positions_mm` is each class's centre;
    /// `referenced`: the model was trained on V_m - V_0 (`et_core::model::FLAG_REFERENCED`).
    ///
    /// # Errors
    /// [`FitError::Export`] when the blob's own validation refuses the tables (e.g. a
    /// covariance too ill-conditioned for f32, or values out of f16 range).
    pub fn to_blob(
        &self,
        electrodes: u8,
        protocol: ProtocolKind,
        feature_index: &[u16],
        positions_mm: &[[f32; 2]],
        precision: Precision,
        referenced: bool,
    ) -> Result<Vec<u8>, FitError> {
        let p = self.features();
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
        let (mut vectors, mut factors, mut constant) = (Vec::new(), Vec::new(), Vec::new());
        for c in &self.classes {
            match self.kind {
                ModelKind::Qda => {
                    vectors.extend(c.mean.iter().map(|&v| v as f32));
                    for r in 0..p {
                        for q in 0..=r {
                            factors.push(c.factor[(r, q)] as f32);
                        }
                    }
                }
                ModelKind::Lda => vectors.extend(c.weights.iter().map(|&v| v as f32)),
            }
            constant.push((-0.5 * c.log_det_or_quad) as f32);
        }
        let tables = ModelTables {
            kind: self.kind,
            precision,
            referenced,
            electrodes,
            protocol,
            feature_index,
            mean: &f32s(&self.feature_mean),
            scale: &f32s(&self.feature_scale),
            positions_mm,
            log_prior: &self
                .classes
                .iter()
                .map(|c| c.log_prior as f32)
                .collect::<Vec<_>>(),
            constant: &constant,
            vectors: &vectors,
            factors: &factors,
        };
        // model_len is usize::MAX when C or p exceed the format's u16 fields: refuse before
        // allocating.
        let len = model_len(self.kind, precision, self.classes.len(), p);
        if len == usize::MAX {
            return Err(FitError::BlobSize {
                classes: self.classes.len(),
                features: p,
            });
        }
        let mut out = vec![0u8; len];
        write_model(&tables, &mut out).map_err(FitError::Export)?;
        Ok(out)
    }
}

/// The index of the largest of `d` (0 when empty).
pub(crate) fn argmax(d: &[f64]) -> u16 {
    (0..d.len())
        .max_by(|&a, &b| d[a].total_cmp(&d[b]))
        .unwrap_or(0) as u16
}
