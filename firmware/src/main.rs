//! et firmware for the STM32F405 (RTIC 2).
//!
//! Wiring only: protocol tables, mux control words, framing and (later) scanning and
//! classification all come from `et-core`, where they are tested on the host. Today the image
//! brings the board up, parks both multiplexers (no current flows), blinks the status LED and
//! sends an `Event::Status` packet over USART2 every `STATUS_PERIOD_MS`.
#![no_std]
#![no_main]

use panic_halt as _;

mod board;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [EXTI0])]
mod app {
    use crate::board;
    use embedded_io::Write as _;
    use et_core::Micros;
    use et_core::frontend::MuxLines;
    use et_core::wire::{self, Event, Status, Uplink};
    use rtic_monotonics::systick::prelude::*;
    use stm32f4xx_hal::gpio::{Output, PA5};
    use stm32f4xx_hal::pac::{TIM2, USART2};
    use stm32f4xx_hal::rcc::Config;
    use stm32f4xx_hal::serial::Tx;
    use stm32f4xx_hal::timer::Delay;
    // The HAL prelude brings its own fugit extension traits; alias them so they do not clash
    // with rtic-monotonics' (DESIGN.md, "Known API frictions").
    use stm32f4xx_hal::prelude::{_fugit_RateExtU32 as _, _stm32f4xx_hal_gpio_GpioExt as _};
    use stm32f4xx_hal::prelude::{
        _stm32f4xx_hal_serial_SerialExt as _, _stm32f4xx_hal_timer_TimerExt as _,
    };
    use stm32f4xx_hal::rcc::RccExt as _;
    use stm32f4xx_hal::time::U32Ext as _;

    systick_monotonic!(Mono, 1_000);

    #[shared]
    struct Shared {}

    #[local]
    struct Local {
        led: PA5<Output>,
        tx: Tx<USART2>,
        mux: MuxLines<board::MuxPin, Delay<TIM2, 1_000_000>>,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut rcc = dp.RCC.freeze(Config::hsi().sysclk(board::SYSCLK_HZ.Hz()));
        Mono::start(cx.core.SYST, board::SYSCLK_HZ);

        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let led = gpioa.pa5.into_push_pull_output();
        let tx = dp
            .USART2
            .tx(gpioa.pa2, board::BAUD.bps(), &mut rcc)
            .unwrap_or_else(|_| panic!());

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
        let delay = dp.TIM2.delay_us(&mut rcc);
        // GPIO writes cannot fail on this chip (the error type is Infallible).
        let Ok(mux) = MuxLines::new(lines, delay, board::MUX_SETTLE_NS);

        heartbeat::spawn().ok();
        (Shared {}, Local { led, tx, mux })
    }

    /// Blinks and reports status; the scan task replaces the idle mux with real scanning.
    #[task(priority = 1, local = [led, tx, mux, buf: [u8; 64] = [0; 64]])]
    async fn heartbeat(cx: heartbeat::Context) {
        let heartbeat::LocalResources {
            led, tx, mux, buf, ..
        } = cx.local;
        let Ok(()) = mux.off();
        let start = Mono::now();
        loop {
            led.toggle();
            let uptime = Micros((Mono::now() - start).as_micros());
            let status = Uplink::Event(Event::Status(Status {
                uptime,
                ..Status::default()
            }));
            if let Ok(n) = wire::encode(&status, buf) {
                // A failed write loses one status packet; the next one follows.
                let _ = tx.write_all(&buf[..n]);
            }
            Mono::delay(board::STATUS_PERIOD_MS.millis()).await;
        }
    }

    /// Sleeps between interrupts (the default busy loop would burn a host core under QEMU).
    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }
}
