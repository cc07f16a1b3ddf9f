use std::path::Path;

use super::*;

fn parse(text: &str, electrodes: u16, base: u16) -> Result<Schedule, ScheduleError> {
    Schedule::parse_csv(Path::new("p.csv"), text, electrodes, base, 1e-3)
}

#[test]
fn a_built_in_protocol_is_its_steps_in_frame_order() {
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let s = Schedule::of_protocol(&protocol, 32e-6).unwrap();
    assert_eq!(s.frame_len(), protocol.frame_len());
    assert_eq!(s.kind(), Some(ProtocolKind::Adjacent));
    for (row, step) in s.rows().iter().zip(protocol.steps()) {
        assert_eq!(row.source, u16::from(step.injection.source.0));
        assert_eq!(row.negative, u16::from(step.measurement.negative.0));
    }
    // Adjacent drops the measurements on drive electrodes; 16 injections serve 208 rows.
    assert_eq!(s.first_on_drive(), None);
    let (injections, of_row) = s.injections();
    assert_eq!(injections.len(), 16);
    assert_eq!(of_row.len(), 208);
    // Written and read back, the same rows (the kind is the file's to forget).
    let back = parse(&s.to_csv(), 16, 0).unwrap();
    assert_eq!(back.rows(), s.rows());
    assert_eq!(back.kind(), None);
}

#[test]
fn files_as_other_systems_write_them() {
    // Headerless, 1-based, all-against-one with measurements on the drive electrodes.
    let s = parse("2 ;1 ;1 ;2\n3;1;2;3\n", 16, 1).unwrap();
    assert_eq!(s.rows()[1].source, 2);
    assert_eq!(s.rows()[1].current_a, 1e-3);
    assert_eq!(s.first_on_drive(), Some((0, 0)));
    // A header in another order, a current per row, other columns ignored.
    let s = parse(
        "# tank, 79 injections\nnegative,positive,current_a,sink,source,note\n1,0,1.4e-3,3,2,x\n",
        16,
        0,
    )
    .unwrap();
    let r = s.rows()[0];
    assert_eq!((r.source, r.sink, r.positive, r.negative), (2, 3, 0, 1));
    assert_eq!(r.current_a, 1.4e-3);
    // A column named as a current that is not current_a (in mA, or a tank's amplitudes) was
    // ignored, each row driving the default current: refused, naming it. Other columns whose
    // words only contain the letters (a sample, a timestamp) are still ignored.
    for header in [
        "current_ma",
        "Current (A)",
        "amplitude_file_units",
        "amps",
        "I_current",
    ] {
        let e = parse(
            &format!("source,sink,positive,negative,{header}\n0,1,2,3,1.4\n"),
            16,
            0,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains(&format!("the column '{header}' reads as a current"))
                && e.contains("current_a"),
            "{e}"
        );
    }
    let e = parse(
        "source,sink,positive,negative,current_a,current_ma\n0,1,2,3,1e-3,1\n",
        16,
        0,
    );
    assert!(e.is_err(), "two currents: which is meant would be a guess");
    let s = parse(
        "sample,timestamp,source,sink,positive,negative\n0,9,0,1,2,3\n",
        16,
        0,
    )
    .unwrap();
    assert_eq!(s.rows()[0].current_a, 1e-3);
    // Cells separated by ';' with decimal commas, as a spreadsheet in Europe writes them
    // (the frame readers took them; the protocol reader refused '0,0014').
    let s = parse(
        "source;sink;positive;negative;current_a\n2;3;0;1;0,0014\n",
        16,
        0,
    )
    .unwrap();
    assert_eq!(s.rows()[0].current_a, 1.4e-3);
    // A row's error names its line after a header, blank and '#' lines.
    let e = parse(
        "source,sink,positive,negative\n\n# note\n0,1,2,3\n0,0,2,3\n",
        16,
        0,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("p.csv:5"), "{e}");
}

#[test]
fn wrong_rows_are_named_by_line_and_cell() {
    // Another of et's files said as what it is (a recording's JSON header was echoed whole),
    // and a header of many other names cut short (a dataset's 200 feature names were said).
    let e = parse("{\"format\":\"et-recording\",\"version\":1}\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.csv:1: an et recording (et sim, et record), not a protocol file"),
        "{e}"
    );
    let names: Vec<String> = (0..200).map(|i| format!("f{i}")).collect();
    let e = parse(&format!("{}\n", names.join(",")), 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("the header names f0, f1, f2, f3, f4, f5, ... (200 columns): name the columns"),
        "{e}"
    );
    let e = parse("source,sink,positive,negative\n0,1,2,3\n0,1,2,16\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.csv:3") && e.contains("electrode 16") && e.contains("base = 1"),
        "{e}"
    );
    // A column named twice is refused, not guessed at (the first `source` was used).
    let e = parse("source,sink,positive,negative,Source\n0,1,2,3,5\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.csv:1") && e.contains("names source twice"),
        "{e}"
    );
    let e = parse("0,0,2,3\n", 16, 0).unwrap_err().to_string();
    assert!(
        e.contains("p.csv:1") && e.contains("source and sink"),
        "{e}"
    );
    let e = parse("0,1,2,2\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("positive and negative"), "{e}");
    let e = parse("0,1,2,3,1e-3\n0,1,2,3,1.4\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.csv:2") && e.contains("1.4 A") && e.contains("50 mA"),
        "{e}"
    );
    // A current pattern (a row per injection of every electrode's current) is said as
    // another form, with the one this file takes.
    let e = parse("1.4,-1.4,0,0,0,0,0,0\n0,1.4,-1.4,0,0,0,0,0\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("8 columns") && e.contains("stim_pattern"), "{e}");
    let e = parse("0,1,2\n", 16, 0).unwrap_err().to_string();
    assert!(
        e.contains("3 columns") && !e.contains("stim_pattern"),
        "{e}"
    );
    // A negative current (a system's sign for the other way) is said with its fix.
    let e = parse("0,1,2,3,-1e-3\n", 16, 0).unwrap_err().to_string();
    assert!(
        e.contains("above 0 A") && e.contains("swap the row's source and sink"),
        "{e}"
    );
    let e = parse("0,1,2,3,nan\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("NaN A") && !e.contains("swap"), "{e}");
    let e = parse("source,sink,plus,neg_v\n0,1,2,3\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no 'negative' column"), "{e}");
    // A current under a unit's name (`I (mA)`) is refused as current_ma is: its rows would
    // have driven the scene's current without a word.
    for name in ["I (mA)", "I_uA", "I [A]", "I_A"] {
        let e = parse(
            &format!("source,sink,positive,negative,{name}\n0,1,2,3,1.4\n"),
            16,
            0,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains(&format!("'{name}' reads as a current")), "{e}");
    }
    // Names beginning with a column's (the tank archives' `source_electrode(+)`), read.
    let begun = "source_electrode(+),sink_electrode(-),plus_electrode,negative_v\n0,1,2,3\n";
    assert_eq!(parse(begun, 16, 0).unwrap().rows()[0].negative, 3);
    // A list of injections or of measurements alone, said as half a protocol with the command
    // that crosses two.
    let e = parse(
        "injection,source_electrode(+),sink_electrode(-)\n1,1,2\n",
        16,
        1,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("the injections alone") && e.contains("et protocol --injections"),
        "{e}"
    );
    let e = parse("measurement,plus_electrode,minus_electrode\n1,1,2\n", 16, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("the measurements alone"), "{e}");
    let e = parse("0,1,2\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("3 columns"), "{e}");
    let e = parse("0,1,x,3\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("positive: 'x'"), "{e}");
    let e = parse("0,1,2,3\n", 16, 1).unwrap_err().to_string();
    assert!(e.contains("counted from 1"), "{e}");
    // Counted from 2 would shift every electrode by one more than any system does.
    let e = parse("2,3,4,5\n", 16, 2).unwrap_err().to_string();
    assert!(e.contains("base = 2") && e.contains("0 (et's) or 1"), "{e}");
    // The names other tools write for the four columns (hardware logs' I+ I- V+ V-,
    // resistivity tomography's A B M N and C1 C2 P1 P2, short forms), in any order.
    let named = parse("source,sink,positive,negative\n0,1,2,3\n", 16, 0).unwrap();
    for header in [
        "src,snk,pos,neg",
        "I+,I-,V+,V-",
        "V-;V+;I-;I+",
        "a,b,m,n",
        "C1,C2,P1,P2",
        "Source,Sink,Plus,Minus",
    ] {
        let reversed = header.contains(';');
        let row = if reversed { "3;2;1;0" } else { "0,1,2,3" };
        let got = parse(&format!("{header}\n{row}\n"), 16, 0);
        assert_eq!(got.as_ref().ok(), Some(&named), "{header}: {got:?}");
    }
    // A header of other names is said as a header, not as a row whose cell is not a number;
    // a name twice beside a missing one is said as twice, by any of its names.
    let e = parse("from,to,hi,lo\n0,1,2,3\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("p.csv:1") && e.contains("names from, to, hi, lo") && e.contains("I+, I-, V+"),
        "{e}"
    );
    let e = parse("source,source,positive,negative\n0,1,2,3\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("names source twice"), "{e}");
    let e = parse("source,I+,positive,negative\n0,1,2,3\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(e.contains("names source twice"), "{e}");
    // Numbers separated by spaces (MATLAB's `save -ascii`, NumPy's `savetxt`) are a row.
    assert_eq!(
        parse("   0   1   2   3\n", 16, 0).unwrap(),
        parse("0,1,2,3\n", 16, 0).unwrap()
    );
    let e = parse("0/1/2/3\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("1 column:") && e.contains("spaces"), "{e}");
    assert_eq!(
        parse("# nothing\n", 16, 0).unwrap_err().to_string(),
        "p.csv: no rows"
    );
    assert!(matches!(
        Schedule::new(16, Vec::new()).unwrap_err(),
        ScheduleError::Empty
    ));
    // Any schedule drives at most 1 A (simulated frames' unit current); a file at most 50 mA.
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    assert!(Schedule::of_protocol(&protocol, 1.0).is_ok());
    let e = Schedule::of_protocol(&protocol, 1.5).unwrap_err();
    assert!(matches!(e, ScheduleError::AboveUnit { .. }), "{e:?}");
    let e = parse("0,1,2,3,1.0\n", 16, 0).unwrap_err().to_string();
    assert!(e.contains("50 mA"), "{e}");
    // And at least 1 nA: 1e-300 A gave frames of 1e-297 V, past single precision.
    assert!(Schedule::of_protocol(&protocol, MIN_CURRENT_A).is_ok());
    let e = Schedule::of_protocol(&protocol, 1e-300).unwrap_err();
    assert!(matches!(e, ScheduleError::BelowNano { .. }), "{e:?}");
    let e = parse("0,1,2,3,1e-3\n0,1,3,4,1e-300\n", 16, 0)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(":2:") && e.contains("1e-300 A is below 1 nA"),
        "{e}"
    );
}

/// A current in some rows only was half read: without a header the first row decides the
/// columns, so a later row's fifth cell, its current, was ignored (that row drove the default
/// current), and a short row read its missing cells as empty. Every row is as wide as the
/// first, or is refused by its line.
#[test]
fn rows_of_another_width_are_refused_not_half_read() {
    for (text, line, cells, first) in [
        ("0,1,2,3\n1,2,3,4,2e-3\n", 2, 5, 4),
        ("0,1,2,3,1e-3\n1,2,3,4\n", 2, 4, 5),
        ("0,1,2,3\n1,2\n", 2, 2, 4),
        (
            "source,sink,positive,negative\n0,1,2,3\n1,2,3,4,2e-3\n",
            3,
            5,
            4,
        ),
    ] {
        let e = parse(text, 16, 0).unwrap_err().to_string();
        let said = format!("p.csv:{line}: {cells} cells, where the first row has {first}");
        assert!(e.contains(&said), "{text:?}: {e}");
    }
    // A delimiter ending every line is the line's end, not a fifth column.
    let ended = parse("0,1,2,3,\n1,2,3,4,\n", 16, 0).unwrap();
    assert_eq!(ended, parse("0,1,2,3\n1,2,3,4\n", 16, 0).unwrap());
    // So it is under a header written by hand without one.
    let headed = "source,sink,positive,negative\n0,1,2,3,\n1,2,3,4,\n";
    assert_eq!(ended, parse(headed, 16, 0).unwrap());
    // Each row's own current, where every row gives one.
    let s = parse("0,1,2,3,1e-3\n1,2,3,4,2e-3\n", 16, 0).unwrap();
    assert_eq!(s.rows()[1].current_a, 2e-3);
}

/// Electrodes written as whole decimals, as NumPy's `savetxt` writes every number by default
/// (`np.savetxt("p.csv", rows, delimiter=",")`), are the same electrodes; a fraction is
/// refused, not truncated.
#[test]
fn electrodes_written_as_whole_decimals_are_read() {
    let plain = parse("0,1,2,3\n", 16, 0).unwrap();
    for text in [
        "0.0,1.0,2.0,3.0\n",
        "0.000000000000000000e+00,1.000000000000000000e+00,2.000000000000000000e+00,3.000000000000000000e+00\n",
        "0;1,0;2;3\n",
    ] {
        assert_eq!(parse(text, 16, 0).unwrap(), plain, "{text}");
    }
    for bad in ["0,1.5,2,3\n", "0,-1.0,2,3\n", "0,1e9,2,3\n", "0,inf,2,3\n"] {
        let e = parse(bad, 16, 0).unwrap_err().to_string();
        assert!(
            e.contains("sink: '") && e.contains("is not an electrode number"),
            "{bad}: {e}"
        );
    }
}

/// A frame of the wrong length is said with what it may be: another built-in protocol's K
/// (opposite's and pseudo-polar's 192 at 16 electrodes beside adjacent's 208), every pair of
/// each injection (16 x 16), or half of K; a length that is none of them, nothing.
#[test]
fn a_frame_of_another_length_is_said_with_what_it_may_be() {
    let said = |n| other_frame_len(n, 208).unwrap_or_default();
    assert_eq!(
        said(192),
        "192 values a frame are pseudo-polar at 16 electrodes, opposite at 16 electrodes"
    );
    assert!(said(256).starts_with("256 = 16 x 16: every electrode pair's value"));
    assert!(said(104).starts_with("104 is half of K"));
    assert_eq!(other_frame_len(241, 208), None);
    // Every built-in protocol's own K is named as it.
    let k = Protocol::new(ProtocolKind::PpPp, 32).unwrap().frame_len();
    assert!(said(k).contains("pp-pp at 32 electrodes"), "{}", said(k));
}

#[test]
fn an_electrode_left_out_takes_every_value_it_drives_or_measures() {
    let protocol = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    let s = Schedule::of_protocol(&protocol, 1e-3).unwrap();
    let (without, kept) = s.without(&[7]).unwrap();
    // Adjacent on 16: the two injections by electrode 7 go (26 values); the two beside them
    // lose one pair (the other already touches their drive), the other twelve two: 2 x 12 +
    // 12 x 11 = 156 kept.
    assert_eq!(without.frame_len(), 156);
    assert_eq!(kept.len(), 156);
    assert_eq!(without.kind(), None);
    for (row, k) in without.rows().iter().zip(&kept) {
        assert_eq!(row, &s.rows()[*k]);
        assert!(![row.source, row.sink, row.positive, row.negative].contains(&7));
    }
    assert!(kept.windows(2).all(|w| w[0] < w[1]));
    // None left out: the same rows; past the sheet refused.
    assert_eq!(s.without(&[]).unwrap().0.rows(), s.rows());
    assert!(matches!(
        s.without(&[16]),
        Err(ScheduleError::Absent {
            electrode: 16,
            electrodes: 16
        })
    ));
    // Half the electrodes may be left out, not more.
    let half: Vec<u16> = (0..8).collect();
    assert!(s.without(&half).is_ok());
    let more: Vec<u16> = (0..9).collect();
    assert!(matches!(
        s.without(&more),
        Err(ScheduleError::TooManyLeftOut {
            left_out: 9,
            electrodes: 16
        })
    ));
    // A protocol whose every value involves electrode 0 (all against it): nothing left.
    let rows = (1..4)
        .map(|e| Row {
            source: e,
            sink: 0,
            positive: e,
            negative: 0,
            current_a: 1e-3,
        })
        .collect();
    let star = Schedule::new(4, rows).unwrap();
    assert!(matches!(
        star.without(&[0]),
        Err(ScheduleError::NothingLeft {
            rows: 3,
            left_out: 1
        })
    ));
    // Opposite on 16 without half its electrodes (0 to 7): each row's four electrodes are two
    // pairs half a sheet apart, so one of them is always among 0 to 7.
    let opposite = Protocol::new(ProtocolKind::Opposite, 16).unwrap();
    let o = Schedule::of_protocol(&opposite, 1e-3).unwrap();
    let e = o.without(&half).unwrap_err().to_string();
    assert!(
        e.contains("every one of the 192 values") && e.contains("leave fewer out"),
        "{e}"
    );
}
