//! Dynamic protocol selection (docs/method.md §8, proposed by the method and never built): image with
//! the adjacent protocol until a touch shows; a region near the centre switches to
//! pseudo-polar, several regions switch to PP-PP, a region near the boundary stays adjacent.
//!
//! The two questions docs/method.md §8 leaves open, answered here:
//! - *Several ROIs*: the image's regions of interest are split at their saddles
//!   ([`crate::touches`]: under noise the alpha that suits the data joins two touches
//!   over a saddle far above the threshold), a peak counts only when it stands out of its
//!   pixel's noise ([`crate::above_noise`]), and then when it reaches `peak_ratio` of
//!   the strongest's and its area reaches `min_area` ([`significant`]): ringing and noise
//!   specks do not.
//! - *A wrong first detection*: a switch happens only after the same decision holds for
//!   `confirm` consecutive frames, and after `lost` frames without any touch the selector
//!   returns to adjacent. A wrong switch therefore needs a wrong decision held for `confirm`
//!   frames, and it undoes itself once the touch is gone.
//!
//! "Central" is read as: the region's centroid within xi d_c of the sheet's centre along both
//! x and y (d_c: centre-to-electrode distance; docs/method.md §8 gives xi = 0.5).

use et_core::protocol::ProtocolKind;

use crate::Region;

/// Settings of the selector.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// Sheet centre, m.
    pub centre: [f64; 2],
    /// d_c: centre-to-electrode distance, m.
    pub d_c: f64,
    /// xi (docs/method.md §8: 0.5).
    pub xi: f64,
    /// A region counts when its peak is at least this share of the strongest's.
    pub peak_ratio: f64,
    /// ... and its area at least this, m^2.
    pub min_area: f64,
    /// Frames a new decision must hold before the protocol switches.
    pub confirm: usize,
    /// Frames without a touch before returning to adjacent.
    pub lost: usize,
}

impl Settings {
    /// docs/method.md §8's xi = 0.5, regions of half the strongest peak and a quarter of a 10 mm
    /// fingertip's area, 2 frames to confirm, 3 to give up.
    #[must_use]
    pub fn new(centre: [f64; 2], d_c: f64) -> Self {
        Self {
            centre,
            d_c,
            xi: 0.5,
            peak_ratio: 0.5,
            min_area: 0.25 * std::f64::consts::PI * 0.005 * 0.005,
            confirm: 2,
            lost: 3,
        }
    }
}

/// The regions that count as touches (see the module docs), strongest first.
#[must_use]
pub fn significant(regions: &[Region], settings: &Settings) -> Vec<Region> {
    let top = regions
        .iter()
        .map(|r| r.peak)
        .fold(f64::NEG_INFINITY, f64::max);
    regions
        .iter()
        .filter(|r| r.peak >= settings.peak_ratio * top && r.area >= settings.min_area)
        .cloned()
        .collect()
}

/// The protocol docs/method.md §8 asks for given the significant regions (None: no touch).
#[must_use]
pub fn decide(regions: &[Region], settings: &Settings) -> Option<ProtocolKind> {
    match regions {
        [] => None,
        [one] => {
            let (dx, dy) = (
                (one.centroid[0] - settings.centre[0]).abs(),
                (one.centroid[1] - settings.centre[1]).abs(),
            );
            let limit = settings.xi * settings.d_c;
            Some(if dx < limit && dy < limit {
                ProtocolKind::PseudoPolar
            } else {
                ProtocolKind::Adjacent
            })
        }
        _ => Some(ProtocolKind::PpPp),
    }
}

/// The selector's state between frames.
#[derive(Clone, Debug, PartialEq)]
pub struct Selector {
    settings: Settings,
    current: ProtocolKind,
    /// A decision different from `current` and for how many frames it has held.
    pending: Option<(ProtocolKind, usize)>,
    /// Frames without a touch.
    quiet: usize,
}

impl Selector {
    /// Starts on the adjacent protocol.
    #[must_use]
    pub fn new(settings: Settings) -> Self {
        Self {
            settings,
            current: ProtocolKind::Adjacent,
            pending: None,
            quiet: 0,
        }
    }

    /// Its settings.
    #[must_use]
    pub fn settings(&self) -> &Settings {
        &self.settings
    }

    /// The protocol being scanned.
    #[must_use]
    pub fn current(&self) -> ProtocolKind {
        self.current
    }

    /// Feeds one frame's regions (the touches of [`crate::touches`] above the noise,
    /// or [`crate::regions`]; empty when no touch was detected); returns the new protocol when the scan should switch.
    pub fn step(&mut self, regions: &[Region]) -> Option<ProtocolKind> {
        let wanted = decide(&significant(regions, &self.settings), &self.settings);
        let Some(wanted) = wanted else {
            self.quiet += 1;
            self.pending = None;
            if self.quiet >= self.settings.lost && self.current != ProtocolKind::Adjacent {
                self.current = ProtocolKind::Adjacent;
                return Some(self.current);
            }
            return None;
        };
        self.quiet = 0;
        if wanted == self.current {
            self.pending = None;
            return None;
        }
        let held = match self.pending {
            Some((p, n)) if p == wanted => n + 1,
            _ => 1,
        };
        if held >= self.settings.confirm {
            self.current = wanted;
            self.pending = None;
            Some(wanted)
        } else {
            self.pending = Some((wanted, held));
            None
        }
    }
}
