//! Sheet-level physics: what a touch does to the frame, the extremes, and the resolution trade.

use super::*;
use crate::touch::Footprint;
use et_core::protocol::ProtocolKind;
use std::time::Instant;

fn square(side: f64, l: u8, resolution: Option<f64>) -> SheetSpec {
    SheetSpec {
        resolution,
        ..SheetSpec::of(Sheet {
            shape: Shape::Rectangle {
                width: side,
                height: side,
            },
            sheet_resistance: SHEET_RESISTANCE,
            electrodes: ElectrodeSpec {
                count: l,
                width: side * 0.04,
                ..ElectrodeSpec::default()
            },
        })
    }
}

fn bvc(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn adjacent(l: u8) -> Protocol {
    Protocol::new(ProtocolKind::Adjacent, l).unwrap()
}

#[test]
fn touching_raises_conductance_and_bvc_grows_with_pressure() {
    let sheet = SimulatedSheet::new(&square(0.13, 16, Some(0.005)), &[]).unwrap();
    let (p, src) = (adjacent(16), Source::default());
    let v0 = frame(&sheet.transfer(&[]).unwrap(), &p, 32e-6, &src);
    let mut last = 0.0;
    for kpa in [2.0, 5.0, 10.0, 20.0, 50.0, 100.0] {
        let t = Touch {
            position: [0.01, -0.02],
            radius: 0.0075,
            pressure: kpa * 1e3,
            footprint: Default::default(),
        };
        let changes = edge_multipliers(
            &sheet.network().grid,
            &[Inclusion::of_touch(&t, &sheet.spec().piezo)],
        );
        assert!(
            changes.iter().all(|&(_, m)| m > 1.0),
            "a touch only raises conductance"
        );
        let v1 = frame(&sheet.transfer(&[t]).unwrap(), &p, 32e-6, &src);
        let b = bvc(&v1, &v0);
        assert!(b > last, "BVC at {kpa} kPa = {b} <= {last}");
        last = b;
    }
    // More conductance between the drive electrodes lowers the load the source sees.
    let t = Touch {
        position: [0.0, -0.06],
        radius: 0.0075,
        pressure: 50e3,
        footprint: Default::default(),
    };
    assert!(sheet.transfer(&[t]).unwrap().load(0, 1) <= sheet.transfer(&[]).unwrap().load(0, 1));
}

#[test]
fn bvc_shrinks_with_distance_from_the_electrodes() {
    let sheet = SimulatedSheet::new(&square(0.13, 16, Some(0.005)), &[]).unwrap();
    let (p, src) = (adjacent(16), Source::default());
    let v0 = frame(&sheet.transfer(&[]).unwrap(), &p, 32e-6, &src);
    let mut last = f64::INFINITY;
    // From 1 cm inside the bottom edge to the centre.
    for y in [-0.055, -0.045, -0.035, -0.025, -0.015, 0.0] {
        let t = Touch {
            position: [0.003, y],
            radius: 0.0075,
            pressure: 20e3,
            footprint: Default::default(),
        };
        let b = bvc(&frame(&sheet.transfer(&[t]).unwrap(), &p, 32e-6, &src), &v0);
        assert!(b < last, "BVC at y = {y}: {b} >= {last}");
        last = b;
    }
}

#[test]
fn extremes_give_finite_sane_frames() {
    let src = Source::default();
    // 4 and 32 electrodes.
    for l in [4u8, 32] {
        let mut spec = square(0.13, l, None);
        spec.physical.electrodes = ElectrodeSpec {
            count: l,
            width: 0.003,
            ..ElectrodeSpec::default()
        };
        let sheet = SimulatedSheet::new(&spec, &[]).unwrap();
        let v = frame(&sheet.transfer(&[]).unwrap(), &adjacent(l), 32e-6, &src);
        assert!(
            v.iter().all(|x| x.is_finite()) && v.iter().any(|x| x.abs() > 1e-4),
            "L = {l}"
        );
    }
    // Contrast 1e-3 .. 1e3.
    let sheet = SimulatedSheet::new(&square(0.13, 16, Some(0.005)), &[]).unwrap();
    let v0 = frame(&sheet.transfer(&[]).unwrap(), &adjacent(16), 32e-6, &src);
    for contrast in [1e-3, 1e-1, 10.0, 1e3] {
        let inc = Inclusion {
            position: [0.02, 0.02],
            radius: 0.01,
            multiplier: contrast,
            footprint: Default::default(),
        };
        let v = frame(
            &sheet.transfer_inclusions(&[inc]).unwrap(),
            &adjacent(16),
            32e-6,
            &src,
        );
        assert!(v.iter().all(|x| x.is_finite()));
        assert!(bvc(&v, &v0) > 1e-4, "contrast {contrast} is visible");
    }
    // Beyond 1e6 the touch is a perfect conductor: 1e15 gives what 1e6 gives (it
    // once gave a 13 V change, 500 times the ceiling), and 1e3 is already most of the way.
    let at = |contrast: f64| {
        let inc = Inclusion {
            position: [0.02, 0.02],
            radius: 0.01,
            multiplier: contrast,
            footprint: Default::default(),
        };
        frame(
            &sheet.transfer_inclusions(&[inc]).unwrap(),
            &adjacent(16),
            32e-6,
            &src,
        )
    };
    let (v3, v6, v15) = (at(1e3), at(1e6), at(1e15));
    for (a, b) in v15.iter().zip(&v6) {
        assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-3), "{a} vs {b}");
    }
    let change = |v: &[f64]| {
        v.iter()
            .zip(&v0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    assert!(change(&v3) <= change(&v6) * 1.001 && change(&v3) > 0.9 * change(&v6));
    // A palm (5 cm) is solved afresh, not by the low-rank update: the same as the oracle.
    let palm = Inclusion {
        position: [0.0, 0.0],
        radius: 0.05,
        multiplier: 3.0,
        footprint: Default::default(),
    };
    let changes = crate::touch::edge_multipliers(&sheet.network().grid, &[palm]);
    assert!(
        changes.len() > 2 * super::FAST_UPDATE_MAX_NODES,
        "{}",
        changes.len()
    );
    let mut g = sheet.network().conductances(None);
    for &(k, m) in &changes {
        g[k] *= m;
    }
    let oracle = sheet.network().solve(&g).unwrap().transfer;
    let got = sheet.transfer_inclusions(&[palm]).unwrap();
    for (a, b) in got.z.iter().zip(&oracle.z) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{a} vs {b}");
    }
    // Contact impedance 0 .. 1e6 ohm: finite; at 1 Mohm the source hits its compliance
    // (load > 16 V / 64 uA = 250 kohm) and the frame shrinks with the current, keeping its shape.
    let frames: Vec<Vec<f64>> = [0.0, 1e3, 1e6]
        .iter()
        .map(|&z| {
            let mut spec = square(0.13, 16, Some(0.005));
            spec.physical.electrodes.contact_ohm = z;
            let s = SimulatedSheet::new(&spec, &[]).unwrap();
            frame(&s.transfer(&[]).unwrap(), &adjacent(16), 32e-6, &src)
        })
        .collect();
    assert!(frames.iter().flatten().all(|x| x.is_finite()));
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let ratio = norm(&frames[2]) / norm(&frames[1]);
    assert!(
        ratio < 0.2,
        "compliance limits the current at 1 Mohm: ratio {ratio}"
    );
    // The frame's shape depends on the contact only through how the current spreads under the
    // drive electrodes.
    let scaled: Vec<f64> = frames[1].iter().map(|x| x * ratio).collect();
    assert!(
        bvc(&frames[2], &scaled) < 0.05 * norm(&scaled),
        "1 Mohm vs 1 kohm shape"
    );
    let contact_effect = bvc(&frames[0], &frames[1]) / norm(&frames[1]);
    println!(
        "0 ohm vs 1 kohm contacts: frames differ by {:.2} %",
        100.0 * contact_effect
    );
    // Measured 10.2 %: a perfect (0 ohm) electrode draws its current to its edges, the complete
    // electrode model's shunting effect, which moves the channels next to the drive.
    assert!(contact_effect < 0.15, "0 vs 1 kohm: {contact_effect}");
    // 1 uA: finite and exactly 1/32 of the 32 uA frame (no compliance).
    let small = frame(&sheet.transfer(&[]).unwrap(), &adjacent(16), 1e-6, &src);
    for (a, b) in small.iter().zip(&v0) {
        assert!((a * 32.0 - b).abs() <= 1e-12 * b.abs().max(1e-9));
    }
}

#[test]
fn sheets_from_1_cm_to_1_m_give_the_same_frame() {
    // 2-D conduction is scale-free: the same outline, electrodes and touch scaled together
    // read the same voltages (contact resistance kept negligible).
    let src = Source::default();
    let frames: Vec<Vec<f64>> = [0.01, 0.13, 1.0]
        .iter()
        .map(|&side| {
            let mut spec = square(side, 16, Some(side / 26.0));
            spec.physical.electrodes.contact_ohm = 0.0;
            let sheet = SimulatedSheet::new(&spec, &[]).unwrap();
            let inc = Inclusion {
                position: [0.1 * side, -0.2 * side],
                radius: 0.08 * side,
                multiplier: 3.0,
                footprint: Default::default(),
            };
            frame(
                &sheet.transfer_inclusions(&[inc]).unwrap(),
                &adjacent(16),
                10e-6,
                &src,
            )
        })
        .collect();
    for f in &frames[1..] {
        for (a, b) in f.iter().zip(&frames[0]) {
            assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-6), "{a} vs {b}");
        }
    }
}

/// Relative RMS difference of the touched frame (and of the touch's effect, dV) between
/// spacing h and h / 2, on the 13 x 13 cm, 16-electrode sheet.
fn refinement_error(h: f64) -> (f64, f64) {
    let touch = Touch {
        position: [0.021, -0.013],
        radius: 0.0075,
        pressure: 20e3,
        footprint: Default::default(),
    };
    let (p, src) = (adjacent(16), Source::default());
    let run = |h: f64| {
        let net = build_network(&square(0.13, 16, Some(h)), &[]).unwrap();
        let piezo = Piezo::default();
        let v0 = frame(
            &direct_transfer(&net, &piezo, &[]).unwrap(),
            &p,
            32e-6,
            &src,
        );
        let v1 = frame(
            &direct_transfer(&net, &piezo, &[touch]).unwrap(),
            &p,
            32e-6,
            &src,
        );
        (v0, v1)
    };
    let ((a0, a1), (b0, b1)) = (run(h), run(h / 2.0));
    let rel = |x: &[f64], y: &[f64]| bvc(x, y) / y.iter().map(|v| v * v).sum::<f64>().sqrt();
    let da: Vec<f64> = a1.iter().zip(&a0).map(|(x, y)| x - y).collect();
    let db: Vec<f64> = b1.iter().zip(&b0).map(|(x, y)| x - y).collect();
    (rel(&a1, &b1), rel(&da, &db))
}

#[test]
fn resolution_trade_at_the_default_spacing() {
    let spec = square(0.13, 16, None);
    let h = spec.default_resolution();
    let started = Instant::now();
    let sheet = SimulatedSheet::new(&spec, &[]).unwrap();
    let build = started.elapsed();
    let (frame_err, dv_err) = refinement_error(h);
    println!(
        "13 x 13 cm, L = 16, default spacing {:.2} mm ({} nodes, built in {:.2?}): frame differs from the \
         next finer network by {:.3} %, the touch's dV by {:.2} %",
        h * 1e3,
        sheet.network().grid.len(),
        build,
        100.0 * frame_err,
        100.0 * dv_err
    );
    // Measured 0.66 % and 1.2 % (see README); the bounds leave room for other machines' libm.
    assert!(
        frame_err < 0.02,
        "frame within 2 % of the finer network: {frame_err}"
    );
    assert!(
        dv_err < 0.03,
        "touch effect within 3 % of the finer network: {dv_err}"
    );
}

#[test]
fn a_bent_sheet_conducts_less_along_its_curve() {
    let flat = square(0.13, 16, Some(0.005));
    let bend = Bend {
        radius: 0.03,
        curves: Axis::X,
        thickness: 0.38e-3,
        gauge_factor: 3.0,
    };
    let bent = SheetSpec {
        bend: Some(bend),
        ..flat.clone()
    };
    let (p, src) = (adjacent(16), Source::default());
    let touch = Touch {
        position: [0.01, 0.02],
        radius: 0.0075,
        pressure: 20e3,
        footprint: Default::default(),
    };
    let sheet = SimulatedSheet::new(&bent, &[]).unwrap();
    let fast = frame(&sheet.transfer(&[touch]).unwrap(), &p, 32e-6, &src);
    let net = build_network(&bent, &[]).unwrap();
    let direct = frame(
        &direct_transfer(&net, &Piezo::default(), &[touch]).unwrap(),
        &p,
        32e-6,
        &src,
    );
    assert!(
        bvc(&fast, &direct) < 1e-9,
        "the fast path includes the bend"
    );
    let flat_frame = frame(
        &SimulatedSheet::new(&flat, &[])
            .unwrap()
            .transfer(&[touch])
            .unwrap(),
        &p,
        32e-6,
        &src,
    );
    let norm = flat_frame.iter().map(|v| v * v).sum::<f64>().sqrt();
    let change = bvc(&fast, &flat_frame) / norm;
    // Strain 0.38 mm / 6 cm = 0.63 %, gauge 3: x-resistors lose 1.9 % of their conductance.
    assert!(
        change > 1e-3 && change < 0.05,
        "bending changes the frame by {change}"
    );
    assert!((bend.multiplier() - 1.0 / 1.019).abs() < 1e-12);
    let bad = SheetSpec {
        bend: Some(Bend {
            radius: 1e-4,
            ..bend
        }),
        ..flat
    };
    assert!(matches!(
        bad.validate(),
        Err(SheetError::Spec(et_core::sheet::SheetError::Field {
            field: "sheet.bend",
            ..
        }))
    ));
}

#[test]
fn an_uneven_sheet_stays_reciprocal_and_a_flat_field_changes_nothing() {
    let spec = square(0.13, 16, Some(0.01));
    let (p, src) = (adjacent(16), Source::default());
    let flat = SimulatedSheet::uneven(&spec, &[], &Unevenness::default()).unwrap();
    let plain = SimulatedSheet::new(&spec, &[]).unwrap();
    let f0 = frame(&plain.transfer(&[]).unwrap(), &p, 32e-6, &src);
    assert_eq!(frame(&flat.transfer(&[]).unwrap(), &p, 32e-6, &src), f0);
    let mut rng = et_core::rng::Rng::new(4);
    let field = Unevenness::draw(0.05, &mut rng);
    let uneven = SimulatedSheet::uneven(&spec, &[], &field).unwrap();
    let z = uneven.transfer(&[]).unwrap();
    // Reciprocity: driving a-b and reading p-q equals driving p-q and reading a-b.
    for (a, b, q, r) in [(0, 1, 5, 6), (2, 3, 9, 10), (0, 8, 4, 12)] {
        let there = z.voltage(a, b, q, r, 1e-3);
        let back = z.voltage(q, r, a, b, 1e-3);
        assert!(
            (there - back).abs() < 1e-9 * there.abs().max(1e-12),
            "{there} vs {back}"
        );
    }
    let f1 = frame(&z, &p, 32e-6, &src);
    let change = bvc(&f1, &f0) / bvc(&f0, &vec![0.0; f0.len()]);
    assert!(
        change > 1e-3 && change < 0.2,
        "a 5 % field moves the frame by {change}"
    );
    let bad = Unevenness {
        coefficients: [f64::NAN; 8],
    };
    assert!(matches!(
        SimulatedSheet::uneven(&spec, &[], &bad),
        Err(SheetError::Spec(et_core::sheet::SheetError::Field { .. }))
    ));
}

/// An elliptic footprint: a half turn is the same ellipse, elongation 1 is the disc, the fast
/// update agrees with a direct solve, its orientation shows in the frame, and on the square
/// sheet an ellipse along x at the centre is the one along y seen after a quarter turn (the
/// electrodes relabelled by L / 4; the grid is symmetric, so to rounding).
#[test]
fn an_elliptic_touch_is_symmetric_where_the_ellipse_is() {
    let spec = square(0.13, 16, Some(0.0025));
    let sheet = SimulatedSheet::new(&spec, &[]).unwrap();
    let touch = |elongation: f64, angle: f64| Touch {
        position: [0.0, 0.0],
        radius: 0.01,
        pressure: 40e3,
        footprint: Footprint { elongation, angle },
    };
    let z = |t: Touch| sheet.transfer(&[t]).unwrap();
    // Every four-electrode voltage between neighbours (drive d, d + 1; measure m, m + 1),
    // with the electrodes relabelled by `shift`.
    let l = 16;
    let frame = |z: &crate::network::Transfer, shift: usize| -> Vec<f64> {
        let e = |i: usize| (i + shift) % l;
        (0..l * l)
            .map(|k| {
                let (d, m) = (k / l, k % l);
                z.voltage(e(d), e(d + 1), e(m), e(m + 1), 1.0)
            })
            .collect()
    };
    let diff = |a: &[f64], b: &[f64]| bvc(a, b) / a.iter().map(|v| v * v).sum::<f64>().sqrt();
    let (along_x, along_y) = (
        z(touch(2.0, 0.0)),
        z(touch(2.0, std::f64::consts::FRAC_PI_2)),
    );
    let (fx, fy) = (frame(&along_x, 0), frame(&along_y, 0));
    let disc = frame(&z(touch(1.0, 0.0)), 0);
    assert!(diff(&frame(&z(touch(2.0, std::f64::consts::PI)), 0), &fx) < 1e-12);
    assert!(diff(&frame(&z(touch(1.0, 0.7)), 0), &disc) < 1e-12);
    let untouched = frame(&sheet.transfer(&[]).unwrap(), 0);
    let (shape, touched) = (diff(&fx, &fy), diff(&disc, &untouched));
    assert!(
        shape > 0.05 * touched,
        "orientation {shape:.2e}, touch {touched:.2e}"
    );
    let net = build_network(&spec, &[]).unwrap();
    let direct = direct_transfer(&net, &spec.piezo, &[touch(2.0, 0.6)]).unwrap();
    assert!(diff(&frame(&direct, 0), &frame(&z(touch(2.0, 0.6)), 0)) < 1e-9);
    // Quarter turn: the y ellipse's sheet seen with electrode e relabelled e + L / 4.
    let (a, b) = (diff(&fx, &frame(&along_y, 4)), diff(&fx, &fy));
    assert!(
        a < 1e-9 * b.max(1e-3),
        "turned {a:.2e} against unturned {b:.2e}"
    );
}

/// A touch under half the grid spacing changes the edges whose midpoints it happens to reach,
/// so its frame depends on where it falls between the nodes (at a quarter spacing one place
/// changed nothing at all); from half the spacing up the change holds to a few tens of per
/// cent wherever it falls. The simulator refuses the smaller ones by name.
#[test]
fn a_touch_under_the_grid_is_refused_not_aliased() {
    let h = 0.005;
    let sheet = SimulatedSheet::new(&square(0.13, 16, Some(h)), &[]).unwrap();
    let (p, src) = (adjacent(16), Source::default());
    let v0 = frame(&sheet.transfer(&[]).unwrap(), &p, 32e-6, &src);
    // The change's size at three places a quarter spacing apart.
    let spread = |radius: f64| {
        let b: Vec<f64> = [0.0, 0.25, 0.5]
            .iter()
            .map(|shift| {
                let t = Touch {
                    position: [0.01 + shift * h, 0.0013],
                    radius,
                    pressure: 20e3,
                    footprint: Default::default(),
                };
                bvc(&frame(&sheet.transfer(&[t]).unwrap(), &p, 32e-6, &src), &v0)
            })
            .collect();
        let (lo, hi) = b
            .iter()
            .fold((f64::MAX, 0.0f64), |(l, u), x| (l.min(*x), u.max(*x)));
        println!("radius {radius}: changes {b:?}");
        hi / lo
    };
    let (under, at) = (spread(h / 4.0), spread(h / 2.0));
    assert!(under > 2.0, "a quarter-spacing touch: {under}");
    assert!(at < 2.0, "a half-spacing touch: {at}");
    assert!(sheet.spec().check_touch(0, h / 2.0).is_ok());
    let e = sheet
        .spec()
        .check_touch(3, h / 4.0)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("touch[3].radius: 0.00125 m is under half") && e.contains("at most 0.0025 m"),
        "{e}"
    );
}
