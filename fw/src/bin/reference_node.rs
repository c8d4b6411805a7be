//! The reference node: an STM32F405 with an IIS3DWB on SPI1 whose FIFO watermark interrupt
//! drains the FIFO through the driver (crate `iis3dwb`) into `Monitor::feed_slice`, logging
//! every event with defmt over RTT.
//!
//! Wiring (STM32F405RG): SPI1 SCK PA5, MISO PA6, MOSI PA7, chip select PA4 (push-pull, idle
//! high); the IIS3DWB's INT1 on PB0 (EXTI0, rising edge). The sensor runs at 26 667 samples/s
//! on the Z axis (the plate's normal) at ±16 g; its FIFO watermark is [`BLOCK`] words, routed
//! to INT1. The EXTI0 handler drains the FIFO in blocks of [`BLOCK`] samples until less than a
//! block is left (INT1 then falls, so the next watermark gives a new rising edge), reports a
//! FIFO overrun to the monitor as a gap (`Gap::AtLeast(1)`: the device does not count lost
//! words) and feeds every block to `Monitor::feed_slice`. The main loop sleeps (`wfi`).
//!
//! The scene is the paper's coal and sandstone gangue on a carbon-steel plate, seen at the
//! IIS3DWB's rate (as `scenes/mems_26k.toml`), with the plate's effective mass and the quiet
//! noise of that scene: on a real plate both are calibration figures of the installation.
//!
//! Build: `cargo build --release --features board --bin reference_node` in `fw/`; run on a
//! board with `probe-rs run --chip STM32F405RGTx <elf>` (fw/README.md). It cannot run in
//! QEMU (no IIS3DWB there); CI builds it and budgets its flash and static RAM.
#![no_std]
#![no_main]

use core::cell::RefCell;

use coalshock::math::DefaultBackend;
use coalshock::scene::DEFAULT_CLASSES;
use coalshock::{
    Event, Material, Monitor, ParticleClass, Range, Scene, SensorChain, Settings, Speed,
};
use coalshock_fw::exit;
use coalshock_node_rt as rt;
use cortex_m_rt::entry;
use critical_section::Mutex;
use embedded_hal_bus::spi::{ExclusiveDevice, NoDelay};
use iis3dwb::{Axis, Config, FullScale, Iis3dwb, SAMPLE_BITS, SAMPLE_RATE_HZ, SampleSource};
use stm32f4xx_hal::gpio::{Edge, ExtiPin, Input, Output, PA4, PB0, Speed as PinSpeed};
use stm32f4xx_hal::pac::{self, interrupt};
use stm32f4xx_hal::prelude::*;
use stm32f4xx_hal::rcc::Config as ClockConfig;
use stm32f4xx_hal::spi::{Mode, Phase, Polarity, Spi};

/// Samples per drained block, and the FIFO watermark in words (half the 512-word FIFO: about
/// 9.6 ms of samples, and as long again before the FIFO overruns).
const BLOCK: usize = 256;

/// Effective mass of the plate under the sensor, in kg (installation calibration).
const PLATE_MASS_KG: f32 = 50.0;
/// RMS noise of the quiet signal, in counts (installation calibration).
const NOISE_RMS_COUNTS: f32 = 4.0;

/// The IIS3DWB on SPI1 with its own chip select.
type Sensor = Iis3dwb<ExclusiveDevice<Spi<pac::SPI1>, PA4<Output>, NoDelay>>;

/// What the watermark interrupt works on.
struct Node {
    sensor: Sensor,
    int1: PB0<Input>,
    monitor: Monitor<DEFAULT_CLASSES, DefaultBackend>,
    buf: [i16; BLOCK],
}

/// The interrupt's state: empty until `main` has set everything up. (An enum with its own
/// zero tag rather than an `Option`, whose `None` would be encoded in a niche of `Node`: an
/// all-zero initial value puts the state in `.bss` instead of 1.5 KB of `.data` in flash.)
// One static, no heap to box into: the size difference is the point.
#[allow(clippy::large_enum_variant)]
#[repr(u8)]
enum Slot {
    Empty,
    Ready(Node),
}

static NODE: Mutex<RefCell<Slot>> = Mutex::new(RefCell::new(Slot::Empty));

impl Node {
    /// Drains the FIFO block by block until less than a block was left.
    fn drain(&mut self) {
        loop {
            let got = match self.sensor.read_samples(&mut self.buf) {
                Ok(got) => got,
                Err(_) => {
                    // The words of this call are lost: a gap of unknown length.
                    defmt::warn!("IIS3DWB read failed");
                    if let Some(e) = self.monitor.gap(1) {
                        log_event(&e);
                    }
                    return;
                }
            };
            if got.gap.is_gap()
                && let Some(e) = self.monitor.gap(got.lost())
            {
                log_event(&e);
            }
            let block = self.buf.get(..got.written).unwrap_or(&[]);
            self.monitor.feed_slice(block, |e| log_event(&e));
            if got.written < BLOCK {
                return;
            }
        }
    }
}

fn log_event(e: &Event) {
    defmt::info!("{}", e);
}

/// The scene: coal and sandstone gangue on carbon steel, seen by the IIS3DWB at ±16 g.
fn scene() -> Result<Scene<DEFAULT_CLASSES, DefaultBackend>, coalshock::Error> {
    let radius = Range::new(0.015, 0.04);
    let speed = Speed::Uniform(Range::new(1.0, 5.0));
    let classes = [
        ParticleClass::new("coal", Material::COAL, radius, speed),
        ParticleClass::new("gangue", Material::SANDSTONE, radius, speed),
    ];
    let chain = SensorChain::from_plate(
        SAMPLE_RATE_HZ,
        PLATE_MASS_KG,
        FullScale::G16.counts_per_m_s2(),
        NOISE_RMS_COUNTS,
        SAMPLE_BITS,
    );
    Scene::new(Material::CARBON_STEEL, &classes, chain, Settings::default())
}

#[entry]
fn main() -> ! {
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        exit(false)
    };
    // The internal 16 MHz oscillator without the PLL: the kernel needs about 1 million
    // instructions per second at 26.7 kS/s, and SPI1 runs at 8 MHz from it.
    let mut rcc = dp.RCC.freeze(ClockConfig::hsi());
    let mut delay = cp.SYST.delay(&rcc.clocks);
    let gpioa = dp.GPIOA.split(&mut rcc);
    let gpiob = dp.GPIOB.split(&mut rcc);

    let mut cs = gpioa.pa4.into_push_pull_output();
    cs.set_high();
    let sck = gpioa.pa5.into_alternate().speed(PinSpeed::VeryHigh);
    let miso = gpioa.pa6.into_alternate().speed(PinSpeed::VeryHigh);
    let mosi = gpioa.pa7.into_alternate().speed(PinSpeed::VeryHigh);
    // SPI mode 3 (the IIS3DWB takes mode 0 or 3), 8 MHz (the device allows 10).
    let mode = Mode {
        polarity: Polarity::IdleHigh,
        phase: Phase::CaptureOnSecondTransition,
    };
    let spi = Spi::new(
        dp.SPI1,
        (Some(sck), Some(miso), Some(mosi)),
        mode,
        8.MHz(),
        &mut rcc,
    );
    // The chip select of the HAL cannot fail (its error type is `Infallible`).
    let Ok(device) = ExclusiveDevice::new_no_delay(spi, cs);

    let Ok(scene) = scene() else {
        defmt::error!("the scene was refused");
        exit(false)
    };
    let monitor = Monitor::new(scene);

    // The boot time of the sensor (10 ms) before the first access.
    delay.delay_ms(10);
    let mut sensor = Iis3dwb::new(
        device,
        Config {
            full_scale: FullScale::G16,
            axis: Axis::Z,
        },
    );
    if let Err(e) = sensor.init(&mut delay) {
        match e {
            iis3dwb::Error::WrongDevice(id) => defmt::error!("WHO_AM_I {=u8:#x}: no IIS3DWB", id),
            _ => defmt::error!("IIS3DWB init failed"),
        }
        exit(false)
    }
    if sensor.set_fifo_watermark(BLOCK as u16).is_err()
        || sensor.route_fifo_watermark_to_int1(true).is_err()
    {
        defmt::error!("IIS3DWB watermark setup failed");
        exit(false)
    }

    let mut syscfg = dp.SYSCFG.constrain(&mut rcc);
    let mut exti = dp.EXTI;
    let mut int1 = gpiob.pb0.into_pull_down_input();
    int1.make_interrupt_source(&mut syscfg);
    int1.trigger_on_edge(&mut exti, Edge::Rising);
    int1.enable_interrupt(&mut exti);
    let irq = int1.interrupt();

    critical_section::with(|cs| {
        NODE.replace(
            cs,
            Slot::Ready(Node {
                sensor,
                int1,
                monitor,
                buf: [0; BLOCK],
            }),
        );
    });
    defmt::info!(
        "reference node: IIS3DWB at {=f32} Hz, watermark {=usize} words",
        SAMPLE_RATE_HZ,
        BLOCK
    );
    rt::unmask(irq);
    // INT1 may already be high (no edge would come): drain once below the watermark.
    critical_section::with(|cs| {
        if let Slot::Ready(node) = &mut *NODE.borrow_ref_mut(cs) {
            node.drain();
        }
    });
    loop {
        cortex_m::asm::wfi();
    }
}

#[interrupt]
fn EXTI0() {
    critical_section::with(|cs| {
        if let Slot::Ready(node) = &mut *NODE.borrow_ref_mut(cs) {
            node.int1.clear_interrupt_pending_bit();
            node.drain();
        }
    });
}
