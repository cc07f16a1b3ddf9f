use et_host::frames::*;
use nalgebra::DMatrix;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("et-frames-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn csv_rows_or_columns_header_or_not() {
    let dir = tmp("csv");
    let f = dir.join("f.csv");
    std::fs::write(&f, "v0,v1,v2\n1e-3,2e-3,3e-3\n4e-3,5e-3,6e-3\n").unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!(r.frames.len(), 2);
    assert_eq!(r.frames[1][2], 6e-3);
    // Three frames of K = 2 stored as columns (MATLAB's habit), `;` with decimal commas.
    std::fs::write(&f, "1,0;4,0;7,5\n2,0;5,0;8,0\n").unwrap();
    let r = read(&f, 2).unwrap();
    assert_eq!(
        r.frames,
        vec![vec![1.0, 2.0], vec![4.0, 5.0], vec![7.5, 8.0]]
    );
    assert!(r.description.contains("transposed"), "{}", r.description);
    let e = read(&f, 5).unwrap_err().to_string();
    assert!(e.contains("2 x 3") && e.contains("K = 5"), "{e}");
    std::fs::write(&f, "1,2\n3,x\n").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("f.csv:2") && e.contains("'x'"), "{e}");
    // A first row counting the columns (a DAQ's channel numbers, from 0 or 1) is a header:
    // it was read as the first frame, the reference.
    for (from, d) in [(0, ","), (1, ","), (1, ";")] {
        let line = |v: &dyn Fn(usize) -> String| (0..8).map(v).collect::<Vec<_>>().join(d);
        let header = line(&|j| (j + from).to_string());
        let frame = line(&|j| format!("{}e-3", j + 2));
        std::fs::write(&f, format!("{header}\n{frame}\n{frame}\n")).unwrap();
        let r = read(&f, 8).unwrap();
        assert_eq!(r.frames.len(), 2, "{header}");
        assert!(
            r.description.contains("the columns' numbers"),
            "{}",
            r.description
        );
    }
    // K frames of K values read either way round: the frames are the lines that are alike
    // (MATLAB's columns of frames were read as rows, each "frame" one channel over time).
    let v0 = [1.0, -2.0, 0.5, 3.0, -0.25, 0.75, -1.5, 2.5];
    let frames: Vec<Vec<f64>> = (0..8)
        .map(|i| v0.iter().map(|v| v * (1.0 + 0.01 * f64::from(i))).collect())
        .collect();
    let as_rows: String = (frames.iter())
        .map(|f| {
            f.iter()
                .map(|v| v.to_string())
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    let as_columns: String = (0..8)
        .map(|c| {
            (frames.iter())
                .map(|f| f[c].to_string())
                .collect::<Vec<_>>()
                .join(",")
                + "\n"
        })
        .collect();
    for (text, said) in [
        (as_rows, "one per row: a K x K"),
        (as_columns, "read transposed: a K x K"),
    ] {
        std::fs::write(&f, text).unwrap();
        let r = read(&f, 8).unwrap();
        assert!(r.description.contains(said), "{}", r.description);
        for (got, want) in r.frames.iter().zip(&frames) {
            let want: Vec<f32> = want.iter().map(|v| *v as f32).collect();
            assert_eq!(got, &want);
        }
    }
    // Complex values (NumPy's savetxt of a complex array, MATLAB's) are said as that, and a
    // row of real and imaginary parts side by side as twice K.
    for cell in ["(9.68e+00+9.68e-01j)", "1.5-2e-3j", "1.5+0.2i"] {
        std::fs::write(&f, format!("1,2\n3,{cell}\n")).unwrap();
        let e = read(&f, 2).unwrap_err().to_string();
        assert!(
            e.contains("but a complex one") && e.contains("V.real"),
            "{e}"
        );
    }
    std::fs::write(&f, "1,2\n3,1e\n").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(!e.contains("complex"), "{e}");
    std::fs::write(&f, "1,2,3,4\n".repeat(5)).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("twice K: real and imaginary parts"), "{e}");
    // A value missing (an empty or NaN cell, a DAQ's dropped sample) keeps its frame, NaN
    // there, said; the file was refused whole. An infinite one is refused where it is.
    std::fs::write(&f, "1,2\n3,nan\n5,6\n,8\n").unwrap();
    let r = read(&f, 2).unwrap();
    assert_eq!(r.frames.len(), 4);
    assert_eq!(r.gaps, [1, 3]);
    assert!(r.frames[1][1].is_nan() && r.frames[3][0].is_nan() && r.frames[2][0] == 5.0);
    let said = "(2 with values missing, empty or NaN: frames 1, 3, from 0)";
    assert!(r.description.contains(said), "{}", r.description);
    assert!(r.check_whole(&f, 0..1, "--frame").is_ok());
    let e = r.check_whole(&f, 2..4, "--frame").unwrap_err().to_string();
    assert!(
        e.contains("frame 3 (from 0) has values missing") && e.contains("in column 0 (from 0)"),
        "{e}"
    );
    std::fs::write(&f, "1,2\n3,-inf\n").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("f.csv:2: column 2: '-inf' is not finite"), "{e}");
    // Values single precision cannot hold are said where they are (1e300 was imaged as a
    // reference of 0 values; 1e-300 everywhere as frames of zeros); at its bounds, taken.
    std::fs::write(&f, "1,2\n3,1e300\n").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(
        e.contains("f.csv:2: column 2: '1e300' is past single precision"),
        "{e}"
    );
    std::fs::write(&f, "1e-300,-2e-300\n0,1e-39\n").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("every value is below 1.2e-38"), "{e}");
    std::fs::write(&f, "3.4e38,-1.2e-38\n0,1e-300\n").unwrap();
    let r = read(&f, 2).unwrap();
    assert_eq!(r.frames[0], vec![3.4e38_f32, -1.2e-38_f32]);
    // A short last row is said as a copy cut short; a short row before it is not.
    for (text, cut) in [("1,2,3\n4,5,6\n7,8", true), ("1,2,3\n4,5\n7,8,9\n", false)] {
        std::fs::write(&f, text).unwrap();
        let e = read(&f, 3).unwrap_err().to_string();
        assert!(e.contains("2 values, the first frame has 3"), "{e}");
        assert_eq!(e.contains("cut short"), cut, "{e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Frames as other tools write them around the values: pandas' `to_csv` with its row index
/// (an unnamed first column counting from 0) and R's `write.csv` with its row names (from 1), a delimiter ending every line (`fprintf('%g,',
/// v)` in a loop), numbers separated by spaces (NumPy's `savetxt`, MATLAB's `save -ascii`),
/// and a first column of times, which is not guessed at but said.
#[test]
fn csv_as_pandas_and_matlab_loops_write_them() {
    let dir = tmp("pandas");
    let f = dir.join("f.csv");
    let plain = vec![vec![1e-3_f32, 2e-3, 3e-3], vec![4e-3, 5e-3, 6e-3]];
    for (text, index) in [
        (
            ",0,1,2
0,1e-3,2e-3,3e-3
1,4e-3,5e-3,6e-3
",
            true,
        ),
        (
            "Unnamed: 0,v0,v1,v2
0,1e-3,2e-3,3e-3
1,4e-3,5e-3,6e-3
",
            true,
        ),
        // R's `write.csv`: its row names, quoted, from 1 (one column too many before).
        (
            "\"\",\"V1\",\"V2\",\"V3\"
\"1\",1e-3,2e-3,3e-3
\"2\",4e-3,5e-3,6e-3
",
            true,
        ),
        (
            "1e-3,2e-3,3e-3,
4e-3,5e-3,6e-3,
",
            false,
        ),
        (
            "v0;v1;v2;
1e-3;2e-3;3e-3;
4e-3;5e-3;6e-3;
",
            false,
        ),
        // A header written by hand, without the loop's line-ending delimiter.
        (
            "v0,v1,v2
1e-3,2e-3,3e-3,
4e-3,5e-3,6e-3,
",
            false,
        ),
        // NumPy's `savetxt` default and MATLAB's `save -ascii`: runs of spaces (they were one
        // cell, "not a number", the first row taken as a header).
        ("1.0e-03 2.0e-03 3.0e-03\n4.0e-03 5.0e-03 6.0e-03\n", false),
        (
            "   1.0e-03   2.0e-03   3.0e-03\n   4.0e-03   5.0e-03   6.0e-03\n",
            false,
        ),
        // pandas' `to_csv(sep=" ", index=False)`: names separated by spaces above them.
        (
            "v0 v1 v2\n1.0e-03 2.0e-03 3.0e-03\n4.0e-03 5.0e-03 6.0e-03\n",
            false,
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        let r = read(&f, 3).unwrap();
        assert_eq!(r.frames, plain, "{text}");
        assert_eq!(
            r.description.contains("skipped as the rows' index"),
            index,
            "{}",
            r.description
        );
    }
    // An unnamed first column that does not count the rows from 0 is data.
    std::fs::write(&f, ",0,1,2\n5,1e-3,2e-3,3e-3\n6,4e-3,5e-3,6e-3\n").unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(
        e.contains("2 x 4 values") && e.contains("one more than K: a first column"),
        "{e}"
    );
    // A DAQ's columns of the rows' times or numbers, named as the table reader knows them,
    // anywhere and of text too, and a row of units under the names: left out and said (they
    // were one column too many, or "'V' is not a number").
    for (text, said) in [
        (
            "time_s,v0,v1,v2\n0,1e-3,2e-3,3e-3\n1,4e-3,5e-3,6e-3\n",
            "its column 'time_s' skipped (the rows' numbers, times, sessions or targets",
        ),
        (
            "Timestamp;v0;v1;v2;Frame\n2026-12-07 10:00:00;1e-3;2e-3;3e-3;1\n\
             2026-12-07 10:00:01;4e-3;5e-3;6e-3;2\n",
            "its columns 'Timestamp', 'Frame' skipped",
        ),
        // pandas' index of times (a `DatetimeIndex`), unnamed.
        (
            ",v0,v1,v2\n2026-12-07 10:00:00,1e-3,2e-3,3e-3\n2026-12-07 10:00:01,4e-3,5e-3,6e-3\n",
            "its first column (unnamed, of text: pandas' index of times?) skipped as the rows' \
             index",
        ),
        // A recording annotated with what was pressed where.
        (
            "v0,v1,v2,label,x,y\n1e-3,2e-3,3e-3,none,,\n4e-3,5e-3,6e-3,left,0.01,0.02\n",
            "its columns 'label', 'x', 'y' skipped (the rows' numbers, times, sessions or \
             targets by name",
        ),
        (
            "Time,ch1,ch2,ch3\ns,V,V,V\n0.0,1e-3,2e-3,3e-3\n0.1,4e-3,5e-3,6e-3\n",
            "its second row (units: V) skipped as a header, its column 'Time' skipped",
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        let r = read(&f, 3).unwrap();
        assert_eq!(r.frames, plain, "{text}");
        assert!(r.description.contains(said), "{}", r.description);
    }
    // Values in a unit of voltage the file names, under the names or in them, read as volts
    // (mV were read as volts: 1000 times the sheet's background, past 100 V a note, under it
    // nothing); another unit (impedances, counts) is said and the values taken as they are.
    for (text, said) in [
        (
            "Time,ch1,ch2,ch3\ns,mV,mV,mV\n0.0,1,2,3\n0.1,4,5,6\n",
            "its second row (units: mV) skipped as a header, its values read as volts (mV x 1e-3)",
        ),
        (
            "U1 [uV];U2 [uV];U3 [uV]\n1000;2000;3000\n4000;5000;6000\n",
            "its values read as volts (uV x 1e-6, as its columns' names say)",
        ),
        (
            "a (V),b (mV),c (mV)\n1e-3,2,3\n4e-3,5,6\n",
            "its values read as volts (V x 1e0, mV x 1e-3, as its columns' names say)",
        ),
        // A quantity over its unit (ISO 80000's way), a unit after an underscore.
        (
            "U1/mV,U2/mV,ch3_mV\n1,2,3\n4,5,6\n",
            "its values read as volts (mV x 1e-3, as its columns' names say)",
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        let r = read(&f, 3).unwrap();
        let near = (r.frames.iter().flatten().zip(plain.iter().flatten()))
            .all(|(a, b)| (a - b).abs() <= 1e-6 * b.abs());
        assert!(near, "{text}: {:?}", r.frames);
        assert!(r.description.contains(said), "{}", r.description);
    }
    std::fs::write(
        &f,
        "ch1,ch2,ch3\nOhm,Ohm,Ohm\n1e-3,2e-3,3e-3\n4e-3,5e-3,6e-3\n",
    )
    .unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!(r.frames, plain);
    assert!(
        (r.description).contains("(units? 'Ohm', not a unit of voltage: the values are taken as"),
        "{}",
        r.description
    );
    // The words tools write for a value missing (R's NA, Excel's #N/A, a Windows C
    // library's -1.#IND) are values missing, as an empty cell is (they were "not a number",
    // or a first row of them a header).
    std::fs::write(&f, "1e-3,NA,3e-3\n#N/A,5e-3,-1.#IND\n").unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!((r.frames.len(), r.gaps.as_slice()), (2, &[0, 1][..]));
    std::fs::write(&f, "v0,v1,v2\nNA,null,None\n4e-3,5e-3,6e-3\n").unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!((r.frames.len(), r.gaps.as_slice()), (2, &[0][..]));
    // A first frame with a value missing, headerless, is a frame (it was taken as a header).
    std::fs::write(&f, "1e-3,,3e-3\n4e-3,5e-3,6e-3\n").unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!((r.frames.len(), r.gaps.as_slice()), (2, &[0][..]));
    // A first frame of NaN alone is a frame with values missing, not a units row (the frames
    // after it would have been counted from it).
    std::fs::write(&f, "v0,v1,v2\nNaN,nan,NAN\n4e-3,5e-3,6e-3\n").unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!((r.frames.len(), r.gaps.as_slice()), (2, &[0][..]));
    // A second row of text and numbers is no units row: said by its cell.
    std::fs::write(&f, "v0,v1,v2\nV,2e-3,V\n4e-3,5e-3,6e-3\n").unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(e.contains(":2: column 1: 'V' is not a number"), "{e}");
    // A logger's header of several lines: the line under the names is asked about; a header
    // alone is said as that.
    std::fs::write(&f, "v0,v1,v2\nrate: 1 kHz,gain 8,\n1e-3,2e-3,3e-3\n").unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(
        e.contains(":2: column 1: 'rate: 1 kHz' is not a number (a header of more lines"),
        "{e}"
    );
    std::fs::write(&f, "v0,v1,v2\n").unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(e.ends_with("no frames (a header row alone)"), "{e}");
    // Every column named as no frame's values (it indexed a matrix of no columns).
    for text in ["time,label\n1,a\n2,b\n", "time,label\ns,\n"] {
        std::fs::write(&f, text).unwrap();
        let e = read(&f, 3).unwrap_err().to_string();
        assert!(
            e.contains("no values: its columns time, label are named"),
            "{e}"
        );
    }
    // Fortran's numbers under a header: no units row, said by the first cell with the fix.
    std::fs::write(&f, "v0,v1,v2\n1.0D-03,2.0D-03,3.0D-03\n").unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(
        e.contains(":2: column 1: '1.0D-03' is not a number but Fortran's D exponent: write E"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A `.npy` file of `descr` values as NumPy writes it (format 1.0, C order).
fn npy_file(descr: &str, shape: (usize, usize), data: &[u8]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': False, 'shape': ({}, {}), }}",
        shape.0, shape.1
    );
    let pad = 64 - (10 + dict.len() + 1) % 64;
    let header = format!("{dict}{}\n", " ".repeat(pad % 64));
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend((header.len() as u16).to_le_bytes());
    out.extend(header.as_bytes());
    out.extend(data);
    out
}

/// Half-precision frames (`np.float16`, as a logger saves to halve its files) are read; complex
/// ones (a system's magnitude and phase) and Python objects are said as what they are, with
/// the fix (both were "unsupported type '<c16' (numbers, booleans or text only)").
#[test]
fn npy_of_half_complex_or_objects_is_read_or_said() {
    let dir = tmp("npy-kinds");
    let f = dir.join("f.npy");
    let halves: Vec<u8> = [1.0_f32, -0.5, 2.0e-3, 6.0e4]
        .iter()
        .flat_map(|&x| et_core::precision::f32_to_f16(x).to_le_bytes())
        .collect();
    std::fs::write(&f, npy_file("<f2", (2, 2), &halves)).unwrap();
    let r = read(&f, 2).unwrap();
    let back = |x: f32| et_core::precision::f16_to_f32(et_core::precision::f32_to_f16(x));
    assert_eq!(r.frames, vec![vec![1.0, -0.5], vec![back(2.0e-3), 6.0e4]]);
    std::fs::write(&f, npy_file("<c16", (2, 2), &[0; 64])).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(
        e.contains("complex values ('<c16')") && e.contains("np.abs"),
        "{e}"
    );
    std::fs::write(&f, npy_file("|O", (2, 2), &[0; 32])).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(
        e.contains("Python objects") && e.contains("dtype=float"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn npy_and_npz_as_numpy_writes_them() {
    let dir = tmp("npy");
    let m = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let mut w = et_learn::npz::Writer::new();
    w.matrix("frames", &m);
    w.matrix("other", &m);
    let npz = dir.join("f.npz");
    std::fs::write(&npz, w.finish().unwrap()).unwrap();
    let named = PathBuf::from(format!("{}:frames", npz.display()));
    assert!(is_table(&named));
    let r = read(&named, 3).unwrap();
    assert_eq!(r.frames[1], vec![4.0, 5.0, 6.0]);
    let e = read(&npz, 3).unwrap_err().to_string();
    assert!(e.contains("2 arrays") && e.contains(":NAME"), "{e}");
    let e = read(&PathBuf::from(format!("{}:none", npz.display())), 3).unwrap_err();
    assert!(e.to_string().contains("none"), "{e}");
    // `np.savez(f, frames=F, t=t, labels=...)`: the one array of K values a frame is the
    // frames, said; two of them still asked (above), as is one of none.
    let mut w = et_learn::npz::Writer::new();
    w.matrix("v", &m);
    w.f64s("t", &[0.0, 0.1]);
    w.text("labels", "none");
    std::fs::write(&npz, w.finish().unwrap()).unwrap();
    let r = read(&npz, 3).unwrap();
    assert_eq!(r.frames[1], vec![4.0, 5.0, 6.0]);
    let said = "array 'v', the only one of its arrays with K = 3 values a frame (the others: t, \
                labels)";
    assert!(r.description.contains(said), "{}", r.description);
    let e = read(&npz, 4).unwrap_err().to_string();
    assert!(e.contains("3 arrays") && e.contains(":NAME"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A MATLAB file as et writes it (and as MATLAB stores frames: one per column) is read by its
/// variable's name, transposed; a second variable makes the name necessary; MATLAB 7.3 (HDF5)
/// and unknown names are refused with what to do.
#[test]
fn matlab_files_by_variable() {
    let dir = tmp("mat");
    let f = dir.join("tank.mat");
    // Three frames of K = 2 as columns.
    let v = DMatrix::from_row_slice(2, 3, &[1e-3, 4e-3, 7e-3, 2e-3, 5e-3, 8e-3]);
    std::fs::write(&f, mat_v5("v", &v)).unwrap();
    let r = read(&f, 2).unwrap();
    assert_eq!(
        r.frames,
        vec![vec![1e-3, 2e-3], vec![4e-3, 5e-3], vec![7e-3, 8e-3]]
    );
    assert!(
        r.description.contains("variable 'v'") && r.description.contains("transposed"),
        "{}",
        r.description
    );
    let by_name = read(&dir.join("tank.mat:v"), 2).unwrap();
    assert_eq!(by_name.frames, r.frames);
    // Two variables of K values a frame: the frames' must be named; beside a variable of
    // another length, the one of K is the frames, said.
    let mut two = mat_v5("v", &v);
    two.extend_from_slice(&mat_v5("t", &DMatrix::from_element(1, 3, 0.1))[128..]);
    std::fs::write(&f, &two).unwrap();
    let r = read(&f, 2).unwrap();
    assert_eq!(r.frames.len(), 3);
    let said = "variable 'v', the only one of its arrays with K = 2 values a frame (the others: t)";
    assert!(r.description.contains(said), "{}", r.description);
    let mut two = mat_v5("v", &v);
    two.extend_from_slice(&mat_v5("ref", &DMatrix::from_element(2, 1, 1.0))[128..]);
    std::fs::write(&f, &two).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(
        e.contains("v, ref") && e.contains("tank.mat:VARIABLE"),
        "{e}"
    );
    assert_eq!(read(&dir.join("tank.mat:ref"), 2).unwrap().frames.len(), 1);
    let e = read(&dir.join("tank.mat:volts"), 2)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no numeric array 'volts'"), "{e}");
    // Complex frames (an impedance system's): the part to save is asked, as of a .npy's
    // (they were "complex or 64-bit integer", though 64-bit integers are read).
    let mut complex = mat_v5("z", &v);
    complex[145] = 0x08; // the array flags' complex bit
    let imag: Vec<u8> = v.iter().flat_map(|x| (x * 0.5).to_le_bytes()).collect();
    complex.extend(9u32.to_le_bytes());
    complex.extend((imag.len() as u32).to_le_bytes());
    complex.extend(&imag);
    let size = u32::from_le_bytes(complex[132..136].try_into().unwrap()) + 8 + imag.len() as u32;
    complex[132..136].copy_from_slice(&size.to_le_bytes());
    std::fs::write(&f, &complex).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(
        e.contains("'z' holds complex values") && e.contains("real(V)"),
        "{e}"
    );
    // The array read, unnamed, is said with a size that is no frame's (a model's nodes, the
    // only numeric array beside its structs, were said by their size alone).
    std::fs::write(&f, mat_v5("nodes", &DMatrix::from_element(20, 2, 0.5))).unwrap();
    let e = read(&f, 208).unwrap_err().to_string();
    assert!(e.contains("variable 'nodes' read: 20 x 2 values"), "{e}");
    std::fs::write(&f, b"MATLAB 7.3 MAT-file, Platform: GLNXA64").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("-v7"), "{e}");
    std::fs::write(&f, b"\x00\x01not a mat file at all").unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("tank.mat") && e.contains("not a MATLAB"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A file named for one array format and holding another (`scipy.io.savemat("f.npy")`, a
/// renamed file) is read as what its first bytes say, and said so; one holding text is read
/// as a table (each was refused as "no magic" or "not a MATLAB version 5 or 7 file: a
/// version 4 file?"); a picture or an HDF5 file is named as what it is. A name given to a
/// .npy, which holds one array, is refused (it was not split from the path).
#[test]
fn array_files_are_read_by_what_they_hold_not_their_name() {
    let dir = tmp("held");
    let m = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let mut w = et_learn::npz::Writer::new();
    w.matrix("frames", &m);
    let npz = w.finish().unwrap();
    let mat = mat_v5("v", &m);
    let csv = b"1,2,3\n4,5,6\n".to_vec();
    let frames = [vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]];
    for (name, bytes, said) in [
        (
            "a.npy",
            &mat,
            "a MATLAB .mat file by its first bytes, though named .npy",
        ),
        (
            "a.mat",
            &npz,
            "a NumPy .npz archive by its first bytes, though named .mat",
        ),
        (
            "b.npz",
            &mat,
            "a MATLAB .mat file by its first bytes, though named .npz",
        ),
        ("t.npy", &csv, "text, though named .npy, read as a table"),
        ("t.mat", &csv, "text, though named .mat, read as a table"),
    ] {
        let f = dir.join(name);
        std::fs::write(&f, bytes).unwrap();
        let r = read(&f, 3).unwrap();
        assert_eq!(r.frames, frames, "{name}");
        assert!(r.description.contains(said), "{}", r.description);
    }
    // Text through a FIFO named .npy: its bytes read once (a second read would wait forever).
    let fifo = dir.join("fifo.npy");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    let writer = {
        let (fifo, csv) = (fifo.clone(), csv.clone());
        std::thread::spawn(move || std::fs::write(fifo, csv).unwrap())
    };
    assert_eq!(read(&fifo, 3).unwrap().frames, frames);
    writer.join().unwrap();
    // Its array named as its own format's are.
    let two = [mat.clone(), mat_v5("w", &m)[128..].to_vec()].concat();
    std::fs::write(dir.join("two.npy"), &two).unwrap();
    let e = read(&dir.join("two.npy"), 3).unwrap_err().to_string();
    assert!(e.contains("two.npy:VARIABLE"), "{e}");
    assert_eq!(read(&dir.join("two.npy:w"), 3).unwrap().frames, frames);
    std::fs::write(dir.join("one.npy"), npy_file("<f8", (2, 3), &[0; 48])).unwrap();
    let e = read(&dir.join("one.npy:x"), 3).unwrap_err().to_string();
    assert!(
        e.contains("a .npy holds one array, not one named 'x'"),
        "{e}"
    );
    for (bytes, said) in [
        (
            &b"\x89PNG\r\n\x1a\n\x00\x00"[..],
            "a PNG picture, though named .mat",
        ),
        (
            b"\x89HDF\r\n\x1a\n\x00\x00",
            "an HDF5 file (h5py, MATLAB's -v7.3), though named .mat",
        ),
    ] {
        std::fs::write(dir.join("x.mat"), bytes).unwrap();
        let e = read(&dir.join("x.mat"), 3).unwrap_err().to_string();
        assert!(e.contains(said), "{e}");
    }
    // A workbook (a zip archive of parts such as Excel writes, no .npy among them), named
    // .npz or .mat: an archive whose one entry is renamed as an Office part.
    let mut xlsx = et_learn::npz::Writer::new();
    xlsx.matrix("[Content_Types]", &m);
    let mut xlsx = xlsx.finish().unwrap();
    let (npy, xml) = (b"[Content_Types].npy", b"[Content_Types].xml");
    while let Some(at) = xlsx.windows(npy.len()).position(|w| w == npy) {
        xlsx[at..at + npy.len()].copy_from_slice(xml);
    }
    for name in ["book.npz", "book.mat"] {
        std::fs::write(dir.join(name), &xlsx).unwrap();
        let e = read(&dir.join(name), 3).unwrap_err().to_string();
        assert!(e.contains("an Excel .xlsx workbook"), "{e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A file named neither as a table nor as a recording (a DAQ's `.dat`, no extension) is read
/// as what it holds: a table unless its first line is a JSON object (`.dat` was read as a
/// recording and refused for its first line). A stream is taken by its name, unread.
#[test]
fn frames_named_otherwise_are_read_by_what_they_hold() {
    let dir = tmp("named-otherwise");
    let table = [
        ("f.dat", "1,2,3\n4,5,6\n"),
        ("frames", "\u{feff}  1 2 3\n4 5 6\n"),
        // (pandas' "split", a column named K: frames, not a recording's header.)
        (
            "split.json",
            "{\"columns\":[\"K\",\"b\",\"c\"],\"index\":[0,1],\"data\":[[1,2,3],[4,5,6]]}",
        ),
    ];
    for (name, text) in table {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        assert!(reads_as_table(&f), "{name}");
        let frames = read(&f, 3).unwrap().frames;
        assert_eq!(frames, [vec![1.0, 2.0, 3.0], vec![4.0, 5.0, 6.0]], "{name}");
    }
    for (name, text) in [
        ("r.dat", " {\"format\":\"et-recording\"}\n"),
        // A recording's header written without its "format" (sorted keys, as Python's
        // json.dumps(..., sort_keys=True) writes them): the recording reader asks for it.
        (
            "no-format.jsonl",
            "{\"K\" : 208, \"columns\": [{\"negative\": 3}]}\n",
        ),
        ("r.jsonl", "1,2,3\n"),
        ("empty.dat", ""),
        ("none.dat", "-"),
    ] {
        let f = dir.join(name);
        if name != "none.dat" {
            std::fs::write(&f, text).unwrap();
        }
        assert!(!reads_as_table(&f), "{name}");
    }
    assert!(reads_as_table(&dir.join("none.csv")), "by name");
    let fifo = dir.join("fifo");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    assert!(made.is_ok_and(|s| s.success()), "mkfifo");
    assert!(!reads_as_table(&fifo), "a FIFO is not read ahead");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Frames as JSON (`json.dump(F.tolist())`, `jsonencode(F)`, pandas' `orient="records"`):
/// they were "not an et recording" as `.json` and "no frames (a header row alone)" as `.txt`.
#[test]
fn frames_as_json_arrays_are_read() {
    let dir = tmp("json");
    let plain = [vec![1.0_f32, 2.0, 3.0], vec![4.0, 5.0, 6.0]];
    for (name, text, said) in [
        (
            "f.json",
            "[[1, 2, 3], [4, 5.0, 6e0]]",
            "a JSON array of frames, 2 frames",
        ),
        (
            "f.txt",
            "\u{feff}[\n [1,2,3],\n [4,5,6]\n]\n",
            "a JSON array of frames, 2",
        ),
        // JSON Lines, an array a frame (a logger's `json.dumps(frame)` each frame).
        (
            "l.jsonl",
            "[1, 2, 3]\n[4, 5, 6]\n",
            "JSON Lines, an array a frame, 2",
        ),
        (
            "r.json",
            r#"[{"t": 0, "a (mV)": 1000, "b (mV)": 2000, "c (mV)": 3000, "label": "none"},
                {"t": 1, "a (mV)": 4000, "b (mV)": 5000, "c (mV)": 6000, "label": "x"}]"#,
            "its values 't', 'label' skipped (the rows' numbers, times, sessions or \
             targets by name, not a frame's values), its values read as volts (mV x 1e-3, as \
             their names say)",
        ),
    ] {
        let f = dir.join(name);
        std::fs::write(&f, text).unwrap();
        assert!(reads_as_table(&f), "{name}");
        let r = read(&f, 3).unwrap();
        assert_eq!(r.frames, plain, "{name}");
        assert!(r.description.contains(said), "{}", r.description);
    }
    let f = dir.join("g.json");
    // Python's NaN and JSON's null are values missing (outside strings only); one array is
    // one frame.
    std::fs::write(&f, r#"[[1, NaN, 3], [4, 5, null]]"#).unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!(r.gaps, [0, 1]);
    std::fs::write(&f, "[1, 2, 3]").unwrap();
    assert_eq!(read(&f, 3).unwrap().frames, [vec![1.0_f32, 2.0, 3.0]]);
    for (text, said) in [
        (
            "[[1, 2, 3], [4, Infinity, 6]]",
            "not JSON at line 1, column 17 (at 'Infinity, 6]]'): an infinite value",
        ),
        (
            "[[1, 2, 3], [4, 5",
            "not JSON: it ends at line 1 before its arrays close",
        ),
        (
            r#"[[1, 2, 3], [4, "NaN", 6]]"#,
            "frame 1, value 1 (from 0): \"NaN\" is not a number",
        ),
        (
            "[[1, 2, 3], [4, [5], 6]]",
            "frame 1, value 1 (from 0): an array is not a number",
        ),
        (
            "[1, 2, 3]\n[4, [5], 6]\n",
            "frame 1, value 1 (from 0): an array is not a number",
        ),
        (
            "[[1, 2, 3], [4, 5]]",
            "frame 1 (from 0) has 2 values, the first 3",
        ),
        (
            "[[1, 2, 3], 4]",
            "element 1 (from 0) is a value among frames",
        ),
        (
            r#"[{"a": 1, "b": 2}, {"b": 2, "a": 1}]"#,
            "frame 1 (from 0) names other values than the first (its keys, in order: b, a)",
        ),
        ("[]", "no frames"),
        // JSON, but past a double's range (it was "not JSON" at the next value).
        (
            "[[1e400, 2, 3], [4, 5, 6]]",
            "line 1, column 7: '1e400' is past the range of a number (at most 1.8e308)",
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        let e = read(&f, 3).unwrap_err().to_string();
        assert!(e.contains(said), "{text}: {e}");
    }
    // An object holding frames is read as pandas' orientations and other tools write it (it
    // was taken as a recording's first line and refused); a recording's, which names its
    // "format" first, is still a recording.
    for (text, said) in [
        (
            // pandas' to_json() default, orient="columns": a key a column, rows by index.
            r#"{"a":{"0":1,"1":4},"b":{"0":2,"1":5},"c":{"0":3,"1":6}}"#,
            "an object of objects, a key a column",
        ),
        // Its columns left out or read as volts by their names, as a CSV's.
        (
            r#"{"t":{"0":0,"1":1},"a (mV)":{"0":1000,"1":4000},"b (mV)":{"0":2000,"1":5000},"c (mV)":{"0":3000,"1":6000},"label":{"0":"none","1":"x"}}"#,
            "its values 't', 'label' skipped",
        ),
        // orient="index": a key a row, read transposed by K.
        (
            r#"{"0":{"a":1,"b":2,"c":3,"label":"none"},"1":{"a":4,"b":5,"c":6,"label":"x"}}"#,
            "one per column: read transposed",
        ),
        (
            r#"{"columns":["t","a","b","c"],"index":[0,1],"data":[[0,1,2,3],[1,4,5,6]]}"#,
            "pandas' orient=\"split\" (its columns by name, its index skipped), its value 't' skipped",
        ),
        (
            r#"{"schema":{"fields":[]},"data":[{"index":0,"a":1,"b":2,"c":3},{"index":1,"a":4,"b":5,"c":6}]}"#,
            "pandas' orient=\"table\"",
        ),
        // MATLAB's jsonencode(struct("frames", F, "fs", 10)).
        (
            r#"{"frames":[[1,2,3],[4,5,6]],"fs":10}"#,
            "its key 'frames'",
        ),
        // pandas' to_json(orient="records", lines=True), and a logger's record a line.
        (
            "{\"a\":1,\"b\":2,\"c\":3}\n{\"a\":4,\"b\":5,\"c\":6}\n",
            "an object a frame (pandas' orient=\"records\", lines=True)",
        ),
        (
            "{\"t\":0.0,\"v\":[1,2,3]}\n{\"t\":0.1,\"v\":[4,5,6]}\n",
            "each frame its line's 'v'",
        ),
        // A logger's events among its frames' lines: skipped and said (the first was read as
        // a frame of named values, "\"start\" is not a number").
        (
            "{\"event\":\"start\",\"rate_hz\":10}\n{\"t\":0.0,\"v\":[1,2,3]}\n\
             {\"event\":\"calibrated\"}\n{\"t\":0.1,\"v\":[4,5,6]}\n",
            "and 2 lines without 'v' (lines 1, 3, from 1: a logger's other records)",
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        assert!(reads_as_table(&f), "{text}");
        let r = read(&f, 3).unwrap();
        assert_eq!(r.frames, plain, "{text}");
        assert!(r.description.contains(said), "{text}: {}", r.description);
    }
    // A Series (one object of values) is one frame; objects of several arrays, or of a column
    // with other rows, are said.
    std::fs::write(&f, r#"{"a":1,"b":2,"c":3}"#).unwrap();
    assert_eq!(read(&f, 3).unwrap().frames, [vec![1.0_f32, 2.0, 3.0]]);
    for (text, said) in [
        (
            r#"{"a":[[1,2,3]],"b":[[4,5,6]]}"#,
            "an object of 2 arrays (a, b)",
        ),
        (
            r#"{"a":{"0":1,"1":4},"b":{"0":2,"2":5}}"#,
            "its column 'b' has other rows",
        ),
        (
            "{\"v\":[1,2,3]}\n7\n",
            "JSON line 2 (from 1) is a value alone",
        ),
        (
            r#"{"a":{"0":1,"1":4},"b":{"0":2,"1":"x"}}"#,
            "'b', its '1': \"x\" is not a number",
        ),
    ] {
        std::fs::write(&f, text).unwrap();
        let e = read(&f, 3).unwrap_err().to_string();
        assert!(e.contains(said), "{text}: {e}");
    }
    std::fs::write(&f, "{\"format\": \"et-recording\", \"version\": 1}\n").unwrap();
    assert!(!reads_as_table(&f));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// LabVIEW's measurement files (`.lvm`, Write To Measurement File): its headers, time and
/// comment columns left out, its units read, its segments one after another, decimal commas;
/// a message names the file's own line (they were "'Writer_Version' is not a number").
#[test]
fn labview_measurement_files_are_read() {
    let dir = tmp("lvm");
    let f = dir.join("run.lvm");
    let head = |separator: &str, decimal: &str| {
        format!(
            "LabVIEW Measurement\t\nWriter_Version\t2\nReader_Version\t2\nSeparator\t{separator}\n\
             Decimal_Separator\t{decimal}\nMulti_Headings\tNo\nX_Columns\tOne\n\
             Time_Pref\tRelative\nDate\t2026/12/07\nTime\t10:00:00.000\n***End_of_Header***\t\n\t\n"
        )
    };
    let segment = |units: &str| {
        format!(
            "Channels\t3\t\nSamples\t2\t2\t2\t\nY_Unit_Label\t{units}\t{units}\t{units}\t\n\
             X_Dimension\tTime\tTime\tTime\t\nDelta_X\t1.0\t1.0\t1.0\t\n***End_of_Header***\t\n"
        )
    };
    let names = "X_Value\tUntitled\tUntitled 1\tUntitled 2\tComment\n";
    // Tab-separated, in mV, two segments, a comment on one row, a value missing.
    let text = head("Tab", ".")
        + &segment("mV")
        + names
        + "0.0\t1.0\t2.0\t3.0\tfirst press\n1.0\t4.0\t5.0\t6.0\n"
        + &segment("mV")
        + names
        + "2.0\t7.0\t\t9.0\n";
    std::fs::write(&f, &text).unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!(r.frames.len(), 3);
    assert!((r.frames[1][2] - 6e-3).abs() < 1e-9, "{:?}", r.frames);
    assert_eq!(r.gaps, [2]);
    assert!(
        r.description.contains("a LabVIEW measurement file, ")
            && r.description
                .contains("its values read as volts (mV x 1e-3, as its columns' names say)"),
        "{}",
        r.description
    );
    // A special header between the file's and the segment's is a header too.
    let special = head("Tab", ".")
        + "***Start_Special***\nNotes\tpressed by hand\n***End_Special***\n"
        + &segment("V")
        + names
        + "0.0\t1e-3\t2e-3\t3e-3\n1.0\t4e-3\t5e-3\t6e-3\n";
    std::fs::write(&f, &special).unwrap();
    assert_eq!(
        read(&f, 3).unwrap().frames,
        [vec![1e-3_f32, 2e-3, 3e-3], vec![4e-3, 5e-3, 6e-3]]
    );
    // Commas between cells, in volts; tabs with decimal commas.
    let comma = head("Comma", ".").replace('\t', ",")
        + &segment("Volts").replace('\t', ",")
        + &names.replace('\t', ",")
        + "0.0,1e-3,2e-3,3e-3\n1.0,4e-3,5e-3,6e-3,\n";
    let decimal = head("Tab", ",")
        + &segment("V")
        + names
        + "0,0\t0,001\t0,002\t0,003\n1,0\t0,004\t0,005\t0,006\n";
    for text in [comma, decimal] {
        std::fs::write(&f, &text).unwrap();
        let r = read(&f, 3).unwrap();
        assert_eq!(
            r.frames,
            [vec![1e-3_f32, 2e-3, 3e-3], vec![4e-3, 5e-3, 6e-3]],
            "{text}"
        );
    }
    // A channel in another unit (an impedance's Ohm) is said, its values taken as volts (it
    // was left in the name without a word).
    let text = head("Tab", ".") + &segment("Ohm") + names + "0.0\t1.0\t2.0\t3.0\n";
    std::fs::write(&f, &text).unwrap();
    let r = read(&f, 3).unwrap();
    assert_eq!(r.frames, [vec![1.0_f32, 2.0, 3.0]]);
    assert!(
        r.description
            .contains("Y_Unit_Label 'Ohm' not a unit of voltage"),
        "{}",
        r.description
    );
    // A damaged sample is named by the file's line and column (its time's counted: it was
    // the column among the channels, one less).
    let text = head("Tab", ".") + &segment("V") + names + "0.0\t1.0\t2.0\t3.0\n1.0\t4.0\tx\t6.0\n";
    std::fs::write(&f, &text).unwrap();
    let e = read(&f, 3).unwrap_err().to_string();
    assert!(
        e.contains("run.lvm:21: column 3: 'x' is not a number"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// MATLAB's default `save` compresses each variable: such a file is read as the plain one,
/// and a damaged compressed variable is refused in words before matfile inflates it (matfile
/// reads a compressed variable to its end, without a limit, and prints debug text on errors).
#[test]
fn compressed_matlab_variables_are_read_and_checked_first() {
    use std::io::Write as _;
    let dir = tmp("matz");
    let v = DMatrix::from_row_slice(2, 3, &[1e-3, 4e-3, 7e-3, 2e-3, 5e-3, 8e-3]);
    let plain = mat_v5("v", &v);
    // The header, then the variable's element (tag and data) compressed as one miCOMPRESSED.
    let mut z = libflate::zlib::Encoder::new(Vec::new()).unwrap();
    z.write_all(&plain[128..]).unwrap();
    let deflated = z.finish().into_result().unwrap();
    let mut file = plain[..128].to_vec();
    file.extend(15u32.to_le_bytes());
    file.extend((deflated.len() as u32).to_le_bytes());
    file.extend(&deflated);
    let f = dir.join("z.mat");
    std::fs::write(&f, &file).unwrap();
    assert_eq!(read(&f, 2).unwrap().frames, read_plain(&dir, &plain));
    let mut damaged = file.clone();
    let n = damaged.len();
    damaged[n - 12..n - 4].fill(0xA5);
    std::fs::write(&f, &damaged).unwrap();
    let e = read(&f, 2).unwrap_err().to_string();
    assert!(e.contains("compressed variable is damaged"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An int32 array as scipy's `savemat` writes it (class int32, its values as miINT32, the
/// name as a small element): read exactly, negative values too, compressed or not (matfile
/// alone refused it as "not a MATLAB version 5 or 7 file").
#[test]
fn int32_matlab_arrays_as_scipy_writes_them() {
    use std::io::Write as _;
    let dir = tmp("mat-int32");
    let word = |v: u32| v.to_le_bytes();
    let values: [i32; 6] = [-3, 1, -2, 2, 7, -2_000_000_000];
    let mut body = Vec::new();
    body.extend(word(6)); // array flags: miUINT32, 8 bytes
    body.extend(word(8));
    body.extend(word(12)); // class int32
    body.extend(word(0));
    body.extend(word(5)); // dimensions: miINT32, 8 bytes: 2 x 3
    body.extend(word(8));
    body.extend(word(2));
    body.extend(word(3));
    body.extend(word((1 << 16) | 1)); // the name 'v', a small element of miINT8
    body.extend(b"v\0\0\0");
    body.extend(word(5)); // the values, miINT32, column-major
    body.extend(word(24));
    values.iter().for_each(|v| body.extend(v.to_le_bytes()));
    let mut file = b"MATLAB 5.0 MAT-file, Platform: posix, Created by: scipy".to_vec();
    file.resize(116, b' ');
    file.extend([0u8; 8]);
    file.extend(0x0100u16.to_le_bytes());
    file.extend(b"IM");
    let header = file.clone();
    file.extend(word(14));
    file.extend(word(body.len() as u32));
    file.extend(&body);
    let mut z = libflate::zlib::Encoder::new(Vec::new()).unwrap();
    z.write_all(&file[128..]).unwrap();
    let deflated = z.finish().into_result().unwrap();
    let mut compressed = header;
    compressed.extend(word(15));
    compressed.extend(word(deflated.len() as u32));
    compressed.extend(&deflated);
    let f = dir.join("i.mat");
    for bytes in [&file, &compressed] {
        std::fs::write(&f, bytes).unwrap();
        let r = read(&f, 3).unwrap();
        // Column-major 2 x 3: rows (-3, -2, 7) and (1, 2, -2e9), K = 3 per row.
        assert_eq!(r.frames, vec![vec![-3.0, -2.0, 7.0], vec![1.0, 2.0, -2e9]]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Writes MATLAB version 5 elements in one byte order, as MATLAB does (small elements for
/// names of up to 4 bytes, empty names for a struct's fields).
struct Mat {
    little: bool,
}

impl Mat {
    fn word(&self, v: u32) -> [u8; 4] {
        if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }

    fn element(&self, kind: u32, data: &[u8]) -> Vec<u8> {
        let mut out = [self.word(kind), self.word(data.len() as u32)].concat();
        out.extend(data);
        out.resize(out.len().next_multiple_of(8), 0);
        out
    }

    fn array(&self, class: u32, dims: [u32; 2], name: &str, rest: &[u8]) -> Vec<u8> {
        let mut body = self.element(6, &[self.word(class), self.word(0)].concat());
        body.extend(self.element(5, &[self.word(dims[0]), self.word(dims[1])].concat()));
        if (1..=4).contains(&name.len()) {
            body.extend(self.word(((name.len() as u32) << 16) | 1));
            let mut padded = name.as_bytes().to_vec();
            padded.resize(4, 0);
            body.extend(padded);
        } else {
            body.extend(self.element(1, name.as_bytes()));
        }
        body.extend(rest);
        self.element(14, &body)
    }

    /// A rows x cols double matrix from its values by columns.
    fn doubles(&self, name: &str, rows: u32, cols: u32, values: &[f64]) -> Vec<u8> {
        let bytes: Vec<u8> = (values.iter())
            .flat_map(|v| {
                if self.little {
                    v.to_le_bytes()
                } else {
                    v.to_be_bytes()
                }
            })
            .collect();
        self.array(6, [rows, cols], name, &self.element(9, &bytes))
    }

    /// A 1 x 1 struct of `fields` (each an array element, its name empty).
    fn structure(&self, name: &str, fields: &[(&str, Vec<u8>)]) -> Vec<u8> {
        let mut rest = [self.word((4 << 16) | 5), self.word(32)].concat();
        let names: Vec<u8> = (fields.iter())
            .flat_map(|(n, _)| {
                let mut b = n.as_bytes().to_vec();
                b.resize(32, 0);
                b
            })
            .collect();
        rest.extend(self.element(1, &names));
        fields.iter().for_each(|(_, f)| rest.extend(f));
        self.array(2, [1, 1], name, &rest)
    }

    fn file(&self, elements: &[Vec<u8>], compressed: bool) -> Vec<u8> {
        use std::io::Write as _;
        let mut out = b"MATLAB 5.0 MAT-file, written as MATLAB writes EIDORS data".to_vec();
        out.resize(124, b' ');
        out.extend(if self.little { [0, 1] } else { [1, 0] });
        out.extend(if self.little { b"IM" } else { b"MI" });
        for e in elements {
            if compressed {
                let mut z = libflate::zlib::Encoder::new(Vec::new()).unwrap();
                z.write_all(e).unwrap();
                let deflated = z.finish().into_result().unwrap();
                out.extend(self.word(15));
                out.extend(self.word(deflated.len() as u32));
                out.extend(deflated);
            } else {
                out.extend(e);
            }
        }
        out
    }
}

/// EIDORS keeps its data in structs (`vh.meas`, `vi.meas`), which the MATLAB reader skips:
/// a struct's numeric fields are read by their dotted names, nested too, in either byte
/// order, compressed or not, and offered by name when none is given (such a file was "no
/// numeric arrays", and `data.mat:vh.meas` "no numeric array 'vh.meas' (it has: )").
#[test]
fn eidors_structs_fields_are_read_by_their_dotted_names() {
    let dir = tmp("mat-struct");
    let f = dir.join("eidors.mat");
    for (little, compressed) in [(true, false), (true, true), (false, false), (false, true)] {
        let m = Mat { little };
        // A char field (the data's name) is text, skipped.
        let text = m.array(4, [1, 2], "", &m.element(17, &[b'v', 0, b'h', 0]));
        let vh = m.structure(
            "vh",
            &[
                ("name", text),
                ("meas", m.doubles("", 2, 1, &[1e-3, 2e-3])),
                (
                    "sub",
                    m.structure("", &[("volts", m.doubles("", 1, 2, &[5e-3, 6e-3]))]),
                ),
            ],
        );
        let vi = m.structure(
            "vi",
            &[(
                "meas",
                m.doubles("", 2, 3, &[1e-3, 2e-3, 3e-3, 4e-3, 5e-3, 6e-3]),
            )],
        );
        std::fs::write(&f, m.file(&[vh, vi], compressed)).unwrap();
        let at = |name: &str| dir.join(format!("eidors.mat:{name}"));
        let r = read(&at("vi.meas"), 2).unwrap();
        assert_eq!(
            r.frames,
            vec![vec![1e-3, 2e-3], vec![3e-3, 4e-3], vec![5e-3, 6e-3]]
        );
        assert!(
            r.description.contains("variable 'vi.meas'"),
            "{}",
            r.description
        );
        assert_eq!(
            read(&at("vh.meas"), 2).unwrap().frames,
            vec![vec![1e-3, 2e-3]]
        );
        assert_eq!(
            read(&at("vh.sub.volts"), 2).unwrap().frames,
            vec![vec![5e-3, 6e-3]]
        );
        let e = read(&f, 2).unwrap_err().to_string();
        assert!(
            e.contains("(vh.meas, vh.sub.volts, vi.meas): name one as"),
            "{little} {compressed}: {e}"
        );
        for name in ["vh", "vh.name"] {
            let e = read(&at(name), 2).unwrap_err().to_string();
            assert!(
                e.contains(&format!("no numeric array '{name}' (it has: vh.meas,")),
                "{e}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

fn read_plain(dir: &Path, bytes: &[u8]) -> Vec<Vec<f32>> {
    let f = dir.join("plain.mat");
    std::fs::write(&f, bytes).unwrap();
    read(&f, 2).unwrap().frames
}

/// Files that hold nothing to read as frames say so, and what to store instead, rather
/// than "0 arrays (): name one" or a parser's internal message; booleans are not voltages.
#[test]
fn files_without_frames_say_what_they_hold() {
    let dir = tmp("nothing");
    // An .npz without arrays (numpy.savez with no arguments).
    let npz = dir.join("none.npz");
    std::fs::write(&npz, et_learn::npz::Writer::new().finish().unwrap()).unwrap();
    let e = read(&npz, 3).unwrap_err().to_string();
    assert!(e.contains("no arrays") && !e.contains("name one"), "{e}");
    // A MATLAB file of no numeric variable: its header alone.
    let m = DMatrix::from_row_slice(2, 3, &[1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    let mat = dir.join("none.mat");
    std::fs::write(&mat, &mat_v5("x", &m)[..128]).unwrap();
    let e = read(&mat, 3).unwrap_err().to_string();
    assert!(
        e.contains("no numeric arrays") && e.contains("matrix of numbers"),
        "{e}"
    );
    // MATLAB's version 4 format (`save -v4`, scipy's format='4'): a 20-byte header of
    // int32 (type 0 = little-endian doubles, rows, columns, imaginary, name length), the
    // name and the values; no text header.
    let mut v4 = Vec::new();
    for word in [0i32, 2, 3, 0, 2] {
        v4.extend(word.to_le_bytes());
    }
    v4.extend(b"x\0");
    v4.extend(m.iter().flat_map(|v| v.to_le_bytes()));
    let old = dir.join("v4.mat");
    std::fs::write(&old, &v4).unwrap();
    let e = read(&old, 3).unwrap_err().to_string();
    assert!(e.contains("version 4") && e.contains("-v7"), "{e}");
    // A boolean .npy (numpy's `frames > 0`).
    let mut npy = b"\x93NUMPY\x01\x00".to_vec();
    let header = "{'descr': '|b1', 'fortran_order': False, 'shape': (2, 3), }";
    let header = format!("{header:<117}\n");
    npy.extend(u16::try_from(header.len()).unwrap().to_le_bytes());
    npy.extend(header.as_bytes());
    npy.extend([1u8, 0, 1, 1, 1, 0]);
    let b = dir.join("b.npy");
    std::fs::write(&b, &npy).unwrap();
    let e = read(&b, 3).unwrap_err().to_string();
    assert!(e.contains("booleans") && e.contains("not voltages"), "{e}");
    // An et dataset's CSV (`et collect`): its columns were read as a frame's values and
    // refused for its K ("1080 x 101 values").
    let dataset = dir.join("train.csv");
    std::fs::write(
        &dataset,
        "# et-dataset 2\n# feature_index: 0 1 2\nf0,f1,f2,label,x_m,y_m,visit\n1,2,3,0,0,0,0\n",
    )
    .unwrap();
    let e = read(&dataset, 3).unwrap_err().to_string();
    assert!(
        e.contains("train.csv:1: an et dataset") && e.contains("et train --data"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
