//! Why a board model cannot be used on a dataset, a sheet or frames, and why it has no blob
//! for the board's model slot.

use crate::dataset::DataError;
use crate::fit::FitError;
use et_core::board::MODEL_SLOT_BYTES;

/// What of a scan decides what its features mean: L, the protocol, the current and the gain.
fn said(c: &et_core::config::ScanConfig) -> String {
    format!(
        "L = {}, {} drive, {} uA, gain {}",
        c.electrodes,
        c.protocol,
        f64::from(c.current_na) / 1e3,
        c.gain
    )
}

/// [`UseError::FrameLength`]'s words: the frames' length, the untouched frame's (none was
/// said as "an untouched frame of 0"), and rows of the model's feature count said as its
/// features given for frames (a dataset's `x`).
fn frame_length_said(
    frame: usize,
    v0: usize,
    k: usize,
    features: usize,
    scan: &et_core::config::ScanConfig,
) -> String {
    let untouched = match v0 {
        0 => " without an untouched frame".to_string(),
        n if n == frame => String::new(),
        n => format!(" and an untouched frame of {n}"),
    };
    let features = if frame == features && frame != k {
        format!(
            " ({frame} values are the features the model reads: its features given for frames? \
             It reads them from whole frames; an et dataset is given whole)"
        )
    } else {
        String::new()
    };
    format!(
        "frames of {frame} values{untouched}: the model takes frames of K = {k} values, of {}{features}",
        said(scan)
    )
}

/// Why a model could not be used on a dataset or a sheet; says which of the two is at fault.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum UseError {
    /// The dataset does not hold what the model needs.
    #[error("data: {0}")]
    Data(#[from] DataError),
    /// The model was trained on another scan than the data's: its features are other
    /// measurements.
    #[error(
        "the model was trained on a scan of {}, the data were measured with {}: train a model \
         on data of this scan",
        said(model),
        said(data)
    )]
    Config {
        /// The model's scan.
        model: et_core::config::ScanConfig,
        /// The data's scan.
        data: et_core::config::ScanConfig,
    },
    /// A frame (or the untouched frame) is not of the model's K values.
    #[error("{}", frame_length_said(*.frame, *.v0, *.k, *.features, .scan))]
    FrameLength {
        /// Values in each frame given.
        frame: usize,
        /// Values in the untouched frame given (0 when none).
        v0: usize,
        /// Values in the model's frames.
        k: usize,
        /// The features the model reads of each frame.
        features: usize,
        /// The model's scan.
        scan: et_core::config::ScanConfig,
    },
    /// A value the model reads, of a frame or the untouched frame, that is NaN or infinite.
    #[error(
        "{}, value {index}: {value}, where a finite number belongs",
        frame.map_or_else(|| "the untouched frame".to_string(), |r| format!("frame {r}"))
    )]
    NotFinite {
        /// The frame (0-based row; None for the untouched frame).
        frame: Option<usize>,
        /// The value's index in the frame (0-based).
        index: usize,
        /// The value.
        value: f64,
    },
    /// The data have another number of classes than the model: their labels name other
    /// places.
    #[error(
        "the data have {data} classes, the model {model}: they were collected on another grid, \
         so their labels name other places; evaluate on data of the model's grid (the same \
         scene and et collect --grid)"
    )]
    Classes {
        /// The model's classes.
        model: usize,
        /// The data's classes (their centres).
        data: usize,
    },
    /// A class of the data is elsewhere than the model's class of that number.
    #[error(
        "the data's class {class} is at ({:.1}, {:.1}) mm, the model's at ({:.1}, {:.1}) mm: \
         the data were collected on another sheet or grid, so their labels name other places; \
         evaluate on data of the model's grid (the same scene and et collect --grid)",
        data_mm[0], data_mm[1], model_mm[0], model_mm[1]
    )]
    Places {
        /// The class.
        class: usize,
        /// The model's centre of it, mm.
        model_mm: [f64; 2],
        /// The data's centre of it, mm.
        data_mm: [f64; 2],
    },
    /// The sheet has another number of electrodes than the one the model was trained on.
    #[error(
        "the model was trained on a sheet of {model} electrodes, this one has {given}: train a \
         model on this sheet (et collect --scene, et train)"
    )]
    Electrodes {
        /// The model's sheet's electrodes.
        model: usize,
        /// This sheet's.
        given: usize,
    },
    /// An electrode of the sheet is elsewhere than on the sheet the model was trained on:
    /// the model's classes are places on another sheet.
    #[error(
        "the model was trained on another sheet: its electrode {} was at ({:.1}, {:.1}) mm, \
         this sheet's is at ({:.1}, {:.1}) mm, so its classes name places on that sheet; give \
         the scene it was trained on (--scene), or train a model on this sheet (et collect \
         --scene, et train)",
        electrode + 1, model_mm[0], model_mm[1], given_mm[0], given_mm[1]
    )]
    Sheet {
        /// The electrode (0-based; said from 1).
        electrode: usize,
        /// Where it was on the model's sheet, mm.
        model_mm: [f64; 2],
        /// Where it is on this sheet, mm.
        given_mm: [f64; 2],
    },
    /// Evaluation on the dataset failed (e.g. a class the model does not know).
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The exported blob does not parse.
    #[error("model blob: {0}")]
    Blob(et_core::model::ModelError),
    /// The chip's evaluation refused an observation.
    #[error("observation {row}: {error}")]
    Frame {
        /// The observation (0-based row).
        row: usize,
        /// Why.
        error: et_core::model::EvalError,
    },
}

/// Why a board model has no blob for a model slot of the board.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SlotError {
    /// The blob's own validation refuses the tables.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// Even in f16 the blob is larger than a slot.
    #[error("the model needs {bytes} bytes in f16, a slot of the board holds {MODEL_SLOT_BYTES}")]
    TooLarge {
        /// The f16 blob's size.
        bytes: usize,
    },
}
