//! What training a board model on an et dataset holds and takes, from the data's shape and
//! before any of it: its cross-validations keep each fold's sufficient statistics (a p x p
//! table per class and fold) and classify every observation against every class's bound
//! once per shrinkage candidate, so both grow with the classes: a 100 x 100 grid (10 000
//! classes, 200 000 observations of 96 features) held 11 GB for over 5 minutes without a
//! word, where a 30 x 30 grid trains in 9 s.

use et_core::model::ModelKind;
use nalgebra::DMatrix;

use crate::dataset::Dataset;
use crate::fastcv::Prepared;
use crate::fit::{FitOptions, Target};

use super::SHRINKAGE_CANDIDATES;

/// The shape of one training: observations, features, classes, the k of the k-fold
/// cross-validation, visits, and whether the shrinkage is chosen (else given).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shape {
    /// Observations n.
    pub n: usize,
    /// Features p (after --keep).
    pub p: usize,
    /// Classes C.
    pub classes: usize,
    /// Folds k of the k-fold cross-validation.
    pub folds: usize,
    /// Visits (two or more: a leave-one-visit-out cross-validation as well).
    pub visits: usize,
    /// Whether the shrinkage is chosen by cross-validation over the candidates.
    pub choose: bool,
}

/// The first steps of each class's forward substitution taken for a block at once
/// (`fastcv`'s lead): a product of C d x d per observation.
const LEAD: f64 = crate::fastcv::LEAD as f64;

/// Classes looked at beyond the bounds' product, per observation (about 8 on 49 classes).
const LOOKED_AT: f64 = 8.0;

impl Shape {
    /// The partitions' folds: the k folds, and each visit when left out one at a time.
    fn partition_folds(&self) -> f64 {
        let by_visit = if self.visits >= 2 { self.visits } else { 0 };
        (self.folds + by_visit) as f64
    }

    /// Bytes held at most: each partition's sufficient statistics (C p x p tables per fold),
    /// each thread's confusion (C x C counts) and fold model (C packed factors and bounds),
    /// the final fit's tables, and the data's copies. Within a fifth of what
    /// `/usr/bin/time -v et train --data` measured on 30 x 30 to 100 x 100 grids.
    #[must_use]
    pub fn bytes(&self) -> u64 {
        let (n, p, c) = (self.n as f64, self.p as f64, self.classes as f64);
        let threads = threads();
        let stats = c * self.partition_folds() * (p * p + p) * 8.0;
        // Two cross-validations at once beside the final fit, each on all threads.
        let confusions = (2.0 * threads + 2.0) * c * c * 4.0;
        let fold_models = 2.0 * threads * c * (p * (p + 1.0) / 2.0 + p + LEAD * LEAD) * 8.0;
        let fit = 2.0 * c * p * p * 8.0;
        let data = 4.0 * n * p * 8.0;
        let total = stats + confusions + fold_models + fit + data;
        // A float past u64's range saturates.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let bytes = total as u64;
        bytes
    }

    /// Multiply-adds of the whole training, as the factors' and the observations': per
    /// cross-validation, each fold's factors (one per class for QDA, p^3 / 3 each; one for
    /// LDA), and every observation's bounds and substitutions (QDA: C d^2 and about 8
    /// classes' first steps; LDA: C p); one per candidate, then the final k-fold and
    /// leave-one-visit-out beside the fit's factors, and the sums of outer products once
    /// per partition.
    #[must_use]
    pub fn multiply_adds(&self, kind: ModelKind) -> [f64; 2] {
        let (n, p, c, k) = (
            self.n as f64,
            self.p as f64,
            self.classes as f64,
            self.folds as f64,
        );
        let factor = p.powi(3) / 3.0;
        let (factors, per_row) = if kind == ModelKind::Qda {
            (c, c * LEAD.min(p).powi(2) + c.min(LOOKED_AT) * p * LEAD)
        } else {
            (1.0, c * p)
        };
        let several = self.visits >= 2;
        let by_visit = if several { self.visits as f64 } else { 0.0 };
        // Cross-validations: each is one pass over every observation, and k (or the
        // visits') factors per class.
        let candidates = if self.choose {
            SHRINKAGE_CANDIDATES.len() as f64
        } else {
            0.0
        };
        let (passes, fold_fits) = if several {
            (candidates + 2.0, candidates * by_visit + k + by_visit)
        } else {
            (candidates + 1.0, (candidates + 1.0) * k)
        };
        let partitions = if several { 2.0 } else { 1.0 };
        [
            (fold_fits + 1.0) * factors * factor,
            passes * n * per_row + partitions * n * p * p,
        ]
    }

    /// Seconds of the whole training: its [`multiply_adds`](Self::multiply_adds) at
    /// `seconds_per` each (the factors', the observations': [`seconds_per`]).
    #[must_use]
    pub fn seconds(&self, kind: ModelKind, seconds_per: [f64; 2]) -> f64 {
        let [factors, rows] = self.multiply_adds(kind);
        factors * seconds_per[0] + rows * seconds_per[1]
    }
}

/// Seconds a training of `shape` on `data` is estimated to take: counted at a Cholesky
/// factor's rate first (about a third of the time taken), and where that says a second or
/// more, at the rates of its own timed pieces ([`seconds_per`]). The pieces cost about one
/// pass over a small training's data, as much as a training of a second or two itself,
/// whose estimate needs no precision.
#[must_use]
pub fn estimate(shape: &Shape, data: &Dataset, kind: ModelKind, seed: u64) -> f64 {
    const QUICK_S: f64 = 1.0;
    let quick = shape.seconds(kind, cholesky_seconds_per(shape.p, shape.folds));
    if quick < QUICK_S {
        quick
    } else {
        shape.seconds(kind, seconds_per(data, kind, shape.folds, seed))
    }
}

/// [`seconds_per`] at the Cholesky factor's rate on the threads `folds` folds use.
fn cholesky_seconds_per(p: usize, folds: usize) -> [f64; 2] {
    let each = 1.0 / (cholesky_rate(p) * threads().min(folds as f64));
    [each, each]
}

/// Seconds a multiply-add of the factors and of the observations' work take in this
/// training on this machine (on the threads it uses): `data`'s first classes (as many as make
/// about 3 x 10^8 of the factors' multiply-adds) cross-validated over `folds` twice, as they are and with each
/// observation eight times, timed; the second's extra time is the observations'. The bounds
/// and the pruning cost more than their multiply-adds, the factors less: one rate for both
/// (a Cholesky factor's) said a third of the time a 30 x 30 or 50 x 50 grid took, one rate
/// from a piece of few classes nearly twice it. The Cholesky factor's rate for both where
/// the pieces do not fit.
#[must_use]
pub fn seconds_per(data: &Dataset, kind: ModelKind, folds: usize, seed: u64) -> [f64; 2] {
    let (n, p, classes) = (data.x.nrows(), data.x.ncols(), data.centres.len());
    let shape = |classes: usize, n: usize| Shape {
        n,
        p,
        classes,
        folds,
        visits: 1,
        choose: false,
    };
    let mut first = classes.min(2);
    while first < classes && shape(first, n * first / classes).multiply_adds(kind)[0] < 3e8 {
        first = (first * 2).min(classes);
    }
    let rows: Vec<usize> = (0..n).filter(|&r| usize::from(data.y[r]) < first).collect();
    const REPEATS: usize = 8;
    let timed = |repeats: usize| {
        let rows: Vec<usize> = rows
            .iter()
            .copied()
            .cycle()
            .take(rows.len() * repeats)
            .collect();
        let x = data.x.select_rows(&rows);
        let y: Vec<u16> = rows.iter().map(|&r| data.y[r]).collect();
        let started = std::time::Instant::now();
        let prepared = Prepared::new(&x, &y, first).ok()?;
        let part = prepared
            .partition(&crate::cv::folds(&y, folds, seed))
            .ok()?;
        let options = FitOptions {
            kind,
            shrinkage: 0.1,
            target: Target::Diagonal,
        };
        prepared.cross_validate(&part, &options).ok()?;
        Some((
            started.elapsed().as_secs_f64(),
            shape(first, rows.len()).multiply_adds(kind),
        ))
    };
    if let (Some((t1, [f, r1])), Some((t8, [_, r8]))) = (timed(1), timed(REPEATS)) {
        // The final fit's factors were not in these pieces.
        let f = f * folds as f64 / (folds as f64 + 1.0);
        let per_row = (t8 - t1) / (r8 - r1);
        let per_factor = (t1 - r1 * per_row) / f;
        if per_row > 0.0 && per_factor > 0.0 && per_row.is_finite() && per_factor.is_finite() {
            return [per_factor, per_row];
        }
    }
    cholesky_seconds_per(p, folds)
}

/// Multiply-adds a second of nalgebra's Cholesky factor of min(`p`, 2000) features, timed
/// (repeated to at least 5 ms).
pub fn cholesky_rate(p: usize) -> f64 {
    let m = p.clamp(2, 2000);
    let a = DMatrix::from_fn(m, m, |i, j| {
        if i == j {
            m as f64
        } else {
            ((i * 31 + j * 17) % 97) as f64 / 97.0
        }
    });
    let started = std::time::Instant::now();
    let mut repeats = 0_u32;
    while repeats == 0 || started.elapsed().as_secs_f64() < 5e-3 {
        let _ = a.clone().cholesky();
        repeats += 1;
    }
    let seconds = started.elapsed().as_secs_f64().max(f64::MIN_POSITIVE);
    f64::from(repeats) * (m as f64).powi(3) / 3.0 / seconds
}

/// An estimate as people say it: "about 14 min", "about 0.08 s" ([`time_said`]).
#[must_use]
pub fn about(seconds: f64) -> String {
    format!("about {}", time_said(seconds))
}

/// Time as people say it, with its unit: two significant digits below 10 s ("0.08 s",
/// "1.0e-9 s": a budget of 1e-9 s was "under a second", past an estimate "under a second"),
/// whole seconds below 100 s, then minutes, then hours. One formatter for every estimate and
/// budget et says (tables' and datasets' trainings alike).
#[must_use]
pub fn time_said(seconds: f64) -> String {
    if seconds <= 0.0 || !seconds.is_finite() {
        format!("{seconds} s")
    } else if seconds < 1e-3 {
        format!("{seconds:.1e} s")
    } else if seconds < 9.95 {
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let decimals = (1.0 - seconds.log10().floor()).max(0.0) as usize;
        format!("{seconds:.decimals$} s")
    } else if seconds < 99.5 {
        format!("{seconds:.0} s")
    } else if seconds < 5940.0 {
        format!("{} min", (seconds / 60.0).round())
    } else {
        format!("{:.1} h", seconds / 3600.0)
    }
}

/// The machine's threads (1 when unknown).
pub(crate) fn threads() -> f64 {
    std::thread::available_parallelism().map_or(1.0, |t| t.get() as f64)
}
