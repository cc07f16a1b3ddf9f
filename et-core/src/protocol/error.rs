//! Why a protocol cannot be built.

use super::{ElectrodeId, L_MAX, L_MIN, MAX_MEASURE_SKIPS, MUX_CHANNELS, SkipSet};

/// Why a protocol cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ProtocolError {
    /// The electrode count is odd or outside `L_MIN..=L_MAX`.
    #[error(
        "electrode count {electrodes} is not supported: use an even number from {L_MIN} to {L_MAX}"
    )]
    ElectrodeCount {
        /// The count asked for.
        electrodes: u8,
    },
    /// The drive skip puts the sink more than half way round (`drive_skip + 1 > L / 2`).
    #[error(
        "drive skip {drive_skip} reaches past the opposite electrode of {electrodes}: use \
         drive_skip + 1 <= L/2 (at most {} here)", electrodes / 2 - 1
    )]
    DriveSkip {
        /// The skip asked for.
        drive_skip: u8,
        /// The electrode count L.
        electrodes: u8,
    },
    /// No measurement skip, more than [`MAX_MEASURE_SKIPS`], or one past half way round.
    #[error(
        "measure skips {measure_skips} do not fit {electrodes} electrodes: give 1 to \
         {MAX_MEASURE_SKIPS} skips, each with skip + 1 <= L/2 (at most {} here)", electrodes / 2 - 1
    )]
    MeasureSkips {
        /// The skip set asked for.
        measure_skips: SkipSet,
        /// The electrode count L.
        electrodes: u8,
    },
    /// The protocol leaves no usable measurement (every pair touches a current electrode).
    #[error("the protocol leaves no usable measurement")]
    Empty,
    /// An electrode number the muxes cannot address (`>= MUX_CHANNELS`).
    #[error("electrode {} cannot be addressed by a {MUX_CHANNELS}:1 multiplexer", .electrode.0)]
    MuxRange {
        /// The electrode asked for.
        electrode: ElectrodeId,
    },
}
