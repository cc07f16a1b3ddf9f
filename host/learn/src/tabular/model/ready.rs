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
        let matrix = |rows: &[Vec<f64>], what: &str| -> Result<Mat<f64>, String> {
            if rows.is_empty() || rows.iter().any(|r| r.len() != p) {
                return Err(format!("{what}: every row needs {p} values"));
            }
            if rows.iter().flatten().any(|v| !v.is_finite()) {
                return Err(format!("{what}: a non-finite value"));
            }
            Ok(Mat::from_fn(rows.len(), p, |i, j| {
                rows.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0)
            }))
        };
        let finite3 = |v: &[[f64; 3]], what: &str| -> Result<(), String> {
            if v.iter().flatten().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(format!("{what}: a non-finite value"))
            }
        };
        let method_ok = |m: Method| {
            if m == self.method {
                Ok(())
            } else {
                Err(format!(
                    "method {} with the tables of {}",
                    self.method.name(),
                    m.name()
                ))
            }
        };
        Ok(match &self.tables {
            Tables::Discriminant { kind, classes } => {
                let (method, mk) = match kind {
                    ModelKind::Qda => (Method::Qda, *kind),
                    ModelKind::Lda => (Method::Lda, *kind),
                };
                method_ok(method)?;
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
                let fitted = fitted_from_records(
                    mk,
                    &self.feature_mean,
                    &self.feature_scale,
                    classes,
                    info.centres_mm.as_deref().unwrap_or(&[]),
                )
                .map_err(|e| e.to_string())?;
                Ready::Discriminant(fitted)
            }
            Tables::Ridge { weights, intercept } => {
                method_ok(Method::Ridge)?;
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
                method_ok(Method::KernelRidge)?;
                let support = matrix(support, "kernel-ridge support")?;
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
                    alpha: Mat::from_fn(alpha.len(), 3, |i, c| {
                        alpha.get(i).and_then(|a| a.get(c)).copied().unwrap_or(0.0)
                    }),
                    support,
                    gamma: *gamma,
                    intercept: *intercept,
                })
            }
            Tables::Gp {
                length_scales,
                signal_variance,
                noise_variance,
                support,
                alpha,
                intercept,
            } => {
                method_ok(Method::Gp)?;
                let support = matrix(support, "gp support")?;
                if alpha.len() != support.nrows() || length_scales.len() != p {
                    return Err(
                        "gp: one alpha row per support row, one length scale per feature".into(),
                    );
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
                // The posterior mean is kernel ridge in the length-scaled space.
                Ready::KernelRidge(KernelRidge {
                    mean: self.feature_mean.clone(),
                    scale: self
                        .feature_scale
                        .iter()
                        .zip(length_scales)
                        .map(|(s, l)| s * l)
                        .collect(),
                    alpha: Mat::from_fn(alpha.len(), 3, |i, c| {
                        alpha.get(i).and_then(|a| a.get(c)).copied().unwrap_or(0.0)
                    }),
                    support: Mat::from_fn(support.nrows(), p, |i, j| {
                        support[(i, j)] / length_scales.get(j).copied().unwrap_or(1.0)
                    }),
                    gamma: 0.5,
                    intercept: *intercept,
                })
            }
            Tables::Mlp {
                activation,
                layers,
                target_mean,
                target_scale,
            } => {
                method_ok(Method::Mlp)?;
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
            Tables::Average { members } => {
                method_ok(Method::Average)?;
                if members.len() < 2
                    || members
                        .iter()
                        .any(|m| m.method == Method::Average || m.method.is_classifier())
                {
                    return Err("average: two regressors or more, none an average".into());
                }
                let models = self.members();
                for (i, m) in models.iter().enumerate() {
                    m.ready().map_err(|e| {
                        format!("average member {} ({}): {e}", i + 1, m.method.name())
                    })?;
                }
                Ready::Average(models)
            }
            Tables::Knn {
                k,
                weighting,
                support,
                targets,
            } => {
                method_ok(Method::Knn)?;
                let support = matrix(support, "knn support")?;
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
}
