//! A saved model's tables checked and rebuilt into the fitted model they describe.

use super::*;

/// Why a saved table model's tables are not the model they claim to be.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum TablesError {
    /// The standardisation's and the feature names' lengths differ, or are zero.
    #[error("feature_mean, feature_scale and feature_names differ in length")]
    FeatureLengths,
    /// A standardisation value that is not finite.
    #[error("a non-finite standardisation value ({0})")]
    NonFiniteStandardisation(f64),
    /// Two features of one name (the data's columns are read by their names).
    #[error("feature_names: '{0}' twice: each feature column is read by its name")]
    SameName(String),
    /// Training rows that are not a rising range.
    #[error("trained_rows: [{}, {}]: the first training row and the one after the last", .0[0], .0[1])]
    TrainedRows([usize; 2]),
    /// A training row's fingerprint that is not one (16 hex digits), or more than et keeps.
    #[error(transparent)]
    Seen(#[from] crate::fingerprint::SeenError),
    /// A feature scale that is not positive.
    #[error("feature_scale must be positive")]
    NonPositiveScale,
    /// The model names one method, its tables are another's.
    #[error("method {} with the tables of {}", method.name(), tables.name())]
    Mismatch {
        /// The method named.
        method: Kind,
        /// The method the tables are of.
        tables: Kind,
    },
    /// Ridge weights not one row per feature.
    #[error("ridge: {rows} weight rows for {features} features")]
    RidgeRows {
        /// The rows.
        rows: usize,
        /// The features.
        features: usize,
    },
    /// A table whose rows are not one value per feature.
    #[error("{what}: every row needs {p} values")]
    RowWidth {
        /// The table.
        what: &'static str,
        /// The features.
        p: usize,
    },
    /// A table holding a value that is not finite.
    #[error("{what}: a non-finite value")]
    NonFinite {
        /// The table.
        what: &'static str,
    },
    /// Tables that disagree with each other: which, and the rule they break.
    #[error("{0}")]
    Inconsistent(&'static str),
    /// A class name given to two classes (a label would be predicted as either).
    #[error("classes.names: '{0}' twice: each class has its own name")]
    SameClassName(String),
    /// A perceptron's layers that do not chain.
    #[error("mlp: {0}")]
    Mlp(#[source] LayersError),
    /// A discriminant's class tables that are not a model.
    #[error(transparent)]
    Classes(FitError),
    /// An average's member that is not a model of its own.
    #[error("average member {member} ({}): {source}", method.name())]
    Member {
        /// The member (1-based).
        member: usize,
        /// Its method.
        method: Kind,
        /// What is wrong with it.
        source: Box<TablesError>,
    },
}

impl TableModel {
    /// An average's regressors as models of their own (empty for any other model).
    #[must_use]
    pub fn members(&self) -> Vec<TableModel> {
        let Tables::Average { members } = &self.tables else {
            return Vec::new();
        };
        members
            .iter()
            .map(|m| TableModel {
                format: self.format.clone(),
                version: self.version,
                method: m.method,
                feature_names: self.feature_names.clone(),
                feature_mean: m.feature_mean.clone(),
                feature_scale: m.feature_scale.clone(),
                unit: self.unit,
                third: self.third.clone(),
                classes: None,
                hyperparameters: m.hyperparameters.clone(),
                search: Vec::new(),
                cv_folds: self.cv_folds,
                cv_scheme: self.cv_scheme,
                trained_rows: self.trained_rows,
                source: String::new(),
                fit_seconds: 0.0,
                chosen_by_drift: false,
                per_group: false,
                reference: None,
                seen: Vec::new(),
                note: None,
                tables: m.tables.clone(),
            })
            .collect()
    }

    /// Checks the standardisation (one finite mean and positive scale per named feature) and
    /// that the tables are the named method's.
    fn check_standardisation(&self) -> Result<(), TablesError> {
        let p = self.features();
        if self.feature_scale.len() != p || self.feature_names.len() != p || p == 0 {
            return Err(TablesError::FeatureLengths);
        }
        if let Some(v) = self
            .feature_mean
            .iter()
            .chain(&self.feature_scale)
            .find(|v| !v.is_finite())
        {
            return Err(TablesError::NonFiniteStandardisation(*v));
        }
        if self.feature_scale.iter().any(|&s| s <= 0.0) {
            return Err(TablesError::NonPositiveScale);
        }
        let tables_of = self.tables.method();
        if tables_of != self.method {
            return Err(TablesError::Mismatch {
                method: self.method,
                tables: tables_of,
            });
        }
        Ok(())
    }

    /// Checks what the file records beside the tables: feature names each once (a name twice
    /// was refused as "a feature column the model was not trained on"), the training rows a
    /// rising range and the fingerprints of training rows as et writes them (an edited one
    /// was skipped, and a range backwards silenced the note they make). Checked when a file
    /// is read, not each time the model is prepared to predict.
    pub(super) fn check_record(&self) -> Result<(), TablesError> {
        let mut names: Vec<&String> = self.feature_names.iter().collect();
        names.sort();
        if let Some((twice, _)) = names.iter().zip(names.iter().skip(1)).find(|(a, b)| a == b) {
            return Err(TablesError::SameName((*twice).clone()));
        }
        if self.trained_rows[0] > self.trained_rows[1] {
            return Err(TablesError::TrainedRows(self.trained_rows));
        }
        Ok(crate::fingerprint::check_seen(&self.seen)?)
    }

    /// Rebuilds the fitted model, checking every table's shape.
    pub(super) fn ready(&self) -> Result<Ready, TablesError> {
        self.check_standardisation()?;
        let p = self.features();
        Ok(match &self.tables {
            Tables::Discriminant { kind, classes } => {
                Ready::Discriminant(self.ready_discriminant(*kind, classes)?)
            }
            Tables::Ridge { weights, intercept } => {
                if weights.len() != p {
                    return Err(TablesError::RidgeRows {
                        rows: weights.len(),
                        features: p,
                    });
                }
                finite3(weights, "ridge weights")?;
                finite3(&[*intercept], "ridge intercept")?;
                Ready::Ridge(Ridge {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    weights: DMatrix::from_fn(p, 3, |j, c| {
                        weights
                            .get(j)
                            .and_then(|w| w.get(c))
                            .copied()
                            .unwrap_or(0.0)
                    }),
                    intercept: *intercept,
                })
            }
            Tables::KernelRidge {
                gamma,
                support,
                alpha,
                intercept,
            } => {
                let support = matrix(support, p, "kernel-ridge support")?;
                if alpha.len() != support.nrows() {
                    return Err(TablesError::Inconsistent(
                        "kernel-ridge: one alpha row per support row",
                    ));
                }
                finite3(alpha, "kernel-ridge alpha")?;
                finite3(&[*intercept], "kernel-ridge intercept")?;
                if !(gamma.is_finite() && *gamma > 0.0) {
                    return Err(TablesError::Inconsistent(
                        "kernel-ridge: gamma must be positive",
                    ));
                }
                Ready::KernelRidge(KernelRidge {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    alpha: rows3_matrix(alpha),
                    support,
                    gamma: *gamma,
                    intercept: *intercept,
                })
            }
            Tables::Gp { .. } => Ready::KernelRidge(self.ready_gp()?),
            Tables::Mlp {
                activation,
                layers,
                target_mean,
                target_scale,
            } => {
                finite3(&[*target_mean, *target_scale], "mlp target standardisation")?;
                Ready::Mlp(
                    Mlp::from_dense(
                        self.feature_mean.clone(),
                        self.feature_scale.clone(),
                        *target_mean,
                        *target_scale,
                        *activation,
                        layers,
                    )
                    .map_err(TablesError::Mlp)?,
                )
            }
            Tables::Average { members } => Ready::Average(self.ready_average(members)?),
            Tables::Knn {
                k,
                weighting,
                support,
                targets,
            } => {
                let support = matrix(support, p, "knn support")?;
                if targets.len() != support.nrows() || *k == 0 || *k > targets.len() {
                    return Err(TablesError::Inconsistent(
                        "knn: one target per support row, 1 <= k <= rows",
                    ));
                }
                finite3(targets, "knn targets")?;
                Ready::Knn(Knn {
                    mean: self.feature_mean.clone(),
                    scale: self.feature_scale.clone(),
                    support,
                    targets: targets.clone(),
                    k: *k,
                    weighting: *weighting,
                })
            }
        })
    }

    /// A discriminant's tables (`classes`, one per class) and this model's class names and
    /// centres, rebuilt.
    fn ready_discriminant(
        &self,
        kind: ModelKind,
        classes: &[ClassRecord],
    ) -> Result<Fitted, TablesError> {
        let info = self
            .classes
            .as_ref()
            .ok_or(TablesError::Inconsistent("a classifier without 'classes'"))?;
        if info.names.len() != classes.len()
            || info
                .centres
                .as_ref()
                .is_some_and(|c| c.len() != classes.len())
        {
            return Err(TablesError::Inconsistent(
                "classes.names (and centres_m) must list every class",
            ));
        }
        let mut seen = std::collections::HashSet::with_capacity(info.names.len());
        if let Some(twice) = info.names.iter().find(|n| !seen.insert(n.as_str())) {
            return Err(TablesError::SameClassName(twice.clone()));
        }
        if (info.label_type.as_deref())
            .is_some_and(|t| !["int", "float", "bool", "bytes", "str"].contains(&t))
        {
            return Err(TablesError::Inconsistent(
                "classes.label_type: int, float, bool, bytes or str",
            ));
        }
        if let Some(g) = &info.grid {
            let [x0, y0, x1, y1] = g.bounds;
            let cells = g.rows.checked_mul(g.cols);
            if g.rows == 0
                || g.cols == 0
                || cells.is_none_or(|c| c < classes.len() || c > MAX_CELLS)
            {
                return Err(TablesError::Inconsistent(
                    "classes.grid: rows and cols must be at least 1, with a cell for every class \
                     and at most a million cells",
                ));
            }
            if !(g.bounds.iter().all(|b| b.is_finite()) && x0 <= x1 && y0 <= y1) {
                return Err(TablesError::Inconsistent(
                    "classes.grid.bounds_m: [x0, y0, x1, y1], finite, x0 <= x1 and y0 <= y1",
                ));
            }
        }
        fitted_from_records(
            kind,
            &self.feature_mean,
            &self.feature_scale,
            classes,
            info.centres.as_deref().unwrap_or(&[]),
        )
        .map_err(TablesError::Classes)
    }

    /// A Gaussian process's tables rebuilt as the kernel ridge its posterior mean is, in the
    /// length-scaled space.
    fn ready_gp(&self) -> Result<KernelRidge, TablesError> {
        let Tables::Gp {
            length_scales,
            signal_variance,
            noise_variance,
            support,
            alpha,
            intercept,
        } = &self.tables
        else {
            return Err(TablesError::Inconsistent("gp: not a gp's tables"));
        };
        let p = self.features();
        let support = matrix(support, p, "gp support")?;
        if alpha.len() != support.nrows() || length_scales.len() != p {
            return Err(TablesError::Inconsistent(
                "gp: one alpha row per support row, one length scale per feature",
            ));
        }
        finite3(alpha, "gp alpha")?;
        finite3(&[*intercept], "gp intercept")?;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(length_scales.iter().all(|&l| positive(l))
            && positive(*signal_variance)
            && positive(*noise_variance))
        {
            return Err(TablesError::Inconsistent(
                "gp: length scales and variances must be positive",
            ));
        }
        Ok(KernelRidge {
            mean: self.feature_mean.clone(),
            scale: self
                .feature_scale
                .iter()
                .zip(length_scales)
                .map(|(s, l)| s * l)
                .collect(),
            alpha: rows3_matrix(alpha),
            support: Mat::from_fn(support.nrows(), p, |i, j| {
                support[(i, j)] / length_scales.get(j).copied().unwrap_or(1.0)
            }),
            gamma: 0.5,
            intercept: *intercept,
        })
    }

    /// An average's members, each checked and rebuilt as a model of its own.
    fn ready_average(&self, members: &[Member]) -> Result<Vec<Prepared>, TablesError> {
        if members.len() < 2
            || members
                .iter()
                .any(|m| m.method == Kind::Average || m.method.is_classifier())
        {
            return Err(TablesError::Inconsistent(
                "average: two regressors or more, none an average",
            ));
        }
        self.members()
            .iter()
            .enumerate()
            .map(|(i, m)| {
                Ok(Prepared {
                    features: m.features(),
                    centres: None,
                    ready: m.ready().map_err(|e| TablesError::Member {
                        member: i + 1,
                        method: m.method,
                        source: Box::new(e),
                    })?,
                })
            })
            .collect()
    }
}

impl Tables {
    /// The method these tables are of.
    #[must_use]
    pub fn method(&self) -> Kind {
        match self {
            Tables::Discriminant {
                kind: ModelKind::Qda,
                ..
            } => Kind::Qda,
            Tables::Discriminant {
                kind: ModelKind::Lda,
                ..
            } => Kind::Lda,
            Tables::Ridge { .. } => Kind::Ridge,
            Tables::KernelRidge { .. } => Kind::KernelRidge,
            Tables::Gp { .. } => Kind::Gp,
            Tables::Mlp { .. } => Kind::Mlp,
            Tables::Average { .. } => Kind::Average,
            Tables::Knn { .. } => Kind::Knn,
        }
    }
}

/// `rows` (each p values, finite) as an n x p matrix; `what` names the table in the error.
fn matrix(rows: &[Vec<f64>], p: usize, what: &'static str) -> Result<Mat<f64>, TablesError> {
    if rows.is_empty() || rows.iter().any(|r| r.len() != p) {
        return Err(TablesError::RowWidth { what, p });
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(TablesError::NonFinite { what });
    }
    Ok(Mat::from_fn(rows.len(), p, |i, j| {
        rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
    }))
}

/// Rows of three values as an n x 3 matrix.
fn rows3_matrix(rows: &[[f64; 3]]) -> Mat<f64> {
    Mat::from_fn(rows.len(), 3, |i, c| {
        rows.get(i).and_then(|a| a.get(c)).copied().unwrap_or(0.0)
    })
}

/// Ok when every value of `v` is finite; `what` names the table in the error.
fn finite3(v: &[[f64; 3]], what: &'static str) -> Result<(), TablesError> {
    if v.iter().flatten().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(TablesError::NonFinite { what })
    }
}

/// The most cells a class grid may have (`--grid RxC` makes a class of each occupied cell).
const MAX_CELLS: usize = 1_000_000;
