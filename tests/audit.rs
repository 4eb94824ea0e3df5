//! The quick audit of the paper (`cosserat audit --quick`): every claim of `cases/paper/`
//! on the specs' short grids and clip excerpts. Each verdict must be the one its spec records
//! (reproduced, differs, refuted, not computable here — the causes in `docs/audit.md`), every
//! figure must be drawn, and the claims table (id, verdict, our numbers to two significant
//! digits) is snapshot-tested, so that a change of any judged number shows in review.
use std::path::Path;

use cosserat::audit::spec::read_spec;
use cosserat::audit::{run_audit, spec_files, AuditOptions, AuditStatus, Verdict};

#[test]
fn quick_audit_verdicts_are_the_recorded_ones() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper");
    let specs: Vec<_> = spec_files(&dir).expect("specs").iter().map(|f| read_spec(f, true).expect("spec")).collect();
    assert!(specs.len() >= 5, "the audit covers §5.1, §5.2 (three specs) and §6");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions { out: out.path().join("audit"), jobs: 0 };
    let report = run_audit(&specs, true, &opts, |_, _| {}).expect("audit");

    let wrong: Vec<String> = report
        .claims
        .iter()
        .filter(|c| c.verdict != Some(c.claim.expect))
        .map(|c| {
            format!(
                "{} ({}): {} ≠ {}; ours: {}",
                c.claim.id,
                c.spec,
                c.verdict.map_or("not judged", |v| v.as_str()),
                c.claim.expect.as_str(),
                c.ours
            )
        })
        .collect();
    assert!(wrong.is_empty(), "verdicts that changed:\n{}", wrong.join("\n"));
    // Every verdict class occurs: the audit can tell them apart.
    for v in [Verdict::Reproduced, Verdict::Differs, Verdict::Refuted, Verdict::NotComputable] {
        assert!(report.claims.iter().any(|c| c.verdict == Some(v)), "no claim is {}", v.as_str());
    }
    // Every figure of every spec was drawn, and the report names each.
    let planned: usize = specs.iter().map(|s| s.plots.len()).sum();
    assert_eq!(report.figures.len(), planned, "figures drawn: {:?}", report.figures);
    let md = std::fs::read_to_string(opts.out.join("REPORT.md")).expect("REPORT.md");
    for f in &report.figures {
        assert!(opts.out.join(f).is_file(), "{f} missing");
        assert!(md.contains(f.as_str()), "REPORT.md does not name {f}");
    }
    let csv = std::fs::read_to_string(opts.out.join("report.csv")).expect("report.csv");
    assert_eq!(csv.lines().count(), report.claims.len() + 1);

    let table: Vec<String> = report
        .claims
        .iter()
        .map(|c| format!("{}/{}: {} | {}", c.spec, c.claim.id, c.verdict.map_or("not judged", |v| v.as_str()), c.ours))
        .collect();
    insta::assert_snapshot!("quick_audit_claims", table.join("\n"));
}

/// A second audit into the same folder replaces the first whole; a folder that is not an
/// audit's is refused, not emptied.
#[test]
fn audit_folder_is_replaced_whole_or_refused() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper");
    let spec = read_spec(&dir.join("fig07_timoshenko.toml"), true).expect("spec");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions { out: out.path().join("a"), jobs: 1 };
    run_audit(std::slice::from_ref(&spec), true, &opts, |_, _| {}).expect("first audit");
    let stale = opts.out.join("fig07_timoshenko/stale.txt");
    std::fs::write(&stale, "from an older audit").expect("write");
    run_audit(std::slice::from_ref(&spec), true, &opts, |_, _| {}).expect("second audit");
    assert!(!stale.exists(), "a file of the older audit survived");

    let foreign = out.path().join("mine");
    std::fs::create_dir_all(&foreign).expect("mkdir");
    std::fs::write(foreign.join("thesis.tex"), "keep me").expect("write");
    let err = run_audit(&[spec], true, &AuditOptions { out: foreign.clone(), jobs: 1 }, |_, _| {})
        .err()
        .expect("a foreign folder is refused");
    assert!(err.to_string().contains("not an audit folder"), "{err}");
    assert!(foreign.join("thesis.tex").is_file());
}

/// The accuracy-per-second spec (`cases/bench/`): the trade-off CSV beside its figure has one
/// row per grid point with the solve's wall time and the error, and the error falls at second
/// order (Appendix A) from 250 to 1000 steps, as its claim says.
#[test]
fn tradeoff_figure_lists_every_point_with_its_time_and_error() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/bench/accuracy_per_second.toml");
    let spec = read_spec(&path, true).expect("spec");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions { out: out.path().join("aps"), jobs: 1 };
    let report = run_audit(std::slice::from_ref(&spec), true, &opts, |_, _| {}).expect("audit");
    assert!(report.claims.iter().all(|c| c.verdict == Some(Verdict::Reproduced)), "{:?}", report.claims[0].ours);
    let csv = std::fs::read_to_string(opts.out.join("accuracy_per_second/accuracy_per_second.csv")).expect("csv");
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplitn(3, ',').take(2).map(|v| v.parse::<f64>().expect("number")).collect())
        .collect();
    assert_eq!(csv.lines().next(), Some("point,status,wall_time_s,modal_tip_rel_error"));
    assert_eq!(rows.len(), 2, "{csv}");
    // rows: [error, time]; 4x the steps: more time, and the error at most 1/8
    assert!(rows.iter().all(|r| r[0] > 0.0 && r[1] > 0.0), "{csv}");
    assert!(rows[1][0] < rows[0][0] / 8.0, "{csv}");
    assert!(opts.out.join("accuracy_per_second/accuracy_per_second.svg").is_file());
}

/// A failed audit (here: a claim reading a metric no point reports, a typo in its spec) writes
/// REPORT.md headed "failed: N of M claims judged", with the claim not judged and counted
/// apart, not a verdict drawn from a number that does not exist.
#[test]
fn a_failed_audit_says_so_and_judges_nothing_it_could_not() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/timoshenko_5pct.toml");
    let spec = format!(
        r#"title = "failed audit"
section = "§5.2"
[runs.t5]
case = "{}"
[[claims]]
id = "good"
where = "§5.2, Fig. 7"
statement = "agrees very well"
paper = "curves on top of each other"
check = {{ kind = "below", run = "t5", metric = "eq63_curve_rel_error", limit = 0.02 }}
expect = "reproduced"
[[claims]]
id = "typo"
where = "§5.2, Fig. 7"
statement = "agrees very well"
paper = "curves on top of each other"
check = {{ kind = "below", run = "t5", metric = "eq63_curve_rel_eror", limit = 0.02 }}
expect = "reproduced"
"#,
        case.display()
    );
    let path = tmp.path().join("failed.toml");
    std::fs::write(&path, spec).expect("spec");
    let spec = read_spec(&path, true).expect("spec");
    let opts = AuditOptions { out: tmp.path().join("out"), jobs: 1 };
    let report = run_audit(&[spec], true, &opts, |_, _| {}).expect("report written");
    assert!(matches!(&report.status, AuditStatus::Failed(e) if e.len() == 1 && e[0].contains("eq63_curve_rel_eror")));
    assert_eq!((report.unjudged(), report.counts()), (1, [1, 0, 0, 0]));
    let md = std::fs::read_to_string(opts.out.join("REPORT.md")).expect("REPORT.md");
    assert!(md.lines().next().unwrap_or_default().ends_with("— failed: 1 of 2 claims judged"), "{md}");
    let typo = md.lines().find(|l| l.starts_with("| typo |")).expect("typo row");
    assert!(typo.contains("*not judged*") && !typo.contains("reproduced"), "{typo}");
}
