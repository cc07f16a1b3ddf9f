//! Why a model blob is refused, and why a frame cannot be classified.

use super::*;

/// Why a model blob is refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ModelError {
    /// Shorter than a header, or not the length its dimensions imply.
    Length {
        /// Bytes the header's dimensions imply (0 if the header itself is missing).
        expected: usize,
        /// Bytes given.
        got: usize,
    },
    /// Not a model blob.
    Magic,
    /// A format version this build does not read.
    Version {
        /// The version found.
        got: u16,
    },
    /// Unknown kind or precision byte, or reserved bytes not zero.
    Header,
    /// Fewer than 2 classes, no feature, or more features than the frame has.
    Dimensions,
    /// The protocol in the header is not valid.
    Protocol(ProtocolError),
    /// The header's frame length is not the protocol's K.
    FrameLength {
        /// K of the protocol.
        expected: u16,
        /// K in the header.
        got: u16,
    },
    /// The CRC does not match: the blob is damaged.
    Checksum,
    /// A feature index points past the frame.
    FeatureIndex {
        /// Which feature.
        feature: u16,
    },
    /// A stored value is NaN or infinite.
    NonFinite,
    /// A feature's scale is not positive.
    Scale {
        /// Which feature.
        feature: u16,
    },
    /// A Cholesky factor has a diagonal entry that is not positive: the covariance is singular.
    Singular {
        /// Which class.
        class: u16,
    },
    /// A class covariance is too ill-conditioned for f32 evaluation ([`MIN_PIVOT_RATIO`]).
    IllConditioned {
        /// Which class.
        class: u16,
    },
    /// A table given to [`write_model`] has the wrong length, or the output is too short.
    Table,
}

impl core::fmt::Display for ModelError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            ModelError::Length { expected, got } => {
                write!(
                    f,
                    "model blob is {got} bytes, its header implies {expected}"
                )
            }
            ModelError::Magic => write!(f, "not a model blob (bad magic)"),
            ModelError::Version { got } => {
                write!(
                    f,
                    "model format version {got}, this build reads {MODEL_VERSION}"
                )
            }
            ModelError::Header => write!(
                f,
                "model header has an unknown kind, precision or reserved byte"
            ),
            ModelError::Dimensions => write!(f, "model needs >= 2 classes and 1..=K features"),
            ModelError::Protocol(e) => write!(f, "model protocol: {e}"),
            ModelError::FrameLength { expected, got } => {
                write!(f, "model says K = {got}, its protocol has K = {expected}")
            }
            ModelError::Checksum => write!(f, "model blob CRC mismatch (damaged)"),
            ModelError::FeatureIndex { feature } => {
                write!(f, "feature {feature} indexes past the frame")
            }
            ModelError::NonFinite => write!(f, "model holds a NaN or infinite value"),
            ModelError::Scale { feature } => {
                write!(f, "feature {feature} has a non-positive scale")
            }
            ModelError::Singular { class } => write!(f, "class {class} has a singular covariance"),
            ModelError::IllConditioned { class } => {
                write!(
                    f,
                    "class {class} covariance is too ill-conditioned for f32 (regularise it)"
                )
            }
            ModelError::Table => write!(f, "model tables have inconsistent lengths"),
        }
    }
}

impl core::error::Error for ModelError {}

/// Why a frame could not be classified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EvalError {
    /// The frame is not as long as the model's K.
    FrameLength {
        /// The model's K.
        expected: usize,
        /// The frame's length.
        got: usize,
    },
    /// Scratch shorter than 2p.
    Scratch {
        /// Needed.
        needed: usize,
        /// Given.
        given: usize,
    },
    /// A used voltage is NaN or infinite, or a discriminant overflowed.
    NonFinite,
    /// A referenced model needs the untouched frame V_0 (K values) and got none or a frame
    /// of the wrong length.
    Untouched,
}

impl core::fmt::Display for EvalError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            EvalError::FrameLength { expected, got } => {
                write!(f, "frame has {got} values, the model expects {expected}")
            }
            EvalError::Scratch { needed, given } => write!(f, "scratch of {given}, need {needed}"),
            EvalError::NonFinite => write!(f, "non-finite voltage or discriminant"),
            EvalError::Untouched => write!(
                f,
                "the model is referenced: it needs the untouched frame (K values)"
            ),
        }
    }
}

impl core::error::Error for EvalError {}
