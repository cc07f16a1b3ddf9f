//! What is wrong with an archive or one of its arrays.

/// What is wrong with an archive or one of its arrays.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{fault}", array.as_ref().map(|a| format!("array '{a}': ")).unwrap_or_default())]
pub struct NpzError {
    /// The array concerned (without `.npy`), when it is about one.
    pub array: Option<String>,
    /// What is wrong.
    pub fault: NpzFault,
}

/// What is wrong with an archive, or with one array of it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NpzFault {
    /// An archive et would write past the zip format's 32-bit limits.
    #[error("more than 4 GiB or 65 535 arrays: too large for an .npz written by et")]
    TooLarge,
    /// The zip structure is damaged (which part).
    #[error("not a readable .npz: {0}")]
    Broken(&'static str),
    /// An entry compressed otherwise than numpy does (deflate), by the zip method given.
    #[error(
        "compressed with zip method {0}, not deflate as numpy.savez_compressed writes: \
         write it with numpy.savez or numpy.savez_compressed"
    )]
    Method(usize),
    /// A deflated entry that does not inflate to the size the archive states.
    #[error(
        "damaged: it does not inflate to the size the archive states (a disk or copy \
         error?): copy or write the archive again"
    )]
    Inflate,
    /// Deflated entries that inflate past the data files' limit together.
    #[error(
        "its compressed arrays inflate past {0} bytes together: more than et reads from \
         one file"
    )]
    Inflates(u64),
    /// An entry the file ends inside.
    #[error("cut short (the file ends inside it)")]
    CutShort,
    /// An entry whose bytes do not give the checksum the archive stored for them.
    #[error(
        "damaged: its bytes do not match the checksum stored with them (a disk or copy \
         error?): copy or write the archive again"
    )]
    Checksum,
    /// Two entries of one name.
    #[error(
        "stored twice in the archive (numpy reads the last, so which one is meant is unclear): \
         write the archive again"
    )]
    Twice,
    /// No array of the name (the names it holds, said).
    #[error("not in the archive, which holds {held}")]
    Missing {
        /// The archive's arrays' names, separated by commas.
        held: String,
    },
    /// The `.npy` inside is damaged (which part).
    #[error("{0}")]
    Npy(&'static str),
    /// The `.npy` header lacks a key.
    #[error("header has no '{0}'")]
    NoKey(&'static str),
    /// Complex values (a system's magnitude and phase, as one number).
    #[error(
        "complex values ('{0}'): save the real voltages, the part you mean: the real part \
         (np.real), the magnitude (np.abs) or the quadrature (np.imag)"
    )]
    Complex(String),
    /// Python objects (a pickled array), not values.
    #[error(
        "Python objects (dtype object, pickled), not numbers: save numbers, \
         np.save(f, np.asarray(x, dtype=float))"
    )]
    Objects,
    /// A type other than numbers, booleans or text.
    #[error("unsupported type '{0}' (numbers, booleans or text only)")]
    Type(String),
    /// Text where numbers belong.
    #[error("text where numbers belong")]
    TextNotNumbers,
    /// Another number of dimensions than the reader's.
    #[error("{found}-d, a {want}-d array was expected")]
    Dimensions {
        /// The array's.
        found: usize,
        /// The reader's.
        want: usize,
    },
    /// An element that is not 0 to 65 535.
    #[error("element {index} is {value}, not a whole number in 0..=65535")]
    NotWhole {
        /// Its index.
        index: usize,
        /// Its value.
        value: f64,
    },
    /// Not one text.
    #[error("not a single text")]
    NotText,
    /// A character that is not one.
    #[error("not valid text")]
    InvalidText,
}

pub(super) fn error(array: Option<&str>, fault: NpzFault) -> NpzError {
    NpzError {
        array: array.map(String::from),
        fault,
    }
}
