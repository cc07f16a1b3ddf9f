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

/// A pixel noise with a cheaper floor: the touch rule makes each region's z, its largest
/// value over noise, from the pixels whose value over the floor could beat the best so far,
/// and finds what the exhaustive maximum over every pixel's own noise finds, asking fewer.
#[test]
fn a_noise_floor_gives_the_exhaustive_z_asking_fewer_pixels() {
    struct Floored<'a> {
        sd: &'a [f64],
        floor: &'a [f64],
        asked: &'a std::cell::Cell<usize>,
    }
    impl PixelNoise for Floored<'_> {
        fn sd(&mut self, p: usize) -> Option<f64> {
            self.asked.set(self.asked.get() + 1);
            self.sd.get(p).copied()
        }
        fn floor(&mut self, p: usize) -> Option<f64> {
            self.floor.get(p).copied()
        }
    }
    let n = 40;
    let g = grid(n);
    let mut rng = et_core::rng::Rng::new(4);
    let a = bump(n, 10.0, 12.0, 4.0, 1.0);
    let b = bump(n, 28.0, 27.0, 3.0, 0.6);
    let image: Vec<Option<f64>> = a
        .iter()
        .zip(&b)
        .map(|(a, b)| Some(a + b + 0.02 * rng.normal()))
        .collect();
    // Each pixel's noise, and a floor below it (some pixels with none: made for every such
    // pixel, as its bound is unknown).
    let sd: Vec<f64> = (0..n * n).map(|_| 0.01 + 0.05 * rng.uniform()).collect();
    let floor: Vec<f64> = sd
        .iter()
        .enumerate()
        .map(|(p, s)| {
            if p % 17 == 0 {
                0.0
            } else {
                s * (0.3 + 0.7 * rng.uniform())
            }
        })
        .collect();
    let exhaustive = touch_rule(&g, &image, 0.1, 5.0, |p: usize| sd.get(p).copied());
    let asked = std::cell::Cell::new(0);
    let floored = Floored {
        sd: &sd,
        floor: &floor,
        asked: &asked,
    };
    let found = touch_rule(&g, &image, 0.1, 5.0, floored);
    assert_eq!(found, exhaustive);
    assert!(
        found.len() >= 2 && found.iter().all(|r| r.z.is_some()),
        "{found:?}"
    );
    let pixels: usize = found.iter().map(|r| r.pixels.len()).sum();
    assert!(asked.get() < pixels / 2, "{} of {pixels}", asked.get());
}
