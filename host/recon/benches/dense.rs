//! et's frame beside the dense matrix-vector product of the Python peer's habit, `H @ dv` with
//! numpy, on the same machine in the same run, one thread each: et writes its one-step
//! matrix multiplied out (triangles x K, or the pixels inside a 64 x 64 grid x K; f64, C
//! order, as the peer keeps it) and a frame's dV as `.npy` files, and `benches/dense_numpy.py`
//! times numpy on them. A 22 cm disc, 16 electrodes adjacent (K = 208), complete electrode
//! model, alpha 0.03, at about 2 000, 8 000 and 30 000 triangles and onto 64 x 64 pixels (on
//! the 8 000-triangle mesh).
//!
//! Both sides are medians of 1 000 applications to the same data, the matrix warm in cache
//! (et's figure is `Reconstructor::frame_median`, the figure `et reconstruct --json` reports
//! as `timings_s.frame`), and of 30 with the matrix cold (a 64 MB buffer written before each
//! application, so that no level of cache holds it).
//!
//! Run: `cargo bench -p et-recon --bench dense` (set `ET_PEER_PYTHON` to an interpreter with
//! numpy, e.g. a venv's `bin/python`; default `python3`). Without numpy it says so and prints
//! et's side alone.

use std::path::Path;
use std::process::Command;
use std::time::Instant;

use et_core::protocol::{Protocol, ProtocolKind};
use et_core::sheet::Sheet;
use et_core::sheet::shape::Shape;
use et_recon::{AlphaRule, FrameOperator, MeshPlan, Method, Reconstructor, Spec};
use nalgebra::DMatrix;

fn disc() -> Sheet {
    let mut s = Sheet::rectangle(0.22, 0.22, 16);
    s.shape = Shape::Disc { radius: 0.11 };
    s.electrodes.width = 0.006;
    s
}

fn set_up(triangles: usize) -> Reconstructor {
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).expect("protocol");
    Spec {
        mesh: MeshPlan::About {
            triangles,
            refine: Vec::new(),
        },
        method: Method::GaussNewton {
            s: 0.5,
            iterations: 1,
        },
        alpha: AlphaRule::Fixed(0.03),
        pixels: 64,
        ..Spec::new(disc(), protocol.schedule(32e-6).expect("a current"))
    }
    .set_up()
    .expect("set-up")
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Writes a 64 MB buffer: afterwards no cache level holds what was read before.
fn evict(buffer: &mut [u8]) {
    for (i, b) in buffer.iter_mut().enumerate().step_by(64) {
        *b = b.wrapping_add(i as u8);
    }
    std::hint::black_box(&buffer);
}

/// Median seconds of `apply` warm (1 000 runs) and cold (30 runs, caches evicted before each).
/// (Applications of the frame itself are timed by `Reconstructor::frame_median`.)
fn warm_and_cold(mut apply: impl FnMut()) -> (f64, f64) {
    apply();
    let warm = median(
        (0..1000)
            .map(|_| {
                let t = Instant::now();
                apply();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    );
    let mut buffer = vec![0u8; 64 << 20];
    let cold = median(
        (0..30)
            .map(|_| {
                evict(&mut buffer);
                let t = Instant::now();
                apply();
                t.elapsed().as_secs_f64()
            })
            .collect(),
    );
    (warm, cold)
}

fn write_npy(path: &Path, m: &DMatrix<f64>) {
    std::fs::write(path, et_learn::npz::npy_of_matrix(m)).expect("write .npy");
}

fn main() {
    let dir = std::env::temp_dir().join(format!("et-dense-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary directory");
    let mut cases = Vec::new();
    for triangles in [2_000, 8_000, 30_000] {
        let mut recon = set_up(triangles);
        let k = recon.schedule().frame_len();
        let dv: Vec<f64> = (0..k).map(|i| 1e-4 * (i as f64 * 0.37).sin()).collect();
        let _ = recon
            .image_dv(dv.clone(), &vec![1e-12; k])
            .expect("a frame");
        let r = recon.one_step().expect("one-step matrix").matrix();
        let rows = r.nrows();
        // et's live frame onto the triangles, drawn on the pixels: as `et reconstruct` times it.
        let (warm, cold) = {
            let mut cold = Vec::new();
            let mut buffer = vec![0u8; 64 << 20];
            for _ in 0..30 {
                evict(&mut buffer);
                cold.push(recon.frame_median(&dv, 1).expect("a linear frame"));
            }
            (
                recon.frame_median(&dv, 1000).expect("a linear frame"),
                median(cold),
            )
        };
        let name = format!("{rows} triangles");
        write_npy(&dir.join(format!("{triangles}.npy")), &r);
        cases.push((name, format!("{triangles}.npy"), warm, cold, rows));
        if triangles == 8_000 {
            // The pixels inside a 64 x 64 grid: the live pipeline's operator.
            let op: FrameOperator = recon.pixel_operator().expect("a fixed alpha");
            let inside: Vec<usize> = recon.grid().triangle.iter().filter_map(|t| *t).collect();
            let p = DMatrix::from_fn(inside.len(), k, |i, c| r[(inside[i], c)]);
            let dv32: Vec<f32> = dv.iter().map(|&v| v as f32).collect();
            let mut out = vec![0.0f32; op.rows()];
            let (warm, cold) = warm_and_cold(|| {
                op.apply(std::hint::black_box(&dv32), &mut out)
                    .expect("sizes");
            });
            write_npy(&dir.join("pixels.npy"), &p);
            cases.push((
                format!("{} pixels (64 x 64)", inside.len()),
                "pixels.npy".into(),
                warm,
                cold,
                inside.len(),
            ));
        }
        write_npy(
            &dir.join(format!("dv{k}.npy")),
            &DMatrix::from_column_slice(k, 1, &dv),
        );
    }
    let python = std::env::var("ET_PEER_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/dense_numpy.py");
    let files: Vec<String> = cases.iter().map(|c| c.1.clone()).collect();
    let numpy: Vec<Option<(f64, f64, f64)>> = match Command::new(&python)
        .env("OMP_NUM_THREADS", "1")
        .env("OPENBLAS_NUM_THREADS", "1")
        .env("MKL_NUM_THREADS", "1")
        .arg(&script)
        .arg(&dir)
        .args(&files)
        .output()
    {
        Ok(out) if out.status.success() => String::from_utf8_lossy(&out.stdout)
            .lines()
            .map(|l| {
                let v: serde_json::Value = serde_json::from_str(l).ok()?;
                Some((
                    v["warm_s"].as_f64()?,
                    v["cold_s"].as_f64()?,
                    v["warm_f32_s"].as_f64()?,
                ))
            })
            .collect(),
        Ok(out) => {
            eprintln!(
                "numpy's side skipped: {python} {} failed: {}",
                script.display(),
                String::from_utf8_lossy(&out.stderr).trim()
            );
            vec![None; cases.len()]
        }
        Err(e) => {
            eprintln!("numpy's side skipped: {python}: {e}");
            vec![None; cases.len()]
        }
    };
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "| frame onto | numpy H @ dv (f64), warm | et, warm | et / numpy | numpy in f32, warm | numpy, cold | et, cold |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    let us = |s: f64| format!("{:.1} us", s * 1e6);
    for ((name, _, warm, cold, _), np) in cases
        .iter()
        .zip(numpy.iter().chain(std::iter::repeat(&None)))
    {
        let (np_warm, np_cold, np_f32) = match np {
            Some((w, c, f)) => (us(*w), us(*c), us(*f)),
            None => ("-".into(), "-".into(), "-".into()),
        };
        let ratio = np.map_or("-".into(), |(w, ..)| format!("{:.2}", warm / w));
        println!(
            "| {name} | {np_warm} | {} | {ratio} | {np_f32} | {np_cold} | {} |",
            us(*warm),
            us(*cold)
        );
    }
}
