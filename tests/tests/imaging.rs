//! Imaging (et-recon) on the simulator's frames: the reconstruction and the simulator share no
//! model (finite elements against a resistor network), so these tests do not commit the
//! inverse crime. Tests of et-recon that need no simulator live beside its code.

mod forward;
mod greit;
mod onestep;

/// For tests: `found` holds exactly one touch per true touch (`truth`: centre and radius, m),
/// each true touch matched to a touch of its own, and a found centroid within each true
/// touch's radius. Returns the matches.
pub(crate) fn assert_found_exactly(
    name: &str,
    grid: &et_recon::PixelGrid,
    found: &[et_recon::Region],
    truth: &[([f64; 2], f64)],
) -> Vec<et_recon::TouchMatch> {
    let at: Vec<[f64; 2]> = found.iter().map(|r| r.centroid).collect();
    assert_eq!(found.len(), truth.len(), "{name}: {at:?}");
    let matches = et_recon::match_touches(grid, found, truth);
    let mut which: Vec<usize> = matches.iter().filter_map(|m| m.found).collect();
    which.sort_unstable();
    which.dedup();
    assert_eq!(which.len(), truth.len(), "{name}: {matches:?}");
    for (centre, radius) in truth {
        let near = at
            .iter()
            .map(|c| (c[0] - centre[0]).hypot(c[1] - centre[1]))
            .fold(f64::INFINITY, f64::min);
        assert!(near < *radius, "{name}: {near} from {centre:?}");
    }
    matches
}
