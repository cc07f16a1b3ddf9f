//! The chosen candidate fitted on every row: the tables a saved model keeps.

use super::*;

/// The final fit of the chosen candidate on every row: its tables and the standardisation;
/// `seed` seeds a perceptron's starts; QDA shrinks toward the target its cross-validation's
/// `fold_rows` chose ([`shrink_target`]).
pub(in crate::tabular) fn fit_final(
    table: &Table,
    best: &Candidate,
    targets: Option<&[Target3]>,
    (classes, fold_rows): (Option<&(Labels, ClassInfo)>, usize),
    members: &[Candidate],
    (seed, progress): (u64, Progress<'_>),
) -> Result<(Tables, Vec<f64>, Vec<f64>), TabularError> {
    let h = |name: &str| best.hyperparameters.get(name).copied().unwrap_or(0.0);
    let need_targets = || targets.ok_or_else(|| usage(Misuse::NeedsPositions));
    Ok(match best.method {
        Kind::Qda | Kind::Lda => {
            let (labels, _) = classes.ok_or_else(|| usage(Misuse::NeedsClasses))?;
            let fit = FitOptions {
                kind: discriminant(best.method),
                shrinkage: h("shrinkage"),
                target: shrink_target(table.x.ncols(), labels, fold_rows),
            };
            let model = Fitted::fit(&table.x, &labels.index, labels.names.len(), &fit)?;
            crate::model_file::check_tables(&model, &[])?;
            (
                Tables::Discriminant {
                    kind: if best.method == Kind::Lda {
                        ModelKind::Lda
                    } else {
                        ModelKind::Qda
                    },
                    classes: class_records(&model),
                },
                model.feature_mean,
                model.feature_scale,
            )
        }
        Kind::Ridge => {
            let m = Ridge::fit(&table.x, need_targets()?, h("lambda"))?;
            (
                Tables::Ridge {
                    weights: m.weight_rows(),
                    intercept: m.intercept,
                },
                m.mean,
                m.scale,
            )
        }
        Kind::KernelRidge => {
            let m = KernelRidge::fit(
                &table.x,
                need_targets()?,
                KRR_SUPPORT,
                h("width"),
                h("lambda"),
            )?;
            (
                Tables::KernelRidge {
                    gamma: m.gamma,
                    support: regress::rows_of(&m.support),
                    alpha: regress::rows3(&m.alpha),
                    intercept: m.intercept,
                },
                m.mean,
                m.scale,
            )
        }
        Kind::Gp => {
            let what = "fitting gp (learning its length scales on every training row)";
            let mut step = |done: usize, of: usize| progress(what, done, of);
            gp_tables(Gp::fit(&table.x, need_targets()?, &GP, &mut step)?)
        }
        Kind::Mlp => {
            let opts = MlpOptions {
                starts: MLP_FINAL_STARTS,
                seed,
                ..mlp_options(&best.hyperparameters)
            };
            progress("fitting mlp", 0, 1);
            let m = Mlp::fit(&table.x, need_targets()?, &opts)?;
            (
                Tables::Mlp {
                    activation: m.activation,
                    layers: m.dense(),
                    target_mean: m.target_mean,
                    target_scale: m.target_scale,
                },
                m.mean,
                m.scale,
            )
        }
        Kind::Average => average_tables(
            table,
            members,
            targets,
            (classes, fold_rows),
            (seed, progress),
        )?,
        Kind::Knn => {
            let weighting = if h("distance_weighted") > 0.5 {
                Weighting::Distance
            } else {
                Weighting::Uniform
            };
            let m = Knn::fit(
                &table.x,
                need_targets()?,
                h("k").max(1.0) as usize,
                weighting,
            )?;
            (
                Tables::Knn {
                    k: m.k,
                    weighting,
                    support: regress::rows_of(&m.support),
                    targets: m.targets.clone(),
                },
                m.mean,
                m.scale,
            )
        }
    })
}

/// A fitted Gaussian process's tables and standardisation: its support rows scaled back by
/// the length scales, the predictor's scales the features' spreads over them.
fn gp_tables(m: Gp) -> (Tables, Vec<f64>, Vec<f64>) {
    let k = &m.predictor;
    let scale = k
        .scale
        .iter()
        .zip(&m.length_scales)
        .map(|(s, l)| s / l)
        .collect();
    (
        Tables::Gp {
            support: (0..k.support.nrows())
                .map(|i| {
                    (k.support.row(i).iter())
                        .zip(&m.length_scales)
                        .map(|(v, l)| v * l)
                        .collect()
                })
                .collect(),
            alpha: regress::rows3(&k.alpha),
            intercept: k.intercept,
            length_scales: m.length_scales.clone(),
            signal_variance: m.signal_variance,
            noise_variance: m.noise_variance,
        },
        k.mean.clone(),
        scale,
    )
}

/// An average's tables: each of its `members` fitted on every row ([`fit_final`]), the
/// standardisation its first member's.
fn average_tables(
    table: &Table,
    members: &[Candidate],
    targets: Option<&[Target3]>,
    classes: (Option<&(Labels, ClassInfo)>, usize),
    (seed, progress): (u64, Progress<'_>),
) -> Result<(Tables, Vec<f64>, Vec<f64>), TabularError> {
    let mut fitted = Vec::with_capacity(members.len());
    for m in members {
        let (tables, feature_mean, feature_scale) =
            fit_final(table, m, targets, classes, &[], (seed, progress))?;
        fitted.push(Member {
            method: m.method,
            hyperparameters: m.hyperparameters.clone(),
            feature_mean,
            feature_scale,
            tables,
        });
    }
    let (mean, scale) = fitted
        .first()
        .map(|m| (m.feature_mean.clone(), m.feature_scale.clone()))
        .ok_or_else(|| usage(Misuse::EmptyAverage))?;
    Ok((Tables::Average { members: fitted }, mean, scale))
}
