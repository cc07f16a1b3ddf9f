//! The simulated front end against the real scan engine.

use super::*;
use crate::sheet::SheetSpec;
use et_core::protocol::ProtocolKind;
use et_core::rng::Rng;
use et_core::{Protocol, Scanner};

pub(crate) fn sheet(resolution: Option<f64>) -> Arc<SimulatedSheet> {
    let spec = SheetSpec {
        resolution,
        ..SheetSpec::rectangle(0.13, 0.13, 16)
    };
    Arc::new(SimulatedSheet::new(&spec, &[]).unwrap())
}

fn column_stats(frames: &[Vec<f32>], k: usize) -> (f64, f64) {
    let n = frames.len() as f64;
    let mean = frames.iter().map(|f| f64::from(f[k])).sum::<f64>() / n;
    let var = frames
        .iter()
        .map(|f| (f64::from(f[k]) - mean).powi(2))
        .sum::<f64>()
        / (n - 1.0);
    (mean, var.sqrt())
}

#[test]
fn scan_engine_through_the_sim_reproduces_the_fast_path() {
    let sheet = sheet(Some(0.005));
    // At the calibration's gain, where the noise spans several codes (at gain 1 a quiet
    // channel's median sits on one code in both paths: no ratio to compare).
    let config = ScanConfig {
        gain: CALIBRATION_GAIN,
        ..ScanConfig::REFERENCE
    };
    let touch = Touch {
        position: [0.02, 0.01],
        radius: 0.0075,
        pressure: 30e3,
        footprint: Default::default(),
    };
    let mut slow = SimFrontend::new(sheet.clone(), FrontendSpec::default(), 1).unwrap();
    let mut fast = SimFrontend::new(sheet, FrontendSpec::default(), 2).unwrap();
    slow.set_touches(&[touch]).unwrap();
    fast.set_touches(&[touch]).unwrap();
    let scanner = Scanner::new(config, &mut slow).unwrap();
    let k = scanner.frame_len();
    let n = 60;
    let mut burst = vec![0u16; 50];
    let mut scanned = Vec::new();
    let mut quick = Vec::new();
    for _ in 0..n {
        let mut v = vec![0.0f32; k];
        let report = scanner.scan(&mut slow, &mut burst, &mut v).unwrap();
        assert_eq!(report.rail.count(), 0);
        scanned.push(v);
        quick.push(fast.fast_frame(&config).unwrap());
    }
    let ideal = slow.ideal_frame(scanner.protocol(), f64::from(config.current_amps()));
    let lsb = f64::from(FrontendSpec::default().scale(config.gain).volts_per_code);
    let mut ratio_sum = 0.0;
    for c in 0..k {
        let (ms, ss) = column_stats(&scanned, c);
        let (mf, sf) = column_stats(&quick, c);
        let tol = 5.0 * ((ss * ss + sf * sf) / n as f64).sqrt() + lsb;
        assert!(
            (ms - mf).abs() <= tol,
            "channel {c}: scan {ms:.6} fast {mf:.6} (tol {tol:.2e})"
        );
        assert!(
            (ms - ideal[c]).abs() <= tol,
            "channel {c}: scan {ms:.6} ideal {:.6}",
            ideal[c]
        );
        ratio_sum += ss / sf;
    }
    let ratio = ratio_sum / k as f64;
    assert!(
        (0.8..1.25).contains(&ratio),
        "noise of scan vs fast path: ratio {ratio}"
    );
}

#[test]
fn settling_matters_when_bursts_are_short() {
    // The median ignores a transient that spoils only a few samples of a long burst; with
    // short bursts and no t_s the transient takes the median with it.
    let sheet = sheet(Some(0.008));
    let quiet = FrontendSpec::default().without_noise();
    let mut fe = SimFrontend::new(sheet, quiet, 3).unwrap();
    let mut err = |samples_per_step: u16, settle_samples: u16| {
        let config = ScanConfig {
            samples_per_step,
            settle_samples,
            ..ScanConfig::REFERENCE
        };
        let scanner = Scanner::new(config, &mut fe).unwrap();
        let mut v = vec![0.0f32; scanner.frame_len()];
        scanner.scan(&mut fe, &mut [0u16; 64], &mut v).unwrap();
        let ideal = fe.ideal_frame(scanner.protocol(), 32e-6);
        v.iter()
            .zip(&ideal)
            .map(|(a, b)| (f64::from(*a) - b).abs())
            .fold(0.0, f64::max)
    };
    let lsb = f64::from(FrontendSpec::default().scale(1).volts_per_code);
    let reference = err(50, 25);
    let short_unsettled = err(12, 0);
    let short_settled = err(12, 8);
    assert!(
        reference <= lsb,
        "the reference t_s = 25 of 50 leaves {reference} V"
    );
    assert!(
        short_unsettled > 20.0 * lsb,
        "12 samples, t_s = 0: {short_unsettled} V"
    );
    assert!(
        short_settled < short_unsettled / 3.0,
        "t_s = 8 of 12: {short_settled} V vs {short_unsettled} V"
    );
}

#[test]
fn adc_rails_are_hit_and_flagged_at_high_gain() {
    let sheet = sheet(Some(0.008));
    let mut fe = SimFrontend::new(sheet, FrontendSpec::default(), 4).unwrap();
    // Gain 100 puts +-50 mV full scale: the big channels next to the drive clip.
    let config = ScanConfig {
        gain: 100,
        ..ScanConfig::REFERENCE
    };
    let scanner = Scanner::new(config, &mut fe).unwrap();
    let mut v = vec![0.0f32; scanner.frame_len()];
    let report = scanner.scan(&mut fe, &mut [0u16; 50], &mut v).unwrap();
    let ideal = fe.ideal_frame(scanner.protocol(), 32e-6);
    let clipped: Vec<usize> = (0..ideal.len())
        .filter(|&c| ideal[c].abs() > 0.051)
        .collect();
    assert!(!clipped.is_empty());
    for &c in &clipped {
        assert!(
            report.rail.get(c),
            "channel {c} at {} V is flagged",
            ideal[c]
        );
    }
    assert!(v.iter().all(|x| x.is_finite()));
    // The fast path flags the same channels (it used to flag none).
    let (fast, fast_report) = fe.fast_frame_with_report(&config).unwrap();
    for &c in &clipped {
        assert!(fast_report.rail.get(c), "fast path: channel {c} flagged");
    }
    let unclipped = (0..ideal.len()).filter(|&c| ideal[c].abs() < 0.045);
    for c in unclipped {
        assert!(
            !fast_report.rail.get(c),
            "channel {c} at {} V is not",
            ideal[c]
        );
    }
    assert_eq!(
        fast_report.rail_samples,
        fast_report.rail.count() as u32 * u32::from(config.kept_samples())
    );
    assert_eq!(fast_report.samples, report.samples);
    assert!(fast.iter().all(|x| x.is_finite()));
}

#[test]
fn misuse_is_a_typed_error() {
    let sheet = sheet(Some(0.01));
    let mut fe = SimFrontend::new(sheet, FrontendSpec::default(), 5).unwrap();
    assert_eq!(fe.acquire(&mut [0; 4]), Err(SimError::NotSelected));
    let wrong = ScanConfig {
        electrodes: 8,
        ..ScanConfig::REFERENCE
    };
    assert!(matches!(
        fe.configure(&wrong),
        Err(SimError::Electrodes { configured: 8, .. })
    ));
    assert!(matches!(
        fe.fast_frame(&wrong),
        Err(SimError::Electrodes { configured: 8, .. })
    ));
    fe.configure(&ScanConfig::REFERENCE).unwrap();
    let p = Protocol::new(ProtocolKind::Adjacent, 32).unwrap();
    let s = p.step(500).unwrap();
    assert!(matches!(
        fe.select(s.injection, s.measurement),
        Err(SimError::Electrode(_))
    ));
    let bad = FrontendSpec {
        white_noise_v: -1.0,
        ..FrontendSpec::default()
    };
    assert!(SimFrontend::new(fe.sheet().clone(), bad, 1).is_err());
}

/// `n` frames of the calibration's operating point at `current_na` through the real scan
/// engine, flattened.
fn scanned(fe: &mut SimFrontend, current_na: u32, n: usize) -> (Vec<f32>, usize) {
    let config = crate::calibration::config(current_na);
    let scanner = Scanner::new(config, fe).unwrap();
    let k = scanner.frame_len();
    let mut frames = vec![0.0f32; n * k];
    let mut burst = [0u16; 50];
    for f in frames.chunks_mut(k) {
        let report = scanner.scan(fe, &mut burst, f).unwrap();
        assert_eq!(
            report.rail.count(),
            0,
            "the calibration's gain clips nothing"
        );
    }
    (frames, k)
}

#[test]
fn calibration_reproduces_the_reference_snr() {
    // docs/method.md §3: 55 dB at 32 uA and 49 dB at 10 uA frame to frame, adjacent protocol,
    // reference scan settings at the calibration's gain, on the 13 x 13 cm 16-electrode sheet,
    // through the sample-level path (the fit used the fast path and other seeds).
    let mut fe = SimFrontend::new(sheet(None), FrontendSpec::default(), 11).unwrap();
    let mut got = Vec::new();
    for (na, reference) in crate::calibration::SNR_DB {
        let (frames, k) = scanned(&mut fe, na, 200);
        let db = f64::from(et_core::stats::snr(&frames, k).unwrap().mean_db);
        println!(
            "calibration: {} uA: SNR {db:.2} dB (reference {reference})",
            na / 1000
        );
        assert!((db - reference).abs() < 1.0, "SNR at {na} nA: {db} dB");
        got.push(db);
    }
    assert!(got[0] > got[1], "more current, more SNR");
}

#[test]
fn calibration_reproduces_the_reference_mad_between_sets() {
    // docs/method.md §3: 0.5 mV at 32 uA and 0.4 mV at 10 uA among measurement sets: each set
    // the sheet (still mounted) in its own junction potentials and conductance, its mean frame
    // of 10 scans (sample-level path) against the mean over sets; draws other than the fit's.
    let spec = crate::calibration::sheet_spec();
    let sets = crate::calibration::replaced_sheets(&spec, CALIBRATION_MOVEMENT_M, 120, 99).unwrap();
    for (na, reference) in crate::calibration::MAD_V {
        let mut means = Vec::new();
        let mut k = 0;
        for (s, sheet) in sets.iter().enumerate() {
            let mut rng = Rng::new(500 + s as u64);
            let spec = FrontendSpec::default();
            let mut fe = SimFrontend::new(sheet.clone(), spec, rng.next_u64()).unwrap();
            fe.set_state(&spec.sets.draw(16, &mut rng)).unwrap();
            let (frames, kk) = scanned(&mut fe, na, 10);
            k = kk;
            let mut mean = vec![0.0f32; k];
            for f in frames.chunks(k) {
                for (m, v) in mean.iter_mut().zip(f) {
                    *m += v / 10.0;
                }
            }
            means.extend(mean);
        }
        let mad = f64::from(et_core::stats::mad(&means, k).unwrap());
        println!(
            "calibration: {} uA: MAD between sets {:.3} mV (reference {})",
            na / 1000,
            mad * 1e3,
            reference * 1e3
        );
        assert!(
            (mad - reference).abs() < 0.1 * reference,
            "MAD at {na} nA: {mad} V"
        );
    }
}

#[test]
fn a_measurement_set_shifts_the_frame_by_its_junction_potentials_and_conductance() {
    // The settled reading of pair (p, q) is V_pq / c + e_p - e_q: checked on the noiseless
    // frame against the nominal set.
    let mut fe = SimFrontend::new(sheet(Some(0.008)), FrontendSpec::default(), 1).unwrap();
    let protocol = ScanConfig::REFERENCE.validate().unwrap();
    let nominal = fe.ideal_frame(&protocol, 32e-6);
    let e: Vec<f64> = (0..16).map(|i| f64::from(i) * 1e-4).collect();
    let set = SetState {
        contact_potentials_v: e.clone(),
        conductance_scale: 1.25,
    };
    fe.set_state(&set).unwrap();
    let shifted = fe.ideal_frame(&protocol, 32e-6);
    for ((step, a), b) in protocol.steps().zip(&nominal).zip(&shifted) {
        let (p, q) = (
            usize::from(step.measurement.positive.0),
            usize::from(step.measurement.negative.0),
        );
        let want = a / 1.25 + e[p] - e[q];
        assert!((b - want).abs() < 1e-12, "{b} vs {want}");
    }
    // Refused: the wrong count, NaN, a conductance of 0.
    for bad in [
        SetState {
            contact_potentials_v: vec![0.0; 8],
            ..set.clone()
        },
        SetState {
            contact_potentials_v: vec![f64::NAN; 16],
            ..set.clone()
        },
        SetState {
            conductance_scale: 0.0,
            ..set.clone()
        },
    ] {
        assert!(matches!(fe.set_state(&bad), Err(SimError::Set { .. })));
    }
}

#[test]
fn at_unity_gain_a_code_limits_the_snr() {
    // At gain 1 a code is 153 uV, three times the per-sample noise: the median of codes cannot
    // resolve the reference's 30 uV frame noise, so the SNR falls well short of the
    // calibrated gain's (what the calibration's choice of gain rests on).
    let sheet = sheet(Some(0.008));
    let snr_at = |gain| {
        let mut fe = SimFrontend::new(sheet.clone(), FrontendSpec::default(), 3).unwrap();
        let config = ScanConfig {
            gain,
            ..ScanConfig::REFERENCE
        };
        let k = config.validate().unwrap().frame_len();
        let frames: Vec<f32> = (0..200)
            .flat_map(|_| fe.fast_frame(&config).unwrap())
            .collect();
        et_core::stats::snr(&frames, k).unwrap().mean_db
    };
    let (one, eight) = (snr_at(1), snr_at(CALIBRATION_GAIN));
    assert!(one < eight - 3.0, "gain 1: {one} dB, gain 8: {eight} dB");
}

#[test]
fn one_microamp_is_quantisation_dominated_but_sane() {
    // At 1 uA the far channels are a few ADC codes: frames stay finite, and the average of
    // many frames still finds the right voltages (the noise dithers the quantiser).
    let mut fe = SimFrontend::new(sheet(Some(0.008)), FrontendSpec::default(), 6).unwrap();
    let config = ScanConfig {
        current_na: 1_000,
        ..ScanConfig::REFERENCE
    };
    let scanner = Scanner::new(config, &mut fe).unwrap();
    let k = scanner.frame_len();
    let n = 200;
    let mut mean = vec![0.0f64; k];
    let mut burst = [0u16; 50];
    let mut v = vec![0.0f32; k];
    for _ in 0..n {
        scanner.scan(&mut fe, &mut burst, &mut v).unwrap();
        assert!(v.iter().all(|x| x.is_finite()));
        for (m, x) in mean.iter_mut().zip(&v) {
            *m += f64::from(*x) / f64::from(n);
        }
    }
    let ideal = fe.ideal_frame(scanner.protocol(), 1e-6);
    let lsb = f64::from(FrontendSpec::default().scale(1).volts_per_code);
    let worst = mean
        .iter()
        .zip(&ideal)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < lsb,
        "mean of {n} frames within one code of the truth: {worst} V"
    );
    assert!(
        ideal.iter().any(|x| x.abs() < 4.0 * lsb),
        "some channels are a few codes"
    );
}

#[test]
fn a_source_in_compliance_is_flagged_in_the_frame_by_both_paths() {
    // Contacts of 1 Mohm put the drive load above 16 V / (2 x 32 uA) = 250 kohm: every
    // injection is in compliance. 1 kohm (the default clip) is not.
    let config = ScanConfig::REFERENCE;
    let frame_of = |contact_ohm: f64, open: Option<u8>| {
        let mut spec = SheetSpec {
            resolution: Some(0.01),
            ..SheetSpec::rectangle(0.13, 0.13, 16)
        };
        spec.physical.electrodes.contact_ohm = contact_ohm;
        let sheet = Arc::new(SimulatedSheet::new(&spec, &[]).unwrap());
        let mut fe = SimFrontend::new(sheet, FrontendSpec::default(), 3).unwrap();
        if let Some(e) = open {
            fe.set_open(e, 1.0).unwrap();
        }
        let scanner = Scanner::new(config, &mut fe).unwrap();
        let mut burst = vec![0u16; usize::from(config.samples_per_step)];
        let mut v = vec![0.0f32; scanner.frame_len()];
        let report = scanner.scan(&mut fe, &mut burst, &mut v).unwrap();
        let (_, fast) = fe.fast_frame_with_report(&config).unwrap();
        let frame =
            et_core::wire::Frame::from_scan(0, et_core::Micros(0), config, &report, 0, &v).unwrap();
        (report.compliance_steps, fast.compliance_steps, frame.flags)
    };
    let k = 208;
    let (scan, fast, flags) = frame_of(1e6, None);
    assert_eq!((scan, fast), (k, k), "every step in compliance at 1 Mohm");
    assert_ne!(flags & et_core::wire::FLAG_COMPLIANCE, 0);
    let (scan, fast, flags) = frame_of(1e3, None);
    assert_eq!((scan, fast), (0, 0), "none at 1 kohm");
    assert_eq!(flags & et_core::wire::FLAG_COMPLIANCE, 0);
    // An open drive contact is an infinite load: the steps that drive through electrode 5
    // (AD: injections 4-5 and 5-6, 13 measurements each) are in compliance.
    let (scan, fast, flags) = frame_of(1e3, Some(5));
    assert_eq!(
        (scan, fast),
        (26, 26),
        "the two injections through the open contact"
    );
    assert_ne!(flags & et_core::wire::FLAG_COMPLIANCE, 0);
}

#[test]
fn a_hand_wobbles_the_touch_per_injection_and_leaves_the_untouched_sheet_alone() {
    let sheet = sheet(Some(0.01));
    let config = ScanConfig {
        gain: CALIBRATION_GAIN,
        ..ScanConfig::REFERENCE
    };
    let spec = FrontendSpec::default().without_noise();
    // One injection lasts S/L = 50 samples at 62.5 kHz, 0.8 ms: with a 2 ms correlation time
    // consecutive injections correlate by exp(-0.4) = 0.67.
    let hand = Hand {
        wobble: 0.3,
        correlation_s: 2e-3,
    };
    let frames = |touches: &[Touch], hand: Option<Hand>, n: usize| {
        let mut fe = SimFrontend::new(sheet.clone(), spec, 9).unwrap();
        if let Some(h) = hand {
            fe.set_hand(h).unwrap();
        }
        fe.set_touches(touches).unwrap();
        (0..n)
            .map(|_| fe.fast_frame(&config).unwrap())
            .collect::<Vec<_>>()
    };
    // Untouched: the hand changes nothing.
    assert_eq!(frames(&[], Some(hand), 3), frames(&[], None, 3));
    let touch = Touch {
        position: [0.02, 0.01],
        radius: 0.0075,
        pressure: 30e3,
        footprint: Default::default(),
    };
    let v0 = &frames(&[], None, 1)[0];
    let steady = &frames(&[touch], None, 1)[0];
    let delta: Vec<f64> = steady
        .iter()
        .zip(v0)
        .map(|(a, b)| f64::from(a - b))
        .collect();
    // Per injection, the reading the touch changes most: (V - V_0) / delta is 1 + the hand.
    let protocol = config.validate().unwrap();
    let mut best: Vec<Option<usize>> = vec![None; 16];
    for (k, s) in protocol.steps().enumerate() {
        let slot = &mut best[usize::from(s.injection.source.0)];
        if slot.is_none_or(|b| delta[k].abs() > delta[b].abs()) {
            *slot = Some(k);
        }
    }
    let best: Vec<usize> = best.into_iter().flatten().collect();
    assert!(best.iter().all(|&k| delta[k].abs() > 1e-4), "{delta:?}");
    let factors: Vec<Vec<f64>> = frames(&[touch], Some(hand), 300)
        .iter()
        .map(|f| {
            best.iter()
                .map(|&k| f64::from(f[k] - v0[k]) / delta[k])
                .collect()
        })
        .collect();
    let all: Vec<f64> = factors.iter().flatten().copied().collect();
    let n = all.len() as f64;
    let mean = all.iter().sum::<f64>() / n;
    let var = all.iter().map(|f| (f - mean).powi(2)).sum::<f64>() / n;
    assert!((mean - 1.0).abs() < 0.05, "mean factor {mean}");
    assert!(
        (var.sqrt() - 0.3).abs() < 0.05,
        "rms of the hand {}",
        var.sqrt()
    );
    let lag1 = factors
        .iter()
        .flat_map(|f| f.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)))
        .collect::<Vec<_>>();
    let r = lag1.iter().sum::<f64>() / lag1.len() as f64 / var;
    assert!((r - (-0.4f64).exp()).abs() < 0.1, "lag-1 correlation {r}");
    // A hand that is not a hand is refused.
    let mut fe = SimFrontend::new(sheet.clone(), spec, 9).unwrap();
    for bad in [
        Hand {
            wobble: -0.1,
            ..hand
        },
        Hand {
            correlation_s: 0.0,
            ..hand
        },
        Hand {
            wobble: f64::NAN,
            ..hand
        },
    ] {
        assert!(matches!(fe.set_hand(bad), Err(SimError::Hand { .. })));
    }
}
