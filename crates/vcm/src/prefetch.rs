//! A hint to start loading data that will be needed soon, for lookups whose addresses are
//! known a while before their data is used (the light vertices a camera vertex connects to,
//! the film's sums a sample is added to).

/// Bytes of a cache line.
const LINE: usize = 64;

/// Asks the CPU to start loading the cache line holding the start of `value` into all cache
/// levels; does nothing on targets without a prefetch instruction. Never faults and changes
/// no result.
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    prefetch_address((value as *const T).cast());
}

/// Asks the CPU to start loading every cache line `value` spans (see [`prefetch`]).
#[inline(always)]
pub(crate) fn prefetch_all<T>(value: &T) {
    let start = (value as *const T).cast::<u8>();
    let last = start.wrapping_add(size_of::<T>().saturating_sub(1));
    // Each line from the first byte's on, then the last byte's (which the steps of a line's
    // size can pass over).
    for offset in (0..size_of::<T>()).step_by(LINE) {
        prefetch_address(start.wrapping_add(offset));
    }
    prefetch_address(last);
}

/// The prefetch instruction for the line holding `address`.
#[inline(always)]
fn prefetch_address(address: *const u8) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint: it reads nothing the program sees and cannot fault,
    // whatever the address. SSE is part of the x86_64 baseline.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>(address.cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = address;
}
