//! A sheet with its electrodes, ready to answer "what do the electrodes read for this touch
//! state?" (docs/method.md §1-2), noiselessly. Noise, the ADC and timing are [`crate::frontend`]'s.

use et_core::protocol::Protocol;
use serde::{Deserialize, Serialize};

use crate::fast::FastNetwork;
use crate::network::{Grid, Network, NetworkError, Transfer, place_contacts};
use crate::touch::{Inclusion, Piezo, Touch, edge_multipliers};
use et_core::sheet::{ElectrodeSpec, FieldFault, SHEET_RESISTANCE, Shape, Sheet};

/// The simulated sheet: the physical sheet, and how the simulator models it (its grid, the
/// pressure-to-conductance law, a bend). A scene's `[sheet]` table holds all of these side by
/// side.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "SheetTable", into = "SheetTable")]
pub struct SheetSpec {
    /// Outline, fabric and electrodes: what imaging models too.
    pub physical: Sheet,
    /// Grid spacing, m. Default: [`SheetSpec::default_resolution`].
    pub resolution: Option<f64>,
    /// Pressure to conductance.
    pub piezo: Piezo,
    /// The sheet bent over a cylinder (docs/method.md §1: a 3 cm radius).
    pub bend: Option<Bend>,
}

/// A scene's `[sheet]` table as written: the physical fields and the simulator's side by side.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SheetTable {
    shape: Shape,
    #[serde(default = "default_rs")]
    sheet_resistance: f64,
    #[serde(default)]
    electrodes: ElectrodeSpec,
    #[serde(default)]
    resolution: Option<f64>,
    #[serde(default)]
    piezo: Piezo,
    #[serde(default)]
    bend: Option<Bend>,
}

impl From<SheetTable> for SheetSpec {
    fn from(t: SheetTable) -> Self {
        Self {
            physical: Sheet {
                shape: t.shape,
                sheet_resistance: t.sheet_resistance,
                electrodes: t.electrodes,
            },
            resolution: t.resolution,
            piezo: t.piezo,
            bend: t.bend,
        }
    }
}

impl From<SheetSpec> for SheetTable {
    fn from(s: SheetSpec) -> Self {
        Self {
            shape: s.physical.shape,
            sheet_resistance: s.physical.sheet_resistance,
            electrodes: s.physical.electrodes,
            resolution: s.resolution,
            piezo: s.piezo,
            bend: s.bend,
        }
    }
}

/// Direction along the sheet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// Along x.
    X,
    /// Along y.
    Y,
}

/// A sheet bent over a cylinder. Bending does not change a thin sheet's own geometry (a
/// cylinder is developable), so the network stays the flat one; what changes is the strain:
/// the fabric is stretched along the direction it curves by thickness / (2 radius), and a
/// stretched yarn conducts less: conductance along `curves` is divided by
/// 1 + gauge_factor x strain.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bend {
    /// Cylinder radius, m.
    pub radius: f64,
    /// The direction in which the sheet curves.
    pub curves: Axis,
    /// Fabric thickness, m (docs/method.md §1: 0.38 mm).
    #[serde(default = "default_thickness")]
    pub thickness: f64,
    /// Relative resistance change per unit strain.
    #[serde(default = "default_gauge")]
    pub gauge_factor: f64,
}

fn default_thickness() -> f64 {
    0.38e-3
}

fn default_gauge() -> f64 {
    3.0
}

impl Bend {
    /// Conductance multiplier of resistors along the curving direction.
    #[must_use]
    pub fn multiplier(&self) -> f64 {
        1.0 / (1.0 + self.gauge_factor * self.thickness / (2.0 * self.radius))
    }
}

fn default_rs() -> f64 {
    SHEET_RESISTANCE
}

/// The most grid nodes a sheet may have: the fast path keeps the untouched network's inverse,
/// nodes x nodes in f64 (12 000 nodes: 1.2 GB). The default resolution of the shipped scenes
/// stays under 6 500.
pub const MAX_GRID_NODES: usize = 12_000;

impl SheetSpec {
    /// The physical `sheet` at the simulator's defaults: the default resolution, the default
    /// fabric's piezoresistive law, flat.
    #[must_use]
    pub fn of(sheet: Sheet) -> Self {
        Self {
            physical: sheet,
            resolution: None,
            piezo: Piezo::default(),
            bend: None,
        }
    }

    /// A flat `width` x `height` m rectangle of the default fabric (30 kohm/sq) with `electrodes`
    /// default clips (5 mm, 1 kohm) equally spaced, at the default resolution.
    #[must_use]
    pub fn rectangle(width: f64, height: f64, electrodes: u8) -> Self {
        Self::of(Sheet::rectangle(width, height, electrodes))
    }

    /// The grid spacing used when none is given: 48 cells across the smaller side, at least 4
    /// per electrode pitch and 2 per electrode width, whichever is finest. Measured accuracy in
    /// the README (`cargo test -p et-sim --release resolution -- --nocapture`).
    #[must_use]
    pub fn default_resolution(&self) -> f64 {
        let Sheet {
            shape, electrodes, ..
        } = &self.physical;
        let pitch = shape.perimeter() / f64::from(electrodes.count.max(1));
        (shape.size() / 48.0)
            .min(pitch / 4.0)
            .min(electrodes.width / 2.0)
    }

    /// The grid spacing, m: `resolution`, else the default that follows the electrodes.
    #[must_use]
    pub fn spacing(&self) -> f64 {
        self.resolution.unwrap_or_else(|| self.default_resolution())
    }

    /// Whether touch `touch` of radius `radius` (m) is resolved by the grid: at least half
    /// its spacing. A smaller touch changes the edges whose midpoints it happens to reach, so
    /// its frames depend on where it falls between the nodes (a quarter-spacing touch gave 0
    /// to 2.9 times the finite elements' change, a half-spacing one 0.9 to 1.4 times, as a
    /// larger one does: `a_touch_under_the_grid_is_refused_not_aliased`).
    ///
    /// # Errors
    /// [`SheetError::Unresolved`].
    pub fn check_touch(&self, touch: usize, radius: f64) -> Result<(), SheetError> {
        let spacing = self.spacing();
        if radius < spacing / 2.0 {
            return Err(SheetError::Unresolved {
                touch,
                radius,
                spacing,
            });
        }
        Ok(())
    }

    /// The simulator's grid: its spacing's nodes within [`MAX_GRID_NODES`]. Checked when a
    /// network is built, not with the other fields: a sheet that only images measured frames
    /// (`et reconstruct --frames`, `et forward`, Python) never builds one, and a 1 m sheet with
    /// 5 mm electrodes was refused for a grid nothing would make.
    ///
    /// # Errors
    /// [`SheetError::TooManyNodes`].
    pub fn check_grid(&self) -> Result<(), SheetError> {
        let h = self.spacing();
        let nodes = self.physical.shape.area() / (h * h);
        if !nodes.is_finite() || nodes > MAX_GRID_NODES as f64 {
            return Err(SheetError::TooManyNodes {
                spacing: h,
                nodes,
                default: self.resolution.is_none(),
            });
        }
        Ok(())
    }

    /// Checks every field (the grid's size is [`SheetSpec::check_grid`]'s).
    ///
    /// # Errors
    /// [`SheetError`] naming the field.
    pub fn validate(&self) -> Result<(), SheetError> {
        self.physical.validate()?;
        if let Some(h) = self.resolution
            && !(h.is_finite() && h > 0.0 && h <= self.physical.shape.size() / 4.0)
        {
            let rule = "a positive spacing below a quarter of the sheet (m)";
            let fault = FieldFault::Value { value: h, rule };
            return Err(SheetError::field("sheet.resolution", fault));
        }
        let p = &self.piezo;
        let high = crate::touch::MAX_MULTIPLIER - 1.0;
        if !(p.gain.is_finite() && p.gain > -1.0 && p.gain <= high) {
            return Err(SheetError::field(
                "sheet.piezo.gain",
                FieldFault::Range {
                    value: p.gain,
                    low: -1.0,
                    high,
                    unit: "(beyond, the pressed fabric conducts perfectly already)",
                },
            ));
        }
        if !(p.half_pressure.is_finite()
            && p.half_pressure > 0.0
            && p.exponent.is_finite()
            && p.exponent > 0.0)
        {
            let rule = "half_pressure > 0 Pa and exponent > 0, both finite";
            return Err(SheetError::rule("sheet.piezo", rule));
        }
        if let Some(b) = &self.bend
            && !(b.radius.is_finite()
                && b.radius > 0.0
                && b.thickness > 0.0
                && b.thickness < b.radius
                && b.gauge_factor >= 0.0)
        {
            let rule = "radius > thickness > 0 m and gauge_factor >= 0";
            return Err(SheetError::rule("sheet.bend", rule));
        }
        Ok(())
    }
}

/// Nodes under a touch above which a fresh solve of the touched network is cheaper than the
/// fast path's low-rank update (whose dense solve costs the cube of the nodes). Measured with
/// `cargo bench -p et-sim --bench frames -- touch_size` on the default 13 cm sheet
/// (2026-11-25, the 2-core AMD EPYC machine): the update takes 0.2 ms for a 7.5 mm fingertip,
/// 13 ms at 2 cm radius, 67 ms at 3 cm and 2.8 s at 5 cm; the fresh solve about 11 ms at any
/// size, so the two cross near 2 cm, which this many nodes marks.
pub const FAST_UPDATE_MAX_NODES: usize = 400;

/// A built sheet: network, fast path and piezo law.
#[derive(Debug)]
pub struct SimulatedSheet {
    spec: SheetSpec,
    network: Network,
    fast: FastNetwork,
}

impl SimulatedSheet {
    /// Builds the network at the spec's resolution with electrodes moved along the outline by
    /// `offsets` (m, one per electrode; empty for none) and solves the untouched sheet.
    ///
    /// # Errors
    /// [`SheetError`] for an invalid spec or an unsolvable network (e.g. overlapping
    /// electrodes at this resolution).
    pub fn new(spec: &SheetSpec, offsets: &[f64]) -> Result<Self, SheetError> {
        Self::with_shorts(spec, offsets, &[])
    }

    /// As [`SimulatedSheet::new`], with the fabric's conductance uneven over the sheet by `field`.
    ///
    /// # Errors
    /// As [`SimulatedSheet::new`], and [`SheetError::Spec`] for a field that is not finite.
    pub fn uneven(
        spec: &SheetSpec,
        offsets: &[f64],
        field: &Unevenness,
    ) -> Result<Self, SheetError> {
        let network = build_network_with(spec, offsets, Some(field), None)?;
        Self::of_network(spec, network)
    }

    /// As [`SimulatedSheet::new`], with each electrode's own contact impedance (`contacts`,
    /// ohm, one per electrode, in place of the spec's one value) and the conductance uneven by
    /// `field` (none: uniform): a real tank's departures from the model that images it.
    ///
    /// # Errors
    /// As [`SimulatedSheet::uneven`], and [`SheetError::Spec`] for a contact count other than
    /// the electrodes' or a contact that is not finite and positive.
    pub fn with_contacts(
        spec: &SheetSpec,
        offsets: &[f64],
        contacts: &[f64],
        field: Option<&Unevenness>,
    ) -> Result<Self, SheetError> {
        let count = usize::from(spec.physical.electrodes.count);
        if contacts.len() != count {
            let what = "contacts, one per electrode";
            return Err(SheetError::field(
                "contacts",
                FieldFault::Count {
                    found: contacts.len(),
                    need: count,
                    what,
                },
            ));
        }
        if !contacts.iter().all(|z| z.is_finite() && *z > 0.0) {
            let rule = "each contact must be finite and positive";
            return Err(SheetError::rule("contacts", rule));
        }
        let network = build_network_with(spec, offsets, field, Some(contacts))?;
        Self::of_network(spec, network)
    }

    /// As [`SimulatedSheet::new`], with pairs of electrodes shorted together (a fault).
    ///
    /// # Errors
    /// As [`SimulatedSheet::new`], and for a short naming an electrode the sheet does not have.
    pub fn with_shorts(
        spec: &SheetSpec,
        offsets: &[f64],
        shorts: &[(usize, usize)],
    ) -> Result<Self, SheetError> {
        let mut network = build_network(spec, offsets)?;
        for &(a, b) in shorts {
            network = network.with_short(a, b).map_err(SheetError::Network)?;
        }
        Self::of_network(spec, network)
    }

    fn of_network(spec: &SheetSpec, network: Network) -> Result<Self, SheetError> {
        let fast =
            FastNetwork::new(&network, network.conductances(None)).map_err(SheetError::Network)?;
        Ok(Self {
            spec: spec.clone(),
            network,
            fast,
        })
    }

    /// The spec it was built from.
    #[must_use]
    pub fn spec(&self) -> &SheetSpec {
        &self.spec
    }

    /// The network.
    #[must_use]
    pub fn network(&self) -> &Network {
        &self.network
    }

    /// Electrode count L.
    #[must_use]
    pub fn electrodes(&self) -> usize {
        self.network.electrodes()
    }

    /// Transfer impedance with these touches on the sheet.
    ///
    /// # Errors
    /// [`SheetError::Network`] if the update fails (non-finite input).
    pub fn transfer(&self, touches: &[Touch]) -> Result<Transfer, SheetError> {
        let incs: Vec<Inclusion> = touches
            .iter()
            .map(|t| Inclusion::of_touch(t, &self.spec.piezo))
            .collect();
        self.transfer_inclusions(&incs)
    }

    /// Transfer impedance with arbitrary conductivity inclusions.
    ///
    /// # Errors
    /// [`SheetError::Network`] if the update fails.
    pub fn transfer_inclusions(&self, inclusions: &[Inclusion]) -> Result<Transfer, SheetError> {
        let changes = edge_multipliers(&self.network.grid, inclusions);
        if self.fast.touched_nodes(&changes) <= FAST_UPDATE_MAX_NODES {
            return self.fast.transfer(&changes).map_err(SheetError::Network);
        }
        // A large touch (a palm, a forearm): the update's dense solve would grow with the
        // cube of the nodes under it, so the touched network is solved afresh (banded
        // Cholesky), a cost that does not depend on the touch's size.
        let mut g = self.network.conductances(None);
        for &(k, m) in &changes {
            if let Some(gk) = g.get_mut(k) {
                *gk *= m;
            }
        }
        Ok(self
            .network
            .solve(&g)
            .map_err(SheetError::Network)?
            .transfer)
    }
}

/// The network of `spec` (validated) with electrodes moved along the outline by `offsets`
/// (m, one per electrode; empty for none), without the fast path's precomputation.
///
/// # Errors
/// [`SheetError`] for an invalid spec or electrodes that cannot be placed.
pub fn build_network(spec: &SheetSpec, offsets: &[f64]) -> Result<Network, SheetError> {
    build_network_with(spec, offsets, None, None)
}

/// [`build_network`] with the fabric's conductance uneven by `field` (none: uniform) and each
/// electrode's own contact (none: the spec's for all).
fn build_network_with(
    spec: &SheetSpec,
    offsets: &[f64],
    field: Option<&Unevenness>,
    contacts: Option<&[f64]>,
) -> Result<Network, SheetError> {
    spec.validate()?;
    spec.check_grid()?;
    if let Some(f) = field
        && !f.coefficients.iter().all(|a| a.is_finite())
    {
        let rule = "the field's coefficients must be finite";
        return Err(SheetError::rule("unevenness", rule));
    }
    let bounds = spec.physical.shape.bounds();
    let h = spec.resolution.unwrap_or_else(|| spec.default_resolution());
    let grid = Grid::new(&spec.physical.shape, h);
    let perimeter = spec.physical.shape.perimeter();
    let positions: Vec<f64> = spec
        .physical
        .electrodes
        .arc_positions(&spec.physical.shape)
        .iter()
        .enumerate()
        .map(|(e, &t)| t + offsets.get(e).copied().unwrap_or(0.0) / perimeter)
        .collect();
    check_moved(spec, offsets, &positions)?;
    let z = contacts.map_or_else(
        || vec![spec.physical.electrodes.contact_ohm; positions.len()],
        <[f64]>::to_vec,
    );
    let contacts = place_contacts(
        &spec.physical.shape,
        &grid,
        &positions,
        spec.physical.electrodes.width,
        &z,
        spec.physical.sheet_resistance,
    );
    let base: Vec<f64> = grid
        .edges
        .iter()
        .map(|e| {
            let (a, b) = (grid.nodes[e.u as usize], grid.nodes[e.v as usize]);
            let along = if (b[0] - a[0]).abs() > (b[1] - a[1]).abs() {
                Axis::X
            } else {
                Axis::Y
            };
            let bent = match spec.bend {
                Some(bend) if bend.curves == along => bend.multiplier(),
                _ => 1.0,
            };
            let middle = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
            bent * field.map_or(1.0, |f| f.multiplier(middle, bounds))
        })
        .collect();
    Network::new(grid, contacts, 1.0 / spec.physical.sheet_resistance)
        .and_then(|n| n.with_base(base))
        .map_err(SheetError::Network)
}

/// Transfer impedance of `network` with `touches`, by a direct solve (no precomputation; the
/// oracle for [`SimulatedSheet::transfer`], and the way to use networks too large to precompute).
///
/// # Errors
/// [`SheetError::Network`] if the network cannot be solved.
pub fn direct_transfer(
    network: &Network,
    piezo: &Piezo,
    touches: &[Touch],
) -> Result<Transfer, SheetError> {
    let incs: Vec<Inclusion> = touches
        .iter()
        .map(|t| Inclusion::of_touch(t, piezo))
        .collect();
    let mut mult = vec![1.0; network.grid.edges.len()];
    for (k, m) in edge_multipliers(&network.grid, &incs) {
        mult[k] = m;
    }
    network
        .solve(&network.conductances(Some(&mult)))
        .map(|s| s.transfer)
        .map_err(SheetError::Network)
}

/// The current source of docs/method.md §2: a Howland pump that delivers its set current only while
/// the load stays below its compliance, V_out_max / (2 I); beyond, the current falls to
/// V_out_max / (2 R_load).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Source {
    /// Largest output voltage of the pump, V.
    pub v_out_max: f64,
    /// On-resistance of each multiplexer switch, ohm (in series with the load, twice).
    pub mux_on_ohm: f64,
}

impl Default for Source {
    /// 16 V supply (docs/method.md §2: 10 mW at 32 uA / 16 V), ADG1606 at 4.5 ohm.
    fn default() -> Self {
        Self {
            v_out_max: 16.0,
            mux_on_ohm: 4.5,
        }
    }
}

impl Source {
    /// Current delivered into `load` ohms when `set` amps are asked for.
    #[must_use]
    pub fn current(&self, set: f64, load: f64) -> f64 {
        let r = load + 2.0 * self.mux_on_ohm;
        if r * 2.0 * set <= self.v_out_max {
            set
        } else {
            self.v_out_max / (2.0 * r)
        }
    }
}

/// The noiseless frame V_m (volts, K values) of `protocol` for transfer `z` at current `amps`.
#[must_use]
pub fn frame(z: &Transfer, protocol: &Protocol, amps: f64, source: &Source) -> Vec<f64> {
    protocol
        .steps()
        .map(|s| {
            let (a, b) = (
                usize::from(s.injection.source.0),
                usize::from(s.injection.sink.0),
            );
            let (p, q) = (
                usize::from(s.measurement.positive.0),
                usize::from(s.measurement.negative.0),
            );
            let i = source.current(amps, z.load(a, b));
            z.voltage(a, b, p, q, i)
        })
        .collect()
}

mod unevenness;
pub use unevenness::Unevenness;

mod error;
pub use error::*;

mod moved;
use moved::check_moved;

#[cfg(test)]
mod tests;
