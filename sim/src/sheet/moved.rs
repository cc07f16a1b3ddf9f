//! Electrodes moved along the outline, checked before a network is built on them.

use super::{SheetError, SheetSpec};

/// Refuses electrodes moved by `offsets` (m) to `positions` (fractions of the outline) that
/// overlap a neighbour or pass it ([`SheetError::Moved`]): the offsets were added without a
/// look, so a movement of 1 m rms on a 13 cm sheet scrambled the electrodes' order.
pub(super) fn check_moved(
    spec: &SheetSpec,
    offsets: &[f64],
    positions: &[f64],
) -> Result<(), SheetError> {
    if offsets.iter().all(|&o| o == 0.0) || positions.len() < 2 {
        return Ok(());
    }
    let perimeter = spec.physical.shape.perimeter();
    let width = spec.physical.electrodes.width;
    let nominal = spec.physical.electrodes.arc_positions(&spec.physical.shape);
    // Each electrode's place as a fraction of the outline in [0, 1), in order along it.
    let along = |t: &[f64]| {
        let mut order: Vec<(f64, usize)> = t
            .iter()
            .enumerate()
            .map(|(e, &t)| (t.rem_euclid(1.0), e))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        order
    };
    let (before, after) = (along(&nominal), along(positions));
    // The electrode after each one along the outline, nominally.
    let mut next = vec![0; positions.len()];
    for (i, &(_, e)) in before.iter().enumerate() {
        next[e] = before[(i + 1) % before.len()].1;
    }
    let moved = |e: usize| offsets.get(e).copied().unwrap_or(0.0) * 1e3;
    for (i, &(t, a)) in after.iter().enumerate() {
        let (u, b) = after[(i + 1) % after.len()];
        let gap = (u - t).rem_euclid(1.0) * perimeter;
        let crossed = next[a] != b;
        if crossed || gap < width {
            return Err(SheetError::Moved {
                a,
                b,
                moved_a: moved(a),
                moved_b: moved(b),
                crossed,
                width_mm: width * 1e3,
                spacing_mm: perimeter / positions.len() as f64 * 1e3,
            });
        }
    }
    Ok(())
}
