//! How a table's features compare in size with those a model was trained on: rows in
//! another unit or at another gain (millivolts where volts were trained) are predicted
//! without an error, and wrongly.

use super::*;

/// How far the rows' features may be from the training's, a factor either way
/// ([`TableModel::features_scale`]), before it is said: a unit (1 000 from V to mV) or a
/// gain setting, where a session's drift changes the features by tens of per cent.
pub const FEATURE_SCALE_SAID: f64 = 10.0;

impl TableModel {
    /// How many times the training's features those of `x` are (n x p, in the model's column
    /// order): [`features_scale`] against its standardisation. None when there is nothing
    /// to compare: features referenced to frames before each press (relative changes, which
    /// carry no unit) or standardised by each group's own statistics.
    #[must_use]
    pub fn features_scale(&self, x: &DMatrix<f64>) -> Option<f64> {
        if self.per_group || self.reference.is_some() {
            return None;
        }
        features_scale(&self.feature_mean, &self.feature_scale, x)
    }

    /// What to say when `x`'s features are past [`FEATURE_SCALE_SAID`] times the training's
    /// either way ([`features_scale`](Self::features_scale)); None when they are alike.
    #[must_use]
    pub fn features_scale_note(&self, x: &DMatrix<f64>) -> Option<String> {
        features_scale_note(self.features_scale(x)?)
    }
}

/// How many times the training's features, of `mean` and standard deviation `scale` per
/// column, those of `x` are (n x p): over the columns, the median of each one's root mean
/// square against the training's. None when `x` has no rows or its columns are all zeros.
#[must_use]
pub fn features_scale(mean: &[f64], scale: &[f64], x: &DMatrix<f64>) -> Option<f64> {
    if x.nrows() == 0 {
        return None;
    }
    let n = x.nrows() as f64;
    let mut ratios: Vec<f64> = (x.column_iter().zip(mean))
        .zip(scale)
        .filter_map(|((column, mean), scale)| {
            let trained = mean.hypot(*scale);
            // Scaled by the largest, so that values past 1e154 do not overflow their squares
            // (features of 1e200 were said nothing of).
            let big = column.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let rms = if big > 0.0 && big.is_finite() {
                big * (column.iter().map(|v| (v / big).powi(2)).sum::<f64>() / n).sqrt()
            } else {
                big
            };
            (trained > 0.0 && rms > 0.0 && rms.is_finite()).then(|| rms / trained)
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    ratios.get(ratios.len().checked_sub(1)? / 2).copied()
}

/// What to say of features `s` times the training's ([`features_scale`]) when past
/// [`FEATURE_SCALE_SAID`] either way; None when they are alike.
#[must_use]
pub fn features_scale_note(s: f64) -> Option<String> {
    if (1.0 / FEATURE_SCALE_SAID..=FEATURE_SCALE_SAID).contains(&s) {
        return None;
    }
    // Two significant digits: "1000 times", "1/12 of", "1.0e200 times".
    let said = |v: f64| {
        let step = 10f64.powf(v.log10().floor() - 1.0);
        if v < 1e6 {
            ((v / step).round() * step).to_string()
        } else {
            format!("{v:.1e}")
        }
    };
    let times = if s > 1.0 {
        format!("{} times", said(s))
    } else {
        format!("1/{} of", said(1.0 / s))
    };
    Some(format!(
        "the features are {times} those the model was trained on (the median over the \
         columns of their root mean square): another unit or gain than the training's \
         (mV where V was trained)? The predictions are not the model's"
    ))
}
