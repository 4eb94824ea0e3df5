//! Jobs of one or many runs into output folders: a case solved into its folder
//! ([`solved`], the run manifest of a job [`job`]), a sweep of one parameter ([`sweep`]), both
//! engines on the same case and their differences ([`compare`], the published values of both:
//! [`compare_published`]), a batch of recordings
//! ([`batch`], on Slurm: [`slurm`], a task of it: [`batch_task`]).
pub mod batch;
pub mod batch_summary;
pub mod batch_task;
pub mod clip_run;
pub mod compare;
pub mod compare_published;
pub mod depth;
pub mod job;
pub mod slurm;
pub mod solved;
pub mod sweep;

/// Most threads a batch, sweep or audit runs at once (`--jobs`): beyond the machine's cores more
/// threads only take turns on them, each holding a solve's memory (tens of MB for a clip of 128
/// nodes), and thousands of them start slower than a signal should be obeyed.
pub const MAX_JOBS: usize = 256;

/// The threads to run `work` items on when `requested` were asked for (0: one per core): no
/// more than the items, nor [`MAX_JOBS`]; at least one.
pub fn threads_for(requested: usize, work: usize) -> usize {
    let cores = || std::thread::available_parallelism().map_or(1, |n| n.get());
    let wanted = if requested == 0 { cores() } else { requested };
    wanted.min(work).clamp(1, MAX_JOBS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn threads_are_bounded_by_the_work_and_the_maximum() {
        assert_eq!(threads_for(300, 6), 6);
        assert_eq!(threads_for(100_000, 10_000), MAX_JOBS);
        assert_eq!(threads_for(3, 0), 1);
        assert_eq!(threads_for(2, 40), 2);
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(threads_for(0, 1000), cores.min(MAX_JOBS));
        assert_eq!(threads_for(0, 1), 1);
    }
}
