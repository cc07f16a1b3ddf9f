//! The board: pin map, clocks, the front end and the model storage of the STM32F405 that
//! drives the mux PCB (SPEC §2), and their QEMU stand-ins.
//!
//! | signal | pin | notes |
//! | --- | --- | --- |
//! | source mux A0..A3, EN | PC0..PC3, PC4 | ADG1606 #1, to the Howland current source |
//! | sink mux A0..A3, EN | PC5..PC8, PC9 | ADG1606 #2, to ground |
//! | serial TX / RX | PA2 / PA3 (USART2) | to the host, 2 000 000 baud, 8N1 |
//! | status LED | PA5 | not driven yet |
//! | PGIA output to ADC | PA0 (ADC1 IN0) | sampling: not yet (see [`Sensor`]) |
//!
//! The mux lines are driven by `et_core::frontend::MuxLines` (break-before-make, settle delay):
//! the firmware only hands it the pins.

use et_core::ScanConfig;

/// Serial link speed, 8N1 (200 000 bytes/s). The busiest configuration the board can run
/// (L = 16, PP-PP, two measurements per step position, at 78 Hz) needs 66 % of it with its
/// touch events; the reference adjacent frame 36 %. At 921 600 baud the largest frames did not fit
/// (`tests/tests/budget.rs`). USB-serial adapters with FT232R, FT232H, CP2102N or CH340 chips
/// run at 2 Mbaud; USART2's clock (42 MHz) divides to it exactly.
pub const BAUD: u32 = 2_000_000;

/// How often a status event goes out, in ms.
pub const STATUS_PERIOD_MS: u32 = 500;

/// The configuration after reset (SPEC §3's reference point: L = 16, adjacent, 78 Hz).
pub const DEFAULT_CONFIG: ScanConfig = ScanConfig::REFERENCE;

#[cfg(feature = "qemu")]
pub use emulated::{SYSTICK_HZ, Sensor, Slots, Store, before_scan, clocks, sensor};
#[cfg(not(feature = "qemu"))]
pub use real::{SYSTICK_HZ, Sensor, Store, before_scan, clocks, sensor, store};

#[cfg(not(feature = "qemu"))]
mod real {
    use stm32f4xx_hal::gpio::{AnyPin, Output};

    /// Settling wait after a mux switch, in ns: the PGIA settles in about 8 us (SPEC §2).
    pub const MUX_SETTLE_NS: u32 = 8_000;

    /// One mux control line.
    pub type MuxPin = AnyPin<Output>;
    use et_core::frontend::{AdcScale, Frontend, MuxError, MuxLines};
    use et_core::{Injection, Measurement, ScanConfig};
    use stm32f4xx_hal::gpio::gpioc;
    use stm32f4xx_hal::pac::{FLASH, TIM2};
    use stm32f4xx_hal::prelude::_fugit_RateExtU32 as _;
    use stm32f4xx_hal::prelude::_stm32f4xx_hal_timer_TimerExt as _;
    use stm32f4xx_hal::rcc::{Config, Rcc};
    use stm32f4xx_hal::timer::Delay;

    /// System clock: HSI (16 MHz internal, no crystal needed) through the PLL.
    pub const SYSCLK_HZ: u32 = 168_000_000;

    /// SysTick counts the core clock.
    pub const SYSTICK_HZ: u32 = SYSCLK_HZ;

    /// The clock tree.
    pub fn clocks() -> Config {
        Config::hsi().sysclk(SYSCLK_HZ.Hz())
    }

    /// Model storage: two flash slots.
    pub type Store = crate::store::FlashStore;

    /// The model slots in flash.
    pub fn store(flash: FLASH) -> Store {
        crate::store::FlashStore::new(flash)
    }

    /// Why the board's front end failed.
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum SensorError {
        /// A mux line refused its level (cannot happen on this chip: GPIO is infallible).
        Mux,
        /// ADC sampling is not written yet: the board scans produce `Fault::Frontend`.
        NoAdc,
    }

    /// The board's front end: the muxes route the current; sampling the PGIA by ADC and DMA is
    /// the part still to come, so `acquire` refuses (every scan reports `Fault::Frontend`
    /// rather than sending made-up voltages).
    pub struct Sensor {
        mux: MuxLines<MuxPin, Delay<TIM2, 1_000_000>>,
    }

    impl Frontend for Sensor {
        type Error = SensorError;
        fn configure(&mut self, config: &ScanConfig) -> Result<AdcScale, SensorError> {
            Ok(AdcScale::bipolar_16bit(5.0, config.gain))
        }
        fn select(&mut self, injection: Injection, _: Measurement) -> Result<(), SensorError> {
            self.mux
                .route(injection)
                .map_err(|_: MuxError<_>| SensorError::Mux)
        }
        fn acquire(&mut self, _: &mut [u16]) -> Result<(), SensorError> {
            let Ok(()) = self.mux.off();
            Err(SensorError::NoAdc)
        }
    }

    /// The front end on its pins, muxes off.
    pub fn sensor(gpioc: gpioc::Parts, tim2: TIM2, rcc: &mut Rcc) -> Sensor {
        let lines = [
            gpioc.pc0.into_push_pull_output().erase(),
            gpioc.pc1.into_push_pull_output().erase(),
            gpioc.pc2.into_push_pull_output().erase(),
            gpioc.pc3.into_push_pull_output().erase(),
            gpioc.pc4.into_push_pull_output().erase(),
            gpioc.pc5.into_push_pull_output().erase(),
            gpioc.pc6.into_push_pull_output().erase(),
            gpioc.pc7.into_push_pull_output().erase(),
            gpioc.pc8.into_push_pull_output().erase(),
            gpioc.pc9.into_push_pull_output().erase(),
        ];
        let delay = tim2.delay_us(rcc);
        // GPIO writes cannot fail on this chip (the error type is Infallible).
        let Ok(mut mux) = MuxLines::new(lines, delay, MUX_SETTLE_NS);
        let Ok(()) = mux.off();
        Sensor { mux }
    }

    /// Before scan `seq`: nothing to do on the board.
    pub fn before_scan(_: &mut Sensor, _: u32) {}
}

#[cfg(feature = "qemu")]
mod emulated {
    use crate::qemu_sheet;
    use et_core::device::RamStore;
    use et_core::emulated::EmulatedSheet;
    use stm32f4xx_hal::gpio::gpioc;
    use stm32f4xx_hal::pac::TIM2;
    use stm32f4xx_hal::rcc::{Config, Rcc};

    /// QEMU's SysTick counts at the netduinoplus2's nominal 168 MHz whatever the clock set-up
    /// says (it does not emulate the RCC), so the monotonic is started at that rate.
    pub const SYSTICK_HZ: u32 = 168_000_000;

    /// The clock tree: HSI at 16 MHz without the PLL (QEMU hangs in the PLL set-up).
    pub fn clocks() -> Config {
        Config::hsi()
    }

    /// Bytes per model slot in RAM (QEMU has no flash programming).
    pub const SLOT_BYTES: usize = 16 * 1024;

    /// Two RAM slots (a static of `init`).
    pub type Slots = RamStore<SLOT_BYTES>;

    /// Model storage: the RAM slots.
    pub type Store = &'static mut Slots;

    /// The front end: the compiled-in sheet.
    pub type Sensor = EmulatedSheet<'static>;

    /// The sheet of `qemu_sheet.rs`.
    pub fn sensor(_: gpioc::Parts, _: TIM2, _: &mut Rcc) -> Sensor {
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
