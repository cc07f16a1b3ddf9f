//! How long a table model takes to predict rows, cold (the first call) and warm.
//!
//! `cargo run --release -p et-learn --example predict_time -- MODEL.json FEATURES.csv TARGETS.csv [ROWS]`
use std::path::Path;
use std::time::Instant;

use et_learn::tabular::{Table, TableModel, Unit};

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
    let model = TableModel::load(Path::new(model)).unwrap_or_else(|e| panic!("{e}"));
    let table = Table::import(Path::new(features), Some(Path::new(targets)), Unit::M)
        .unwrap_or_else(|e| panic!("{e}"))
        .select(rows.parse().unwrap_or_else(|e| panic!("{e:?}")))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut times = Vec::new();
    for _ in 0..20 {
        let t = Instant::now();
        let p = model.predict(&table.x).unwrap_or_else(|e| panic!("{e}"));
        times.push(t.elapsed().as_secs_f64() * 1e3);
        assert_eq!(p.len(), table.rows());
    }
    let first = times[0];
    times.sort_by(f64::total_cmp);
    println!(
        "{} rows, {}: first {first:.1} ms, median of 20 {:.1} ms",
        table.rows(),
        model.method.name(),
        times[10]
    );
}
