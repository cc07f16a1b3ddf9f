//! The board's sampling: ADC1 converts every electrode's buffered potential in one scan
//! (channels 0 to L-1), TIM2's update event triggers each scan at the configured sample rate,
//! and DMA2 stream 0 (channel 0) moves the codes into RAM. One burst of `samples_per_step`
//! scans per injection; the measurements of that injection are differences of two channels of
//! the same burst (`et_core::frontend::ParallelBurst`), the reference board's "all channels of
//! an injection in parallel" (docs/method.md §2, §3: 16 channels x 62.5 kS/s = 1 MS/s aggregate).
//!
//! Register-level on purpose: the burst length changes with the configuration, which the
//! HAL's fixed-size DMA transfers do not allow. Not runnable under QEMU (no ADC there).

use core::sync::atomic::{Ordering, compiler_fence};

use et_core::frontend::{
    AdcScale, BurstError, Frontend, MuxError, MuxLines, ParallelBurst, difference_scale,
};
use et_core::{Injection, Measurement, ScanConfig};
use stm32f4xx_hal::gpio::{AnyPin, Output};
use stm32f4xx_hal::pac::{ADC_COMMON, ADC1, DMA2, TIM2, TIM5};
use stm32f4xx_hal::timer::Delay;

/// Codes one burst may hold: 16 channels x 512 scans (16 KiB of RAM).
pub const BURST_MAX: usize = 16 * 512;
/// ADC resolution.
const ADC_BITS: u8 = 12;
/// Volts at an electrode per ADC code: 3.3 V over 4096 codes through the unity-gain buffers.
const VOLTS_PER_CODE: f32 = 3.3 / 4096.0;
/// Give up on a burst after this many polls of the DMA flags (a stuck trigger).
const POLLS_MAX: u32 = 200_000_000;

/// What the board's front end can fail with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorError {
    /// The configuration needs more electrodes than the board has (16).
    Electrodes,
    /// The board has no programmable gain: only gain 1.
    Gain,
    /// L x samples per step exceeds [`BURST_MAX`].
    Burst,
    /// The sample rate cannot be made from the timer clock.
    Rate,
    /// A mux line failed, or the injection is outside the mux.
    Mux,
    /// The DMA reported an error, the ADC overran, or the burst never completed.
    Sampling,
    /// `acquire` before `configure` and `select`.
    NotReady,
    /// The burst could not be cut into the measurement.
    Cut(BurstError),
}

/// The 10 mux lines' pin type.
pub type MuxPin = AnyPin<Output>;

/// The board's front end (see the module docs).
pub struct Sensor {
    mux: MuxLines<MuxPin, Delay<TIM5, 1_000_000>>,
    adc: ADC1,
    dma: DMA2,
    tim: TIM2,
    /// TIM2's input clock, Hz.
    timer_hz: u32,
    buffer: &'static mut [u16; BURST_MAX],
    channels: usize,
    /// The injection whose burst is in `buffer` (None: stale).
    sampled: Option<Injection>,
    injection: Option<Injection>,
    probe: Option<(usize, usize)>,
}

impl Sensor {
    /// Takes the peripherals (clocks already enabled by the caller) and the burst buffer.
    pub fn new(
        mux: MuxLines<MuxPin, Delay<TIM5, 1_000_000>>,
        adc: ADC1,
        common: &ADC_COMMON,
        dma: DMA2,
        tim: TIM2,
        timer_hz: u32,
        buffer: &'static mut [u16; BURST_MAX],
    ) -> Self {
        // ADC clock = APB2 / 4 = 21 MHz (at most 36 MHz).
        common.ccr().modify(|_, w| w.adcpre().div4());
        adc.cr1().write(|w| w.scan().set_bit()); // RES = 0: 12 bits
        // Convert on TIM2 TRGO's rising edge; DMA request after each conversion, kept on.
        adc.cr2().write(|w| {
            w.exten().rising_edge();
            w.extsel().tim2trgo();
            w.dma().set_bit();
            w.dds().set_bit();
            w.adon().set_bit()
        });
        // Sample time 3 ADC clocks on every channel (code 0): 15 clocks per conversion, 0.71 us
        // at 21 MHz, so 16 channels take 11.4 us (up to 87 kS/s per channel).
        adc.smpr1().write(|w| unsafe { w.bits(0) });
        adc.smpr2().write(|w| unsafe { w.bits(0) });
        // TIM2: update event as TRGO; the period is set per configuration.
        tim.cr2().write(|w| w.mms().update());
        Self {
            mux,
            adc,
            dma,
            tim,
            timer_hz,
            buffer,
            channels: 0,
            sampled: None,
            injection: None,
            probe: None,
        }
    }

    /// Parks the muxes (no current flows).
    pub fn off(&mut self) {
        let Ok(()) = self.mux.off();
    }

    /// One burst of `scans` scans of `self.channels` channels into the buffer.
    fn burst(&mut self, scans: usize) -> Result<(), SensorError> {
        let n = scans * self.channels;
        if n > BURST_MAX || n == 0 {
            return Err(SensorError::Burst);
        }
        let st = self.dma.st(0);
        st.cr().modify(|_, w| w.en().clear_bit());
        while st.cr().read().en().bit_is_set() {}
        self.dma.lifcr().write(|w| {
            w.ctcif0().set_bit();
            w.chtif0().set_bit();
            w.cteif0().set_bit();
            w.cdmeif0().set_bit();
            w.cfeif0().set_bit()
        });
        let dr = self.adc.dr().as_ptr() as u32;
        let buf = self.buffer.as_mut_ptr() as u32;
        // SAFETY (register values): addresses of ADC1's data register and of our static buffer,
        // a count within the buffer; channel 0 of stream 0 is ADC1 (RM0090 table 43).
        st.par().write(|w| unsafe { w.bits(dr) });
        st.m0ar().write(|w| unsafe { w.bits(buf) });
        st.ndtr().write(|w| unsafe { w.bits(n as u32) });
        st.cr().write(|w| {
            unsafe { w.chsel().bits(0) };
            w.msize().bits16();
            w.psize().bits16();
            w.minc().set_bit();
            w.dir().peripheral_to_memory();
            w.en().set_bit()
        });
        // Re-arm the ADC's DMA requests (cleared by an overrun) and start the trigger.
        self.adc.sr().modify(|_, w| w.ovr().clear_bit());
        self.adc.cr2().modify(|_, w| w.dma().clear_bit());
        self.adc.cr2().modify(|_, w| w.dma().set_bit());
        self.tim.cnt().reset();
        self.tim.cr1().modify(|_, w| w.cen().set_bit());
        let mut result = Err(SensorError::Sampling);
        for _ in 0..POLLS_MAX {
            let flags = self.dma.lisr().read();
            if flags.tcif0().bit_is_set() {
                result = Ok(());
                break;
            }
            if flags.teif0().bit_is_set() || self.adc.sr().read().ovr().bit_is_set() {
                break;
            }
        }
        self.tim.cr1().modify(|_, w| w.cen().clear_bit());
        compiler_fence(Ordering::SeqCst);
        result
    }
}

impl Frontend for Sensor {
    type Error = SensorError;

    fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, SensorError> {
        let l = usize::from(config.electrodes);
        if l > 16 {
            return Err(SensorError::Electrodes);
        }
        if config.gain != 1 {
            return Err(SensorError::Gain);
        }
        if l * usize::from(config.samples_per_step) > BURST_MAX {
            return Err(SensorError::Burst);
        }
        let ticks = self.timer_hz / config.sample_rate_hz.max(1);
        if ticks < 2 {
            return Err(SensorError::Rate);
        }
        // Channels 0..L in sequence order.
        let ch = |k: usize| if k < l { k as u32 } else { 0 };
        let sqr3 = (0..6).fold(0, |a, k| a | ch(k) << (5 * k));
        let sqr2 = (0..6).fold(0, |a, k| a | ch(k + 6) << (5 * k));
        let sqr1 = (0..4).fold(0, |a, k| a | ch(k + 12) << (5 * k)) | ((l as u32 - 1) << 20);
        // SAFETY (register values): channel numbers below 16 and a length L - 1 below 16.
        self.adc.sqr3().write(|w| unsafe { w.bits(sqr3) });
        self.adc.sqr2().write(|w| unsafe { w.bits(sqr2) });
        self.adc.sqr1().write(|w| unsafe { w.bits(sqr1) });
        self.tim.psc().write(|w| w.psc().set(0));
        self.tim.arr().write(|w| unsafe { w.bits(ticks - 1) });
        self.channels = l;
        self.sampled = None;
        Ok(difference_scale(ADC_BITS, VOLTS_PER_CODE))
    }

    fn select(
        &mut self,
        injection: Injection,
        measurement: Measurement,
    ) -> Result<(), SensorError> {
        if self.injection != Some(injection) {
            self.mux
                .route(injection)
                .map_err(|_: MuxError<_>| SensorError::Mux)?;
            self.injection = Some(injection);
        }
        self.probe = Some((
            usize::from(measurement.positive.0),
            usize::from(measurement.negative.0),
        ));
        Ok(())
    }

    fn acquire(&mut self, samples: &mut [u16]) -> Result<(), SensorError> {
        let (Some(injection), Some((p, q))) = (self.injection, self.probe) else {
            return Err(SensorError::NotReady);
        };
        if self.sampled != Some(injection) {
            self.sampled = None;
            self.burst(samples.len())?;
            self.sampled = Some(injection);
        }
        let n = samples.len() * self.channels;
        ParallelBurst::new(&self.buffer[..n], self.channels, ADC_BITS)
            .and_then(|b| b.difference(p, q, samples))
            .map_err(SensorError::Cut)
    }
}
