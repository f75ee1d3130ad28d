//! A hint to start loading data that will be needed soon, for lookups whose addresses are
//! known a while before their data is used (the light vertices a camera vertex connects to).

/// Asks the CPU to start loading the cache line holding the start of `value` into all cache
/// levels; does nothing on targets without a prefetch instruction. Never faults and changes
/// no result.
#[inline(always)]
pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is only a hint: it reads nothing the program sees and cannot fault.
    // SSE is part of the x86_64 baseline.
    unsafe {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        _mm_prefetch::<_MM_HINT_T0>((value as *const T).cast::<i8>());
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
