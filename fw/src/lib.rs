//! What the firmware binaries share: the panic handler, the exit through semihosting, the
//! global defmt logger (semihosting in QEMU; RTT on a board with feature `rtt`) and the
//! `counters` line in defmt.
#![no_std]

use coalshock_replay::CounterLine;
use cortex_m_semihosting::debug;

#[cfg(not(feature = "rtt"))]
use defmt_semihosting as _;

#[cfg(feature = "rtt")]
use defmt_rtt as _;

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // No formatting: the release build must not contain any panic path at all (fw/measure.sh
    // checks), and a panic message would pull in core::fmt.
    exit(false)
}

/// Ends the run through semihosting with success or failure (QEMU exits with status 0 or 1;
/// `probe-rs run` on a board ends the same way).
pub fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Logs the `counters` line through defmt (compared with the host's by `fw/ci.sh`), after
/// `prefix` (`""`, or `"chain "` for the chain stream).
pub fn log_counters(prefix: &str, l: &CounterLine) {
    defmt::println!(
        "{=str}counters samples={=u64} pulses={=u32} ambiguous={=u32} out={=u32} rejected={=u32} stuck={=u32} gaps={=u32} lost={=u64} balanced={=u32}",
        prefix,
        l.samples,
        l.pulses,
        l.ambiguous,
        l.out,
        l.rejected,
        l.stuck,
        l.gaps,
        l.lost,
        l.balanced
    );
}
