//! Signal statistics of repeated frames (SNR, MAD; docs/method.md §3), the reference frame
//! V_0 and the noise of dV, and the boundary voltage change of a frame difference (BVC, §7).
//!
//! `frames` is always row-major: `n` frames of `k` values each (`frames[f * k + i]` is channel
//! i of frame f). Sums are accumulated in f64.

/// Why a statistic could not be computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StatsError {
    /// `k` is 0, `frames.len()` is not a multiple of `k`, or two frames differ in length.
    #[error("frames do not have a consistent length")]
    Shape,
    /// Fewer frames than the statistic needs (2 for a variance, 1 for a mean).
    #[error("{frames} frame(s): need at least {needed}")]
    TooFewFrames {
        /// Frames given.
        frames: usize,
        /// Frames the statistic needs.
        needed: usize,
    },
    /// A value is NaN or infinite.
    #[error("a voltage is NaN or infinite")]
    NonFinite,
    /// No channel had both signal and noise, so no SNR is defined.
    #[error("no channel has both signal and noise")]
    NoChannel,
}

/// Signal-to-noise ratio over repeated frames [3.1].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Snr {
    /// Mean over the used channels of 20 log10(|E\[V_i]| / sqrt(Var V_i)), in dB.
    pub mean_db: f32,
    /// Channels averaged.
    pub channels: usize,
    /// Channels left out because they had no noise at all (infinite SNR, e.g. noise below one
    /// ADC code) or a mean of exactly zero (SNR of minus infinity).
    pub excluded: usize,
}

fn shape(frames: &[f32], k: usize, min_frames: usize) -> Result<usize, StatsError> {
    if k == 0 || !frames.len().is_multiple_of(k) {
        return Err(StatsError::Shape);
    }
    let n = frames.len() / k;
    if n < min_frames {
        return Err(StatsError::TooFewFrames {
            frames: n,
            needed: min_frames,
        });
    }
    if frames.iter().any(|v| !v.is_finite()) {
        return Err(StatsError::NonFinite);
    }
    Ok(n)
}

/// Mean and sample variance (n - 1) of channel `i`.
fn mean_var(frames: &[f32], k: usize, n: usize, i: usize) -> (f64, f64) {
    let column = || frames.iter().skip(i).step_by(k).map(|&v| f64::from(v));
    let mean = column().sum::<f64>() / n as f64;
    let var = column().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
    (mean, var)
}

/// SNR per channel = 20 log10(|E\[V_i]| / sqrt(Var(V_i))), averaged over channels (docs/method.md §3:
/// the printed [3.1] has the ratio upside down; signal over noise is what is meant and what
/// gives the 45 to 60 dB band).
///
/// # Errors
/// [`StatsError`] for a bad shape, fewer than 2 frames, non-finite values, or no usable channel.
pub fn snr(frames: &[f32], k: usize) -> Result<Snr, StatsError> {
    let n = shape(frames, k, 2)?;
    let (mut sum, mut channels, mut excluded) = (0.0f64, 0usize, 0usize);
    for i in 0..k {
        match snr_of_channel(frames, k, n, i) {
            Some(db) => {
                sum += db;
                channels += 1;
            }
            None => excluded += 1,
        }
    }
    if channels == 0 {
        return Err(StatsError::NoChannel);
    }
    Ok(Snr {
        mean_db: (sum / channels as f64) as f32,
        channels,
        excluded,
    })
}

/// The SNR of each channel, dB, into `out` (k values): as [`snr`] before the average, None
/// for a channel without noise or with a zero mean.
///
/// # Errors
/// [`StatsError`] for a bad shape, fewer than 2 frames, non-finite values, or `out` not of
/// length `k`.
pub fn channel_snr(frames: &[f32], k: usize, out: &mut [Option<f64>]) -> Result<(), StatsError> {
    let n = shape(frames, k, 2)?;
    if out.len() != k {
        return Err(StatsError::Shape);
    }
    for (i, o) in out.iter_mut().enumerate() {
        *o = snr_of_channel(frames, k, n, i);
    }
    Ok(())
}

/// 20 log10(|E\[V_i]| / sqrt(Var V_i)) of channel `i`, None without noise or signal.
fn snr_of_channel(frames: &[f32], k: usize, n: usize, i: usize) -> Option<f64> {
    let (mean, var) = mean_var(frames, k, n, i);
    (var > 0.0 && mean != 0.0).then(|| 20.0 * libm_log10(mean.abs() / sqrt(var)))
}

/// Mean absolute deviation of repeated frames: the mean over channels and frames of
/// |V_i - E\[V_i]|, in the frames' unit (volts). docs/method.md §3 reference: 0.5 mV at 32 uA.
///
/// # Errors
/// [`StatsError`] for a bad shape, fewer than 2 frames or non-finite values.
pub fn mad(frames: &[f32], k: usize) -> Result<f32, StatsError> {
    let n = shape(frames, k, 2)?;
    let mut total = 0.0f64;
    for i in 0..k {
        let (mean, _) = mean_var(frames, k, n, i);
        total += frames
            .iter()
            .skip(i)
            .step_by(k)
            .map(|&v| (f64::from(v) - mean).abs())
            .sum::<f64>();
    }
    Ok((total / (n * k) as f64) as f32)
}

/// Boundary voltage change BVC = ||V_1 - V_0|| (Euclidean) [4.1], in volts.
///
/// # Errors
/// [`StatsError::Shape`] if the lengths differ or are 0, [`StatsError::NonFinite`].
pub fn bvc(v1: &[f32], v0: &[f32]) -> Result<f32, StatsError> {
    if v1.len() != v0.len() || v1.is_empty() {
        return Err(StatsError::Shape);
    }
    if v1.iter().chain(v0).any(|v| !v.is_finite()) {
        return Err(StatsError::NonFinite);
    }
    let sq: f64 = v1
        .iter()
        .zip(v0)
        .map(|(&a, &b)| {
            let d = f64::from(a) - f64::from(b);
            d * d
        })
        .sum();
    Ok(sqrt(sq) as f32)
}

/// BVC = ||dV|| of a frame difference already formed (dV = V_1 - V_0, V), as
/// [`bvc`] gives from the two frames.
#[must_use]
pub fn bvc_dv(dv: &[f64]) -> f64 {
    sqrt(dv.iter().map(|v| v * v).sum())
}

/// Checks that `frames` all have `k` finite values and returns their count.
fn frame_count<F: AsRef<[T]>, T: Copy + Into<f64>>(
    frames: &[F],
    k: usize,
) -> Result<f64, StatsError> {
    for f in frames {
        let f = f.as_ref();
        if f.len() != k {
            return Err(StatsError::Shape);
        }
        if f.iter().any(|&v| !v.into().is_finite()) {
            return Err(StatsError::NonFinite);
        }
    }
    Ok(frames.len() as f64)
}

/// V_0, the reference of difference imaging and of referenced models: the mean of each
/// channel over `frames` (untouched frames of K values each, V) into `v0` (K values). This
/// is the one place et averages reference frames.
///
/// # Errors
/// [`StatsError::TooFewFrames`] for no frame, [`StatsError::Shape`] when a frame's length
/// is not `v0.len()`, [`StatsError::NonFinite`].
pub fn reference<F: AsRef<[T]>, T: Copy + Into<f64>>(
    frames: &[F],
    v0: &mut [f64],
) -> Result<(), StatsError> {
    if frames.is_empty() {
        return Err(StatsError::TooFewFrames {
            frames: 0,
            needed: 1,
        });
    }
    let n = frame_count(frames, v0.len())?;
    for (c, out) in v0.iter_mut().enumerate() {
        *out = frames.iter().map(|f| f.as_ref()[c].into()).sum::<f64>() / n;
    }
    Ok(())
}

/// The variance of each channel of dV = V_1 - V_0 when V_0 is the mean of `frames`
/// (untouched, V, [`reference`]) and V_1 one more frame of the same noise: the sample
/// variance x (1 + 1/n), V^2, into `var` (K values). With fewer than two frames the noise
/// is unknown and every value is 0.
///
/// # Errors
/// [`StatsError::Shape`] when a frame's length is not `var.len()`, [`StatsError::NonFinite`].
pub fn dv_variance<F: AsRef<[T]>, T: Copy + Into<f64>>(
    frames: &[F],
    var: &mut [f64],
) -> Result<(), StatsError> {
    let n = frame_count(frames, var.len())?;
    if frames.len() < 2 {
        var.fill(0.0);
        return Ok(());
    }
    for (c, out) in var.iter_mut().enumerate() {
        let x = |f: &F| -> f64 { f.as_ref()[c].into() };
        let mean = frames.iter().map(x).sum::<f64>() / n;
        let ss: f64 = frames
            .iter()
            .map(|f| {
                let d = x(f) - mean;
                d * d
            })
            .sum();
        *out = ss / (n - 1.0) * (1.0 + 1.0 / n);
    }
    Ok(())
}

/// log10 without std: log2 by exponent/mantissa split and a series, good to ~1e-12.
fn libm_log10(x: f64) -> f64 {
    ln(x) / core::f64::consts::LN_10
}

/// Natural log for positive finite x (no_std has no f64::ln).
fn ln(x: f64) -> f64 {
    debug_assert!(x > 0.0 && x.is_finite());
    // x = m * 2^e with m in [1, 2); ln x = e ln 2 + ln m, ln m = 2 atanh((m-1)/(m+1)).
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if e == -1023 {
        // Subnormal: renormalise.
        let scaled = x * f64::from_bits(0x4330_0000_0000_0000); // 2^52
        let b = scaled.to_bits();
        e = ((b >> 52) & 0x7ff) as i64 - 1023 - 52;
        m = f64::from_bits((b & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    }
    if m > core::f64::consts::SQRT_2 {
        m /= 2.0;
        e += 1;
    }
    let t = (m - 1.0) / (m + 1.0);
    let t2 = t * t;
    let mut term = t;
    let mut sum = 0.0;
    let mut n = 1.0;
    while n < 60.0 {
        sum += term / n;
        term *= t2;
        n += 2.0;
    }
    e as f64 * core::f64::consts::LN_2 + 2.0 * sum
}

/// Square root for non-negative finite x (Newton from the exponent-halved guess).
fn sqrt(x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let guess = f64::from_bits((x.to_bits() >> 1) + (0x3ff0_0000_0000_0000 >> 1));
    // One step lands at or above sqrt(x); from there Newton decreases strictly until it
    // settles, so the loop ends.
    let mut y = 0.5 * (guess + x / guess);
    loop {
        let next = 0.5 * (y + x / y);
        if next >= y {
            return y;
        }
        y = next;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    #[test]
    fn log_and_sqrt_match_std() {
        for &x in &[
            1e-300, 1e-12, 0.3, 1.0, 1.5, 2.0, 10.0, 12345.678, 1e200, 5e-324,
        ] {
            assert!(
                (ln(x) - x.ln()).abs() <= 1e-12 * x.ln().abs().max(1.0),
                "ln {x}"
            );
            assert!((sqrt(x) - x.sqrt()).abs() <= 1e-14 * x.sqrt(), "sqrt {x}");
        }
        assert!((libm_log10(1000.0) - 3.0).abs() < 1e-13);
    }

    #[test]
    fn snr_of_a_known_signal() {
        // Channel 0: mean 1, values 1 +- 0.01 alternating -> sample std = 0.01 * sqrt(n/(n-1)).
        // Channel 1: mean -0.1 (sign must not matter), same noise.
        let n = 1000;
        let mut frames = Vec::new();
        for f in 0..n {
            let d = if f % 2 == 0 { 0.01 } else { -0.01 };
            frames.extend([1.0 + d, -0.1 + d]);
        }
        let s = snr(&frames, 2).unwrap();
        let corr = 10.0 * (n as f64 / (n - 1) as f64).log10();
        let want = ((40.0 - corr) + (20.0 - corr)) / 2.0;
        assert!(
            (f64::from(s.mean_db) - want).abs() < 1e-3,
            "{s:?} want {want}"
        );
        assert_eq!((s.channels, s.excluded), (2, 0));
        // Per channel: each its own value; a constant channel has none.
        let with_flat: Vec<f32> = frames.chunks(2).flat_map(|f| [f[0], f[1], 0.5]).collect();
        let mut per = [None; 3];
        channel_snr(&with_flat, 3, &mut per).unwrap();
        assert!((per[0].unwrap() - (40.0 - corr)).abs() < 1e-3, "{per:?}");
        assert!((per[1].unwrap() - (20.0 - corr)).abs() < 1e-3, "{per:?}");
        assert_eq!(per[2], None);
        assert_eq!(
            channel_snr(&with_flat, 3, &mut per[..2]),
            Err(StatsError::Shape)
        );
        // Larger noise, lower SNR: the sign is the right way round.
        let noisy: Vec<f32> = frames
            .iter()
            .enumerate()
            .map(|(i, v)| v + if i % 4 < 2 { 0.05 } else { -0.05 })
            .collect();
        assert!(snr(&noisy, 2).unwrap().mean_db < s.mean_db);
    }

    #[test]
    fn mad_and_bvc() {
        let frames = [1.0, 2.0, 3.0, 2.0, 1.0, 6.0];
        // k = 3: ch0 = {1, 2}, ch1 = {2, 1}, ch2 = {3, 6}: deviations 0.5,0.5 / 0.5,0.5 / 1.5,1.5.
        assert!((mad(&frames, 3).unwrap() - (0.5 * 4.0 + 3.0) / 6.0).abs() < 1e-6);
        assert_eq!(bvc(&[3.0, 4.0], &[0.0, 0.0]).unwrap(), 5.0);
        assert_eq!(bvc(&[1.0], &[1.0, 2.0]), Err(StatsError::Shape));
    }

    #[test]
    fn bad_inputs_are_errors_not_nans() {
        assert_eq!(snr(&[1.0, 2.0, 3.0], 2), Err(StatsError::Shape));
        assert_eq!(
            snr(&[1.0, 2.0], 2),
            Err(StatsError::TooFewFrames {
                frames: 1,
                needed: 2
            })
        );
        assert_eq!(
            snr(&[1.0, f32::NAN, 1.0, 1.0], 2),
            Err(StatsError::NonFinite)
        );
        assert_eq!(snr(&[1.0, 1.0, 1.0, 1.0], 2), Err(StatsError::NoChannel));
        assert_eq!(bvc(&[f32::INFINITY], &[0.0]), Err(StatsError::NonFinite));
        // A noiseless channel is excluded and counted, not averaged in as infinity.
        let s = snr(&[1.0, 5.0, 1.1, 5.0, 0.9, 5.0], 2).unwrap();
        assert_eq!((s.channels, s.excluded), (1, 1));
        assert!(s.mean_db.is_finite());
    }

    #[test]
    fn reference_and_dv_variance_of_known_frames() {
        let frames: [[f32; 2]; 3] = [[1.0, -2.0], [2.0, -2.0], [3.0, -2.0]];
        let mut v0 = [0.0; 2];
        reference(&frames, &mut v0).unwrap();
        assert_eq!(v0, [2.0, -2.0]);
        let mut var = [9.0; 2];
        dv_variance(&frames, &mut var).unwrap();
        // Sample variance 1 (n - 1 = 2) times (1 + 1/3); the constant channel has none.
        assert!(
            (var[0] - 4.0 / 3.0).abs() < 1e-12 && var[1] == 0.0,
            "{var:?}"
        );
        dv_variance(&frames[..1], &mut var).unwrap();
        assert_eq!(var, [0.0, 0.0]);
        assert_eq!(
            reference::<[f32; 2], f32>(&[], &mut v0),
            Err(StatsError::TooFewFrames {
                frames: 0,
                needed: 1
            })
        );
        assert_eq!(reference(&frames, &mut [0.0; 3]), Err(StatsError::Shape));
        assert_eq!(
            reference(&[[f64::NAN, 0.0]], &mut v0),
            Err(StatsError::NonFinite)
        );
        assert!((bvc_dv(&[3.0, -4.0]) - 5.0).abs() < 1e-15);
    }
}
