//! The rank-1 update of [`super::BandLu::factor`] with AVX2 (or AVX-512) vectors where the CPU
//! has them.
use super::Sweep;
use crate::linalg::cpu::Avx2;
#[cfg(target_arch = "x86_64")]
use crate::linalg::cpu::Avx512;

/// Most rows below a pivot that [`update`] takes (`KL`): the multipliers are held in
/// `MAX_ROWS / 4` AVX2 or `MAX_ROWS / 8` AVX-512 registers. Block size 12, the largest of the
/// solvers, has at most 23 rows below a pivot.
pub const MAX_ROWS: usize = 24;
/// AVX2 registers (4 lanes) that hold the multipliers of [`kernel`].
const REGS_AVX2: usize = MAX_ROWS / 4;
/// AVX-512 registers (8 lanes) that hold the full lanes of the multipliers of [`kernel512`].
const REGS_AVX512: usize = MAX_ROWS / 8;
const _: () = assert!(REGS_AVX2 * 4 == MAX_ROWS && REGS_AVX512 * 8 == MAX_ROWS, "MAX_ROWS fills whole registers");

/// [`super::update`] four rows at a time ([`kernel`]), or eight with AVX-512 (e.g. AMD Zen 4,
/// Intel Xeon), the last `KL mod 8` under a mask ([`kernel512`]): the `KL` multipliers stay in
/// registers for all `span` columns, and each row is `d − l · u` with one rounding per
/// operation, as there. `KL ≤ MAX_ROWS`, checked at compile time.
#[inline]
pub fn update<const KL: usize>(cpu: Avx2, head: &[f64], tail: &mut [f64], at: Sweep) {
    const { assert!(KL <= MAX_ROWS, "more rows below the pivot than the kernels hold in registers") };
    #[cfg(target_arch = "x86_64")]
    if Avx512::detect().is_some() {
        // SAFETY: an `Avx512` token was just made, so the CPU has AVX-512F; KL ≤ MAX_ROWS above.
        unsafe { kernel512::<KL>(head, tail, at) }
    } else {
        let _: Avx2 = cpu;
        // SAFETY: the `Avx2` token `cpu` exists, so the CPU has AVX2; KL ≤ MAX_ROWS above.
        unsafe { kernel::<KL>(head, tail, at) }
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _: Avx2 = cpu;
        super::update::<KL>(head, tail, at)
    }
}

/// [`kernel`] with 8-wide vectors; masked lanes are neither read nor written.
///
/// # Safety
/// The CPU must have AVX-512F (an [`Avx512`] token was made), and `KL ≤ MAX_ROWS` (asserted
/// by [`update`]; beyond it rows would be left out). The slice bounds are checked.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn kernel512<const KL: usize>(head: &[f64], tail: &mut [f64], at: Sweep) {
    let Sweep { col, kv, ld, span } = at;
    use std::arch::x86_64::{
        _mm512_loadu_pd, _mm512_mask_storeu_pd, _mm512_maskz_loadu_pd, _mm512_mul_pd, _mm512_set1_pd, _mm512_storeu_pd,
        _mm512_sub_pd,
    };
    let l: &[f64; KL] = head[col + 1..col + 1 + KL].try_into().expect("KL multipliers");
    let (full, rest) = (KL / 8, KL % 8);
    let mask = ((1u32 << rest) - 1) as u8;
    // SAFETY (loads and stores): full lanes 8v..8v + 8 ≤ KL, masked lanes < KL, of `l` and
    // of the KL-long `dst`.
    let lv: [_; REGS_AVX512] =
        std::array::from_fn(|v| if v < full { _mm512_loadu_pd(l.as_ptr().add(8 * v)) } else { _mm512_set1_pd(0.0) });
    let lr = _mm512_maskz_loadu_pd(mask, l.as_ptr().add(8 * full));
    for (t, column) in tail.chunks_exact_mut(ld).take(span).enumerate() {
        let base = kv - 1 - t;
        let ujc = column[base];
        if ujc != 0.0 {
            let dst: &mut [f64; KL] = (&mut column[base + 1..base + 1 + KL]).try_into().expect("KL rows");
            let u = _mm512_set1_pd(ujc);
            for (v, lv) in lv.iter().enumerate().take(full) {
                let p = dst.as_mut_ptr().add(8 * v);
                _mm512_storeu_pd(p, _mm512_sub_pd(_mm512_loadu_pd(p), _mm512_mul_pd(*lv, u)));
            }
            if rest != 0 {
                let p = dst.as_mut_ptr().add(8 * full);
                let d = _mm512_maskz_loadu_pd(mask, p);
                _mm512_mask_storeu_pd(p, mask, _mm512_sub_pd(d, _mm512_mul_pd(lr, u)));
            }
        }
    }
}

/// [`super::update`] with 4-wide vectors, the last `KL mod 4` rows one at a time.
///
/// # Safety
/// The CPU must have AVX2 (an [`Avx2`] token was made), and `KL ≤ MAX_ROWS` (asserted by
/// [`update`]; beyond it rows would be left out). The slice bounds are checked.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn kernel<const KL: usize>(head: &[f64], tail: &mut [f64], at: Sweep) {
    let Sweep { col, kv, ld, span } = at;
    use std::arch::x86_64::{_mm256_loadu_pd, _mm256_mul_pd, _mm256_set1_pd, _mm256_storeu_pd, _mm256_sub_pd};
    let l: &[f64; KL] = head[col + 1..col + 1 + KL].try_into().expect("KL multipliers");
    let full = KL / 4;
    // SAFETY (loads and stores): lanes 4v..4v + 4 ≤ KL of `l` and of the KL-long `dst`.
    let lv: [_; REGS_AVX2] =
        std::array::from_fn(|v| if v < full { _mm256_loadu_pd(l.as_ptr().add(4 * v)) } else { _mm256_set1_pd(0.0) });
    for (t, column) in tail.chunks_exact_mut(ld).take(span).enumerate() {
        let base = kv - 1 - t;
        let ujc = column[base];
        if ujc != 0.0 {
            let dst: &mut [f64; KL] = (&mut column[base + 1..base + 1 + KL]).try_into().expect("KL rows");
            let u = _mm256_set1_pd(ujc);
            for (v, lv) in lv.iter().enumerate().take(full) {
                let p = dst.as_mut_ptr().add(4 * v);
                _mm256_storeu_pd(p, _mm256_sub_pd(_mm256_loadu_pd(p), _mm256_mul_pd(*lv, u)));
            }
            for r in 4 * full..KL {
                dst[r] -= l[r] * ujc;
            }
        }
    }
}
