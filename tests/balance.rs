//! The energy and the momenta of a dynamic run (`model::balance`, `balance.csv`): the flying
//! spaghetti in its plane (`cases/benchmarks/flying_spaghetti_planar.toml`), a free–free rod
//! pushed for 5 s and then in free flight.
//!
//! - Newton's second law for the whole rod: after the load, the linear momentum is the load's
//!   impulse (20 N s along e1) and stays so; the time stepping of Appendix A (68) conserves it
//!   exactly, because the position rows of the internal force sum to zero (`Σ_a ∂s N_a = 0`).
//! - Free flight conserves the angular momentum about the origin and the energy. The momenta
//!   are kept to round-off; the energy changes by the scheme's time-discretisation error, which
//!   falls at second order with Δt (the scheme is of order 2).
//! - Both engines write the same balance (FreeFEM: its own integrals of the same rules).
//!
//! FreeFEM must be installed; `COSSERAT_SKIP_FREEFEM=1` runs the Rust engine only.
mod common;

use cosserat::case::Case;
use cosserat::engine::metrics::{Metric, Metrics};
use cosserat::engine::{run_case, Engine, RunResult};

fn spaghetti(steps: usize) -> Case {
    let text = common::case_text("benchmarks/flying_spaghetti_planar");
    let text = common::edit(&text, "steps = 150", &format!("steps = {steps}"));
    common::case_from(&text, "flying_spaghetti_planar")
}

fn run(case: &Case, engine: Engine) -> (RunResult, Metrics) {
    let dir = tempfile::tempdir().expect("tempdir");
    let r = run_case(case, engine, dir.path(), |_, _| {}).unwrap_or_else(|e| panic!("{}", common::error_chain(&e)));
    let m = cosserat::engine::metrics::all_metrics(case, &r).expect("metrics");
    (r, m)
}

fn get(m: &Metrics, key: Metric) -> f64 {
    m.get(key).unwrap_or_else(|| panic!("metric {key:?} missing"))
}

/// The impulse of the hat-shaped force `3.2 min(t, 5 − t)` N over 0 ≤ t ≤ 5 s: 20 N s.
const IMPULSE_N_S: f64 = 3.2 * 2.5 * 5.0 / 2.0;

#[test]
fn free_flight_keeps_the_impulse_and_the_angular_momentum() {
    let (r, m) = run(&spaghetti(150), Engine::Rust);
    // the load stops at t = 5 s: the free flight is what follows
    assert_eq!(get(&m, Metric::UnloadedFrom), 5.0);
    assert!(r.tip.iter().filter(|t| t.time_s > 5.0 + 1e-9).all(|t| !t.loaded));
    let p = r.tip.last().expect("records").balance.momentum_n_s;
    assert!((p[0] - IMPULSE_N_S).abs() <= 1e-10 * IMPULSE_N_S, "p_x = {}", p[0]);
    assert!(p[1].abs() <= 1e-10 * IMPULSE_N_S && p[2].abs() <= 1e-10 * IMPULSE_N_S, "p = {p}");
    assert!(get(&m, Metric::UnloadedMomentumChange) <= 1e-10 * IMPULSE_N_S);
    let h = get(&m, Metric::AngularMomentumY);
    assert!(h.abs() > 1.0, "the push turns the rod: h_y = {h}");
    assert!(get(&m, Metric::UnloadedAngularMomentumChange) <= 1e-10 * h.abs());
    // planar motion in the (e1, e3) plane: its angular momentum is along e2
    assert_eq!(get(&m, Metric::AngularMomentumX), 0.0);
    assert_eq!(get(&m, Metric::AngularMomentumZ), 0.0);
}

/// The energy's change over the free flight is the scheme's error: it falls at order 2 as Δt
/// halves (measured 9.5e-3, 8.7e-4, 1.3e-4 at 150, 300, 600 steps; the asymptotic order is
/// reached from 300 steps on).
#[test]
fn free_flight_energy_change_falls_at_second_order() {
    let change = |steps| get(&run(&spaghetti(steps), Engine::Rust).1, Metric::UnloadedEnergyChangeRel);
    let (coarse, fine) = (change(300), change(600));
    let order = (coarse / fine).log2();
    assert!(order >= 1.8, "energy change {coarse:e} → {fine:e}: order {order:.2}");
    assert!(fine < 2e-4, "energy change {fine:e}");
}

/// Both engines write the same balance at every time step.
#[test]
fn both_engines_write_the_same_balance() {
    if !common::freefem_required() {
        return;
    }
    let case = spaghetti(150);
    let (rust, _) = run(&case, Engine::Rust);
    let (ff, _) = run(&case, Engine::Freefem);
    assert_eq!(rust.tip.len(), ff.tip.len());
    let scale = rust.tip.iter().map(|t| t.balance.energy_j()).fold(0.0_f64, f64::max);
    for (a, b) in rust.tip.iter().zip(&ff.tip) {
        let (ba, bb) = (&a.balance, &b.balance);
        let close = |x: f64, y: f64, s: f64| (x - y).abs() <= 1e-10 * s;
        assert!(
            close(ba.kinetic_j, bb.kinetic_j, scale) && close(ba.elastic_j, bb.elastic_j, scale),
            "t = {}",
            a.time_s
        );
        assert!((ba.momentum_n_s - bb.momentum_n_s).norm() <= 1e-10 * IMPULSE_N_S, "t = {}", a.time_s);
        let h = ba.angular_momentum_n_m_s.norm().max(1.0);
        assert!((ba.angular_momentum_n_m_s - bb.angular_momentum_n_m_s).norm() <= 1e-10 * h, "t = {}", a.time_s);
        assert_eq!(a.loaded, b.loaded, "t = {}", a.time_s);
    }
}
