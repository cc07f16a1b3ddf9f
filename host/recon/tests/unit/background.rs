use et_core::schedule::Row;
use et_core::schedule::Schedule;
use et_core::sheet::Sheet;
use et_recon::background::*;
use et_recon::fem::{Electrodes, Forward};
use et_recon::mesh::Mesh;

/// A 28 cm tank of 8 electrodes, all against electrode 0 and adjacent, every pair
/// measured (the drive electrodes' too).
fn tank() -> (Sheet, Mesh, Schedule) {
    let mut sheet = Sheet::disc(0.14, 8);
    sheet.electrodes.width = 0.025;
    let mesh = Mesh::with_about(&sheet, 1_500).unwrap();
    let mut rows = Vec::new();
    for (source, sink) in (1..8)
        .map(|e| (e, 0))
        .chain((0..8).map(|e| (e, (e + 1) % 8)))
    {
        for m in 0..8 {
            rows.push(Row {
                source,
                sink,
                positive: m,
                negative: (m + 1) % 8,
                current_a: 1e-3,
            });
        }
    }
    (sheet, mesh, Schedule::new(8, rows).unwrap())
}

/// The model's own frame at (R_s, z_c) is fitted back to them, from a guess far off; with
/// the scaling identity V(R_s, z_c) = R_s F(z_c / R_s) checked on the way.
#[test]
fn the_models_own_frame_is_fitted_back() {
    let (mut sheet, mesh, schedule) = tank();
    let (rs, contact) = (230.0, 60.0);
    sheet.sheet_resistance = rs;
    sheet.electrodes.contact_ohm = contact;
    let forward = Forward::new(mesh.clone(), Electrodes::of_sheet(&sheet).unwrap()).unwrap();
    let n = mesh.triangles.len();
    let v0 = forward.frame(&vec![1.0 / rs; n], &schedule).unwrap();
    let unit = UnitSheet::new(&sheet, &mesh, &schedule)
        .and_then(|mut u| u.frame(Some(contact / rs)))
        .unwrap();
    for (a, b) in v0.iter().zip(&unit) {
        assert!(
            (a - rs * b).abs() < 1e-9 * a.abs().max(1e-3),
            "{a} vs {}",
            rs * b
        );
    }
    let mut guess = sheet.clone();
    guess.sheet_resistance = 100.0;
    guess.electrodes.contact_ohm = 5.0;
    let fit = fit(&guess, &mesh, &schedule, &v0).unwrap();
    assert!(fit.contact_fitted);
    assert!((fit.sheet_resistance / rs - 1.0).abs() < 1e-3, "{fit:?}");
    assert!((fit.contact_ohm / contact - 1.0).abs() < 1e-2, "{fit:?}");
    assert!(fit.residual < 1e-4 && fit.scene_residual > 0.3, "{fit:?}");
}

/// Without measurements on drive electrodes the contact is kept at the guess's ratio and
/// R_s still fitted; a frame of the other sign is refused with the likely causes.
#[test]
fn contact_only_where_the_frame_shows_it_and_a_reversed_frame_refused() {
    let (mut sheet, mesh, schedule) = tank();
    let off_drive: Vec<Row> = schedule
        .rows()
        .iter()
        .copied()
        .filter(|r| r.on_drive().is_none())
        .collect();
    let off_drive = Schedule::new(8, off_drive).unwrap();
    sheet.sheet_resistance = 150.0;
    let forward = Forward::new(mesh.clone(), Electrodes::of_sheet(&sheet).unwrap()).unwrap();
    let n = mesh.triangles.len();
    let v0 = forward.frame(&vec![1.0 / 150.0; n], &off_drive).unwrap();
    let mut guess = sheet.clone();
    guess.sheet_resistance = 300.0;
    let fit = fit(&guess, &mesh, &off_drive, &v0).unwrap();
    assert!(!fit.contact_fitted);
    assert!((fit.sheet_resistance / 150.0 - 1.0).abs() < 0.05, "{fit:?}");
    let reversed: Vec<f64> = v0.iter().map(|v| -v).collect();
    let e = et_recon::background::fit(&guess, &mesh, &off_drive, &reversed).unwrap_err();
    assert!(matches!(e, BackgroundError::Sign { .. }), "{e}");
    assert!(e.to_string().contains("direction"), "{e}");
    // (Its values are of both signs: magnitudes are not this frame, and are not asked about.)
    assert!(!e.to_string().contains("magnitudes"), "{e}");
    // Magnitudes without their sign (some systems write them; this protocol's values change
    // sign around the tank) are said as that, not as a polarity swapped.
    let negative = v0.iter().filter(|v| **v < 0.0).count();
    assert!(
        (v0.len()..=9 * v0.len()).contains(&(10 * negative)),
        "{negative} of {} negative",
        v0.len()
    );
    let magnitudes: Vec<f64> = v0.iter().map(|v| v.abs()).collect();
    let e = et_recon::background::fit(&guess, &mesh, &off_drive, &magnitudes).unwrap_err();
    assert!(
        matches!(
            e,
            BackgroundError::NotSigned(NotSigned::Magnitudes { sign: 1, .. })
        ),
        "{e}"
    );
    assert!(
        e.to_string().contains("magnitudes without their sign"),
        "{e}"
    );
    assert!(et_recon::background::fit(&guess, &mesh, &off_drive, &v0[1..]).is_err());
    assert!(et_recon::background::fit(&guess, &mesh, &off_drive, &vec![0.0; v0.len()]).is_err());
}

/// A frame of one value is said as it was written: frames are read in single precision, so
/// 0.01 arrives as 0.009999999776482582, which the message printed.
#[test]
fn a_frame_of_one_value_says_the_value_as_written() {
    for (value, said) in [
        (f64::from(0.01_f32), "is 0.01 in every entry"),
        (0.01, "is 0.01 in every entry"),
        (0.0, "is 0 in every entry"),
        (-0.0, "is 0 in every entry"),
        (1e-7, "is 0.0000001 in every entry"),
        (0.1 + 0.2, "is 0.30000000000000004 in every entry"),
    ] {
        let text = not_measured_said(value);
        assert!(text.contains(said), "{value}: {text}");
    }
}

/// The model's own frame with electrode 3's values off by a gain g (a contact that reads a
/// share of its potential): the rest is the model's exactly at scale 1, so `rest` is 0 (to the
/// sums' rounding, 1e-8 of the frame) and `own` is |g|, electrode 3 the worst; it stands out
/// from half its size on, and is named as the user counts (from 1 with base = 1). The model's
/// frame as it is leaves nothing; one reading far off names no electrode, two of one
/// electrode's name it.
#[test]
fn an_electrode_off_the_model_is_the_worst_by_its_own_share() {
    let (sheet, mesh, schedule) = tank();
    let forward = Forward::new(mesh.clone(), Electrodes::of_sheet(&sheet).unwrap()).unwrap();
    let n = mesh.triangles.len();
    let model = forward.frame(&vec![1e-3; n], &schedule).unwrap();
    let of = |r: &Row, e: u16| [r.source, r.sink, r.positive, r.negative].contains(&e);
    let values = schedule.rows().iter().filter(|r| of(r, 3)).count();
    for (gain, stands_out) in [
        (-0.3, false),
        (-0.45, false),
        (-0.6, true),
        (-1.0, true),
        (2.0, true),
    ] {
        let v0: Vec<f64> = (schedule.rows().iter().zip(&model))
            .map(|(r, m)| if of(r, 3) { m * (1.0 + gain) } else { *m })
            .collect();
        let worst = electrode_misfit(schedule.rows(), 8, &v0, &model).unwrap();
        assert_eq!(worst.electrode, 3, "{gain}: {worst:?}");
        assert_eq!(worst.values, values);
        assert!(worst.rest < 1e-6, "{gain}: {worst:?}");
        assert!(
            (worst.own - f64::abs(gain)).abs() < 1e-9,
            "{gain}: {worst:?}"
        );
        assert_eq!(worst.stands_out(), stands_out, "{gain}: {worst:?}");
        if stands_out {
            assert!(worst.said(1).unwrap().starts_with("electrode 4's"));
            assert!(worst.said(0).unwrap().starts_with("electrode 3's"));
        } else {
            assert_eq!(worst.said(0), None);
        }
    }
    let same = electrode_misfit(schedule.rows(), 8, &model, &model).unwrap();
    assert!(same.own < 1e-6 && !same.stands_out(), "{same:?}");
    // One reading far off (a rail: 20 times the largest value) is in four electrodes'
    // values and names none of them; two of one electrode's readings so far off name it.
    let largest = model.iter().fold(0.0f64, |a, m| a.max(m.abs()));
    let rows = schedule.rows();
    let mut glitch = model.clone();
    let k = (0..rows.len()).find(|&k| of(&rows[k], 3)).unwrap();
    glitch[k] = 20.0 * largest;
    let worst = electrode_misfit(rows, 8, &glitch, &model).unwrap();
    assert!(!worst.stands_out(), "{worst:?}");
    assert!(detached_electrodes(rows, 8, &glitch, &model).is_empty());
    // Another of electrode 3's readings, sharing no other electrode with the first.
    let shares = |j: usize| {
        let r = &rows[j];
        [r.source, r.sink, r.positive, r.negative]
            .iter()
            .any(|&e| e != 3 && of(&rows[k], e))
    };
    let other = (k + 1..rows.len())
        .find(|&j| of(&rows[j], 3) && !shares(j))
        .unwrap();
    glitch[other] = 20.0 * largest;
    let worst = electrode_misfit(rows, 8, &glitch, &model).unwrap();
    assert!(worst.electrode == 3 && worst.stands_out(), "{worst:?}");
}

/// Two electrodes read as detached (their values' sign flipped and doubled, as far off as
/// noise on a floating input is) on 16 electrodes: each raises the misfit of the rest against
/// which the other is weighed, so the worst electrode alone does not stand out, and
/// `detached_electrodes` names both; one alone is named alone; a frame far off everywhere (of
/// another protocol, say) names none, nor does the model's own frame.
#[test]
fn two_detached_electrodes_are_both_named_and_a_frame_off_everywhere_none() {
    use et_core::protocol::{Protocol, ProtocolKind};
    let sheet = Sheet::disc(0.1, 16);
    let mesh = Mesh::with_about(&sheet, 1_500).unwrap();
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let schedule = Schedule::of_protocol(&protocol, 1e-3).unwrap();
    let forward = Forward::new(mesh.clone(), Electrodes::of_sheet(&sheet).unwrap()).unwrap();
    let model = forward
        .frame(&vec![1e-3; mesh.triangles.len()], &schedule)
        .unwrap();
    let rows = schedule.rows();
    let off = |dead: &[u16]| -> Vec<f64> {
        (rows.iter().zip(&model))
            .map(|(r, m)| {
                let of = [r.source, r.sink, r.positive, r.negative]
                    .iter()
                    .any(|e| dead.contains(e));
                if of { -2.0 * m } else { *m }
            })
            .collect()
    };
    let named = |v0: &[f64]| -> Vec<u16> {
        detached_electrodes(rows, 16, v0, &model)
            .iter()
            .map(|m| m.electrode)
            .collect()
    };
    let two = off(&[3, 11]);
    assert!(
        !electrode_misfit(rows, 16, &two, &model)
            .unwrap()
            .stands_out()
    );
    assert_eq!(named(&two), [3, 11]);
    assert_eq!(named(&off(&[5])), [5]);
    assert_eq!(named(&model), Vec::<u16>::new());
    let everywhere: Vec<f64> = (model.iter().enumerate())
        .map(|(k, m)| m * (1.0 + 0.9 * (k as f64 * 1.7).sin()))
        .collect();
    assert_eq!(named(&everywhere), Vec::<u16>::new());
    let (said, numbers) = detached_said(&detached_electrodes(rows, 16, &two, &model), 1).unwrap();
    assert!(said.starts_with("electrodes 4, 12:"), "{said}");
    assert_eq!(numbers, "4,12");
}
