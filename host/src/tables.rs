//! A protocol's tables as plain data: what `et protocol` prints, as text or JSON.

use std::fmt::Write as _;

use et_core::protocol::{Halving, MuxWord, Protocol};
use serde::Serialize;

/// One injection and what is measured during it.
#[derive(Debug, Clone, Serialize)]
pub struct InjectionRow {
    /// Injection number, 0..L.
    pub index: u8,
    /// Electrode connected to the current source.
    pub source: u8,
    /// Electrode connected to ground.
    pub sink: u8,
    /// The 10-line mux control word (docs/method.md §2), absent when an electrode is past 15.
    pub mux_word: Option<u16>,
    /// Bit c set = candidate measurement c is kept (see `et_core::protocol::Protocol::candidates`).
    pub selection_mask: u64,
    /// Frame index of the first measurement of this injection.
    pub first_k: usize,
    /// Selected measurements as [positive, negative] electrode pairs, in frame order.
    pub measurements: Vec<[u8; 2]>,
}

/// Everything `et protocol` reports.
#[derive(Debug, Clone, Serialize)]
pub struct ProtocolTables {
    /// Protocol name (adjacent, pseudo-polar, pp-pp, opposite, custom).
    pub protocol: &'static str,
    /// Electrode count L.
    pub electrodes: u8,
    /// Inject between i and i + drive_skip + 1.
    pub drive_skip: u8,
    /// Measure between j and j + s + 1 for each s.
    pub measure_skips: Vec<u8>,
    /// Frame length K.
    #[serde(rename = "K")]
    pub frame_len: usize,
    /// Feature count with reciprocity halving (the classifier's p, docs/method.md §9).
    pub p_halved: usize,
    /// Feature count without halving (= K).
    pub p_full: usize,
    /// Frame indices of the halved feature set.
    pub features_halved: Vec<usize>,
    /// The L injections.
    pub injections: Vec<InjectionRow>,
}

impl ProtocolTables {
    /// Collects the tables of `protocol`.
    #[must_use]
    pub fn new(protocol: &Protocol) -> Self {
        let per = protocol.measurements_per_injection();
        let injections = (0..protocol.electrodes())
            .map(|i| {
                let inj = protocol.injection(i);
                InjectionRow {
                    index: i,
                    source: inj.source.0,
                    sink: inj.sink.0,
                    mux_word: MuxWord::for_injection(inj).ok().map(|w| w.0),
                    selection_mask: protocol.selection_mask(i),
                    first_k: usize::from(i) * per,
                    measurements: protocol
                        .measurements(i)
                        .map(|m| [m.positive.0, m.negative.0])
                        .collect(),
                }
            })
            .collect();
        let pattern = protocol.pattern();
        let features_halved: Vec<usize> = protocol.features(Halving::Reciprocity).collect();
        Self {
            protocol: protocol.kind().name(),
            electrodes: protocol.electrodes(),
            drive_skip: pattern.drive_skip,
            measure_skips: pattern.measure_skips.iter().collect(),
            frame_len: protocol.frame_len(),
            p_halved: features_halved.len(),
            p_full: protocol.feature_count(Halving::None),
            features_halved,
            injections,
        }
    }

    /// A human-readable report: the summary, then one line per injection.
    #[must_use]
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let skips: Vec<String> = self.measure_skips.iter().map(u8::to_string).collect();
        let _ = writeln!(
            s,
            "protocol {} on L = {} electrodes",
            self.protocol, self.electrodes
        );
        let _ = writeln!(
            s,
            "  drive skip {} (inject i -> i+{}), measure skip(s) {}",
            self.drive_skip,
            self.drive_skip + 1,
            skips.join(", ")
        );
        let _ = writeln!(
            s,
            "  K = {} measurements per frame ({} injections x {})",
            self.frame_len,
            self.injections.len(),
            self.injections.first().map_or(0, |r| r.measurements.len())
        );
        let _ = writeln!(
            s,
            "  p = {} features with reciprocity halving, {} without",
            self.p_halved, self.p_full
        );
        let _ = writeln!(s);
        let _ = writeln!(s, "  inj  src  sink  mux word   k     measurements (+ -)");
        for r in &self.injections {
            let mux = r
                .mux_word
                .map_or_else(|| "(>15)".to_string(), |w| format!("{w:#05x}"));
            let pairs: Vec<String> = r
                .measurements
                .iter()
                .map(|[a, b]| format!("{a}-{b}"))
                .collect();
            let _ = writeln!(
                s,
                "  {:>3}  {:>3}  {:>4}  {:>8}  {:>4}  {}",
                r.index,
                r.source,
                r.sink,
                mux,
                r.first_k,
                pairs.join(" ")
            );
        }
        s
    }
}
