//! EIDORS's stimulation struct arrays read as protocols (`pairs::stimulation`): SciPy's
//! writing of them (tests/data/eidors_stim.mat, made by tests/data/make_eidors_stim.py) and
//! MATLAB's compact one, written here; each against the protocol EIDORS documents.

use et_host::pairs::*;
use std::path::{Path, PathBuf};

/// SciPy's file: `stim` (16 electrodes, adjacent, EIDORS's defaults, 10 mA) and
/// `fmdl.stimulation` (8 electrodes, opposite drive, rotate_meas and meas_current, 1 mA).
fn scipy_file() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/eidors_stim.mat")
}

fn rows(c: &Crossed) -> Vec<[u16; 4]> {
    (c.schedule.rows().iter())
        .map(|r| [r.source, r.sink, r.positive, r.negative])
        .collect()
}

/// EIDORS's protocol as its documentation describes it (from 0): injection k drives
/// `-I` at electrode k + inj[0] and `+I` at k + inj[1] (so the source is the second);
/// measurement j is `u(j + ofs) - u(j + ofs + 1)`, `ofs` = k with rotate_meas; the ones on a
/// drive electrode left out unless meas_current.
fn eidors(l: u16, inj: [u16; 2], rotate: bool, meas_current: bool) -> Vec<[u16; 4]> {
    let mut out = Vec::new();
    for k in 0..l {
        let (sink, source) = ((k + inj[0]) % l, (k + inj[1]) % l);
        let ofs = if rotate { k } else { 0 };
        for j in 0..l {
            let (p, n) = ((j + ofs) % l, (j + ofs + 1) % l);
            if meas_current || ![p, n].iter().any(|e| *e == source || *e == sink) {
                out.push([source, sink, p, n]);
            }
        }
    }
    out
}

#[test]
fn scipy_stimulation_struct_arrays_are_eidors_protocols() {
    let file = scipy_file();
    let spec = |name: &str| PathBuf::from(format!("{}:{name}", file.display()));
    let c = stimulation(&spec("stim"), &Crossing::default()).unwrap();
    assert_eq!(rows(&c), eidors(16, [0, 1], false, false));
    // The same uncompressed (save -v6).
    let v6 = PathBuf::from(format!(
        "{}:stim",
        file.with_file_name("eidors_stim_v6.mat").display()
    ));
    assert_eq!(
        stimulation(&v6, &Crossing::default()).unwrap().schedule,
        c.schedule
    );
    assert_eq!(c.schedule.rows().len(), 208);
    assert!(c.schedule.rows().iter().all(|r| r.current_a == 0.010));
    let said = c.said.join("\n");
    assert!(
        said.contains("13 each") && said.contains("from 0"),
        "{said}"
    );
    // A forward model's field, its measurements turning with the drive, counted from 1.
    let crossing = Crossing {
        base: Some(1),
        ..Crossing::default()
    };
    let c = stimulation(&spec("fmdl.stimulation"), &crossing).unwrap();
    assert_eq!(rows(&c), eidors(8, [0, 4], true, true));
    assert!(c.schedule.rows().iter().all(|r| r.current_a == 0.001));
    assert!(
        c.to_csv()
            .starts_with("source,sink,positive,negative,current_a\n5,1,1,2,")
    );
    // no_meas_current asked of et: the values on each drive's electrodes left out.
    let crossing = Crossing {
        no_meas_current: true,
        ..Crossing::default()
    };
    let c = stimulation(&spec("fmdl.stimulation"), &crossing).unwrap();
    assert_eq!(rows(&c), eidors(8, [0, 4], true, false));
    // Two struct arrays and none named; a name it does not have; a numeric variable.
    let e = stimulation(&file, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("stim, fmdl.stimulation") && e.contains(":NAME"),
        "{e}"
    );
    let e = (stimulation(&spec("fmdl"), &Crossing::default()).unwrap_err()).to_string();
    assert!(
        e.contains("no struct array 'fmdl'") && e.contains("it has: stim"),
        "{e}"
    );
    // Given as a list of injections or measurements: the command that reads it whole.
    let e = cross(&spec("stim"), &spec("stim"), &Crossing::default()).unwrap_err();
    let e = e.to_string();
    assert!(
        e.contains("struct arrays stim, fmdl.stimulation") && e.contains("--stimulation"),
        "{e}"
    );
    // Other files given for it, said as what they are.
    let dir = std::env::temp_dir().join(format!("et-eidors-other-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (bytes, said) in [
        (
            &b"source,sink,positive,negative\n0,1,2,3\n"[..],
            "text, not a MATLAB .mat file: EIDORS's stimulation is read from the struct array \
             saved from MATLAB (save('stim.mat', 'stim')); lists or patterns of pairs go to \
             --injections",
        ),
        (
            &b"\x93NUMPY\x01\x00"[..],
            "a NumPy .npy array, not a MATLAB .mat file",
        ),
        (&b""[..], "an empty file, not a MATLAB .mat file"),
        (
            &b"MATLAB 7.3 MAT-file, Platform: GLNXA64"[..],
            "save('stim.mat', 'stim', '-v7')",
        ),
    ] {
        let other = dir.join("other.mat");
        std::fs::write(&other, bytes).unwrap();
        let e = stimulation(&other, &Crossing::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains(said), "{e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
    // Flags that do not fit: another sheet's electrodes, a pattern's orientation.
    let crossing = Crossing {
        electrodes: Some(32),
        ..Crossing::default()
    };
    let e = stimulation(&spec("stim"), &crossing)
        .unwrap_err()
        .to_string();
    assert!(e.contains("-l 16"), "{e}");
    let crossing = Crossing {
        by: Some(By::Rows),
        ..Crossing::default()
    };
    let e = stimulation(&spec("stim"), &crossing)
        .unwrap_err()
        .to_string();
    assert!(e.contains("leave it out"), "{e}");
}

/// A field's value as MATLAB's writer stores it.
enum Value {
    /// A double array of small integers, kept as int8 (MATLAB stores values in the smallest
    /// type that holds them), by columns.
    Dense(usize, usize, Vec<i8>),
    /// A sparse double array: (row, column, value) by columns.
    Sparse(usize, usize, Vec<(usize, usize, f64)>),
    /// Text.
    Text(&'static str),
}

/// A data element: the small form (type and size in one word) where its data fit in 4
/// bytes, as MATLAB writes them, else the long form padded to 8 bytes.
fn element(out: &mut Vec<u8>, kind: u32, data: &[u8]) {
    if data.len() <= 4 && !data.is_empty() {
        let start = out.len();
        out.extend(((data.len() as u32) << 16 | kind).to_le_bytes());
        out.extend(data);
        out.resize(start + 8, 0);
    } else {
        out.extend(kind.to_le_bytes());
        out.extend((data.len() as u32).to_le_bytes());
        out.extend(data);
        out.resize(out.len().next_multiple_of(8), 0);
    }
}

/// An array element (miMATRIX) of `class`, `[rows, columns]`, `name` and its sub-elements.
fn array(class: u8, nzmax: u32, dims: [usize; 2], name: &str, body: &[u8]) -> Vec<u8> {
    let mut inner = Vec::new();
    let mut flags = vec![class, 0, 0, 0];
    flags.extend(nzmax.to_le_bytes());
    element(&mut inner, 6, &flags);
    let dims: Vec<u8> = dims
        .iter()
        .flat_map(|d| (*d as i32).to_le_bytes())
        .collect();
    element(&mut inner, 5, &dims);
    element(&mut inner, 1, name.as_bytes());
    inner.extend(body);
    let mut out = Vec::new();
    element(&mut out, 14, &inner);
    out
}

fn value(v: &Value) -> Vec<u8> {
    let mut body = Vec::new();
    match v {
        Value::Dense(r, c, values) => {
            let bytes: Vec<u8> = values.iter().map(|v| *v as u8).collect();
            element(&mut body, 1, &bytes);
            array(6, 0, [*r, *c], "", &body)
        }
        Value::Sparse(r, c, entries) => {
            let ir: Vec<u8> = (entries.iter())
                .flat_map(|e| (e.0 as i32).to_le_bytes())
                .collect();
            let jc: Vec<u8> = (0..=*c)
                .flat_map(|col| (entries.iter().filter(|e| e.1 < col).count() as i32).to_le_bytes())
                .collect();
            let pr: Vec<u8> = entries.iter().flat_map(|e| e.2.to_le_bytes()).collect();
            element(&mut body, 5, &ir);
            element(&mut body, 5, &jc);
            element(&mut body, 9, &pr);
            array(5, entries.len() as u32, [*r, *c], "", &body)
        }
        Value::Text(t) => {
            let chars: Vec<u8> = t.encode_utf16().flat_map(u16::to_le_bytes).collect();
            element(&mut body, 4, &chars);
            array(4, 0, [1, t.len()], "", &body)
        }
    }
}

/// A MATLAB file of the 1 x n struct array `name` whose elements hold `stimulation`,
/// `stim_pattern` and `meas_pattern`.
fn mat_stim(dir: &Path, name: &str, elements: &[[Value; 2]]) -> PathBuf {
    let mut body = Vec::new();
    element(&mut body, 5, &32_i32.to_le_bytes());
    let mut names = Vec::new();
    for field in ["stimulation", "stim_pattern", "meas_pattern"] {
        let mut n = field.as_bytes().to_vec();
        n.resize(32, 0);
        names.extend(n);
    }
    element(&mut body, 1, &names);
    for [stim, meas] in elements {
        body.extend(value(&Value::Text("Amp")));
        body.extend(value(stim));
        body.extend(value(meas));
    }
    let mut file = b"MATLAB 5.0 MAT-file, written as MATLAB writes a struct array".to_vec();
    file.resize(116, b' ');
    file.extend([0u8; 8]);
    file.extend(0x0100u16.to_le_bytes());
    file.extend(b"IM");
    file.extend(array(2, 0, [1, elements.len()], name, &body));
    let path = dir.join(format!("{name}.mat"));
    std::fs::write(&path, file).unwrap();
    path
}

/// EIDORS's own unit test of mk_stim_patterns(4,1,[0,1],[0,1],{},1): stim(1).stim_pattern
/// = [-1;1;0;0] and meas_pattern = [0,0,1,-1]; stim(4)'s [1;0;0;-1] and [0,1,-1,0]. Written
/// as MATLAB stores them (int8 values of doubles, small elements, sparse and dense mixed)
/// and read as those rows; the unit current asked to be given; faults named by element.
#[test]
fn matlab_compact_struct_arrays_and_their_faults() {
    let dir = std::env::temp_dir().join(format!("et-eidors-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let element = |k: usize| -> [Value; 2] {
        let mut stim = vec![0i8; 4];
        (stim[k], stim[(k + 1) % 4]) = (-1, 1);
        let (p, n) = ((k + 2) % 4, (k + 3) % 4);
        if k.is_multiple_of(2) {
            let mut entries = vec![(0, p, 1.0), (0, n, -1.0)];
            entries.sort_by_key(|e| e.1);
            [Value::Dense(4, 1, stim), Value::Sparse(1, 4, entries)]
        } else {
            let mut meas = vec![0i8; 4];
            (meas[p], meas[n]) = (1, -1);
            let mut entries: Vec<_> = (0..4)
                .filter(|&i| stim[i] != 0)
                .map(|i| (i, 0, f64::from(stim[i])))
                .collect();
            entries.sort_by_key(|e| e.0);
            [Value::Sparse(4, 1, entries), Value::Dense(1, 4, meas)]
        }
    };
    let file = mat_stim(&dir, "stim", &(0..4).map(element).collect::<Vec<_>>());
    let e = stimulation(&file, &Crossing::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("unit current") && e.contains("--current-a"),
        "{e}"
    );
    let crossing = Crossing {
        current_a: Some(1e-3),
        ..Crossing::default()
    };
    let c = stimulation(&file, &crossing).unwrap();
    let expected = [[1, 0, 2, 3], [2, 1, 3, 0], [3, 2, 0, 1], [0, 3, 1, 2]];
    assert_eq!(rows(&c), expected);
    // Given as frames, said as a protocol (its 4 stim_patterns were read as 4 frames).
    let e = et_host::frames::read(&file, 16).unwrap_err().to_string();
    assert!(e.contains("holds EIDORS's stimulation 'stim'"), "{e}");
    // Injections of other measurement counts (EIDORS's no_redundant keeps fewer under the
    // later ones): each its own, in order; a second injection measuring on its drive
    // electrodes too (meas_current), two rows, the second -1 before +1.
    let two = Value::Sparse(
        2,
        4,
        vec![(1, 0, -1.0), (0, 2, 1.0), (0, 3, -1.0), (1, 3, 1.0)],
    );
    let file = mat_stim(
        &dir,
        "varied",
        &[element(0), [Value::Dense(4, 1, vec![0, -1, 1, 0]), two]],
    );
    let c = stimulation(&file, &crossing).unwrap();
    assert_eq!(rows(&c), [[1, 0, 2, 3], [2, 1, 2, 3], [2, 1, 3, 0]]);
    assert!(c.said.join(" ").contains("(1 to 2)"), "{:?}", c.said);
    // Faults, each named by its element and field.
    let drive = Value::Dense(4, 1, vec![2, 0, -2, 0]);
    let nan = Value::Sparse(1, 4, vec![(0, 1, f64::NAN), (0, 2, 1.0), (0, 3, -1.0)]);
    let cases: [(&str, [Value; 2], &str); 5] = [
        (
            "nan",
            [Value::Dense(4, 1, vec![-1, 1, 0, 0]), nan],
            "stim(2).meas_pattern: its entry (1, 2) is NaN",
        ),
        (
            "mono",
            [
                Value::Dense(4, 1, vec![1, 0, 0, 0]),
                Value::Dense(1, 4, vec![0, 0, 1, -1]),
            ],
            "stim(2).stim_pattern: 1 entry above 0 and no entry below",
        ),
        (
            "transposed",
            [
                Value::Dense(4, 1, vec![-1, 1, 0, 0]),
                Value::Dense(4, 1, vec![0, 0, 1, -1]),
            ],
            "stim(2).meas_pattern: 4 x 1, where it is a row a measurement of the 4 electrodes",
        ),
        (
            "text",
            [drive, Value::Text("ad")],
            "stim(2).meas_pattern: not a matrix of real numbers",
        ),
        (
            "sheets",
            [
                Value::Dense(6, 1, vec![-1, 1, 0, 0, 0, 0]),
                Value::Dense(1, 6, vec![0, 0, 1, -1, 0, 0]),
            ],
            "stim(2).stim_pattern: 6 electrodes, where stim(1)'s are 4",
        ),
    ];
    for (case, second, said) in cases {
        let case_dir = dir.join(case);
        std::fs::create_dir_all(&case_dir).unwrap();
        let file = mat_stim(&case_dir, "stim", &[element(0), second]);
        let e = stimulation(&file, &crossing).unwrap_err().to_string();
        assert!(e.contains(said), "{case}: {e}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// EIDORS's frames as a loop keeps them (`vi(k) = fwd_solve(img)`: a struct array of data
/// structs, each its `meas`), read as frames by the field's dotted name, compressed or not,
/// each element a frame in order; unnamed, the file's one array of K values.
#[test]
fn a_struct_arrays_field_of_frames_is_read() {
    for file in ["eidors_stim.mat", "eidors_stim_v6.mat"] {
        let path = scipy_file().with_file_name(file);
        let spec = PathBuf::from(format!("{}:vi.meas", path.display()));
        let r = et_host::frames::read(&spec, 208).unwrap();
        let expected: Vec<Vec<f32>> = (0..3)
            .map(|k| {
                (0..208)
                    .map(|j| (1e-3 * f64::from(k + 1) + 1e-6 * f64::from(j)) as f32)
                    .collect()
            })
            .collect();
        assert_eq!(r.frames, expected, "{file}");
        assert!(
            r.description.contains("struct array 'vi''s field 'meas'"),
            "{}",
            r.description
        );
        // Unnamed, the file's one array of K values is read, the model's nodes and the
        // loop's times beside it (it asked for a name: a struct's field's shape was unknown).
        let r = et_host::frames::read(&path, 208).unwrap();
        assert_eq!(r.frames, expected, "{file}");
        assert!(
            r.description
                .contains("the only one of its arrays with K = 208 values a frame")
                && r.description.contains("fmdl.nodes"),
            "{}",
            r.description
        );
        // Of another K, none is: asked for by name.
        let e = et_host::frames::read(&path, 16).unwrap_err().to_string();
        assert!(e.contains("vi.meas") && e.contains(":VARIABLE"), "{e}");
    }
    // The extension in capitals, as Windows tools write it (`RUN.MAT:vi.meas` was looked for
    // as a file of that name): read alike, frames and stimulation.
    let dir = std::env::temp_dir().join(format!("et-eidors-caps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let caps = dir.join("RUN.MAT");
    std::fs::copy(scipy_file(), &caps).unwrap();
    let spec = PathBuf::from(format!("{}:vi.meas", caps.display()));
    assert_eq!(et_host::frames::read(&spec, 208).unwrap().frames.len(), 3);
    let spec = PathBuf::from(format!("{}:stim", caps.display()));
    assert_eq!(
        stimulation(&spec, &Crossing::default())
            .unwrap()
            .schedule
            .rows()
            .len(),
        208
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // A model alone, its nodes beside its stimulation: said as the protocol's file, not its
    // nodes read as frames ("variable 'fmdl.nodes' read: 20 x 2 values"); the nodes named,
    // they are read as asked.
    let path = scipy_file().with_file_name("eidors_fmdl.mat");
    let e = et_host::frames::read(&path, 208).unwrap_err().to_string();
    let command = format!(
        "et protocol --stimulation {}:fmdl.stimulation",
        path.display()
    );
    assert!(
        e.contains("holds EIDORS's stimulation 'fmdl.stimulation'") && e.contains(&command),
        "{e}"
    );
    // A stimulation of one injection, a 1 x 1 struct of sparse patterns as SciPy writes it:
    // said as one too (it was "no numeric arrays").
    let one = scipy_file().with_file_name("eidors_one.mat");
    let e = et_host::frames::read(&one, 208).unwrap_err().to_string();
    assert!(e.contains("holds EIDORS's stimulation 'one'"), "{e}");
    let nodes = PathBuf::from(format!("{}:fmdl.nodes", path.display()));
    let e = et_host::frames::read(&nodes, 208).unwrap_err().to_string();
    assert!(e.contains("20 x 2 values"), "{e}");
}

/// EIDORS's stimulation of one injection (a 1 x 1 struct) is said as a stimulation; beside a
/// variable of its own of no frame's size, that variable is said by its size (frames of
/// another protocol?), not the file as the stimulation's alone.
#[test]
fn a_variable_beside_a_stimulation_is_said_by_its_size() {
    let dir = std::env::temp_dir().join(format!("et-eidors-beside-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pattern = [
        Value::Dense(4, 1, vec![-1, 1, 0, 0]),
        Value::Dense(1, 4, vec![0, 0, 1, -1]),
    ];
    let file = mat_stim(&dir, "stim", &[pattern]);
    // Of one injection, a 1 x 1 struct: alone, said as the stimulation too.
    let e = et_host::frames::read(&file, 16).unwrap_err().to_string();
    assert!(e.contains("holds EIDORS's stimulation 'stim'"), "{e}");
    let mut bytes = std::fs::read(&file).unwrap();
    let mut body = Vec::new();
    let values: Vec<u8> = (0..6).flat_map(|v| f64::from(v).to_le_bytes()).collect();
    element(&mut body, 9, &values);
    bytes.extend(array(6, 0, [3, 2], "V", &body));
    std::fs::write(&file, bytes).unwrap();
    let e = et_host::frames::read(&file, 16).unwrap_err().to_string();
    assert!(
        e.contains("variable 'V' read: 3 x 2 values") && !e.contains("EIDORS's stimulation"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
