//! Numbers as text for the output tables and ParaView files: [`push_exp`] writes exactly what
//! `format!("{v:.N$e}")` writes (the same bytes), about three times faster than the standard
//! library's exact-precision algorithm (33–38 against 121 ns per number on the 2-core VM,
//! `cargo run --release --example bench_fmt`); a clip writes some ten million numbers.
//!
//! Two exact routes. For `|v|` between about 1e-17 and 1e10 (`v = m 2^e`): `v 10^k` with
//! `k = P − 1 − e10` is `m 5^k 2^(e+k)`, an integer product of at most 116 bits shifted, so its
//! floor and the remainder against one half are exact: correct rounding to `P` digits in a few
//! integer operations (an exact tie goes to the standard library). Elsewhere, from the shortest
//! round-trip digits of the `ryu` crate:
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
    let p = decimals + 1;
    let (q, e10) = match exact_digits(v.abs(), p) {
        Some(Rounded::Digits(q, e10)) => (q, e10),
        Some(Rounded::Tie) => {
            let _ = write!(out, "{v:.decimals$e}");
            return;
        }
        None => match rounded_shortest(v.abs(), p) {
            Some(d) => d,
            None => {
                let _ = write!(out, "{v:.decimals$e}");
                return;
            }
        },
    };
    push_digits(out, v < 0.0, q, p, e10);
}

/// `round(v · 10^k)` exactly, `k = p − 1 − e10`, when `v = m 2^e` and `5^k` fit the integer
/// arithmetic (`0 ≤ k ≤ 27`: `m 5^k < 2^116`): the `p` significant digits of `v` correctly
/// rounded and the power of ten of the first (`Tie`: `v` lies exactly between two `p`-digit
/// decimals); `None` outside that range.
fn exact_digits(v: f64, p: usize) -> Option<Rounded> {
    let bits = v.to_bits();
    let (m, e) = ((bits & ((1 << 52) - 1)) | (1 << 52), ((bits >> 52) & 0x7ff) as i32 - 1075);
    // v ∈ [2^(e+52), 2^(e+53)): its decimal exponent is est or est + 1, est = ⌊(e + 52) log10 2⌋
    // (78913 / 2^18 ≈ log10 2, exact as a floor for |x| < 2620; `>>` of an i32 floors)
    let est = ((e + 52) * 78913) >> 18;
    for e10 in [est, est + 1] {
        let k = p as i32 - 1 - e10;
        if !(0..=27).contains(&k) {
            return None;
        }
        let n = u128::from(m) * u128::from(POW5[k as usize]);
        let s = e + k; // v 10^k = n 2^s
        let (floor, rem, half) = if s >= 0 {
            (n.checked_shl(s as u32)?, 0, 1)
        } else if s > -120 {
            let sh = (-s) as u32;
            (n >> sh, n & ((1u128 << sh) - 1), 1u128 << (sh - 1))
        } else {
            return None;
        };
        if floor >= u128::from(POW10[p]) {
            continue; // the decimal exponent is est + 1
        }
        if rem == half {
            return Some(Rounded::Tie);
        }
        let mut q = floor as u64 + u64::from(rem > half);
        let mut e10 = e10;
        if q == POW10[p] {
            q = POW10[p - 1];
            e10 += 1;
        }
        return Some(Rounded::Digits(q, e10));
    }
    None
}

/// What [`exact_digits`] finds.
enum Rounded {
    /// the `p` digits as an integer in `[10^(p−1), 10^p)` and the power of ten of the first
    Digits(u64, i32),
    /// exactly halfway between two `p`-digit decimals
    Tie,
}

/// The `p` significant digits of `v` rounded from its shortest representation (`ryu`; see the
/// module doc) and the power of ten of the first; `None` where that argument does not decide
/// (the shortest digits are themselves a midpoint).
fn rounded_shortest(v: f64, p: usize) -> Option<(u64, i32)> {
    let mut buf = ryu::Buffer::new();
    let (m, nd, last) = shortest_digits(buf.format_finite(v).as_bytes())?;
    // `m`: the nd significant digits (no leading or trailing zeros), the last one at 10^last
    let mut e10 = last + nd as i32 - 1;
    let q = if nd > p {
        let drop = POW10[nd - p];
        let (mut q, r) = (m / drop, m % drop);
        // a 5 alone after the P digits is a midpoint of the P-digit grid: see the module doc
        if nd == p + 1 && r == 5 {
            return None;
        }
        if r >= drop / 2 {
            q += 1;
            if q == POW10[p] {
                q = POW10[p - 1];
                e10 += 1;
            }
        }
        q
    } else {
        m * POW10[p - nd]
    };
    Some((q, e10))
}

/// Append `±d.ddd…e±x` for the `p` digits `q` (in `[10^(p−1), 10^p)`) and the exponent `e10`.
fn push_digits(out: &mut String, negative: bool, q: u64, p: usize, e10: i32) {
    // sign, d.ddd…, 'e', exponent: at most 1 + 16 + 1 + 4 bytes
    let mut text = [0u8; 24];
    let mut n = 0;
    if negative {
        text[0] = b'-';
        n = 1;
    }
    let mut rest = q;
    for k in (1..p).rev() {
        text[n + 1 + k] = b'0' + (rest % 10) as u8;
        rest /= 10;
    }
    text[n] = b'0' + rest as u8;
    if p > 1 {
        text[n + 1] = b'.';
        n += p + 1;
    } else {
        n += 1;
    }
    text[n] = b'e';
    n += 1;
    if e10 < 0 {
        text[n] = b'-';
        n += 1;
    }
    let mut e = e10.unsigned_abs();
    let width = if e >= 100 {
        3
    } else if e >= 10 {
        2
    } else {
        1
    };
    for k in (0..width).rev() {
        text[n + k] = b'0' + (e % 10) as u8;
        e /= 10;
    }
    n += width;
    out.push_str(std::str::from_utf8(&text[..n]).expect("ASCII digits"));
}

/// Powers of five up to 5^27 (< 2^63).
const POW5: [u64; 28] = powers(5);

/// Powers of ten up to 10^17 (17 significant digits at most from the shortest representation).
const POW10: [u64; 18] = powers(10);

/// `[1, base, base², …]`, `N` of them.
const fn powers<const N: usize>(base: u64) -> [u64; N] {
    let mut t = [1u64; N];
    let mut k = 1;
    while k < N {
        t[k] = t[k - 1] * base;
        k += 1;
    }
    t
}

/// The significant digits of a shortest representation (`1.2345e-7`, `0.00123`, `123.0`; no
/// sign) as an integer without leading or trailing zeros, their count and the power of ten of
/// the last one; `None` for text of another shape.
fn shortest_digits(text: &[u8]) -> Option<(u64, usize, i32)> {
    let (mut m, mut nd, mut frac, mut point) = (0u64, 0usize, 0i32, false);
    let mut exp = 0i32;
    let mut bytes = text.iter();
    while let Some(&c) = bytes.next() {
        match c {
            b'.' => point = true,
            b'0'..=b'9' => {
                frac += i32::from(point);
                if nd == 0 && c == b'0' {
                    continue;
                }
                if nd == 17 {
                    return None;
                }
                m = m * 10 + u64::from(c - b'0');
                nd += 1;
            }
            b'e' | b'E' => {
                let mut sign = 1;
                for &c in bytes.by_ref() {
                    match c {
                        b'-' => sign = -1,
                        b'+' => {}
                        b'0'..=b'9' => exp = exp * 10 + i32::from(c - b'0'),
                        _ => return None,
                    }
                }
                exp *= sign;
            }
            _ => return None,
        }
    }
    if nd == 0 {
        return None;
    }
    let mut last = exp - frac;
    while m % 10 == 0 {
        m /= 10;
        nd -= 1;
        last += 1;
    }
    Some((m, nd, last))
}

/// `v` formatted as `{v:.decimals$e}` ([`push_exp`]).
pub fn exp(v: f64, decimals: usize) -> String {
    let mut s = String::with_capacity(24);
    push_exp(&mut s, v, decimals);
    s
}

/// Append the count, index or flag `v` (a whole number held as `f64`: iteration counts, frame
/// and node indices, 0/1 flags) as an integer, `12` rather than `1.2000000000e1`; a value that
/// is not a whole number (never written by the callers) keeps the `{v:.decimals$e}` form.
pub fn push_integer(out: &mut String, v: f64, decimals: usize) {
    /// 2^53: every whole `f64` below it is an exact integer
    const EXACT: f64 = 9_007_199_254_740_992.0;
    if v.fract() == 0.0 && v.abs() < EXACT {
        out.push_str(itoa::Buffer::new().format(v as i64));
    } else {
        push_exp(out, v, decimals);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_are_written_as_integers() {
        let text = |v: f64| {
            let mut s = String::new();
            push_integer(&mut s, v, 10);
            s
        };
        assert_eq!([text(0.0), text(12.0), text(-3.0), text(1.0)], ["0", "12", "-3", "1"]);
        assert_eq!(text(0.5), "5.0000000000e-1");
        assert_eq!(text(f64::NAN), "NaN");
    }

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
