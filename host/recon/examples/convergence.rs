//! The finite elements against the exact solution of the unit disc (16 electrodes of width
//! 0.1, contact 0.05 ohm m, sigma = 1, adjacent protocol, 1 A), point and complete electrode
//! models, from 500 to 100 000 triangles: the relative error (largest difference over the
//! largest frame value) and its order in the edge length between rows.
//!
//! Run: `cargo run --release -p et-recon --example convergence`

use et_recon::exact::unit_disc_error;
use et_sim::sheet::ElectrodeModel;

fn main() {
    println!("| model | triangles | relative error | order |");
    println!("| --- | --- | --- | --- |");
    for model in [ElectrodeModel::Point, ElectrodeModel::Complete] {
        let mut last: Option<(f64, usize)> = None;
        for target in [500, 1_000, 2_000, 4_000, 8_000, 16_000, 32_000, 100_000] {
            let Some((e, n)) = unit_disc_error(model, target) else {
                println!("| {model:?} | {target} | failed | |");
                continue;
            };
            let order = last.map_or(String::new(), |(e0, n0)| {
                format!("{:.2}", (e0 / e).ln() / (n as f64 / n0 as f64).sqrt().ln())
            });
            println!("| {model:?} | {n} | {e:.2e} | {order} |");
            last = Some((e, n));
        }
    }
}
