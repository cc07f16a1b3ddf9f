use et_recon::pixels::*;

fn grid(width: usize, height: usize) -> PixelGrid {
    PixelGrid {
        width,
        height,
        origin: [-0.01, 0.02],
        size: 0.005,
        triangle: vec![Some(0); width * height],
    }
}

/// Total length of an outline, m.
fn length(edges: &[[[f64; 2]; 2]]) -> f64 {
    edges
        .iter()
        .map(|[a, b]| (a[0] - b[0]).hypot(a[1] - b[1]))
        .sum()
}

#[test]
fn outlines_are_the_perimeter_of_the_marked_pixels() {
    let g = grid(4, 3);
    let mut member = vec![false; 12];
    assert!(g.outline(&member).is_empty());
    // One pixel inside: its four sides, around its own centre.
    member[5] = true;
    let one = g.outline(&member);
    assert_eq!(one.len(), 4);
    assert!((length(&one) - 4.0 * g.size).abs() < 1e-15);
    let c = g.centre(5);
    for [a, b] in &one {
        let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let d = (mid[0] - c[0]).abs().max((mid[1] - c[1]).abs());
        assert!((d - g.size / 2.0).abs() < 1e-15, "{mid:?} around {c:?}");
    }
    // Its right-hand neighbour joins it: the shared side is gone (a 2 x 1 rectangle).
    member[6] = true;
    let two = g.outline(&member);
    assert_eq!(two.len(), 6);
    assert!((length(&two) - 6.0 * g.size).abs() < 1e-15);
    // The whole grid: its border, whatever the grid's edge (no neighbour) is.
    let all = g.outline(&[true; 12]);
    assert_eq!(all.len(), 2 * (4 + 3));
    // Flags beyond the grid are ignored; a short list marks only what it covers.
    assert_eq!(g.outline(&[true]).len(), 4);
}
