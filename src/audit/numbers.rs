//! How the audit writes numbers. A measured value has two significant digits by default, so
//! that the report's text changes only when a result does; but no digit that decides a
//! verdict is rounded away:
//! - an integer of three digits or more (an iteration or frame count) is written exactly
//!   (148 iterations, not 150);
//! - a value compared with a reference or limit has the digits that show its difference from
//!   it ([`against`]: a frequency of 206.78 rad/s against 207.0236, not 210 against 210);
//! - a spec's input (a limit, a reference) is written as the spec gives it ([`input`]).

/// `x` with two significant digits: plain for 0.01 ≤ |x| < 1e4, else scientific (`8.2e-5`);
/// an integer from 100 on exactly (`361`).
pub fn sig2(x: f64) -> String {
    sig(x, 2)
}

/// `x` with `n` ≥ 1 significant digits, in the style of [`sig2`].
pub fn sig(x: f64, n: usize) -> String {
    if !x.is_finite() {
        return format!("{x}");
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    // a count: every digit (148 iterations, 1160 frames)
    if (100.0..1e6).contains(&a) && x.fract() == 0.0 {
        return format!("{x}");
    }
    let n = n.max(1) as i32;
    let e = a.log10().floor() as i32;
    if (0.01..1e4).contains(&a) {
        if e + 1 > n {
            // more integer digits than significant ones: round the rest away (361.4 → 360)
            let p = 10f64.powi(e + 1 - n);
            return format!("{}", (x / p).round() * p);
        }
        let digits = (n - 1 - e).max(0) as usize;
        format!("{x:.digits$}")
    } else {
        let digits = (n - 1) as usize;
        format!("{x:.digits$e}").replace("e-0", "e-")
    }
}

/// `x` beside the `reference` it is compared with: two significant digits, or more (up to
/// six) where two would hide their difference: with d = |x − reference|, the digits down to
/// a fifth of d (206.78 against 207.0236; 0.039 against 0.05).
pub fn against(x: f64, reference: f64) -> String {
    let d = (x - reference).abs();
    if !x.is_finite() || !reference.is_finite() || x == 0.0 || d == 0.0 {
        return sig2(x);
    }
    // the last digit's unit 10^(e − n + 1) at most d / 5
    let e = x.abs().log10().floor();
    let n = (e + 1.0 + 5f64.log10() - d.log10()).ceil().clamp(2.0, 6.0) as usize;
    sig(x, n)
}

/// A spec's input (a limit, a reference value) as the spec gives it: [`sig2`] when that is
/// exact (`0.050`, `1.0e-3`), else every digit (`207.0236`).
pub fn input(x: f64) -> String {
    let short = sig2(x);
    // exact up to the round-off of a difference (a factor 1.1 as 1 + 0.10000000000000009)
    if short.parse::<f64>().is_ok_and(|s| (s - x).abs() <= 1e-12 * x.abs()) {
        return short;
    }
    let a = x.abs();
    if (0.01..1e4).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `text` with every number of more than two significant digits written as [`sig2`] (an
/// error's `9.378712387458614e-8` is `9.4e-8`), so that the report's text changes only when a
/// result does.
pub fn round_numbers(text: &str) -> String {
    text.split(' ')
        .map(|word| {
            let end = word.trim_end_matches([',', ';', ')', ':']);
            let start = end.trim_start_matches('(');
            match start.parse::<f64>() {
                Ok(x) if start.contains('.') && start.len() > 6 => {
                    format!("{}{}{}", &end[..end.len() - start.len()], sig2(x), &word[end.len()..])
                }
                _ => word.to_string(),
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

#[cfg(test)]
mod tests {
    use super::{against, input, round_numbers, sig, sig2};

    #[test]
    fn two_significant_digits() {
        assert_eq!(sig2(8.19499e-5), "8.2e-5");
        assert_eq!(sig2(0.0860337), "0.086");
        assert_eq!(sig2(361.4), "360");
        assert_eq!(sig2(1.0), "1.0");
        assert_eq!(sig2(12.4), "12");
        assert_eq!(sig2(2.5e6), "2.5e6");
        assert_eq!(sig2(-0.0025), "-2.5e-3");
        assert_eq!(sig(206.7812, 5), "206.78");
        assert_eq!(sig(8.19499e-5, 3), "8.19e-5");
    }

    #[test]
    fn counts_are_written_exactly() {
        // iteration and frame counts: 148 is not 150
        assert_eq!(sig2(148.0), "148");
        assert_eq!(sig2(3000.0), "3000");
        assert_eq!(sig2(1160.0), "1160");
    }

    #[test]
    fn a_value_shows_its_difference_from_its_reference() {
        // the first natural frequency of the cantilever against the paper's ω0
        assert_eq!(against(206.7812, 207.0236), "206.78");
        assert_eq!(input(207.0236), "207.0236");
        // far from its limit: two digits
        assert_eq!(against(0.0391, 0.05), "0.039");
        assert_eq!(input(0.05), "0.050");
        assert_eq!(input(1e-3), "1.0e-3");
        // close to it: enough digits to see on which side it lies
        assert_eq!(against(0.04996, 0.05), "0.049960");
        assert_eq!(against(0.99, 0.5), "0.99");
        assert_eq!(against(1.04, 2.0), "1.0");
        assert_eq!(input(1.1 - 1.0), "0.10");
    }

    #[test]
    fn long_numbers_of_an_error_are_rounded() {
        assert_eq!(
            round_numbers(
                "change (x, α) is 9.378712387458614e-8, but 1e-10 (after 3000 iterations: 1.0245671838684249e-1)"
            ),
            "change (x, α) is 9.4e-8, but 1e-10 (after 3000 iterations: 0.10)"
        );
    }
}
