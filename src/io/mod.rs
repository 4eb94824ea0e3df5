//! Everything that touches files or other programs: atomic writes and CSV ([`files`]), the
//! forward data file `data.csv` ([`data`]), clip files ([`clip_files`], [`npy`]), the outputs of
//! a run ([`run_files`]) and of a clip ([`clip_output`], [`clip_figures`], [`vtk`], [`compact`], the resume [`journal`]),
//! SVG figures ([`plot`], [`heatmap`], [`posture`], their text [`figure_text`]), numbers as text ([`number`]), the FreeFEM engine ([`freefem`], its progress [`freefem_progress`]), a case in either engine from its files ([`engine`]) and the
//! files of a sweep ([`sweep`]), a batch of recordings ([`batch`], on Slurm: [`slurm`]) and a
//! corpus of synthetic recordings ([`corpus`]); the output-folder contract ([`run_folder`]: its
//! lock [`folder_lock`], what runs leave beside a folder `staging`, a full disk [`disk`]).
pub mod batch;
pub mod clip_figures;
pub mod clip_files;
pub mod clip_output;
pub mod clip_run;
pub mod compact;
pub mod compare;
pub mod corpus;
pub mod data;
pub mod disk;
pub mod engine;
pub mod figure_text;
pub mod files;
pub mod folder_lock;
pub mod freefem;
pub mod freefem_clip;
pub mod freefem_include;
pub mod freefem_progress;
pub mod heatmap;
pub mod job;
pub mod journal;
pub mod manifest;
pub mod npy;
pub mod number;
pub mod plot;
pub mod posture;
pub mod run_files;
pub mod run_folder;
pub mod slurm;
pub mod solved;
mod staging;
pub mod sweep;
pub mod truth_file;
pub mod vtk;

pub use files::{write_atomic, InputError, OutputError};
