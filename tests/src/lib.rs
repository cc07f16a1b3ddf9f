//! Shared fixtures of the end-to-end tests.
//!
//! [`ScriptedSheet`] is a stand-in sensor for tests that need `et-core`'s pieces wired together
//! before the simulator exists: each step's voltage is a fixed function of the step and of the
//! touched class, plus a switching transient and deterministic noise. It is not a physical
//! model (that is `et-sim`'s job) and must never be used to judge accuracy.

use et_core::ScanConfig;
use et_core::frontend::{AdcScale, Frontend};
use et_core::protocol::{Injection, Measurement};
use et_core::rng::Rng;

/// A scripted sensor with `classes` touch positions.
#[derive(Debug)]
pub struct ScriptedSheet {
    scale: AdcScale,
    settle: usize,
    selected: Option<(Injection, Measurement)>,
    /// The touched class (0..classes) or `None` for no touch.
    pub touch: Option<u16>,
    /// Noise amplitude in ADC codes (uniform, +- this).
    pub noise_codes: u16,
    rng: Rng,
}

impl ScriptedSheet {
    /// A sheet with a deterministic noise seed.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self {
            scale: AdcScale::bipolar_16bit(5.0, 1),
            settle: 0,
            selected: None,
            touch: None,
            noise_codes: 3,
            rng: Rng::new(seed),
        }
    }

    fn noise(&mut self) -> i32 {
        let span = 2 * u64::from(self.noise_codes) + 1;
        (self.rng.next_u64() % span) as i32 - i32::from(self.noise_codes)
    }

    /// The noiseless code of a measurement under the current touch.
    #[must_use]
    pub fn level(&self, inj: Injection, m: Measurement) -> i32 {
        let (a, b, c, d) = (
            i32::from(inj.source.0),
            i32::from(inj.sink.0),
            i32::from(m.positive.0),
            i32::from(m.negative.0),
        );
        let base = 33_000 + 40 * (c - d) * (1 + (a - b).abs());
        let bump = self.touch.map_or(0, |t| {
            let t = i32::from(t);
            // Each class moves a different subset of measurements by a few hundred codes.
            if (a + 2 * c + t) % 3 == 0 {
                300 + 50 * t
            } else {
                -120
            }
        });
        base + bump
    }
}

impl Frontend for ScriptedSheet {
    type Error = &'static str;

    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, Self::Error> {
        self.settle = usize::from(config.settle_samples);
        Ok(self.scale)
    }

    fn select(
        &mut self,
        injection: Injection,
        measurement: Measurement,
    ) -> Result<(), Self::Error> {
        self.selected = Some((injection, measurement));
        Ok(())
    }

    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), Self::Error> {
        let (inj, m) = self.selected.ok_or("acquire before select")?;
        let level = self.level(inj, m);
        for (n, s) in samples.iter_mut().enumerate() {
            let transient = if n < self.settle { 4_000 } else { 0 };
            *s = (level + transient + self.noise()).clamp(0, 65_535) as u16;
        }
        Ok(())
    }
}

/// A QDA blob header (PP-PP on 32 electrodes, the longest frame) whose table sizes wrap 32-bit
/// arithmetic to a length under `max_len`: the blob has that wrapped length and a valid CRC,
/// the attack on the board's old unchecked layout. A sound parser refuses it.
///
/// # Panics
/// If no class count and feature count wrap under `max_len` (there are many for 16 KiB).
#[must_use]
pub fn wrapping_qda_blob(max_len: usize) -> Vec<u8> {
    use et_core::model::{HEADER_LEN, MODEL_MAGIC, MODEL_VERSION};
    use et_core::protocol::{Protocol, ProtocolKind};
    // The layout as 32-bit code without overflow checks computed it (f32 tables).
    let wrapped_len = |c: u32, p: u32| -> u32 {
        let pad4 = |n: u32| n.div_ceil(4).wrapping_mul(4);
        let packed = p.wrapping_mul(p + 1) / 2;
        let end = (HEADER_LEN as u32 + pad4(2 * p) + 8 * p)
            .wrapping_add(16u32.wrapping_mul(c))
            .wrapping_add(4u32.wrapping_mul(c).wrapping_mul(p))
            .wrapping_add(4u32.wrapping_mul(c).wrapping_mul(packed));
        pad4(end).wrapping_add(4)
    };
    let k = Protocol::new(ProtocolKind::PpPp, 32)
        .map(|p| p.frame_len() as u32)
        .unwrap_or(0);
    let (c, p, len) = (1..=k)
        .rev()
        .flat_map(|p| (2..=u32::from(u16::MAX)).map(move |c| (c, p)))
        .map(|(c, p)| (c, p, wrapped_len(c, p) as usize))
        .find(|&(_, _, len)| (HEADER_LEN + 4..=max_len).contains(&len))
        .expect("a wrapping header");
    let mut blob = vec![0u8; len];
    blob[..4].copy_from_slice(&MODEL_MAGIC);
    blob[4..6].copy_from_slice(&MODEL_VERSION.to_le_bytes());
    blob[8..10].copy_from_slice(&(c as u16).to_le_bytes());
    blob[10..12].copy_from_slice(&(p as u16).to_le_bytes());
    blob[12..14].copy_from_slice(&(k as u16).to_le_bytes());
    blob[14] = 32;
    blob[15] = 2;
    let crc = et_core::wire::crc32(&blob[..len - 4]);
    blob[len - 4..].copy_from_slice(&crc.to_le_bytes());
    blob
}
