//! A cache prefetch hint for the random gathers of the work-only mode (feature entries by
//! Gaussian id in depth order). A hint only: it never changes a result, and it is a no-op on
//! targets without one.

/// Asks the CPU to bring the cache lines of `*p` (at most two lines from its start) closer.
#[inline(always)]
pub fn prefetch<T>(p: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use core::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        let a = p as *const T as *const i8;
        // SAFETY: SSE is part of the x86_64 baseline, and a prefetch never faults nor
        // dereferences (the second address may lie past the value).
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(a);
            if std::mem::size_of::<T>() > 64 - (a as usize % 64) {
                _mm_prefetch::<_MM_HINT_T0>(a.wrapping_add(64));
            }
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}
