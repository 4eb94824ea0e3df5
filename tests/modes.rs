//! The lowest natural frequencies by shift-invert block Lanczos (`solve::modes::lowest_modes`,
//! D28) against the dense eigen-solve of the same pencil (`modal_model`), and against the
//! Euler–Bernoulli cantilever's frequencies (R. D. Blevins, Formulas for Natural Frequency and
//! Mode Shape, 1979, Table 8-1) with their mesh-convergence order; the case is
//! `tests/modes/cantilever_frequencies.toml` (a steel wire, L/r = 1000, round section).
mod common;

use common::{case_from, case_text, edit};
use cosserat::case::Case;
use cosserat::solve::modes::{lowest_modes, modal_model};

/// `β_n L` of the clamped-free beam (Blevins 1979, Table 8-1), n = 1..4.
const BETA_L: [f64; 4] = [1.87510407, 4.69409113, 7.85475744, 10.99554073];

fn benchmark_path() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/modes/cantilever_frequencies.toml")
}

fn benchmark(elements: usize) -> Case {
    let text = std::fs::read_to_string(benchmark_path()).expect("case");
    case_from(&edit(&text, "elements = 200", &format!("elements = {elements}")), "cantilever_frequencies")
}

/// The lowest ten ω of the Lanczos method equal the dense Cholesky–QR ones to 1e-9 on small
/// stocky rods: a rectangular section (§5.1's cantilever, simple frequencies) and a round one
/// (the benchmark's wire thickened to L/r = 50; every bending frequency double, which a
/// single-vector Lanczos would see once). Stocky, because the dense QR's error in ω_k² is
/// about ε ω_max² (the axial and shear modes of the shortest element): on the wire itself
/// (L/r = 1000, 8 elements, ω_max²/ω_1² ~ 1e10) the dense ω_1 is 1.2e-6 off, the
/// shift-invert one is not (it resolves the lowest modes first).
#[test]
fn lanczos_matches_the_dense_eigen_solve() {
    for n in [8, 16] {
        let dynamic = edit(&case_text("cantilever_dynamic"), "elements = 100", &format!("elements = {n}"));
        let stocky = edit(&std::fs::read_to_string(benchmark_path()).expect("case"), "r = 1e-3 ", "r = 2e-2 ");
        let stocky = edit(&stocky, "elements = 200", &format!("elements = {n}"));
        for c in [case_from(&stocky, "stocky_round"), case_from(&dynamic, "cantilever_dynamic")] {
            let dense = modal_model(&c.problem()).expect("dense").omegas;
            let sparse = lowest_modes(&c.problem(), 10).expect("sparse");
            assert_eq!(sparse.omegas.len(), 10);
            for (k, (s, d)) in sparse.omegas.iter().zip(&dense).enumerate() {
                let e = (s / d - 1.0).abs();
                assert!(e <= 1e-9, "{} elements, {}: mode {}: {s} vs {d} ({e:.1e})", n, c.name, k + 1);
            }
            assert!(sparse.asymmetry <= 1e-10);
        }
    }
}

/// Mesh convergence of the wire's lowest four bending frequencies (each double): order 2 in
/// the element size (differences at 100 → 200 → 400 elements), and the Richardson limit
/// below the Euler–Bernoulli beam's `(β_n L)² √(EI/(ρA L⁴))` by the shear and rotary inertia
/// that a Cosserat rod has and the beam lacks: Timoshenko beam theory estimates the relative
/// shift as `½ (β_n r_g)² (1 + E/(kG))` (r_g = r/2), 1.7e-6 … 5.9e-5 here; the limit must lie
/// in `[−2 shift, 0]` (a `β_n L` wrong in its fifth digit misses it).
#[test]
fn cantilever_frequencies_converge_to_euler_bernoulli() {
    let runs: Vec<(Case, Vec<f64>)> = [100, 200, 400]
        .iter()
        .map(|&n| {
            let c = benchmark(n);
            let w = lowest_modes(&c.problem(), 8).expect("modes").omegas;
            (c, w)
        })
        .collect();
    let c = &runs[0].0;
    let (ei, m, l) = (c.props.bend_twist_nm2[0], c.props.mass_per_length_kg_m, c.mesh.length_m);
    // E/(kG) = EA/(kGA); the radius of gyration r_g = √(I/A) = √(EI/EA)
    let (ea, kga) = (c.props.shear_stretch_n[2], c.props.shear_stretch_n[0]);
    let r_g = (ei / ea).sqrt();
    for (_, w) in &runs {
        for k in 0..4 {
            assert!((w[2 * k + 1] / w[2 * k] - 1.0).abs() < 1e-12, "a double frequency: {w:?}");
        }
    }
    for k in 0..4 {
        let w: Vec<f64> = runs.iter().map(|(_, w)| w[2 * k]).collect();
        let order = ((w[0] - w[1]) / (w[1] - w[2])).log2();
        let limit = w[2] + (w[2] - w[1]) / 3.0;
        let beam = BETA_L[k].powi(2) * (ei / (m * l.powi(4))).sqrt();
        let shift = 0.5 * (BETA_L[k] / l * r_g).powi(2) * (1.0 + ea / kga);
        let error = limit / beam - 1.0;
        eprintln!("mode {}: ω = {:?}, order {order:.3}, limit {limit:.9} vs beam {beam:.9}: {error:.3e} (Timoshenko shift −{shift:.2e})", k + 1, w);
        assert!((1.95..2.05).contains(&order), "mode {}: order {order}", k + 1);
        assert!((-2.0 * shift..0.0).contains(&error), "mode {}: {error:.3e} against −{shift:.2e}", k + 1);
    }
}
