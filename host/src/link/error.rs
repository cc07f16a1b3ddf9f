//! What can go wrong on the link, in words: a port that cannot be opened said with why.

use et_core::wire::{CommandTag, Refusal, WireError};

/// What can go wrong on the link.
#[derive(Debug, thiserror::Error)]
pub enum LinkError {
    /// The port could not be opened.
    #[error("{}", open_said(path, error))]
    Open {
        /// The port's path.
        path: String,
        /// Why (said in the message where it adds to it; not a cause said again).
        error: serialport::Error,
    },
    /// Writing to the port failed (the cable may be out: the reader reconnects).
    #[error("writing to the serial port: {0}")]
    Write(std::io::Error),
    /// The port is closed right now (waiting to reconnect).
    #[error("the serial port is disconnected (waiting for it to come back)")]
    Disconnected,
    /// No reply within the timeout.
    #[error(
        "no answer from the device while waiting for {}",
        waiting_for.map_or("a message".into(), |t| format!("the reply to {t:?}"))
    )]
    Timeout {
        /// The command whose reply was waited for (none: any message).
        waiting_for: Option<et_core::wire::CommandTag>,
    },
    /// The device refused a command.
    #[error("the device refused {command}: {reason}")]
    Refused {
        /// The command.
        command: CommandTag,
        /// The device's reason.
        reason: Refusal,
    },
    /// The device refused the start of a model upload for its size (its storage, which it
    /// does not report, is smaller).
    #[error(
        "the device refused the model: its {bytes} bytes ({:.0} KiB) do not fit the device's \
         model storage (et's firmware holds {} KiB a slot on the board, {} KiB in its QEMU \
         image); fewer classes or features make it smaller (et train --keep N, et collect \
         --grid), and half precision halves it (et export --precision f16)",
        *.bytes as f64 / 1024.0,
        et_core::board::MODEL_SLOT_BYTES / 1024,
        et_core::board::QEMU_MODEL_SLOT_BYTES / 1024
    )]
    TooLarge {
        /// The blob's size.
        bytes: usize,
    },
    /// A message could not be encoded (a bug: commands always fit).
    #[error("encoding a command: {0}")]
    Encode(WireError),
}

/// What to check when a board never answers on a port opened at `baud`, for people: the rate
/// when it is not the firmware's, else the board and the port.
#[must_use]
pub fn silent_board_hint(baud: u32) -> String {
    if baud == et_core::board::BAUD {
        "is the board powered and flashed with et's firmware, and is this its port? \
         `et ports` lists the ports"
            .to_string()
    } else {
        format!(
            "et's firmware talks at {} baud: leave out --baud",
            et_core::board::BAUD
        )
    }
}

/// Why the port at `path` could not be opened, in words, with what to do: a path that is a
/// file, a folder or a device that is no terminal is not a port; a port another program holds,
/// or one the user may not open (Linux: the `dialout` group), is said so (the system's "Not a
/// typewriter" and "Permission denied" were all they said).
fn open_said(path: &str, error: &serialport::Error) -> String {
    const LIST: &str = "`et ports` lists the ports";
    let said = error.to_string();
    let meta = std::fs::metadata(path);
    let why = if path.trim().is_empty() {
        return format!("no serial port given: give the board's port ({LIST})");
    } else if meta.as_ref().is_ok_and(std::fs::Metadata::is_dir) {
        "a folder, not a port".to_string()
    } else if meta.as_ref().is_ok_and(std::fs::Metadata::is_file) {
        "a file, not a port (a recording is played with --replay: et stream, et view)".to_string()
    } else if meta.is_err() {
        "no such port: is the board plugged in, and the path right?".to_string()
    } else if said.contains("typewriter") || said.contains("Inappropriate ioctl") {
        format!("not a serial port ({said})")
    } else if matches!(
        error.kind(),
        serialport::ErrorKind::Io(std::io::ErrorKind::PermissionDenied)
    ) || said.contains("Permission denied")
    {
        "permission denied: on Linux, join the group that owns the port (often dialout: \
         sudo usermod -aG dialout $USER, then log in again)"
            .to_string()
    } else if said.contains("busy") {
        format!(
            "{said}: another program holds it (a viewer or et stream left open, a serial monitor?)"
        )
    } else {
        said
    };
    format!("cannot open serial port {path}: {why} ({LIST})")
}
