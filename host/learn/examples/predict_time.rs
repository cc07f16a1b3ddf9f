//! How long a table model takes to predict rows: cold (the first call), warm with the model
//! rebuilt from its tables each call (`TableModel::predict`), and prepared once
//! (`TableModel::prepare`, then `Prepared::predict`).
//!
//! `cargo run --release -p et-learn --example predict_time -- MODEL.json FEATURES.csv TARGETS.csv [ROWS]`
//!
//! MODEL may be several single models joined by `+` (`gp.json+knn.json`): their average, as
//! `auto` saves one.
use std::path::Path;
use std::time::Instant;

use et_learn::tabular::{Kind, Member, Table, TableModel, Tables, Unit};

/// The model file, or the average of the models joined by `+`.
fn model_of(spec: &str) -> TableModel {
    let load = |p: &str| TableModel::load(Path::new(p)).unwrap_or_else(|e| panic!("{e}"));
    let parts: Vec<TableModel> = spec.split('+').map(load).collect();
    let [first, ..] = parts.as_slice() else {
        unreachable!("split gives one part at least")
    };
    if parts.len() == 1 {
        return first.clone();
    }
    let mut average = first.clone();
    average.method = Kind::Average;
    average.tables = Tables::Average {
        members: parts
            .iter()
            .map(|m| Member {
                method: m.method,
                hyperparameters: m.hyperparameters.clone(),
                feature_mean: m.feature_mean.clone(),
                feature_scale: m.feature_scale.clone(),
                tables: m.tables.clone(),
            })
            .collect(),
    };
    average
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(model), Some(features), Some(targets)) = (args.get(1), args.get(2), args.get(3))
    else {
        eprintln!(
            "usage: predict_time MODEL.json FEATURES.csv TARGETS.csv [ROWS, default 2000..2500]"
        );
        std::process::exit(2);
    };
    let rows = args.get(4).map_or("2000..2500", String::as_str);
    let model = model_of(model);
    let table = Table::import(Path::new(features), Some(Path::new(targets)), Unit::M)
        .unwrap_or_else(|e| panic!("{e}"))
        .select(rows.parse().unwrap_or_else(|e| panic!("{e:?}")))
        .unwrap_or_else(|e| panic!("{e}"));
    let median_of_20 = |predict: &dyn Fn() -> usize| {
        let mut times = Vec::new();
        for _ in 0..20 {
            let t = Instant::now();
            assert_eq!(predict(), table.rows());
            times.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let first = times[0];
        times.sort_by(f64::total_cmp);
        (first, times[10])
    };
    let (first, rebuilt) = median_of_20(&|| {
        model
            .predict(&table.x)
            .unwrap_or_else(|e| panic!("{e}"))
            .len()
    });
    let prepared = model.prepare().unwrap_or_else(|e| panic!("{e}"));
    let (_, warm) = median_of_20(&|| {
        prepared
            .predict(&table.x)
            .unwrap_or_else(|e| panic!("{e}"))
            .len()
    });
    println!(
        "{} rows, {}: first {first:.1} ms, median of 20 {rebuilt:.1} ms (model rebuilt each \
         call), {warm:.2} ms prepared once",
        table.rows(),
        model.method.name(),
    );
}
