//! What a touch looks like to a downstream program, and how `et stream --json` rounds it.

use super::*;

/// What a touch looks like to a downstream program (`et stream --json` prints these).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TouchEvent {
    /// Device time of the frame, us.
    pub t_us: u32,
    /// Frame sequence number.
    pub seq: u32,
    /// The class (a trained model's, or the board's), when there is a model.
    pub class: Option<u16>,
    /// Position on the sheet, mm: the model's posterior-weighted class centre, else the
    /// strongest image region's centroid. Printed to 0.1 mm (a pixel is several mm).
    #[serde(serialize_with = "tenths")]
    pub position_mm: [f64; 2],
    /// The image's strongest pixel over that pixel's noise on the untouched sheet (a z-score:
    /// noise alone stays below about 3.5 on the simulator; a 20 kPa press reaches tens).
    /// Printed to 0.1.
    #[serde(serialize_with = "tenth")]
    pub intensity: f64,
    /// The model's posterior of its class (0 to 1), when there is a model. Printed to 0.001.
    #[serde(serialize_with = "thousandth")]
    pub confidence: Option<f64>,
    /// Touches in the image: its regions split at their saddles (`recon::touches`), above
    /// the touch factor times their noise, with half the strongest peak and a quarter
    /// fingertip's area (`et_recon::select::significant`).
    pub regions: usize,
}

/// `x` rounded to `digits` decimals for printing (JSON has no NaN: non-finite stays as serde
/// writes it, null).
fn rounded(x: f64, digits: i32) -> f64 {
    let scale = 10f64.powi(digits);
    if x.is_finite() {
        (x * scale).round() / scale
    } else {
        x
    }
}

fn tenths<S: serde::Serializer>(p: &[f64; 2], s: S) -> Result<S::Ok, S::Error> {
    [rounded(p[0], 1), rounded(p[1], 1)].serialize(s)
}

fn tenth<S: serde::Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
    rounded(*x, 1).serialize(s)
}

fn thousandth<S: serde::Serializer>(x: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    x.map(|c| rounded(c, 3)).serialize(s)
}
