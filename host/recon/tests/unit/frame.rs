use et_core::sheet::Sheet;
use et_recon::reconstructor::*;

/// The model's own frame of a bump of `scale` x sigma_0 near (3, 2) cm on a 10 cm disc
/// of 16 electrodes (pairs adjacent, drive electrodes measured too), imaged at alpha 0.1:
/// the linearisation's misfit at that image.
fn misfit_at(recon: &mut Reconstructor, scale: f64) -> f64 {
    let (v0, v) = (bump_frame(recon, 0.0), bump_frame(recon, scale));
    let reference = Reference::from_frames(&[v0]).unwrap();
    let image = recon.image(&v, &reference).unwrap();
    recon.linearisation_misfit(&image).unwrap().unwrap()
}

#[test]
fn the_linearisation_misfit_is_of_second_order() {
    // F(sigma_0 + d) - F(sigma_0) - J d is O(|d|^2) while dV is O(|d|): the misfit's share
    // halves as the change halves, and vanishes with it.
    let sheet = Sheet::disc(0.1, 16);
    let pairs: Vec<(u16, u16)> = (0..16).map(|i| (i, (i + 1) % 16)).collect();
    let schedule = et_core::schedule::Schedule::adjacent_pairs_under(16, &pairs, 1e-3).unwrap();
    let mut recon = Spec {
        mesh: MeshPlan::About {
            triangles: 600,
            refine: Vec::new(),
        },
        alpha: AlphaRule::Fixed(0.1),
        ..Spec::new(sheet, schedule)
    }
    .set_up()
    .unwrap();
    let (large, small) = (misfit_at(&mut recon, 0.4), misfit_at(&mut recon, 0.1));
    assert!(small < 0.05, "at a 10 % bump: {small}");
    let ratio = large / small;
    assert!(
        (2.5..6.0).contains(&ratio),
        "4 times the change, {ratio:.2} times the misfit's share ({large:.4} against {small:.4})"
    );
}

/// A 10 cm disc of 16 electrodes, the adjacent protocol, the given alpha rule; the model's
/// frames of the untouched sheet and of a bump of `scale` x sigma_0 near (3, 2) cm.
fn disc_and_bump(alpha: AlphaRule, scales: &[f64]) -> (Reconstructor, Vec<f32>, Vec<Vec<f32>>) {
    let sheet = Sheet::disc(0.1, 16);
    let protocol =
        et_core::protocol::Protocol::new(et_core::protocol::ProtocolKind::Adjacent, 16).unwrap();
    let schedule = et_core::schedule::Schedule::of_protocol(&protocol, 1e-3).unwrap();
    let recon = Spec {
        mesh: MeshPlan::About {
            triangles: 900,
            refine: Vec::new(),
        },
        alpha,
        ..Spec::new(sheet, schedule)
    }
    .set_up()
    .unwrap();
    let frames = scales.iter().map(|&s| bump_frame(&recon, s)).collect();
    let v0 = bump_frame(&recon, 0.0);
    (recon, v0, frames)
}

/// The model's own frame (f32, as et's frames are) of a bump of `scale` x sigma_0 near
/// (3, 2) cm, 1.5 cm wide.
fn bump_frame(recon: &Reconstructor, scale: f64) -> Vec<f32> {
    let sigma0 = recon.imager().background();
    let mesh = recon.imager().forward.mesh();
    let sigma: Vec<f64> = (0..sigma0.len())
        .map(|t| {
            let [x, y] = mesh.centroid(t);
            let r2 = (x - 0.03).powi(2) + (y - 0.02).powi(2);
            sigma0[t] * (1.0 + scale * (-r2 / (2.0 * 0.015f64.powi(2))).exp())
        })
        .collect();
    (recon
        .imager()
        .forward
        .frame(&sigma, recon.schedule())
        .unwrap())
    .into_iter()
    .map(|x| x as f32)
    .collect()
}

/// Frames against a reference set once: the same image as with the reference given, the
/// noise image from the squared rows (second frame on) as from the factors, the pixels
/// alone as the whole image's (f64 at a matrix's first frame, f32 after), a matrix kept when
/// alpha comes back to it, and a clear error before any reference.
#[test]
fn frames_against_a_reference_set_once_image_as_with_it_given() {
    let (mut recon, v0, frames) = disc_and_bump(AlphaRule::Gcv, &[0.5, 0.05]);
    let e = recon.image_frame(&frames[0]).unwrap_err();
    assert!(matches!(e, ImagingError::NoReference), "{e}");
    assert!(e.to_string().contains("set_reference"), "{e}");
    // Two reference frames 1 uV apart: the noise of dV is known (no redundancy estimate).
    let v0b: Vec<f32> = v0.iter().map(|v| v + 1e-6).collect();
    let reference = Reference::from_frames(&[v0.clone(), v0b]).unwrap();
    let given = recon.image(&frames[0], &reference).unwrap();
    recon.set_reference(reference.clone()).unwrap();
    let first = recon.image_frame(&frames[0]).unwrap();
    assert_eq!(first.pixels, given.pixels);
    // The noise from the factors at the matrix's first frame, from the squared rows (f32)
    // after.
    close_relative(&first.noise_sd, &given.noise_sd, 1e-5);
    assert!(first.noise_sd.iter().flatten().any(|v| *v > 0.0));
    // The pixels alone: exact at a fresh matrix, f32's precision through the operator.
    let (mut fresh, _, _) = disc_and_bump(AlphaRule::Gcv, &[]);
    fresh.set_reference(reference).unwrap();
    let peak = first
        .pixels
        .iter()
        .flatten()
        .fold(0.0f64, |m, v| m.max(v.abs()));
    for k in 0..3 {
        let p = fresh.frame_pixels(&frames[0]).unwrap();
        assert_eq!(p.alpha, first.alpha);
        if k == 0 {
            assert_eq!(p.pixels, first.pixels);
        } else {
            // The f32 operator: 1e-5 of the peak measured (the live pipeline's precision).
            close(&p.pixels, &first.pixels, 1e-4 * peak);
        }
    }
    // A weaker bump may take another alpha; coming back, the first matrix is still kept.
    let weak = recon.image_frame(&frames[1]).unwrap();
    let again = recon.image_frame(&frames[0]).unwrap();
    assert_eq!(again.alpha, first.alpha);
    if weak.alpha != first.alpha {
        assert!(
            weak.timings.matrix.is_some(),
            "a new alpha makes its matrix"
        );
    }
    assert_eq!(
        again.timings.matrix, None,
        "the matrix at the first alpha was kept"
    );
    assert_eq!(again.pixels, first.pixels);
}

/// Two images' pixels (None outside) within a relative `tol` of each other.
fn close_relative(a: &[Option<f64>], b: &[Option<f64>], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (p, (a, b)) in a.iter().zip(b).enumerate() {
        match (a, b) {
            (Some(a), Some(b)) => {
                assert!((a - b).abs() <= tol * a.abs(), "pixel {p}: {a} against {b}")
            }
            _ => assert_eq!(a.is_some(), b.is_some(), "pixel {p}"),
        }
    }
}

/// Two images' pixels (None outside) within `tol` of each other, relative for values above
/// 1 and absolute below.
fn close(a: &[Option<f64>], b: &[Option<f64>], tol: f64) {
    assert_eq!(a.len(), b.len());
    for (p, (a, b)) in a.iter().zip(b).enumerate() {
        match (a, b) {
            (Some(a), Some(b)) => {
                assert!(
                    (a - b).abs() <= tol * a.abs().max(1.0),
                    "pixel {p}: {a} against {b}"
                )
            }
            _ => assert_eq!(a.is_some(), b.is_some(), "pixel {p}"),
        }
    }
}

/// Many frames at once (over every core): each frame's pixels, alpha, noise, objects and
/// touches as the frame imaged whole and alone finds them (the objects' pixels' noise made
/// through the f32 operator's squared rows, to f32's precision), in the frames' order; a
/// frame that cannot be imaged named by its place.
#[test]
fn a_batch_of_frames_finds_what_each_frame_alone_finds() {
    let scales = [0.5, 0.05, 0.3, 0.5, 0.2, 0.05];
    let (mut recon, v0, frames) = disc_and_bump(
        AlphaRule::Chosen(et_recon::gcv::Criterion::CornerAboveFloor),
        &scales,
    );
    let v0b: Vec<f32> = v0.iter().map(|v| v + 1e-6).collect();
    let reference = Reference::from_frames(&[v0, v0b]).unwrap();
    let (mut alone, _, _) = disc_and_bump(
        AlphaRule::Chosen(et_recon::gcv::Criterion::CornerAboveFloor),
        &[],
    );
    recon.set_reference(reference.clone()).unwrap();
    alone.set_reference(reference).unwrap();
    let views: Vec<&[f32]> = frames.iter().map(Vec::as_slice).collect();
    let batch = recon.image_frames(&views, true).unwrap();
    assert_eq!(batch.len(), frames.len());
    let grid = recon.grid().clone();
    for (k, (frame, got)) in frames.iter().zip(&batch).enumerate() {
        let whole = alone.image_frame(frame).unwrap();
        assert_eq!(got.pixels.alpha, whole.alpha, "frame {k}");
        assert_eq!(got.noise, whole.noise, "frame {k}");
        let peak = (whole.pixels.iter().flatten()).fold(0.0f64, |m, v| m.max(v.abs()));
        close(&got.pixels.pixels, &whole.pixels, 1e-4 * peak);
        let found = got.found.as_ref().expect("objects were asked for");
        let objects = alone.objects(&whole);
        assert!(!objects.is_empty(), "frame {k}: the bump is an object");
        assert_eq!(found.objects.len(), objects.len(), "frame {k}");
        for (a, b) in found.objects.iter().zip(&objects) {
            assert_eq!(a.sign, b.sign, "frame {k}");
            let moved = (a.region.centroid[0] - b.region.centroid[0])
                .hypot(a.region.centroid[1] - b.region.centroid[1]);
            assert!(moved <= grid.size, "frame {k}: {moved} m");
            let (za, zb) = (a.region.z.unwrap(), b.region.z.unwrap());
            assert!(
                (za - zb).abs() <= 1e-3 * zb,
                "frame {k}: z {za} against {zb}"
            );
        }
        assert_eq!(found.touches.len(), whole.touches.len(), "frame {k}");
    }
    // Without objects: the pixels alone.
    let bare = recon.image_frames(&views[..2], false).unwrap();
    assert!(bare.iter().all(|f| f.found.is_none()));
    // A frame of the wrong length among good ones: named by its place.
    let short = &frames[1][1..];
    let e = recon
        .image_frames(&[views[0], short, views[2]], true)
        .unwrap_err();
    assert!(matches!(e, ImagingError::Frame { index: 1, .. }), "{e:?}");
    assert!(e.to_string().contains("frame 1"), "{e}");
}

/// A frame's scale to its reference is the median of its values' ratios: a frame in mV
/// against V_0 in V is 1000 times it, a press a few per cent, and a frame whose detached
/// electrode's values sit at a rail (a quarter of adjacent's on 16) is still 1 (the
/// least-squares scale was 0.27, and the frame was said as of another unit).
#[test]
fn a_frames_scale_to_its_reference_holds_past_an_electrode_off() {
    let (recon, v0, frames) = disc_and_bump(AlphaRule::Fixed(0.1), &[0.2]);
    let reference = Reference::from_frames(std::slice::from_ref(&v0)).unwrap();
    let near = |s: Option<f64>, want: f64| s.is_some_and(|s| (s / want - 1.0).abs() < 0.05);
    let mv: Vec<f32> = v0.iter().map(|v| v * 1e3).collect();
    assert!(near(reference.scale_of(&mv), 1e3));
    assert!(
        near(reference.scale_of(&frames[0]), 1.0),
        "{:?}",
        reference.scale_of(&frames[0])
    );
    let rows = recon.schedule().rows();
    let railed: Vec<f32> = (v0.iter().zip(rows))
        .map(
            |(v, r)| match [r.source, r.sink, r.positive, r.negative].contains(&5) {
                true => 3.3,
                false => *v,
            },
        )
        .collect();
    let dot = |a: &[f32], b: &[f32]| {
        a.iter()
            .zip(b)
            .map(|(x, y)| f64::from(*x) * f64::from(*y))
            .sum::<f64>()
    };
    let least_squares = dot(&railed, &v0) / dot(&v0, &v0);
    assert!(!(0.5..=2.0).contains(&least_squares), "{least_squares}");
    assert!(
        near(reference.scale_of(&railed), 1.0),
        "{:?}",
        reference.scale_of(&railed)
    );
}

/// A reference of the other sign (a polarity or a drive swapped, or magnitudes of a protocol
/// whose values are all of one sign) or all zero is refused when set, naming what to check; the model's own reference, and one 30 % off in scale, are taken.
#[test]
fn a_reference_against_the_model_is_refused() {
    let (mut recon, v0, _) = disc_and_bump(AlphaRule::Fixed(0.1), &[]);
    let negated: Vec<f32> = v0.iter().map(|v| -v).collect();
    let e = recon
        .set_reference(Reference::from_frames(&[negated]).unwrap())
        .unwrap_err();
    assert!(
        matches!(e, ImagingError::ReferenceAgainstModel(..)),
        "{e:?}"
    );
    assert!(e.to_string().contains("-1.00"), "{e}");
    assert!(e.to_string().contains("direction"), "{e}");
    // Adjacent's values are all of one sign, so magnitudes of its frames are this frame: said
    // as a cause too (magnitudes were asked about only where the model has both signs).
    assert!(
        e.to_string()
            .ends_with("? Or magnitudes without their sign: every value of the reference is of one sign, the model's all of the other; et images signed voltages (the real part)"),
        "{e}"
    );
    assert!(recon.reference().is_none(), "nothing set");
    // One value throughout (all zero, a constant) is no measurement: not asked about
    // swapped electrodes.
    for value in [0.0f32, 1.0] {
        let constant = vec![value; v0.len()];
        let e = recon
            .set_reference(Reference::from_frames(&[constant]).unwrap())
            .unwrap_err();
        assert!(matches!(e, ImagingError::ReferenceNotMeasured(_)), "{e:?}");
        let said = e.to_string();
        assert!(
            said.contains("not measured") && !said.contains("swapped"),
            "{said}"
        );
    }
    let scaled: Vec<f32> = v0.iter().map(|v| 1.3 * v).collect();
    recon
        .set_reference(Reference::from_frames(&[scaled]).unwrap())
        .unwrap();
    recon
        .set_reference(Reference::from_frames(&[v0]).unwrap())
        .unwrap();
}

/// Magnitudes without their sign under a protocol whose values change sign around the sheet
/// (PP-PP) are refused as that, either sign; ADC counts about a mid-scale as the model's
/// frame plus a common level, named; the signed frame is taken. (Its magnitudes were imaged:
/// no object where the bump was.)
#[test]
fn a_reference_of_magnitudes_is_refused() {
    let sheet = Sheet::disc(0.1, 16);
    let protocol =
        et_core::protocol::Protocol::new(et_core::protocol::ProtocolKind::PpPp, 16).unwrap();
    let schedule = et_core::schedule::Schedule::of_protocol(&protocol, 1e-3).unwrap();
    let mut recon = Spec {
        mesh: MeshPlan::About {
            triangles: 900,
            refine: Vec::new(),
        },
        ..Spec::new(sheet, schedule)
    }
    .set_up()
    .unwrap();
    let v0 = bump_frame(&recon, 0.0);
    for sign in [1.0f32, -1.0] {
        let magnitudes: Vec<f32> = v0.iter().map(|v| sign * v.abs()).collect();
        let e = recon
            .set_reference(Reference::from_frames(&[magnitudes]).unwrap())
            .unwrap_err();
        assert!(matches!(e, ImagingError::ReferenceNotSigned(_)), "{e:?}");
        let said = e.to_string();
        let has = if sign > 0.0 { "positive" } else { "negative" };
        assert!(
            said.contains(&format!("every value {has} or zero"))
                && said.contains("magnitudes without their sign"),
            "{said}"
        );
    }
    // ADC counts about a mid-scale (the frame at a gain plus 2048, every value positive): the
    // model's frame plus a common level, said as that (it was said as magnitudes, or under the
    // adjacent protocol as a polarity swapped).
    let largest = v0.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let counts: Vec<f32> = v0.iter().map(|v| 2048.0 + v / largest * 1000.0).collect();
    assert!(counts.iter().all(|c| *c > 0.0));
    let e = recon
        .set_reference(Reference::from_frames(&[counts]).unwrap())
        .unwrap_err();
    let level = match e {
        ImagingError::ReferenceNotSigned(et_recon::background::NotSigned::Offset {
            level,
            with,
            ..
        }) => {
            assert!(with < 1e-4, "{with}");
            level
        }
        other => panic!("{other}"),
    };
    assert!((level - 2048.0).abs() < 0.1, "{level}");
    recon
        .set_reference(Reference::from_frames(&[v0]).unwrap())
        .unwrap();
}

/// A set-up asked to stop ends at its next stage (Python's Ctrl-C ran it to its end in the
/// background): stopped at the n-th of its three asks (after the mesh, the forward model,
/// the Jacobian), it asks no more and returns `Stopped`; never stopped, it asks three times.
#[test]
fn a_set_up_asked_to_stop_ends_at_its_next_stage() {
    let spec = || {
        let sheet = Sheet::disc(0.1, 16);
        let protocol =
            et_core::protocol::Protocol::new(et_core::protocol::ProtocolKind::Adjacent, 16)
                .unwrap();
        let schedule = et_core::schedule::Schedule::of_protocol(&protocol, 1e-3).unwrap();
        Spec {
            mesh: MeshPlan::About {
                triangles: 600,
                refine: Vec::new(),
            },
            ..Spec::new(sheet, schedule)
        }
    };
    for at in 1..=3 {
        let asked = std::cell::Cell::new(0);
        let stop = || {
            asked.set(asked.get() + 1);
            asked.get() >= at
        };
        let e = spec().set_up_until(&stop).unwrap_err();
        assert!(matches!(e, ImagingError::Stopped), "{e}");
        assert_eq!(asked.get(), at, "asked again after it said stop");
    }
    let asked = std::cell::Cell::new(0);
    let never = || {
        asked.set(asked.get() + 1);
        false
    };
    assert!(spec().set_up_until(&never).is_ok());
    assert_eq!(asked.get(), 3);
}

/// What the model of the untouched sheet leaves of a reference unexplained
/// (`Reconstructor::unexplained`): nothing of its own frame at any scale; |e| / |m + e| of
/// its frame m plus a part e no scale of m makes (the identity sqrt(1 - r^2)); the background
/// fit's own residual once fitted to a reference of a bump; and more than `POOR_FIT` of the
/// frame of another protocol of the same K (opposite's under pseudo-polar, 192 values each),
/// which `et reconstruct`, `et stream`, `et view` and Python warn of.
#[test]
fn what_the_model_leaves_of_a_reference_unexplained() {
    use et_core::protocol::{Protocol, ProtocolKind};
    use et_recon::background::{POOR_FIT, poor_fit_said};
    let spec = |kind| {
        let protocol = Protocol::new(kind, 16).unwrap();
        let schedule = et_core::schedule::Schedule::of_protocol(&protocol, 1e-3).unwrap();
        Spec {
            mesh: MeshPlan::About {
                triangles: 900,
                refine: Vec::new(),
            },
            ..Spec::new(Sheet::disc(0.1, 16), schedule)
        }
    };
    let opposite = spec(ProtocolKind::Opposite).set_up().unwrap();
    let m: Vec<f64> = bump_frame(&opposite, 0.0)
        .iter()
        .map(|&v| f64::from(v))
        .collect();
    for scale in [1e-3, 1.0, 250.0] {
        let scaled: Vec<f64> = m.iter().map(|v| v * scale).collect();
        assert!(opposite.unexplained(&scaled) < 1e-3, "{scale}");
    }
    // e: a pattern with m's part taken out.
    let mm: f64 = m.iter().map(|v| v * v).sum();
    let rms = (mm / m.len() as f64).sqrt();
    let w: Vec<f64> = (0..m.len())
        .map(|k| (k as f64 * 0.7).sin() * 0.1 * rms)
        .collect();
    let wm: f64 = w.iter().zip(&m).map(|(a, b)| a * b).sum();
    let e: Vec<f64> = w.iter().zip(&m).map(|(a, b)| a - wm / mm * b).collect();
    let ee: f64 = e.iter().map(|v| v * v).sum();
    let v0: Vec<f64> = m.iter().zip(&e).map(|(a, b)| a + b).collect();
    let expected = (ee / (mm + ee)).sqrt();
    let got = opposite.unexplained(&v0);
    assert!(
        expected > 0.01 && (got - expected).abs() < 1e-3 * expected,
        "{got} {expected}"
    );

    let bumped: Vec<f64> = bump_frame(&opposite, 1.0)
        .iter()
        .map(|&v| f64::from(v))
        .collect();
    let (fitted, fit) = spec(ProtocolKind::Opposite)
        .set_up_fitted(&bumped, Weighting::Alike)
        .unwrap();
    assert!(fit.residual > 1e-4, "{}", fit.residual);
    let got = fitted.unexplained(&bumped);
    assert!(
        (got - fit.residual).abs() < 0.05 * fit.residual,
        "{got} {}",
        fit.residual
    );
    assert_eq!(poor_fit_said(fit.residual), None);

    let pseudo_polar = spec(ProtocolKind::PseudoPolar).set_up().unwrap();
    let other = pseudo_polar.unexplained(&m);
    let said = poor_fit_said(other).unwrap();
    assert!(
        other > POOR_FIT && said.contains("the protocol's order"),
        "{other}: {said}"
    );
}

/// Reference frames that differ as a change of the sheet does (a touch while the reference
/// was taken) are told from frames that differ by noise alone: the mean square of each
/// frame's difference from their mean over that of its part no conductivity change can make
/// is about 1 for noise and far above for a bump in some of them, said past
/// `REFERENCE_CHANGE_SAID`.
#[test]
fn a_reference_taken_while_touched_is_told_from_noise() {
    use et_recon::background::{REFERENCE_CHANGE_SAID, reference_changes_said};
    let (recon, v0, bumps) = disc_and_bump(AlphaRule::Gcv, &[0.3]);
    let bump = &bumps[0];
    let largest = v0.iter().fold(0.0f32, |m, v| m.max(v.abs()));
    let mut rng = et_core::rng::Rng::new(11);
    let mut noisy = |v: &[f32]| -> Vec<f32> {
        v.iter()
            .map(|x| x + (1e-4 * f64::from(largest) * rng.normal()) as f32)
            .collect()
    };
    let untouched: Vec<Vec<f32>> = (0..20).map(|_| noisy(&v0)).collect();
    let fewer = Some((|n| format!("--reference {n}")) as fn(usize) -> String);
    let changes = recon.reference_changes(&untouched).unwrap();
    assert!(changes.ratio < 3.0, "{changes:?}");
    assert_eq!(changes.first_unlike, None);
    assert_eq!(reference_changes_said(changes, fewer), None);
    // Said only where a frame differs from their mean past the bound (as before the first to
    // differ was named): a step within it says nothing.
    let within = et_recon::ReferenceChanges {
        frame: 0,
        ratio: REFERENCE_CHANGE_SAID,
        first_unlike: Some((3, 2.0 * REFERENCE_CHANGE_SAID)),
    };
    assert_eq!(reference_changes_said(within, fewer), None);
    // The first five pressed.
    let touched: Vec<Vec<f32>> = (0..20)
        .map(|i| noisy(if i < 5 { bump } else { &v0 }))
        .collect();
    let changes = recon.reference_changes(&touched).unwrap();
    assert!(
        changes.frame < 5 && changes.ratio > 10.0 * REFERENCE_CHANGE_SAID,
        "{changes:?}"
    );
    let said = reference_changes_said(changes, None).unwrap();
    assert!(
        said.contains("was the sheet touched, or drifting") && !said.contains("--reference"),
        "{said}"
    );
    // Pressed from frame `from` on (an untouched frame, then a file's touches; a press
    // while the reference is taken): the frame where it began is named, with the count
    // of frames before it to take alone.
    for from in [1, 12] {
        let pressed: Vec<Vec<f32>> = (0..20)
            .map(|i| noisy(if i < from { &v0 } else { bump }))
            .collect();
        let changes = recon.reference_changes(&pressed).unwrap();
        let (first, ratio) = changes.first_unlike.unwrap();
        assert!(
            first == from && ratio > 10.0 * REFERENCE_CHANGE_SAID,
            "{from}: {changes:?}"
        );
        let said = reference_changes_said(changes, fewer).unwrap();
        assert!(
            said.contains(&format!("frame {from} (from 0) is the first to differ"))
                && said.contains(&format!("alone (--reference {from})")),
            "{said}"
        );
    }
    assert_eq!(recon.reference_changes(&untouched[..1]), None);
}
