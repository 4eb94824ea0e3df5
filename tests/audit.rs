//! The quick audit of the paper (`cosserat audit --quick`): every claim of `cases/paper/`
//! on the specs' short grids and clip excerpts. Each verdict must be the one its spec records
//! (reproduced, differs, refuted, not computable here — the causes in `docs/audit.md`), every
//! figure must be drawn, and the claims table (id, verdict, our numbers to two significant
//! digits) is snapshot-tested, so that a change of any judged number shows in review.
use std::path::Path;

use cosserat::audit::spec::read_spec;
use cosserat::audit::{run_audit, spec_files, AuditOptions, AuditStatus, Depth, Verdict};

#[test]
fn quick_audit_verdicts_are_the_recorded_ones() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper");
    let specs: Vec<_> =
        spec_files(&dir).expect("specs").iter().map(|f| read_spec(f, Depth::Quick).expect("spec")).collect();
    assert!(specs.len() >= 5, "the audit covers §5.1, §5.2 (three specs) and §6");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions::new(out.path().join("audit"));
    let report = run_audit(&specs, Depth::Quick, &opts, |_, _| {}).expect("audit");

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
    // Every verdict class occurs: the audit can tell them apart ("refuted" needs the reruns in
    // FreeFEM and the other reading, `--engines`, which the quick audit does not run; the
    // synthetic test of tests/audit_convergence.rs gives it).
    for v in [Verdict::Reproduced, Verdict::Differs, Verdict::NotComputable] {
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
    // Size: clip points keep their tables only (issue 30: the quick audit wrote 218 MB, the
    // full one 2.9 GB, of per-node fields and VTK); the report prints time and size.
    assert!(report.bytes <= cosserat::audit::FULL_AUDIT_BUDGET_BYTES / 4, "quick audit: {} bytes", report.bytes);
    assert_eq!(report.bytes, cosserat::audit::folder_bytes(&opts.out) - (md.len() + csv.len()) as u64);
    assert!(md.contains(&format!("{:.1} MB in this folder", report.bytes as f64 / 1e6)), "{md}");

    // The claims inventory of §5–6 names only rows the audit has, and every claim of the paper
    // judges some sentence of it; the report shows its coverage.
    let cov = report.coverage.as_ref().expect("cases/paper/inventory.csv").as_ref().expect("inventory read");
    assert!(cov.dangling.is_empty(), "inventory rows the audit does not have: {:?}", cov.dangling);
    assert!(cov.unlisted.is_empty(), "rows judging no sentence of the inventory: {:?}", cov.unlisted);
    let [rows, not_checkable, no_row] = cov.counts();
    assert_eq!(rows + not_checkable + no_row, cov.entries.len());
    assert!(md.contains(&format!("**{rows} are judged by rows above, {not_checkable} are not checkable here, {no_row} are checkable but have no row yet**")), "{md}");
    // docs/audit.md and the causes of the specs hold no number the run does not give
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(root.join("docs/audit.md")).expect("docs/audit.md");
    check_docs_numbers(&report, &doc, &spec_inputs(&dir));
    check_causes_have_no_measured_numbers(&report, &spec_inputs(&dir));
    check_causes_only_for_failed_checks(&report, &md);
    check_digits_and_whole_messages(&report);
    check_figures(&opts.out);
    let results = std::fs::read_to_string(root.join("docs/results.md")).expect("docs/results.md");
    check_docs_counts(&report, &results);

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
    let spec = read_spec(&dir.join("fig07_timoshenko.toml"), Depth::Quick).expect("spec");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions { jobs: 1, ..AuditOptions::new(out.path().join("a")) };
    run_audit(std::slice::from_ref(&spec), Depth::Quick, &opts, |_, _| {}).expect("first audit");
    let stale = opts.out.join("fig07_timoshenko/stale.txt");
    std::fs::write(&stale, "from an older audit").expect("write");
    run_audit(std::slice::from_ref(&spec), Depth::Quick, &opts, |_, _| {}).expect("second audit");
    assert!(!stale.exists(), "a file of the older audit survived");

    let foreign = out.path().join("mine");
    std::fs::create_dir_all(&foreign).expect("mkdir");
    std::fs::write(foreign.join("thesis.tex"), "keep me").expect("write");
    let err =
        run_audit(&[spec], Depth::Quick, &AuditOptions { jobs: 1, ..AuditOptions::new(foreign.clone()) }, |_, _| {})
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
    let spec = read_spec(&path, Depth::Quick).expect("spec");
    let out = tempfile::tempdir().expect("tempdir");
    let opts = AuditOptions { jobs: 1, ..AuditOptions::new(out.path().join("aps")) };
    let report = run_audit(std::slice::from_ref(&spec), Depth::Quick, &opts, |_, _| {}).expect("audit");
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
    let spec = read_spec(&path, Depth::Quick).expect("spec");
    let opts = AuditOptions { jobs: 1, ..AuditOptions::new(tmp.path().join("out")) };
    let report = run_audit(&[spec], Depth::Quick, &opts, |_, _| {}).expect("report written");
    assert!(matches!(&report.status, AuditStatus::Failed(e) if e.len() == 1 && e[0].contains("eq63_curve_rel_eror")));
    assert_eq!((report.unjudged(), report.counts()), (1, [1, 0, 0, 0]));
    let md = std::fs::read_to_string(opts.out.join("REPORT.md")).expect("REPORT.md");
    assert!(md.lines().next().unwrap_or_default().ends_with("— failed: 1 of 2 claims judged"), "{md}");
    let typo = md.lines().find(|l| l.starts_with("| typo |")).expect("typo row");
    assert!(typo.contains("*not judged*") && !typo.contains("reproduced"), "{typo}");
}

/// The numbers of a text: decimal or scientific tokens (`0.018`, `1.6e-5`, `-2.5e-3`, `361`)
/// that stand alone: not part of a name (`eq64`, `A5`, `fig05`), a section (`§5.2`), an
/// equation or reference number in brackets (`(61)`, `[12]`), a figure, remark or table
/// number. Each with its byte offset and its text.
fn numbers(text: &str) -> Vec<(usize, String)> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    let word = |c: u8| c.is_ascii_alphanumeric() || matches!(c, b'.' | b'_' | b'/' | b'^' | b'#' | b'~');
    while i < b.len() {
        let prev = |k: usize| if k == 0 { b' ' } else { b[k - 1] };
        let sign_ok = prev(i) == b'-' && !word(prev(i - 1)) && prev(i - 1) != b'-';
        let starts =
            b[i].is_ascii_digit() && (!word(prev(i)) && prev(i) != b'-' || sign_ok) && !text[..i].ends_with('§');
        if !starts {
            i += 1;
            continue;
        }
        let s = if sign_ok { i - 1 } else { i };
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
            i += 1;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
        if i + 1 < b.len() && b[i] == b'e' && (b[i + 1].is_ascii_digit() || b[i + 1] == b'-' && i + 2 < b.len()) {
            let mut j = i + 1 + usize::from(b[i + 1] == b'-');
            if j < b.len() && b[j].is_ascii_digit() {
                while j < b.len() && b[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
            }
        }
        let before = text[..s].trim_end();
        let integer = text[s..i].bytes().all(|c| c.is_ascii_digit());
        let bracketed = integer
            && ((before.ends_with('(') && text[i..].starts_with(')'))
                || (before.ends_with('[') && text[i..].starts_with(']')));
        let labelled = ["Fig.", "Figs.", "Figure", "Remark", "Table", "eq.", "Eq.", "issue", "frames", "Appendix"]
            .iter()
            .any(|w| before.ends_with(w));
        let continues = i < b.len() && (b[i].is_ascii_alphabetic() && !text[i..].starts_with("e ") || b[i] == b'_');
        if !(bracketed || labelled || continues) {
            out.push((s, text[s..i].to_string()));
        }
    }
    out
}

/// Does `shown` (our number as the report prints it) agree with `doc` (the number as
/// docs/audit.md writes it) within the rounding of both (half a unit of the last digit of each)?
fn same_within_rounding(doc: &str, shown: &str) -> bool {
    let half_unit = |s: &str| {
        let (mantissa, exp) = s.split_once('e').map_or((s, 0), |(m, e)| (m, e.parse::<i32>().unwrap_or(0)));
        let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len() as i32);
        0.5 * 10f64.powi(exp - decimals)
    };
    match (doc.parse::<f64>(), shown.parse::<f64>()) {
        (Ok(d), Ok(o)) => (d.abs() - o.abs()).abs() <= half_unit(doc) + half_unit(shown) + 1e-12 * d.abs(),
        _ => false,
    }
}

/// Every number of docs/audit.md comes from the quick audit or from the specs: a number the
/// audit measures is written `NUMBER<!--q:ID-->` and must agree, within the rounding of both,
/// with a number of claim ID's "ours" in this audit; any other number must be an input of the
/// specs (a grid value, a limit, a weight, a count the paper gives) or a small count (≤ 10).
/// So the document cannot keep a number the run no longer gives.
fn check_docs_numbers(report: &cosserat::audit::AuditReport, doc: &str, specs_text: &str) {
    let inputs: Vec<f64> = numbers(specs_text).iter().filter_map(|(_, n)| n.parse::<f64>().ok()).collect();
    let mut problems = Vec::new();
    let mut tagged = 0;
    for (at, n) in numbers(doc) {
        let tag = doc[at + n.len()..].strip_prefix("<!--q:").and_then(|t| t.split_once("-->")).map(|(id, _)| id);
        match tag {
            Some(id) => {
                tagged += 1;
                let Some(c) =
                    report.claims.iter().find(|c| c.claim.id == id || format!("{}/{}", c.spec, c.claim.id) == id)
                else {
                    problems.push(format!("{n}: no claim `{id}` in the quick audit"));
                    continue;
                };
                // the row's numbers: ours, our standard and the other engine's
                let row = [Some(&c.ours), c.standard.as_ref(), c.engines.as_ref()].into_iter().flatten();
                let row = row.cloned().collect::<Vec<_>>().join("; ");
                if !numbers(&row).iter().any(|(_, o)| same_within_rounding(&n, o)) {
                    problems.push(format!("{n} (claim {id}): the quick audit gives {row}"));
                }
            }
            None => {
                let v: f64 = n.parse().unwrap_or(f64::NAN);
                let input = inputs.iter().any(|x| (x.abs() - v.abs()).abs() <= 1e-9 * v.abs().max(1e-300));
                if !(input || (v.fract() == 0.0 && v.abs() <= 10.0)) {
                    let line = doc[..at].lines().count();
                    problems.push(format!("line {line}: {n} is neither tagged <!--q:ID--> nor an input of the specs"));
                }
            }
        }
    }
    // every tag follows a number (a tag after a word would check nothing)
    assert_eq!(tagged, doc.matches("<!--q:").count(), "a <!--q:ID--> tag of docs/audit.md follows no number");
    assert!(problems.is_empty(), "docs/audit.md:\n{}", problems.join("\n"));
}

/// The text of the specs' inputs: every line of `cases/paper/*.toml` but comments and the
/// texts written by us about results (`cause`, `not_computable`, `substitute`, `partial`).
fn spec_inputs(dir: &Path) -> String {
    let mut text = String::new();
    for f in spec_files(dir).expect("specs") {
        for line in std::fs::read_to_string(&f).expect("spec").lines() {
            let l = line.trim_start();
            let ours = ["cause", "not_computable", "substitute", "partial", "scheme"]
                .iter()
                .any(|k| l.starts_with(&format!("{k} =")));
            if !l.starts_with('#') && !ours {
                text.push_str(line);
                text.push('\n');
            }
        }
    }
    text
}

/// A cause text of a spec explains; it does not restate a measurement (which the next run may
/// change: issue 30, A8). Its numbers are the specs' inputs or small counts; our numbers are
/// in the row's "ours".
fn check_causes_have_no_measured_numbers(report: &cosserat::audit::AuditReport, inputs: &str) {
    let allowed: Vec<f64> = numbers(inputs).iter().filter_map(|(_, n)| n.parse::<f64>().ok()).collect();
    let mut problems = Vec::new();
    for c in &report.claims {
        for text in c.claim.caveats.cause.iter() {
            for (_, n) in numbers(text) {
                let v: f64 = n.parse().unwrap_or(f64::NAN);
                let ok = allowed.iter().any(|x| (x.abs() - v.abs()).abs() <= 1e-9 * v.abs().max(1e-300))
                    || (v.fract() == 0.0 && v.abs() <= 10.0);
                if !ok {
                    problems.push(format!("{}/{}: {n} in \"{text}\"", c.spec, c.claim.id));
                }
            }
        }
    }
    assert!(problems.is_empty(), "numbers in the causes of the specs that are not inputs:\n{}", problems.join("\n"));
}

/// The row of claim `id` in REPORT.md.
fn report_row<'a>(md: &'a str, id: &str) -> &'a str {
    md.lines().find(|l| l.starts_with(&format!("| {id} |"))).unwrap_or_else(|| panic!("no row {id} in REPORT.md"))
}

/// A cause explains a failed check: a row whose check holds (reproduced, not computable here)
/// shows none of its spec's cause text; the causes that name where a grid starts to fail
/// name the points of this run (eq64-2: the histories part after λl = 1e-6 of the quick grid,
/// eq65-4: 1e-8 is the first point that does not stall).
fn check_causes_only_for_failed_checks(report: &cosserat::audit::AuditReport, md: &str) {
    for c in &report.claims {
        let Some(text) = &c.claim.caveats.cause else { continue };
        let held = matches!(c.verdict, Some(Verdict::Reproduced | Verdict::NotComputable));
        if held {
            assert_eq!(c.cause, None, "{}: a check that holds has no cause", c.claim.id);
            let start: String = text.chars().take(40).collect();
            assert!(!report_row(md, &c.claim.id).contains(&start), "{} shows its cause: {start}", c.claim.id);
        }
    }
    for id in ["fig5", "t1-minimal", "ld-dominated", "ld-oscillation", "omega3-needed"] {
        let c = report.claims.iter().find(|c| c.claim.id == id).expect(id);
        assert_eq!(c.cause, None, "{id}: {}", c.ours);
    }
    let cause = |id: &str| report.claims.iter().find(|c| c.claim.id == id).and_then(|c| c.cause.clone()).expect(id);
    let eq64_2 = cause("eq64-2");
    assert!(eq64_2.starts_with("identical up to lambda_l = 1e-6; from lambda_l = 1e3 on"), "{eq64_2}");
    let eq65_4 = cause("eq65-4");
    assert!(eq65_4.starts_with("from lambda_kappa3 = 1e-8 on"), "{eq65_4}");
    assert!(report_row(md, "eq65-4").contains(&eq65_4), "REPORT.md shows the judged cause");
}

/// A value compared with a reference shows their difference (the first natural frequency
/// 206.78 rad/s against the paper's 207.0236, not 210 against 210), counts are exact, and no
/// message is cut short.
fn check_digits_and_whole_messages(report: &cosserat::audit::AuditReport) {
    let ours = |id: &str| report.claims.iter().find(|c| c.claim.id == id).map(|c| c.ours.clone()).expect(id);
    let omega0 = ours("fig5-omega0");
    assert!(omega0.starts_with("first_frequency_rad_per_s 206.7"), "{omega0}");
    assert!(omega0.contains("of 207.0236)"), "{omega0}");
    assert!(ours("eq64-2").contains("(148 iterations)"), "{}", ours("eq64-2"));
    for c in &report.claims {
        assert!(!c.ours.contains('…'), "{}: a message cut short: {}", c.claim.id, c.ours);
    }
}

/// What the figures say agrees with the runs they draw:
/// - Fig. 9: the λl runs that meet the paper's stopping rule (eq64-2: 148 iterations) are not
///   labelled "not converged"; λl = 1e3 stops at the iteration limit (3000) and is; the rule's
///   threshold (the spec's `solver.tolerance`, 3e-6) is drawn;
/// - Fig. 16: one colour scale for every frame (one colour bar);
/// - Fig. 19: the caption's pair, Table 1 against λf = 1e-20, λl = 1e-10, and nothing else;
/// - Fig. 20: every axis of the objective's terms has a unit;
/// - every figure title has a strip of its own (not in a panel's title).
fn check_figures(out: &Path) {
    let svg = |f: &str| std::fs::read_to_string(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    let texts = |s: &str| -> Vec<String> {
        let text = |t: &str| Some(t.split_once('>')?.1.split("</text>").next()?.trim().replace("&apos;", "'"));
        s.split("<text").skip(1).filter_map(text).collect()
    };
    let fig9 = texts(&svg("sec52_eq64/fig09_lambda_l.svg"));
    for converged in ["λl = 1e-20", "λl = 1e-6"] {
        assert!(fig9.iter().any(|t| t == converged), "{converged} is labelled otherwise: {fig9:?}");
    }
    assert!(fig9.iter().any(|t| t.starts_with("λl = 1e3 (not converged")), "{fig9:?}");
    assert!(fig9.iter().any(|t| t == "stopping rule: 3e-6"), "{fig9:?}");
    let fig16 = svg("sec6_worm/fig16_postures.svg");
    assert_eq!(fig16.matches("|κ| [1/mm]").count(), 1, "one colour bar in fig16");
    let fig19 = texts(&svg("sec6_worm/fig19_objectives.svg"));
    let legend: std::collections::BTreeSet<&String> = fig19.iter().filter(|t| t.starts_with("λf = ")).collect();
    let pair = ["λf = 1e-20, λl = 1e-10", "λf = 1e-3, λl = 1e-6"];
    assert_eq!(legend.into_iter().map(|s| s.as_str()).collect::<Vec<_>>(), pair, "fig19's curves");
    let fig20 = texts(&svg("sec6_worm/fig20_objectives.svg"));
    for axis in ["λf/2 ∫|f|² ds [–]", "λd/2 ∫|∂s x − d3|² ds [–]", "J [–]"] {
        assert!(fig20.iter().any(|t| t == axis), "fig20 has no axis {axis}: {fig20:?}");
    }
    for (f, title) in [
        (
            "fig05_cantilever/fig05_tip_history.svg",
            "Fig. 5: the cantilever's tip, Cosserat rod against the modal solution",
        ),
        ("sec6_worm/fig17_kymograph.svg", "Fig. 17: κ1, κ2, κ3 over time and body, Table 1"),
    ] {
        assert!(texts(&svg(f)).iter().any(|t| t == title), "{f}: the title is not a text of its own");
    }
}

/// The counts docs/results.md states of the audit ("judged N claims of the paper", the
/// verdicts, the figures) are this run's: the quick and the full audit give the same verdicts.
fn check_docs_counts(report: &cosserat::audit::AuditReport, results: &str) {
    let section = results.split("## The audit of the paper").nth(1).expect("the audit's section");
    let section = section.split("\n## ").next().unwrap_or_default().replace('\n', " ");
    let [rep, dif, refu, nc] = report.counts();
    let ours = report.claims.iter().filter(|c| c.claim.ours).count();
    let figures = report.figures.len();
    for stated in [
        format!("judged {} claims of the paper and {ours} checks of ours", report.claims.len() - ours),
        format!("{rep} reproduced, {dif} differ, {refu} refuted and {nc} not computable here"),
        format!("drew {figures} figures"),
    ] {
        assert!(
            section.contains(&stated),
            "docs/results.md, the audit of the paper, does not say \"{stated}\":\n{section}"
        );
    }
}

#[test]
fn numbers_are_found_and_compared_within_their_rounding() {
    let found: Vec<String> = numbers(
        "eq64-2 at §5.2 (61), Fig. 20, [1e-14]: 0.018 and -2.5e-3, A5, 361 iterations, [12], fig05.svg, 1e-3 I",
    )
    .into_iter()
    .map(|(_, n)| n)
    .collect();
    assert_eq!(found, ["1e-14", "0.018", "-2.5e-3", "361", "1e-3"]);
    assert!(same_within_rounding("0.018", "0.018"));
    assert!(same_within_rounding("1.6e-5", "1.64e-5"));
    assert!(!same_within_rounding("1.6e-5", "1.1e-5"));
    assert!(!same_within_rounding("0.018", "0.039"));
    assert!(same_within_rounding("360", "361"));
    assert!(!same_within_rounding("18", "4"));
}

/// A check weaker than the paper's words (`partial`) yields at best "differs": a spec that
/// expects more is refused when read, and a partial check that holds is judged "differs";
/// a statement with our words inside the quotation ("(here: …)") is refused; a check of ours
/// (`ours = true`) is counted apart from the paper's claims.
#[test]
fn partial_checks_and_our_words_are_kept_apart_from_the_paper() {
    let tmp = tempfile::tempdir().expect("tempdir");
    let case = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/timoshenko_5pct.toml");
    let spec = |expect: &str, statement: &str, extra: &str| {
        format!(
            r#"title = "partial"
section = "§5.2"
[runs.t5]
case = "{}"
[[claims]]
id = "c"
where = "§5.2, Fig. 7"
statement = "{statement}"
paper = "curves on top of each other"
check = {{ kind = "below", run = "t5", metric = "eq63_curve_rel_error", limit = 0.02 }}
expect = "{expect}"
partial = "the tip only"
cause = "partial"
[[claims]]
id = "o"
where = "§5.2, Fig. 7"
statement = "agrees very well"
paper = "ours"
check = {{ kind = "below", run = "t5", metric = "eq63_curve_rel_error", limit = 0.02 }}
expect = "reproduced"
ours = true
{extra}"#,
            case.display()
        )
    };
    let read = |text: String| {
        let path = tmp.path().join("p.toml");
        std::fs::write(&path, text).expect("spec");
        read_spec(&path, Depth::Quick)
    };
    let err = read(spec("reproduced", "agrees very well", "")).expect_err("refused");
    assert!(err.to_string().contains("at best \"differs\""), "{err}");
    let err = read(spec("differs", "agrees very well (here: 2 %)", "")).expect_err("refused");
    assert!(err.to_string().contains("verbatim"), "{err}");
    let err = read(spec("refuted", "agrees very well", "")).expect_err("refused");
    assert!(err.to_string().contains("both engines"), "{err}");
    let spec = read(spec("differs", "agrees very well", "")).expect("spec");
    let opts = AuditOptions { jobs: 1, ..AuditOptions::new(tmp.path().join("out")) };
    let report = run_audit(&[spec], Depth::Quick, &opts, |_, _| {}).expect("audit");
    // the same check, which holds (fig7-5pct): partial → differs; ours → reproduced, apart
    assert_eq!(report.claims[0].verdict, Some(Verdict::Differs), "{}", report.claims[0].ours);
    assert!(report.claims[0].ours.contains("[partial check: the tip only]"), "{}", report.claims[0].ours);
    assert_eq!(report.claims[1].verdict, Some(Verdict::Reproduced));
    assert_eq!((report.counts(), report.our_counts()), ([0, 1, 0, 0], [1, 0, 0, 0]));
    let md = std::fs::read_to_string(opts.out.join("REPORT.md")).expect("REPORT.md");
    let ours_table = md.split("## Our checks").nth(1).expect("a table of our checks");
    assert!(ours_table.contains("| o |") && !ours_table.contains("| c |"), "{md}");
}
