//! Every file parser of et on damaged files: no panic, no abort, and no allocation beyond a
//! small multiple of the file's size.
//!
//! Each case takes a valid file (a scene, a dataset, a foreign CSV and its targets, a board or
//! table model, a model blob, a recording, another system's frames as CSV and `.mat`, a Gmsh
//! mesh, a CSV mesh) and damages it: bit flips, deletions, repeated
//! stretches (files that grow), extreme tokens inserted or put in place of a number (counts of
//! 10^20, 1e308, NaN, -1, a byte-order mark, stray separators, section names), truncation.
//! The parser reads it from disk as `et` would.
//!
//! Its own test binary: the peak-tracking allocator counts the whole process, so its tests take
//! turns, and the parsers are fuzzed in child processes of it, one per core, each with its own
//! count. Cases per parser from PROPTEST_CASES (default
//! 2 000); the long run of docs/guide.md:
//!
//! ```sh
//! PROPTEST_CASES=1000000 cargo test --release -p et-tests --test fuzz -- --nocapture
//! ```
//!
//! `ET_FUZZ_PARSERS` picks parsers by name (comma-separated parts of the names printed, e.g.
//! `ET_FUZZ_PARSERS=scene,mesh`), to spread a long run over several processes.

use std::path::{Path, PathBuf};
use std::time::Instant;

use et_core::ScanConfig;
use et_core::model::ModelKind;
use et_core::protocol::ProtocolKind;
use et_core::rng::Rng;
use et_host::recording::{Header, Record, Writer};
use et_learn::fit::{FitOptions, Fitted, Target};
use et_learn::model_file::ModelFile;
use et_learn::tabular::{Choice, Kind, Member, Table, TableModel, Tables, TrainOptions, Unit};
use nalgebra::DMatrix;
use peak_alloc::PeakAlloc;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

#[global_allocator]
static ALLOC: PeakAlloc = PeakAlloc;

/// The allocator's peak is the whole process's: the tests take turns, and the parsers are
/// fuzzed in child processes of this binary, one per core, each with its own peak.
static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Allowed peak allocation while parsing a file of `len` bytes: a multiple of it plus a
/// constant for the parser's fixed tables and buffers. The TOML parser is the hungriest: about
/// 100 bytes per byte of a file of many short keys (scenes are capped at 1 MiB for it).
fn allowance(len: usize) -> usize {
    128 * len + (4 << 20)
}

/// Tokens that break parsers.
const NASTY: &[&str] = &[
    "",
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-320",
    "NaN",
    "inf",
    "-inf",
    "18446744073709551615",
    "100000000000000000000",
    "4294967296",
    "65536",
    "2147483648",
    "3.5",
    "\u{feff}",
    "\r\n",
    "\n",
    ",",
    ";",
    "#",
    " ",
    "\"",
    "{",
    "}",
    "[",
    "]",
    "=",
    "null",
    "true",
    "\u{0}",
    "\u{fffd}",
    "$Nodes",
    "$EndNodes",
    "$Elements",
    "$EndElements",
    "$MeshFormat",
];

#[derive(Clone, Debug)]
enum Edit {
    Flip(usize, u8),
    Delete(usize, usize),
    Repeat(usize, usize, usize),
    Insert(usize, usize),
    /// The number at or after the position becomes a nasty token.
    Replace(usize, usize),
    Cut(usize),
}

fn edit() -> impl Strategy<Value = Edit> {
    let token = 0..NASTY.len();
    prop_oneof![
        2 => (any::<usize>(), 0u8..8).prop_map(|(i, b)| Edit::Flip(i, b)),
        1 => (any::<usize>(), 1usize..32).prop_map(|(i, n)| Edit::Delete(i, n)),
        1 => (any::<usize>(), 1usize..80, 1usize..3000).prop_map(|(i, n, k)| Edit::Repeat(i, n, k)),
        2 => (any::<usize>(), token.clone()).prop_map(|(i, t)| Edit::Insert(i, t)),
        4 => (any::<usize>(), token).prop_map(|(i, t)| Edit::Replace(i, t)),
        1 => any::<usize>().prop_map(Edit::Cut),
    ]
}

fn apply(seed: &[u8], edits: &[Edit]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for e in edits {
        let at = |i: usize, len: usize| if len == 0 { 0 } else { i % len };
        match *e {
            Edit::Flip(i, bit) if !b.is_empty() => {
                let i = at(i, b.len());
                b[i] ^= 1 << bit;
            }
            Edit::Delete(i, n) if !b.is_empty() => {
                let i = at(i, b.len());
                let end = (i + n).min(b.len());
                b.drain(i..end);
            }
            Edit::Repeat(i, n, k) if !b.is_empty() => {
                let i = at(i, b.len());
                let end = (i + n).min(b.len());
                let stretch = b[i..end].to_vec();
                let grown: Vec<u8> = std::iter::repeat_n(stretch, k).flatten().collect();
                b.splice(end..end, grown);
            }
            Edit::Insert(i, t) => {
                let i = at(i, b.len() + 1);
                b.splice(i..i, NASTY[t].bytes());
            }
            Edit::Replace(i, t) if !b.is_empty() => {
                let start = at(i, b.len());
                if let Some(s) = (start..b.len()).find(|&j| b[j].is_ascii_digit()) {
                    let e = (s..b.len())
                        .find(|&j| !(b[j].is_ascii_digit() || b"eE.+-".contains(&b[j])))
                        .unwrap_or(b.len());
                    b.splice(s..e, NASTY[t].bytes());
                }
            }
            Edit::Cut(i) => {
                let i = at(i, b.len() + 1);
                b.truncate(i);
            }
            _ => {}
        }
    }
    b
}

/// One parser under test: seed files (one or more, each fuzzed in turn) and how to read them.
struct Parser {
    name: &'static str,
    /// The files as the parser finds them on disk, valid.
    seeds: Vec<Vec<u8>>,
    /// Reads the files at these paths (as many as seeds); Ok or a typed error, never a panic.
    parse: fn(&[PathBuf]) -> bool,
}

/// A new folder for one test's or one parser's files (each test removes its own).
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("et-fuzz-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn small_config() -> ScanConfig {
    ScanConfig {
        electrodes: 8,
        protocol: ProtocolKind::Adjacent,
        ..ScanConfig::REFERENCE
    }
}

/// A structured square mesh, `n` x `n` cells, 4 electrodes (one boundary edge each), as Gmsh
/// 2.2 text and as the three CSV files.
fn square_mesh(n: usize) -> (String, [String; 3]) {
    use std::fmt::Write as _;
    let h = 0.1 / n as f64;
    let id = |i: usize, j: usize| j * (n + 1) + i;
    let mut msh = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    let mut nodes = String::from("x,y\n");
    let _ = writeln!(msh, "{}", (n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 * h, j as f64 * h);
            let _ = writeln!(msh, "{} {x} {y} 0", id(i, j) + 1);
            let _ = writeln!(nodes, "{x},{y}");
        }
    }
    let edges = [
        (id(1, 0), id(2, 0)),
        (id(n, 1), id(n, 2)),
        (id(n - 1, n), id(n - 2, n)),
        (id(0, n - 1), id(0, n - 2)),
    ];
    let mut electrodes = String::new();
    let _ = writeln!(msh, "$EndNodes\n$Elements\n{}", 4 + 2 * n * n);
    let mut k = 1;
    for (e, (a, b)) in edges.iter().enumerate() {
        let _ = writeln!(msh, "{k} 1 2 {} 1 {} {}", e + 1, a + 1, b + 1);
        let _ = writeln!(electrodes, "{a},{b}");
        k += 1;
    }
    let mut triangles = String::new();
    for j in 0..n {
        for i in 0..n {
            for t in [
                [id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                [id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ] {
                let _ = writeln!(msh, "{k} 2 2 1 1 {} {} {}", t[0] + 1, t[1] + 1, t[2] + 1);
                let _ = writeln!(triangles, "{},{},{}", t[0], t[1], t[2]);
                k += 1;
            }
        }
    }
    msh.push_str("$EndElements\n");
    (msh, [nodes, triangles, electrodes])
}

/// A small QDA model, as `et train` writes it.
fn model(dir: &Path) -> ModelFile {
    let mut rng = Rng::new(5);
    let (classes, per, p) = (3, 12, 4);
    let y: Vec<u16> = (0..classes * per).map(|r| (r / per) as u16).collect();
    let x = DMatrix::from_fn(y.len(), p, |r, _| {
        f64::from(y[r]) * 0.01 + 1e-3 * rng.normal()
    });
    let fitted = Fitted::fit(
        &x,
        &y,
        classes,
        &FitOptions {
            kind: ModelKind::Qda,
            shrinkage: 0.1,
            target: Target::Diagonal,
        },
    )
    .unwrap();
    let file = ModelFile::new(
        &fitted,
        0.1,
        small_config(),
        vec![0, 3, 7, 20],
        vec![[0.0, 0.0], [0.01, 0.0], [0.0, 0.01]],
        true,
    );
    let path = dir.join("seed-model.json");
    file.save(&path).unwrap();
    ModelFile::load(&path).unwrap()
}

fn model_json(dir: &Path) -> Vec<u8> {
    let path = dir.join("seed-model.json");
    model(dir).save(&path).unwrap();
    std::fs::read(path).unwrap()
}

/// A small table model of `method` (an average: of knn and kernel ridge, as `auto` may
/// choose; QDA: four classes from a 2 x 2 grid of positions), as `et train --features` writes
/// it.
fn table_model_json(dir: &Path, method: Kind) -> Vec<u8> {
    let mut rng = Rng::new(3);
    let n = 48;
    let positions: Vec<[f64; 2]> = (0..n)
        .map(|r| [(r % 7) as f64 * 3.0, (r % 5) as f64 * 4.0])
        .collect();
    let x = DMatrix::from_fn(n, 3, |r, j| {
        let [px, py] = positions[r];
        (0.1 * px).sin() * (j as f64 + 1.0)
            + 0.05 * py * py / (j as f64 + 1.0)
            + 0.02 * (1.0 + (r % 4) as f64) * rng.normal()
    });
    let table = Table {
        x,
        feature_names: ["a", "b", "c"].map(String::from).to_vec(),
        labels: None,
        // The positions above are mm; a table holds m.
        positions: Some(
            positions
                .iter()
                .map(|p| [p[0] * 1e-3, p[1] * 1e-3])
                .collect(),
        ),
        third: None,
        description: "fuzz seed".into(),
        first_row: 0,
        unit: Unit::Mm,
        groups: None,
    };
    let train = |m: Kind, grid| {
        let options = TrainOptions {
            folds: 3,
            grid,
            ..TrainOptions::default()
        };
        et_learn::tabular::train(&table, Choice::One(m), &options, &mut |_, _, _| {}).unwrap()
    };
    let model = if method == Kind::Average {
        let members = [Kind::Knn, Kind::KernelRidge].map(|m| {
            let fitted = train(m, None);
            Member {
                method: m,
                hyperparameters: fitted.hyperparameters,
                feature_mean: fitted.feature_mean,
                feature_scale: fitted.feature_scale,
                tables: fitted.tables,
            }
        });
        let mut model = train(Kind::Ridge, None);
        model.method = Kind::Average;
        model.tables = Tables::Average {
            members: members.to_vec(),
        };
        model
    } else {
        train(method, Some((2, 2)))
    };
    let path = dir.join("seed-table-model.json");
    model.save(&path).unwrap();
    std::fs::read(path).unwrap()
}

/// Another system's frames: 5 frames of the 8-electrode adjacent protocol's 40 values.
fn frames_matrix() -> DMatrix<f64> {
    DMatrix::from_fn(5, 40, |f, k| 1e-3 * (k as f64 + 1.0) + 1e-5 * f as f64)
}

fn frames_csv() -> String {
    let m = frames_matrix();
    (0..m.nrows())
        .map(|f| {
            let row: Vec<String> = m.row(f).iter().map(|v| format!("{v:e}")).collect();
            row.join(",") + "\n"
        })
        .collect()
}

/// The frames as a DAQ writes them: Excel's `sep=` line, a header naming a time column and a
/// label, a row of units, a value missing (the paths that leave columns and rows out).
fn frames_daq_csv() -> String {
    let m = frames_matrix();
    let names: Vec<String> = (0..m.ncols()).map(|k| format!("ch{k}")).collect();
    let mut text = format!(
        "sep=;\nTime;{};label\ns;{};\n",
        names.join(";"),
        ["mV"; 40].join(";")
    );
    for f in 0..m.nrows() {
        let mut row: Vec<String> = m.row(f).iter().map(|v| format!("{v:e}")).collect();
        if f == 2 {
            row[7] = String::new();
        }
        text += &format!("{};{};none\n", f as f64 * 0.01, row.join(";"));
    }
    text
}

/// The frames as JSON records, as pandas' `to_json(orient="records")` and Python's
/// `json.dump` write them: named values, a time, one value NaN.
fn frames_json() -> String {
    let m = frames_matrix();
    let rows: Vec<String> = (0..m.nrows())
        .map(|f| {
            let values: Vec<String> = (m.row(f).iter().enumerate())
                .map(|(k, v)| match (f, k) {
                    (1, 3) => format!("\"ch{k} (mV)\": NaN"),
                    _ => format!("\"ch{k} (mV)\": {:e}", v * 1e3),
                })
                .collect();
            format!("{{\"t\": {f}, {}}}", values.join(", "))
        })
        .collect();
    format!("[{}]", rows.join(",\n "))
}

/// The frames as pandas' `to_json()` writes them by default (`orient="columns"`: a key a
/// column, each an object of its values by the rows' index), a value missing among them.
fn frames_json_columns() -> String {
    let m = frames_matrix();
    let columns: Vec<String> = (0..m.ncols())
        .map(|k| {
            let rows: Vec<String> = (0..m.nrows())
                .map(|f| match (f, k) {
                    (1, 3) => format!("\"{f}\":null"),
                    _ => format!("\"{f}\":{:e}", m[(f, k)]),
                })
                .collect();
            format!("\"v{k}\":{{{}}}", rows.join(","))
        })
        .collect();
    format!("{{{}}}", columns.join(","))
}

/// The frames as a logger writes them, a JSON object a line (`{"t": 0.1, "v": [...]}`) after
/// a record of its own, and as pandas' `to_json(orient="split")` writes them: the readers of
/// JSON objects'.
fn frames_json_objects() -> [String; 2] {
    let m = frames_matrix();
    let row = |f: usize| -> Vec<String> { m.row(f).iter().map(|v| format!("{v:e}")).collect() };
    let lines: Vec<String> = (0..m.nrows())
        .map(|f| {
            format!(
                "{{\"t\": {}, \"v\": [{}]}}",
                f as f64 * 0.1,
                row(f).join(", ")
            )
        })
        .collect();
    let names: Vec<String> = (0..m.ncols()).map(|k| format!("\"v{k}\"")).collect();
    let rows: Vec<String> = (0..m.nrows())
        .map(|f| format!("[{}]", row(f).join(",")))
        .collect();
    let index: Vec<String> = (0..m.nrows()).map(|f| f.to_string()).collect();
    let split = format!(
        "{{\"columns\":[{}],\"index\":[{}],\"data\":[{}]}}",
        names.join(","),
        index.join(","),
        rows.join(",")
    );
    // (A logger's other records among its frames' lines, skipped.)
    let logged = format!("{{\"event\": \"start\"}}\n{}\n", lines.join("\n"));
    [logged, split]
}

/// The frames as LabVIEW's Write To Measurement File writes them (`.lvm`): its headers, a time
/// column, units, a comment on one row, two segments.
fn frames_lvm() -> String {
    let m = frames_matrix();
    let tabs = |cells: Vec<String>| cells.join("\t");
    let each = |word: &str| tabs(vec![word.to_string(); m.ncols()]);
    let mut text = "LabVIEW Measurement\t\nWriter_Version\t2\nSeparator\tTab\n\
                    Decimal_Separator\t.\n***End_of_Header***\t\n\t\n"
        .to_string();
    for (segment, rows) in [(0, 0..3), (1, 3..m.nrows())] {
        text += &format!(
            "Channels\t{}\nY_Unit_Label\t{}\n***End_of_Header***\t\nX_Value\t{}\tComment\n",
            m.ncols(),
            each("mV"),
            each("Untitled")
        );
        for f in rows {
            let row: Vec<String> = m.row(f).iter().map(|v| format!("{:e}", v * 1e3)).collect();
            let comment = if segment == 0 && f == 1 {
                "\tpressed"
            } else {
                ""
            };
            text += &format!("{}\t{}{comment}\n", f as f64 * 0.01, tabs(row));
        }
    }
    text
}

/// The frames as another system's `.npz` (one array, "frames").
fn frames_npz() -> Vec<u8> {
    let mut w = et_learn::npz::Writer::new();
    w.matrix("frames", &frames_matrix());
    w.finish().expect("a small archive")
}

/// A one-array archive of et's ([`frames_npz`]) with its array deflated, as
/// `numpy.savez_compressed` stores it (zip method 8; the local header, the directory entry's
/// sizes and the directory's offset rewritten to suit).
fn deflated_npz(stored: &[u8]) -> Vec<u8> {
    use std::io::Write as _;
    let u16_at = |at: usize| usize::from(u16::from_le_bytes([stored[at], stored[at + 1]]));
    let u32_at = |at: usize| u32::from_le_bytes(stored[at..at + 4].try_into().unwrap()) as usize;
    let (name_len, extra_len, size) = (u16_at(26), u16_at(28), u32_at(18));
    let data_at = 30 + name_len + extra_len;
    let mut encoder = libflate::deflate::Encoder::new(Vec::new());
    encoder.write_all(&stored[data_at..data_at + size]).unwrap();
    let packed = encoder.finish().into_result().unwrap();
    let mut local = stored[..data_at].to_vec();
    local[8..10].copy_from_slice(&8u16.to_le_bytes());
    local[18..22].copy_from_slice(&(packed.len() as u32).to_le_bytes());
    let mut central = stored[data_at + size..].to_vec();
    central[10..12].copy_from_slice(&8u16.to_le_bytes());
    central[20..24].copy_from_slice(&(packed.len() as u32).to_le_bytes());
    let end = central.len() - 22;
    let offset = (data_at + packed.len()) as u32;
    central[end + 16..end + 20].copy_from_slice(&offset.to_le_bytes());
    [local, packed, central].concat()
}

/// The frames as EIDORS keeps its data: a 1 x 1 struct `vi` whose field `meas` holds them
/// (the array [`et_host::frames::mat_v5`] writes, its name emptied as a struct's fields'
/// are).
fn frames_mat_struct() -> Vec<u8> {
    let plain = et_host::frames::mat_v5("v", &frames_matrix());
    let word = |v: u32| v.to_le_bytes().to_vec();
    // The array's sub-elements: flags and dimensions (32 bytes), its name (16), its values.
    let array = &plain[128 + 8..];
    let field = [&array[..32], &word(1), &word(0), &array[48..]].concat();
    let mut names = b"meas".to_vec();
    names.resize(32, 0);
    let body = [
        [word(6), word(8), word(2), word(0)].concat(), // flags: class struct
        [word(5), word(8), word(1), word(1)].concat(), // 1 x 1
        [word((2 << 16) | 1), b"vi\0\0".to_vec()].concat(), // its name, a small element
        [word((4 << 16) | 5), word(32)].concat(),      // field names 32 bytes wide
        [word(1), word(32), names].concat(),
        [word(14), word(field.len() as u32), field].concat(),
    ]
    .concat();
    [
        plain[..128].to_vec(),
        word(14),
        word(body.len() as u32),
        body,
    ]
    .concat()
}

/// A protocol file as other systems write one: a header, 1-based electrodes, each row's
/// current (A), 40 rows (the frames' K).
fn protocol_csv() -> String {
    let mut text = String::from("source,sink,positive,negative,current_a\n");
    for k in 0..40u16 {
        let (a, m) = (k / 10, k % 10);
        let (s, t) = (a + 1, a + 2);
        let (p, n) = ((a + 3 + m) % 16 + 1, (a + 4 + m) % 16 + 1);
        text += &format!("{s},{t},{p},{n},1e-3\n");
    }
    text
}

/// A system's protocol as two lists, the tank archives' way: injection pairs counted from 1
/// under names of their own with currents in mA, and measurement patterns a row (+1, -1).
fn protocol_pairs() -> [String; 2] {
    let mut injections =
        String::from("injection,source_electrode(+),sink_electrode(-),amplitude\n");
    for i in 0..16 {
        injections += &format!("{},{},{},1.41\n", i + 1, i + 1, (i + 1) % 16 + 1);
    }
    // (8 of the 16 adjacent pairs: a square matrix would read either way round, and be asked.)
    let mut patterns = String::new();
    for m in 0..8 {
        let row: Vec<&str> = (0..16)
            .map(|e| match e {
                _ if e == m => "1",
                _ if e == (m + 1) % 16 => "-1",
                _ => "0",
            })
            .collect();
        patterns += &(row.join(",") + "\n");
    }
    [injections, patterns]
}

/// `et_host::frames::read` picks the format by extension: the case's file is given one
/// through a symbolic link (so an endless input stays endless), removed after.
fn read_frames(case: &Path, ext: &str) -> bool {
    let named = std::env::temp_dir().join(format!("et-fuzz-{}-link.{ext}", std::process::id()));
    let _ = std::fs::remove_file(&named);
    let read = std::os::unix::fs::symlink(case, &named).is_ok()
        && et_host::frames::read(&named, 40).is_ok();
    let _ = std::fs::remove_file(&named);
    read
}

/// tests/data's SciPy writing of EIDORS's struct arrays, uncompressed.
fn eidors_v6() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("data/eidors_stim_v6.mat")).unwrap()
}

/// `read` of the damaged file `case`'s array `name`, linked under a `.mat` name (as
/// `FILE.mat:NAME` is read).
fn named_mat(case: &Path, name: &str, read: impl Fn(&Path) -> bool) -> bool {
    let named = std::env::temp_dir().join(format!("et-fuzz-{}-named.mat", std::process::id()));
    let _ = std::fs::remove_file(&named);
    let spec = PathBuf::from(format!("{}:{name}", named.display()));
    let ok = std::os::unix::fs::symlink(case, &named).is_ok() && read(&spec);
    let _ = std::fs::remove_file(&named);
    ok
}

fn recording(dir: &Path) -> Vec<u8> {
    let config = small_config();
    let header = Header::new("fuzz", &config).unwrap();
    let path = dir.join("seed.jsonl");
    let mut w = Writer::create(&path, &header).unwrap();
    for seq in 0..3u32 {
        let k = header.frame_len;
        w.append(&Record {
            seq,
            t_us: seq * 1000,
            flags: 0,
            rail_count: 0,
            voltages: (0..k).map(|i| i as f32 * 1e-3).collect(),
            invalid: Vec::new(),
            touches: None,
        })
        .unwrap();
    }
    drop(w);
    std::fs::read(path).unwrap()
}

const DATASET: &str = "# et-dataset 1
# config: {\"electrodes\":8,\"protocol\":\"Adjacent\",\"samples_per_step\":200,\"settle_samples\":40,\"current_na\":32000,\"sample_rate_hz\":10000,\"gain\":1}
# feature_index: 0 3 7
# centres_mm: 0 0; 10 10
# electrodes_mm: -50 0; 50 0; 0 50; 0 -50
# untouched: 0.1 0.2 0.3; 0.1 0.2 0.31
label,x_mm,y_mm,visit,pressure_kpa,v0,v3,v7
0,0.5,-0.2,0,20,0.11,0.2,0.3
1,9.5,10.2,0,25,0.1,0.22,0.3
0,0.1,0.3,1,30,0.12,0.2,0.29
1,10.1,9.9,1,35,0.1,0.21,0.33
";

/// The [`DATASET`] seed as this build writes it (version 2, SI).
fn dataset_csv(dir: &std::path::Path) -> Vec<u8> {
    let (old, new) = (
        dir.join("seed-dataset-1.csv"),
        dir.join("seed-dataset-2.csv"),
    );
    std::fs::write(&old, DATASET).unwrap();
    let data = et_learn::dataset::load_csv(&old).unwrap();
    et_learn::dataset::save_csv(&data, &new, "fuzz seed").unwrap();
    std::fs::read(&new).unwrap()
}

/// The [`DATASET`] seed as an `.npz` archive.
fn dataset_npz(dir: &std::path::Path) -> Vec<u8> {
    let (csv, npz) = (dir.join("seed-dataset.csv"), dir.join("seed-dataset.npz"));
    std::fs::write(&csv, DATASET).unwrap();
    let data = et_learn::dataset::load_csv(&csv).unwrap();
    et_learn::dataset::save_npz(&data, &npz, "fuzz seed").unwrap();
    std::fs::read(&npz).unwrap()
}

/// Every parser, its seeds made in `dir`.
fn parsers(dir: &Path) -> Vec<Parser> {
    let dir = dir.to_path_buf();
    let (msh, [nodes, triangles, electrodes]) = square_mesh(3);
    let scene = include_str!("../../sim/scenes/square-13cm-16-swipe.toml");
    vec![
        Parser {
            name: "scene TOML",
            seeds: vec![scene.into()],
            parse: |p| et_sim::scene::Scene::load(&p[0]).is_ok(),
        },
        Parser {
            name: "dataset CSV",
            seeds: vec![dataset_csv(&dir)],
            parse: |p| et_learn::dataset::load_csv(&p[0]).is_ok(),
        },
        Parser {
            name: "dataset CSV, version 1",
            seeds: vec![DATASET.into()],
            parse: |p| et_learn::dataset::load_csv(&p[0]).is_ok(),
        },
        Parser {
            name: "dataset NPZ",
            seeds: vec![dataset_npz(&dir)],
            parse: |p| et_learn::dataset::load_npz(&p[0]).is_ok(),
        },
        Parser {
            name: "foreign CSV + targets",
            seeds: vec![
                "\u{feff}a,b,c,label\r\n1.5E-05,2,3,0\r\n4,5,6,1\r\n7,8,9,0\r\n\r\n".into(),
                "x,y\n0.1,0.2\n0.3,0.4\n0.5,0.6\n".into(),
            ],
            parse: |p| {
                et_learn::dataset::Table::import(&p[0], Some(&p[1]), et_learn::dataset::Unit::Mm)
                    .is_ok()
            },
        },
        Parser {
            name: "model JSON",
            seeds: vec![model_json(&dir)],
            parse: |p| ModelFile::load(&p[0]).is_ok(),
        },
        Parser {
            name: "table model JSON, average of regressors",
            seeds: vec![table_model_json(&dir, Kind::Average)],
            parse: |p| TableModel::load(&p[0]).is_ok(),
        },
        Parser {
            name: "table model JSON, QDA",
            seeds: vec![table_model_json(&dir, Kind::Qda)],
            parse: |p| TableModel::load(&p[0]).is_ok(),
        },
        Parser {
            name: "model blob",
            seeds: vec![model(&dir).blob(et_core::model::Precision::F16).unwrap()],
            // As `et board upload` reads it.
            parse: |p| {
                et_core::text::read_at_most(&p[0], 1 << 24)
                    .is_ok_and(|b| et_core::model::Model::parse(&b).is_ok())
            },
        },
        Parser {
            name: "recording JSONL",
            seeds: vec![recording(&dir)],
            parse: |p| et_host::recording::read(&p[0]).is_ok(),
        },
        Parser {
            name: "frames CSV",
            seeds: vec![frames_csv().into()],
            parse: |p| read_frames(&p[0], "csv"),
        },
        Parser {
            name: "frames CSV as a DAQ writes it",
            seeds: vec![frames_daq_csv().into()],
            parse: |p| read_frames(&p[0], "csv"),
        },
        Parser {
            name: "frames LabVIEW .lvm",
            seeds: vec![frames_lvm().into()],
            parse: |p| read_frames(&p[0], "lvm"),
        },
        Parser {
            name: "frames JSON",
            seeds: vec![frames_json().into()],
            parse: |p| read_frames(&p[0], "json"),
        },
        Parser {
            name: "frames JSON, pandas' columns",
            seeds: vec![frames_json_columns().into()],
            parse: |p| read_frames(&p[0], "json"),
        },
        Parser {
            name: "frames JSON Lines, a logger's",
            seeds: vec![frames_json_objects()[0].clone().into_bytes()],
            parse: |p| read_frames(&p[0], "jsonl"),
        },
        Parser {
            name: "frames JSON, pandas' split",
            seeds: vec![frames_json_objects()[1].clone().into_bytes()],
            parse: |p| read_frames(&p[0], "json"),
        },
        Parser {
            name: "frames NumPy .npy",
            seeds: vec![et_learn::npz::npy_of_matrix(&frames_matrix())],
            parse: |p| read_frames(&p[0], "npy"),
        },
        Parser {
            name: "frames NumPy .npz",
            seeds: vec![frames_npz()],
            parse: |p| read_frames(&p[0], "npz"),
        },
        Parser {
            name: "frames NumPy .npz, deflated",
            // As numpy.savez_compressed writes: the inflater's input damaged.
            seeds: vec![deflated_npz(&frames_npz())],
            parse: |p| read_frames(&p[0], "npz"),
        },
        Parser {
            name: "protocol CSV",
            seeds: vec![protocol_csv().into()],
            // As a scene's `protocol = { file = ... }` reads it: 16 electrodes, 1-based.
            parse: |p| et_core::schedule::Schedule::read_csv(&p[0], 16, 1, 1e-3).is_ok(),
        },
        Parser {
            name: "protocol pair lists",
            seeds: protocol_pairs().map(String::into_bytes).to_vec(),
            // As `et protocol --injections --measurements --current-unit mA` crosses them.
            parse: |p| {
                let crossing = et_host::pairs::Crossing {
                    current_unit: Some(("mA".into(), 1e-3)),
                    ..et_host::pairs::Crossing::default()
                };
                et_host::pairs::cross(&p[0], &p[1], &crossing).is_ok()
            },
        },
        Parser {
            name: "EIDORS stimulation .mat",
            // SciPy's writing of EIDORS's struct arrays, uncompressed (tests/data).
            seeds: vec![eidors_v6()],
            // As `et protocol --stimulation FILE.mat:stim` reads it.
            parse: |p| {
                named_mat(&p[0], "stim", |spec| {
                    et_host::pairs::stimulation(spec, &et_host::pairs::Crossing::default()).is_ok()
                })
            },
        },
        Parser {
            name: "frames MATLAB .mat, struct array",
            // The same file's frames as a loop keeps them (vi(k).meas).
            seeds: vec![eidors_v6()],
            // As `et reconstruct --frames FILE.mat:vi.meas` reads it.
            parse: |p| {
                named_mat(&p[0], "vi.meas", |spec| {
                    et_host::frames::read(spec, 208).is_ok()
                })
            },
        },
        Parser {
            name: "frames MATLAB .mat",
            seeds: vec![et_host::frames::mat_v5("v", &frames_matrix())],
            parse: |p| read_frames(&p[0], "mat"),
        },
        Parser {
            name: "frames MATLAB .mat, a struct's field",
            seeds: vec![frames_mat_struct()],
            parse: |p| read_frames(&p[0], "mat"),
        },
        Parser {
            name: "Gmsh 2.2",
            seeds: vec![msh.into()],
            parse: |p| et_recon::mesh::Mesh::from_gmsh(&p[0]).is_ok(),
        },
        Parser {
            name: "CSV mesh",
            seeds: vec![nodes.into(), triangles.into(), electrodes.into()],
            parse: |p| et_recon::mesh::Mesh::from_csv(&p[0], &p[1], &p[2]).is_ok(),
        },
    ]
}

#[test]
fn every_parser_survives_damaged_files_in_bounded_memory() {
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let cases: u32 = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000);
    let only: Vec<String> = std::env::var("ET_FUZZ_PARSERS")
        .map(|v| v.split(',').map(|s| s.trim().to_lowercase()).collect())
        .unwrap_or_default();
    // "i/n": this process fuzzes every n-th parser from the i-th (a child of the run below).
    let shard: Option<(usize, usize)> = std::env::var("ET_FUZZ_SHARD").ok().map(|v| {
        let (i, n) = v.split_once('/').expect("ET_FUZZ_SHARD is i/n");
        (i.parse().unwrap(), n.parse().unwrap())
    });
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    if shard.is_none() && cores > 1 {
        shards(cores);
        return;
    }
    let (first, every) = shard.unwrap_or((0, 1));
    let dir = scratch("damaged");
    for target in parsers(&dir)
        .into_iter()
        .filter(|t| {
            only.is_empty()
                || only
                    .iter()
                    .any(|o| !o.is_empty() && t.name.to_lowercase().contains(o.as_str()))
        })
        .skip(first)
        .step_by(every)
    {
        damage(
            &target,
            &scratch(&format!("damaged/{}", target.name)),
            cases,
        );
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// The fuzz test in `n` child processes of this test binary at once, each fuzzing every n-th
/// parser (`ET_FUZZ_SHARD`); their reports printed, their failures this test's.
fn shards(n: usize) {
    let children: Vec<_> = (0..n)
        .map(|i| {
            std::process::Command::new(std::env::current_exe().unwrap())
                .args([
                    "--exact",
                    "every_parser_survives_damaged_files_in_bounded_memory",
                    "--nocapture",
                ])
                .env("ET_FUZZ_SHARD", format!("{i}/{n}"))
                .stdout(std::process::Stdio::piped())
                .stderr(std::process::Stdio::piped())
                .spawn()
                .unwrap()
        })
        .collect();
    let mut failed = Vec::new();
    for (i, child) in children.into_iter().enumerate() {
        let out = child.wait_with_output().unwrap();
        let text = String::from_utf8_lossy(&out.stdout);
        // The child's own reports, without libtest's lines around them.
        for line in text.lines().filter(|l| l.contains("damaged inputs")) {
            println!("{line}");
        }
        if !out.status.success() {
            failed.push(format!(
                "shard {i}/{n}: {}\n{text}\n{}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            ));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// `cases` damaged versions of `target`'s seeds, written to `dir` and parsed: no panic, and
/// the parse's peak allocation within [`allowance`] of the files' size.
fn damage(target: &Parser, dir: &Path, cases: u32) {
    let paths: Vec<PathBuf> = (0..target.seeds.len())
        .map(|i| dir.join(format!("case-{i}")))
        .collect();
    let write = |files: &[Vec<u8>]| {
        for (p, b) in paths.iter().zip(files) {
            std::fs::write(p, b).unwrap();
        }
    };
    // The seeds are valid: damage starts from files the parser accepts.
    write(&target.seeds);
    assert!((target.parse)(&paths), "{}: the seed parses", target.name);
    let started = Instant::now();
    let accepted = std::cell::Cell::new(0u64);
    // The largest peak allocation seen, and the size of the input that caused it.
    let largest = std::cell::Cell::new((0usize, 0usize));
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    let strategy = (
        0..target.seeds.len(),
        proptest::collection::vec(edit(), 1..6),
    );
    let result = runner.run(&strategy, |(which, edits)| {
        let mut files = target.seeds.clone();
        files[which] = apply(&files[which], &edits);
        write(&files);
        let len: usize = files.iter().map(Vec::len).sum();
        let before = ALLOC.current_usage();
        ALLOC.reset_peak_usage();
        let ok = (target.parse)(&paths);
        let peak = ALLOC.peak_usage().saturating_sub(before);
        accepted.set(accepted.get() + u64::from(ok));
        if peak > largest.get().0 {
            largest.set((peak, len));
        }
        prop_assert!(
            peak <= allowance(len),
            "{}: {peak} bytes allocated for a {len}-byte input",
            target.name
        );
        Ok(())
    });
    if let Err(e) = result {
        panic!("{}: {e}", target.name);
    }
    let (peak, len) = largest.get();
    println!(
        "{:<40} {cases:>8} damaged inputs, {:>7} accepted, no panic; largest peak \
         allocation {:.2} MB (for a {:.1} kB input); {:.1} s",
        target.name,
        accepted.get(),
        peak as f64 / 1e6,
        len as f64 / 1e3,
        started.elapsed().as_secs_f64(),
    );
}

/// Every reader given an endless stream (`/dev/zero`) or a huge file (sparse, one byte past
/// the largest file et reads) in place of each of its files: a clean refusal, never a panic,
/// an abort or memory past the reader's limit. A huge regular file is refused by its size
/// before it is read; a stream is read to the reader's limit (the data files' limit, 1 GiB by
/// default, lowered here by `set_max_file_bytes`; 1 MiB for scenes, 16 MiB for blobs) and no
/// further, and the buffer never grows past that limit (the last growth copies from a half-size
/// buffer: 1.5 x the limit at most).
#[test]
fn every_reader_stops_at_its_limit_on_endless_and_huge_inputs() {
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = scratch("endless");
    // A huge file is one byte past the default limit (sparse, refused by its size); an endless
    // stream is read to a limit lowered for this test, 1/32 of the default, since reading 1 GiB
    // from /dev/zero per reader and file would take a minute and prove no more.
    let huge = dir.join("huge");
    std::fs::File::create(&huge)
        .unwrap()
        .set_len(et_core::text::MAX_FILE_BYTES + 1)
        .unwrap();
    let lowered = et_core::text::MAX_FILE_BYTES / 32;
    let limit = lowered as usize;
    for target in parsers(&dir) {
        let paths: Vec<PathBuf> = (0..target.seeds.len())
            .map(|i| dir.join(format!("{}-{i}", target.seeds.len())))
            .collect();
        for (p, b) in paths.iter().zip(&target.seeds) {
            std::fs::write(p, b).unwrap();
        }
        for which in 0..paths.len() {
            for (what, input, allowed) in [
                (
                    "endless",
                    Path::new("/dev/zero"),
                    limit + limit / 2 + (4 << 20),
                ),
                ("huge", huge.as_path(), 4 << 20),
            ] {
                let mut given = paths.clone();
                given[which] = input.into();
                et_core::text::set_max_file_bytes(if what == "endless" { lowered } else { 0 });
                let started = Instant::now();
                let before = ALLOC.current_usage();
                ALLOC.reset_peak_usage();
                let ok = (target.parse)(&given);
                et_core::text::set_max_file_bytes(0);
                let peak = ALLOC.peak_usage().saturating_sub(before);
                println!(
                    "{:<40} file {which}: {what:<7} refused, peak allocation {:>7.1} MB, {:.2} s",
                    target.name,
                    peak as f64 / 1e6,
                    started.elapsed().as_secs_f64()
                );
                assert!(!ok, "{}: an {what} file {which} accepted", target.name);
                assert!(
                    peak <= allowed,
                    "{}: {peak} bytes allocated for an {what} file {which}",
                    target.name
                );
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `.mat` of many compressed variables, each within the data files' limit when inflated but
/// all together past it, is refused before any is parsed: the limit counts their total (a
/// 4.6 MB file inflated to 4.5 GB when each was checked alone).
#[test]
fn compressed_matlab_variables_are_bounded_together() {
    use std::io::Write as _;
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let limit: u64 = 1 << 20;
    // One variable of 256 KiB of zeros, compressed (a few hundred bytes).
    let plain = et_host::frames::mat_v5("v", &DMatrix::zeros(128, 256));
    let mut z = libflate::zlib::Encoder::new(Vec::new()).unwrap();
    z.write_all(&plain[128..]).unwrap();
    let deflated = z.finish().into_result().unwrap();
    let file_of = |copies: usize| {
        let mut file = plain[..128].to_vec();
        for _ in 0..copies {
            file.extend(15u32.to_le_bytes());
            file.extend((deflated.len() as u32).to_le_bytes());
            file.extend(&deflated);
        }
        file
    };
    let dir = scratch("mat-total");
    let (one, many) = (dir.join("one.mat"), dir.join("many.mat"));
    std::fs::write(&one, file_of(1)).unwrap();
    std::fs::write(&many, file_of(8)).unwrap();
    et_core::text::set_max_file_bytes(limit);
    let alone = et_host::frames::read(&one, 256);
    let together = et_host::frames::read(&many, 256);
    et_core::text::set_max_file_bytes(0);
    let _ = std::fs::remove_dir_all(&dir);
    assert!(alone.is_ok(), "one variable within the limit: {alone:?}");
    let e = together.unwrap_err().to_string();
    assert!(e.contains("inflate past") && e.contains("together"), "{e}");
}

/// Tables of numbers are read record by record: what a reader holds is its numbers (8 bytes
/// a value, a copy or two while the matrix is shaped) beside the file's text, never its cells
/// as strings (a frames CSV of one-digit cells took 37 times its size, 777 MB for 21 MB).
#[test]
fn tables_are_read_within_a_small_multiple_of_the_numbers_kept() {
    let _turn = ONE_AT_A_TIME
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = scratch("table-memory");
    let (rows, k) = (2_000, 208);
    let mut rng = Rng::new(5);
    let row = |rng: &mut Rng| {
        (0..k)
            .map(|_| (1 + rng.next_u32() % 9).to_string())
            .collect::<Vec<_>>()
            .join(",")
    };
    let frames: String = (0..rows).map(|_| row(&mut rng) + "\n").collect();
    let names: Vec<String> = (0..k - 1).map(|j| format!("f{j}")).collect();
    let features = format!("{},label\n", names.join(","))
        + &(0..rows).map(|_| row(&mut rng) + "\n").collect::<String>();
    let json = format!("[[{}]]\n", frames.trim_end().replace('\n', "],\n ["));
    // pandas' to_json() default (a key a column, an object of its rows by index): a key a
    // value in the file, not in memory.
    let cells: Vec<Vec<&str>> = frames.lines().map(|l| l.split(',').collect()).collect();
    let columns: Vec<String> = (0..k)
        .map(|c| {
            let rows: Vec<String> = (0..rows)
                .map(|r| format!("\"{r}\":{}", cells[r][c]))
                .collect();
            format!("\"v{c}\":{{{}}}", rows.join(","))
        })
        .collect();
    let pandas = format!("{{{}}}", columns.join(","));
    let (f, t, j, p) = (
        dir.join("frames.csv"),
        dir.join("features.csv"),
        dir.join("frames.json"),
        dir.join("pandas.json"),
    );
    std::fs::write(&f, &frames).unwrap();
    std::fs::write(&j, &json).unwrap();
    std::fs::write(&p, &pandas).unwrap();
    std::fs::write(&t, &features).unwrap();
    let values = rows * k;
    let allowed = |text: usize| text + 4 * 8 * values + (1 << 20);
    for (what, len, read) in [
        (
            "frames CSV",
            frames.len(),
            Box::new(|| et_host::frames::read(&f, k).is_ok()) as Box<dyn Fn() -> bool>,
        ),
        (
            "frames JSON",
            json.len(),
            Box::new(|| et_host::frames::read(&j, k).is_ok()),
        ),
        (
            "frames JSON, pandas' columns",
            pandas.len(),
            Box::new(|| et_host::frames::read(&p, k).is_ok()),
        ),
        (
            "features CSV",
            features.len(),
            Box::new(|| {
                et_learn::dataset::Table::import(&t, None, et_learn::dataset::Unit::Mm).is_ok()
            }),
        ),
    ] {
        let before = ALLOC.current_usage();
        ALLOC.reset_peak_usage();
        assert!(read(), "{what} read");
        let peak = ALLOC.peak_usage().saturating_sub(before);
        println!(
            "{what}: {len} bytes, {values} values, peak allocation {:.1} MB",
            peak as f64 / 1e6
        );
        assert!(
            peak <= allowed(len),
            "{what}: {peak} bytes allocated, allowed {}",
            allowed(len)
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
