use et_recon::pixels::PixelGrid;
use et_recon::segment::*;
use et_recon::touches::objects;

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
