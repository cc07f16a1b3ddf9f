//! The board: pin map, clocks, the front end and the model storage of the STM32F405 that
//! drives the mux PCB (docs/method.md §2), and their QEMU stand-ins.
//!
//! | signal | pin | notes |
//! | --- | --- | --- |
//! | electrode 0..7 potential | PA0..PA7 (ADC1 IN0..IN7) | unity-gain buffers, 0 to 3.3 V |
//! | electrode 8, 9 | PB0, PB1 (IN8, IN9) | |
//! | electrode 10..15 | PC0..PC5 (IN10..IN15) | |
//! | source mux A0..A3, EN | PB4..PB7, PB8 | ADG1606 #1, to the Howland current source |
//! | sink mux A0..A3, EN | PB9, PB12..PB14, PB15 | ADG1606 #2, to ground |
//! | serial TX / RX | PA9 / PA10 (USART1) | to the host, 2 000 000 baud, 8N1 |
//!
//! Sampling: ADC1 scans the L electrodes on every TIM2 update (the sample rate), DMA2 stream 0
//! stores the burst (`sampler.rs`); a measurement is the difference of two electrodes. The
//! mux lines are driven by `et_core::frontend::MuxLines` (break-before-make, settle delay,
//! TIM5 as the delay). JTAG's PB3/PB4 are free once the mux takes PB4: debug with SWD
//! (PA13/PA14).

use et_core::ScanConfig;

/// Serial link speed, 8N1: `et_core::board::BAUD` (the host opens the port at the same).
pub use et_core::board::BAUD;

/// How often a status event goes out, in ms.
pub const STATUS_PERIOD_MS: u32 = 500;

/// The configuration after reset (docs/method.md §3's reference point: L = 16, adjacent, 78 Hz).
pub const DEFAULT_CONFIG: ScanConfig = ScanConfig::REFERENCE;

#[cfg(not(feature = "qemu"))]
pub use crate::sampler::BURST_MAX;
#[cfg(feature = "qemu")]
pub use emulated::{SYSTICK_HZ, Sensor, Slots, Store, before_scan, clocks, sensor};
#[cfg(not(feature = "qemu"))]
pub use real::{SYSTICK_HZ, Sensor, SensorParts, Store, before_scan, clocks, sensor, store};

#[cfg(not(feature = "qemu"))]
mod real {
    use crate::sampler::{self, BURST_MAX, MuxPin};
    use et_core::frontend::MuxLines;
    use stm32f4xx_hal::gpio::{Analog, AnyPin};
    use stm32f4xx_hal::pac::{ADC_COMMON, ADC1, DMA2, FLASH, TIM2, TIM5};
    use stm32f4xx_hal::prelude::_fugit_RateExtU32 as _;
    use stm32f4xx_hal::prelude::_stm32f4xx_hal_timer_TimerExt as _;
    use stm32f4xx_hal::rcc::{Config, Enable, Rcc, Reset};

    /// Settling wait after a mux switch, in ns: the buffers and the source settle in about
    /// 8 us (docs/method.md §2).
    pub const MUX_SETTLE_NS: u32 = 8_000;

    /// System clock: HSI (16 MHz internal, no crystal needed) through the PLL.
    pub const SYSCLK_HZ: u32 = 168_000_000;

    /// SysTick counts the core clock.
    pub const SYSTICK_HZ: u32 = SYSCLK_HZ;

    /// TIM2's clock: APB1 at 42 MHz, doubled for the timers.
    const TIM2_HZ: u32 = 84_000_000;

    /// The clock tree: 168 MHz core, APB1 42 MHz (USART1 on APB2 at 84 MHz divides to 2 Mbaud
    /// exactly).
    pub fn clocks() -> Config {
        Config::hsi()
            .sysclk(SYSCLK_HZ.Hz())
            .pclk1(42.MHz())
            .pclk2(84.MHz())
    }

    /// Model storage: two flash slots.
    pub type Store = crate::store::FlashStore;

    /// The model slots in flash.
    pub fn store(flash: FLASH) -> Store {
        crate::store::FlashStore::new(flash)
    }

    /// The board's front end.
    pub type Sensor = sampler::Sensor;

    /// What the front end is made of.
    pub struct SensorParts {
        /// Electrode inputs in electrode order (their analog mode is all that matters).
        pub analog: [AnyPin<Analog>; 16],
        /// The mux lines in `MuxWord` order.
        pub mux: [MuxPin; 10],
        /// The ADC.
        pub adc: ADC1,
        /// The ADCs' common registers.
        pub common: ADC_COMMON,
        /// The DMA controller.
        pub dma: DMA2,
        /// The sample-rate timer.
        pub trigger: TIM2,
        /// The mux settling delay.
        pub delay: TIM5,
    }

    /// The front end on its pins, muxes off.
    pub fn sensor(
        parts: SensorParts,
        rcc: &mut Rcc,
        burst: &'static mut [u16; BURST_MAX],
    ) -> Sensor {
        let SensorParts {
            analog,
            mux,
            adc,
            common,
            dma,
            trigger,
            delay,
        } = parts;
        let _ = analog; // in analog mode from here on
        ADC1::enable(rcc);
        ADC1::reset(rcc);
        DMA2::enable(rcc);
        TIM2::enable(rcc);
        TIM2::reset(rcc);
        let delay = delay.delay_us(rcc);
        // GPIO writes cannot fail on this chip (the error type is Infallible).
        let Ok(mut mux) = MuxLines::new(mux, delay, MUX_SETTLE_NS);
        let Ok(()) = mux.off();
        sampler::Sensor::new(mux, adc, &common, dma, trigger, TIM2_HZ, burst)
    }

    /// Before scan `seq`: nothing to do on the board.
    pub fn before_scan(_: &mut Sensor, _: u32) {}
}

#[cfg(feature = "qemu")]
mod emulated {
    use crate::qemu_sheet;
    use et_core::device::RamStore;
    use et_core::emulated::EmulatedSheet;
    use stm32f4xx_hal::rcc::Config;

    /// QEMU's SysTick counts at the netduinoplus2's nominal 168 MHz whatever the clock set-up
    /// says (it does not emulate the RCC), so the monotonic is started at that rate.
    pub const SYSTICK_HZ: u32 = 168_000_000;

    /// The clock tree: HSI at 16 MHz without the PLL (QEMU hangs in the PLL set-up).
    pub fn clocks() -> Config {
        Config::hsi()
    }

    /// Bytes per model slot in RAM (QEMU has no flash programming).
    pub const SLOT_BYTES: usize = et_core::board::QEMU_SLOT_BYTES;

    /// Two RAM slots (a static of `init`).
    pub type Slots = RamStore<SLOT_BYTES>;

    /// Model storage: the RAM slots.
    pub type Store = &'static mut Slots;

    /// The front end: the compiled-in sheet.
    pub type Sensor = EmulatedSheet<'static>;

    /// The sheet of `qemu_sheet.rs`.
    pub fn sensor() -> Sensor {
        EmulatedSheet::new(
            qemu_sheet::ELECTRODES,
            &qemu_sheet::Z,
            qemu_sheet::NOISE_V,
            0x5eed,
        )
        .unwrap_or_else(|_| panic!("qemu_sheet.rs holds whole L x L tables"))
    }

    /// Before scan `seq`: the touch state of that frame (`et_sim::emulated::QemuSheet::state_of`).
    pub fn before_scan(sheet: &mut Sensor, seq: u32) {
        sheet.set_state((seq / qemu_sheet::FRAMES_PER_STATE) as usize);
    }
}
