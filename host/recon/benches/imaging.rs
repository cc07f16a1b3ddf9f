//! Imaging speed (issue: mesh + forward + Jacobian + reconstruction matrix for a 16-electrode
//! disc, adjacent protocol, complete electrode model, at about 8 000 and 30 000 triangles; a
//! live frame). One core: faer runs sequentially, nalgebra is single-threaded.
//!
//! Run: `cargo bench -p et-recon --bench imaging`

use std::sync::LazyLock;

use et_core::protocol::{Protocol, ProtocolKind};
use et_recon::fem::{Electrodes, Forward};
use et_recon::mesh::Mesh;
use et_recon::{OneStep, PixelGrid};
use et_sim::shape::Shape;
use et_sim::sheet::SheetSpec;
use nalgebra::{DMatrix, DVector};

fn main() {
    divan::main();
}

fn disc() -> SheetSpec {
    let mut s = SheetSpec::rectangle(0.22, 0.22, 16);
    s.shape = Shape::Disc { radius: 0.11 };
    s.electrodes.width = 0.006;
    s
}

/// Everything a reconstruction needs, from the sheet spec: the mesh, the forward model at the
/// background, the Jacobian and the one-step matrix. Returns the triangle count.
fn set_up(triangles: usize) -> (usize, OneStep, Mesh) {
    let spec = disc();
    let mesh = Mesh::with_about(&spec, triangles).expect("mesh");
    let n = mesh.triangles.len();
    let z = vec![spec.electrodes.contact_ohm * spec.electrodes.width; 16];
    let fwd = Forward::new(mesh.clone(), Electrodes::Complete(z)).expect("forward");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    let (_, jac) = fwd
        .jacobian(&vec![1.0 / spec.sheet_resistance; n], &protocol, 32e-6)
        .expect("jacobian");
    (n, OneStep::new(&jac, 0.03, 0.5).expect("recon"), mesh)
}

#[divan::bench(args = [2_000, 8_000, 30_000], sample_count = 5, sample_size = 1)]
fn set_up_mesh_forward_jacobian_matrix(triangles: usize) -> usize {
    set_up(triangles).0
}

static LIVE: LazyLock<(OneStep, DMatrix<f32>, DVector<f64>)> = LazyLock::new(|| {
    let (_, r, mesh) = set_up(8_000);
    let grid = PixelGrid::new(&mesh, 32);
    let pix = grid.project(&r);
    let dv = DVector::from_fn(r.matrix.ncols(), |k, _| (k as f64 * 0.37).sin() * 1e-4);
    (r, pix, dv)
});

/// A live frame onto the 8 000-triangle mesh (f64).
#[divan::bench]
fn live_frame_onto_the_mesh() -> f64 {
    let (r, _, dv) = &*LIVE;
    (&r.matrix * divan::black_box(dv)).sum()
}

/// A live frame onto a 32 x 32 pixel grid (f32).
#[divan::bench]
fn live_frame_onto_32x32_pixels() -> f32 {
    let (_, pix, dv) = &*LIVE;
    let dv32: DVector<f32> = dv.map(|v| v as f32);
    (pix * divan::black_box(&dv32)).sum()
}

static FORWARD: LazyLock<(Forward, DMatrix<f64>, Vec<f64>)> = LazyLock::new(|| {
    let spec = disc();
    let mesh = Mesh::with_about(&spec, 8_000).expect("mesh");
    let n = mesh.triangles.len();
    let z = vec![spec.electrodes.contact_ohm * spec.electrodes.width; 16];
    let fwd = Forward::new(mesh, Electrodes::Complete(z)).expect("forward");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    let currents = Forward::injection_currents(&protocol, 32e-6);
    let sigma = (0..n)
        .map(|t| (1.0 + 0.5 * (t as f64 * 0.01).sin()) / spec.sheet_resistance)
        .collect();
    (fwd, currents, sigma)
});

/// One forward solve (16 injections) at a new conductivity on the 8 000-triangle mesh: the
/// per-iterate cost of iterative Gauss-Newton besides its Jacobian's lead fields.
#[divan::bench(sample_count = 20, sample_size = 1)]
fn forward_solve_at_a_new_conductivity() -> f64 {
    let (fwd, currents, sigma) = &*FORWARD;
    let sol = fwd.solve(divan::black_box(sigma), currents).expect("solve");
    sol.electrodes[(0, 0)]
}
