//! The recording format: JSON Lines (`.jsonl`), one JSON object per line.
//!
//! Line 1 is a [`Header`]: format name and version, where the frames come from, the scan
//! configuration, K, and the measurement table (injection and measurement electrodes of every
//! column), so a recording can be read without et. Every further line is one [`Record`]: a
//! frame's sequence number, time, flags and V_m in volts, and, for simulated frames, the
//! truth (the touches that were on the sheet: centre and radius in metres, pressure in
//! pascals). The header's `units` says so: every number in the file is SI.
//!
//! Why JSON Lines: Python reads it with the standard library (`python/et_recording.py`),
//! MATLAB with `jsondecode` per line, pandas with `read_json(lines=True)`; and a line is
//! flushed as soon as its frame arrives, so a crash or a pulled cable loses at most the frame
//! in flight. A reader skips a truncated last line and says so.

// Reads untrusted bytes (a file or the wire): no unwrap, expect or unchecked indexing.
#![deny(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use et_core::ScanConfig;
use et_core::protocol::Protocol;
use et_core::wire::Frame;
use serde::{Deserialize, Serialize};

/// The `format` value of a recording's header.
pub const FORMAT: &str = "et-recording";
/// The format version this build writes and reads.
pub const VERSION: u32 = 1;

/// What a recording's numbers are in: SI, as every et file.
pub const UNITS: &str =
    "SI: voltages in V, touch positions and radii in m, pressure in Pa; t_us in microseconds";

fn units() -> String {
    UNITS.into()
}

/// One column of V_m: which injection and which measurement produced it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Column {
    /// Electrode the current enters.
    pub source: u8,
    /// Electrode the current leaves.
    pub sink: u8,
    /// Amplifier + input.
    pub positive: u8,
    /// Amplifier - input.
    pub negative: u8,
}

/// The first line of a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    pub version: u32,
    /// What the numbers are in, for whoever opens the file ([`UNITS`]; files written before
    /// it was added read as the same).
    #[serde(default = "units")]
    pub units: String,
    /// Where the frames come from (`sim:<scene file>`, `port:<path>`, ...).
    pub source: String,
    /// Electrode count L.
    pub electrodes: u8,
    /// Protocol name.
    pub protocol: String,
    /// Frame length K.
    #[serde(rename = "K")]
    pub frame_len: usize,
    /// Scan settings.
    pub config: ScanConfig,
    /// What each of the K columns measures.
    pub columns: Vec<Column>,
}

impl Header {
    /// The header of frames produced with `config`.
    ///
    /// # Errors
    /// If `config` is not a valid configuration.
    pub fn new(
        source: impl Into<String>,
        config: &ScanConfig,
    ) -> Result<Self, et_core::config::ConfigError> {
        let protocol: Protocol = config.validate()?;
        let columns = protocol
            .steps()
            .map(|s| Column {
                source: s.injection.source.0,
                sink: s.injection.sink.0,
                positive: s.measurement.positive.0,
                negative: s.measurement.negative.0,
            })
            .collect();
        Ok(Self {
            format: FORMAT.into(),
            version: VERSION,
            units: UNITS.into(),
            source: source.into(),
            electrodes: config.electrodes,
            protocol: config.protocol.name().into(),
            frame_len: protocol.frame_len(),
            config: *config,
            columns,
        })
    }
}

/// A touch as recorded (metres, pascals).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TouchRecord {
    /// Centre x, m.
    pub x: f64,
    /// Centre y, m.
    pub y: f64,
    /// Contact radius, m.
    pub radius: f64,
    /// Pressure the fabric feels, Pa.
    pub pressure: f64,
}

/// One frame line.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Record {
    /// Sequence number.
    pub seq: u32,
    /// Device time of the frame, us.
    pub t_us: u32,
    /// Frame flags (`et_core::wire::FLAG_*`).
    pub flags: u8,
    /// Measurements with ADC rail samples.
    pub rail_count: u16,
    /// V_m, volts, K values. JSON has no NaN: a value the board sent as NaN or infinite is
    /// written as `null` and read back as NaN (Python's `None`, MATLAB's `NaN`), and its
    /// column is listed in `invalid`.
    #[serde(deserialize_with = "volts_or_null")]
    pub voltages: Vec<f32>,
    /// Columns (0-based) whose value was not finite; absent when every value is.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub invalid: Vec<usize>,
    /// For simulated frames: the touches on the sheet.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub touches: Option<Vec<TouchRecord>>,
}

impl Record {
    /// The record of `frame`, with the truth if known.
    #[must_use]
    pub fn new(frame: &Frame, touches: Option<Vec<TouchRecord>>) -> Self {
        Self {
            seq: frame.seq,
            t_us: frame.timestamp.0,
            flags: frame.flags,
            rail_count: frame.rail_count,
            voltages: frame.voltages.to_vec(),
            invalid: invalid_columns(&frame.voltages),
            touches,
        }
    }
}

/// The columns of `v` that are NaN or infinite.
fn invalid_columns(v: &[f32]) -> Vec<usize> {
    v.iter()
        .enumerate()
        .filter(|(_, x)| !x.is_finite())
        .map(|(i, _)| i)
        .collect()
}

/// Reads V_m with `null` (a non-finite value on writing) as NaN.
fn volts_or_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Vec<f32>, D::Error> {
    let v: Vec<Option<f32>> = Deserialize::deserialize(d)?;
    Ok(v.into_iter().map(|x| x.unwrap_or(f32::NAN)).collect())
}

/// Why a recording could not be written or read.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordingError {
    /// The file could not be created, written or read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// A line is not what the format says.
    #[error("{}:{line}: {message}", path.display())]
    Line {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The file may not be written (it exists, or it is an input).
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// Writes a recording line by line, flushing each line.
#[derive(Debug)]
pub struct Writer {
    path: PathBuf,
    out: BufWriter<File>,
    k: usize,
}

impl Writer {
    /// Creates (or truncates) `path` and writes the header.
    ///
    /// # Errors
    /// [`RecordingError::Io`].
    pub fn create(path: &Path, header: &Header) -> Result<Self, RecordingError> {
        let io = |source| RecordingError::Io {
            path: path.into(),
            source,
        };
        let file = File::create(path).map_err(io)?;
        Self::start(path, file, header)
    }

    /// Creates `path`, refusing an existing file ([`crate::output::OutputError::Exists`]),
    /// and writes the header. For recordings that stream (`et record`), which cannot be
    /// written aside and renamed at the end: a crash must leave every frame so far.
    ///
    /// # Errors
    /// [`RecordingError::Output`] when `path` exists, [`RecordingError::Io`].
    pub fn create_new(path: &Path, header: &Header) -> Result<Self, RecordingError> {
        let file = File::options()
            .write(true)
            .create_new(true)
            .open(path)
            .map_err(|source| {
                if source.kind() == std::io::ErrorKind::AlreadyExists {
                    RecordingError::Output(crate::output::OutputError::Exists { out: path.into() })
                } else {
                    RecordingError::Io {
                        path: path.into(),
                        source,
                    }
                }
            })?;
        Self::start(path, file, header)
    }

    fn start(path: &Path, file: File, header: &Header) -> Result<Self, RecordingError> {
        let mut w = Self {
            path: path.into(),
            out: BufWriter::new(file),
            k: header.frame_len,
        };
        w.line(header)?;
        Ok(w)
    }

    fn line<T: Serialize>(&mut self, value: &T) -> Result<(), RecordingError> {
        let io = |source| RecordingError::Io {
            path: self.path.clone(),
            source,
        };
        serde_json::to_writer(&mut self.out, value).map_err(|e| io(e.into()))?;
        self.out.write_all(b"\n").map_err(io)?;
        self.out.flush().map_err(io)
    }

    /// Appends one frame (flushed before returning).
    ///
    /// # Errors
    /// [`RecordingError::Line`] if the frame's length is not the header's K;
    /// [`RecordingError::Io`].
    pub fn append(&mut self, record: &Record) -> Result<(), RecordingError> {
        if record.voltages.len() != self.k {
            return Err(RecordingError::Line {
                path: self.path.clone(),
                line: 0,
                message: format!(
                    "frame {} has {} values, the header says K = {}",
                    record.seq,
                    record.voltages.len(),
                    self.k
                ),
            });
        }
        let invalid = invalid_columns(&record.voltages);
        if record.invalid == invalid {
            self.line(record)
        } else {
            self.line(&Record {
                invalid,
                ..record.clone()
            })
        }
    }
}

/// A recording read back.
#[derive(Clone, Debug, PartialEq)]
pub struct Recording {
    /// The header.
    pub header: Header,
    /// The frames.
    pub records: Vec<Record>,
    /// Whether the last line was cut short (a crash while writing) and skipped.
    pub truncated_tail: bool,
}

/// Reads a recording, checking the header and every frame's length. A frame with non-finite
/// values (`null` in the file) is kept, with NaN there and its columns in `invalid`: readers
/// that image or classify refuse that frame, not the recording.
///
/// # Errors
/// [`RecordingError`] naming the file and line.
pub fn read(path: &Path) -> Result<Recording, RecordingError> {
    let io = |source| RecordingError::Io {
        path: path.into(),
        source,
    };
    let bad = |line, message: String| RecordingError::Line {
        path: path.into(),
        line,
        message,
    };
    // Read whole, but never more than a data file's limit (an endless stream stops there).
    let text = et_core::text::read_text_at_most(path, et_core::text::MAX_FILE_BYTES).map_err(io)?;
    let lines: Vec<&str> = text.lines().collect();
    let first = lines
        .first()
        .ok_or_else(|| bad(1, "empty file: no header".into()))?;
    let header: Header = serde_json::from_str(first).map_err(|e| bad(1, format!("header: {e}")))?;
    if header.format != FORMAT {
        return Err(bad(
            1,
            format!("format '{}' is not {FORMAT}", header.format),
        ));
    }
    if header.version != VERSION {
        return Err(bad(
            1,
            format!("version {} (this build reads {VERSION})", header.version),
        ));
    }
    // The header must agree with itself: every reader takes K and L from the configuration.
    let protocol = header
        .config
        .validate()
        .map_err(|e| bad(1, format!("header config: {e}")))?;
    if header.frame_len != protocol.frame_len() || header.electrodes != header.config.electrodes {
        return Err(bad(
            1,
            format!(
                "header says K = {} on {} electrodes, its config ({} on {}) gives K = {}",
                header.frame_len,
                header.electrodes,
                header.config.protocol.name(),
                header.config.electrodes,
                protocol.frame_len()
            ),
        ));
    }
    // The columns say what each value is: they must be the protocol's, in its order (a
    // reader images by the configuration's protocol; columns in another order would give a
    // silently wrong image).
    let expected = Header::new(header.source.clone(), &header.config)
        .map_err(|e| bad(1, format!("header config: {e}")))?
        .columns;
    if header.columns.len() != expected.len() {
        return Err(bad(
            1,
            format!(
                "header lists {} columns, its protocol has K = {}",
                header.columns.len(),
                expected.len()
            ),
        ));
    }
    if let Some((k, (got, want))) = header
        .columns
        .iter()
        .zip(&expected)
        .enumerate()
        .find(|(_, (a, b))| a != b)
    {
        let show = |c: &Column| {
            format!(
                "source {}, sink {}, + {}, - {}",
                c.source, c.sink, c.positive, c.negative
            )
        };
        return Err(bad(
            1,
            format!(
                "header column {k} is ({}) but the {} protocol's column {k} is ({}): the \
                 columns must follow the protocol's order (another system's frames in another \
                 order: give them as a table with a protocol file, et reconstruct --frames)",
                show(got),
                header.config.protocol.name(),
                show(want)
            ),
        ));
    }
    let mut records = Vec::new();
    let mut truncated_tail = false;
    let last = lines.len();
    for (i, text) in lines.iter().enumerate().skip(1) {
        if text.trim().is_empty() {
            continue;
        }
        match serde_json::from_str::<Record>(text) {
            Ok(mut r) if r.voltages.len() == header.frame_len => {
                // What the values say, not what the line claims.
                r.invalid = invalid_columns(&r.voltages);
                records.push(r);
            }
            Ok(r) => {
                return Err(bad(
                    i + 1,
                    format!(
                        "frame {} has {} values, K = {}",
                        r.seq,
                        r.voltages.len(),
                        header.frame_len
                    ),
                ));
            }
            Err(e) if i + 1 == last && e.is_eof() => truncated_tail = true,
            Err(e) => return Err(bad(i + 1, e.to_string())),
        }
    }
    Ok(Recording {
        header,
        records,
        truncated_tail,
    })
}

impl Recording {
    /// What a reader should say about the frames' order, if anything: where `seq` goes back or
    /// repeats, or the board's clock `t_us` goes back (a wrap of its 32 bits, every 71.6
    /// minutes, is not going back). Such a file is a board that restarted mid-recording or
    /// recordings joined; readers still take the frames in file order, and say so.
    #[must_use]
    pub fn order_note(&self) -> Option<String> {
        let (mut seq_back, mut time_back, mut first) = (0usize, 0usize, None);
        for (i, pair) in self.records.windows(2).enumerate() {
            let [a, b] = pair else { continue };
            let seq = b.seq <= a.seq;
            let time = b.t_us.wrapping_sub(a.t_us) > u32::MAX / 2;
            seq_back += usize::from(seq);
            time_back += usize::from(time);
            if (seq || time) && first.is_none() {
                first = Some((i + 1, a.seq, b.seq));
            }
        }
        let (at, before, after) = first?;
        Some(format!(
            "frames out of order: seq goes back or repeats {seq_back} time(s), the board's clock \
             goes back {time_back} time(s), first at frame {at} of the file (seq {before} then \
             {after}): a board that restarted, or recordings joined; the frames are taken in \
             file order"
        ))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::indexing_slicing)]
mod tests {
    use super::*;
    use et_core::Micros;
    use et_core::scan::ScanReport;

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
        // Damage elsewhere is an error naming the line.
        let text = std::fs::read_to_string(dir.join("a.jsonl"))
            .unwrap()
            .replacen("\"seq\":1", "\"seq\":\"x\"", 1);
        std::fs::write(&path, text).unwrap();
        let err = read(&path).unwrap_err().to_string();
        assert!(err.contains("a.jsonl:3"), "{err}");
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
        for f in [frame(0, 208), bad, frame(2, 208)] {
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
        assert!(
            out.contains("frames 3") && out.contains("invalid_frames 1"),
            "{out}"
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
}
