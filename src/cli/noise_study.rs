//! `cosserat noise-study SPEC --out DIR`: the noise study of `cosserat::study` — synthetic
//! recordings at several noise levels reconstructed beside a smoothing spline — with its table
//! (`noise_study.csv`) and figure (`noise_study.svg`).
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, Result};

use cosserat::figures::panels::render_panels_svg;
use cosserat::figures::plot::{LinePlot, Scale, Series};
use cosserat::io::write_atomic;
use cosserat::study::{centreline_name, recovered_name, run_study, Depth, StudyRow, StudySpec, SPLINE};

use super::progress::{Progress, Visibility};

/// `cosserat noise-study`.
#[derive(clap::Args, Debug)]
pub struct NoiseStudyArgs {
    /// The study spec (TOML), e.g. cases/bench/noise_study.toml
    spec: PathBuf,
    /// Output folder: corpora/, cases/, runs/ (one batch per mesh, noise level and variant),
    /// noise_study.csv (one row per mesh, noise level, method and recording) and noise_study.svg;
    /// it must be new or empty unless --force
    #[arg(long)]
    out: PathBuf,
    /// The spec's [quick] plan: fewer noise levels, recordings and frames
    #[arg(long)]
    quick: bool,
    /// Replace a folder that is not empty
    #[arg(long)]
    force: bool,
    /// Do not show progress
    #[arg(long)]
    quiet: bool,
}

pub fn cmd_noise_study(a: NoiseStudyArgs) -> Result<ExitCode> {
    let spec = StudySpec::read(&a.spec)?;
    if a.out.exists() && std::fs::read_dir(&a.out).map(|mut d| d.next().is_some()).unwrap_or(true) {
        anyhow::ensure!(a.force, "noise-study: {} is not empty; choose a new --out or pass --force", a.out.display());
        std::fs::remove_dir_all(&a.out).with_context(|| format!("cannot remove {}", a.out.display()))?;
    }
    std::fs::create_dir_all(&a.out).with_context(|| format!("cannot create {}", a.out.display()))?;
    let depth = if a.quick { Depth::Quick } else { Depth::Full };
    let plan = spec.plan(depth);
    let total = spec.meshes.len() * plan.noise_m.len() * spec.variants.len();
    let pb = Progress::new(&spec.title, "batches", total, Visibility::unless(a.quiet));
    let rows =
        run_study(&spec, &a.out, depth, |_| pb.inc()).with_context(|| format!("noise study {}", a.spec.display()))?;
    pb.finish();
    let svg = figure(&spec, &rows)?;
    write_atomic(&a.out.join("noise_study.svg"), svg.as_bytes())?;
    print!("{}", table(&spec, &rows));
    eprintln!("wrote {}/noise_study.csv and noise_study.svg", a.out.display());
    Ok(ExitCode::SUCCESS)
}

/// Per mesh, σ and method: the range over the recordings of the median and the worst frame,
/// and the reconstructed fraction.
struct Cell {
    median: (f64, f64),
    worst: (f64, f64),
    reconstructed: usize,
    frames: usize,
    noise_estimate: Option<(f64, f64)>,
    lambda_g: Option<(f64, f64)>,
}

fn range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| if x.is_finite() { (a.min(x), b.max(x)) } else { (a, b) })
}

/// A cell's key: the mesh (nodes, shape changes' RMS as bits), the method, σ as bits.
type CellKey = ((usize, u64), String, u64);

fn cells(rows: &[StudyRow]) -> BTreeMap<CellKey, Cell> {
    let mut groups: BTreeMap<CellKey, Vec<&StudyRow>> = BTreeMap::new();
    for r in rows {
        groups
            .entry(((r.nodes, r.shape_noise_m.to_bits()), r.method.clone(), r.noise_m.to_bits()))
            .or_default()
            .push(r);
    }
    let opt = |r: (f64, f64)| if r.0.is_finite() { Some(r) } else { None };
    groups
        .into_iter()
        .map(|(k, g)| {
            let cell = Cell {
                median: range(g.iter().map(|r| r.bending_err_median)),
                worst: range(g.iter().map(|r| r.bending_err_worst)),
                reconstructed: g.iter().map(|r| r.frames_reconstructed).sum(),
                frames: g.iter().map(|r| r.frames).sum(),
                noise_estimate: opt(range(g.iter().filter_map(|r| r.noise_estimate_m))),
                lambda_g: opt(range(g.iter().filter_map(|r| r.lambda_g))),
            };
            (k, cell)
        })
        .collect()
}

fn methods(spec: &StudySpec) -> Vec<(String, String)> {
    let mut m: Vec<(String, String)> = Vec::new();
    for v in &spec.variants {
        m.push((v.name.clone(), v.label.clone()));
        if v.recovered {
            m.push((recovered_name(&v.name), format!("{}, nodal recovery", v.label)));
        }
        if v.centreline {
            m.push((centreline_name(&v.name), format!("{}, its centreline's curvature", v.label)));
        }
    }
    m.push((SPLINE.into(), "smoothing spline (GCV)".into()));
    m
}

/// A mesh as the table names it: `33` or `33, shape changes 5 µm`.
fn mesh_name(nodes: usize, shape_noise_m: f64) -> String {
    match shape_noise_m > 0.0 {
        true => format!("{nodes}, shape changes {} µm", shape_noise_m * 1e6),
        false => nodes.to_string(),
    }
}

/// The markdown table of the study (docs/results.md).
fn table(spec: &StudySpec, rows: &[StudyRow]) -> String {
    let cells = cells(rows);
    let span = |(a, b): (f64, f64)| if a.is_finite() { format!("{a:.3}–{b:.3}") } else { "–".into() };
    let span_e = |r: Option<(f64, f64)>| r.map_or("".into(), |(a, b)| format!("{a:.2e}–{b:.2e}"));
    let mut s = String::from("| nodes | σ [µm] | method | frames reconstructed | bending error, median | worst frame | σ estimated [µm] | λg chosen |\n|---|---|---|---|---|---|---|---|\n");
    for (((nodes, shape), method, bits), c) in &cells {
        let nodes = mesh_name(*nodes, f64::from_bits(*shape));
        let label = methods(spec).into_iter().find(|m| &m.0 == method).map_or(method.clone(), |m| m.1);
        let est = c.noise_estimate.map(|(a, b)| (a * 1e6, b * 1e6));
        s += &format!(
            "| {nodes} | {} | {label} | {} / {} | {} | {} | {} | {} |\n",
            (f64::from_bits(*bits) * 1e12).round() / 1e6,
            c.reconstructed,
            c.frames,
            span(c.median),
            span(c.worst),
            est.map_or("".into(), |(a, b)| format!("{a:.3}–{b:.3}")),
            span_e(c.lambda_g)
        );
    }
    s
}

/// Per mesh: the bending error's median and worst frame (each the worst recording's) and the
/// reconstructed fraction against σ, for the variants marked `plot` and the spline.
fn figure(spec: &StudySpec, rows: &[StudyRow]) -> Result<String> {
    let cells = cells(rows);
    let shown: Vec<(String, String)> = methods(spec)
        .into_iter()
        .filter(|(name, _)| name == SPLINE || spec.variants.iter().any(|v| &v.name == name && v.plot))
        .collect();
    let mut panels = Vec::new();
    for mesh in &spec.meshes {
        let panel = |what: &str, y_label: &str, y_scale: Scale| LinePlot {
            title: match mesh.shape_noise_m > 0.0 {
                true => format!("{} nodes, shape changes {} µm: {what}", mesh.nodes, mesh.shape_noise_m * 1e6),
                false => format!("{} nodes: {what}", mesh.nodes),
            },
            x_label: "noise σ per coordinate [µm] (σ = 0: see the table)".into(),
            y_label: y_label.into(),
            x_scale: Scale::Log,
            y_scale,
            ..LinePlot::default()
        };
        let mut median = panel("bending error, median frame", "relative L² error of |κ| [–]", Scale::Log);
        let mut worst = panel("bending error, worst frame", "relative L² error of |κ| [–]", Scale::Log);
        let mut frac = panel("frames reconstructed", "fraction of frames [–]", Scale::Linear);
        for (name, label) in &shown {
            let pts: Vec<(f64, &Cell)> = cells
                .iter()
                .filter(|((n, m, _), _)| *n == (mesh.nodes, mesh.shape_noise_m.to_bits()) && m == name)
                .map(|((_, _, b), c)| (f64::from_bits(*b) * 1e6, c))
                .filter(|(s, _)| *s > 0.0)
                .collect();
            let x: Vec<f64> = pts.iter().map(|p| p.0).collect();
            let series = |y: Vec<f64>| Series::new(label.clone(), x.clone(), y);
            median.series.push(series(pts.iter().map(|p| p.1.median.1).collect()));
            worst.series.push(series(pts.iter().map(|p| p.1.worst.1).collect()));
            frac.series.push(series(pts.iter().map(|p| p.1.reconstructed as f64 / p.1.frames.max(1) as f64).collect()));
        }
        panels.extend([median, worst, frac]);
    }
    Ok(render_panels_svg(&panels, 3)?)
}
