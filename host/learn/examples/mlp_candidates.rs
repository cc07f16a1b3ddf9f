//! Every candidate of `et train --kind mlp`'s grid (relu or tanh, L2 0.1 or 1; hidden layers
//! 300, 50, 20) fitted alone on the training rows with one start per seed, and its error on
//! the test rows: how much of a comparison is the perceptron and how much the choice among
//! candidates (docs/measurements.md, "The perceptron beside scikit-learn's").
//!
//! Usage: cargo run --release -p et-learn --example mlp_candidates -- FEATURES TARGETS TRAIN
//! TEST [SEEDS] (a table and its targets in m as `et train` reads them, row ranges such as
//! 0..2000 and 2000..2500, seeds 1 to SEEDS, default 3). Prints per candidate each seed's
//! mean x, y error on the test rows (mm) and the passes its early stop took.

use std::path::PathBuf;

use et_learn::mlp::{Activation, Mlp, MlpOptions};
use et_learn::tabular::{RowRange, Table, Unit};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let usage = "usage: mlp_candidates FEATURES TARGETS TRAIN TEST [SEEDS]";
    let mut args = std::env::args().skip(1);
    let mut next = || args.next().ok_or(usage);
    let (features, targets) = (PathBuf::from(next()?), PathBuf::from(next()?));
    let (train, test) = (next()?.parse::<RowRange>()?, next()?.parse::<RowRange>()?);
    let seeds: u64 = next().map_or(Ok(3), |s| s.parse())?;
    let table = Table::import(&features, Some(&targets), Unit::M)?;
    let (train, test) = (table.select(train)?, table.select(test)?);
    let (t_train, t_test) = (
        train.targets().ok_or("no positions")?,
        test.targets().ok_or("no positions")?,
    );
    for activation in [Activation::Relu, Activation::Tanh] {
        for l2 in [0.1, 1.0] {
            let mut said = Vec::new();
            for seed in 1..=seeds {
                let opts = MlpOptions {
                    activation,
                    l2,
                    starts: 1,
                    seed,
                    ..MlpOptions::default()
                };
                let m = Mlp::fit(&train.x, &t_train, &opts)?;
                let predicted = m.predict_many(&test.x);
                let mean_mm = 1e3
                    * predicted
                        .iter()
                        .zip(&t_test)
                        .map(|(p, t)| (p[0] - t[0]).hypot(p[1] - t[1]))
                        .sum::<f64>()
                    / t_test.len().max(1) as f64;
                said.push(format!("{mean_mm:.3} mm ({} passes)", m.epochs));
            }
            println!("{} L2 {l2}: {}", activation.name(), said.join(", "));
        }
    }
    Ok(())
}
