//! How `auto` chooses among the searched candidates beyond the lowest cross-validated error:
//! the steadiest of the close ones without groups, and the average of several methods when
//! it cross-validates better.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

/// Contiguous blocks of rows over which a candidate's error is checked for steadiness when the
/// rows have no groups.
pub const STABILITY_BLOCKS: usize = 5;
/// Candidates whose cross-validated error is within this share of the best are close: without
/// groups, `auto` takes the steadiest of them over [`STABILITY_BLOCKS`].
pub const CLOSE: f64 = 0.05;

/// `auto` averages at most this many methods ...
pub const AVERAGE_MOST: usize = 3;
/// ... and keeps the average when its cross-validated error is this share below the best
/// single method's.
pub const AVERAGE_GAIN: f64 = 0.02;

/// The candidates that cross-validated, best first, and what their ranking says.
///
/// A candidate whose fit on every row fails (a covariance that cross-validated but is
/// singular on the whole set) gives way to the next. Without groups (`grouped` false) nothing
/// in the rows shows a new session, so regressors are ranked by their plain error and their
/// error with the held-out channels drifted together (`Candidate::choice_loss`): a model that
/// latches onto a few channels, or needs every channel as it was, loses there what it would
/// lose on a new session, and one that holds but is coarse loses by its plain error; `auto`
/// then puts the steadiest of the close ones first ([`steadiest_close`]).
pub(super) fn rank(
    search: &[Candidate],
    choice: Choice,
    grouped: bool,
) -> (Vec<&Candidate>, Vec<String>) {
    let by_drift = !grouped;
    let mut ranked: Vec<&Candidate> = search.iter().filter(|c| c.loss().is_finite()).collect();
    ranked.sort_by(|a, b| a.choice_loss(by_drift).total_cmp(&b.choice_loss(by_drift)));
    let mut notes: Vec<String> = drift_note(&ranked, by_drift).into_iter().collect();
    if !grouped
        && choice == Choice::Auto
        && let Some((steadier, why)) = steadiest_close(&ranked, by_drift)
    {
        notes.push(why);
        ranked.insert(0, steadier);
    }
    (ranked, notes)
}

/// Without groups: among the best of each method within [`CLOSE`] of the best error, the one
/// whose error varies least over the recording's blocks, with why, when it is not the best.
pub(super) fn steadiest_close<'a>(
    ranked: &[&'a Candidate],
    by_drift: bool,
) -> Option<(&'a Candidate, String)> {
    let best = *ranked.first()?;
    if best.method.is_classifier() {
        return None;
    }
    let mut per_method: Vec<&Candidate> = Vec::new();
    for c in ranked {
        if !per_method.iter().any(|p| p.method == c.method) {
            per_method.push(c);
        }
    }
    let steadiest = per_method
        .iter()
        .filter(|c| c.choice_loss(by_drift) <= best.choice_loss(by_drift) * (1.0 + CLOSE))
        .min_by(|a, b| a.block_spread_mm().total_cmp(&b.block_spread_mm()))?;
    (steadiest.method != best.method && steadiest.block_spread_mm() < best.block_spread_mm()).then(
        || {
            (
                *steadiest,
                format!(
                    "{} ({:.2} mm{}) is within {:.0} % of {} ({:.2} mm) and steadier over the \
                     recording's {} blocks (their errors vary by {:.2} mm against {:.2}): chose {}",
                    steadiest.method.name(),
                    steadiest.choice_loss(by_drift),
                    if by_drift {
                        format!(", {} of its plain and drifted errors", drift_weighting())
                    } else {
                        String::new()
                    },
                    100.0 * CLOSE,
                    best.method.name(),
                    best.choice_loss(by_drift),
                    STABILITY_BLOCKS,
                    steadiest.block_spread_mm(),
                    best.block_spread_mm(),
                    steadiest.method.name()
                ),
            )
        },
    )
}

/// The best candidate of each regression method, best first.
pub(super) fn best_per_method<'a>(ranked: &[&'a Candidate]) -> Vec<&'a Candidate> {
    let mut out: Vec<&Candidate> = Vec::new();
    for c in ranked {
        if !c.method.is_classifier() && !out.iter().any(|p| p.method == c.method) {
            out.push(c);
        }
    }
    out
}

/// The mean of two or three methods' out-of-fold predictions (each method's best candidate;
/// the set whose mean cross-validates best), as a candidate, when it beats the best single
/// one by [`AVERAGE_GAIN`]; and its members. Methods that err differently average best, and
/// they need not be the two best alone.
pub(super) fn average_of_best(
    ranked: &[&Candidate],
    t: &[Target3],
    fold: &[usize],
    grouped: bool,
    by_drift: bool,
) -> Option<(Candidate, Vec<Candidate>)> {
    let bests = best_per_method(ranked);
    let best = bests.first()?.choice_loss(by_drift);
    // Every set of two or three methods (their best candidates), best first within a set.
    let k = bests.len();
    let sets: Vec<Vec<usize>> = (0..k)
        .flat_map(|a| (a + 1..k).map(move |b| vec![a, b]))
        .chain(
            (0..k)
                .flat_map(|a| (a + 1..k).flat_map(move |b| (b + 1..k).map(move |c| vec![a, b, c]))),
        )
        .filter(|set| set.len() <= AVERAGE_MOST)
        .collect();
    sets.into_iter()
        .filter_map(|set| {
            let members: Vec<Candidate> = set
                .iter()
                .filter_map(|&i| bests.get(i).map(|&c| c.clone()))
                .collect();
            let predictions: Vec<&[Vec<Target3>; 2]> = members
                .iter()
                .map(|c| c.out_of_fold.as_ref())
                .collect::<Option<_>>()?;
            // The members' mean prediction of each row, as measured (0) and drifted (1: each
            // draw's).
            let mean = |which: usize| -> Vec<Target3> {
                let len = predictions
                    .first()
                    .and_then(|p| p.get(which))
                    .map_or(0, Vec::len);
                (0..len)
                    .map(|r| {
                        let mut s = [0.0; 3];
                        for p in &predictions {
                            let q = p
                                .get(which)
                                .and_then(|v| v.get(r))
                                .copied()
                                .unwrap_or([0.0; 3]);
                            s = [s[0] + q[0], s[1] + q[1], s[2] + q[2]];
                        }
                        s.map(|v| v / predictions.len() as f64)
                    })
                    .collect()
            };
            let (measured, drifted) = (mean(0), mean(1));
            Some((
                Candidate {
                    cv_mean_error_mm: Some(mean_error(&measured, t)),
                    cv_block_errors_mm: block_errors(&Some(measured), t, fold, grouped),
                    cv_drifted_error_mm: Some(drifted_error(&drifted, t)),
                    ..Candidate::new(Kind::Average, params(&[("members", members.len() as f64)]))
                },
                members,
            ))
        })
        .filter(|(c, _)| c.choice_loss(by_drift) < best * (1.0 - AVERAGE_GAIN))
        .min_by(|a, b| {
            a.0.choice_loss(by_drift)
                .total_cmp(&b.0.choice_loss(by_drift))
        })
}

/// When ranking `by_drift` put first another method than the lowest plain cross-validated
/// error would have, a note that says so and why.
pub(super) fn drift_note(ranked: &[&Candidate], by_drift: bool) -> Option<String> {
    let chosen = *ranked.first()?;
    let plain = ranked.iter().min_by(|a, b| a.loss().total_cmp(&b.loss()))?;
    (by_drift && !chosen.method.is_classifier() && plain.method != chosen.method).then(|| {
        format!(
            "{} cross-validates best ({:.2} mm) but its error grows to {:.2} mm when the held-out \
             rows' channels drift as between sessions (gain {:.0} %, level {:.2} of each \
             channel's spread); {} holds better ({:.2} mm, {:.2} mm drifted): chose by both \
             errors ({} of the plain P and the drifted D), as nothing in rows without --groups \
             shows a new session",
            plain.method.name(),
            plain.loss(),
            plain.cv_drifted_error_mm.unwrap_or(f64::INFINITY),
            100.0 * DRIFT_GAIN,
            DRIFT_OFFSET,
            chosen.method.name(),
            chosen.loss(),
            chosen.cv_drifted_error_mm.unwrap_or(f64::INFINITY),
            drift_weighting(),
        )
    })
}

/// The mean error of each fold's rows (`grouped`: folds are groups), else of each of
/// [`STABILITY_BLOCKS`] contiguous blocks of rows, mm (`t` in m); None when a prediction is missing.
pub(super) fn block_errors(
    pred: &Option<Vec<Target3>>,
    t: &[Target3],
    fold: &[usize],
    grouped: bool,
) -> Option<Vec<f64>> {
    let pred = pred.as_ref()?;
    let n = t.len();
    let of = |r: usize| {
        if grouped {
            fold.get(r).copied().unwrap_or(0)
        } else {
            r * STABILITY_BLOCKS / n.max(1)
        }
    };
    let blocks = (0..n).map(of).max().map_or(0, |m| m + 1);
    let mut sum = vec![(0.0, 0usize); blocks];
    for (r, (p, q)) in pred.iter().zip(t).enumerate() {
        if let Some(s) = sum.get_mut(of(r)) {
            *s = (s.0 + 1e3 * (p[0] - q[0]).hypot(p[1] - q[1]), s.1 + 1);
        }
    }
    Some(
        sum.iter()
            .filter(|s| s.1 > 0)
            .map(|s| s.0 / s.1 as f64)
            .collect(),
    )
}

/// When no candidate could be fitted: why, in the methods' words (a class of one row, values
/// beyond single precision), each reason once with the methods that gave it.
pub(super) fn nothing_fitted(search: &[Candidate]) -> Option<TabularError> {
    let mut why: Vec<(String, Vec<&str>)> = Vec::new();
    for c in search {
        let Some(failure) = &c.failure else { continue };
        let name = c.method.name();
        match why.iter_mut().find(|(f, _)| f == failure) {
            Some((_, methods)) if !methods.contains(&name) => methods.push(name),
            Some(_) => {}
            None => why.push((failure.clone(), vec![name])),
        }
    }
    let said: Vec<String> = why
        .iter()
        .map(|(f, methods)| format!("{}: {f}", methods.join(", ")))
        .collect();
    (!said.is_empty()).then(|| TabularError::NothingFitted(said.join("; ")))
}

/// A note when the chosen candidate cross-validated no better than guessing
/// ([`crate::guess`]): a classifier against always the commonest of `labels`, a regressor
/// against the mean of the `targets` (m) each fold trains on (`fold`, each row's).
pub(super) fn guessing_note(
    best: &Candidate,
    targets: Option<&[Target3]>,
    labels: Option<&Labels>,
    fold: impl FnOnce() -> Vec<usize>,
) -> Option<String> {
    let no_better = match (best.method.is_classifier(), targets, labels) {
        (true, _, Some(l)) => {
            let mut counts = vec![0usize; l.names.len()];
            for &c in &l.index {
                *counts.get_mut(usize::from(c))? += 1;
            }
            crate::guess::classes(best.cv_accuracy?, &counts)
        }
        (false, Some(t), _) => crate::guess::positions(best.cv_mean_error_mm?, t, &fold()),
        _ => None,
    };
    no_better.map(|g| g.to_string())
}
