//! Training speed (docs/method.md §10: the reference took 81 s to train QDA once on 49 classes x 2 400
//! observations). Data: the docs/method.md §9 procedure on the simulated 13 x 13 cm, 16-electrode sheet
//! (opposite protocol, p = 96), collected once before timing.
//!
//! Run: `cargo bench -p et-learn --bench learn`

use std::sync::LazyLock;

use et_core::ScanConfig;
use et_learn::collect::{Dataset, Plan, collect, grid, training_config};
use et_learn::cv::folds;
use et_learn::fastcv::cross_validate_fast;
use et_learn::fit::{FitOptions, Fitted};
use et_sim::frontend::FrontendSpec;
use et_sim::sheet::SheetSpec;

fn main() {
    divan::main();
}

static DATA: LazyLock<Dataset> = LazyLock::new(|| {
    let spec = SheetSpec::rectangle(0.13, 0.13, 16);
    let config = training_config(ScanConfig::REFERENCE);
    // docs/method.md §9's collection, as the README's training-speed numbers say.
    let plan = Plan::default();
    let d = collect(
        &spec,
        FrontendSpec::default(),
        config,
        &grid(&spec, 7, 7, 0.0),
        &plan,
    )
    .expect("collect");
    assert_eq!((d.x.nrows(), d.x.ncols()), (49 * 2400, 96));
    d
});

/// One QDA fit on 49 classes x 2 400 observations x 96 features.
#[divan::bench(sample_count = 5)]
fn qda_fit(bencher: divan::Bencher) {
    let d = &*DATA;
    bencher.bench(|| Fitted::fit(&d.x, &d.y, 49, &FitOptions::default()).expect("fit"));
}

/// One QDA fit plus stratified 10-fold cross-validation (what the done-means of the learning
/// issue times).
#[divan::bench(sample_count = 5)]
fn qda_fit_and_10_fold_cv(bencher: divan::Bencher) {
    let d = &*DATA;
    let fold = folds(&d.y, 10, 1);
    bencher.bench(|| {
        let model = Fitted::fit(&d.x, &d.y, 49, &FitOptions::default()).expect("fit");
        let cv = cross_validate_fast(&d.x, &d.y, 49, &FitOptions::default(), &fold).expect("cv");
        (model.features(), cv.accuracy())
    });
}
