//! The wire's events in words, as a user reads them (no Rust names).

use core::fmt;

use super::{CommandTag, Fault, Refusal};

impl fmt::Display for CommandTag {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Self::Configure => "the scan configuration",
            Self::Start => "start",
            Self::Stop => "stop",
            Self::Ping => "ping",
            Self::ModelBegin => "the start of a model upload",
            Self::ModelChunk => "a piece of a model upload",
            Self::ModelCommit => "the end of a model upload",
            Self::ModelClear => "clearing the model",
            Self::Unknown => "a command it could not read",
            Self::Tare => "tare",
        })
    }
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Malformed(e) => write!(f, "the packet was damaged ({e})"),
            Self::BadConfig => f.write_str("the configuration is not one it can scan"),
            Self::UploadOrder => f.write_str("model upload commands out of order"),
            Self::TooLarge => f.write_str("the model does not fit its model storage"),
            Self::BadModel => {
                f.write_str("the model failed its checksum or checks (the old model is kept)")
            }
            Self::ModelMismatch => f.write_str("the model was trained for another scan"),
            Self::Storage => f.write_str("its model storage failed (the old model is kept)"),
        }
    }
}

impl fmt::Display for Fault {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Frontend { seq } => write!(
                f,
                "the front end failed at scan {seq}: that frame was not sent (just after a new \
                 configuration, the front end cannot scan it: another electrode count than its \
                 own? the board goes back to the scan it made before)"
            ),
            Self::Saturated { seq, measurements } => write!(
                f,
                "frame {seq}: {measurements} measurement(s) on the ADC's rail (lower the gain \
                 or the current)"
            ),
            Self::Electrode { electrode } => {
                write!(f, "electrode {electrode} looks disconnected or shorted")
            }
            Self::Overflow { dropped } => {
                write!(f, "{dropped} frame(s) dropped: the link could not keep up")
            }
        }
    }
}
