use et_host::frames::mat_v5;
use et_host::pairs::*;
use nalgebra::DMatrix;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("et-pairs-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The rows of a crossed protocol, electrodes from 0: (source, sink, positive, negative).
fn rows(c: &Crossed) -> Vec<[u16; 4]> {
    (c.schedule.rows().iter())
        .map(|r| [r.source, r.sink, r.positive, r.negative])
        .collect()
}

/// KIT4's protocol (its README): 16 electrodes counted from 1 clockwise, injections adjacent,
/// skip 1, 2, 3 and all against electrode 1 (79), each in mA; under each the 16 adjacent
/// differences U_m - U_(m+1), drive electrodes included. Built here from the description,
/// independently of the reader: (source, sink) from 0.
fn kit4_injections() -> Vec<[u16; 2]> {
    let mut drives = Vec::new();
    for skip in 0..4 {
        drives.extend((0..16).map(|k| [k, (k + skip + 1) % 16]));
    }
    drives.extend((1..16).map(|k| [k, 0]));
    drives
}

fn kit4_expected() -> Vec<[u16; 4]> {
    let mut rows = Vec::new();
    for [s, k] in kit4_injections() {
        rows.extend((0..16).map(|m| [s, k, m, (m + 1) % 16]));
    }
    rows
}

/// The tank archives' way: two lists of pairs counted from 1 under headers of their own
/// names, the currents in an unnamed unit. Crossed into the protocol the archive describes,
/// each of the 1 264 rows right; the unit asked for, then taken.
#[test]
fn kit4_pair_lists_are_crossed_as_its_frames_are_ordered() {
    let dir = tmp("kit4");
    let (inj, meas) = (
        dir.join("injection_pairs.csv"),
        dir.join("measurement_pairs.csv"),
    );
    let mut text =
        String::from("injection,source_electrode(+),sink_electrode(-),amplitude_file_units\n");
    for (i, [s, k]) in kit4_injections().iter().enumerate() {
        text += &format!("{},{},{},1.4142135623730951\n", i + 1, s + 1, k + 1);
    }
    std::fs::write(&inj, text).unwrap();
    let mut text = String::from("measurement,plus_electrode,minus_electrode\n");
    for m in 0..16 {
        text += &format!("{},{},{}\n", m + 1, m + 1, (m + 1) % 16 + 1);
    }
    std::fs::write(&meas, text).unwrap();
    let e = cross(&inj, &meas, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'amplitude_file_units'") && e.contains("--current-unit mA"),
        "{e}"
    );
    let mut crossing = Crossing {
        current_unit: Some(("mA".into(), 1e-3)),
        ..Crossing::default()
    };
    let c = cross(&inj, &meas, &crossing).unwrap();
    assert_eq!(rows(&c), kit4_expected());
    assert_eq!((c.base, c.schedule.electrodes()), (1, 16));
    assert!(
        c.schedule
            .rows()
            .iter()
            .all(|r| (r.current_a - std::f64::consts::SQRT_2 * 1e-3).abs() < 1e-15)
    );
    let said = c.said.join("\n");
    assert!(
        said.contains("from 1") && said.contains("K = 1264") && said.contains("base = 1"),
        "{said}"
    );
    // The file keeps the lists' numbering, and reads back as the same protocol with base = 1.
    let csv = c.to_csv();
    assert!(
        csv.starts_with("source,sink,positive,negative,current_a\n1,2,1,2,"),
        "{csv}"
    );
    let back =
        et_core::schedule::Schedule::parse_csv(Path::new("p.csv"), &csv, 16, 1, 1e-3).unwrap();
    assert_eq!(back, c.schedule);
    // EIDORS's no_meas_current: each injection's values on its own drive electrodes left out
    // (adjacent: 3 of 16 touch the pair; all-against-one: 4, or 3 where they neighbour).
    crossing.no_meas_current = true;
    let c = cross(&inj, &meas, &crossing).unwrap();
    let expected: Vec<[u16; 4]> = (kit4_expected().into_iter())
        .filter(|[s, k, p, n]| ![p, n].iter().any(|e| *e == s || *e == k))
        .collect();
    assert_eq!(rows(&c), expected);
    assert!(c.said.join(" ").contains("--no-meas-current"));
    // A list given as the other side, and a sheet smaller than the lists.
    let e = cross(&meas, &inj, &crossing).unwrap_err().to_string();
    assert!(e.contains("give it as --measurements"), "{e}");
    crossing.electrodes = Some(8);
    let e = cross(&inj, &meas, &crossing).unwrap_err().to_string();
    assert!(e.contains("electrode 9") && e.contains("-l"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The same protocol as matrices of patterns in a MATLAB file (KIT4's Injref, 16 x 79, and
/// Mpat, 16 x 16, a pattern a column): Mpat reads either way round, so it is asked, and
/// then read as told; a CSV of the injections a row (79 x 16) reads by its shape.
#[test]
fn patterns_by_rows_or_columns_from_matlab_or_csv() {
    let dir = tmp("patterns");
    let drives = kit4_injections();
    let mut injref = DMatrix::zeros(16, drives.len());
    for (i, [s, k]) in drives.iter().enumerate() {
        injref[(usize::from(*s), i)] = std::f64::consts::SQRT_2;
        injref[(usize::from(*k), i)] = -std::f64::consts::SQRT_2;
    }
    let mut mpat = DMatrix::zeros(16, 16);
    for m in 0..16 {
        mpat[(m, m)] = 1.0;
        mpat[((m + 1) % 16, m)] = -1.0;
    }
    let mat = dir.join("ref.mat");
    let file = [
        mat_v5("Injref", &injref),
        mat_v5("Mpat", &mpat)[128..].to_vec(),
    ]
    .concat();
    std::fs::write(&mat, file).unwrap();
    let (inj, meas) = (
        PathBuf::from(format!("{}:Injref", mat.display())),
        PathBuf::from(format!("{}:Mpat", mat.display())),
    );
    let mut crossing = Crossing {
        current_unit: Some(("mA".into(), 1e-3)),
        ..Crossing::default()
    };
    let e = cross(&inj, &meas, &crossing).unwrap_err().to_string();
    assert!(
        e.contains("16 x 16") && e.contains("--patterns columns"),
        "{e}"
    );
    crossing.by = Some(By::Columns);
    let c = cross(&inj, &meas, &crossing).unwrap();
    assert_eq!(rows(&c), kit4_expected());
    assert_eq!(c.base, 0);
    // By rows, Mpat's row e is U_e - U_(e-1), and Injref, whose rows are no patterns, is
    // still read by its columns.
    crossing.by = Some(By::Rows);
    let by_rows: Vec<[u16; 4]> = (kit4_expected().into_iter())
        .map(|[s, k, p, _]| [s, k, p, (p + 15) % 16])
        .collect();
    assert_eq!(rows(&cross(&inj, &meas, &crossing).unwrap()), by_rows);
    // A CSV of the injections a row (the archive's injections.csv), beside the Mpat asked.
    let csv = dir.join("injections.csv");
    let text: String = (injref.column_iter())
        .map(|c| c.iter().map(f64::to_string).collect::<Vec<_>>().join(",") + "\n")
        .collect();
    std::fs::write(&csv, text).unwrap();
    crossing.by = Some(By::Columns);
    assert_eq!(
        rows(&cross(&csv, &meas, &crossing).unwrap()),
        kit4_expected()
    );
    // Told a way round no file needed: said, not ignored.
    let pairs = dir.join("m.csv");
    std::fs::write(&pairs, "0,1\n1,2\n").unwrap();
    let e = cross(&csv, &pairs, &crossing).unwrap_err().to_string();
    assert!(e.contains("no file needed it"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// pyEIT's `ex_mat` saved (`np.savez("ex_mat.npz", ex_mat)`: source, sink from 0, no
/// currents) and a two-column list: counted from 0 (an electrode 0 is there), 1 mA unless
/// given; the electrodes the largest number's; bad patterns and currents said by place.
#[test]
fn pyeit_lists_units_and_faults_are_said() {
    let dir = tmp("pyeit");
    let mut w = et_learn::npz::Writer::new();
    let ex_mat = DMatrix::from_row_slice(4, 2, &[0.0, 4.0, 1.0, 5.0, 2.0, 6.0, 3.0, 7.0]);
    w.matrix("array", &ex_mat);
    // (An .npz of one array is read by its only array.)
    let npz = dir.join("ex_mat.npz");
    std::fs::write(&npz, w.finish().unwrap()).unwrap();
    let meas = dir.join("meas.txt");
    std::fs::write(&meas, "0 1\n1 2\n2 3\n3 4\n4 5\n5 6\n6 7\n7 0\n").unwrap();
    let c = cross(&npz, &meas, &Crossing::default()).unwrap();
    assert_eq!(
        (c.base, c.schedule.electrodes(), c.schedule.frame_len()),
        (0, 8, 32)
    );
    assert!(c.schedule.rows().iter().all(|r| r.current_a == 1e-3));
    assert!(c.said.join(" ").contains("1 mA"));
    assert_eq!(rows(&c)[9], [1, 5, 1, 2]);
    // Currents in a third column, in amperes by default: 1.414 A is said as mA's slip.
    let inj = dir.join("inj.csv");
    std::fs::write(&inj, "0,4,1.414\n1,5,1.414\n").unwrap();
    let e = cross(&inj, &meas, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("injection 1") && e.contains("--current-unit mA"),
        "{e}"
    );
    // Named in amperes, its unit given otherwise: refused, not chosen.
    std::fs::write(&inj, "source,sink,current_a\n0,4,1.4e-3\n").unwrap();
    let crossing = Crossing {
        current_unit: Some(("mA".into(), 1e-3)),
        ..Crossing::default()
    };
    let e = cross(&inj, &meas, &crossing).unwrap_err().to_string();
    assert!(e.contains("names its currents' unit A"), "{e}");
    // A current named by its unit alone (`I (mA)`) is read in it (it was ignored, every
    // injection driving 1 mA); a column read for nothing is said.
    std::fs::write(
        &inj,
        "\"I+\";\"I-\";\"I (mA)\";note\n0;4;1,414;a\n1;5;1,414;b\n",
    )
    .unwrap();
    let c = cross(&inj, &meas, &Crossing::default()).unwrap();
    assert!(
        c.schedule
            .rows()
            .iter()
            .all(|r| (r.current_a - 1.414e-3).abs() < 1e-12)
    );
    assert!(
        c.said[0].contains("its column 'note' ignored"),
        "{}",
        c.said[0]
    );
    // A current below 0 in a list (not a matrix of patterns) said as the list's, by its row.
    std::fs::write(&inj, "0,4,1e-3\n1,5,-1e-3\n").unwrap();
    let e = cross(&inj, &meas, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("row 1") && e.contains("swap the row's source and sink"),
        "{e}"
    );
    std::fs::write(&inj, "source,sink,current_a\n0,4,1.4e-3\n").unwrap();
    // A measurement pattern against ground, and one of two sizes.
    let m = dir.join("m.csv");
    std::fs::write(&m, "1,-1,0,0\n0,1,0,0\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("measurement pattern 2") && e.contains("ground"),
        "{e}"
    );
    std::fs::write(&m, "1,-1,0,0\n0,1,-2,0\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("not of one size"), "{e}");
    // A header naming neither side's columns, and an electrode that is not a number.
    std::fs::write(&m, "a_col,b_col\n0,1\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("m.csv:1") && e.contains("positive and negative"),
        "{e}"
    );
    std::fs::write(&m, "plus,minus\n0,1\n1,x\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("m.csv:3") && e.contains("'x'"), "{e}");
    // A pair of one electrode, said by the file's numbering; a list under a header of other
    // names refused (a row's number would have been its first electrode), where patterns
    // under one (pandas' `to_csv` of named columns, its index first) are read.
    std::fs::write(&m, "0,1\n2,2\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("measurement 2 is between electrode 2 and itself"),
        "{e}"
    );
    std::fs::write(&m, "idx,from,to\n0,0,1\n1,1,2\n").unwrap();
    let e = cross(&inj, &m, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("m.csv:1") && e.contains("idx, from, to"), "{e}");
    let named: String = (0..8).map(|e| format!(",e{e}")).collect();
    std::fs::write(
        &m,
        format!("{named}\n0,1,-1,0,0,0,0,0,0\n1,0,1,-1,0,0,0,0,0\n"),
    )
    .unwrap();
    let c = cross(&inj, &m, &Crossing::default()).unwrap();
    assert_eq!(rows(&c)[..2], [[0, 4, 0, 1], [0, 4, 1, 2]]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Units of current as files write them; other words are none.
#[test]
fn units_of_current() {
    for (unit, per) in [
        ("A", 1.0),
        ("mA", 1e-3),
        ("(mA)", 1e-3),
        ("uA", 1e-6),
        ("µA", 1e-6),
        ("nA", 1e-9),
        ("amperes", 1.0),
        ("milliamps", 1e-3),
    ] {
        assert_eq!(amperes_per(unit), Some(per), "{unit}");
    }
    for unit in ["V", "units", "MA", "counts", ""] {
        assert_eq!(amperes_per(unit), None, "{unit}");
    }
}
