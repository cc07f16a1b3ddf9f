//! Why a scene cannot be used, in words: the TOML parser's message cut to fit.

use super::*;

/// Why a scene cannot be used.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The file could not be read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The reason.
        source: std::io::Error,
    },
    /// A file of no table or key (empty, or comments alone): the TOML parser's "missing
    /// field `sheet`" pointed at its first line.
    #[error(
        "{path}: an empty scene (no table or key in it): a scene is a TOML file of [sheet], \
         [scan] and [[touch]] tables, as in sim/scenes/; its [sheet] at least (shape and \
         electrodes)"
    )]
    Empty {
        /// The file.
        path: String,
    },
    /// Another of et's files given as a scene (a recording, a dataset, a model file, a
    /// protocol file): said as what it is and where it goes (the TOML parser's "invalid
    /// key-value pair" was all it said).
    #[error(
        "{path}: {}, not a scene (a TOML file of [sheet], [scan] and [[touch]] tables, as in \
         sim/scenes/): {}",
        kind.said(),
        match kind {
            et_core::text::EtFile::Protocol =>
                "a scene names it as [scan] protocol = { file = \"FILE\" }",
            et_core::text::EtFile::Recording =>
                "give it as --frames (et reconstruct) or --replay (et stream, et view), and the \
                 scene of its sheet as --scene",
            et_core::text::EtFile::Dataset => "give it as --data (et train, et eval)",
            et_core::text::EtFile::Model =>
                "give it as --model, and the scene of its sheet as --scene",
        }
    )]
    OtherFile {
        /// The file.
        path: String,
        /// What it is.
        kind: et_core::text::EtFile,
    },
    /// The file is not valid TOML or does not fit the scene format (the parser's message
    /// names the key and the line).
    #[error("{path}: {}", parse_said(error))]
    Parse {
        /// The file.
        path: String,
        /// The parser's error (said in the message, shortened; not a cause said again).
        error: toml::de::Error,
    },
    /// The text is longer than a scene is.
    #[error(
        "{path}: {bytes} bytes: a scene is at most {MAX_SCENE_BYTES} bytes (scenes are a few hundred)"
    )]
    TooLarge {
        /// The file.
        path: String,
        /// Its length.
        bytes: usize,
    },
    /// Brackets and braces nest deeper than [`MAX_NESTING`].
    #[error(
        "{path}: line {line}: brackets and braces nest deeper than {MAX_NESTING} (an unclosed '{{' or '['?)"
    )]
    TooDeep {
        /// The file.
        path: String,
        /// The 1-based line where the nesting goes too deep.
        line: usize,
    },
    /// A value is out of range.
    #[error("{path}: {error}")]
    Invalid {
        /// The file.
        path: String,
        /// The field at fault and why.
        error: FieldError,
    },
    /// The sheet could not be built or solved (e.g. electrodes overlapping at the resolution).
    #[error("simulation: {0}")]
    Sheet(#[from] SheetError),
    /// The simulated acquisition chain refused a request.
    #[error("simulation: {0}")]
    Sim(#[from] SimError),
    /// The scan engine refused the configuration or a scan failed.
    #[error("simulation: scan: {0}")]
    Scan(#[from] ScanError<SimError>),
    /// A frame could not be encoded.
    #[error("simulation: frame: {0}")]
    Wire(#[from] WireError),
}

/// What a scene's field that must be given is, with a value to start from (sim/scenes/ has
/// a scene of every shape).
fn field_said(field: &str) -> Option<&'static str> {
    Some(match field {
        "sheet" => {
            "the sheet's table, [sheet], with its outline (shape = { kind = \"disc\", radius = 0.11 })"
        }
        "shape" => {
            "the sheet's outline, m: shape = { kind = \"disc\", radius = 0.11 }, { kind = \
             \"rectangle\", width = 0.13, height = 0.13 } or { kind = \"polygon\", vertices = \
             [[x, y], ...] }"
        }
        "radius" => "a radius, m (a disc sheet's: 0.11; a touch's contact: 0.008, a fingertip)",
        "width" | "height" => "the rectangle's extent along x (width) and y (height), m",
        "vertices" => "the polygon's corners, [[x, y], ...] in m, counter-clockwise",
        "position" => "the touch's centre, [x, y] in m from the outline's centre",
        "pressure" => "the touch's pressure while on, Pa (a firm press: 20e3)",
        "kind" => {
            "what it is: an outline's \"disc\", \"rectangle\" or \"polygon\"; an electrode \
             fault's \"disconnected\", \"intermittent\" or \"shorted\""
        }
        "electrode" => "the faulty electrode's number, from 0",
        "per_kelvin" => "the relative change of conductance per kelvin (PPy fabric: about 0.01)",
        "kelvin_per_minute" => "the temperature's ramp, K per minute",
        "file" => "the protocol file's path, relative to the scene (et protocol --csv writes one)",
        _ => return None,
    })
}

/// The TOML parser's message, each line of its snippet of the file cut at 120 characters (a
/// CSV given as a scene echoed a line of 5 000), and where the file is not a scene at all
/// (its first line is no TOML), said so; a field at fault on the first line is not asked
/// about.
fn parse_said(source: &toml::de::Error) -> String {
    const WIDE: usize = 120;
    let text = et_core::said::serde_said(&source.to_string());
    let mut said: Vec<String> = text
        .trim_end()
        .lines()
        .map(|line| match line.char_indices().nth(WIDE) {
            Some((at, _)) => format!("{} ...", &line[..at]),
            None => line.to_string(),
        })
        .collect();
    // A field left out is said with what it is and a value to start from (serde names it
    // alone: "missing field `pressure`" left its unit to guess), after the lines are cut.
    const MISSING: &str = "missing field `";
    for line in &mut said {
        if let Some(at) = line.find(MISSING)
            && let Some((field, _)) = line[at + MISSING.len()..].split_once('`')
            && let Some(what) = field_said(field)
        {
            let end = at + MISSING.len() + field.len() + 1;
            line.insert_str(end, &format!(": {what}"));
        }
    }
    // A scene's own field at fault on its first line (`protocol = ...` outside `[scan]`) is
    // said by its fields; only a first line that is no TOML asks.
    let of_fields = ["unknown field", "missing field", "belongs", "unknown value"]
        .iter()
        .any(|w| text.contains(w));
    if source.span().is_some_and(|span| span.start < 200)
        && text.contains("at line 1,")
        && !of_fields
    {
        said.push(
            "(is it a scene? a scene is a TOML file of [sheet], [scan] and [[touch]] tables, as \
             in sim/scenes/)"
                .to_string(),
        );
    }
    said.join("\n")
}
