//! Link and signal health over time: frame rate, per-channel SNR, BVC, lost frames.

use super::*;

/// Frame rate, per-channel SNR and BVC over time.
#[derive(Clone, Debug, Default)]
pub struct Monitor {
    /// (wall time s since start, frames/s over the last second).
    pub rate: VecDeque<(f64, f64)>,
    /// (frame time s, BVC V).
    pub bvc: VecDeque<(f64, f64)>,
    /// Per-channel SNR over the last `WINDOW` frames, dB (20 log10 |mean| / std).
    pub snr_db: Vec<f64>,
    recent: VecDeque<Vec<f32>>,
    arrivals: VecDeque<f64>,
    started: Option<Instant>,
    last_seq: Option<u32>,
    /// Sequence gaps seen.
    pub gaps: u64,
    /// Frames seen.
    pub frames: u64,
}

impl Monitor {
    /// Frames kept for the SNR.
    pub const WINDOW: usize = 50;
    /// Points kept per plot.
    pub const HISTORY: usize = 600;

    /// Takes one processed frame.
    pub fn add(&mut self, out: &Output) {
        let now = self
            .started
            .get_or_insert_with(Instant::now)
            .elapsed()
            .as_secs_f64();
        self.frames += 1;
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
            push(&mut self.bvc, (f64::from(out.frame.t_us) * 1e-6, out.bvc));
        }
        if self
            .recent
            .front()
            .is_some_and(|f| f.len() != out.frame.voltages.len())
        {
            self.recent.clear();
        }
        self.recent.push_back(out.frame.voltages.clone());
        if self.recent.len() > Self::WINDOW {
            self.recent.pop_front();
        }
        let n = self.recent.len();
        if n >= 2 {
            let k = out.frame.voltages.len();
            self.snr_db = (0..k)
                .map(|i| {
                    let mean = self.recent.iter().map(|f| f64::from(f[i])).sum::<f64>() / n as f64;
                    let var = self
                        .recent
                        .iter()
                        .map(|f| (f64::from(f[i]) - mean).powi(2))
                        .sum::<f64>()
                        / (n - 1) as f64;
                    if var > 0.0 {
                        20.0 * (mean.abs() / var.sqrt()).log10()
                    } else {
                        f64::NAN
                    }
                })
                .collect();
        }
    }
}

pub(super) fn push(q: &mut VecDeque<(f64, f64)>, p: (f64, f64)) {
    q.push_back(p);
    if q.len() > Monitor::HISTORY {
        q.pop_front();
    }
}
