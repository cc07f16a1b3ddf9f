//! Live touch sensing from any source: frames in, images and touch events out. The viewer
//! (`et view`) and `et stream` are both thin shells over this module.
//!
//! - [`Source`]: where frames come from, a simulated scene (which a pointer can press), a
//!   recording (replay with pause and seek) or a board on a serial port.
//! - [`Processor`]: V_0 from the first untouched frames, then per frame dV = V_m - V_0, the
//!   one-step image onto a pixel grid (docs/method.md §6), its touches (regions split at their saddles),
//!   and a [`TouchEvent`] when a touch stands out of the image's noise; with a trained model also the class,
//!   its posterior and the posterior-weighted position (docs/method.md §9, §11).
//! - [`Monitor`]: frame rate, per-channel SNR and BVC over time, and lost frames.

use std::collections::VecDeque;
use std::path::Path;
use std::time::{Duration, Instant};

use et_core::ScanConfig;
use et_core::config::ConfigError;
use et_core::protocol::ProtocolKind;
use et_core::stats;
use et_core::wire::{Command, Event, Uplink};
use et_sim::scene::{Detail, Run, Scene, SceneError};
use et_sim::sheet::SheetSpec;
use et_sim::touch::Touch;
use serde::Serialize;

use crate::link::{Counters, Keepalive, Link, LinkChange, LinkError};
use crate::recording::{self, Recording};
use et_core::sheet::Sheet;
use et_learn::model::Board;
use et_recon::background::ElectrodeMisfit;
use et_recon::{
    AlphaRule, FrameOperator, Imager, ImagingError, MeshPlan, Method, PixelGrid, ReconError,
    Reconstructor, Region, SquaredRows, TOUCH_Z, default_threshold, touch_rule,
};

mod contacts;
mod monitor;
mod processor;
mod source;

pub use contacts::{BACK_AFTER, Contact, Contacts, SAID_TIMES};
pub use monitor::Monitor;
pub use processor::{Output, Processor, Referencing, Settings, TouchEvent};
pub use source::{
    Health, PortSource, ReplaySource, SimSource, Source, SourceSpec, default_scene, open_source,
};

/// One frame as the live pipeline sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct LiveFrame {
    /// Sequence number (gaps: frames lost).
    pub seq: u32,
    /// Device time of the scan, us.
    pub t_us: u32,
    /// What produced it.
    pub config: ScanConfig,
    /// The frame's `et_core::wire::FLAG_*` bits (rail, compliance, ...).
    pub flags: u8,
    /// V_m, V (K values).
    pub voltages: Vec<f32>,
    /// The true touches, when the source knows them (simulated or recorded from the sim).
    pub truth: Option<Vec<Touch>>,
    /// The board's own class for this frame (`Event::Touch`).
    pub chip_class: Option<ChipClass>,
}

impl From<et_core::wire::HostFrame> for LiveFrame {
    /// A board's frame as it came off the wire (no truth, no class yet).
    fn from(f: et_core::wire::HostFrame) -> Self {
        Self {
            seq: f.seq,
            t_us: f.timestamp.0,
            config: f.config,
            flags: f.flags,
            voltages: f.voltages,
            truth: None,
            chip_class: None,
        }
    }
}

/// A board's event that people need to hear of, in words: a fault it found (a front end
/// that cannot scan its configuration, a saturated or suspect electrode) or a command it
/// refused; None for the rest (status, replies, touches).
#[must_use]
pub fn board_report(event: &et_core::wire::Event) -> Option<String> {
    use et_core::wire::Event;
    match event {
        Event::Fault(f) => Some(format!("the board reports: {f}")),
        Event::Refused { command, reason } => {
            Some(format!("the board refused {command}: {reason}"))
        }
        _ => None,
    }
}

/// What a frame's flags (`et_core::wire::FLAG_*`) say of its readings, in words: the board
/// found samples on an ADC rail, or its current source in compliance, while scanning it; None
/// when they say neither. Its values are then not what the sheet gave, and an image of them
/// places touches wrongly.
#[must_use]
pub fn flagged_readings(flags: u8) -> Option<String> {
    use et_core::wire::{FLAG_COMPLIANCE, FLAG_RAIL};
    if !readings_flagged(flags) {
        return None;
    }
    let kinds: Vec<&str> = [
        (
            FLAG_RAIL,
            "readings with samples on an ADC rail (clipped: a gain too high for the sheet, or \
             a contact that opens)",
        ),
        (
            FLAG_COMPLIANCE,
            "the current source in compliance (a load more than it can drive: a contact come \
             loose or dry; the readings too small)",
        ),
    ]
    .into_iter()
    .filter(|(flag, _)| flags & flag != 0)
    .map(|(_, said)| said)
    .collect();
    (!kinds.is_empty()).then(|| format!("the board flagged {}", kinds.join(" and ")))
}

/// Whether a frame's flags say its readings are wrong ([`flagged_readings`] has words for
/// them): a test of bits, for counting every frame.
#[must_use]
pub fn readings_flagged(flags: u8) -> bool {
    flags & (et_core::wire::FLAG_RAIL | et_core::wire::FLAG_COMPLIANCE) != 0
}

/// The board's flags said so far, each kind once: a stream flagged frame after frame says
/// the first of each.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FlagsSaid(u8);

impl FlagsSaid {
    /// The words ([`flagged_readings`]) of the kinds `flags` carries that were not said
    /// before, which are said from now on; None when there are none.
    pub fn first(&mut self, flags: u8) -> Option<String> {
        let words = flagged_readings(flags & !self.0)?;
        self.mark(flags);
        Some(words)
    }

    /// The kinds `flags` carries, said elsewhere (with V_0's status): not said again.
    pub fn mark(&mut self, flags: u8) {
        self.0 |= flags;
    }
}

/// The class a board found for a frame, as its `Event::Touch` says.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChipClass {
    /// The class.
    pub class: u16,
    /// How far its discriminant leads the runner-up's (nats).
    pub margin: f32,
}

/// The protocols the live pipeline offers, plus automatic selection (docs/method.md §8).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProtocolChoice {
    /// One protocol.
    Fixed(ProtocolKind),
    /// `et_recon::select::Selector` picks from the regions.
    Automatic,
}

/// Why the live pipeline could not open a source, talk to a board or process a frame.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LiveError {
    /// The scene file could not be read, or its simulation failed.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The recording could not be read.
    #[error(transparent)]
    Recording(#[from] recording::RecordingError),
    /// A recording made with another electrode count than the sheet it is played on.
    #[error("{}: frames of {recorded} electrodes, the sheet has {sheet}", .path.display())]
    OtherSheet {
        /// The recording.
        path: std::path::PathBuf,
        /// Electrodes in its frames.
        recorded: u8,
        /// Electrodes of the sheet.
        sheet: u8,
    },
    /// The serial port could not be opened, or the board refused or did not answer.
    #[error("{port}: {error}")]
    Link {
        /// The port.
        port: String,
        /// What went wrong.
        error: LinkError,
    },
    /// The board did not answer the first command.
    #[error(
        "no answer from the board on {port} at {baud} baud ({error}): {}",
        crate::link::silent_board_hint(*baud)
    )]
    Silent {
        /// The port.
        port: String,
        /// The rate it was opened at.
        baud: u32,
        /// The link's timeout.
        error: LinkError,
    },
    /// Bytes that are not a model blob.
    #[error("not a valid model blob: {0}")]
    Blob(et_core::model::ModelError),
    /// The board loaded the model but could not take V_0 for it.
    #[error("the board verified and loaded the model, but taking V_0 failed: {0}")]
    Tare(LinkError),
    /// Another system's frames (CSV, .npy, .npz, .mat) could not be read.
    #[error(transparent)]
    Frames(#[from] crate::frames::FramesError),
    /// Another system's frames under a scene the live pipeline does not play (a protocol
    /// file).
    #[error(
        "{scene}: {error}: image the frames with `et reconstruct --scene {scene} --frames {}`",
        frames.display()
    )]
    Table {
        /// The scene's file, as the user named it.
        scene: String,
        /// The frames' file.
        frames: std::path::PathBuf,
        /// Why the scene's scan is not one the live pipeline plays.
        error: et_sim::scene::FieldError,
    },
    /// Another system's frames with no scene: they carry neither the sheet nor the protocol.
    #[error(
        "{}: another system's frames carry neither the sheet they were measured on nor its \
         protocol, and imaged on et's default 13 x 13 cm sheet their touches would be in the \
         wrong places: give a scene with --scene (its [sheet] and [scan] protocol, docs/guide.md \
         \"Your own system's frames\")",
        .0.display()
    )]
    NoScene(std::path::PathBuf),
    /// A recording plays the protocol it was recorded with.
    #[error("a recording plays the protocol it was recorded with")]
    Recorded,
    /// A scan configuration the board cannot scan.
    #[error("scan configuration: {0}")]
    Config(#[from] ConfigError),
    /// An electrode to leave out that is not the sheet's, as its user counts them
    /// (`Processor::counted_from_zero`).
    #[error(
        "electrode {electrode}: the sheet's electrodes are {base} to {}{}",
        u32::from(*base) + u32::from(*count) - 1,
        if *base == 0 { String::new() } else { format!(" (its protocol file counts them from {base})") }
    )]
    Counted {
        /// The electrode named.
        electrode: u16,
        /// The number of the first.
        base: u16,
        /// How many the sheet has.
        count: u16,
    },
    /// Electrodes that cannot be left out of the images (`Processor::set_left_out`).
    #[error("leaving electrodes out: {0}")]
    LeftOut(#[from] et_core::schedule::ScheduleError),
    /// A frame whose value count is not its protocol's K.
    #[error("frame {seq}: {got} values, its protocol has {expected}")]
    FrameLength {
        /// The frame's sequence number.
        seq: u32,
        /// Values in it.
        got: usize,
        /// K of its protocol.
        expected: usize,
    },
    /// A frame imaged against a reference of one frame, whose noise cannot be estimated from
    /// its own dV (the protocol has too little redundancy).
    #[error(
        "frame {seq}: one reference frame gives no noise, and this protocol has too little \
         redundancy to estimate it from the frame: take two or more reference frames"
    )]
    UnknownNoise {
        /// The frame's sequence number.
        seq: u32,
    },
    /// A frame with a NaN or infinite value.
    #[error("frame {seq}: a value is not finite")]
    NonFinite {
        /// The frame's sequence number.
        seq: u32,
    },
    /// The sheet could not be meshed or modelled, or its reconstruction set up.
    #[error(transparent)]
    Imaging(#[from] ImagingError),
    /// The one-step reconstruction matrix could not be built.
    #[error("reconstruction: {0}")]
    Recon(#[from] ReconError),
    /// The reference frames could not be averaged.
    #[error("reference frames: {0}")]
    Stats(#[from] stats::StatsError),
}

impl LiveError {
    /// Whether the untouched reference V_0 itself is refused (one value throughout,
    /// magnitudes without their sign, or running against the model): every frame after it
    /// would be refused alike, so a stream ends here rather than skip frame after frame.
    #[must_use]
    pub fn is_reference(&self) -> bool {
        matches!(
            self,
            LiveError::Imaging(
                ImagingError::ReferenceNotMeasured(_)
                    | ImagingError::ReferenceNotSigned(_)
                    | ImagingError::ReferenceAgainstModel(..)
            )
        )
    }
}
