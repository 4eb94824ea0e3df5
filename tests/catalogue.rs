//! The catalogue of bad inputs (issue 15, "runs that never lie"): every entry of
//! `tests/catalogue/catalogue.toml` is one mistake a new user could make (a bad case file,
//! recording, NPY file, expression, audit spec, command line, folder or resource), run through
//! the real binary under a 4 GB address-space limit and a timeout. Each must end with
//!
//! - a non-zero exit status, not a signal (an allocation abort, a timeout);
//! - no panic;
//! - an error naming every `word` of the entry (case-insensitive; `a|b` is either): the culprit
//!   and the reason, decided from the mistake, not copied from the binary's output;
//! - no output that could be taken for a result: every folder the run wrote files into holds a
//!   `run.json` whose `status` is not `complete`, and `nodes.csv`, `metrics.json`,
//!   `frames.csv` or `fields.csv` only beside a `run.json` saying `failed` or `interrupted`.
//!
//! All entries run (two at a time), then a table of verdicts is printed and every failing entry
//! is listed. `tests/catalogue/generate.py` writes the catalogue; its base cases, each valid,
//! are run by `catalogue_base_cases_are_valid` as the control.
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

use assert_cmd::Command;
use rayon::prelude::*;
use serde::Deserialize;

/// Address-space limit of every run [KiB]: an allocation of the whole machine aborts instead.
const ULIMIT_KIB: u64 = 4 * 1024 * 1024;
/// Time limit of every run.
const TIMEOUT: Duration = Duration::from_secs(60);
/// Runs at a time.
const PARALLEL: usize = 2;
/// Files that hold results.
const RESULT_FILES: [&str; 4] = ["nodes.csv", "metrics.json", "frames.csv", "fields.csv"];

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Catalogue {
    /// the valid cases the entries change (`cases/<base>.toml`)
    bases: Vec<String>,
    entry: Vec<Entry>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Entry {
    id: String,
    #[serde(default = "default_kind")]
    kind: String,
    /// the mistake, in words
    #[serde(default)]
    what: String,
    args: Vec<String>,
    words: Vec<String>,
    stdin: Option<String>,
    /// files created in `{tmp}` before the run (relative path → content)
    #[serde(default)]
    files: BTreeMap<String, String>,
}

fn default_kind() -> String {
    "case".into()
}

fn catalogue_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/catalogue")
}

fn read_catalogue() -> Catalogue {
    let path = catalogue_dir().join("catalogue.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let c: Catalogue = toml::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let ids: BTreeSet<&str> = c.entry.iter().map(|e| e.id.as_str()).collect();
    assert_eq!(ids.len(), c.entry.len(), "entry ids must be unique");
    c
}

/// `cosserat ARGS` under the address-space limit, in `cwd`.
fn cosserat(args: &[String], cwd: &Path, umask: Option<&str>) -> Command {
    let script = match umask {
        Some(m) => format!("ulimit -v {ULIMIT_KIB}; umask {m}; exec \"$0\" \"$@\""),
        None => format!("ulimit -v {ULIMIT_KIB}; exec \"$0\" \"$@\""),
    };
    let mut c = Command::new("sh");
    c.arg("-c").arg(script).arg(env!("CARGO_BIN_EXE_cosserat")).args(args);
    c.current_dir(cwd).env_remove("RUST_BACKTRACE").env("NO_COLOR", "1").timeout(TIMEOUT);
    c
}

/// The verdict on one entry, worst first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
enum Verdict {
    AbortOrTimeout,
    Panic,
    SucceededWrongly,
    ResultLeft,
    Vague,
    Clear,
}

impl Verdict {
    const ALL: [Verdict; 6] = [
        Verdict::Clear,
        Verdict::Vague,
        Verdict::Panic,
        Verdict::AbortOrTimeout,
        Verdict::SucceededWrongly,
        Verdict::ResultLeft,
    ];

    fn as_str(self) -> &'static str {
        match self {
            Verdict::Clear => "clear",
            Verdict::Vague => "vague",
            Verdict::Panic => "panic",
            Verdict::AbortOrTimeout => "abort-or-timeout",
            Verdict::SucceededWrongly => "succeeded-wrongly",
            Verdict::ResultLeft => "result-left",
        }
    }
}

struct Outcome {
    id: String,
    kind: String,
    what: String,
    command: String,
    verdict: Verdict,
    /// why the verdict is not `clear`
    detail: String,
    /// the first line of stderr
    first_line: String,
}

/// Substitute `{cat}`, `{out}`, `{tmp}`.
fn expand(arg: &str, cat: &Path, out: &Path, tmp: &Path) -> String {
    arg.replace("{cat}", &cat.to_string_lossy())
        .replace("{out}", &out.to_string_lossy())
        .replace("{tmp}", &tmp.to_string_lossy())
}

/// Every file below `dir` (relative paths).
fn files_below(dir: &Path) -> BTreeSet<PathBuf> {
    fn walk(root: &Path, dir: &Path, acc: &mut BTreeSet<PathBuf>) {
        let Ok(rd) = std::fs::read_dir(dir) else { return };
        for e in rd.flatten() {
            let p = e.path();
            match e.file_type() {
                Ok(t) if t.is_dir() => walk(root, &p, acc),
                Ok(_) => {
                    acc.insert(p.strip_prefix(root).expect("below root").to_path_buf());
                }
                Err(_) => {}
            }
        }
    }
    let mut acc = BTreeSet::new();
    walk(dir, dir, &mut acc);
    acc
}

/// The `status` of `dir/run.json`, if the file exists (`Some("?")` if it cannot be read).
fn run_status(dir: &Path) -> Option<String> {
    let text = std::fs::read_to_string(dir.join("run.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).unwrap_or(serde_json::Value::Null);
    Some(v.get("status").and_then(|s| s.as_str()).unwrap_or("?").to_string())
}

/// What the run left that could be taken for a result: the folders (relative to `tmp`) that
/// received files without a `run.json` saying the run did not complete, and the result files
/// beside a `run.json` that does not say `failed` or `interrupted`. Files the test created
/// before the run must be there unchanged.
fn results_left(tmp: &Path, before: &BTreeMap<PathBuf, String>) -> Vec<String> {
    let mut problems = Vec::new();
    for (rel, content) in before {
        match std::fs::read_to_string(tmp.join(rel)) {
            Ok(now) if &now == content => {}
            Ok(_) => problems.push(format!("{} (the user's file) was changed", rel.display())),
            Err(_) => problems.push(format!("{} (the user's file) was removed", rel.display())),
        }
    }
    let mut by_dir: BTreeMap<PathBuf, Vec<String>> = BTreeMap::new();
    for f in files_below(tmp) {
        if before.contains_key(&f) {
            continue;
        }
        let dir = f.parent().map(Path::to_path_buf).unwrap_or_default();
        by_dir.entry(dir).or_default().push(f.file_name().expect("file").to_string_lossy().into_owned());
    }
    // A file in a sub-folder (vtk/, a sweep point) belongs to the nearest folder with a run.json.
    for (dir, names) in &by_dir {
        let owner = dir.ancestors().find(|d| tmp.join(d).join("run.json").is_file());
        let shown = if dir.as_os_str().is_empty() { ".".to_string() } else { dir.display().to_string() };
        let results: Vec<&String> = names.iter().filter(|n| RESULT_FILES.contains(&n.as_str())).collect();
        match owner.map(|d| run_status(&tmp.join(d)).unwrap_or_default()) {
            None => problems.push(format!("{shown}/ holds {} without run.json", names.join(", "))),
            Some(s) if s == "complete" => problems.push(format!("{shown}/ holds run.json with status complete")),
            Some(s) if !results.is_empty() && s != "failed" && s != "interrupted" => problems.push(format!(
                "{shown}/ holds {} beside run.json status {s:?}",
                results.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ")
            )),
            Some(_) => {}
        }
    }
    problems.sort();
    problems.dedup();
    problems
}

/// Characters that end a path in a message.
const PATH_END: &[char] = &[' ', '\t', '\n', ':', ',', ';', '`', '\'', '"', '(', ')', '[', ']'];

/// The message with every path below the catalogue or the run's folder shown as `«name»` (its
/// last component), every case name (`stems`, the file stems of the case files run) as
/// `«stem»`, and the rest in lower case, so that a word is not found in the names of the
/// entry's own files (`toml_empty.toml` does not say "empty").
fn sanitise(stderr: &str, roots: &[&Path], stems: &[String]) -> String {
    let mut s = stderr.to_string();
    for root in roots {
        let root = root.to_string_lossy().into_owned();
        let mut out = String::new();
        let mut rest = s.as_str();
        while let Some(at) = rest.find(&root) {
            out.push_str(&rest[..at]);
            let tail = &rest[at..];
            let end = tail.find(PATH_END).unwrap_or(tail.len());
            let path = tail[..end].trim_end_matches('.');
            let name = path.rsplit('/').find(|c| !c.is_empty() && *c != "..").unwrap_or("");
            out.push_str(&format!("«{name}»"));
            rest = &tail[path.len()..];
        }
        out.push_str(rest);
        s = out;
    }
    for stem in stems.iter().filter(|s| !s.is_empty()) {
        let mut out = String::new();
        let mut rest = s.as_str();
        while let Some(at) = rest.find(stem.as_str()) {
            let inside = rest[..at].ends_with('«');
            out.push_str(&rest[..at]);
            if inside {
                out.push_str(stem);
            } else {
                out.push_str(&format!("«{stem}»"));
            }
            rest = &rest[at + stem.len()..];
        }
        out.push_str(rest);
        s = out;
    }
    s.to_lowercase()
}

/// Is the alternative `alt` (lower case) in the sanitised message: in its text, or as the whole
/// name of a path, or, when it is a file name (`good.csv`), as the end of one or as its stem
/// (a case named by its name: `case good`)?
fn says(message: &str, alt: &str) -> bool {
    let mut text = String::new();
    let mut names = Vec::new();
    let mut rest = message;
    while let Some(a) = rest.find('«') {
        text.push_str(&rest[..a]);
        text.push(' ');
        let tail = &rest[a + '«'.len_utf8()..];
        let b = tail.find('»').unwrap_or(tail.len());
        names.push(&tail[..b]);
        rest = tail.get(b + '»'.len_utf8()..).unwrap_or("");
    }
    text.push_str(rest);
    let stem = alt.rsplit_once('.').map(|(s, _)| s).filter(|s| !s.is_empty());
    text.contains(alt) || names.iter().any(|n| *n == alt || (stem.is_some() && (n.ends_with(alt) || Some(*n) == stem)))
}

/// The words (any of their `|` alternatives, case-insensitive) the message does not say.
fn missing_words<'a>(words: &'a [String], message: &str) -> Vec<&'a str> {
    words.iter().filter(|w| !w.split('|').any(|alt| says(message, &alt.to_lowercase()))).map(String::as_str).collect()
}

fn run_entry(e: &Entry, cat: &Path) -> Outcome {
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("out");
    let mut before = BTreeMap::new();
    for (rel, content) in &e.files {
        let p = tmp.path().join(rel);
        std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
        std::fs::write(&p, content).expect("write");
        before.insert(PathBuf::from(rel), content.clone());
    }
    let args: Vec<String> = e.args.iter().map(|a| expand(a, cat, &out, tmp.path())).collect();
    let command = format!(
        "cosserat {}",
        e.args
            .iter()
            .map(|a| {
                let a = a.replace("{cat}", "tests/catalogue");
                if a.is_empty() || a.contains(' ') {
                    format!("'{a}'")
                } else {
                    a
                }
            })
            .collect::<Vec<_>>()
            .join(" ")
    ) + if e.stdin.is_some() { " < stdin" } else { "" };
    let mut cmd = cosserat(&args, tmp.path(), None);
    if let Some(s) = &e.stdin {
        cmd.write_stdin(s.clone());
    }
    let start = Instant::now();
    let output = cmd.output();
    let elapsed = start.elapsed();
    let (verdict, detail, first_line) = match output {
        Err(err) => (Verdict::AbortOrTimeout, format!("could not run: {err}"), String::new()),
        Ok(o) => judge(e, &args, &o, elapsed, tmp.path(), &before, cat),
    };
    Outcome { id: e.id.clone(), kind: e.kind.clone(), what: e.what.clone(), command, verdict, detail, first_line }
}

fn judge(
    e: &Entry,
    args: &[String],
    o: &Output,
    elapsed: Duration,
    tmp: &Path,
    before: &BTreeMap<PathBuf, String>,
    cat: &Path,
) -> (Verdict, String, String) {
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    let shown = stderr.replace(&*cat.to_string_lossy(), "{cat}").replace(&*tmp.to_string_lossy(), "{tmp}");
    let first_line = shown.lines().find(|l| !l.trim().is_empty()).unwrap_or("").trim().to_string();
    let first_line = if first_line.chars().count() > 300 {
        first_line.chars().take(300).collect::<String>() + " …"
    } else {
        first_line
    };
    if elapsed >= TIMEOUT {
        return (Verdict::AbortOrTimeout, format!("timeout after {} s", TIMEOUT.as_secs()), first_line);
    }
    if stderr.contains("memory allocation of") {
        return (Verdict::AbortOrTimeout, "memory allocation failed (abort)".into(), first_line);
    }
    if stderr.contains("panicked at") || stderr.contains("RUST_BACKTRACE") {
        let at = stderr.lines().find(|l| l.contains("panicked at")).unwrap_or("").trim().to_string();
        return (Verdict::Panic, at, first_line);
    }
    let Some(code) = o.status.code() else {
        return (Verdict::AbortOrTimeout, format!("killed by a signal ({})", o.status), first_line);
    };
    let left = results_left(tmp, before);
    if code == 0 {
        let detail = if left.is_empty() { "exit status 0".to_string() } else { format!("exit 0; {}", left.join("; ")) };
        return (Verdict::SucceededWrongly, detail, first_line);
    }
    let stems: Vec<String> = args
        .iter()
        .filter(|a| a.ends_with(".toml"))
        .filter_map(|a| Path::new(a).file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    let missing = missing_words(&e.words, &sanitise(&stderr, &[cat, tmp], &stems));
    let missing = if missing.is_empty() {
        String::new()
    } else {
        format!("message lacks {}", missing.iter().map(|w| format!("`{w}`")).collect::<Vec<_>>().join(", "))
    };
    if !left.is_empty() {
        let detail = [left.join("; "), missing].into_iter().filter(|s| !s.is_empty()).collect::<Vec<_>>();
        return (Verdict::ResultLeft, detail.join("; "), first_line);
    }
    if !missing.is_empty() {
        return (Verdict::Vague, missing, first_line);
    }
    (Verdict::Clear, String::new(), first_line)
}

#[test]
fn every_bad_input_of_the_catalogue_fails_clearly() {
    let cat = catalogue_dir();
    let catalogue = read_catalogue();
    assert!(catalogue.entry.len() >= 110, "the catalogue has {} entries, at least 110 expected", catalogue.entry.len());
    let pool = rayon::ThreadPoolBuilder::new().num_threads(PARALLEL).build().expect("pool");
    let inputs = files_below(&cat);
    let start = Instant::now();
    let outcomes: Vec<Outcome> = pool.install(|| catalogue.entry.par_iter().map(|e| run_entry(e, &cat)).collect());
    let wall = start.elapsed();
    let written: Vec<String> = files_below(&cat).difference(&inputs).map(|p| p.display().to_string()).collect();

    let width = outcomes.iter().map(|o| o.id.len()).max().unwrap_or(2);
    println!("\n{:<width$}  {:<10}  {:<17}  first line of stderr", "id", "kind", "verdict");
    for o in &outcomes {
        println!("{:<width$}  {:<10}  {:<17}  {}", o.id, o.kind, o.verdict.as_str(), o.first_line);
    }
    let mut kinds: BTreeMap<&str, usize> = BTreeMap::new();
    for o in &outcomes {
        *kinds.entry(o.kind.as_str()).or_default() += 1;
    }
    println!(
        "\n{} entries ({}) in {:.1} s",
        outcomes.len(),
        kinds.iter().map(|(k, n)| format!("{k} {n}")).collect::<Vec<_>>().join(", "),
        wall.as_secs_f64()
    );
    for v in Verdict::ALL {
        println!("  {:<17} {}", v.as_str(), outcomes.iter().filter(|o| o.verdict == v).count());
    }
    let mut failing: Vec<&Outcome> = outcomes.iter().filter(|o| o.verdict != Verdict::Clear).collect();
    failing.sort_by(|a, b| (a.verdict, &a.id).cmp(&(b.verdict, &b.id)));
    if !failing.is_empty() {
        println!("\nfailing entries (verdict | id | mistake | command | first line of stderr | detail):");
        for o in &failing {
            println!(
                "{} | {} | {} | {} | {} | {}",
                o.verdict.as_str(),
                o.id,
                o.what,
                o.command,
                o.first_line,
                o.detail
            );
        }
    }
    assert!(written.is_empty(), "runs wrote into the catalogue folder tests/catalogue/: {written:?}");
    // Known open entries (tests/catalogue/open.toml, each with its reason) may stay vague, wrong
    // or leave a result; never panic or abort. An open entry that is now clear must leave the list.
    let open = read_open();
    let unexpected: Vec<&&Outcome> = failing
        .iter()
        .filter(|o| !open.contains_key(&o.id) || matches!(o.verdict, Verdict::Panic | Verdict::AbortOrTimeout))
        .collect();
    let fixed: Vec<&String> =
        open.keys().filter(|id| outcomes.iter().any(|o| &o.id == *id && o.verdict == Verdict::Clear)).collect();
    println!(
        "\nopen (known, tests/catalogue/open.toml): {} of {} entries",
        failing.len() - unexpected.len(),
        outcomes.len()
    );
    assert!(fixed.is_empty(), "entries of open.toml that are now clear (remove them): {fixed:?}");
    assert!(
        unexpected.is_empty(),
        "{} of {} bad inputs are not refused clearly: {}",
        unexpected.len(),
        outcomes.len(),
        unexpected.iter().map(|o| format!("{} ({})", o.id, o.verdict.as_str())).collect::<Vec<_>>().join(", ")
    );
}

/// `tests/catalogue/open.toml`: entries known not to be clear yet, id → why.
fn read_open() -> BTreeMap<String, String> {
    #[derive(Deserialize)]
    struct Open {
        open: BTreeMap<String, String>,
    }
    let path = catalogue_dir().join("open.toml");
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    toml::from_str::<Open>(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display())).open
}

/// The control: every base case the entries change is valid and runs.
#[test]
fn catalogue_base_cases_are_valid() {
    let cat = catalogue_dir();
    let catalogue = read_catalogue();
    let mut failures = Vec::new();
    for base in &catalogue.bases {
        let tmp = tempfile::tempdir().expect("tempdir");
        let case = cat.join("cases").join(format!("{base}.toml"));
        let args = vec![
            "run".to_string(),
            case.to_string_lossy().into_owned(),
            "--out".into(),
            tmp.path().join("out").to_string_lossy().into_owned(),
            "--quiet".into(),
        ];
        let o = cosserat(&args, tmp.path(), None).output().expect("run");
        if !o.status.success() {
            failures.push(format!("{base}: {}", String::from_utf8_lossy(&o.stderr).trim()));
        }
    }
    assert!(failures.is_empty(), "base cases that do not run:\n{}", failures.join("\n"));
}

/// Result files are readable by others when the umask says so (022 → 0644).
#[test]
fn result_files_follow_the_umask() {
    use std::os::unix::fs::PermissionsExt;
    let tmp = tempfile::tempdir().expect("tempdir");
    let out = tmp.path().join("out");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/timoshenko_5pct.toml");
    let args = vec![
        "run".to_string(),
        case.to_string_lossy().into_owned(),
        "--out".into(),
        out.to_string_lossy().into_owned(),
        "--quiet".into(),
    ];
    let o = cosserat(&args, tmp.path(), Some("022")).output().expect("run");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let files = files_below(&out);
    assert!(files.len() >= 3, "{files:?}");
    let wrong: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let mode = std::fs::metadata(out.join(f)).expect("metadata").permissions().mode() & 0o777;
            (mode != 0o644).then(|| format!("{} {mode:o}", f.display()))
        })
        .collect();
    assert!(wrong.is_empty(), "files not 0644 under umask 022: {wrong:?}");
}
