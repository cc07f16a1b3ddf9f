//! A saved model's tables checked and rebuilt into the fitted model they describe.

use super::*;

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
                note: None,
                tables: m.tables.clone(),
            })
            .collect()
    }

    /// Rebuilds the fitted model, checking every table's shape.
    pub(super) fn ready(&self) -> Result<Ready, String> {
        let p = self.features();
        if self.feature_scale.len() != p || self.feature_names.len() != p || p == 0 {
            return Err("feature_mean, feature_scale and feature_names differ in length".into());
        }
        if let Some(v) = self
            .feature_mean
            .iter()
            .chain(&self.feature_scale)
            .find(|v| !v.is_finite())
        {
            return Err(format!("a non-finite standardisation value ({v})"));
        }
        if self.feature_scale.iter().any(|&s| s <= 0.0) {
            return Err("feature_scale must be positive".into());
        }
        let tables_of = self.tables.method();
        if tables_of != self.method {
            return Err(format!(
                "method {} with the tables of {}",
                self.method.name(),
                tables_of.name()
            ));
        }
        Ok(match &self.tables {
            Tables::Discriminant { kind, classes } => {
                Ready::Discriminant(self.ready_discriminant(*kind, classes)?)
            }
            Tables::Ridge { weights, intercept } => {
                if weights.len() != p {
                    return Err(format!(
                        "ridge: {} weight rows for {p} features",
                        weights.len()
                    ));
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
                    return Err("kernel-ridge: one alpha row per support row".into());
                }
                finite3(alpha, "kernel-ridge alpha")?;
                finite3(&[*intercept], "kernel-ridge intercept")?;
                if !(gamma.is_finite() && *gamma > 0.0) {
                    return Err("kernel-ridge: gamma must be positive".into());
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
                    .map_err(|e| format!("mlp: {e}"))?,
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
                    return Err("knn: one target per support row, 1 <= k <= rows".into());
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
    ) -> Result<Fitted, String> {
        let info = self
            .classes
            .as_ref()
            .ok_or("a classifier without 'classes'")?;
        if info.names.len() != classes.len()
            || info
                .centres_mm
                .as_ref()
                .is_some_and(|c| c.len() != classes.len())
        {
            return Err("classes.names (and centres_mm) must list every class".into());
        }
        fitted_from_records(
            kind,
            &self.feature_mean,
            &self.feature_scale,
            classes,
            info.centres_mm.as_deref().unwrap_or(&[]),
        )
        .map_err(|e| e.to_string())
    }

    /// A Gaussian process's tables rebuilt as the kernel ridge its posterior mean is, in the
    /// length-scaled space.
    fn ready_gp(&self) -> Result<KernelRidge, String> {
        let Tables::Gp {
            length_scales,
            signal_variance,
            noise_variance,
            support,
            alpha,
            intercept,
        } = &self.tables
        else {
            return Err("gp: not a gp's tables".into());
        };
        let p = self.features();
        let support = matrix(support, p, "gp support")?;
        if alpha.len() != support.nrows() || length_scales.len() != p {
            return Err("gp: one alpha row per support row, one length scale per feature".into());
        }
        finite3(alpha, "gp alpha")?;
        finite3(&[*intercept], "gp intercept")?;
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !(length_scales.iter().all(|&l| positive(l))
            && positive(*signal_variance)
            && positive(*noise_variance))
        {
            return Err("gp: length scales and variances must be positive".into());
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

    /// An average's members, each checked as a model of its own.
    fn ready_average(&self, members: &[Member]) -> Result<Vec<TableModel>, String> {
        if members.len() < 2
            || members
                .iter()
                .any(|m| m.method == Method::Average || m.method.is_classifier())
        {
            return Err("average: two regressors or more, none an average".into());
        }
        let models = self.members();
        for (i, m) in models.iter().enumerate() {
            m.ready()
                .map_err(|e| format!("average member {} ({}): {e}", i + 1, m.method.name()))?;
        }
        Ok(models)
    }
}

impl Tables {
    /// The method these tables are of.
    #[must_use]
    pub fn method(&self) -> Method {
        match self {
            Tables::Discriminant {
                kind: ModelKind::Qda,
                ..
            } => Method::Qda,
            Tables::Discriminant {
                kind: ModelKind::Lda,
                ..
            } => Method::Lda,
            Tables::Ridge { .. } => Method::Ridge,
            Tables::KernelRidge { .. } => Method::KernelRidge,
            Tables::Gp { .. } => Method::Gp,
            Tables::Mlp { .. } => Method::Mlp,
            Tables::Average { .. } => Method::Average,
            Tables::Knn { .. } => Method::Knn,
        }
    }
}

/// `rows` (each p values, finite) as an n x p matrix; `what` names the table in the error.
fn matrix(rows: &[Vec<f64>], p: usize, what: &str) -> Result<Mat<f64>, String> {
    if rows.is_empty() || rows.iter().any(|r| r.len() != p) {
        return Err(format!("{what}: every row needs {p} values"));
    }
    if rows.iter().flatten().any(|v| !v.is_finite()) {
        return Err(format!("{what}: a non-finite value"));
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
fn finite3(v: &[[f64; 3]], what: &str) -> Result<(), String> {
    if v.iter().flatten().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(format!("{what}: a non-finite value"))
    }
}
