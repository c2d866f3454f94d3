//! A memory hint shared by the stages whose loops know their next reads ahead (the horizon sweep, crystal growth).

/// Hints the processor to load the cache line holding `x`. It has no effect on any result: only on when memory is
/// read. A no-op on targets other than x86-64.
#[inline(always)]
pub fn prefetch<T>(x: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        // SAFETY: a prefetch has no architectural effect, and the address comes from a live reference.
        unsafe { _mm_prefetch::<_MM_HINT_T0>((x as *const T).cast()) };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = x;
}
