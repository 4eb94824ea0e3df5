fn main() {
    let path = std::env::args().nth(1).expect("case");
    let case = cosserat::case::Case::from_file(std::path::Path::new(&path)).expect("case");
    let r = cosserat::engine::rust::run_rust(&case, |_, _| {}).expect("run");
    let inv = r.inverse.as_ref().unwrap();
    for h in inv.history.iter().filter(|h| h.iteration % 50 == 0 || h.iteration < 4) {
        eprintln!(
            "{} {:.3e} {:.3e} {:.3e} J {:?}",
            h.iteration,
            h.rel_change,
            h.x_err_rel,
            h.tangent_misfit,
            h.objective.values()
        );
    }
    eprintln!("iterations {} wall {:.3}", r.stats.iterations, r.stats.wall_time_s);
}
