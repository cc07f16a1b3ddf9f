//! The condition number of the one-step data-space system A + lambda I (A = J P^-1 J^T,
//! K x K, NOSER s = 0.5) against alpha, on the 22 cm disc with 16 electrodes at about 8 000
//! triangles, adjacent and PP-PP: what decides whether the set-up could run in f32 (its
//! Cholesky factor's relative error is about the condition number times 6e-8).
//!
//! Run: `cargo run --release -p et-recon --example conditioning`

use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::Sheet;
use et_core::sheet::shape::Shape;
use et_recon::Imager;
use et_recon::mesh::Mesh;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut spec = Sheet::rectangle(0.22, 0.22, 16);
    spec.shape = Shape::Disc { radius: 0.11 };
    let imager = Imager::new(&spec, Mesh::with_about(&spec, 8_000)?, 64)?;
    let alphas = [0.01, 0.03, 0.1, 0.4, 1.0, 2.5];
    print!("| protocol | K | triangles |");
    alphas.iter().for_each(|a| print!(" alpha {a} |"));
    println!("\n|---|---|---|{}", "---|".repeat(alphas.len()));
    for kind in [ProtocolKind::Adjacent, ProtocolKind::PpPp] {
        let protocol = Protocol::new(kind, 16)?;
        let j = imager.jacobian(&protocol.schedule(32e-6).unwrap())?;
        // J P^-1 with P^-1 = diag(J^T J)^-s, s = 0.5.
        let p_inv: Vec<f64> = (0..j.ncols())
            .map(|c| j.column(c).norm_squared().powf(-0.5))
            .collect();
        let jp = nalgebra::DMatrix::from_fn(j.nrows(), j.ncols(), |k, t| j[(k, t)] * p_inv[t]);
        let a = &jp * j.transpose();
        let a = (&a + a.transpose()) * 0.5;
        let e = a.symmetric_eigenvalues();
        let (top, bottom) = (e.max(), e.min().max(0.0));
        // lambda = alpha^2 tr(A) / K, as the one-step reconstruction's alpha.
        let scale = e.sum() / e.len() as f64;
        print!("| {kind} | {} | {} |", j.nrows(), j.ncols());
        for alpha in alphas {
            let lambda = alpha * alpha * scale;
            print!(" {:.1e} |", (top + lambda) / (bottom + lambda));
        }
        println!();
    }
    Ok(())
}
