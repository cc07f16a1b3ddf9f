use et_core::Micros;
use et_core::ScanConfig;
use et_core::scan::ScanReport;
use et_core::wire::Frame;
use et_host::recording::*;

fn frame(seq: u32, k: usize) -> Frame {
    let v: Vec<f32> = (0..k).map(|i| i as f32 * 1e-3 + seq as f32).collect();
    Frame::from_scan(
        seq,
        Micros(seq * 12_800),
        ScanConfig::REFERENCE,
        &ScanReport::default(),
        0,
        &v,
    )
    .unwrap()
}

/// A board that restarted mid-recording (seq from 0 again), or two recordings joined, is
/// said; a clock that wraps its 32 bits is not going back.
#[test]
fn frames_out_of_order_are_noted() {
    let header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    let recording = |stamps: &[(u32, u32)]| Recording {
        header: header.clone(),
        records: stamps
            .iter()
            .map(|&(seq, t_us)| Record {
                seq,
                t_us,
                flags: 0,
                rail_count: 0,
                voltages: vec![0.0; 208],
                invalid: Vec::new(),
                touches: None,
            })
            .collect(),
        truncated_tail: false,
    };
    let wraps = recording(&[(7, u32::MAX - 100), (8, 12_700), (9, 25_500)]);
    assert_eq!(wraps.order_note(), None);
    let restarted = recording(&[(0, 0), (1, 12_800), (0, 5), (1, 12_805)]);
    let note = restarted.order_note().unwrap();
    assert!(
        note.contains("repeats 1 time(s)") && note.contains("goes back 1 time(s)"),
        "{note}"
    );
    assert!(
        note.contains("frame 2 of the file (seq 1 then 0)"),
        "{note}"
    );
    let repeated = recording(&[(0, 0), (1, 12_800), (1, 12_800)]);
    assert!(repeated.order_note().unwrap().contains("repeats 1 time(s)"));
}

#[test]
fn round_trip_and_a_cut_tail_loses_only_the_last_frame() {
    let dir = std::env::temp_dir().join(format!("et-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("a.jsonl");
    let header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    assert_eq!((header.frame_len, header.columns.len()), (208, 208));
    let mut w = Writer::create(&path, &header).unwrap();
    let touches = Some(vec![TouchRecord {
        x: 0.01,
        y: -0.02,
        radius: 0.0075,
        pressure: 2e4,
    }]);
    for seq in 0..5 {
        w.append(&Record::new(&frame(seq, 208), touches.clone()))
            .unwrap();
    }
    assert!(
        w.append(&Record::new(&frame(9, 10), None)).is_err(),
        "wrong K refused"
    );
    drop(w);
    // The header says what the numbers are in.
    let first = std::fs::read_to_string(&path).unwrap();
    let first: serde_json::Value = serde_json::from_str(first.lines().next().unwrap()).unwrap();
    assert!(
        first["units"].as_str().unwrap().starts_with("SI"),
        "{first}"
    );
    let rec = read(&path).unwrap();
    assert_eq!(rec.header, header);
    // A header written before `units` existed reads as the same.
    let mut old = serde_json::to_value(&header).unwrap();
    old.as_object_mut().unwrap().remove("units");
    let old: Header = serde_json::from_value(old).unwrap();
    assert_eq!(old, header);
    assert_eq!(rec.records.len(), 5);
    assert_eq!(rec.records[3].voltages, frame(3, 208).voltages.to_vec());
    assert_eq!(rec.records[0].touches, touches);
    assert!(!rec.truncated_tail);
    // A crash mid-line: everything before it survives.
    let mut bytes = std::fs::read(&path).unwrap();
    bytes.truncate(bytes.len() - 40);
    std::fs::write(&path, &bytes).unwrap();
    let cut = read(&path).unwrap();
    assert_eq!(cut.records.len(), 4);
    assert!(cut.truncated_tail);
    // And readers say so (et reconstruct --frames, et stream --replay print the notes).
    assert!(rec.notes().is_empty());
    assert!(
        cut.notes()
            .first()
            .is_some_and(|n| n.contains("cut short") && n.contains("4 whole frames read")),
        "{:?}",
        cut.notes()
    );
    // Damage elsewhere is an error naming the line, the field and the value: a number past
    // its field's type is said with the range, not as serde's "expected u32" (and the field
    // was not named: "256 is out of range: 0 to 255" of which?).
    let original = std::fs::read_to_string(&path).unwrap();
    for (field, value, line, said) in [
        (
            "seq",
            "\"x\"",
            3,
            "seq: \"x\" is text, where a whole number belongs",
        ),
        ("seq", "-1", 3, "seq: -1 is out of range: 0 to 4294967295"),
        ("flags", "256", 2, "flags: 256 is out of range: 0 to 255"),
    ] {
        let was = format!("\"{field}\":{}", if field == "seq" { "1" } else { "0" });
        assert!(original.contains(&was), "{was}");
        let text = original.replacen(&was, &format!("\"{field}\":{value}"), 1);
        std::fs::write(&path, text).unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(err.contains(&format!("a.jsonl:{line}: {said}")), "{err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A NaN or infinite value from the board used to be written as `null` and then refused
/// the whole recording (here and in Python). It is kept: NaN, flagged in `invalid`.
#[test]
fn a_frame_with_nan_or_inf_stays_readable_and_flagged() {
    let dir = std::env::temp_dir().join(format!("et-rec-nan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("nan.jsonl");
    let header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    let mut w = Writer::create(&path, &header).unwrap();
    let mut bad = frame(1, 208);
    bad.voltages[3] = f32::NAN;
    bad.voltages[7] = f32::INFINITY;
    // The last one flagged by the board (a reading on a rail, its source in compliance).
    let mut railed = frame(2, 208);
    railed.flags = et_core::wire::FLAG_RAIL | et_core::wire::FLAG_COMPLIANCE;
    for f in [frame(0, 208), bad, railed] {
        w.append(&Record::new(&f, None)).unwrap();
    }
    drop(w);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.contains("null") && text.contains("\"invalid\":[3,7]"),
        "{text}"
    );
    let rec = read(&path).unwrap();
    assert_eq!(rec.records.len(), 3);
    let r = &rec.records[1];
    assert!(r.voltages[3].is_nan() && r.voltages[7].is_nan());
    assert_eq!(r.voltages[4], frame(1, 208).voltages[4]);
    assert_eq!(r.invalid, vec![3, 7]);
    assert!(rec.records[0].invalid.is_empty() && rec.records[2].invalid.is_empty());
    // The standard-library Python reader reads it too (NaN for null).
    let py = std::process::Command::new("python3")
        .arg(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../python/et_recording.py"
        ))
        .arg(&path)
        .output()
        .expect("python3");
    let out = String::from_utf8_lossy(&py.stdout);
    assert!(
        py.status.success(),
        "{out}{}",
        String::from_utf8_lossy(&py.stderr)
    );
    for said in [
        "frames 3",
        "invalid_frames 1",
        "rail_frames 1",
        "compliance_frames 1",
    ] {
        assert!(out.contains(said), "{said}: {out}");
    }
    // Written by Python's json, a NaN is the token NaN, which JSON has not: said as that, by
    // its place (it was "expected value (column 60)").
    let python = dir.join("python.jsonl");
    std::fs::write(&python, text.replacen("null", "NaN", 1)).unwrap();
    let e = read(&python).unwrap_err().to_string();
    assert!(
        e.contains("python.jsonl:3: NaN at column ")
            && e.contains("not JSON, which has no NaN or infinity")
            && e.contains("written null"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Columns in another order than the protocol's are refused by the first that differs
/// (they were ignored: the same frames with the columns reversed gave the same image).
#[test]
fn columns_in_another_order_than_the_protocols_are_refused() {
    let dir = std::env::temp_dir().join(format!("et-rec-cols-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("c.jsonl");
    let mut header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    header.columns.reverse();
    let mut text = serde_json::to_string(&header).unwrap();
    text.push('\n');
    text.push_str(&serde_json::to_string(&Record::new(&frame(0, 208), None)).unwrap());
    text.push('\n');
    std::fs::write(&path, &text).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("c.jsonl:1") && err.contains("header column 0") && err.contains("order"),
        "{err}"
    );
    header.columns.pop();
    let mut text = serde_json::to_string(&header).unwrap();
    text.push('\n');
    std::fs::write(&path, &text).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(err.contains("207 columns"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A header whose K disagrees with its own protocol (frames of 100 values under an
/// adjacent 16-electrode config, K = 208) is refused at line 1; `et reconstruct` used to
/// take K from the config and panic on the frames.
#[test]
fn a_header_that_contradicts_its_protocol_is_refused() {
    let dir = std::env::temp_dir().join(format!("et-rec-k-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("k.jsonl");
    let mut header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    header.frame_len = 100;
    header.columns.truncate(100);
    let mut text = serde_json::to_string(&header).unwrap();
    text.push('\n');
    text.push_str(&serde_json::to_string(&Record::new(&frame(0, 100), None)).unwrap());
    text.push('\n');
    std::fs::write(&path, text).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("k.jsonl:1") && err.contains("K = 208"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Files that are not et recordings, or lines that are not its records, are said as such,
/// by the field's name, without serde's "at line 1 column 9" (the place in one line of
/// JSON nobody wrote by hand).
#[test]
fn what_is_not_a_recording_is_said_so() {
    let dir = std::env::temp_dir().join(format!("et-rec-not-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("r.jsonl");
    // Another system's CSV given a recording's name.
    std::fs::write(&path, "v0,v1\n1,2\n").unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("r.jsonl:1") && err.contains("not an et recording") && err.contains(".csv"),
        "{err}"
    );
    assert!(!err.contains("at line"), "{err}");
    // Another tool's JSON, without a "format": said as not et's ("header: missing field
    // `format`" was all it said).
    for json in ["{\"a\": 1}", "[1, 2, 3]"] {
        std::fs::write(&path, format!("{json}\n")).unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(
            err.contains("r.jsonl:1: not an et recording: its first line is JSON without et's")
                && !err.contains("missing field"),
            "{err}"
        );
    }
    // et's header written without its "format" (by hand, from Python): asked for the field.
    let header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    let mut value = serde_json::to_value(&header).unwrap();
    value.as_object_mut().unwrap().remove("format");
    std::fs::write(&path, format!("{value}\n")).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("r.jsonl:1: header: missing field `format`: \"et-recording\""),
        "{err}"
    );
    // Another of et's files: said as what it is (a dataset was "its first line is not JSON").
    for (text, said) in [
        (
            "# et-dataset 2\nf0,label\n1,0\n",
            "r.jsonl:1: an et dataset (et collect), not a recording: give it as --data",
        ),
        (
            "source,sink,positive,negative\n0,1,2,3\n",
            "r.jsonl:1: a protocol file (et protocol --csv), not a recording",
        ),
    ] {
        std::fs::write(&path, text).unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(err.contains(said), "{err}");
    }
    // Another JSON format: said by its format before its fields are asked for.
    std::fs::write(&path, "{\"format\":\"et-model\",\"version\":2}\n").unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(err.contains("format 'et-model'"), "{err}");
    // A header with a field missing, a record with one missing: named, and no place in the
    // line.
    let header = Header::new("test", &ScanConfig::REFERENCE).unwrap();
    let mut value = serde_json::to_value(&header).unwrap();
    value.as_object_mut().unwrap().remove("config");
    std::fs::write(&path, format!("{value}\n")).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("missing field `config`: the board's scan settings")
            && !err.contains("at line"),
        "{err}"
    );
    // Left out deeper, said with what it is and its unit, by its place (a column's `source`
    // is an electrode, the header's a file's origin).
    for (pointer, field, said) in [
        (
            "/config",
            "gain",
            "config: missing field `gain`: the amplifier's gain",
        ),
        (
            "/config",
            "protocol",
            "config: missing field `protocol`: the protocol the board scans",
        ),
        (
            "/columns/3",
            "source",
            "columns[3]: missing field `source`: the electrode the current",
        ),
        (
            "",
            "source",
            "header: missing field `source`: where the frames come from",
        ),
    ] {
        let mut value = serde_json::to_value(&header).unwrap();
        let table = value.pointer_mut(pointer).unwrap().as_object_mut().unwrap();
        table.remove(field).unwrap();
        std::fs::write(&path, format!("{value}\n")).unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(err.contains(said), "{err}");
    }
    let mut text = serde_json::to_string(&header).unwrap();
    text.push_str("\n{\"seq\":1}\n{\"seq\":2}\n");
    std::fs::write(&path, text).unwrap();
    let err = read(&path).unwrap_err().to_string();
    assert!(
        err.contains("r.jsonl:2")
            && err.contains("missing field `t_us`: the frame's time on the board, microseconds")
            && !err.contains("column"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
