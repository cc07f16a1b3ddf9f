use crate::segment::{bump, grid};
use et_recon::touches::*;

/// A speck (one pixel at 30 % of the top: the boundary's specks on a real tank at small
/// alpha) passes the peak's share but not the mass's; a weaker object as wide as the
/// strongest (40 % of its peak) passes both.
#[test]
fn a_speck_above_the_peaks_share_is_no_object_a_weak_wide_one_is() {
    let n = 40;
    let g = grid(n);
    let strong = bump(n, 10.0, 10.0, 3.0, 1.0);
    let weak = bump(n, 30.0, 28.0, 3.0, -0.4);
    let mut image: Vec<Option<f64>> = strong.iter().zip(&weak).map(|(a, b)| Some(a + b)).collect();
    let speck = 5 * n + 35;
    image[speck] = Some(0.3);
    // The speck alone would pass the share of the peak.
    let found = touches(&g, &image, &[], OBJECT_FRACTION, PROMINENCE);
    assert!(found.iter().any(|r| r.peak_pixel == speck), "{found:?}");
    let found = objects(&g, &image, &[], OBJECT_FRACTION, 0.0);
    let signs: Vec<i8> = found.iter().map(|o| o.sign).collect();
    assert_eq!(signs, [1, -1], "{found:?}");
    assert!(found.iter().all(|o| o.region.peak_pixel != speck));
}
