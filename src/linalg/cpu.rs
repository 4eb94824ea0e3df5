//! CPU-feature tokens: a value of [`Avx2`] (or [`Avx512`]) exists only once the running CPU
//! has been seen to have the feature, so a function that takes one may use its instructions;
//! the type carries the run-time check to the code that relies on it.

/// Proof that the CPU has AVX2 (made only by [`Avx2::detect`]).
#[derive(Clone, Copy, Debug)]
pub struct Avx2 {
    _checked: (),
}

impl Avx2 {
    /// `Some` when the CPU has AVX2 (detected once, then cached by the standard library);
    /// always `None` off x86-64.
    #[inline]
    pub fn detect() -> Option<Avx2> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            return Some(Avx2 { _checked: () });
        }
        None
    }
}

/// Proof that the CPU has AVX-512F (made only by [`Avx512::detect`]).
#[derive(Clone, Copy, Debug)]
pub struct Avx512 {
    _checked: (),
}

impl Avx512 {
    /// `Some` when the CPU has AVX-512F (e.g. AMD Zen 4, Intel Xeon); always `None` off x86-64.
    #[inline]
    pub fn detect() -> Option<Avx512> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx512f") {
            return Some(Avx512 { _checked: () });
        }
        None
    }
}
