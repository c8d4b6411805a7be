//! The front-end check on the host: the same code as the node's `front_end` binary
//! (`coalshock_replay::front_end`: the IIS3DWB driver over a fake SPI sensor serving the
//! replayed stream into `Monitor::feed_slice`, compared with a plain replay), printing the same
//! lines; `fw/ci.sh` requires them to equal the node's.
//!
//! Run: `cargo run -p host-sim --example front_end`.

use coalshock_replay::CounterLine;
use coalshock_replay::front_end::run;

fn main() {
    let o = run().unwrap_or_else(|e| {
        eprintln!("error {e}");
        std::process::exit(1)
    });
    println!(
        "front_end reads={} spi={} words={} overruns={}",
        o.reads, o.transactions, o.words, o.overruns
    );
    println!(
        "front_end events={} same={} differ={} index_shift={}",
        o.events, o.same, o.differ, o.shift
    );
    println!("front_end counters_equal={}", o.counters_equal as u32);
    let l = CounterLine::new(&o.front);
    println!(
        "counters samples={} pulses={} ambiguous={} out={} rejected={} stuck={} gaps={} lost={} balanced={}",
        l.samples, l.pulses, l.ambiguous, l.out, l.rejected, l.stuck, l.gaps, l.lost, l.balanced
    );
    std::process::exit(if o.ok() { 0 } else { 1 });
}
