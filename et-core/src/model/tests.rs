//! Model blob and discriminant tests. The blob is built from an f64 fit done here (Cholesky
//! route, as a trainer would); the reference discriminants are computed independently (Gauss-
//! Jordan inverse and LU determinant in f64), straight from docs/method.md §9's formulas.

use super::*;
use crate::protocol::Halving;
use crate::rng::Rng;
use std::vec;
use std::vec::Vec;

type Mat = Vec<Vec<f64>>;

fn cholesky(a: &Mat) -> Option<Mat> {
    let n = a.len();
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = a[i][j] - (0..j).map(|k| l[i][k] * l[j][k]).sum::<f64>();
            if i == j {
                if s <= 0.0 {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    Some(l)
}

/// Gauss-Jordan with partial pivoting: (inverse, log |det|).
fn inverse_logdet(a: &Mat) -> (Mat, f64) {
    let n = a.len();
    let mut m: Mat = a
        .iter()
        .map(|r| r.iter().copied().chain((0..n).map(|_| 0.0)).collect())
        .collect();
    for i in 0..n {
        m[i][n + i] = 1.0;
    }
    let mut logdet = 0.0;
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&x, &y| m[x][col].abs().total_cmp(&m[y][col].abs()))
            .unwrap();
        m.swap(col, piv);
        let d = m[col][col];
        logdet += d.abs().ln();
        for v in m[col].iter_mut() {
            *v /= d;
        }
        for r in 0..n {
            if r != col {
                let f = m[r][col];
                if f != 0.0 {
                    let pivot_row = m[col].clone();
                    for (v, pv) in m[r].iter_mut().zip(&pivot_row) {
                        *v -= f * pv;
                    }
                }
            }
        }
    }
    (m.into_iter().map(|r| r[n..].to_vec()).collect(), logdet)
}

/// A synthetic classification problem on opposite-protocol frames at L = 8 (K = 32, p = 16).
struct Problem {
    features: Vec<u16>,
    mean: Vec<f64>,
    scale: Vec<f64>,
    /// Per class: mean and covariance in z-space, prior.
    mu: Vec<Vec<f64>>,
    sigma: Vec<Mat>,
    prior: Vec<f64>,
    /// Held-out frames (full V_m) to evaluate.
    test_frames: Vec<Vec<f32>>,
}

fn problem(classes: usize, seed: u64, near_singular: bool) -> Problem {
    let protocol = Protocol::new(ProtocolKind::Opposite, 8).unwrap();
    let features: Vec<u16> = protocol
        .features(Halving::Reciprocity)
        .map(|k| k as u16)
        .collect();
    let (k, p) = (protocol.frame_len(), features.len());
    let mut rng = Rng::new(seed);
    // Class c: frame = base + offset_c + A_c * noise, volts.
    let base: Vec<f64> = (0..k).map(|_| 0.05 + 0.02 * rng.normal()).collect();
    let mut frames_by_class = Vec::new();
    let counts: Vec<usize> = (0..classes).map(|c| 150 + 40 * c).collect();
    for &n in counts.iter() {
        let offset: Vec<f64> = (0..k).map(|_| 2e-3 * rng.normal()).collect();
        let mix: Vec<Vec<f64>> = (0..k)
            .map(|_| (0..k).map(|_| 2e-4 * rng.normal()).collect())
            .collect();
        let mut frames = Vec::new();
        for _ in 0..n {
            let e: Vec<f64> = (0..k).map(|_| rng.normal()).collect();
            let mut f: Vec<f64> = (0..k)
                .map(|i| {
                    base[i]
                        + offset[i]
                        + (0..k).map(|j| mix[i][j] * e[j]).sum::<f64>()
                        + 1e-5 * rng.normal()
                })
                .collect();
            if near_singular {
                // Feature 1 is feature 0 plus a whisper of independent noise: cond(Sigma) ~ 1e6.
                let (a, b) = (usize::from(features[0]), usize::from(features[1]));
                f[b] = f[a] + 1e-7 * rng.normal();
            }
            frames.push(f);
        }
        frames_by_class.push(frames);
    }
    let all: Vec<&Vec<f64>> = frames_by_class.iter().flatten().collect();
    let n_all = all.len() as f64;
    let mean: Vec<f64> = features
        .iter()
        .map(|&i| all.iter().map(|f| f[usize::from(i)]).sum::<f64>() / n_all)
        .collect();
    let scale: Vec<f64> = features
        .iter()
        .zip(&mean)
        .map(|(&i, m)| {
            (all.iter()
                .map(|f| (f[usize::from(i)] - m).powi(2))
                .sum::<f64>()
                / (n_all - 1.0))
                .sqrt()
        })
        .collect();
    let z = |f: &Vec<f64>| -> Vec<f64> {
        features
            .iter()
            .enumerate()
            .map(|(j, &i)| (f[usize::from(i)] - mean[j]) / scale[j])
            .collect()
    };
    let mut mu = Vec::new();
    let mut sigma = Vec::new();
    for frames in &frames_by_class {
        let zs: Vec<Vec<f64>> = frames.iter().map(z).collect();
        let n = zs.len() as f64;
        let m: Vec<f64> = (0..p)
            .map(|j| zs.iter().map(|v| v[j]).sum::<f64>() / n)
            .collect();
        let s: Mat = (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| {
                        zs.iter()
                            .map(|v| (v[a] - m[a]) * (v[b] - m[b]))
                            .sum::<f64>()
                            / (n - 1.0)
                    })
                    .collect()
            })
            .collect();
        mu.push(m);
        sigma.push(s);
    }
    let total: usize = counts.iter().sum();
    let prior = counts.iter().map(|&n| n as f64 / total as f64).collect();
    // Test frames: fresh draws near each class (reuse the class's frames with a shift), plus
    // a few far from everything.
    let mut test_frames: Vec<Vec<f32>> = frames_by_class
        .iter()
        .flat_map(|fs| {
            fs.iter()
                .step_by(7)
                .map(|f| f.iter().map(|&v| (v + 1e-5 * 0.5) as f32).collect())
        })
        .collect();
    test_frames.push(vec![0.0; k]);
    test_frames.push(base.iter().map(|&v| (v * 1.5) as f32).collect());
    Problem {
        features,
        mean,
        scale,
        mu,
        sigma,
        prior,
        test_frames,
    }
}

fn packed(l: &Mat) -> Vec<f32> {
    (0..l.len())
        .flat_map(|r| (0..=r).map(move |c| (r, c)))
        .map(|(r, c)| l[r][c] as f32)
        .collect()
}

fn qda_blob(pr: &Problem, precision: Precision) -> Vec<u8> {
    let c_n = pr.mu.len();
    let p = pr.features.len();
    let mut factors = Vec::new();
    let mut constant = Vec::new();
    for s in &pr.sigma {
        let l = cholesky(s).expect("positive definite");
        constant.push((-(0..p).map(|i| l[i][i].ln()).sum::<f64>()) as f32); // -1/2 log det
        factors.extend(packed(&l));
    }
    let tables = ModelTables {
        kind: ModelKind::Qda,
        precision,
        referenced: false,
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        feature_index: &pr.features,
        mean: &pr.mean.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        scale: &pr.scale.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        positions_mm: &(0..c_n).map(|c| [10.0 * c as f32, 5.0]).collect::<Vec<_>>(),
        log_prior: &pr.prior.iter().map(|p| p.ln() as f32).collect::<Vec<_>>(),
        constant: &constant,
        vectors: &pr
            .mu
            .iter()
            .flatten()
            .map(|&v| v as f32)
            .collect::<Vec<_>>(),
        factors: &factors,
    };
    let mut out = vec![0u8; model_len(ModelKind::Qda, precision, c_n, p)];
    let n = write_model(&tables, &mut out).unwrap();
    assert_eq!(n, out.len());
    out
}

fn zspace(pr: &Problem, v: &[f32]) -> Vec<f64> {
    pr.features
        .iter()
        .enumerate()
        .map(|(j, &i)| (f64::from(v[usize::from(i)]) - pr.mean[j]) / pr.scale[j])
        .collect()
}

fn reference_qda(pr: &Problem, v: &[f32]) -> Vec<f64> {
    let z = zspace(pr, v);
    (0..pr.mu.len())
        .map(|c| {
            let (inv, logdet) = inverse_logdet(&pr.sigma[c]);
            let d: Vec<f64> = z.iter().zip(&pr.mu[c]).map(|(a, b)| a - b).collect();
            let q: f64 = (0..d.len())
                .map(|i| d[i] * (0..d.len()).map(|j| inv[i][j] * d[j]).sum::<f64>())
                .sum();
            -0.5 * q - 0.5 * logdet + pr.prior[c].ln()
        })
        .collect()
}

fn assert_close(got: &[f32], want: &[f64], rel: f64, what: &str) {
    for (c, (&g, &w)) in got.iter().zip(want).enumerate() {
        let err = (f64::from(g) - w).abs() / w.abs().max(1.0);
        assert!(
            err <= rel,
            "{what}: class {c}: got {g}, reference {w}, relative error {err:e}"
        );
    }
}

fn argmax(v: &[f64]) -> usize {
    (0..v.len()).max_by(|&a, &b| v[a].total_cmp(&v[b])).unwrap()
}

#[test]
fn qda_agrees_with_an_independent_f64_reference() {
    let pr = problem(5, 0x5eed, false);
    let blob = qda_blob(&pr, Precision::F32);
    let model = Model::parse(&blob).unwrap();
    assert_eq!(
        (model.classes(), model.features(), model.frame_len()),
        (5, 16, 32)
    );
    let mut scratch = vec![0.0; model.scratch_len()];
    let mut d = vec![0.0; 5];
    for v in &pr.test_frames {
        model.discriminants(v, &mut scratch, &mut d).unwrap();
        let want = reference_qda(&pr, v);
        assert_close(&d, &want, 1e-4, "QDA");
        let decision = model.evaluate(v, &mut scratch).unwrap();
        let best = argmax(&want);
        assert_eq!(usize::from(decision.class), best);
        let mut sorted = want.clone();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let margin = sorted[0] - sorted[1];
        assert!(
            (f64::from(decision.margin) - margin).abs() <= 1e-4 * sorted[0].abs().max(1.0) * 2.0
        );
        assert!(decision.margin >= 0.0);
    }
}

#[test]
fn lda_agrees_with_an_independent_f64_reference() {
    let pr = problem(4, 0xabcdef, false);
    let (c_n, p) = (pr.mu.len(), pr.features.len());
    // Pooled covariance [5.3] (equal weighting of the within-class scatter).
    let pooled: Mat = (0..p)
        .map(|a| {
            (0..p)
                .map(|b| pr.sigma.iter().map(|s| s[a][b]).sum::<f64>() / c_n as f64)
                .collect()
        })
        .collect();
    // Trainer's route: w_c = Sigma^-1 mu_c by Cholesky solves.
    let l = cholesky(&pooled).unwrap();
    let solve = |b: &[f64]| -> Vec<f64> {
        let mut y = vec![0.0; p];
        for i in 0..p {
            y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
        }
        let mut x = vec![0.0; p];
        for i in (0..p).rev() {
            x[i] = (y[i] - (i + 1..p).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
        }
        x
    };
    let w: Vec<Vec<f64>> = pr.mu.iter().map(|m| solve(m)).collect();
    let constant: Vec<f32> = w
        .iter()
        .zip(&pr.mu)
        .map(|(w, m)| (-0.5 * w.iter().zip(m).map(|(a, b)| a * b).sum::<f64>()) as f32)
        .collect();
    let tables = ModelTables {
        kind: ModelKind::Lda,
        precision: Precision::F32,
        referenced: false,
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        feature_index: &pr.features,
        mean: &pr.mean.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        scale: &pr.scale.iter().map(|&v| v as f32).collect::<Vec<_>>(),
        positions_mm: &vec![[0.0, 0.0]; c_n],
        log_prior: &pr.prior.iter().map(|p| p.ln() as f32).collect::<Vec<_>>(),
        constant: &constant,
        vectors: &w.iter().flatten().map(|&v| v as f32).collect::<Vec<_>>(),
        factors: &[],
    };
    let mut blob = vec![0u8; model_len(ModelKind::Lda, Precision::F32, c_n, p)];
    write_model(&tables, &mut blob).unwrap();
    let model = Model::parse(&blob).unwrap();
    assert_eq!(model.kind(), ModelKind::Lda);
    let (inv, _) = inverse_logdet(&pooled);
    let mut scratch = vec![0.0; model.scratch_len()];
    let mut d = vec![0.0; c_n];
    for v in &pr.test_frames {
        let z = zspace(&pr, v);
        let want: Vec<f64> = (0..c_n)
            .map(|c| {
                let sm: Vec<f64> = (0..p)
                    .map(|i| (0..p).map(|j| inv[i][j] * pr.mu[c][j]).sum())
                    .collect();
                let x_s_m: f64 = z.iter().zip(&sm).map(|(a, b)| a * b).sum();
                let m_s_m: f64 = pr.mu[c].iter().zip(&sm).map(|(a, b)| a * b).sum();
                x_s_m - 0.5 * m_s_m + pr.prior[c].ln()
            })
            .collect();
        model.discriminants(v, &mut scratch, &mut d).unwrap();
        assert_close(&d, &want, 1e-4, "LDA");
        assert_eq!(
            usize::from(model.evaluate(v, &mut scratch).unwrap().class),
            argmax(&want)
        );
    }
}

#[test]
fn near_singular_covariance_stays_finite() {
    let pr = problem(3, 77, true);
    let blob = qda_blob(&pr, Precision::F32);
    let model = Model::parse(&blob).expect("cond ~1e6 is still usable in f32");
    let mut scratch = vec![0.0; model.scratch_len()];
    let mut d = vec![0.0; 3];
    for v in &pr.test_frames {
        model.discriminants(v, &mut scratch, &mut d).unwrap();
        assert!(d.iter().all(|x| x.is_finite()));
        assert_eq!(
            usize::from(model.evaluate(v, &mut scratch).unwrap().class),
            argmax(&reference_qda(&pr, v))
        );
    }
    // Extreme but finite inputs give a decision or a typed error, never a NaN.
    for scale in [1e3f32, 1e10, 1e30] {
        let v = vec![scale; model.frame_len()];
        match model.evaluate(&v, &mut scratch) {
            Ok(dec) => assert!(dec.discriminant.is_finite() && dec.margin.is_finite()),
            Err(e) => assert_eq!(e, EvalError::NonFinite),
        }
    }
    let mut v = pr.test_frames[0].clone();
    v[usize::from(pr.features[3])] = f32::NAN;
    assert_eq!(model.evaluate(&v, &mut scratch), Err(EvalError::NonFinite));
}

/// Rewrites the factor diagonal of class 1 with `f(row)` and re-signs the blob.
fn with_diagonal(blob: &[u8], f: impl Fn(usize) -> f32) -> Vec<u8> {
    let model = Model::parse(blob).unwrap();
    let p = model.features();
    let mut b = blob.to_vec();
    let lay = model.layout;
    for r in 0..p {
        let at = lay.factors + 4 * (packed_len(p) + packed_len(r) + r);
        b[at..at + 4].copy_from_slice(&f(r).to_le_bytes());
    }
    let crc = crc32(&b[..lay.crc]);
    b[lay.crc..].copy_from_slice(&crc.to_le_bytes());
    b
}

#[test]
fn singular_and_ill_conditioned_models_are_refused_at_load() {
    let pr = problem(3, 99, false);
    let blob = qda_blob(&pr, Precision::F32);
    let zero = with_diagonal(&blob, |r| if r == 4 { 0.0 } else { 1.0 });
    assert_eq!(
        Model::parse(&zero).unwrap_err(),
        ModelError::Singular { class: 1 }
    );
    let tiny = with_diagonal(&blob, |r| if r == 4 { 1e-7 } else { 1.0 });
    assert_eq!(
        Model::parse(&tiny).unwrap_err(),
        ModelError::IllConditioned { class: 1 }
    );
    let ok = with_diagonal(&blob, |r| if r == 4 { 1e-4 } else { 1.0 });
    assert!(Model::parse(&ok).is_ok());
    let nan = with_diagonal(&blob, |r| if r == 2 { f32::NAN } else { 1.0 });
    assert_eq!(
        Model::parse(&nan).unwrap_err(),
        ModelError::NonFinite { class: 1 }
    );
    // A feature's mean past single precision is named by its feature.
    let mut mean = blob.clone();
    let (lay, at) = (Model::parse(&blob).unwrap().layout, 3);
    let m = lay.mean + 4 * at;
    mean[m..m + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
    let crc = crc32(&mean[..lay.crc]);
    mean[lay.crc..].copy_from_slice(&crc.to_le_bytes());
    assert_eq!(
        Model::parse(&mean).unwrap_err(),
        ModelError::NonFiniteFeature { feature: 3 }
    );
}

#[test]
fn corrupted_or_mismatched_blobs_are_refused() {
    let pr = problem(2, 5, false);
    let blob = qda_blob(&pr, Precision::F32);
    // Every single-byte corruption anywhere is refused (CRC-32 catches all of them).
    for i in 0..blob.len() {
        for flip in [0x01u8, 0x80, 0xff] {
            let mut b = blob.clone();
            b[i] ^= flip;
            assert!(
                Model::parse(&b).is_err(),
                "flip {flip:#x} at byte {i} accepted"
            );
        }
    }
    assert!(matches!(
        Model::parse(&blob[..blob.len() - 1]),
        Err(ModelError::Length { .. })
    ));
    assert!(matches!(
        Model::parse(&blob[..10]),
        Err(ModelError::Length { .. })
    ));
    let mut longer = blob.clone();
    longer.push(0);
    assert!(matches!(
        Model::parse(&longer),
        Err(ModelError::Length { .. })
    ));
    let resign = |mut b: Vec<u8>| {
        let n = b.len() - 4;
        let crc = crc32(&b[..n]);
        b[n..].copy_from_slice(&crc.to_le_bytes());
        b
    };
    let mut v2 = blob.clone();
    v2[4] = 2;
    assert_eq!(
        Model::parse(&resign(v2)).unwrap_err(),
        ModelError::Version { got: 2 }
    );
    let mut magic = blob.clone();
    magic[0] = b'X';
    assert_eq!(Model::parse(&magic).unwrap_err(), ModelError::Magic);
    let mut kind = blob.clone();
    kind[6] = 9;
    assert_eq!(Model::parse(&resign(kind)).unwrap_err(), ModelError::Header);
    let mut flags = blob.clone();
    flags[17] = 2; // an unknown flag
    assert_eq!(
        Model::parse(&resign(flags)).unwrap_err(),
        ModelError::Header
    );
    let mut idx = blob.clone();
    idx[HEADER_LEN..HEADER_LEN + 2].copy_from_slice(&32u16.to_le_bytes());
    assert_eq!(
        Model::parse(&resign(idx)).unwrap_err(),
        ModelError::FeatureIndex { feature: 0 }
    );
    // A frame value read twice (or out of frame order) would weigh one channel twice.
    let mut twice = blob.clone();
    twice.copy_within(HEADER_LEN..HEADER_LEN + 2, HEADER_LEN + 2);
    assert_eq!(
        Model::parse(&resign(twice)).unwrap_err(),
        ModelError::FeatureOrder { feature: 1 }
    );
    let mut elec = blob.clone();
    elec[14] = 16; // K of opposite at L = 16 is 192, header says 32
    assert_eq!(
        Model::parse(&resign(elec)).unwrap_err(),
        ModelError::FrameLength {
            expected: 192,
            got: 32
        }
    );
    // Mismatch against a configuration and a frame.
    let model = Model::parse(&blob).unwrap();
    let cfg = ScanConfig {
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        ..ScanConfig::REFERENCE
    };
    assert_eq!(model.check_config(&cfg), Ok(()));
    assert_eq!(
        model.check_config(&ScanConfig {
            protocol: ProtocolKind::Adjacent,
            ..cfg
        }),
        Err(Mismatch::Protocol)
    );
    assert_eq!(
        model.check_config(&ScanConfig {
            electrodes: 16,
            ..cfg
        }),
        Err(Mismatch::Electrodes)
    );
    let mut scratch = vec![0.0; model.scratch_len()];
    assert_eq!(
        model.evaluate(&[0.0; 208], &mut scratch),
        Err(EvalError::FrameLength {
            expected: 32,
            got: 208
        })
    );
    assert_eq!(
        model.evaluate(&[0.0; 32], &mut scratch[..3]),
        Err(EvalError::Scratch {
            needed: 32,
            given: 3
        })
    );
}

#[test]
fn f16_storage_halves_the_size_and_keeps_the_decisions() {
    let pr = problem(5, 0x5eed, false);
    let full = qda_blob(&pr, Precision::F32);
    let half = qda_blob(&pr, Precision::F16);
    let (m32, m16) = (Model::parse(&full).unwrap(), Model::parse(&half).unwrap());
    assert!(
        half.len() * 10 < full.len() * 6,
        "{} vs {}",
        half.len(),
        full.len()
    );
    let mut s = vec![0.0; m32.scratch_len()];
    let (mut d32, mut d16) = (vec![0.0; 5], vec![0.0; 5]);
    let mut agree = 0;
    for v in &pr.test_frames {
        m32.discriminants(v, &mut s, &mut d32).unwrap();
        m16.discriminants(v, &mut s, &mut d16).unwrap();
        let want: Vec<f64> = d32.iter().map(|&x| f64::from(x)).collect();
        assert_close(&d16, &want, 2e-2, "f16 vs f32");
        agree += usize::from(
            m32.evaluate(v, &mut s).unwrap().class == m16.evaluate(v, &mut s).unwrap().class,
        );
    }
    assert!(
        agree * 100 >= pr.test_frames.len() * 97,
        "{agree} of {}",
        pr.test_frames.len()
    );
}

#[test]
fn sizes_of_the_reference_models() {
    // docs/design.md: a full-covariance QDA for 49 classes at p = 96 in f32 is about 0.93 MB.
    let qda49 = model_len(ModelKind::Qda, Precision::F32, 49, 96);
    assert!((930_000..935_000).contains(&qda49), "{qda49}");
    assert!(model_len(ModelKind::Qda, Precision::F16, 49, 96) < 470_000);
    // 100 classes only fit 1 MiB of flash in f16 (barely) or as LDA.
    assert!(model_len(ModelKind::Qda, Precision::F32, 100, 96) > 1 << 20);
    assert!(model_len(ModelKind::Qda, Precision::F16, 100, 96) < 1 << 20);
    assert!(model_len(ModelKind::Lda, Precision::F32, 100, 96) < 50_000);
}

#[test]
fn writer_refuses_inconsistent_tables() {
    let t = ModelTables {
        kind: ModelKind::Lda,
        precision: Precision::F32,
        referenced: false,
        electrodes: 8,
        protocol: ProtocolKind::Opposite,
        feature_index: &[0, 1],
        mean: &[0.0, 0.0],
        scale: &[1.0], // one short
        positions_mm: &[[0.0, 0.0]; 2],
        log_prior: &[-0.7, -0.7],
        constant: &[0.0, 0.0],
        vectors: &[0.0; 4],
        factors: &[],
    };
    let mut out = vec![0u8; 1024];
    assert_eq!(write_model(&t, &mut out), Err(ModelError::Table));
    let t = ModelTables {
        scale: &[1.0, 0.0],
        ..t
    };
    assert_eq!(
        write_model(&t, &mut out),
        Err(ModelError::Scale { feature: 1 })
    );
    let t = ModelTables {
        scale: &[1.0, 1.0],
        ..t
    };
    assert_eq!(write_model(&t, &mut out[..10]), Err(ModelError::Table));
    assert!(write_model(&t, &mut out).is_ok());
}

#[test]
fn a_referenced_model_classifies_the_frame_minus_the_untouched_frame() {
    let pr = problem(5, 0x7a3e, false);
    let plain = qda_blob(&pr, Precision::F32);
    let mut blob = plain.clone();
    blob[17] = FLAG_REFERENCED;
    let n = blob.len() - 4;
    let crc = crc32(&blob[..n]);
    blob[n..].copy_from_slice(&crc.to_le_bytes());
    let (plain, model) = (Model::parse(&plain).unwrap(), Model::parse(&blob).unwrap());
    assert!(model.referenced() && !plain.referenced());
    let mut scratch = vec![0.0; model.scratch_len()];
    let (mut d, mut want) = (vec![0.0; 5], vec![0.0; 5]);
    // An untouched frame with standing voltages of its own.
    let v_0: Vec<f32> = (0..32).map(|i| 0.01 * i as f32 - 0.1).collect();
    for v in &pr.test_frames {
        let v_m: Vec<f32> = v.iter().zip(&v_0).map(|(a, b)| a + b).collect();
        model
            .discriminants_referenced(&v_m, Some(&v_0), &mut scratch, &mut d)
            .unwrap();
        plain.discriminants(v, &mut scratch, &mut want).unwrap();
        for (g, w) in d.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-4 * w.abs().max(1.0), "{g} vs {w}");
        }
        // The unreferenced model ignores an untouched frame.
        plain
            .discriminants_referenced(v, Some(&v_0), &mut scratch, &mut d)
            .unwrap();
        assert_eq!(d, want);
    }
    let v = &pr.test_frames[0];
    assert_eq!(model.evaluate(v, &mut scratch), Err(EvalError::Untouched));
    assert_eq!(
        model.evaluate_referenced(v, Some(&v_0[..31]), &mut scratch),
        Err(EvalError::Untouched)
    );
    let mut bad = v_0.clone();
    bad[usize::from(pr.features[0])] = f32::NAN;
    assert_eq!(
        model.evaluate_referenced(v, Some(&bad), &mut scratch),
        Err(EvalError::NonFinite)
    );
}

/// The smallest blob there is, byte for byte: LDA, f32, C = 2, p = 1, adjacent on 4 electrodes
/// (K = 4). The expected bytes were written from the layout table in the module docs by a
/// separate Python script (struct.pack, zlib.crc32 for the CRC-32/ISO-HDLC), not by this code:
/// a change to the format must change this test and the version.
#[test]
fn golden_bytes_of_the_blob_format() {
    let tables = ModelTables {
        kind: ModelKind::Lda,
        precision: Precision::F32,
        referenced: false,
        electrodes: 4,
        protocol: ProtocolKind::Adjacent,
        feature_index: &[2],
        mean: &[0.5],
        scale: &[2.0],
        positions_mm: &[[10.0, 20.0], [30.0, 40.0]],
        log_prior: &[-0.5, -1.5],
        constant: &[0.25, -0.75],
        vectors: &[1.0, -2.0],
        factors: &[],
    };
    let golden = [
        "45544441010001000200010004000400",
        "00000000000000000000000000000000",
        "020000000000003f0000004000002041",
        "0000a0410000f04100002042000000bf",
        "0000c0bf0000803e000040bf0000803f",
        "000000c0fe569615",
    ]
    .concat();
    let want: Vec<u8> = (0..golden.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&golden[i..i + 2], 16).unwrap())
        .collect();
    assert_eq!(model_len(ModelKind::Lda, Precision::F32, 2, 1), want.len());
    let mut blob = vec![0u8; want.len()];
    write_model(&tables, &mut blob).unwrap();
    assert_eq!(blob, want);
    let model = Model::parse(&want).unwrap();
    assert_eq!((model.classes(), model.features()), (2, 1));
}

/// Header fields whose table sizes pass 4 GiB: on the board (usize = u32) the old unchecked
/// layout wrapped such a QDA header's length into one a crafted blob could match, and the
/// table checks then read past it (`tests/tests/qemu.rs` uploads one to the firmware image).
/// The layout now sums in u64 and refuses what the address space cannot hold; checked here
/// with the board's usize::MAX, on any host.
#[test]
fn sizes_beyond_the_32_bit_address_space_are_refused() {
    let k = Protocol::new(ProtocolKind::PpPp, 32).unwrap().frame_len();
    let (c, p) = (usize::from(u16::MAX), k);
    let true_len = model_len(ModelKind::Qda, Precision::F32, c, p) as u64;
    assert!(true_len > u64::from(u32::MAX), "{true_len}");
    let on_board = |c, p| layout_within(ModelKind::Qda, Precision::F32, c, p, u64::from(u32::MAX));
    assert_eq!(on_board(c, p), None);
    // Small models are unaffected: the same layout as the host's.
    assert_eq!(
        on_board(49, 96),
        layout(ModelKind::Qda, Precision::F32, 49, 96)
    );
    // Counts beyond the format's u16 fields never fit.
    assert_eq!(
        model_len(ModelKind::Lda, Precision::F32, 2, 1 << 16),
        usize::MAX
    );
}

mod never_panics {
    use super::*;
    use proptest::prelude::*;

    /// A valid QDA blob (C = 3, p = 4, opposite on 8 electrodes) to mutate.
    fn valid_blob() -> Vec<u8> {
        let (c_n, p) = (3, 4);
        let factors: Vec<f32> = (0..c_n)
            .flat_map(|_| (0..p).flat_map(|r| (0..=r).map(move |q| if q == r { 1.0 } else { 0.1 })))
            .collect();
        let tables = ModelTables {
            kind: ModelKind::Qda,
            precision: Precision::F16,
            referenced: true,
            electrodes: 8,
            protocol: ProtocolKind::Opposite,
            feature_index: &[0, 3, 7, 11],
            mean: &[0.1; 4],
            scale: &[1.0; 4],
            positions_mm: &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            log_prior: &[-1.1; 3],
            constant: &[0.0; 3],
            vectors: &[0.5; 12],
            factors: &factors,
        };
        let mut blob = vec![0u8; model_len(ModelKind::Qda, Precision::F16, c_n, p)];
        write_model(&tables, &mut blob).unwrap();
        Model::parse(&blob).unwrap();
        blob
    }

    /// Parses `bytes` and, if accepted, evaluates a frame with it: neither may panic.
    fn parse_and_use(bytes: &[u8]) {
        if let Ok(m) = Model::parse(bytes) {
            let v = vec![0.01f32; m.frame_len()];
            let mut scratch = vec![0.0f32; m.scratch_len()];
            let _ = m.evaluate_referenced(&v, Some(&v), &mut scratch);
        }
        let _ = Model::parse_header(bytes);
    }

    proptest! {
        /// Any bytes at all.
        #[test]
        fn on_any_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
            parse_and_use(&bytes);
        }

        /// A valid blob with bytes overwritten, its CRC made valid again (so the checks after
        /// the CRC see the damage), and perhaps cut short.
        #[test]
        fn on_damaged_blobs_with_valid_crcs(
            edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..8),
            cut in proptest::option::of(any::<usize>()),
        ) {
            let mut blob = valid_blob();
            for (at, v) in edits {
                let i = at % blob.len();
                blob[i] = v;
            }
            let n = blob.len();
            let crc = crate::wire::crc32(&blob[..n - 4]);
            blob[n - 4..].copy_from_slice(&crc.to_le_bytes());
            if let Some(cut) = cut {
                blob.truncate(cut % (n + 1));
            }
            parse_and_use(&blob);
        }
    }
}
