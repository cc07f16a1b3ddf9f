//! Whether a cross-validated score is better than guessing without the features. A classifier
//! whose accuracy is the commonest class's share, or a regressor whose position error is that
//! of always answering the training rows' mean position, has learnt nothing from its features
//! (labels that do not belong to their rows, a sensor that did not sense the touches), however
//! its number reads: 26 % of four classes, or 39 mm on a 10 cm sheet, is what a guess scores.

// Reads untrusted bytes (a file's rows): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

/// Standard errors of the guess a cross-validated score must clear to count as better: within
/// two, a score is what guessing gives about one time in twenty or more.
pub const MARGIN: f64 = 2.0;

/// A cross-validated score within [`MARGIN`] standard errors of guessing.
#[derive(Clone, Debug, PartialEq)]
pub enum NoBetter {
    /// A classifier: its accuracy, and the commonest class's share of the `rows`.
    Classes {
        /// Cross-validated accuracy (0..1).
        accuracy: f64,
        /// The commonest class's share of the rows (0..1): always guessing it scores that.
        commonest: f64,
        /// Rows cross-validated.
        rows: usize,
    },
    /// A regressor: its mean position error, and that of always guessing the mean position of
    /// the rows each fold trains on (mm).
    Positions {
        /// Cross-validated mean position error, mm.
        error_mm: f64,
        /// The guess's mean error on the same held-out rows, mm.
        guess_mm: f64,
    },
}

/// A classifier's cross-validated `accuracy` against always guessing the commonest class,
/// `counts` the rows of each class: [`NoBetter::Classes`] when it is not above the commonest
/// class's share by [`MARGIN`] standard errors of a binomial count at that share.
#[must_use]
pub fn classes(accuracy: f64, counts: &[usize]) -> Option<NoBetter> {
    let rows: usize = counts.iter().sum();
    if rows == 0 || counts.len() < 2 || !accuracy.is_finite() {
        return None;
    }
    let p = *counts.iter().max()? as f64 / rows as f64;
    let standard_error = (p * (1.0 - p) / rows as f64).sqrt();
    (accuracy <= p + MARGIN * standard_error).then_some(NoBetter::Classes {
        accuracy,
        commonest: p,
        rows,
    })
}

/// A regressor's cross-validated mean position error `error_mm` against always guessing the
/// mean (x, y) of the rows each fold trains on: `t` the rows' positions (m; a third value is
/// not compared), `fold[r]` row r's fold. [`NoBetter::Positions`] when the error is not below
/// the guess's mean error by [`MARGIN`] standard errors of that mean.
#[must_use]
pub fn positions(error_mm: f64, t: &[[f64; 3]], fold: &[usize]) -> Option<NoBetter> {
    let n = t.len();
    if n < 2 || fold.len() != n || !error_mm.is_finite() {
        return None;
    }
    let k = fold.iter().max()? + 1;
    let (mut sums, mut counts) = (vec![[0.0; 2]; k], vec![0usize; k]);
    for (p, &f) in t.iter().zip(fold) {
        let (s, c) = (sums.get_mut(f)?, counts.get_mut(f)?);
        *s = [s[0] + p[0], s[1] + p[1]];
        *c += 1;
    }
    let total = sums
        .iter()
        .fold([0.0; 2], |a, s| [a[0] + s[0], a[1] + s[1]]);
    let guesses: Vec<f64> = t
        .iter()
        .zip(fold)
        .map(|(p, &f)| {
            let (s, c) = (sums.get(f)?, *counts.get(f)?);
            let rest = (n - c) as f64;
            (rest > 0.0).then(|| {
                let mean = [(total[0] - s[0]) / rest, (total[1] - s[1]) / rest];
                1e3 * (p[0] - mean[0]).hypot(p[1] - mean[1])
            })
        })
        .collect::<Option<_>>()?;
    let guess_mm = guesses.iter().sum::<f64>() / n as f64;
    let variance = guesses.iter().map(|g| (g - guess_mm).powi(2)).sum::<f64>() / (n - 1) as f64;
    let standard_error = (variance / n as f64).sqrt();
    (error_mm >= guess_mm - MARGIN * standard_error)
        .then_some(NoBetter::Positions { error_mm, guess_mm })
}

impl std::fmt::Display for NoBetter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let why = |targets: &str| {
            format!(
                "{targets} that do not belong to their rows, or a sensor that did not sense the \
                 touches: not connected, another sheet, or places pressed other than labelled"
            )
        };
        match self {
            Self::Classes {
                accuracy,
                commonest,
                rows,
            } => write!(
                f,
                "the cross-validated accuracy, {:.1} %, is no better than always guessing the \
                 commonest class ({:.1} % of the {rows} rows): the features do not tell the \
                 classes apart ({})",
                100.0 * accuracy,
                100.0 * commonest,
                why("labels")
            ),
            Self::Positions { error_mm, guess_mm } => write!(
                f,
                "the cross-validated mean error, {error_mm:.2} mm, is no better than always \
                 guessing the training rows' mean position ({guess_mm:.2} mm): the features do \
                 not tell the positions apart ({})",
                why("positions")
            ),
        }
    }
}
