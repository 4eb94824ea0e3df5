//! `cosserat list`: the cases of a folder with their descriptions; exit status 1 if one is
//! invalid (each named on stderr with its error).
use std::path::Path;
use std::process::ExitCode;

use anyhow::{Context, Result};

use cosserat::case::{case_files, Case};

pub fn cmd_list(dir: &Path) -> Result<ExitCode> {
    let files = case_files(dir).with_context(|| format!("cannot list {}", dir.display()))?;
    if files.is_empty() {
        anyhow::bail!("no *.toml case files in {}", dir.display());
    }
    let mut invalid = 0;
    for f in files {
        match Case::from_file(&f) {
            Ok(c) => println!("{:<24} {}", c.name, c.origin.description),
            Err(e) => {
                invalid += 1;
                let stem = f.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
                println!("{stem:<24} INVALID (see below)");
                eprintln!("INVALID {}: {e}", f.display());
            }
        }
    }
    if invalid > 0 {
        eprintln!("error: {invalid} invalid case file(s) in {} (marked INVALID above)", dir.display());
        return Ok(ExitCode::from(1));
    }
    Ok(ExitCode::SUCCESS)
}
