//! The lowest natural frequencies by shift-invert block Lanczos (`solve::modes::lowest_modes`,
//! D28) against the dense eigen-solve of the same pencil (`modal_model`), and against the
//! Euler–Bernoulli cantilever's frequencies (R. D. Blevins, Formulas for Natural Frequency and
//! Mode Shape, 1979, Table 8-1) with their mesh-convergence order; the case is
//! `tests/modes/cantilever_frequencies.toml` (a steel wire, L/r = 1000, round section); and
//! `run`'s `solver.vibration_modes` in both engines (`cases/benchmarks/cantilever_frequencies.toml`,
//! FreeFEM's ARPACK on the same pencil, `freefem/modes.idp`).
mod common;

use common::{case_from, case_text, edit};
use cosserat::case::Case;
use cosserat::engine::metrics::all_metrics;
use cosserat::engine::{run_case, Engine};
use cosserat::output::run_files::write_run;
use cosserat::solve::modes::{lowest_modes, modal_model, RITZ_TOLERANCE};

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

/// The benchmark case `cases/benchmarks/cantilever_frequencies.toml` at `elements`, with
/// `solver.vibration_modes = count`.
fn benchmark_case(elements: usize, count: usize) -> Case {
    let path = common::cases_dir().join("benchmarks/cantilever_frequencies.toml");
    let text = std::fs::read_to_string(path).expect("case");
    let text = edit(&text, "elements = 200", &format!("elements = {elements}"));
    case_from(&edit(&text, "vibration_modes = 30", &format!("vibration_modes = {count}")), "cantilever_frequencies")
}

/// `run` with `solver.vibration_modes` gives the frequencies of `lowest_modes` (the same numbers,
/// bit for bit) as metrics `omega_{k}_rad_per_s` and in `modes.csv`; the FreeFEM engine's
/// ARPACK on the same pencil (freefem/modes.idp) agrees within the round-off floor of the
/// lowest frequencies. The floor, derived: a backward-stable factorisation of `K` perturbs
/// `ω²` by about `ε κ ω₁²` in absolute terms, `κ ≈ (GA L²/EI) N` the conditioning of the thin
/// rod's `K` (D28), so `ω_k` moves by `½ ε κ (ω₁/ω_k)²` relatively; ten times that, and 1e-10
/// (the Ritz tolerance of both, `RITZ_TOLERANCE`, on `θ = 1/ω²`) for the well-conditioned modes.
/// A frequency of the wrong pencil (the mass at one point, the angle rows without `A(0)ᵀ`) or a
/// double frequency seen once (the next one in its place) misses by far more.
#[test]
fn run_writes_the_frequencies_in_both_engines() {
    let case = benchmark_case(60, 12);
    let dir = tempfile::tempdir().expect("tempdir");
    let rust = run_case(&case, Engine::Rust, dir.path(), |_, _| {}).expect("rust");
    let direct = lowest_modes(&case.problem(), 12).expect("modes").omegas;
    let metrics = all_metrics(&case, &rust).expect("metrics");
    for (k, w) in direct.iter().enumerate() {
        assert_eq!(metrics.named(&format!("omega_{}_rad_per_s", k + 1)), Some(*w), "mode {}", k + 1);
    }
    let out = tempfile::tempdir().expect("tempdir");
    let written = write_run(&case, &rust, &metrics, out.path()).expect("files");
    let csv = std::fs::read_to_string(out.path().join("modes.csv")).expect("modes.csv");
    assert!(written.iter().any(|p| p.ends_with("modes.csv")));
    assert_eq!(csv.lines().next(), Some("mode,omega_rad_per_s,frequency_hz,period_s"));
    assert_eq!(csv.lines().count(), 13);
    if !common::freefem_required() {
        return;
    }
    let ff = run_case(&case, Engine::Freefem, dir.path(), |_, _| {}).expect("freefem");
    let ffw = &ff.stability.as_ref().expect("stability").omegas_rad_per_s;
    assert_eq!(ffw.len(), 12);
    let p = &case.props;
    let kappa = p.shear_stretch_n[0] * case.mesh.length_m.powi(2) / p.bend_twist_nm2[0] * case.mesh.elements as f64;
    for (k, (r, f)) in direct.iter().zip(ffw).enumerate() {
        let floor = 0.5 * f64::EPSILON * kappa * (direct[0] / r).powi(2);
        let tol = 10.0 * floor + RITZ_TOLERANCE;
        let e = (f / r - 1.0).abs();
        eprintln!("mode {}: rust {r:.12} freefem {f:.12}: {e:.2e} (tolerance {tol:.1e})", k + 1);
        assert!(e <= tol, "mode {}: rust {r} freefem {f}: {e:.2e} > {tol:.1e}", k + 1);
    }
}

/// `solver.vibration_modes` is refused where the pencil of `solve::modes` is not the rod's: an
/// analysis other than static, a rod without density, ends other than the paper's, a singular
/// mass matrix, no mode or more than the unknowns give; each error names the key.
#[test]
fn vibration_modes_is_refused_where_it_makes_no_sense() {
    let text =
        std::fs::read_to_string(common::cases_dir().join("benchmarks/cantilever_frequencies.toml")).expect("case");
    let refused = |t: String, key: &str| {
        let e = Case::from_toml(&t, "c", std::path::Path::new("c.toml")).expect_err("refused").to_string();
        assert!(e.contains(key), "{e}");
    };
    refused(edit(&text, "vibration_modes = 30", "vibration_modes = 0"), "solver.vibration_modes");
    refused(edit(&text, "vibration_modes = 30", "vibration_modes = 601"), "solver.vibration_modes");
    refused(edit(&text, "density_kg_m3 = \"rho\"\n", ""), "solver.vibration_modes");
    refused(edit(&text, "[solver]\n", "[ends.end]\nkind = \"pinned\"\n\n[solver]\n"), "solver.vibration_modes");
    refused(
        edit(&text, "method = \"newton\"\n", "method = \"newton\"\nquadrature = \"midpoint\"\n"),
        "solver.quadrature",
    );
    let dynamic = edit(&case_text("cantilever_dynamic"), "[solver]\n", "[solver]\nvibration_modes = 4\n");
    refused(dynamic, "solver.vibration_modes");
}
