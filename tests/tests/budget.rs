//! The serial link budget (DESIGN.md, "Link budget"): every configuration the board supports
//! (L = 4 to 16 electrodes, every protocol including every general pattern, at the reference
//! timing of 78 Hz at L = 16 or faster at fewer electrodes) fits the firmware's baud rate with
//! at least 20 % to spare, and the host opens the port at the firmware's rate.

use et_core::ScanConfig;
use et_core::protocol::{L_MIN, Pattern, ProtocolKind, SkipSet};
use et_core::wire::link_load;
use et_host::link::DEFAULT_BAUD;

/// The board's mux is 16:1 (SPEC §2).
const BOARD_ELECTRODES_MAX: u8 = 16;

/// `pub const BAUD: u32 = ...;` of firmware/src/board.rs.
fn firmware_baud() -> u32 {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../firmware/src/board.rs");
    let text = std::fs::read_to_string(path).unwrap();
    let line = text
        .lines()
        .find(|l| l.starts_with("pub const BAUD: u32 = "))
        .expect("board.rs defines BAUD");
    line.trim_start_matches("pub const BAUD: u32 = ")
        .trim_end_matches(';')
        .replace('_', "")
        .parse()
        .unwrap()
}

fn every_protocol(l: u8) -> Vec<ProtocolKind> {
    let mut kinds = vec![
        ProtocolKind::Adjacent,
        ProtocolKind::PseudoPolar,
        ProtocolKind::PpPp,
        ProtocolKind::Opposite,
    ];
    let half = l / 2;
    for drive_skip in 0..half {
        for a in 0..half {
            for b in a..half {
                kinds.push(ProtocolKind::Custom(Pattern {
                    drive_skip,
                    measure_skips: SkipSet((1 << a) | (1 << b)),
                }));
            }
        }
    }
    kinds
}

#[test]
fn every_supported_configuration_fits_the_link_with_margin() {
    let baud = firmware_baud();
    assert_eq!(
        baud, DEFAULT_BAUD,
        "host and firmware must agree on the rate"
    );
    let mut worst = (0.0f32, ProtocolKind::Adjacent, 0u8);
    let mut checked = 0;
    for l in (L_MIN..=BOARD_ELECTRODES_MAX).step_by(2) {
        for protocol in every_protocol(l) {
            let config = ScanConfig {
                electrodes: l,
                protocol,
                ..ScanConfig::REFERENCE
            };
            let Some(load) = link_load(&config, baud) else {
                continue; // not a valid pattern at this L
            };
            checked += 1;
            if load > worst.0 {
                worst = (load, protocol, l);
            }
        }
    }
    assert!(checked > 100, "{checked} configurations");
    println!(
        "worst link load at {baud} baud: {:.0} % ({:?}, L = {})",
        100.0 * worst.0,
        worst.1,
        worst.2
    );
    assert!(worst.0 <= 0.8, "worst load {worst:?}");
    // The reference point itself (AD, L = 16, 78 Hz) leaves most of the line free.
    let reference = link_load(&ScanConfig::REFERENCE, baud).unwrap();
    println!(
        "reference (AD, L = 16) link load: {:.0} %",
        100.0 * reference
    );
    assert!(reference < 0.5, "reference load {reference}");
    // At the old 921 600 baud the worst case did not fit: the test can fail.
    assert!(link_load(&worst_config(worst.1, worst.2), 921_600).unwrap() > 1.0);
}

fn worst_config(protocol: ProtocolKind, electrodes: u8) -> ScanConfig {
    ScanConfig {
        electrodes,
        protocol,
        ..ScanConfig::REFERENCE
    }
}
