//! The finite elements against the exact solution of the unit disc (16 electrodes of width
//! 0.1, contact 0.05 ohm m, sigma = 1, adjacent protocol, 1 A), point and complete electrode
//! models, from 500 to 100 000 triangles: the relative error in two norms (the largest
//! difference over the largest frame value, and |V_h - V| / |V|) and its order in the edge
//! length between rows.
//!
//! Run: `cargo run --release -p et-recon --example convergence`

use et_core::sheet::ElectrodeModel;
use et_recon::exact::{FrameError, unit_disc_error};

fn main() {
    println!("| model | triangles | max error | order | L2 error | order |");
    println!("| --- | --- | --- | --- | --- | --- |");
    for model in [ElectrodeModel::Point, ElectrodeModel::Complete] {
        let mut last: Option<FrameError> = None;
        for target in [500, 1_000, 2_000, 4_000, 8_000, 16_000, 32_000, 100_000] {
            let Some(e) = unit_disc_error(model, target) else {
                println!("| {model:?} | {target} | failed | | | |");
                continue;
            };
            let order = |norm: fn(&FrameError) -> f64| {
                last.map_or(String::new(), |l| {
                    let h_ratio = (e.triangles as f64 / l.triangles as f64).sqrt();
                    format!("{:.2}", (norm(&l) / norm(&e)).ln() / h_ratio.ln())
                })
            };
            println!(
                "| {model:?} | {} | {:.2e} | {} | {:.2e} | {} |",
                e.triangles,
                e.max,
                order(|e| e.max),
                e.l2,
                order(|e| e.l2)
            );
            last = Some(e);
        }
    }
}
