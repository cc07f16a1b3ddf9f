//! The fabric's conductance uneven over the sheet: a smooth field of cosine modes.

/// The fabric's conductance, uneven over the sheet and smooth: relative to nominal it is
/// exp(sum a_ij cos(i pi u) cos(j pi v)) over 0 <= i, j <= 2 except i = j = 0, with u, v the
/// position scaled to 0..1 across the sheet's bounding box. The constant mode is left out: the
/// sheet's mean conductance is the front end's (`frontend::SetSpread::conductance`). A knitted
/// fabric is not uniform, and it does not stay so: it relaxes unevenly where it was stretched
/// or pressed, and temperature and humidity vary across it, so each measurement set finds a
/// slightly different field.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Unevenness {
    /// a_ij in the order (0,1) (0,2) (1,0) (1,1) (1,2) (2,0) (2,1) (2,2): natural-log units.
    pub coefficients: [f64; 8],
}

impl Unevenness {
    /// The modes (i, j) in the order of [`Unevenness::coefficients`].
    pub const MODES: [(u8, u8); 8] = [
        (0, 1),
        (0, 2),
        (1, 0),
        (1, 1),
        (1, 2),
        (2, 0),
        (2, 1),
        (2, 2),
    ];

    /// A field with every coefficient drawn normal with rms `rms`.
    #[must_use]
    pub fn draw(rms: f64, rng: &mut et_core::rng::Rng) -> Self {
        let mut coefficients = [0.0; 8];
        for a in &mut coefficients {
            *a = rms * rng.normal();
        }
        Self { coefficients }
    }

    /// The conductance multiplier at `p` (m) on a sheet with bounding box `bounds`
    /// ([x0, y0, x1, y1], m).
    #[must_use]
    pub fn multiplier(&self, p: [f64; 2], bounds: [f64; 4]) -> f64 {
        let [x0, y0, x1, y1] = bounds;
        let u = (p[0] - x0) / (x1 - x0).max(f64::MIN_POSITIVE);
        let v = (p[1] - y0) / (y1 - y0).max(f64::MIN_POSITIVE);
        let pi = std::f64::consts::PI;
        let exponent: f64 = Self::MODES
            .iter()
            .zip(&self.coefficients)
            .map(|(&(i, j), a)| a * (f64::from(i) * pi * u).cos() * (f64::from(j) * pi * v).cos())
            .sum();
        exponent.exp()
    }
}
