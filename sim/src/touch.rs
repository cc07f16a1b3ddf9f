//! Touches (docs/method.md §1): pressing the fabric raises its local conductance, non-linearly in the
//! pressure.
//!
//! A touch is a patch of contact (centre, radius, and a [`Footprint`]: a disc, or the ellipse
//! of a finger pressed at a slant) at a pressure. The piezoresistive law maps pressure to a
//! conductance multiplier; the contact profile spreads it over the patch with a smooth edge. Several touches multiply. What the network sees is an [`Inclusion`]: a region
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
    /// The contact's shape (default: a disc of `radius`).
    #[serde(default)]
    pub footprint: Footprint,
}

/// The shape of a contact patch: an ellipse with the area of the disc of the touch's radius r,
/// semi-axes r sqrt(e) along `angle` and r / sqrt(e) across it. A fingertip pressed straight
/// down touches a disc (e = 1); pressed at a slant, its pad touches an ellipse whose long axis
/// points along the finger (e about 1.5 for a finger at 30 to 45 degrees to the sheet).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Footprint {
    /// e: the long axis over the short one (>= 1; 1 = a disc, at most [`MAX_ELONGATION`]).
    pub elongation: f64,
    /// Direction of the long axis, rad counter-clockwise from +x.
    pub angle: f64,
}

/// The most elongated footprint a touch may have (a finger laid flat: about 3).
pub const MAX_ELONGATION: f64 = 10.0;

impl Default for Footprint {
    fn default() -> Self {
        Self::ROUND
    }
}

impl Footprint {
    /// A disc.
    pub const ROUND: Self = Self {
        elongation: 1.0,
        angle: 0.0,
    };

    /// `offset` (m, from the centre) in units of a footprint of radius `radius`: the
    /// ellipse's own radius, 1 on its outline (for a disc, |offset| / radius).
    #[must_use]
    pub fn scaled_distance(&self, offset: [f64; 2], radius: f64) -> f64 {
        let (s, c) = self.angle.sin_cos();
        let along = c * offset[0] + s * offset[1];
        let across = -s * offset[0] + c * offset[1];
        let e = self.elongation.sqrt();
        (along / e).hypot(across * e) / radius
    }

    /// Whether the footprint is one the simulator takes: elongation finite in
    /// [1, [`MAX_ELONGATION`]], angle finite.
    #[must_use]
    pub fn is_valid(&self) -> bool {
        (1.0..=MAX_ELONGATION).contains(&self.elongation) && self.angle.is_finite()
    }
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

/// A disc (or an ellipse, by its [`Footprint`]) of the sheet whose conductance is multiplied by
/// `multiplier` at its centre, with a smooth edge (full effect to 0.8 r, cos^2 taper to
/// nothing at 1.2 r, r the footprint's own radius along each direction).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Inclusion {
    /// Centre, m.
    pub position: [f64; 2],
    /// Radius, m.
    pub radius: f64,
    /// Conductance multiplier (> 0; 1 = no change).
    pub multiplier: f64,
    /// Shape: a disc of `radius`, or the ellipse of the same area.
    pub footprint: Footprint,
}

impl Inclusion {
    /// The inclusion of a touch under `piezo`.
    #[must_use]
    pub fn of_touch(t: &Touch, piezo: &Piezo) -> Self {
        Self {
            position: t.position,
            radius: t.radius,
            multiplier: piezo.multiplier(t.pressure),
            footprint: t.footprint,
        }
    }

    /// A round inclusion.
    #[must_use]
    pub fn disc(position: [f64; 2], radius: f64, multiplier: f64) -> Self {
        Self {
            position,
            radius,
            multiplier,
            footprint: Footprint::ROUND,
        }
    }

    /// Fraction of the full effect at `offset` (m) from the centre.
    #[must_use]
    pub fn profile(&self, offset: [f64; 2]) -> f64 {
        let rho = self.footprint.scaled_distance(offset, self.radius);
        if rho <= 0.8 {
            1.0
        } else if rho >= 1.2 {
            0.0
        } else {
            let c = (std::f64::consts::FRAC_PI_2 * (rho - 0.8) / 0.4).cos();
            c * c
        }
    }

    /// Distance beyond which the inclusion has no effect, m (1.2 times the long semi-axis).
    #[must_use]
    pub fn reach(&self) -> f64 {
        1.2 * self.radius * self.footprint.elongation.sqrt()
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
            let offset = [mid[0] - inc.position[0], mid[1] - inc.position[1]];
            if offset[0].hypot(offset[1]) < inc.reach() {
                m *= 1.0 + (inc.multiplier - 1.0) * inc.profile(offset);
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
        let inc = Inclusion::disc([0.0, 0.0], 0.01, 3.0);
        let along_x = |d: f64| inc.profile([d, 0.0]);
        assert_eq!(along_x(0.0), 1.0);
        assert_eq!(along_x(0.008), 1.0);
        assert!((along_x(0.01) - 0.5).abs() < 1e-12);
        assert_eq!(along_x(0.012), 0.0);
        // A disc's profile is the same in every direction.
        assert!((inc.profile([0.006, 0.008]) - along_x(0.01)).abs() < 1e-12);
        let steps: Vec<f64> = (0..100).map(|i| along_x(i as f64 * 1.3e-4)).collect();
        // Steepest slope of the taper: pi / 0.8 per unit of d / r; steps are 0.013 r.
        assert!(
            steps
                .windows(2)
                .all(|w| w[1] <= w[0] && w[0] - w[1] <= 0.013 * std::f64::consts::PI / 0.8 + 1e-12)
        );
    }

    #[test]
    fn an_elliptic_footprint_has_the_discs_area_and_points_along_its_angle() {
        let r = 0.01;
        let e: f64 = 2.25; // semi-axes 1.5 r and r / 1.5
        for angle in [0.0, 0.4, std::f64::consts::FRAC_PI_2, 2.5] {
            let f = Footprint {
                elongation: e,
                angle,
            };
            assert!(f.is_valid());
            let (s, c) = f64::sin_cos(angle);
            // On the outline at the ends of both semi-axes.
            let long = [1.5 * r * c, 1.5 * r * s];
            let short = [-r / 1.5 * s, r / 1.5 * c];
            assert!((f.scaled_distance(long, r) - 1.0).abs() < 1e-12, "{angle}");
            assert!((f.scaled_distance(short, r) - 1.0).abs() < 1e-12, "{angle}");
            // Symmetric through the centre.
            assert!(
                (f.scaled_distance([0.003, -0.002], r) - f.scaled_distance([-0.003, 0.002], r))
                    .abs()
                    < 1e-15
            );
            // Area inside the outline (scaled distance < 1) on a fine grid: pi r^2.
            let (n, half) = (400, 2.0 * r);
            let h = 2.0 * half / n as f64;
            let inside = (0..n * n)
                .filter(|k| {
                    let p = [
                        -half + (k % n) as f64 * h + h / 2.0,
                        -half + (k / n) as f64 * h + h / 2.0,
                    ];
                    f.scaled_distance(p, r) < 1.0
                })
                .count();
            let area = inside as f64 * h * h;
            let disc = std::f64::consts::PI * r * r;
            assert!(
                (area / disc - 1.0).abs() < 0.01,
                "{angle}: {area} vs {disc}"
            );
        }
        // The reach covers the long semi-axis's taper.
        let inc = Inclusion {
            footprint: Footprint {
                elongation: e,
                angle: 0.0,
            },
            ..Inclusion::disc([0.0, 0.0], r, 3.0)
        };
        assert!((inc.reach() - 1.2 * 1.5 * r).abs() < 1e-15);
        assert!(inc.profile([1.19 * 1.5 * r, 0.0]) > 0.0);
        assert_eq!(inc.profile([0.0, 1.21 * r / 1.5]), 0.0);
        for bad in [0.5, f64::NAN, MAX_ELONGATION * 1.01, f64::INFINITY] {
            let f = Footprint {
                elongation: bad,
                angle: 0.0,
            };
            assert!(!f.is_valid(), "{bad}");
        }
        assert!(
            !Footprint {
                elongation: 1.0,
                angle: f64::NAN
            }
            .is_valid()
        );
    }
}
