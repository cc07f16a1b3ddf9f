//! et firmware for the STM32F405 (RTIC 2).
//!
//! Wiring only: the scan engine, framing, command handling, model upload and classification
//! are `et_core` (`Scanner`, `wire`, `device::Device`), tested on the host. This file moves
//! bytes and samples between them and the peripherals:
//!
//! | task | priority | does |
//! | --- | --- | --- |
//! | `usart1` (interrupt) | 3 | received bytes into `rx`; bytes of `tx` out while the transmitter is free |
//! | `commands` | 2 | reassembles packets from `rx` (resynchronising after garbage), hands them to `Device`, sends the reply |
//! | `scan` | 1 | rebuilds the `Scanner` on a new configuration, scans, sends the frame and its events, paces to the frame rate, sends a status event every `STATUS_PERIOD_MS` (and, started on a configuration the front end refused, its fault every 4) |
//!
//! The scan samples without holding the `Device`, so commands are answered during a scan; it
//! locks the device and the transmit queue only to turn the scan into a frame. A frame that
//! does not fit the transmit queue is dropped and counted (`Status::dropped`,
//! `FLAG_DROPPED_BEFORE` on the next one); the scan never waits for the link. Replies and
//! events are small and go out first when the queue is short of room for a frame.
//!
//! The `qemu` feature builds the same application for QEMU's netduinoplus2: internal clock,
//! model slots in RAM, and the sheet of `qemu_sheet.rs` as the front end (docs/design.md).
#![no_std]
#![no_main]

use defmt_rtt as _;
use panic_halt as _;

mod board;
#[cfg(feature = "qemu")]
mod qemu_sheet;
#[cfg(not(feature = "qemu"))]
mod sampler;
#[cfg(not(feature = "qemu"))]
mod store;

#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true, dispatchers = [EXTI0, EXTI1])]
mod app {
    use crate::board;
    use embedded_hal_nb::serial::{Read as _, Write as _};
    use et_core::device::Device;
    use et_core::protocol::K_MAX;
    use et_core::wire::{self, COMMAND_PACKET_MAX, Command, Event, Fault, PACKET_MAX, Uplink};
    use et_core::{Micros, ScanConfig, Scanner};
    use heapless::spsc::{Consumer, Producer, Queue};
    use rtic::Mutex as _;
    use rtic_monotonics::systick::prelude::*;
    use stm32f4xx_hal::pac::{self, USART1};
    use stm32f4xx_hal::rcc::RccExt as _;
    use stm32f4xx_hal::serial::{Config as SerialConfig, Rx, RxListen as _, Serial, Tx};
    use stm32f4xx_hal::serial::{TxISR as _, TxListen as _};
    // The HAL prelude brings its own fugit extension traits; alias them so they do not clash
    // with rtic-monotonics' (the HAL and rtic-monotonics bring two fugit versions).
    use stm32f4xx_hal::prelude::_stm32f4xx_hal_gpio_GpioExt as _;
    use stm32f4xx_hal::time::U32Ext as _;

    systick_monotonic!(Mono, 1_000);

    /// Bytes waiting to go out: two reference frames and their events.
    const TX_QUEUE: usize = 2048;
    /// Bytes received and not yet decoded: a few command packets.
    const RX_QUEUE: usize = 1024;

    #[shared]
    struct Shared {
        device: Device<board::Store>,
        tx: Producer<'static, u8>,
    }

    #[local]
    struct Local {
        serial_tx: Tx<USART1>,
        serial_rx: Rx<USART1>,
        tx_out: Consumer<'static, u8>,
        rx_in: Producer<'static, u8>,
        rx_out: Consumer<'static, u8>,
        sensor: board::Sensor,
    }

    #[init(local = [
        txq: Queue<u8, TX_QUEUE> = Queue::new(),
        rxq: Queue<u8, RX_QUEUE> = Queue::new(),
        #[cfg(feature = "qemu")]
        slots: board::Slots = board::Slots::new(),
        #[cfg(not(feature = "qemu"))]
        burst: [u16; board::BURST_MAX] = [0; board::BURST_MAX],
    ])]
    fn init(cx: init::Context) -> (Shared, Local) {
        let dp = cx.device;
        let mut rcc = dp.RCC.freeze(board::clocks());
        Mono::start(cx.core.SYST, board::SYSTICK_HZ);

        let gpioa = dp.GPIOA.split(&mut rcc);
        let gpiob = dp.GPIOB.split(&mut rcc);
        let gpioc = dp.GPIOC.split(&mut rcc);
        let serial: Serial<USART1> = Serial::new(
            dp.USART1,
            (gpioa.pa9, gpioa.pa10),
            SerialConfig::default().baudrate(board::BAUD.bps()),
            &mut rcc,
        )
        .unwrap_or_else(|_| panic!("USART1 set-up"));
        let (serial_tx, mut serial_rx) = serial.split();
        serial_rx.listen();

        #[cfg(feature = "qemu")]
        let sensor = {
            let _ = (gpiob, gpioc);
            board::sensor()
        };
        #[cfg(not(feature = "qemu"))]
        let sensor = {
            let analog = [
                gpioa.pa0.into_analog().erase(),
                gpioa.pa1.into_analog().erase(),
                gpioa.pa2.into_analog().erase(),
                gpioa.pa3.into_analog().erase(),
                gpioa.pa4.into_analog().erase(),
                gpioa.pa5.into_analog().erase(),
                gpioa.pa6.into_analog().erase(),
                gpioa.pa7.into_analog().erase(),
                gpiob.pb0.into_analog().erase(),
                gpiob.pb1.into_analog().erase(),
                gpioc.pc0.into_analog().erase(),
                gpioc.pc1.into_analog().erase(),
                gpioc.pc2.into_analog().erase(),
                gpioc.pc3.into_analog().erase(),
                gpioc.pc4.into_analog().erase(),
                gpioc.pc5.into_analog().erase(),
            ];
            let mux = [
                gpiob.pb4.into_push_pull_output().erase(),
                gpiob.pb5.into_push_pull_output().erase(),
                gpiob.pb6.into_push_pull_output().erase(),
                gpiob.pb7.into_push_pull_output().erase(),
                gpiob.pb8.into_push_pull_output().erase(),
                gpiob.pb9.into_push_pull_output().erase(),
                gpiob.pb12.into_push_pull_output().erase(),
                gpiob.pb13.into_push_pull_output().erase(),
                gpiob.pb14.into_push_pull_output().erase(),
                gpiob.pb15.into_push_pull_output().erase(),
            ];
            board::sensor(
                board::SensorParts {
                    analog,
                    mux,
                    adc: dp.ADC1,
                    common: dp.ADC_COMMON,
                    dma: dp.DMA2,
                    trigger: dp.TIM2,
                    delay: dp.TIM5,
                },
                &mut rcc,
                cx.local.burst,
            )
        };
        #[cfg(feature = "qemu")]
        let store = cx.local.slots;
        #[cfg(not(feature = "qemu"))]
        let store = board::store(dp.FLASH);
        let device = Device::new(store, board::DEFAULT_CONFIG)
            .unwrap_or_else(|_| panic!("the default configuration is valid"));

        let (tx, tx_out) = cx.local.txq.split();
        let (rx_in, rx_out) = cx.local.rxq.split();
        // A model committed before the restart scans and classifies again.
        defmt::info!(
            "et firmware {=str} up: {} at {=u32} baud{=str}",
            env!("CARGO_PKG_VERSION"),
            *device.config(),
            board::BAUD,
            if device.model().is_some() {
                ", its stored model restored"
            } else {
                ""
            }
        );
        scan::spawn().ok();
        commands::spawn().ok();
        (
            Shared { device, tx },
            Local {
                serial_tx,
                serial_rx,
                tx_out,
                rx_in,
                rx_out,
                sensor,
            },
        )
    }

    /// Encodes `message` and queues it whole, or not at all (returns false when the queue is
    /// too full or the message does not encode).
    fn send(tx: &mut Producer<'static, u8>, message: &Uplink, buf: &mut [u8]) -> bool {
        let Ok(n) = wire::encode(message, buf) else {
            return false;
        };
        if tx.capacity() - tx.len() < n {
            return false;
        }
        for &b in &buf[..n] {
            // Room was checked above; only this task produces.
            let _ = tx.enqueue(b);
        }
        rtic::pend(pac::Interrupt::USART1);
        true
    }

    fn uptime() -> Micros {
        Micros(Mono::now().duration_since_epoch().as_micros())
    }

    /// The serial port: received bytes into `rx_in`, queued bytes out while TXE is set.
    #[task(binds = USART1, priority = 3, local = [serial_tx, serial_rx, tx_out, rx_in])]
    fn usart1(cx: usart1::Context) {
        let usart1::LocalResources {
            serial_tx,
            serial_rx,
            tx_out,
            rx_in,
            ..
        } = cx.local;
        loop {
            match serial_rx.read() {
                // A full queue loses the byte: the packet it belonged to fails its CRC and is
                // refused, the host resends.
                Ok(byte) => {
                    let _ = rx_in.enqueue(byte);
                }
                Err(nb::Error::WouldBlock) => break,
                // Overrun, framing or noise: the flags are cleared by the read; the damaged
                // packet is refused by its CRC.
                Err(nb::Error::Other(_)) => {}
            }
        }
        while serial_tx.is_tx_empty() {
            let Some(byte) = tx_out.dequeue() else { break };
            let _ = serial_tx.write(byte);
        }
        if tx_out.is_empty() {
            serial_tx.unlisten();
        } else {
            serial_tx.listen();
        }
    }

    /// Command packets in, replies out (docs/design.md: a bad command is refused, the scan goes on).
    #[task(priority = 2, shared = [device, tx], local = [
        rx_out,
        packets: wire::Accumulator<COMMAND_PACKET_MAX> = wire::Accumulator::new(),
        buf: [u8; 64] = [0; 64],
    ])]
    async fn commands(cx: commands::Context) {
        let commands::LocalResources {
            rx_out,
            packets,
            buf,
            ..
        } = cx.local;
        let mut shared = cx.shared;
        loop {
            (&mut shared.device, &mut shared.tx).lock(|device, tx| {
                while let Some(byte) = rx_out.dequeue() {
                    if let Some(decoded) = packets.feed::<Command>(byte)
                        && let Some(reply) = device.handle_decoded(decoded)
                    {
                        match &reply {
                            Event::Refused { command, reason } => {
                                defmt::warn!("refused {}: {}", command, reason);
                            }
                            Event::Ack { command } => defmt::debug!("done: {}", command),
                            _ => {}
                        }
                        send(tx, &Uplink::Event(reply), buf);
                    }
                }
            });
            Mono::delay(1.millis()).await;
        }
    }

    /// Scans continuously while started, at the configured frame rate. The scan itself runs
    /// without holding the device, so commands are handled while it samples.
    #[task(priority = 1, shared = [device, tx], local = [
        sensor,
        burst: [u16; et_core::config::SAMPLES_PER_STEP_MAX as usize] =
            [0; et_core::config::SAMPLES_PER_STEP_MAX as usize],
        v_m: [f32; K_MAX] = [0.0; K_MAX],
        packet: [u8; PACKET_MAX] = [0; PACKET_MAX],
    ])]
    async fn scan(cx: scan::Context) {
        let scan::LocalResources {
            sensor,
            burst,
            v_m,
            packet,
            ..
        } = cx.local;
        let mut shared = cx.shared;
        let mut scanner: Option<Scanner> = None;
        let mut last_status = Mono::now();
        let mut last_refused = Mono::now();
        loop {
            let start = Mono::now();
            let (reconfigure, scanning, seq) = shared
                .device
                .lock(|d| (d.take_reconfigure(), d.scanning(), d.next_seq()));
            if let Some(config) = reconfigure {
                scanner = Scanner::new(config, sensor).ok();
                if scanner.is_none() {
                    defmt::error!("the front end refused {}", config);
                    fault(&mut shared, seq, packet);
                    // Back to the last scan made (picked up on the next pass), so the board
                    // is not left on one it cannot make until reset.
                    shared.device.lock(|d| d.front_end_refused());
                } else {
                    defmt::info!("scanning with {}", config);
                }
            }
            let mut period_ms = 10;
            if let (true, Some(scanner)) = (scanning, scanner.as_ref()) {
                period_ms = frame_period_ms(scanner.config());
                let k = scanner.frame_len();
                board::before_scan(sensor, seq);
                let timestamp = uptime();
                match scanner.scan(sensor, burst, &mut v_m[..k]) {
                    Ok(report) => (&mut shared.device, &mut shared.tx).lock(|device, tx| {
                        let config = scanner.config();
                        if let Ok(out) = device.frame(config, timestamp, &report, &v_m[..k], 0) {
                            if !send(tx, &Uplink::Frame(out.frame), packet) {
                                defmt::debug!("link busy: frame dropped");
                                device.dropped();
                            }
                            for event in out.events.iter() {
                                if let Event::Fault(f) = event {
                                    defmt::warn!("{}", f);
                                }
                            }
                            for event in out.events {
                                send(tx, &Uplink::Event(event), packet);
                            }
                        }
                    }),
                    Err(e) => {
                        defmt::error!("scan {=u32} failed: {}", seq, defmt::Debug2Format(&e));
                        fault(&mut shared, seq, packet);
                    }
                }
            } else if scanning
                && (Mono::now() - last_refused).as_millis() >= 4 * board::STATUS_PERIOD_MS
            {
                // Started on a configuration the front end refused: said again every 2 s, so
                // a host that connects later hears why no frames come (it heard nothing).
                last_refused = Mono::now();
                fault(&mut shared, seq, packet);
            }
            let now = Mono::now();
            if (now - last_status).as_millis() >= board::STATUS_PERIOD_MS {
                last_status = now;
                (&mut shared.device, &mut shared.tx).lock(|device, tx| {
                    let status = device.status(uptime());
                    send(tx, &Uplink::Event(Event::Status(status)), packet);
                });
            }
            Mono::delay_until(start + period_ms.millis()).await;
        }
    }

    /// Reports that the front end failed at scan `seq`.
    fn fault(shared: &mut scan::SharedResources<'_>, seq: u32, packet: &mut [u8]) {
        let event = Uplink::Event(Event::Fault(Fault::Frontend { seq }));
        shared.tx.lock(|tx| send(tx, &event, packet));
    }

    /// One frame's duration at `config`'s rate in ms, at least 1 (the tick).
    fn frame_period_ms(config: &ScanConfig) -> u32 {
        ((1e3 / config.frame_rate_hz().max(1e-3)) as u32).max(1)
    }

    /// Sleeps between interrupts (the default busy loop would burn a host core under QEMU).
    #[idle]
    fn idle(_: idle::Context) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }
}
