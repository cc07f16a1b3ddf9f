//! What a collection holds, checked against the memory free before any press.

use et_core::ScanConfig;
use et_core::protocol::Halving;

use super::{CollectError, Plan};

/// Bytes a collection of `observations` rows of `features` holds at its peak: each visit's
/// rows as collected and as its matrix, the visits stacked into one, and the file's writer
/// (measured with `/usr/bin/time -v et collect --grid 7x7 --scans 1|20`: 3.5 copies of the
/// features in double precision to CSV, 4.5 to .npz; five are counted, the labels, positions
/// and pressures beside them).
#[must_use]
pub fn collection_bytes(observations: usize, features: usize) -> u64 {
    5 * (observations as u64) * (features as u64 + 4) * 8
}

impl Plan {
    /// Observations a collection of `classes` classes over `visits` visits makes: one per
    /// sub-section of every scan of every class.
    #[must_use]
    pub fn observations(&self, classes: usize, visits: usize) -> usize {
        classes
            .saturating_mul(visits)
            .saturating_mul(self.scans)
            .saturating_mul(self.subsections)
    }

    /// Refuses a collection of `classes` over `visits` that would not fit in the memory free
    /// (`--grid 100x100` at the default scans held 24 million observations, about 18 GB, and
    /// ran for hours before the system would have ended it), naming its size and what to cut.
    ///
    /// # Errors
    /// [`CollectError::TooLarge`]; [`CollectError::Config`] for a configuration that is not
    /// valid.
    pub fn fits_in_memory(
        &self,
        config: ScanConfig,
        classes: usize,
        visits: usize,
    ) -> Result<(), CollectError> {
        let features = config.validate()?.features(Halving::Reciprocity).count();
        let observations = self.observations(classes, visits);
        let need_bytes = collection_bytes(observations, features);
        match et_core::text::available_memory_bytes() {
            Some(free_bytes) if need_bytes > free_bytes => Err(CollectError::TooLarge {
                observations,
                features,
                need_bytes,
                free_bytes,
            }),
            _ => Ok(()),
        }
    }
}
