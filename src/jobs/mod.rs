//! Jobs of one or many runs into output folders: a case solved into its folder
//! ([`solved`], the run manifest of a job [`job`]), a sweep of one parameter ([`sweep`]), both
//! engines on the same case and their differences ([`compare`], the published values of both:
//! [`compare_published`]), a batch of recordings
//! ([`batch`], on Slurm: [`slurm`], a task of it: [`batch_task`]).
pub mod batch;
pub mod batch_task;
pub mod compare;
pub mod compare_published;
pub mod job;
pub mod slurm;
pub mod solved;
pub mod sweep;
