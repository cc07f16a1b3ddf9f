//! The same work side by side with the Python peer, pyeit 1.2.4 (`benches/peer.py`), on one
//! core each (one BLAS thread for numpy): a 16-electrode unit disc with point electrodes
//! (pyeit's), adjacent drive and measurement (208 values), meshes of pyeit's own sizes (h0 =
//! 0.06 and 0.03: about 2 000 and 8 000 triangles) and et's meshes of the same count.
//! Stages: the mesh; one-step Gauss-Newton's set-up (forward model, Jacobian, the
//! reconstruction matrix with lambda fixed) and a frame onto the triangles; GREIT's set-up
//! (the same, onto 64 x 64 pixels, lambda fixed: the same work as pyeit's) and a frame. Set-up
//! stages are the median of 3 runs on et's side, one on pyeit's; frames the median of 200.
//! Then accuracy at equal element count: each side's adjacent frame against the exact
//! solution (point electrodes in closed form, `et_recon::exact`), both norms, at pyeit's
//! h0 = 0.1 to 0.015 (about 700 to 32 000 triangles).
//!
//! Run: `cargo bench -p et-recon --bench peer` (set `ET_PEER_PYTHON` to an interpreter with
//! pyeit installed, e.g. a venv's `bin/python`; default `python3`). Without pyeit it says so
//! and exits successfully.

use std::process::Command;
use std::time::Instant;

use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::shape::Shape;
use et_core::sheet::{ElectrodeModel, Sheet};
use et_recon::exact::unit_disc_error;
use et_recon::mesh::Mesh;
use et_recon::{DataSpace, Greit, GreitOptions, Imager, Regularisation};

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, t.elapsed().as_secs_f64())
}

/// et's stages at about `triangles` triangles: (triangles, mesh, one-step set-up, one-step
/// frame, GREIT set-up, GREIT frame), seconds.
fn et_side(triangles: usize) -> (usize, [f64; 5]) {
    let mut spec = Sheet::rectangle(2.0, 2.0, 16);
    spec.shape = Shape::Disc { radius: 1.0 };
    spec.electrodes.model = ElectrodeModel::Point;
    spec.sheet_resistance = 1.0;
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    let mut stages: Vec<[f64; 5]> = Vec::new();
    let mut count = 0;
    for _ in 0..3 {
        let (mesh, t_mesh) = timed(|| Mesh::with_about(&spec, triangles).expect("mesh"));
        count = mesh.triangles.len();
        let ((imager, one), t_one) = timed(|| {
            let imager = Imager::new(&spec, mesh, 64).expect("imager");
            let jac = imager
                .transfer_jacobian(&protocol.schedule(1.0).unwrap())
                .expect("jacobian");
            let one = DataSpace::factored(&jac, 0.5)
                .and_then(|d| d.one_step(0.1))
                .expect("one-step");
            (imager, one)
        });
        let (greit, t_greit) = timed(|| {
            let jac = imager
                .transfer_jacobian(&protocol.schedule(1.0).unwrap())
                .expect("jacobian");
            Greit::new(
                &imager,
                &jac,
                &GreitOptions {
                    radius: None,
                    regularisation: Regularisation::Alpha(0.1),
                },
            )
            .expect("greit")
        });
        let dv: Vec<f64> = (0..one.frame_len())
            .map(|k| 1e-3 * ((k * 7 % 13) as f64 - 6.0))
            .collect();
        let frames = |f: &dyn Fn() -> usize| {
            median(
                (0..200)
                    .map(|_| timed(|| std::hint::black_box(f())).1)
                    .collect(),
            )
        };
        let t_one_frame = frames(&|| one.reconstruct(&dv).expect("frame").len());
        let t_greit_frame = frames(&|| greit.image(&dv).expect("frame").len());
        stages.push([t_mesh, t_one, t_one_frame, t_greit, t_greit_frame]);
    }
    let each = |i: usize| median(stages.iter().map(|s| s[i]).collect());
    (count, [each(0), each(1), each(2), each(3), each(4)])
}

/// Runs the peer's script with `args`, one BLAS thread; its JSON lines.
fn peer(python: &str, args: &[&str]) -> Vec<serde_json::Value> {
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/peer.py");
    let out = Command::new(python)
        .arg(&script)
        .args(args)
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .env("MKL_NUM_THREADS", "1")
        .output()
        .expect("run the peer");
    if !out.status.success() {
        eprintln!("{}", String::from_utf8_lossy(&out.stderr));
        std::process::exit(1);
    }
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|line| serde_json::from_str(line).expect("the peer's JSON"))
        .collect()
}

fn main() {
    let python = std::env::var("ET_PEER_PYTHON").unwrap_or_else(|_| "python3".into());
    let has_pyeit = Command::new(&python)
        .args(["-c", "import pyeit, numpy, scipy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_pyeit {
        println!(
            "skipped: pyeit is not importable by {python} (install it with `pip install \
             pyeit==1.2.4`, or set ET_PEER_PYTHON to an interpreter that has it)"
        );
        return;
    }
    println!(
        "| stage | pyeit triangles | pyeit, s | et triangles | et, s | pyeit / et |\n| --- | --- | --- | --- | --- | --- |"
    );
    for peer in peer(&python, &["0.06", "0.03"]) {
        let n = peer["triangles"].as_u64().expect("triangles") as usize;
        let (ours_n, ours) = et_side(n);
        let keys = [
            ("mesh", "mesh"),
            (
                "one-step GN set-up (forward, Jacobian, matrix)",
                "one_step_setup",
            ),
            ("one-step GN frame onto the triangles", "one_step_frame"),
            (
                "GREIT set-up (forward, Jacobian, 64 x 64 matrix)",
                "greit_setup",
            ),
            ("GREIT frame onto 64 x 64 pixels", "greit_frame"),
        ];
        for ((label, key), et) in keys.iter().zip(ours) {
            let theirs = peer[key].as_f64().expect("a time");
            println!(
                "| {label} | {n} | {theirs:.3e} | {ours_n} | {et:.3e} | {:.1} |",
                theirs / et
            );
        }
    }
    println!(
        "\n| pyeit triangles | pyeit max / L2 error | et triangles | et max / L2 error | pyeit / et (max, L2) |\n| --- | --- | --- | --- | --- |"
    );
    let sizes = ["--accuracy", "0.1", "0.06", "0.04", "0.03", "0.02", "0.015"];
    let mut log_ratios = Vec::new();
    for peer in peer(&python, &sizes) {
        let n = peer["triangles"].as_u64().expect("triangles") as usize;
        let (max, l2) = (peer["error_max"].as_f64(), peer["error_l2"].as_f64());
        let (max, l2) = (max.expect("error_max"), l2.expect("error_l2"));
        let et = unit_disc_error(ElectrodeModel::Point, n).expect("et's error");
        println!(
            "| {n} | {max:.2e} / {l2:.2e} | {} | {:.2e} / {:.2e} | {:.1} / {:.1} |",
            et.triangles,
            et.max,
            et.l2,
            max / et.max,
            l2 / et.l2
        );
        log_ratios.push([(max / et.max).ln(), (l2 / et.l2).ln()]);
    }
    let mean =
        |i: usize| (log_ratios.iter().map(|r| r[i]).sum::<f64>() / log_ratios.len() as f64).exp();
    println!(
        "\ngeometric mean of pyeit / et over the sizes: max error {:.2}, L2 error {:.2}",
        mean(0),
        mean(1)
    );
}
