//! Imaging speed: mesh + forward + Jacobian + one-step matrix for a 16-electrode disc
//! (adjacent protocol, complete electrode model) at about 2 000, 8 000 and 30 000 triangles,
//! and 32 electrodes PP-PP at 8 000; other systems' protocols of 1 264 and 2 304 values at
//! 8 000, and the 32-electrode one fitted to its reference and imaging its first frame with
//! defaults (what `et reconstruct` does with a tank's frame); GREIT's set-up at 2 000 and 8 000; the one-step matrix
//! alone; a live frame onto the mesh
//! against reading its matrix once (the memory-bandwidth limit) and onto a 32 x 32 grid. One
//! core: faer runs sequentially, nalgebra is single-threaded.
//!
//! Run: `cargo bench -p et-recon --bench imaging`

use std::sync::LazyLock;

use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::Sheet;
use et_core::sheet::shape::Shape;
use et_recon::fem::{Electrodes, Forward, TransferJacobian};
use et_recon::mesh::Mesh;
use et_recon::{AlphaRule, DataSpace, FrameOperator, MeshPlan, Method, OneStep, PixelGrid, Spec};
use nalgebra::{DMatrix, DVector};

fn main() {
    divan::main();
}

fn disc(electrodes: u8) -> Sheet {
    let mut s = Sheet::rectangle(0.22, 0.22, electrodes);
    s.shape = Shape::Disc { radius: 0.11 };
    s.electrodes.width = 0.006;
    s
}

fn jacobian(triangles: usize, electrodes: u8, kind: ProtocolKind) -> (TransferJacobian, Mesh) {
    let spec = disc(electrodes);
    let mesh = Mesh::with_about(&spec, triangles).expect("mesh");
    let n = mesh.triangles.len();
    let fwd = Forward::new(mesh.clone(), Electrodes::of_sheet(&spec).expect("z")).expect("forward");
    let protocol = Protocol::new(kind, electrodes).expect("protocol");
    let jac = fwd
        .transfer_jacobian(
            &vec![1.0 / spec.sheet_resistance; n],
            &protocol.schedule(32e-6).unwrap(),
        )
        .expect("jacobian");
    (jac, mesh)
}

/// The whole set-up through et's entry point ([`Spec::set_up`]): mesh, forward model, pixel
/// grid, Jacobian, data space and the one-step matrix at alpha 0.03.
fn reconstructor(
    triangles: usize,
    electrodes: u8,
    kind: ProtocolKind,
    method: Method,
    alpha: AlphaRule,
) -> usize {
    let protocol = Protocol::new(kind, electrodes).expect("protocol");
    Spec {
        mesh: MeshPlan::About {
            triangles,
            refine: Vec::new(),
        },
        method,
        alpha,
        ..Spec::new(
            disc(electrodes),
            protocol.schedule(32e-6).expect("a current"),
        )
    }
    .set_up()
    .expect("set-up")
    .imager()
    .triangles()
}

#[divan::bench(args = [2_000, 8_000, 30_000], sample_count = 5, sample_size = 1)]
fn set_up_mesh_forward_jacobian_matrix(triangles: usize) -> usize {
    reconstructor(
        triangles,
        16,
        ProtocolKind::Adjacent,
        Method::default(),
        AlphaRule::Fixed(0.03),
    )
}

/// 32 electrodes, PP-PP, 8 000 triangles.
#[divan::bench(sample_count = 3, sample_size = 1)]
fn set_up_32_electrodes_pp_pp_8000() -> usize {
    reconstructor(
        8_000,
        32,
        ProtocolKind::PpPp,
        Method::default(),
        AlphaRule::Fixed(0.03),
    )
}

/// Another system's protocol through the whole set-up (mesh, forward model, Jacobian, the
/// one-step matrix at alpha 0.1) on a 28 cm tank at 8 000 triangles, every adjacent pair
/// measured under each injection, the drive electrodes' too: 16 electrodes 2.5 cm wide with 79
/// injections (adjacent, skip 1 to 3, all against electrode 0: K = 1 264), and 32 electrodes 1
/// cm wide injecting between odd electrodes only (1 to 4 apart and opposite, 72 injections:
/// K = 2 304).
#[divan::bench(args = [16, 32], sample_count = 3, sample_size = 1)]
fn set_up_foreign_protocol_8000(electrodes: u16) -> usize {
    let l = electrodes;
    let injections: Vec<(u16, u16)> = if l == 16 {
        (0..4)
            .flat_map(|skip| (0..l).map(move |i| (i, (i + skip + 1) % l)))
            .chain((1..l).map(|i| (i, 0)))
            .collect()
    } else {
        let odd = |i: u16| (2 * i + 1) % l;
        (1..=4)
            .flat_map(|d| (0..l / 2).map(move |i| (odd(i), odd(i + d))))
            .chain((0..l / 4).map(|i| (odd(i), odd(i + l / 4))))
            .collect()
    };
    let schedule = et_core::schedule::Schedule::adjacent_pairs_under(l, &injections, 1e-3)
        .expect("a schedule");
    let mut sheet = Sheet::disc(0.14, l as u8);
    sheet.electrodes.width = if l == 16 { 0.025 } else { 0.01 };
    Spec {
        alpha: AlphaRule::Fixed(0.1),
        ..Spec::new(sheet, schedule)
    }
    .set_up()
    .expect("set-up")
    .imager()
    .triangles()
}

/// Another system's 32-electrode tank as `et reconstruct` images one of its frames with
/// defaults: the set-up fitted to the reference frame ([`Spec::set_up_fitted`]: mesh, the
/// background's sheet resistance and contact, the Jacobian there, the data space) and the
/// first frame's image (alpha at the L-curve's corner, the one-step matrix at it, the frame,
/// its noise and objects). The 32-electrode protocol of `set_up_foreign_protocol_8000`
/// (K = 2 304) on a 28 cm tank at 8 000 triangles; V_0 and the frame from the finite elements
/// on a finer mesh at another sheet resistance and contact, the frame with a rod of 5 times
/// the conductivity 7 cm from the centre.
#[divan::bench(sample_count = 3, sample_size = 1)]
fn set_up_fitted_and_first_frame_32_electrodes() -> usize {
    let (spec, v0, v1) = &*TANK_32;
    let reference = et_recon::Reference::from_frames(&[v0]).expect("V_0");
    let (mut r, _) = spec
        .clone()
        .set_up_fitted(&reference.v0, et_recon::reconstructor::Weighting::Alike)
        .expect("set-up");
    r.image(v1, &reference).expect("image").touches.len()
}

static TANK_32: LazyLock<(Spec, Vec<f32>, Vec<f32>)> = LazyLock::new(|| {
    let l = 32u16;
    let odd = |i: u16| (2 * i + 1) % l;
    let injections: Vec<(u16, u16)> = (1..=4)
        .flat_map(|d| (0..l / 2).map(move |i| (odd(i), odd(i + d))))
        .chain((0..l / 4).map(|i| (odd(i), odd(i + l / 4))))
        .collect();
    let schedule = et_core::schedule::Schedule::adjacent_pairs_under(l, &injections, 1e-3)
        .expect("a schedule");
    let mut sheet = Sheet::disc(0.14, 32);
    sheet.electrodes.width = 0.01;
    // The tank: a finer mesh, 10 % more resistive, contacts twice the scene's.
    let mut tank = sheet.clone();
    tank.sheet_resistance *= 1.1;
    tank.electrodes.contact_ohm *= 2.0;
    let mesh = Mesh::with_about(&tank, 20_000).expect("mesh");
    let fwd = Forward::new(mesh, Electrodes::of_sheet(&tank).expect("z")).expect("forward");
    let sigma0 = 1.0 / tank.sheet_resistance;
    let mut sigma = vec![sigma0; fwd.mesh().triangles.len()];
    let f32s = |v: Vec<f64>| v.into_iter().map(|x| x as f32).collect::<Vec<f32>>();
    let v0 = f32s(fwd.frame(&sigma, &schedule).expect("V_0"));
    for (t, s) in sigma.iter_mut().enumerate() {
        let [x, y] = fwd.mesh().centroid(t);
        if (x - 0.07).hypot(y) < 0.02 {
            *s = 5.0 * sigma0;
        }
    }
    let v1 = f32s(fwd.frame(&sigma, &schedule).expect("V_1"));
    let spec = Spec {
        mesh: MeshPlan::About {
            triangles: 8_000,
            refine: Vec::new(),
        },
        ..Spec::new(sheet, schedule)
    };
    (spec, v0, v1)
});

/// GREIT's full set-up at the consensus noise figure: mesh, forward model, Jacobian, the
/// desired images, the noise-figure search and the matrix onto a 64 x 64 grid (16 electrodes,
/// adjacent).
#[divan::bench(args = [2_000, 8_000], sample_count = 5, sample_size = 1)]
fn set_up_greit_64_pixels(triangles: usize) -> usize {
    reconstructor(
        triangles,
        16,
        ProtocolKind::Adjacent,
        Method::Greit { radius: None },
        AlphaRule::NoiseFigure(et_recon::greit::NOISE_FIGURE),
    )
}

/// The one-step matrix alone (data space, its Cholesky and the solve), 16 electrodes
/// adjacent, from the Jacobian.
#[divan::bench(args = [8_000, 30_000], sample_count = 5, sample_size = 1)]
fn one_step_matrix(bencher: divan::Bencher, triangles: usize) {
    let (jac, _) = jacobian(triangles, 16, ProtocolKind::Adjacent);
    bencher.bench(|| {
        DataSpace::factored(divan::black_box(&jac), 0.5)
            .and_then(|d| d.one_step(0.03))
            .expect("recon")
    });
}

/// The one-step matrix's operator for live frames (its thin f32 factors, orthonormalised and
/// packed): the part of the set-up the f32 frame costs.
#[divan::bench(args = [8_000, 30_000], sample_count = 5, sample_size = 1)]
fn frame_operator_of_the_one_step_matrix(bencher: divan::Bencher, triangles: usize) {
    let (jac, _) = jacobian(triangles, 16, ProtocolKind::Adjacent);
    let r = DataSpace::factored(&jac, 0.5)
        .and_then(|d| d.one_step(0.03))
        .expect("recon");
    bencher.bench(|| FrameOperator::of(divan::black_box(&r)));
}

static LIVE: LazyLock<(OneStep, [FrameOperator; 3], DVector<f64>)> = LazyLock::new(|| {
    // The stages by hand: these benchmarks time the live frame's kernels themselves.
    let (jac, mesh) = jacobian(8_000, 16, ProtocolKind::Adjacent);
    let r = DataSpace::factored(&jac, 0.5)
        .and_then(|d| d.one_step(0.03))
        .expect("recon");
    let [a, b] = [32, 64].map(|n| PixelGrid::new(&mesh, n).project(&r));
    let pix = [a, b, FrameOperator::of(&r)];
    let dv = DVector::from_fn(r.frame_len(), |k, _| (k as f64 * 0.37).sin() * 1e-4);
    (r, pix, dv)
});

/// A live frame onto the 8 000-triangle mesh in f32 (the packed thin factors: q = 104).
#[divan::bench]
fn live_frame_onto_the_mesh(bencher: divan::Bencher) {
    let (_, pix, dv) = &*LIVE;
    let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
    let mut out = vec![0.0f32; pix[2].rows()];
    bencher.bench_local(|| {
        pix[2]
            .apply(divan::black_box(&dv32), &mut out)
            .expect("sizes");
        out[0]
    });
}

/// A live frame onto the 8 000-triangle mesh in f64 (faer's products on the factors: r = 120).
#[divan::bench]
fn live_frame_onto_the_mesh_f64() -> f64 {
    let (r, _, dv) = &*LIVE;
    r.reconstruct(divan::black_box(dv.as_slice()))
        .expect("frame")
        .iter()
        .sum()
}

/// A live frame onto a 32 x 32 and a 64 x 64 pixel grid (f32, the thin factors: pixels
/// inside x q and q x K).
#[divan::bench(args = [0, 1])]
fn live_frame_onto_pixels_32_64(bencher: divan::Bencher, which: usize) {
    let (_, pix, dv) = &*LIVE;
    let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
    let mut out = vec![0.0f32; pix[which].rows()];
    bencher.bench_local(|| {
        pix[which]
            .apply(divan::black_box(&dv32), &mut out)
            .expect("sizes");
        out[0]
    });
}

/// Reading as many bytes as the 32 x 32, 64 x 64 and 8 000-triangle frames' packed factors
/// hold, once, with nothing else (a sum in eight vector registers): the memory-bandwidth limit
/// each frame is measured against.
#[divan::bench(args = [0, 1, 2])]
fn read_the_factors_once(bencher: divan::Bencher, which: usize) {
    let (_, pix, _) = &*LIVE;
    let data = vec![1.0f32; pix[which].bytes() / 4];
    bencher.bench_local(|| bandwidth::sum(divan::black_box(&data)));
}

/// STREAM's triad, a = b + s c, on one core over three arrays of `n` f32 each: 3 x 4 n bytes
/// moved (counted as STREAM counts them: two read, one written). Warm: arrays that fit this
/// machine's L3 cache together (3 x 1.5 MB); cold: 3 x 64 MB, far past it.
#[divan::bench(args = [393_216, 16_777_216], sample_count = 30)]
fn stream_triad(bencher: divan::Bencher, n: usize) {
    let b = vec![1.0f32; n];
    let c = vec![2.0f32; n];
    let mut a = vec![0.0f32; n];
    bencher
        .counter(divan::counter::BytesCount::new(12 * n))
        .bench_local(|| {
            bandwidth::triad(&mut a, divan::black_box(&b), &c, 3.0);
            a[0]
        });
}

mod bandwidth {
    use pulp::{Arch, Simd, WithSimd};

    /// The sum of `data` in eight vector accumulators (the reading speed of one core).
    pub fn sum(data: &[f32]) -> f32 {
        struct Sum<'a>(&'a [f32]);
        impl WithSimd for Sum<'_> {
            type Output = f32;
            #[inline(always)]
            fn with_simd<S: Simd>(self, simd: S) -> f32 {
                let (v, tail) = S::as_simd_f32s(self.0);
                let mut acc = [simd.splat_f32s(0.0); 8];
                for chunk in v.chunks_exact(8) {
                    for (a, x) in acc.iter_mut().zip(chunk) {
                        *a = simd.add_f32s(*a, *x);
                    }
                }
                let total = acc
                    .iter()
                    .fold(simd.splat_f32s(0.0), |s, a| simd.add_f32s(s, *a));
                simd.reduce_sum_f32s(total) + tail.iter().sum::<f32>()
            }
        }
        Arch::new().dispatch(Sum(data))
    }

    /// a = b + s c.
    pub fn triad(a: &mut [f32], b: &[f32], c: &[f32], s: f32) {
        struct Triad<'a>(&'a mut [f32], &'a [f32], &'a [f32], f32);
        impl WithSimd for Triad<'_> {
            type Output = ();
            #[inline(always)]
            fn with_simd<S: Simd>(self, simd: S) {
                let Triad(a, b, c, s) = self;
                let (av, at) = S::as_mut_simd_f32s(a);
                let (bv, bt) = S::as_simd_f32s(b);
                let (cv, ct) = S::as_simd_f32s(c);
                let sv = simd.splat_f32s(s);
                for ((a, b), c) in av.iter_mut().zip(bv).zip(cv) {
                    *a = simd.mul_add_f32s(*c, sv, *b);
                }
                for ((a, b), c) in at.iter_mut().zip(bt).zip(ct) {
                    *a = c.mul_add(s, *b);
                }
            }
        }
        Arch::new().dispatch(Triad(a, b, c, s));
    }
}

static FORWARD: LazyLock<(Forward, DMatrix<f64>, Vec<f64>)> = LazyLock::new(|| {
    let spec = disc(16);
    let mesh = Mesh::with_about(&spec, 8_000).expect("mesh");
    let n = mesh.triangles.len();
    let z = vec![spec.electrodes.contact_ohm * spec.electrodes.width; 16];
    let fwd = Forward::new(mesh, Electrodes::Complete(z)).expect("forward");
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    let currents = Forward::injection_currents(&protocol.schedule(32e-6).unwrap());
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
