//! The classifiers' search: every shrinkage of QDA or LDA scored by cross-validation.

// Reads untrusted bytes (a file): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use super::*;

/// The classes of a table: its labels, or the grid cells of its positions (cells without
/// rows dropped), with each class's position where known.
pub(super) fn class_targets(
    table: &Table,
    grid: Option<(usize, usize)>,
) -> Result<Option<(Labels, ClassInfo)>, TabularError> {
    if let Some((rows, cols)) = grid {
        let p = table
            .positions
            .as_ref()
            .ok_or_else(|| usage(Misuse::GridNeedsPositions))?;
        if rows.saturating_mul(cols) < 2 || rows > GRID_MOST || cols > GRID_MOST {
            return Err(usage(Misuse::EmptyGrid { rows, cols }));
        }
        let g = Grid::over(p, rows, cols);
        let cells: Vec<usize> = p.iter().map(|&q| g.cell(q)).collect();
        let mut used: Vec<usize> = cells.clone();
        used.sort_unstable();
        used.dedup();
        let of: BTreeMap<usize, u16> = used
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u16))
            .collect();
        let labels = Labels {
            index: cells
                .iter()
                .map(|c| of.get(c).copied().unwrap_or(0))
                .collect(),
            names: used.iter().map(|&c| g.name(c)).collect(),
        };
        let info = ClassInfo {
            names: labels.names.clone(),
            centres: Some(used.iter().map(|&c| g.centre(c)).collect()),
            grid: Some(g),
            label_type: None,
        };
        return Ok(Some((labels, info)));
    }
    let Some(text) = &table.labels else {
        return Ok(None);
    };
    let labels = Labels::from_text(text)?;
    let centres = table.positions.as_ref().map(|p| {
        let mut sum = vec![[0.0, 0.0, 0.0]; labels.names.len()];
        for (&c, q) in labels.index.iter().zip(p) {
            if let Some(s) = sum.get_mut(usize::from(c)) {
                *s = [s[0] + q[0], s[1] + q[1], s[2] + 1.0];
            }
        }
        sum.iter()
            .map(|s| [s[0] / s[2].max(1.0), s[1] / s[2].max(1.0)])
            .collect()
    });
    let info = ClassInfo {
        names: labels.names.clone(),
        centres,
        grid: None,
        label_type: None,
    };
    Ok(Some((labels, info)))
}

/// Every shrinkage of QDA or LDA, scored by cross-validation (accuracy; and the mean distance
/// from the true position to the predicted class's position when the rows have positions);
/// `estimate_s` its time, said beforehand.
pub(super) fn search_classifier(
    table: &Table,
    method: Kind,
    labels: &Labels,
    fold: &[usize],
    estimate_s: Option<f64>,
    progress: Progress<'_>,
) -> Result<Vec<Candidate>, TabularError> {
    let classes = labels.names.len();
    if classes < 2 {
        return Err(usage(Misuse::OneClass {
            class: labels.names.first().cloned().unwrap_or_default(),
        }));
    }
    // Each class once: no fold can both learn and test one (it was "cross-validation needs
    // at least 2 folds (1 given)", of folds nobody gave).
    let mut count = vec![0_usize; classes];
    for &c in &labels.index {
        if let Some(n) = count.get_mut(usize::from(c)) {
            *n += 1;
        }
    }
    if count.iter().all(|&n| n < 2) {
        let rows = labels.index.len();
        return Err(usage(Misuse::OneRowClasses { classes, rows }));
    }

    // QDA and LDA hold their tables in single precision, as the board does: a feature whose
    // level or spread f32 cannot hold is said, not fitted into tables the check refuses.
    if let Some(failure) = beyond_single_precision(table) {
        return Ok(SHRINKAGES
            .iter()
            .map(|&lambda| Candidate {
                failure: Some(failure.clone()),
                ..Candidate::new(method, params(&[("shrinkage", lambda)]))
            })
            .collect());
    }
    let kind = discriminant(method);
    let k = fold.iter().max().map_or(0, |m| m + 1);
    let what = format!(
        "cross-validating {} ({} shrinkages, {k} folds, then the final fit{})",
        method.name(),
        SHRINKAGES.len(),
        estimate_s.map_or(String::new(), |s| format!(
            ": {}",
            crate::pipeline::cost::about(s)
        ))
    );
    let mut out = Vec::new();
    for (i, &lambda) in SHRINKAGES.iter().enumerate() {
        progress(&what, i, SHRINKAGES.len());
        let fit = FitOptions {
            kind,
            shrinkage: lambda,
            // Toward the diagonal when a fold has too few rows to pool.
            target: shrink_target(table.x.ncols(), labels, fold_rows(fold)),
        };
        let conf = match cross_validate_fast(&table.x, &labels.index, classes, &fit, fold) {
            // A fold whose training rows lack some class (blocks of a recording): fit on the
            // classes present, and count the absent class's rows as missed.
            Err(FitError::EmptyClass { .. }) => cv_present_classes(&table.x, labels, &fit, fold),
            other => other,
        };
        // A fit that fails scores nothing; why is kept to say if nothing else fits.
        out.push(Candidate {
            cv_accuracy: conf.as_ref().ok().map(Confusion::accuracy),
            failure: conf.err().map(|e| e.to_string()),
            ..Candidate::new(method, params(&[("shrinkage", lambda)]))
        });
    }
    progress(&what, SHRINKAGES.len(), SHRINKAGES.len());
    Ok(out)
}

/// The first feature whose mean or spread single precision cannot hold (beyond about
/// 3.4e38, or a spread below 1.2e-38), in words.
fn beyond_single_precision(table: &Table) -> Option<String> {
    let (mean, scale) = crate::fit::standardisation(&table.x);
    let held = |v: f64| (v as f32).is_finite() && (v == 0.0 || (v as f32).is_normal());
    let (j, (m, sd)) = mean
        .iter()
        .zip(&scale)
        .enumerate()
        .find(|(_, (m, sd))| !held(**m) || !held(**sd))?;
    let name = table.feature_names.get(j).cloned().unwrap_or_default();
    Some(format!(
        "feature {name}: mean {m:.3e}, spread {sd:.3e}, beyond single precision (1.2e-38 to \
         3.4e38), in which QDA and LDA hold their tables as the board does: give it in other \
         units"
    ))
}

/// QDA shrinks toward the pooled covariance, unless the `rows` a fit has (those of the
/// smallest cross-validation training set, [`fold_rows`]: the saved model is fitted toward
/// the target its cross-validation scored) leave fewer degrees of freedom than features
/// (then toward the diagonal, which needs no pooled estimate of full rank).
pub(super) fn shrink_target(p: usize, labels: &Labels, rows: usize) -> Target {
    if rows <= p + labels.names.len() {
        Target::Diagonal
    } else {
        Target::Pooled
    }
}

/// The training rows of the smallest fold's training set (`fold`: each row's fold).
pub(super) fn fold_rows(fold: &[usize]) -> usize {
    let mut sizes: BTreeMap<usize, usize> = BTreeMap::new();
    for &f in fold {
        *sizes.entry(f).or_default() += 1;
    }
    fold.len() - sizes.values().copied().max().unwrap_or(0)
}

pub(super) fn discriminant(method: Kind) -> ModelKind {
    if method == Kind::Lda {
        ModelKind::Lda
    } else {
        ModelKind::Qda
    }
}

/// Cross-validation where a fold's training rows may lack classes: each fold fits on the
/// classes it has (relabelled), and held-out rows of a class it lacks count as missed.
///
/// # Errors
/// The first fold's that cannot be fitted.
pub(super) fn cv_present_classes(
    x: &DMatrix<f64>,
    labels: &Labels,
    fit: &FitOptions,
    fold: &[usize],
) -> Result<Confusion, FitError> {
    let classes = labels.names.len();
    let k = fold.iter().max().map_or(0, |m| m + 1);
    let mut conf = Confusion::new(classes);
    for f in 0..k {
        let train: Vec<usize> = (0..x.nrows())
            .filter(|&r| fold.get(r) != Some(&f))
            .collect();
        let test: Vec<usize> = (0..x.nrows())
            .filter(|&r| fold.get(r) == Some(&f))
            .collect();
        let y = |r: usize| labels.index.get(r).copied().unwrap_or(0);
        let mut present: Vec<u16> = train.iter().map(|&r| y(r)).collect();
        present.sort_unstable();
        present.dedup();
        if present.len() < 2 {
            return Err(FitError::NoCandidates(
                "a fold's training rows hold one class only (a class with fewer rows than \
                 folds: give it more rows, fewer folds (--folds, folds=), or leave it out)",
            ));
        }
        let local: BTreeMap<u16, u16> = present
            .iter()
            .enumerate()
            .map(|(i, &c)| (c, i as u16))
            .collect();
        let yt: Vec<u16> = train
            .iter()
            .map(|&r| local.get(&y(r)).copied().unwrap_or(0))
            .collect();
        let model = Fitted::fit(&rows_of(x, &train), &yt, present.len(), fit)?;
        // Tables a board would refuse (and the model file's reader with it) score nothing.
        crate::model_file::check_tables(&model, &[])?;
        let mut row = vec![0.0; x.ncols()];
        for &r in &test {
            for (j, v) in row.iter_mut().enumerate() {
                *v = x[(r, j)];
            }
            let predicted = present
                .get(usize::from(model.predict(&row)))
                .copied()
                .unwrap_or(0);
            conf.add(y(r), predicted);
        }
    }
    Ok(conf)
}
