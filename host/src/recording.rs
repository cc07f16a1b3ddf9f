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

mod error;
mod made_on;
pub use error::{LineFault, RecordingError};

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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Column {
    /// Electrode the current enters.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub source: u8,
    /// Electrode the current leaves.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub sink: u8,
    /// Amplifier + input.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub positive: u8,
    /// Amplifier - input.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub negative: u8,
}

impl std::fmt::Display for Column {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Self {
            source,
            sink,
            positive,
            negative,
        } = self;
        write!(
            f,
            "source {source}, sink {sink}, + {positive}, - {negative}"
        )
    }
}

/// The first line of a recording.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// Always [`FORMAT`].
    pub format: String,
    /// [`VERSION`].
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub version: u32,
    /// What the numbers are in, for whoever opens the file ([`UNITS`]; files written before
    /// it was added read as the same).
    #[serde(default = "units")]
    pub units: String,
    /// Where the frames come from (`sim:<scene file>`, `port:<path>`, ...).
    pub source: String,
    /// Electrode count L.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub electrodes: u8,
    /// Protocol name.
    pub protocol: String,
    /// Frame length K.
    #[serde(rename = "K", deserialize_with = "et_core::whole::whole")]
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
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub seq: u32,
    /// Device time of the frame, us.
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub t_us: u32,
    /// Frame flags (`et_core::wire::FLAG_*`).
    #[serde(deserialize_with = "et_core::whole::whole")]
    pub flags: u8,
    /// Measurements with ADC rail samples.
    #[serde(deserialize_with = "et_core::whole::whole")]
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
    pub fn new<V: AsRef<[f32]>>(frame: &Frame<V>, touches: Option<Vec<TouchRecord>>) -> Self {
        let voltages = frame.voltages.as_ref();
        Self {
            seq: frame.seq,
            t_us: frame.timestamp.0,
            flags: frame.flags,
            rail_count: frame.rail_count,
            voltages: voltages.to_vec(),
            invalid: invalid_columns(voltages),
            touches,
        }
    }
}

/// The columns of `v` that are NaN or infinite.
#[must_use]
pub fn invalid_columns(v: &[f32]) -> Vec<usize> {
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
                fault: LineFault::FrameLength {
                    seq: record.seq,
                    values: record.voltages.len(),
                    k: self.k,
                },
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
    let bad = |line, fault: LineFault| RecordingError::Line {
        path: path.into(),
        line,
        fault,
    };
    // Read whole, but never more than a data file's limit (an endless stream stops there).
    let text =
        et_core::text::read_text_at_most(path, et_core::text::max_file_bytes()).map_err(io)?;
    let lines: Vec<&str> = text.lines().collect();
    let first = lines.first().ok_or_else(|| bad(1, LineFault::Empty))?;
    let header = serde_json::from_str::<serde_json::Value>(first).map_err(|e| {
        match et_core::text::EtFile::of(&text) {
            // Another of et's files (a dataset, a protocol file) said as what it is.
            Some(kind) => bad(1, LineFault::OtherFile(kind)),
            None => bad(1, LineFault::NotJson(e)),
        }
    })?;
    // Another format's JSON is said as such before its fields are asked for.
    match header.get("format").and_then(serde_json::Value::as_str) {
        Some(format) if format != FORMAT => {
            return Err(bad(1, LineFault::Format(format.to_string())));
        }
        // (A JSON file of another tool's was said as "missing field `format`".)
        // (A header of et's fields without its "format", written by hand, is asked for it
        // below.)
        None if header.get("format").is_none()
            && !(header.get("K").is_some()
                && (header.get("columns").is_some() || header.get("config").is_some())) =>
        {
            return Err(bad(1, LineFault::NoFormat));
        }
        _ => {}
    }
    let header: Header =
        et_learn::model_file::from_value_named(header).map_err(|e| bad(1, LineFault::Header(e)))?;
    header.check().map_err(|fault| bad(1, fault))?;
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
                    LineFault::FrameLength {
                        seq: r.seq,
                        values: r.voltages.len(),
                        k: header.frame_len,
                    },
                ));
            }
            Err(e) if i + 1 == last && e.is_eof() => truncated_tail = true,
            Err(e) => {
                let fault = match et_learn::model_file::non_finite_at(text, &e) {
                    Some(token) => LineFault::NonFinite {
                        token,
                        column: e.column(),
                    },
                    None => LineFault::Frame(named(text, e)),
                };
                return Err(bad(i + 1, fault));
            }
        }
    }
    Ok(Recording {
        header,
        records,
        truncated_tail,
    })
}

/// `error`, the error of a frame line `text` that is JSON, again with the field it is of in
/// front (`flags: 256 is out of range`, which said no field); as it was for text that is not
/// JSON. Read again only when a line fails, so the frames' fast path stays as it is.
fn named(text: &str, error: serde_json::Error) -> serde_json::Error {
    serde_json::from_str::<serde_json::Value>(text)
        .ok()
        .and_then(|v| et_learn::model_file::from_value_named::<Record>(v).err())
        .unwrap_or(error)
}

impl Header {
    /// Whether this header is one et reads: its format and version, and its frame length,
    /// electrodes and columns those of its configuration's protocol, in its order. Err says
    /// what is wrong, for people.
    fn check(&self) -> Result<(), LineFault> {
        if self.format != FORMAT {
            return Err(LineFault::Format(self.format.clone()));
        }
        if self.version != VERSION {
            return Err(LineFault::Version(self.version));
        }
        // The header must agree with itself: every reader takes K and L from the
        // configuration.
        let protocol = self.config.validate().map_err(LineFault::Config)?;
        if self.frame_len != protocol.frame_len() || self.electrodes != self.config.electrodes {
            return Err(LineFault::HeaderK {
                k: self.frame_len,
                electrodes: self.electrodes,
                protocol: self.config.protocol.name(),
                config_electrodes: self.config.electrodes,
                config_k: protocol.frame_len(),
            });
        }
        // The columns say what each value is: they must be the protocol's, in its order (a
        // reader images by the configuration's protocol; columns in another order would give
        // a silently wrong image).
        let expected = Header::new(self.source.clone(), &self.config)
            .map_err(LineFault::Config)?
            .columns;
        if self.columns.len() != expected.len() {
            return Err(LineFault::ColumnCount {
                listed: self.columns.len(),
                k: expected.len(),
            });
        }
        if let Some((k, (got, want))) = self
            .columns
            .iter()
            .zip(&expected)
            .enumerate()
            .find(|(_, (a, b))| a != b)
        {
            return Err(LineFault::ColumnOrder {
                column: k,
                got: *got,
                protocol: self.config.protocol.name(),
                want: *want,
            });
        }
        Ok(())
    }
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

    /// What a reader of this recording says before using it: a last line cut short and
    /// skipped ([`Recording::truncated_tail`]), frames out of order ([`Recording::order_note`]).
    #[must_use]
    pub fn notes(&self) -> Vec<String> {
        let cut = self.truncated_tail.then(|| {
            format!(
                "its last line was cut short (a recording stopped while it was written) and is \
                 skipped: {} whole frame{} read",
                self.records.len(),
                if self.records.len() == 1 { "" } else { "s" }
            )
        });
        cut.into_iter().chain(self.order_note()).collect()
    }
}
