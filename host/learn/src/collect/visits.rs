//! Visits collected side by side on the machine's cores, their presses counted for a
//! progress display.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::RecvTimeoutError;

use et_core::ScanConfig;
use et_sim::frontend::FrontendSpec;
use et_sim::sheet::SheetSpec;

use super::{CollectError, Plan, collect_counting};
use crate::dataset::Dataset;

/// [`collect`](super::collect) once per seed in `seeds`, each a visit with its own
/// electrode positions, joined into one dataset (visit numbers in seed order);
/// `each(presses, visits)` is called with the presses scanned and the visits finished so far,
/// after each visit and every fifth of a second between (a progress bar's ETA from the first
/// seconds of a long visit). The visits are independent, so they run side by side on the
/// machine's cores; the dataset is the same as one visit after another would give.
///
/// # Errors
/// [`CollectError::NoVisits`] for no seeds; as [`collect`](super::collect) (the first failing
/// visit's error, in seed order).
pub fn collect_visits(
    spec: &SheetSpec,
    frontend: FrontendSpec,
    config: ScanConfig,
    centres: &[[f64; 2]],
    plan: &Plan,
    seeds: impl IntoIterator<Item = u64>,
    mut each: impl FnMut(usize, usize),
) -> Result<Dataset, CollectError> {
    let seeds: Vec<u64> = seeds.into_iter().collect();
    let pressed = AtomicUsize::new(0);
    let threads = std::thread::available_parallelism()
        .map_or(1, std::num::NonZero::get)
        .min(seeds.len());
    let mut visits: Vec<Option<Result<Dataset, CollectError>>> = Vec::new();
    visits.resize_with(seeds.len(), || None);
    std::thread::scope(|scope| {
        let (done, finished) = std::sync::mpsc::channel();
        for t in 0..threads {
            let (done, seeds, pressed) = (done.clone(), &seeds, &pressed);
            scope.spawn(move || {
                for (v, &seed) in seeds.iter().enumerate().skip(t).step_by(threads) {
                    let plan = Plan {
                        seed,
                        ..plan.clone()
                    };
                    let visit = collect_counting(spec, frontend, config, centres, &plan, pressed);
                    if done.send((v, visit)).is_err() {
                        return;
                    }
                }
            });
        }
        drop(done);
        let mut finished_visits = 0;
        loop {
            match finished.recv_timeout(std::time::Duration::from_millis(200)) {
                Ok((v, visit)) => {
                    visits[v] = Some(visit);
                    finished_visits += 1;
                }
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break,
            }
            each(pressed.load(Ordering::Relaxed), finished_visits);
        }
    });
    let mut data: Option<Dataset> = None;
    for visit in visits {
        // Every visit sent its result unless a worker panicked (which the scope re-raises).
        let visit = visit.ok_or(CollectError::NoVisits)??;
        match data.as_mut() {
            None => data = Some(visit),
            Some(d) => d.append(visit).map_err(CollectError::Data)?,
        }
    }
    data.ok_or(CollectError::NoVisits)
}
