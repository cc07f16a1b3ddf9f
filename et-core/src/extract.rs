//! One voltage from one burst (docs/method.md §3, Algorithm 1): drop the first t_s samples (the switching
//! transient), take the median of the rest. The median, not the mean, so that spikes do not
//! move the result; samples on an ADC rail are counted so that the caller can flag them.

use crate::frontend::AdcScale;

/// The median of one burst, in ADC codes, and how many of its samples sat on a rail.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Extracted {
    /// Median code (the mean of the two middle codes for an even count).
    pub median_code: f32,
    /// Samples (after t_s) at code 0 or the top code.
    pub rail_samples: u16,
}

/// Median of `codes`, reordering them in place. `None` for an empty slice.
///
/// For an even count the median is the mean of the two middle values, so it can end in .5.
#[must_use]
pub fn median_in_place(codes: &mut [u16]) -> Option<f32> {
    let n = codes.len();
    if n == 0 {
        return None;
    }
    let (below, &mut upper, _) = codes.select_nth_unstable(n / 2);
    if n % 2 == 1 {
        return Some(f32::from(upper));
    }
    // Everything below index n/2 is <= upper; the lower middle is the largest of them.
    let lower = below.iter().copied().max().unwrap_or(upper);
    Some((f32::from(lower) + f32::from(upper)) / 2.0)
}

/// Drops the first `settle` samples of `burst` and returns the median of the rest (Algorithm 1),
/// with the rail count. Reorders the kept samples. `None` if nothing is left after `settle`.
#[must_use]
pub fn settle_median(burst: &mut [u16], settle: usize, scale: &AdcScale) -> Option<Extracted> {
    let kept = burst.get_mut(settle..)?;
    let rail_samples = kept.iter().filter(|&&c| scale.at_rail(c)).count() as u16;
    median_in_place(kept).map(|median_code| Extracted {
        median_code,
        rail_samples,
    })
}

/// Sub-section medians (Algorithms 2-3): drops `settle` samples, cuts the rest into `out.len()`
/// equal consecutive sub-sections (a remainder at the end is not used) and writes the median
/// of each into `out`. Each sub-section median is one training observation of this
/// measurement. Returns the rail count over the used samples, `None` if a sub-section would be
/// empty.
#[must_use]
pub fn subsection_medians(
    burst: &mut [u16],
    settle: usize,
    scale: &AdcScale,
    out: &mut [Extracted],
) -> Option<u16> {
    let kept = burst.get_mut(settle..)?;
    let n_sub = out.len();
    if n_sub == 0 {
        return Some(0);
    }
    let len = kept.len() / n_sub;
    if len == 0 {
        return None;
    }
    let mut rail_total = 0u16;
    for (chunk, slot) in kept.chunks_exact_mut(len).zip(out.iter_mut()) {
        let rail_samples = chunk.iter().filter(|&&c| scale.at_rail(c)).count() as u16;
        rail_total = rail_total.saturating_add(rail_samples);
        *slot = Extracted {
            median_code: median_in_place(chunk)?,
            rail_samples,
        };
    }
    Some(rail_total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use std::vec::Vec;

    fn sorted_median(v: &[u16]) -> f32 {
        let mut s = v.to_vec();
        s.sort_unstable();
        let n = s.len();
        if n % 2 == 1 {
            f32::from(s[n / 2])
        } else {
            (f32::from(s[n / 2 - 1]) + f32::from(s[n / 2])) / 2.0
        }
    }

    proptest! {
        #[test]
        fn median_matches_sorting(v in proptest::collection::vec(any::<u16>(), 1..300)) {
            let mut w = v.clone();
            prop_assert_eq!(median_in_place(&mut w), Some(sorted_median(&v)));
        }
    }

    #[test]
    fn settle_drops_the_transient_and_median_ignores_spikes() {
        let scale = AdcScale::bipolar_16bit(5.0, 1);
        // A decaying transient, then a plateau at 40 000 with two spikes and one rail hit.
        let mut burst: Vec<u16> = (0..10).map(|i| 60_000 - i * 2_000).collect();
        burst.extend([
            40_000, 40_001, 39_999, 50_000, 40_000, 65_535, 40_002, 39_998, 10_000, 40_000,
        ]);
        let e = settle_median(&mut burst, 10, &scale).unwrap();
        assert_eq!(e.median_code, 40_000.0);
        assert_eq!(e.rail_samples, 1);
        assert_eq!(settle_median(&mut [1, 2, 3], 3, &scale), None);
        assert_eq!(settle_median(&mut [1, 2, 3], 4, &scale), None);
    }

    #[test]
    fn subsections_each_take_their_own_median() {
        let scale = AdcScale::bipolar_16bit(5.0, 1);
        // settle 2, then three sections of 3 samples, then a remainder of 1 that is unused.
        let mut burst = [9, 9, 10, 11, 12, 20, 22, 21, 0, 31, 30, 7];
        let mut out = [Extracted {
            median_code: 0.0,
            rail_samples: 0,
        }; 3];
        let rails = subsection_medians(&mut burst, 2, &scale, &mut out).unwrap();
        let medians: Vec<f32> = out.iter().map(|e| e.median_code).collect();
        assert_eq!(medians, [11.0, 21.0, 30.0]);
        assert_eq!(rails, 1);
        assert_eq!(out[2].rail_samples, 1);
        let mut too_many = [Extracted {
            median_code: 0.0,
            rail_samples: 0,
        }; 11];
        assert_eq!(
            subsection_medians(&mut burst, 2, &scale, &mut too_many),
            None
        );
    }
}
