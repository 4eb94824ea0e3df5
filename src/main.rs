//! `cosserat` command-line interface: parsing ([`cli::args`]) and dispatch only; every command
//! is a function of `cli/` ([`cli::commands`] for those on one case, [`cli`] for those of many
//! recordings).
use std::process::ExitCode;

use anyhow::Result;
use clap::Parser;

mod cli;

use cli::args::{Cli, Command};
use cli::commands::{cmd_audit, cmd_buckling, cmd_compare, cmd_modes, cmd_run, cmd_sweep};

/// Exit status of a run stopped by SIGINT/SIGTERM (128 + SIGINT, the shell's convention).
const EXIT_INTERRUPTED: u8 = 130;

/// SIGINT/SIGTERM/SIGHUP: the first asks the running loops to stop after the current frame
/// (time step, iteration) so that the files stay consistent; a second one exits at once.
fn install_signal_handler() {
    let result = ctrlc::set_handler(|| {
        if cosserat::interrupt::requested() {
            eprintln!("\nsecond signal: exiting at once (the output folder keeps its previous state)");
            std::process::exit(i32::from(EXIT_INTERRUPTED));
        }
        cosserat::interrupt::request();
        eprintln!("\nsignal received: stopping after the current frame / step (again to exit at once)");
    });
    if let Err(e) = result {
        eprintln!("warning: cannot handle SIGINT/SIGTERM ({e}); an interrupted run will not be marked");
    }
}

/// A failed allocation ends the process with a message and status 1, not an abort.
#[global_allocator]
static ALLOCATOR: cli::alloc::Guarded = cli::alloc::Guarded;

fn main() -> ExitCode {
    cli::alloc::at_start();
    cli::keep_freed_memory();
    let cli = Cli::parse();
    install_signal_handler();
    match dispatch(cli) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

fn dispatch(cli: Cli) -> Result<ExitCode> {
    match cli.command {
        Command::Run(a) => cmd_run(a),
        Command::Compare(a) => cmd_compare(a),
        Command::Sweep(a) => cmd_sweep(a),
        Command::Audit(a) => cmd_audit(a),
        Command::Batch(a) => cli::cmd_batch(a),
        Command::BatchTask(a) => cli::cmd_batch_task(a),
        Command::Gather { out } => cli::cmd_gather(&out),
        Command::Synth(a) => cli::synth::cmd_synth(a),
        Command::NoiseStudy(a) => cli::noise_study::cmd_noise_study(a),
        Command::List { dir } => cli::list::cmd_list(&dir),
        Command::Modes { case, count, limits } => cmd_modes(&case, count, limits),
        Command::Buckling { case, count } => cmd_buckling(&case, count),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
