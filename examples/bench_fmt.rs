//! Time per number of `io::number::push_exp` (the clip outputs' float formatting) against the
//! standard library's `{:.10e}` (the same bytes) and the `ryu` shortest representation alone,
//! on a million values of the sizes the outputs hold.
//! `cargo run --release --example bench_fmt`
use std::time::Instant;

fn main() {
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let vals: Vec<f64> = (0..1_000_000)
        .map(|_| {
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            (u - 0.5) * 10f64.powi((next() % 16) as i32 - 12)
        })
        .collect();
    let per = |t: Instant| t.elapsed().as_secs_f64() / vals.len() as f64 * 1e9;
    let t = Instant::now();
    let n: usize = vals.iter().map(|v| ryu::Buffer::new().format_finite(*v).len()).sum();
    println!("ryu shortest alone: {:.1} ns per number ({n} bytes)", per(t));
    let t = Instant::now();
    let mut out = String::with_capacity(20 * vals.len());
    for v in &vals {
        use std::fmt::Write as _;
        let _ = write!(out, "{v:.10e},");
    }
    println!("standard library format!(\"{{:.10e}}\"): {:.1} ns per number ({} bytes)", per(t), out.len());
    for decimals in [10, 9] {
        let mut best = f64::INFINITY;
        for _ in 0..5 {
            let mut out = String::with_capacity(20 * vals.len());
            let t = Instant::now();
            for v in &vals {
                cosserat::io::number::push_exp(&mut out, *v, decimals);
                out.push(',');
            }
            best = best.min(per(t));
        }
        println!("push_exp, {decimals} decimals: {best:.1} ns per number");
    }
}
