//! The output-folder contract: a run's files ([`run_files`]: nodes, curvature, metrics, the
//! plot, the published values of [`reference_file`], the natural frequencies of [`modes_file`]), a clip's files streamed frame by frame ([`clip_output`], its figures
//! [`clip_figures`], the resume [`journal`]); the folder itself ([`run_folder`]: its lock [`folder_lock`], what runs leave
//! beside it, `staging`, and what runs that ended left in a folder of them, [`tidy`]) and its record `run.json` ([`manifest`]).
//! It writes files and runs no engine: a clip case run into its folder is
//! [`crate::jobs::clip_run`]'s.
pub mod clip_figures;
pub mod clip_output;
pub mod folder_lock;
pub mod journal;
pub mod manifest;
pub mod modes_file;
pub mod path_files;
pub mod reference_file;
pub mod run_files;
pub mod run_folder;
mod staging;
pub mod tidy;
