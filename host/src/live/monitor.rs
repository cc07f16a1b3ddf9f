//! Link and signal health over time: frame rate, per-channel SNR, BVC, lost frames.

use super::*;

/// Frame rate, per-channel SNR and BVC over time.
#[derive(Clone, Debug, Default)]
pub struct Monitor {
    /// (wall time s since start, frames/s over the last second).
    pub rate: VecDeque<(f64, f64)>,
    /// (wall time s since start, BVC V): as the frame rate's, so that a recording's loops
    /// and seeks, and another system's frames without times, still run to now.
    pub bvc: VecDeque<(f64, f64)>,
    /// Per-channel SNR over the last `WINDOW` frames, dB (`et_core::stats::channel_snr`); None
    /// for a channel without noise (below one ADC code) or signal.
    pub snr_db: Vec<Option<f64>>,
    /// The last `WINDOW` frames, row-major (K values each).
    recent: VecDeque<f32>,
    /// K of the frames in `recent`.
    k: usize,
    arrivals: VecDeque<f64>,
    started: Option<Instant>,
    last_seq: Option<u32>,
    /// Sequence gaps seen.
    pub gaps: u64,
    /// Frames seen.
    pub frames: u64,
    /// Frames with readings on an ADC rail (`et_core::wire::FLAG_RAIL`).
    pub rail_frames: u64,
    /// Frames scanned with the current source in compliance (`et_core::wire::FLAG_COMPLIANCE`):
    /// a drive contact too resistive or open, readings too small.
    pub compliance_frames: u64,
}

impl Monitor {
    /// Frames kept for the SNR.
    pub const WINDOW: usize = 50;
    /// Points kept per plot.
    pub const HISTORY: usize = 600;

    /// The next frame does not follow the last in sequence (a recording sought to another
    /// place): its sequence number's jump is no gap.
    pub fn resume(&mut self) {
        self.last_seq = None;
    }

    /// Takes one processed frame.
    pub fn add(&mut self, out: &Output) {
        let now = self
            .started
            .get_or_insert_with(Instant::now)
            .elapsed()
            .as_secs_f64();
        self.frames += 1;
        self.rail_frames += u64::from(out.frame.flags & et_core::wire::FLAG_RAIL != 0);
        self.compliance_frames += u64::from(out.frame.flags & et_core::wire::FLAG_COMPLIANCE != 0);
        if let Some(last) = self.last_seq
            && out.frame.seq > last.wrapping_add(1)
        {
            self.gaps += u64::from(out.frame.seq - last - 1);
        }
        self.last_seq = Some(out.frame.seq);
        self.arrivals.push_back(now);
        while self.arrivals.front().is_some_and(|&t| now - t > 1.0) {
            self.arrivals.pop_front();
        }
        push(&mut self.rate, (now, self.arrivals.len() as f64));
        if out.referencing.is_none() {
            push(&mut self.bvc, (now, out.bvc));
        }
        let k = out.frame.voltages.len();
        if k != self.k {
            self.recent.clear();
            self.k = k;
        }
        self.recent.extend(&out.frame.voltages);
        while self.recent.len() > Self::WINDOW * k {
            self.recent.drain(..k);
        }
        self.snr_db.resize(k, None);
        // A frame window with too few frames (or a non-finite value) keeps the last SNR.
        let _ = stats::channel_snr(self.recent.make_contiguous(), k, &mut self.snr_db);
    }
}

pub(super) fn push(q: &mut VecDeque<(f64, f64)>, p: (f64, f64)) {
    q.push_back(p);
    if q.len() > Monitor::HISTORY {
        q.pop_front();
    }
}
