use super::*;

#[test]
fn protocols_display_as_people_name_them() {
    assert_eq!(ProtocolKind::PpPp.to_string(), "pp-pp");
    assert_eq!(ProtocolKind::Adjacent.to_string(), "adjacent");
    let custom = ProtocolKind::Custom(Pattern {
        drive_skip: 3,
        measure_skips: SkipSet::single(0).with(7),
    });
    assert_eq!(custom.to_string(), "drive skip 3, measure skips 0 7");
}

fn every_l() -> impl Iterator<Item = u8> {
    (L_MIN..=L_MAX).step_by(2)
}

/// The named protocols that exist at `l`: all four, except opposite at L = 4, which has
/// K = L (L - 4) = 0 measurements (checked in `counts_match_the_formulas_for_every_l`).
fn all(l: u8) -> impl Iterator<Item = Protocol> {
    ProtocolKind::NAMED
        .into_iter()
        .filter(move |&k| !(l == 4 && k == ProtocolKind::Opposite))
        .map(move |k| Protocol::new(k, l).unwrap())
}

/// Brute-force count, independent of the candidate walk: for every injection and every
/// measured distance, every electrode pair at that distance that avoids both injection
/// electrodes.
fn brute_force_k(l: u8, pattern: Pattern) -> usize {
    let mut k = 0;
    for i in 0..l {
        let (a, b) = (i, (i + pattern.drive_skip + 1) % l);
        for s in pattern.measure_skips.iter() {
            let off = s + 1;
            for x in 0..l {
                let y = (x + off) % l;
                // Ordered pair (x, x + off); for off == L/2 count each unordered pair once.
                let once = off != l / 2 || x < l / 2;
                if once && ![a, b].contains(&x) && ![a, b].contains(&y) {
                    k += 1;
                }
            }
        }
    }
    k
}

#[test]
fn counts_match_the_formulas_for_every_l() {
    for l in every_l() {
        let lu = usize::from(l);
        let ad = Protocol::new(ProtocolKind::Adjacent, l).unwrap();
        assert_eq!(ad.frame_len(), lu * (lu - 3), "AD at L={l}");
        match Protocol::new(ProtocolKind::Opposite, l) {
            // L (L - 4) = 0 at L = 4: every adjacent pair touches one of the two electrodes.
            Err(e) => assert!(l == 4 && e == ProtocolError::Empty, "L={l}: {e}"),
            Ok(op) => {
                assert_eq!(op.frame_len(), lu * (lu - 4), "opposite at L={l}");
                assert_eq!(
                    op.feature_count(Halving::Reciprocity),
                    lu * (lu - 4) / 2,
                    "p at L={l}"
                );
                assert_eq!(op.feature_count(Halving::None), lu * (lu - 4));
            }
        }
        let pp = Protocol::new(ProtocolKind::PseudoPolar, l).unwrap();
        let pppp = Protocol::new(ProtocolKind::PpPp, l).unwrap();
        if l == 6 {
            // The smallest L where every named protocol exists.
            assert_eq!(pp.frame_len(), 12);
        }
        if l == 4 {
            // L/2 - 1 = 1: pseudo-polar degenerates to adjacent, and PP-PP's two skips coincide.
            assert_eq!(pp.pattern(), ad.pattern());
            assert_eq!(pppp.frame_len(), ad.frame_len());
        } else {
            assert_eq!(pp.frame_len(), lu * (lu - 4), "PP at L={l}");
            assert_eq!(pppp.frame_len(), lu * (2 * lu - 7), "PP-PP at L={l}");
        }
        for p in all(l) {
            assert_eq!(
                p.frame_len(),
                brute_force_k(l, p.pattern()),
                "{:?} L={l}",
                p.kind()
            );
            assert_eq!(p.steps().count(), p.frame_len());
            for i in 0..l {
                assert_eq!(p.measurements(i).count(), p.measurements_per_injection());
            }
            for (k, s) in p.steps().enumerate() {
                assert_eq!(p.step(k), Some(s));
            }
            assert_eq!(p.step(p.frame_len()), None);
            assert!(p.frame_len() <= K_MAX);
        }
    }
    // The method's worked numbers at L = 16.
    assert_eq!(
        Protocol::new(ProtocolKind::Adjacent, 16)
            .unwrap()
            .frame_len(),
        208
    );
    let op16 = Protocol::new(ProtocolKind::Opposite, 16).unwrap();
    assert_eq!(op16.feature_count(Halving::Reciprocity), 96);
    let op8 = Protocol::new(ProtocolKind::Opposite, 8).unwrap();
    assert_eq!(op8.feature_count(Halving::Reciprocity), 16);
    assert_eq!(op8.feature_count(Halving::None), 32);
}

#[test]
fn no_measurement_touches_a_current_carrying_electrode() {
    for l in every_l() {
        for p in all(l) {
            for s in p.steps() {
                assert!(!s.injection.carries(s.measurement.positive), "{s:?}");
                assert!(!s.injection.carries(s.measurement.negative), "{s:?}");
                assert_ne!(s.measurement.positive, s.measurement.negative);
            }
            // And the mask drops exactly the candidates that do.
            for i in 0..l {
                let inj = p.injection(i);
                for (c, (m, _)) in p.candidates(i).enumerate() {
                    let touches = inj.carries(m.positive) || inj.carries(m.negative);
                    assert_eq!(p.selection_mask(i) & (1 << c) == 0, touches);
                }
            }
        }
    }
}

#[test]
fn every_electrode_injects_and_sinks() {
    for l in every_l() {
        for p in all(l) {
            for e in 0..l {
                let e = ElectrodeId(e);
                assert!(
                    p.injections().any(|inj| inj.source == e),
                    "{:?} L={l}",
                    p.kind()
                );
                assert!(
                    p.injections().any(|inj| inj.sink == e),
                    "{:?} L={l}",
                    p.kind()
                );
            }
            assert_eq!(p.injection_count(), usize::from(l));
        }
    }
}

#[test]
fn reciprocity_pairs_map_onto_each_other() {
    for l in every_l() {
        for p in all(l) {
            let halved: Vec<usize> = p.features(Halving::Reciprocity).collect();
            for k in 0..p.frame_len() {
                let (r, sign) = p.representative(k);
                assert!(r <= k);
                // The representative is kept, and maps back onto k with the same sign.
                assert!(halved.binary_search(&r).is_ok());
                let back = p.equivalents(r).find(|&(j, _)| j == k);
                assert_eq!(back, Some((k, sign)), "{:?} L={l} k={k}", p.kind());
                // The pair really is the same two electrode pairs.
                let (s, t) = (p.step(k).unwrap(), p.step(r).unwrap());
                let pairs = |s: Step| {
                    let mut a = [s.injection.source.0, s.injection.sink.0];
                    let mut b = [s.measurement.positive.0, s.measurement.negative.0];
                    a.sort();
                    b.sort();
                    let mut both = [a, b];
                    both.sort();
                    both
                };
                assert_eq!(pairs(s), pairs(t));
            }
        }
    }
}

#[test]
fn adjacent_halving_is_exact_reciprocity() {
    // AD at L = 16: injection (i, i+1) measure (j, j+1) <-> injection (j, j+1) measure (i, i+1).
    let p = Protocol::new(ProtocolKind::Adjacent, 16).unwrap();
    assert_eq!(p.feature_count(Halving::Reciprocity), 104);
    let a = p.index_of(
        Injection {
            source: ElectrodeId(0),
            sink: ElectrodeId(1),
        },
        Measurement {
            positive: ElectrodeId(5),
            negative: ElectrodeId(6),
        },
    );
    let b = p.index_of(
        Injection {
            source: ElectrodeId(5),
            sink: ElectrodeId(6),
        },
        Measurement {
            positive: ElectrodeId(0),
            negative: ElectrodeId(1),
        },
    );
    let (a, b) = (a.unwrap(), b.unwrap());
    assert_eq!(p.representative(b), (a, Sign::Plus));
}

#[test]
fn general_patterns_validate() {
    let custom = |drive_skip, skips| {
        ProtocolKind::Custom(Pattern {
            drive_skip,
            measure_skips: SkipSet(skips),
        })
    };
    assert_eq!(
        Protocol::new(custom(8, 1), 16),
        Err(ProtocolError::DriveSkip {
            drive_skip: 8,
            electrodes: 16
        })
    );
    assert!(matches!(
        Protocol::new(custom(1, 0), 16),
        Err(ProtocolError::MeasureSkips { .. })
    ));
    assert!(matches!(
        Protocol::new(custom(1, 0b111), 16),
        Err(ProtocolError::MeasureSkips { .. })
    ));
    assert!(matches!(
        Protocol::new(custom(1, 1 << 8), 16),
        Err(ProtocolError::MeasureSkips { .. })
    ));
    // Said as the skips given and the bound at this L (it was "measure skips 0x20", a mask).
    assert_eq!(
        Protocol::new(custom(0, 1 << 5), 8).unwrap_err().to_string(),
        "measure skips 5 do not fit 8 electrodes: give 1 to 2 skips, each with skip + 1 <= L/2 \
         (at most 3 here)"
    );
    assert_eq!(
        Protocol::new(custom(0, 0), 8).unwrap_err().to_string(),
        "measure skips none do not fit 8 electrodes: give 1 to 2 skips, each with skip + 1 <= \
         L/2 (at most 3 here)"
    );
    for l in [0, 2, 3, 5, 34, 255] {
        assert_eq!(
            Protocol::new(ProtocolKind::Adjacent, l),
            Err(ProtocolError::ElectrodeCount { electrodes: l })
        );
    }
    // Every valid custom pattern for every L agrees with brute force and stays under K_MAX.
    for l in every_l() {
        for d in 0..l / 2 {
            for s1 in 0..l / 2 {
                for s2 in s1..l / 2 {
                    let kind = custom(d, (1 << s1) | (1 << s2));
                    match Protocol::new(kind, l) {
                        Ok(p) => {
                            assert_eq!(p.frame_len(), brute_force_k(l, p.pattern()));
                            assert!(p.frame_len() <= K_MAX);
                        }
                        Err(e) => {
                            assert_eq!(e, ProtocolError::Empty);
                            assert_eq!(brute_force_k(l, kind.pattern(l)), 0);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn named_protocols_are_cases_of_the_general_form() {
    for l in every_l() {
        for named in all(l) {
            let general = Protocol::new(ProtocolKind::Custom(named.pattern()), l).unwrap();
            assert!(named.steps().eq(general.steps()));
        }
    }
    for kind in ProtocolKind::NAMED {
        assert_eq!(ProtocolKind::from_name(kind.name()), Some(kind));
    }
    assert_eq!(
        ProtocolKind::from_name("PP"),
        Some(ProtocolKind::PseudoPolar)
    );
    assert_eq!(ProtocolKind::from_name("nope"), None);
}

#[test]
fn mux_words_route_the_injection() {
    let p = Protocol::new(ProtocolKind::Opposite, 16).unwrap();
    for inj in p.injections() {
        let w = MuxWord::for_injection(inj).unwrap();
        assert_eq!(w.injection(), Some(inj));
        assert_eq!(w.disabled().injection(), None);
        assert!(w.0 < 1 << MuxWord::LINES);
        let source_addr: u8 = (0..4).map(|b| u8::from(w.line(b)) << b).sum();
        let sink_addr: u8 = (0..4).map(|b| u8::from(w.line(5 + b)) << b).sum();
        assert_eq!((source_addr, sink_addr), (inj.source.0, inj.sink.0));
        assert!(w.line(4) && w.line(9));
    }
    let p32 = Protocol::new(ProtocolKind::Adjacent, 32).unwrap();
    assert_eq!(
        MuxWord::for_injection(p32.injection(20)),
        Err(ProtocolError::MuxRange {
            electrode: ElectrodeId(20)
        })
    );
}
