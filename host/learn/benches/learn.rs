//! Training speed (docs/method.md §10: the reference took 81 s to train QDA once on 49 classes x 2 400
//! observations). Data: the docs/method.md §9 procedure on the simulated 13 x 13 cm, 16-electrode sheet
//! (opposite protocol, p = 96), collected once before timing.
//!
//! Run: `cargo bench -p et-learn --bench learn`

use std::sync::LazyLock;

use et_core::ScanConfig;
use et_learn::collect::{Plan, collect, grid, training_config};
use et_learn::cv::folds;
use et_learn::dataset::Dataset;
use et_learn::fastcv::cross_validate_fast;
use et_learn::fit::{FitOptions, Fitted};
use et_learn::regress::{KernelRidge, Target3};
use et_sim::frontend::FrontendSpec;
use et_sim::sheet::SheetSpec;
use nalgebra::DMatrix;

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

/// 2 000 training rows of 192 features (another sensor's table: 16 electrodes, opposite drive
/// in both polarities, 12 measurements each) and 500 rows to predict; a smooth non-linear map
/// to (x, y, pressure). Random data: the times do not depend on the values.
static TABLE: LazyLock<(DMatrix<f64>, Vec<Target3>, DMatrix<f64>)> = LazyLock::new(|| {
    let mut rng = et_core::rng::Rng::new(7);
    let mut rows = |n: usize| DMatrix::from_fn(n, 192, |_, _| rng.normal());
    let (x, test) = (rows(2_000), rows(500));
    let t = x
        .row_iter()
        .map(|r| [r[0].sin() * 40.0, (r[1] * r[2]).tanh() * 40.0, r[3].abs()])
        .collect();
    (x, t, test)
});

/// Kernel ridge (Gaussian kernel) fitted on all 2 000 rows: the kernel matrix and its
/// Cholesky factor.
#[divan::bench(sample_count = 5)]
fn kernel_ridge_fit_2000x192(bencher: divan::Bencher) {
    let (x, t, _) = &*TABLE;
    bencher.bench(|| KernelRidge::fit(x, t, 2_000, 0.5, 1e-2).expect("fit"));
}

/// Kernel ridge predicting 500 rows at once.
#[divan::bench(sample_count = 10)]
fn kernel_ridge_predict_500(bencher: divan::Bencher) {
    let (x, t, test) = &*TABLE;
    let krr = KernelRidge::fit(x, t, 2_000, 0.5, 1e-2).expect("fit");
    bencher.bench(|| krr.predict_many(test));
}

/// The `.npz` entries' CRC-32 (zip's, ISO-HDLC) over 16 MB: crc32fast, which `npz` uses
/// (SIMD where the CPU has it), against the `crc` crate of the wire format with its byte table
/// (what et-core uses, 1 KB on the board) and a 16-row table.
#[divan::bench(args = ["crc32fast", "crc table 1", "crc table 16"])]
fn crc32_of_16_mb(bencher: divan::Bencher, which: &str) {
    let data: Vec<u8> = (0..16_000_000u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 24) as u8)
        .collect();
    let table1 = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);
    let table16 = crc::Crc::<u32, crc::Table<16>>::new(&crc::CRC_32_ISO_HDLC);
    bencher.bench_local(|| match which {
        "crc32fast" => crc32fast::hash(divan::black_box(&data)),
        "crc table 1" => table1.checksum(divan::black_box(&data)),
        _ => table16.checksum(divan::black_box(&data)),
    });
}
