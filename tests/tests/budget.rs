//! The serial link budget (docs/design.md, "Link budget"): every configuration the board supports
//! (L = 4 to 16 electrodes, every protocol including every general pattern, at the reference
//! timing of 78 Hz at L = 16 or faster at fewer electrodes) fits the firmware's baud rate with
//! at least 20 % to spare, at the one rate firmware and host share (`et_core::board::BAUD`).

use et_core::ScanConfig;
use et_core::board::BAUD;
use et_core::device::FEATURES_MAX;
use et_core::model::{ModelKind, Precision, model_len};
use et_core::protocol::{L_MIN, Pattern, ProtocolKind, SkipSet};
use et_core::wire::link_load;

/// The board's mux is 16:1 (docs/method.md §2).
const BOARD_ELECTRODES_MAX: u8 = 16;

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
    // The firmware configures its USART from `et_core::board::BAUD`, the host opens ports at it.
    let baud = BAUD;
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

use et_core::board::MODEL_SLOT_BYTES as SLOT_BYTES;

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
    // The full-covariance QDA of docs/design.md (49 classes, p = 96, f32) does not fit a slot.
    assert!(model_len(ModelKind::Qda, Precision::F32, 49, 96) > SLOT_BYTES);
}
