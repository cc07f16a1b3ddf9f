//! A prepared model's predictions: checked features in, checked predictions out.

use super::*;

impl Prepared {
    /// Features it reads per row.
    #[must_use]
    pub fn features(&self) -> usize {
        self.features
    }

    /// Predicts every row of `x` (n x p, the training files' units), as
    /// [`TableModel::predict`].
    ///
    /// # Errors
    /// [`TabularError::Usage`] when `x` has another feature count, a value that is NaN or
    /// infinite, or a prediction that is not finite (tables that overflow).
    pub fn predict(&self, x: &DMatrix<f64>) -> Result<Vec<Prediction>, TabularError> {
        if x.ncols() != self.features {
            return Err(usage(Misuse::FeatureCount {
                data: x.ncols(),
                model: self.features,
                rows: Some(x.nrows()),
            }));
        }
        finite_features(x)?;
        let predicted = self.predict_finite(x)?;
        if let Some(row) = predicted
            .iter()
            .position(|p| p.target.is_some_and(|t| t.iter().any(|v| !v.is_finite())))
        {
            return Err(usage(Misuse::NonFinitePrediction { row }));
        }
        Ok(predicted)
    }

    /// [`Prepared::predict`] of finite features.
    fn predict_finite(&self, x: &DMatrix<f64>) -> Result<Vec<Prediction>, TabularError> {
        let regression = |t: Vec<Target3>| {
            t.into_iter()
                .map(|t| Prediction {
                    class: None,
                    target: Some(t),
                })
                .collect()
        };
        Ok(match &self.ready {
            Ready::Discriminant(m) => {
                let centres = self.centres.as_ref();
                let mut row = vec![0.0; x.ncols()];
                (0..x.nrows())
                    .map(|r| {
                        for (j, v) in row.iter_mut().enumerate() {
                            *v = x[(r, j)];
                        }
                        // The argmax of discriminants that overflow names an arbitrary class.
                        let class = (m.predict_finite(&row))
                            .ok_or(usage(Misuse::NonFinitePrediction { row: r }))?;
                        Ok(Prediction {
                            class: Some(class),
                            target: centres
                                .and_then(|c| c.get(usize::from(class)))
                                .map(|c| [c[0], c[1], 0.0]),
                        })
                    })
                    .collect::<Result<_, TabularError>>()?
            }
            Ready::Ridge(m) => regression(m.predict_many(x)),
            Ready::KernelRidge(m) => regression(m.predict_many(x)),
            Ready::Knn(m) => regression(m.predict_many(x)),
            Ready::Mlp(m) => regression(m.predict_many(x)),
            Ready::Average(members) => {
                let mut sum = vec![[0.0; 3]; x.nrows()];
                // In turn: each member on a thread of its own was slower on the development
                // machine for the usual two members (their large matrices page-faulted afresh
                // in each thread's heap), and faster only for three on two cores.
                for m in members {
                    for (s, p) in sum.iter_mut().zip(m.predict(x)?) {
                        let t = p.target.unwrap_or([0.0; 3]);
                        *s = [s[0] + t[0], s[1] + t[1], s[2] + t[2]];
                    }
                }
                let k = members.len().max(1) as f64;
                regression(sum.into_iter().map(|s| s.map(|v| v / k)).collect())
            }
        })
    }
}
