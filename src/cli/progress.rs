//! Progress of a long command on stderr, one helper for every command (`run`, `compare`,
//! `sweep`, `audit`, `batch`): a bar where stderr is a terminal; elsewhere (a log file, `nohup`,
//! a Slurm task) one line every [`INTERVAL_S`] seconds — done/total, rate, time left — and a
//! final line. `--quiet` shows neither.
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Seconds between two progress lines without a terminal.
pub const INTERVAL_S: f64 = 10.0;
/// Environment variable that sets another interval [s] (tests use a short one).
pub const INTERVAL_VAR: &str = "COSSERAT_PROGRESS_INTERVAL_S";

/// Whether a command shows its progress (`--quiet`: hidden).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Visibility {
    Shown,
    Hidden,
}

impl Visibility {
    /// Hidden if `hidden` (`--quiet`, or progress shown another way), else shown.
    pub fn unless(hidden: bool) -> Self {
        if hidden {
            Visibility::Hidden
        } else {
            Visibility::Shown
        }
    }
}

/// Which line [`State::line`] writes: one while the command runs, or its last.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Line {
    Running,
    Last,
}

/// The progress of one command.
pub struct Progress {
    shown: Shown,
}

enum Shown {
    Hidden,
    Bar(ProgressBar),
    Lines { state: Arc<State>, ticker: Option<std::thread::JoinHandle<()>> },
}

/// What the line printer reads.
struct State {
    label: String,
    unit: &'static str,
    done: AtomicU64,
    /// 0: not known (a spinner's elapsed time only)
    total: AtomicU64,
    start: Instant,
    stopped: Mutex<bool>,
    wake: Condvar,
}

impl State {
    fn line(&self, which: Line) -> String {
        let last = which == Line::Last;
        let (done, total) = (self.done.load(Ordering::SeqCst), self.total.load(Ordering::SeqCst));
        let elapsed = self.start.elapsed().as_secs_f64();
        let (label, unit) = (&self.label, self.unit);
        if total == 0 {
            let verb = if last { "ended after" } else { "running," };
            return format!("{label}: {verb} {}", duration(elapsed));
        }
        let rate = done as f64 / elapsed.max(1e-9);
        let per_s = format!("{} {unit}/s", significant(rate));
        if last {
            return format!("{label}: {done}/{total} {unit} in {}, {per_s}", duration(elapsed));
        }
        let left = if done == 0 { "unknown".to_string() } else { duration((total - done.min(total)) as f64 / rate) };
        let percent = 100.0 * done as f64 / total as f64;
        format!("{label}: {done}/{total} {unit} ({percent:.0}%) after {}, {per_s}, ETA {left}", duration(elapsed))
    }
}

/// A rate to three significant digits: `212`, `3.05`, `0.0412`.
fn significant(v: f64) -> String {
    let decimals = if v > 0.0 { (2 - v.log10().floor() as i32).clamp(0, 6) as usize } else { 0 };
    format!("{v:.decimals$}")
}

/// `7.2 s`, `3 min 05 s`, `2 h 03 min`.
fn duration(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.1} s")
    } else if s < 3600.0 {
        format!("{} min {:02} s", (s / 60.0) as u64, (s % 60.0) as u64)
    } else {
        format!("{} h {:02} min", (s / 3600.0) as u64, ((s % 3600.0) / 60.0) as u64)
    }
}

fn interval() -> Duration {
    let s = std::env::var(INTERVAL_VAR).ok().and_then(|v| v.parse::<f64>().ok()).filter(|s| *s > 0.0);
    Duration::from_secs_f64(s.unwrap_or(INTERVAL_S))
}

impl Progress {
    /// Progress of `label` counted in `unit` ("frames", "points"); `total` 0 where it is not
    /// known (then only the time elapsed is shown).
    pub fn new(label: &str, unit: &'static str, total: usize, visibility: Visibility) -> Progress {
        if visibility == Visibility::Hidden {
            return Progress { shown: Shown::Hidden };
        }
        if std::io::stderr().is_terminal() {
            let bar = if total == 0 { ProgressBar::new_spinner() } else { ProgressBar::new(total as u64) };
            let template = if total == 0 {
                "{prefix} {spinner} {elapsed}".to_string()
            } else {
                format!("{{prefix}} [{{bar:40}}] {{pos}}/{{len}} {unit} {{per_sec}} eta {{eta}}")
            };
            bar.set_style(
                ProgressStyle::with_template(&template)
                    .unwrap_or_else(|_| ProgressStyle::default_bar())
                    .progress_chars("=> "),
            );
            bar.set_prefix(label.to_string());
            if total == 0 {
                bar.enable_steady_tick(Duration::from_millis(200));
            }
            return Progress { shown: Shown::Bar(bar) };
        }
        let state = Arc::new(State {
            label: label.to_string(),
            unit,
            done: AtomicU64::new(0),
            total: AtomicU64::new(total as u64),
            start: Instant::now(),
            stopped: Mutex::new(false),
            wake: Condvar::new(),
        });
        let s = Arc::clone(&state);
        let every = interval();
        let ticker = std::thread::spawn(move || {
            let mut stopped = s.stopped.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                let (guard, _) = s.wake.wait_timeout(stopped, every).unwrap_or_else(|e| e.into_inner());
                stopped = guard;
                if *stopped {
                    return;
                }
                eprintln!("{}", s.line(Line::Running));
            }
        });
        Progress { shown: Shown::Lines { state, ticker: Some(ticker) } }
    }

    /// `done` of `total` (a total of 0 keeps the one given before).
    pub fn set(&self, done: usize, total: usize) {
        match &self.shown {
            Shown::Hidden => {}
            Shown::Bar(b) => {
                if total > 0 {
                    b.set_length(total as u64);
                }
                b.set_position(done as u64);
            }
            Shown::Lines { state, .. } => {
                if total > 0 {
                    state.total.store(total as u64, Ordering::SeqCst);
                }
                state.done.store(done as u64, Ordering::SeqCst);
            }
        }
    }

    /// One more done.
    pub fn inc(&self) {
        match &self.shown {
            Shown::Hidden => {}
            Shown::Bar(b) => b.inc(1),
            Shown::Lines { state, .. } => {
                state.done.fetch_add(1, Ordering::SeqCst);
            }
        }
    }

    /// The end: the bar is cleared; without a terminal, the final line.
    pub fn finish(mut self) {
        self.end();
    }

    fn end(&mut self) {
        match std::mem::replace(&mut self.shown, Shown::Hidden) {
            Shown::Hidden => {}
            Shown::Bar(b) => b.finish_and_clear(),
            Shown::Lines { state, ticker } => {
                *state.stopped.lock().unwrap_or_else(|e| e.into_inner()) = true;
                state.wake.notify_all();
                if let Some(t) = ticker {
                    let _ = t.join();
                }
                eprintln!("{}", state.line(Line::Last));
            }
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.end();
    }
}

/// The progress of the FreeFEM runs of a command (`compare`): the frames of a clip or the time
/// steps of a dynamic run as FreeFEM writes them (`cosserat::engine::freefem_progress`), shown as
/// [`Progress`] shows a command's own (a bar, or lines every 10 s and a final line).
pub struct FreefemProgress {
    shown: Arc<Mutex<Option<Progress>>>,
}

impl FreefemProgress {
    /// Shows the counts of every FreeFEM run until [`FreefemProgress::finish`], as `label`.
    pub fn start(label: &str) -> FreefemProgress {
        use cosserat::engine::freefem_progress::{observe, Count, Unit};
        let shown: Arc<Mutex<Option<Progress>>> = Arc::new(Mutex::new(None));
        let into = Arc::clone(&shown);
        let label = label.to_string();
        observe(Some(Arc::new(move |c: Count| {
            let unit = match c.unit {
                Unit::Frames => "frames",
                Unit::Steps => "time steps",
                Unit::PathSteps => "path steps",
            };
            let mut p = into.lock().unwrap_or_else(|e| e.into_inner());
            p.get_or_insert_with(|| Progress::new(&label, unit, c.total, Visibility::Shown)).set(c.done, c.total);
        })));
        FreefemProgress { shown }
    }

    /// The end: no more counts; the bar is cleared, or the final line printed.
    pub fn finish(self) {}
}

impl Drop for FreefemProgress {
    fn drop(&mut self) {
        cosserat::engine::freefem_progress::observe(None);
        if let Some(p) = self.shown.lock().unwrap_or_else(|e| e.into_inner()).take() {
            p.finish();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_say_done_total_rate_and_time_left() {
        let s = State {
            label: "clip".into(),
            unit: "frames",
            done: AtomicU64::new(30),
            total: AtomicU64::new(120),
            start: Instant::now() - Duration::from_secs(10),
            stopped: Mutex::new(false),
            wake: Condvar::new(),
        };
        let line = s.line(Line::Running);
        assert!(line.starts_with("clip: 30/120 frames (25%) after 10.0 s, 3.00 frames/s, ETA 30.0 s"), "{line}");
        assert!(
            s.line(Line::Last).starts_with("clip: 30/120 frames in 10.0 s, 3.00 frames/s"),
            "{}",
            s.line(Line::Last)
        );
        assert_eq!((significant(212.4), significant(0.04123)), ("212".into(), "0.0412".into()));
        assert_eq!((duration(185.0), duration(7500.0)), ("3 min 05 s".into(), "2 h 05 min".into()));
    }
}
