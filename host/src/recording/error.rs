//! Why a recording could not be written or read, and what is wrong with one of its lines.

use std::path::PathBuf;

use super::{Column, FORMAT, VERSION};

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
    #[error("{}:{line}: {fault}", path.display())]
    Line {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0: a frame being appended).
        line: usize,
        /// What is wrong.
        fault: LineFault,
    },
    /// The file may not be written (it exists, or it is an input).
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
}

/// What is wrong with one line of a recording (or a frame appended to one).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LineFault {
    /// The file has no line.
    #[error("empty file: no header")]
    Empty,
    /// The first line is not JSON: not an et recording.
    #[error(
        "not an et recording: its first line is not JSON ({}); et sim and et record write \
         JSON lines, another system's frames are read from .csv, .npy, .npz or .mat (and a \
         file of any other name that is no recording; a pipe is read as one by its name)",
        et_learn::model_file::json_said(.0, true)
    )]
    NotJson(serde_json::Error),
    /// The first line is JSON without a "format": another tool's JSON.
    #[error(
        "not an et recording: its first line is JSON without et's \"format\": \"{FORMAT}\" \
         (another tool's file?); et sim and et record write recordings, another system's \
         frames are read from .csv, .npy, .npz or .mat, or JSON as an array of frames \
         ([[v0, v1, ...], ...], as json.dump(F.tolist()) and pandas' \
         to_json(orient=\"values\") write it)"
    )]
    NoFormat,
    /// Another of et's files than a recording (a dataset, a protocol file).
    #[error(
        "{}, not a recording: {}",
        .0.said(),
        match .0 {
            et_core::text::EtFile::Dataset => "give it as --data (et train, et eval)",
            et_core::text::EtFile::Protocol =>
                "a scene names it as [scan] protocol = { file = \"FILE\" }",
            _ => "et sim and et record write recordings",
        }
    )]
    OtherFile(et_core::text::EtFile),
    /// The header is JSON but not the format's fields (named by their place).
    #[error("header: {}", missing_said(.0))]
    Header(serde_json::Error),
    /// Another format's file (a model file said as what it is: "format 'et-table-model' is
    /// not et-recording" was all it said).
    #[error("format '{}' is not {FORMAT}{}", .0, model_said(.0))]
    Format(String),
    /// Another version of the format.
    #[error("version {0} (this build reads {VERSION})")]
    Version(u32),
    /// The header's configuration is not one et scans.
    #[error("header config: {0}")]
    Config(et_core::config::ConfigError),
    /// The header's K and electrodes disagree with its configuration.
    #[error(
        "header says K = {k} on {electrodes} electrodes, its config ({protocol} on \
         {config_electrodes}) gives K = {config_k}"
    )]
    HeaderK {
        /// The header's K.
        k: usize,
        /// The header's electrode count.
        electrodes: u8,
        /// The configuration's protocol.
        protocol: &'static str,
        /// The configuration's electrode count.
        config_electrodes: u8,
        /// The configuration's K.
        config_k: usize,
    },
    /// The header lists another number of columns than its protocol's K.
    #[error("header lists {listed} columns, its protocol has K = {k}")]
    ColumnCount {
        /// Columns listed.
        listed: usize,
        /// The protocol's K.
        k: usize,
    },
    /// A header column is not the protocol's column there.
    #[error(
        "header column {column} is ({got}) but the {protocol} protocol's column {column} is \
         ({want}): the columns must follow the protocol's order (another system's frames in \
         another order: give them as a table with a protocol file, et reconstruct --frames)"
    )]
    ColumnOrder {
        /// The column (0-based).
        column: usize,
        /// The header's.
        got: Column,
        /// The protocol's name.
        protocol: &'static str,
        /// The protocol's.
        want: Column,
    },
    /// A frame of another length than the header's K.
    #[error("frame {seq} has {values} values, the header says K = {k}")]
    FrameLength {
        /// Its sequence number.
        seq: u32,
        /// Its values.
        values: usize,
        /// The header's K.
        k: usize,
    },
    /// A frame line is not the format's JSON.
    #[error("{}", missing_said(.0))]
    Frame(serde_json::Error),
    /// A frame line holding `NaN` or `Infinity`, which JSON has not (Python's `json` writes
    /// them): it was "expected value (column 60)".
    #[error(
        "{token} at column {column}: not JSON, which has no NaN or infinity (Python's json \
         writes them; json.dump(..., allow_nan=False) refuses them): a value not measured is \
         written null, as et writes it"
    )]
    NonFinite {
        /// `NaN`, `Infinity` or `-Infinity`.
        token: &'static str,
        /// Where on the line, from 1.
        column: usize,
    },
}

/// What is said of a file of `format` given as a recording beside "is not et-recording".
fn model_said(format: &str) -> &'static str {
    match format {
        "et-model" | "et-table-model" => {
            ": an et model file (et train), not a recording: give it as --model"
        }
        _ => "",
    }
}

/// The JSON error of a line, a field left out said with what it holds, its unit and a value
/// to start from (serde said "missing field `t_us`" alone).
fn missing_said(error: &serde_json::Error) -> String {
    const MISSING: &str = "missing field `";
    let said = et_learn::model_file::json_said(error, true);
    let Some(at) = said.find(MISSING) else {
        return said;
    };
    let field = said[at + MISSING.len()..]
        .split('`')
        .next()
        .unwrap_or_default();
    // (The field's place in front, as `from_value_named` writes it: `columns[3]: `.)
    let place = said[..at].trim_end_matches([':', ' ']);
    match field_said(place, field) {
        Some(what) => format!("{said}: {what}"),
        None => said,
    }
}

/// What a recording's `field` holds, at `place` (`config`, `columns[3]`, `touches[0]`, or
/// empty: the header's or a frame's own fields).
fn field_said(place: &str, field: &str) -> Option<&'static str> {
    let in_list = |list: &str| place.starts_with(list);
    Some(match field {
        "source" | "sink" if in_list("columns") => {
            "the electrode the current enters (source) or leaves (sink), from 0"
        }
        "positive" | "negative" => "the amplifier's + (positive) or - (negative) electrode, from 0",
        "x" | "y" | "radius" => "the touch's centre (x, y) or contact radius, m",
        "pressure" => "the touch's pressure, Pa",
        "format" => "\"et-recording\", the format's name",
        "version" => "the format's version (1)",
        "source" => "where the frames come from (\"sim:scene.toml\", \"port:/dev/ttyACM0\")",
        "electrodes" => "the electrode count L (16)",
        "protocol" if in_list("config") => {
            "the protocol the board scans (\"Adjacent\", \"Opposite\")"
        }
        "protocol" => "the protocol's name (\"adjacent\", \"opposite\")",
        "K" => "the frame's length, values a frame (208 for adjacent on 16 electrodes)",
        "config" => {
            "the board's scan settings: {\"electrodes\", \"protocol\", \"samples_per_step\", \
             \"settle_samples\", \"current_na\", \"sample_rate_hz\", \"gain\"}, as et record \
             writes them"
        }
        "columns" => {
            "each of the K values' electrodes, in order: [{\"source\", \"sink\", \"positive\", \
             \"negative\"}, ...]"
        }
        "samples_per_step" => "ADC samples a measurement (50)",
        "settle_samples" => "samples skipped after each switch (25)",
        "current_na" => "the current injected, nA (32000)",
        "sample_rate_hz" => "the ADC's sample rate, Hz (62500)",
        "gain" => "the amplifier's gain (8)",
        "seq" => "the frame's sequence number, from 0",
        "t_us" => "the frame's time on the board, microseconds",
        "flags" => "the board's frame flags (0: none)",
        "rail_count" => "measurements with samples on an ADC rail (0: none)",
        "voltages" => "the frame's K values, V",
        _ => return None,
    })
}
