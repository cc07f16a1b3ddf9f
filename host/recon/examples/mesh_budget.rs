//! How closely `Mesh::with_about` meets a triangle budget, from 200 to 100 000 triangles, on
//! the reference sheets (16 and 8 electrodes), and how long meshing takes.
//!
//! Run: `cargo run --release -p et-recon --example mesh_budget`

use std::time::Instant;

use et_core::sheet::shape::Shape;
use et_core::sheet::{ElectrodeModel, Sheet};
use et_recon::mesh::Mesh;

fn main() {
    let mut disc = Sheet::rectangle(0.22, 0.22, 16);
    disc.shape = Shape::Disc { radius: 0.11 };
    disc.electrodes.width = 0.006;
    let mut point = disc.clone();
    point.electrodes.model = ElectrodeModel::Point;
    let sheets = [
        (
            "13 cm square, 16 electrodes",
            Sheet::rectangle(0.13, 0.13, 16),
        ),
        (
            "13 cm square, 8 electrodes",
            Sheet::rectangle(0.13, 0.13, 8),
        ),
        ("22 cm disc, 16 electrodes", disc),
        ("22 cm disc, 16 point electrodes", point),
        (
            "22 x 10 cm strip, 32 electrodes",
            Sheet::rectangle(0.22, 0.10, 32),
        ),
    ];
    println!(
        "{:<34} {:>8} {:>8} {:>7} {:>9} {:>8}",
        "sheet", "budget", "made", "miss", "min angle", "seconds"
    );
    for (name, spec) in &sheets {
        for target in [200, 300, 500, 1_000, 2_000, 8_000, 30_000, 100_000] {
            let t = Instant::now();
            match Mesh::with_about(spec, target) {
                Ok(mesh) => {
                    let n = mesh.triangles.len();
                    println!(
                        "{name:<34} {target:>8} {n:>8} {:>+6.1}% {:>9.1} {:>8.3}",
                        100.0 * (n as f64 / target as f64 - 1.0),
                        mesh.min_angle_deg(),
                        t.elapsed().as_secs_f64()
                    );
                }
                Err(e) => println!("{name:<34} {target:>8} error: {e}"),
            }
        }
    }
}
