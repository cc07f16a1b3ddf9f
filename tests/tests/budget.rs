//! The serial link budget (DESIGN.md, "Link budget"): every configuration the board supports
//! (L = 4 to 16 electrodes, every protocol including every general pattern, at the reference
//! timing of 78 Hz at L = 16 or faster at fewer electrodes) fits the firmware's baud rate with
//! at least 20 % to spare, and the host opens the port at the firmware's rate.

use et_core::ScanConfig;
use et_core::device::FEATURES_MAX;
use et_core::model::{ModelKind, Precision, model_len};
use et_core::protocol::{L_MIN, Pattern, ProtocolKind, SkipSet};
use et_core::wire::link_load;
use et_host::link::DEFAULT_BAUD;

/// The board's mux is 16:1 (SPEC §2).
const BOARD_ELECTRODES_MAX: u8 = 16;

/// The value of `pub const NAME: TYPE = A * B ...;` in a firmware source file: the firmware is
/// its own workspace, so its constants are read from the source.
fn firmware_const(file: &str, declaration: &str) -> usize {
    let path = format!("{}/../firmware/src/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let line = text
        .lines()
        .find_map(|l| l.strip_prefix(declaration))
        .unwrap_or_else(|| panic!("{path} defines `{declaration}`"));
    line.trim_end_matches(';')
        .split('*')
        .map(|f| f.trim().replace('_', "").parse::<usize>().unwrap())
        .product()
}

fn firmware_baud() -> u32 {
    firmware_const("board.rs", "pub const BAUD: u32 = ") as u32
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

/// Bytes of one model slot in the board's flash (`firmware/src/store.rs`), as the host
/// checks models against it.
const SLOT_BYTES: usize = et_host::learn::pipeline::MODEL_SLOT_BYTES;

/// The most features a model of `classes` classes can use and still fit a flash slot (and the
/// device's evaluation limit).
fn largest_p(kind: ModelKind, precision: Precision, classes: usize) -> usize {
    (1..=FEATURES_MAX)
        .take_while(|&p| model_len(kind, precision, classes, p) <= SLOT_BYTES)
        .last()
        .unwrap_or(0)
}

#[test]
fn largest_models_that_fit_a_flash_slot() {
    let slot = firmware_slot_bytes();
    assert_eq!(
        slot, SLOT_BYTES,
        "firmware/src/store.rs changed its slot size"
    );
    for classes in [49, 100] {
        for (kind, precision) in [
            (ModelKind::Qda, Precision::F32),
            (ModelKind::Qda, Precision::F16),
            (ModelKind::Lda, Precision::F32),
            (ModelKind::Lda, Precision::F16),
        ] {
            let p = largest_p(kind, precision, classes);
            println!(
                "{classes} classes, {kind:?} {precision:?}: up to p = {p} ({} bytes)",
                model_len(kind, precision, classes, p)
            );
            assert!(p >= 40, "{classes} {kind:?} {precision:?}: p = {p}");
        }
    }
    // The README's 100-class QDA with 48 Fisher-ranked features in f16 (95.2 % next-day) fits.
    assert!(model_len(ModelKind::Qda, Precision::F16, 100, 48) <= SLOT_BYTES);
    // The full-covariance QDA of DESIGN.md (49 classes, p = 96, f32) does not fit a slot.
    assert!(model_len(ModelKind::Qda, Precision::F32, 49, 96) > SLOT_BYTES);
}

fn firmware_slot_bytes() -> usize {
    firmware_const("store.rs", "pub const SLOT_BYTES: usize = ")
}
