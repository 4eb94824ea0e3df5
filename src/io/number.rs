//! Numbers as text for the output tables and ParaView files: [`push_exp`] writes exactly what
//! `format!("{v:.N$e}")` writes (the same bytes), from the shortest round-trip digits of the
//! `ryu` crate instead of the standard library's exact-precision algorithm, about four times
//! faster; a clip writes some ten million numbers.
//!
//! Why the shortest digits give the correctly rounded ones: let `S` be the shortest decimal that
//! reads back as `v` (what ryu prints) and `P = N + 1` the significant digits wanted. If `S` has
//! at most `P` digits, `v` rounds to `S` (v and S differ by under half an ulp, far less than half
//! a unit in the P-th digit). Otherwise a rounding midpoint `M` (P + 1 digits ending in 5) lying
//! strictly between `v` and `S` would read back as `v` too and be shorter than `S`: impossible.
//! So rounding `S` to `P` digits rounds `v` the same way, except when `S` is itself a midpoint
//! (P + 1 digits, the last a 5), where `v` may lie on either side: that case, zero, subnormals
//! (whose ulp is not small), NaN, the infinities and more than 15 significant digits go to the
//! standard library.
use std::fmt::Write as _;

/// Most decimals handled here (15 significant digits): half a unit in the 15th digit is above
/// half an ulp of any double, which the argument above needs; more go to the standard library.
const MAX_DECIMALS: usize = 14;

/// Append `v` formatted as `{v:.decimals$e}` (e.g. `1.2500000000e-5` for 10 decimals).
pub fn push_exp(out: &mut String, v: f64, decimals: usize) {
    if !v.is_normal() || decimals > MAX_DECIMALS {
        let _ = write!(out, "{v:.decimals$e}");
        return;
    }
    let mut buf = ryu::Buffer::new();
    let text = buf.format_finite(v.abs());
    let (mantissa, exp) = match text.find('e') {
        Some(i) => (&text[..i], text[i + 1..].parse::<i32>().expect("ryu exponent")),
        None => (text, 0),
    };
    // significant digits (no leading or trailing zeros) and the power of ten of the last one
    let mut digits = [0u8; 24];
    let mut nd = 0;
    let mut frac = 0i32;
    let mut point = false;
    for &c in mantissa.as_bytes() {
        if c == b'.' {
            point = true;
            continue;
        }
        if point {
            frac += 1;
        }
        if nd == 0 && c == b'0' {
            continue;
        }
        digits[nd] = c - b'0';
        nd += 1;
    }
    let mut last = exp - frac;
    while nd > 1 && digits[nd - 1] == 0 {
        nd -= 1;
        last += 1;
    }
    let mut e10 = last + nd as i32 - 1;
    let p = decimals + 1;
    if nd > p {
        let first = digits[p];
        if first == 5 && nd == p + 1 {
            let _ = write!(out, "{v:.decimals$e}");
            return;
        }
        if first >= 5 {
            // round up, carrying
            let mut k = p;
            loop {
                if k == 0 {
                    digits[0] = 1;
                    digits[1..p].iter_mut().for_each(|d| *d = 0);
                    e10 += 1;
                    break;
                }
                k -= 1;
                if digits[k] == 9 {
                    digits[k] = 0;
                } else {
                    digits[k] += 1;
                    break;
                }
            }
        }
    } else {
        digits[nd..p].iter_mut().for_each(|d| *d = 0);
    }
    if v < 0.0 {
        out.push('-');
    }
    out.push((b'0' + digits[0]) as char);
    if p > 1 {
        out.push('.');
        out.extend(digits[1..p].iter().map(|&d| (b'0' + d) as char));
    }
    let _ = write!(out, "e{e10}");
}

/// `v` formatted as `{v:.decimals$e}` ([`push_exp`]).
pub fn exp(v: f64, decimals: usize) -> String {
    let mut s = String::with_capacity(24);
    push_exp(&mut s, v, decimals);
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(v: f64) {
        for d in [0, 1, 3, 9, 10, 14, 15, 16] {
            assert_eq!(exp(v, d), format!("{v:.d$e}"), "{v:e} with {d} decimals");
        }
    }

    /// The same bytes as the standard library on random bit patterns (every exponent), on
    /// random values of the sizes the outputs hold, and on the hard cases: midpoints of the
    /// 10- and 11-digit grids, carries (9.99…), powers of ten, the extremes and subnormals.
    #[test]
    fn matches_the_standard_library() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s
        };
        for _ in 0..200_000 {
            let bits = next();
            check(f64::from_bits(bits));
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            check((u - 0.5) * 10f64.powi((next() % 40) as i32 - 20));
        }
        for k in -300..300 {
            let p = 10f64.powi(k);
            for m in [1.0, 9.999_999_999_95, 9.999_999_999_5, 1.000_000_000_05, 2.5, 1.234_567_890_15, 0.5] {
                check(m * p);
                check(-m * p);
                check(f64::from_bits((m * p).to_bits() + 1));
                check(f64::from_bits((m * p).to_bits().saturating_sub(1)));
            }
        }
        for v in [f64::MAX, f64::MIN_POSITIVE, 5e-324, 1e-310, 0.0, -0.0, f64::NAN, f64::INFINITY, -f64::INFINITY] {
            check(v);
        }
        // every 11-digit midpoint near 1.25: x.xxxxxxxxxx5 exactly representable or not
        for i in 0..20_000u64 {
            let v = 1.25 + i as f64 * 1e-11 + 5e-12;
            check(v);
        }
    }
}
