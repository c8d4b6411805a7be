//! The front-end check on the node: the IIS3DWB driver (crate `iis3dwb`) over a fake SPI
//! sensor serving the replayed stream into `Monitor::feed_slice`, compared event by event with
//! a plain replay (`coalshock_replay::front_end` has the fake and the check; its docs define
//! the output lines). Exit status 0 when every event and counter agrees.
//!
//! Run: `cargo run --release --bin front_end` in `fw/` (QEMU, runner `fw/run.sh`);
//! `cargo run -p host-sim --example front_end` prints the same lines on the host.
#![no_std]
#![no_main]
use coalshock_fw::{exit, log_counters};
use coalshock_node_rt as _;
use coalshock_replay::CounterLine;
use coalshock_replay::front_end::run;
use cortex_m_rt::entry;

#[entry]
fn main() -> ! {
    let o = match run() {
        Ok(o) => o,
        Err(e) => {
            defmt::println!("error {=str}", e);
            exit(false)
        }
    };
    defmt::println!(
        "front_end reads={=u32} spi={=u32} words={=u32} overruns={=u32}",
        o.reads,
        o.transactions,
        o.words,
        o.overruns
    );
    defmt::println!(
        "front_end events={=u32} same={=u32} differ={=u32} index_shift={=u64}",
        o.events,
        o.same,
        o.differ,
        o.shift
    );
    defmt::println!("front_end counters_equal={=u32}", o.counters_equal as u32);
    log_counters("", &CounterLine::new(&o.front));
    exit(o.ok())
}
