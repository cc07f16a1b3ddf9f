//! Touches (docs/method.md §1): pressing the fabric raises its local conductance, non-linearly in the
//! pressure.
//!
//! A touch is a disc of contact (centre, radius) at a pressure. The piezoresistive law maps
//! pressure to a conductance multiplier; the contact profile spreads it over the disc with a
//! smooth edge. Several touches multiply. What the network sees is an [`Inclusion`]: a region
//! whose conductance is multiplied, which is also how tests ask for arbitrary contrasts.

use serde::{Deserialize, Serialize};

use crate::network::Grid;

/// One finger (or any object) on the sheet.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Touch {
    /// Centre `[x, y]`, m.
    pub position: [f64; 2],
    /// Contact radius, m (a fingertip: 5 to 8 mm; docs/method.md §7's target of 1.46 % of a 22 cm disc:
    /// 13 mm).
    pub radius: f64,
    /// Contact pressure, Pa (gentle: below 10 kPa; medium: 10 to 100 kPa).
    pub pressure: f64,
}

/// Pressure to conductance: m(p) = 1 + gain (p/p_half)^n / (1 + (p/p_half)^n), a saturating
/// (Hill) law: yarn contact area grows quickly at first, then saturates.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Piezo {
    /// Largest relative conductance increase (multiplier 1 + gain at high pressure).
    pub gain: f64,
    /// Pressure of half the full effect, Pa.
    pub half_pressure: f64,
    /// Hill exponent (steepness).
    pub exponent: f64,
}

impl Default for Piezo {
    /// PPy fabric roughly: conductance x2.5 at 20 kPa, x4.3 at 100 kPa, x1.4 at 5 kPa.
    fn default() -> Self {
        Self {
            gain: 4.0,
            half_pressure: 30e3,
            exponent: 1.2,
        }
    }
}

impl Piezo {
    /// The conductance multiplier at pressure `p` Pa (1 at p <= 0).
    #[must_use]
    pub fn multiplier(&self, p: f64) -> f64 {
        if p.is_nan() || p <= 0.0 {
            return 1.0;
        }
        // x / (1 + x) with x = (p / p_half)^n, written so that a steep law (large n) saturates
        // to 0 or 1 instead of dividing infinity by infinity.
        1.0 + self.gain / (1.0 + (self.half_pressure / p).powf(self.exponent))
    }
}

/// The largest conductance multiplier the simulator applies: a touched region 10^6 times more
/// conductive than the fabric is a perfect conductor to within 10^-6 of the boundary voltages,
/// and larger ratios only cost the update its precision (a gain of 10^15 once gave a 13 V
/// change where a perfect conductor gives 24 mV). Larger multipliers act as this one.
pub const MAX_MULTIPLIER: f64 = 1e6;

/// A disc of the sheet whose conductance is multiplied by `multiplier` at its centre, with a
/// smooth edge (full effect to 0.8 r, cos^2 taper to nothing at 1.2 r).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Inclusion {
    /// Centre, m.
    pub position: [f64; 2],
    /// Radius, m.
    pub radius: f64,
    /// Conductance multiplier (> 0; 1 = no change).
    pub multiplier: f64,
}

impl Inclusion {
    /// The inclusion of a touch under `piezo`.
    #[must_use]
    pub fn of_touch(t: &Touch, piezo: &Piezo) -> Self {
        Self {
            position: t.position,
            radius: t.radius,
            multiplier: piezo.multiplier(t.pressure),
        }
    }

    /// Fraction of the full effect at distance `d` from the centre.
    #[must_use]
    pub fn profile(&self, d: f64) -> f64 {
        let rho = d / self.radius;
        if rho <= 0.8 {
            1.0
        } else if rho >= 1.2 {
            0.0
        } else {
            let c = (std::f64::consts::FRAC_PI_2 * (rho - 0.8) / 0.4).cos();
            c * c
        }
    }

    /// Distance beyond which the inclusion has no effect, m.
    #[must_use]
    pub fn reach(&self) -> f64 {
        1.2 * self.radius
    }
}

/// The edges whose conductance changes, with their multipliers (sorted by edge index), for a
/// set of inclusions (they multiply where they overlap).
#[must_use]
pub fn edge_multipliers(grid: &Grid, inclusions: &[Inclusion]) -> Vec<(usize, f64)> {
    let mut out: Vec<(usize, f64)> = Vec::new();
    for (k, e) in grid.edges.iter().enumerate() {
        let (a, b) = (grid.nodes[e.u as usize], grid.nodes[e.v as usize]);
        let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let mut m = 1.0;
        for inc in inclusions {
            let d = (mid[0] - inc.position[0]).hypot(mid[1] - inc.position[1]);
            if d < inc.reach() {
                m *= 1.0 + (inc.multiplier - 1.0) * inc.profile(d);
            }
        }
        if m != 1.0 {
            out.push((k, m.min(MAX_MULTIPLIER)));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn piezo_law_is_monotone_and_saturates() {
        let p = Piezo::default();
        assert_eq!(p.multiplier(0.0), 1.0);
        assert_eq!(p.multiplier(-5.0), 1.0);
        assert_eq!(p.multiplier(f64::NAN), 1.0);
        // A steep law is a step, not NaN.
        let steep = Piezo {
            exponent: 500.0,
            ..p
        };
        assert_eq!(steep.multiplier(60e3), 1.0 + p.gain);
        assert_eq!(steep.multiplier(15e3), 1.0);
        assert!((steep.multiplier(30e3) - (1.0 + p.gain / 2.0)).abs() < 1e-12);
        let mut last = 1.0;
        for kpa in [1.0, 5.0, 10.0, 20.0, 50.0, 100.0, 1000.0] {
            let m = p.multiplier(kpa * 1e3);
            assert!(m > last, "{kpa} kPa");
            last = m;
        }
        assert!(last < 1.0 + p.gain);
        assert!((p.multiplier(30e3) - (1.0 + p.gain / 2.0)).abs() < 1e-12);
    }

    #[test]
    fn profile_is_smooth_and_bounded() {
        let inc = Inclusion {
            position: [0.0, 0.0],
            radius: 0.01,
            multiplier: 3.0,
        };
        assert_eq!(inc.profile(0.0), 1.0);
        assert_eq!(inc.profile(0.008), 1.0);
        assert!((inc.profile(0.01) - 0.5).abs() < 1e-12);
        assert_eq!(inc.profile(0.012), 0.0);
        let steps: Vec<f64> = (0..100).map(|i| inc.profile(i as f64 * 1.3e-4)).collect();
        // Steepest slope of the taper: pi / 0.8 per unit of d / r; steps are 0.013 r.
        assert!(
            steps
                .windows(2)
                .all(|w| w[1] <= w[0] && w[0] - w[1] <= 0.013 * std::f64::consts::PI / 0.8 + 1e-12)
        );
    }
}
