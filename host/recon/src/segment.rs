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
