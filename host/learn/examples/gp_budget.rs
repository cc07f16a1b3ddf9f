//! How the Gaussian process's held-out error and fit time depend on its learning budget (the
//! rows its length scales are learned on, and the L-BFGS iterations), on the stand-in's
//! chronological split: train on rows 0..2000, test on 2000..2500. The numbers behind
//! `et_learn::gp::GpOptions::default` in docs/measurements.md.
//!
//! Usage: cargo run --release -p et-learn --example gp_budget -- DIR
//! (DIR holds features.csv and targets.csv from the standin example, 2 500 rows).

use std::path::PathBuf;

use et_learn::gp::{Gp, GpOptions};
use et_learn::tabular::{RowRange, Table, Unit};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).ok_or("usage: gp_budget DIR")?);
    let table = Table::import(
        &dir.join("features.csv"),
        Some(&dir.join("targets.csv")),
        Unit::M,
    )?;
    let train = table.select("0..2000".parse::<RowRange>()?)?;
    let test = table.select("2000..2500".parse::<RowRange>()?)?;
    let (t_train, t_test) = (
        train.targets().ok_or("no positions")?,
        test.targets().ok_or("no positions")?,
    );
    println!("learn_rows  iterations  taken  fit_s   test_mean_mm  test_median_mm");
    for (learn_rows, iterations) in [(500, 60), (1000, 30), (1000, 60), (1000, 120), (1500, 60)] {
        let opts = GpOptions {
            learn_rows,
            iterations,
            ..GpOptions::default()
        };
        let started = std::time::Instant::now();
        let gp = Gp::fit(&train.x, &t_train, &opts, &mut |_, _| {})?;
        let fit = started.elapsed().as_secs_f64();
        let mut e: Vec<f64> = gp
            .predict_many(&test.x)
            .iter()
            .zip(&t_test)
            .map(|(p, t)| (p[0] - t[0]).hypot(p[1] - t[1]))
            .collect();
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        e.sort_by(f64::total_cmp);
        println!(
            "{learn_rows:>10}  {iterations:>10}  {:>5}  {fit:>5.1}   {mean:>12.2}  {:>14.2}",
            gp.iterations,
            e[e.len() / 2]
        );
    }
    Ok(())
}
