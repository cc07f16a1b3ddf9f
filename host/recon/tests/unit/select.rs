use et_core::protocol::ProtocolKind;
use et_recon::Region;
use et_recon::select::*;

fn region(x: f64, y: f64, peak: f64) -> Region {
    Region {
        centroid: [x, y],
        area: 4e-4,
        peak,
        peak_pixel: 0,
        z: None,
        pixels: Vec::new(),
    }
}

#[test]
fn decisions_follow_spec_8() {
    let s = Settings::new([0.0, 0.0], 0.11);
    assert_eq!(decide(&[], &s), None);
    assert_eq!(
        decide(&[region(0.02, -0.03, 1.0)], &s),
        Some(ProtocolKind::PseudoPolar)
    );
    assert_eq!(
        decide(&[region(0.08, 0.0, 1.0)], &s),
        Some(ProtocolKind::Adjacent)
    );
    assert_eq!(
        decide(&[region(0.05, 0.0, 1.0), region(-0.05, 0.0, 0.9)], &s),
        Some(ProtocolKind::PpPp)
    );
    // A weak speck and a tiny region do not count as second touches.
    let speck = Region {
        area: 1e-6,
        ..region(-0.05, 0.0, 0.9)
    };
    let regions = [region(0.02, 0.0, 1.0), region(0.08, 0.05, 0.2), speck];
    assert_eq!(significant(&regions, &s).len(), 1);
}

#[test]
fn switches_need_confirmation_and_undo_themselves() {
    let s = Settings::new([0.0, 0.0], 0.11);
    let mut sel = Selector::new(s);
    let central = [region(0.01, 0.01, 1.0)];
    let two = [region(0.05, 0.0, 1.0), region(-0.05, 0.0, 1.0)];
    // One spurious frame with two regions does not switch.
    assert_eq!(sel.step(&two), None);
    assert_eq!(sel.step(&central), None);
    assert_eq!(sel.current(), ProtocolKind::Adjacent);
    // The central touch held for two frames switches to pseudo-polar.
    assert_eq!(sel.step(&central), Some(ProtocolKind::PseudoPolar));
    assert_eq!(sel.step(&central), None);
    // A second finger, held, switches to PP-PP.
    assert_eq!(sel.step(&two), None);
    assert_eq!(sel.step(&two), Some(ProtocolKind::PpPp));
    // The touches go: after 3 quiet frames, back to adjacent; a touch in between resets.
    assert_eq!(sel.step(&[]), None);
    assert_eq!(sel.step(&[]), None);
    assert_eq!(sel.step(&two), None);
    assert_eq!(sel.step(&[]), None);
    assert_eq!(sel.step(&[]), None);
    assert_eq!(sel.step(&[]), Some(ProtocolKind::Adjacent));
    assert_eq!(sel.step(&[]), None, "already adjacent");
}
