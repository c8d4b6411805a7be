//! Runtime support for the coalshock firmware (`coalshock-fw`: the node binaries).
//!
//! The kernel and the firmware forbid `unsafe`; the few things a bare-metal node
//! cannot do without it live here, each small and documented:
//!
//! - a `HardFault` handler that ends the emulator with a failure status instead of spinning
//!   (the default handler loops forever, which hangs QEMU);
//! - repainting the free stack with `PAINT` below the current stack pointer;
//! - scanning the painted stack for the lowest word that was overwritten (high-water mark);
//! - unmasking an interrupt in the NVIC (the reference node's FIFO watermark interrupt).
//!
//! With cortex-m-rt's `paint-stack` feature (enabled here) the whole stack region is painted
//! at reset, so `lowest_touched` right before exit gives the peak use of the whole program.
//!
//! On the host this crate is empty.
#![no_std]

#[cfg(target_os = "none")]
mod node {
    use cortex_m_rt::{ExceptionFrame, exception};
    use cortex_m_semihosting::debug;

    /// The paint pattern (cortex-m-rt's `STACK_PAINT_VALUE`).
    pub const PAINT: u32 = 0xCCCC_CCCC;

    unsafe extern "C" {
        /// Lowest address of the stack region (cortex-m-rt's `link.x`: end of `.uninit`).
        static _stack_end: u32;
        /// Highest address of the stack region (initial stack pointer).
        static _stack_start: u32;
    }

    /// `[lowest, highest)` address of the stack region.
    pub fn stack_region() -> (usize, usize) {
        // Only the addresses of the linker symbols are taken, never their contents.
        let lo = &raw const _stack_end as usize;
        let hi = &raw const _stack_start as usize;
        (lo, hi)
    }

    /// The current main stack pointer.
    #[inline(always)]
    pub fn stack_pointer() -> usize {
        cortex_m::register::msp::read() as usize
    }

    /// Paints the free stack, from the bottom of the region up to 64 bytes below this
    /// function's own stack pointer, with [`PAINT`]. Returns the caller-side stack pointer
    /// estimate (this function's stack pointer), from which [`used_since`] measures.
    #[inline(never)]
    pub fn paint() -> usize {
        let sp = stack_pointer();
        let (lo, _) = stack_region();
        let end = sp.saturating_sub(64) & !3;
        let mut p = lo;
        while p < end {
            // SAFETY: `p` is word aligned and lies in the stack region below the live stack
            // (64 bytes under the current stack pointer, and nothing else runs: no interrupts
            // are enabled), so no live data is overwritten.
            unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
            p += 4;
        }
        sp
    }

    /// Lowest stack address whose word is no longer [`PAINT`] (the stack's high-water mark
    /// since the last paint). Scans upward from the bottom of the region.
    #[inline(never)]
    pub fn lowest_touched() -> usize {
        let (lo, hi) = stack_region();
        let mut p = lo;
        while p < hi {
            // SAFETY: `p` is word aligned and inside the RAM of the stack region.
            let w = unsafe { core::ptr::read_volatile(p as *const u32) };
            if w != PAINT {
                return p;
            }
            p += 4;
        }
        hi
    }

    /// Bytes of stack used below `base` (from [`paint`]) since that paint.
    pub fn used_since(base: usize) -> usize {
        base.saturating_sub(lowest_touched())
    }

    /// Bytes of stack used since reset (the whole region was painted at reset).
    pub fn used_total() -> usize {
        stack_region().1.saturating_sub(lowest_touched())
    }

    /// Unmasks interrupt `irq` in the NVIC (the reference node's FIFO watermark line).
    pub fn unmask<I: cortex_m::interrupt::InterruptNumber>(irq: I) {
        // SAFETY: unmasking can break a critical section that relies on the mask; the firmware
        // calls this once, after the handler's shared state is in place, and shares that state
        // only through `critical_section::Mutex`, which masks interrupts globally, not per line.
        unsafe { cortex_m::peripheral::NVIC::unmask(irq) };
    }

    #[exception]
    unsafe fn HardFault(_frame: &ExceptionFrame) -> ! {
        // No logging here: the fault may have come from the logger itself.
        debug::exit(debug::EXIT_FAILURE);
        #[allow(clippy::empty_loop)]
        loop {}
    }
}

#[cfg(target_os = "none")]
pub use node::{
    PAINT, lowest_touched, paint, stack_pointer, stack_region, unmask, used_since, used_total,
};
