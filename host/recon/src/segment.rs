//! Three-class segmentation of a difference image (docs/method.md §6.5): background, resistive
//! (the conductivity fell: a plastic rod, a cut) and conductive (it rose: a metal rod, a
//! press), the picture tomography challenges score.
//!
//! The classes come from the image's objects ([`crate::touches::objects`]), not from the
//! histogram of its values: a pixel is an object's class when it belongs to the object's
//! region and its value is at least [`SEGMENT_LEVEL`] of that object's peak; every other pixel
//! is background. So a class without an object that stands out of the noise stays empty (a
//! histogram's thresholds always make three classes, and draw the noise of an image with one
//! kind of target as the other kind), and each object's extent is set by its own peak, not by
//! the strongest object's.

use crate::touches::Object;

/// The share of its own peak a pixel of an object must reach to be drawn as that object's
/// class. A smooth image of a sharp-edged inclusion (the inclusion blurred by the
/// reconstruction's point spread) crosses about half its height at the inclusion's edge; the
/// smaller alpha, the sharper the image and the lower the best share. Chosen by the worst of
/// both real tanks under the default alpha rule (the challenge's score per case, 0.4 to 0.7
/// tried; 0.5 best by the worse tank, 0.80 and 0.84 a case): `ET_TANKS_LEVELS=0.4,0.5,0.6,0.7
/// cargo run --release -p et-host --example tanks`, docs/measurements.md "Defaults on real
/// tanks".
pub const SEGMENT_LEVEL: f64 = 0.5;

/// A pixel's class.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[repr(u8)]
pub enum Class {
    /// Neither object kind: the background's conductivity.
    Background = 0,
    /// The conductivity fell.
    Resistive = 1,
    /// The conductivity rose.
    Conductive = 2,
}

impl Class {
    /// The class of an object of `sign` (+1 conductive, -1 resistive).
    #[must_use]
    pub fn of_sign(sign: i8) -> Self {
        if sign > 0 {
            Self::Conductive
        } else {
            Self::Resistive
        }
    }
}

/// The three-class picture of `image` (one value per pixel, None outside the sheet) from its
/// `objects`: each object's pixels at or above `level` of its peak (by magnitude) take its
/// class, every other pixel of the sheet is background. Where two objects' pixels meet (they
/// do not overlap: an object's pixels have its sign), each keeps its own.
#[must_use]
pub fn segment(image: &[Option<f64>], objects: &[Object], level: f64) -> Vec<Option<Class>> {
    let mut classes: Vec<Option<Class>> =
        image.iter().map(|v| v.map(|_| Class::Background)).collect();
    for object in objects {
        let s = f64::from(object.sign);
        let cut = level * object.region.peak;
        for &p in &object.region.pixels {
            if image
                .get(p)
                .copied()
                .flatten()
                .is_some_and(|v| s * v >= cut)
            {
                classes[p] = Some(Class::of_sign(object.sign));
            }
        }
    }
    classes
}

/// The classes as numbers (0 background, 1 resistive, 2 conductive; None outside the sheet),
/// for the files and arrays that carry them beside an image's values.
#[must_use]
pub fn as_values(classes: &[Option<Class>]) -> Vec<Option<f64>> {
    classes
        .iter()
        .map(|c| c.map(|c| f64::from(c as u8)))
        .collect()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::pixels::PixelGrid;
    use crate::touches::objects;

    /// A square grid of `n` x `n` pixels of 1 mm.
    pub(crate) fn grid(n: usize) -> PixelGrid {
        PixelGrid {
            origin: [0.0, 0.0],
            size: 1e-3,
            width: n,
            height: n,
            triangle: vec![Some(0); n * n],
        }
    }

    /// A Gaussian bump of height `h` and width `w` pixels at pixel (cx, cy).
    pub(crate) fn bump(n: usize, cx: f64, cy: f64, w: f64, h: f64) -> Vec<f64> {
        (0..n * n)
            .map(|p| {
                let (x, y) = ((p % n) as f64 - cx, (p / n) as f64 - cy);
                h * (-(x * x + y * y) / (2.0 * w * w)).exp()
            })
            .collect()
    }

    #[test]
    fn two_objects_of_opposite_sign_give_their_classes_at_the_level_of_their_peaks() {
        let n = 40;
        let g = grid(n);
        let up = bump(n, 10.0, 10.0, 3.0, 1.0);
        let down = bump(n, 30.0, 28.0, 3.0, -0.6);
        let image: Vec<Option<f64>> = up.iter().zip(&down).map(|(a, b)| Some(a + b)).collect();
        let found = objects(&g, &image, &[], 0.25, 0.0);
        let classes = segment(&image, &found, SEGMENT_LEVEL);
        let count = |c: Class| classes.iter().filter(|&&k| k == Some(c)).count();
        // A Gaussian of width w is above L of its peak on a disc of radius w sqrt(2 ln(1/L)).
        let disc = std::f64::consts::PI * 9.0 * 2.0 * (1.0 / SEGMENT_LEVEL).ln();
        for c in [Class::Conductive, Class::Resistive] {
            let k = count(c) as f64;
            assert!(
                (k - disc).abs() < 0.35 * disc,
                "{c:?}: {k} pixels, the disc above {SEGMENT_LEVEL} of the peak has {disc:.0}"
            );
        }
        assert_eq!(classes[10 * n + 10], Some(Class::Conductive));
        assert_eq!(classes[28 * n + 30], Some(Class::Resistive));
        assert_eq!(classes[0], Some(Class::Background));
    }

    #[test]
    fn without_objects_every_pixel_of_the_sheet_is_background() {
        let image = vec![Some(0.1), None, Some(-0.2)];
        assert_eq!(
            segment(&image, &[], SEGMENT_LEVEL),
            vec![Some(Class::Background), None, Some(Class::Background)]
        );
    }
}
