//! Why a model blob is refused, and why a frame cannot be classified.

use super::*;

/// Why a model blob is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ModelError {
    /// Shorter than a header, or not the length its dimensions imply.
    #[error("model blob is {got} bytes, its header implies {expected}")]
    Length {
        /// Bytes the header's dimensions imply (0 if the header itself is missing).
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// Not a model blob.
    #[error("not a model blob (bad magic)")]
    Magic,
    /// A format version this build does not read.
    #[error("model format version {got}, this build reads {MODEL_VERSION}")]
    Version {
        /// The version found.
        got: u16,
    },
    /// Unknown kind or precision byte, or reserved bytes not zero.
    #[error("model header has an unknown kind, precision or reserved byte")]
    Header,
    /// Fewer than 2 classes, no feature, or more features than the frame has.
    #[error("model needs >= 2 classes and 1..=K features")]
    Dimensions,
    /// The protocol in the header is not valid.
    #[error("model protocol: {0}")]
    Protocol(ProtocolError),
    /// The header's frame length is not the protocol's K.
    #[error("model says K = {got}, its protocol has K = {expected}")]
    FrameLength {
        /// K of the protocol.
        expected: u16,
        /// K in the header.
        got: u16,
    },
    /// The CRC does not match: the blob is damaged.
    #[error("model blob CRC mismatch (damaged)")]
    Checksum,
    /// A feature index points past the frame.
    #[error("feature {feature} indexes past the frame")]
    FeatureIndex {
        /// Which feature.
        feature: u16,
    },
    /// A feature's mean or scale is NaN or infinite (past single precision, in which the
    /// tables are held: an edited 1e300 is infinite there).
    #[error(
        "feature {feature}'s mean or scale is NaN or infinite in single precision (past \
         3.4e38), in which the tables are held"
    )]
    NonFiniteFeature {
        /// Which feature.
        feature: u16,
    },
    /// A class's table holds a NaN or infinite value (its position, prior, constant, vector
    /// or factor; past single precision).
    #[error(
        "class {class}'s table (position, prior, mean or weights, factor) holds a NaN or \
         infinite value in single precision (past 3.4e38), in which the tables are held"
    )]
    NonFinite {
        /// Which class.
        class: u16,
    },
    /// A feature's frame index is not above the one before: each frame value is a feature at
    /// most once, in frame order (a repeated index would read one channel twice).
    #[error(
        "feature {feature}'s frame index repeats or is below the one before (each frame value once, in frame order)"
    )]
    FeatureOrder {
        /// Which feature.
        feature: u16,
    },
    /// A feature's scale is not positive.
    #[error("feature {feature} has a non-positive scale")]
    Scale {
        /// Which feature.
        feature: u16,
    },
    /// A Cholesky factor has a diagonal entry that is not positive: the covariance is singular.
    #[error("class {class} has a singular covariance")]
    Singular {
        /// Which class.
        class: u16,
    },
    /// A class covariance is too ill-conditioned for f32 evaluation ([`MIN_PIVOT_RATIO`]).
    #[error("class {class} covariance is too ill-conditioned for f32 (regularise it)")]
    IllConditioned {
        /// Which class.
        class: u16,
    },
    /// A table given to [`write_model`] has the wrong length, or the output is too short.
    #[error("model tables have inconsistent lengths")]
    Table,
}

/// Why a frame could not be classified.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EvalError {
    /// The frame is not as long as the model's K.
    #[error("frame has {got} values, the model expects {expected}")]
    FrameLength {
        /// The model's K.
        expected: usize,
        /// The frame's length.
        got: usize,
    },
    /// Scratch shorter than 2p.
    #[error("scratch of {given}, need {needed}")]
    Scratch {
        /// Needed.
        needed: usize,
        /// Given.
        given: usize,
    },
    /// A used voltage is NaN or infinite, or a discriminant overflowed.
    #[error("non-finite voltage or discriminant")]
    NonFinite,
    /// A referenced model needs the untouched frame V_0 (K values) and got none or a frame
    /// of the wrong length.
    #[error("the model is referenced: it needs the untouched frame (K values)")]
    Untouched,
}
