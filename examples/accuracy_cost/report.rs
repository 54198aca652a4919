//! The report's files: the markdown tables and one log-log SVG per problem and metric.

use super::claims::Claim;
use super::problems::{order, Problem, PROBLEMS, SCHEMES};
use super::{cost_of, find_cost, precisions, series, Cost, Row};
use std::fmt::Write as _;

/// Writes `README.md` and the plots into `dir`.
pub fn write(
    dir: &str,
    rows: &[Row],
    costs: &[Cost],
    claims: &[Claim],
    seconds: f64,
    source: &str,
) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let precs = precisions(rows);
    let mut md = String::new();
    let _ = writeln!(md, "# What accuracy costs in time\n");
    let _ = writeln!(
        md,
        "Written by `cargo run --release --example accuracy_cost` at {} ({seconds:.0} s for {}, \
on {}), from kernel source sha256 `{source}` (every file under src/ and Cargo.toml; CI's \
`python3 .ci/accuracy_source.py` fails when the source no longer matches). Errors are \
against exact solutions; ns per particle-step is the step_cost measurement of each scheme \
(the 2D step_cost scene, 131072 particles, with the problem's effect: median of 5 runs of 4 \
steps, the widest instance the CPU has), on one worker and on two (`step_cost --threads 2`). \
The cost to reach an error is one worker's time for the whole run, `ns x particles x steps`, \
interpolated log-log along the refinement series; `<=` when the coarsest run is already below \
it, `-` when the finest is not.\n",
        commit(),
        precs.join(" and "),
        cpu()
    );
    let _ = writeln!(md, "## Schemes\n\n| scheme | setting |\n|---|---|");
    for s in SCHEMES {
        let _ = writeln!(md, "| {} | {} |", s.label, s.describe());
    }
    let _ = writeln!(md, "\n## Claims (checked, also by `cargo test`)\n");
    for c in claims {
        let _ = writeln!(
            md,
            "- **{}**: {}. {}",
            if c.holds { "holds" } else { "FAILS" },
            c.text,
            c.detail
        );
    }
    summary(&mut md, rows, costs, &precs);
    for p in PROBLEMS {
        let _ = writeln!(md, "\n## {}\n\n{}\n", p.title, p.about);
        for (m, metric) in p.metrics.iter().enumerate() {
            let file = format!("{}-{}.svg", p.key, metric.replace(' ', "-"));
            let points = plot_points(p, m, rows, costs, &precs);
            std::fs::write(
                format!("{dir}/{file}"),
                svg(&format!("{}: {metric} error", p.title), &points),
            )?;
            let _ = writeln!(md, "![{} {metric}]({file})\n", p.title);
            table(&mut md, p, m, rows, costs, &precs);
        }
    }
    std::fs::write(format!("{dir}/README.md"), md)
}

/// One line per problem and metric: the cheapest scheme to reach the stated error, the lowest
/// error at the finest resolution, and the Pareto front of the plot.
fn summary(md: &mut String, rows: &[Row], costs: &[Cost], precs: &[String]) {
    let _ = writeln!(
        md,
        "\n## Summary\n\n| problem | metric | cheapest to reach the stated error (ms) | lowest \
error at the finest resolution | Pareto front (cost, then error) |\n|---|---|---|---|---|"
    );
    for p in PROBLEMS {
        for (m, metric) in p.metrics.iter().enumerate() {
            let mut cheapest: Option<(f64, String)> = None;
            for s in SCHEMES {
                for prec in precs {
                    let Some(ns) = cost_of(costs, s.label, prec, p.declares) else {
                        continue;
                    };
                    let runs = runs_of(rows, p, s.label, prec);
                    if let Some(v) = reach_ms(&work_series(&runs, m, ns), p.targets[m]) {
                        if cheapest.as_ref().is_none_or(|c| v < c.0) {
                            cheapest = Some((v, format!("{} {prec}", s.label)));
                        }
                    }
                }
            }
            let points = plot_points(p, m, rows, costs, precs);
            let best = points.iter().min_by(|a, b| a.y.total_cmp(&b.y));
            let front: Vec<String> = pareto(&points)
                .iter()
                .map(|&i| {
                    format!(
                        "{} ({:.0} ns, {:.1e})",
                        points[i].label, points[i].x, points[i].y
                    )
                })
                .collect();
            let _ = writeln!(
                md,
                "| {} | {metric} | {} | {} | {} |",
                p.title,
                cheapest.map_or(
                    format!("none reaches {:e}", p.targets[m]),
                    |(v, l)| format!("{l}: {} to reach {:e}", ms(v), p.targets[m])
                ),
                best.map_or("-".into(), |b| format!("{} {:.1e}", b.label, b.y)),
                front.join(", ")
            );
        }
    }
}

/// The commit the report was made from, as `git describe --always --dirty` names it (a
/// `-dirty` suffix: with uncommitted changes), if git is there to say.
fn commit() -> String {
    std::process::Command::new("git")
        .args(["describe", "--always", "--dirty"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .map(|s| format!("commit {}", s.trim()))
        .unwrap_or_else(|| "an unknown commit".into())
}

/// The CPU's model name, if the system says.
fn cpu() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "an unnamed CPU".into())
}

/// The runs of one problem, scheme and precision, coarsest first.
fn runs_of<'a>(rows: &'a [Row], p: &Problem, scheme: &str, prec: &str) -> Vec<&'a Row> {
    let mut runs: Vec<&Row> = rows
        .iter()
        .filter(|r| r.problem == p.key && r.scheme == scheme && r.precision == prec)
        .collect();
    runs.sort_by_key(|r| r.cells);
    runs
}

/// (error of metric `m`, single-core ms of the run) along a refinement series, at `ns` per
/// particle-step: ns x particles x steps.
fn work_series(runs: &[&Row], m: usize, ns: f64) -> Vec<(f64, f64)> {
    runs.iter()
        .map(|r| (r.errors[m], ns * r.particles as f64 * r.steps as f64 * 1e-6))
        .collect()
}

/// The cost (ms) to reach `target` along a refinement series of (error, ms), coarsest first:
/// log-log interpolation between the two runs that bracket it.
pub fn cost_to_reach(series: &[(f64, f64)], target: f64) -> String {
    match (
        series.iter().position(|&(e, _)| e <= target),
        reach_ms(series, target),
    ) {
        (Some(0), Some(v)) => format!("<= {}", ms(v)),
        (_, Some(v)) => ms(v),
        _ => "-".into(),
    }
}

/// The cost (ms) to reach `target` (an upper bound when the coarsest run already does), or
/// None if no run of the series does.
fn reach_ms(series: &[(f64, f64)], target: f64) -> Option<f64> {
    let k = series.iter().position(|&(e, _)| e <= target)?;
    if k == 0 {
        return Some(series[0].1);
    }
    let ((e0, c0), (e1, c1)) = (series[k - 1], series[k]);
    if !e0.is_finite() {
        return Some(c1);
    }
    let f = (e0 / target).ln() / (e0 / e1).ln();
    Some((c0.ln() + f * (c1.ln() - c0.ln())).exp())
}

fn ms(v: f64) -> String {
    if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

fn table(md: &mut String, p: &Problem, m: usize, rows: &[Row], costs: &[Cost], precs: &[String]) {
    let target = p.targets[m];
    let _ = writeln!(
        md,
        "| problem | scheme | precision | cells per unit length | {} error | order | ns per \
particle-step, 1 / 2 workers | ms to reach {target:e} |\n|---|---|---|---:|---:|---:|---:|---:|",
        p.metrics[m]
    );
    for s in SCHEMES {
        for prec in precs {
            let cost = find_cost(costs, s.label, prec, p.declares);
            let ns = cost.map(|c| c.ns);
            let runs = runs_of(rows, p, s.label, prec);
            let reach = ns.map_or("n/a".into(), |ns| {
                cost_to_reach(&work_series(&runs, m, ns), target)
            });
            for (k, r) in runs.iter().enumerate() {
                let e = r.errors[m];
                let ord = if k > 0 {
                    format!(
                        "{:.2}",
                        order((runs[k - 1].cells, runs[k - 1].errors[m]), (r.cells, e))
                    )
                } else {
                    String::new()
                };
                let _ = writeln!(
                    md,
                    "| {} | {} | {prec} | {} | {} | {ord} | {} | {} |",
                    p.key,
                    s.label,
                    r.cells,
                    if e.is_nan() {
                        "failed".into()
                    } else {
                        format!("{e:.3e}")
                    },
                    cost.map_or("n/a".into(), |c| format!("{:.1} / {:.1}", c.ns, c.ns_two)),
                    if k == 0 { reach.as_str() } else { "" }
                );
            }
        }
    }
    let _ = writeln!(md);
}

/// One plotted scheme: label, ns per particle-step, error at the finest level, f32 or not.
pub struct Point {
    pub label: String,
    pub x: f64,
    pub y: f64,
    pub filled: bool,
}

fn plot_points(
    p: &Problem,
    m: usize,
    rows: &[Row],
    costs: &[Cost],
    precs: &[String],
) -> Vec<Point> {
    let mut points = vec![];
    for s in SCHEMES {
        for prec in precs {
            let (Some(ns), Some(&(_, e))) = (
                cost_of(costs, s.label, prec, p.declares),
                series(rows, p.key, m, s.label, prec).last(),
            ) else {
                continue;
            };
            if e.is_finite() {
                points.push(Point {
                    label: if prec == "f32" {
                        s.label.to_string()
                    } else {
                        format!("{} {prec}", s.label)
                    },
                    x: ns,
                    y: e.max(1e-16),
                    filled: prec == "f32",
                });
            }
        }
    }
    points
}

/// Indices of the points no other point beats in both cost and error, by cost.
pub fn pareto(points: &[Point]) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..points.len()).collect();
    idx.sort_by(|&a, &b| {
        points[a]
            .x
            .total_cmp(&points[b].x)
            .then(points[a].y.total_cmp(&points[b].y))
    });
    let mut front = vec![];
    let mut best = f64::INFINITY;
    for i in idx {
        if points[i].y < best {
            best = points[i].y;
            front.push(i);
        }
    }
    front
}

/// A log-log scatter plot of `points`, the Pareto front joined and ringed.
fn svg(title: &str, points: &[Point]) -> String {
    let (w, h, left, right, top, bottom) = (900.0, 600.0, 70.0, 190.0, 40.0, 50.0);
    let decade = |v: f64, up: bool| {
        if up {
            v.log10().ceil()
        } else {
            v.log10().floor()
        }
    };
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in points {
        x0 = x0.min(p.x);
        x1 = x1.max(p.x);
        y0 = y0.min(p.y);
        y1 = y1.max(p.y);
    }
    if points.is_empty() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1.0, 10.0);
    }
    // y spans whole decades.
    // x spans its points with 0.05 decade to spare, at least 0.3 decade.
    let (lx0, lx1) = (
        x0.log10() - 0.05,
        (x1.log10() + 0.05).max(x0.log10() + 0.25),
    );
    // A fifth of a decade above the highest point keeps its label inside the frame.
    let (ly0, ly1) = (
        decade(y0, false),
        decade(y1 * 1.6, true).max(decade(y0, false) + 1.0),
    );
    let px = |x: f64| left + (x.log10() - lx0) / (lx1 - lx0) * (w - left - right);
    let py = |y: f64| top + (ly1 - y.log10()) / (ly1 - ly0) * (h - top - bottom);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
viewBox=\"0 0 {w} {h}\" font-family=\"sans-serif\" font-size=\"11\">\n\
<rect width=\"{w}\" height=\"{h}\" fill=\"white\"/>\n\
<text x=\"{}\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">{}</text>",
        w / 2.0,
        escape(title)
    );
    // Frame, grid and ticks.
    let _ = writeln!(
        s,
        "<rect x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>",
        w - left - right,
        h - top - bottom
    );
    let mut e = ly0;
    while e <= ly1 + 1e-9 {
        let y = py(10f64.powf(e));
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" x2=\"{}\" y1=\"{y:.1}\" y2=\"{y:.1}\" stroke=\"#ddd\"/>\
<text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{e}</text>",
            w - right,
            left - 4.0,
            y + 4.0
        );
        e += 1.0;
    }
    // A grid line at every integer multiple of a power of ten, labelled at 1, 2, 3 and 5.
    for d in -1..5 {
        for v in 1..10 {
            let x = v as f64 * 10f64.powi(d);
            let l = x.log10();
            if l >= lx0 && l <= lx1 {
                let xp = px(x);
                let _ = write!(
                    s,
                    "<line x1=\"{xp:.1}\" x2=\"{xp:.1}\" y1=\"{top}\" y2=\"{}\" stroke=\"#eee\"/>",
                    h - bottom
                );
                if [1, 2, 3, 5].contains(&v) {
                    let _ = write!(
                        s,
                        "<text x=\"{xp:.1}\" y=\"{}\" text-anchor=\"middle\">{x}</text>",
                        h - bottom + 16.0
                    );
                }
                s.push('\n');
            }
        }
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">ns per particle-step (log)</text>\n\
<text transform=\"translate(16 {}) rotate(-90)\" text-anchor=\"middle\">error at the finest \
resolution (log)</text>",
        left + (w - left - right) / 2.0,
        h - 12.0,
        top + (h - top - bottom) / 2.0
    );
    // The Pareto front: a dashed staircase through its points, each ringed.
    let front = pareto(points);
    if !front.is_empty() {
        let mut d = String::new();
        for (k, &i) in front.iter().enumerate() {
            let (x, y) = (px(points[i].x), py(points[i].y));
            if k == 0 {
                let _ = write!(d, "M{x:.1},{y:.1}");
            } else {
                let _ = write!(d, " H{x:.1} V{y:.1}");
            }
        }
        let _ = writeln!(
            s,
            "<path d=\"{d}\" fill=\"none\" stroke=\"#c00\" stroke-dasharray=\"5,3\"/>"
        );
        for &i in &front {
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"8\" fill=\"none\" stroke=\"#c00\"/>",
                px(points[i].x),
                py(points[i].y)
            );
        }
    }
    // Labels go right of their point, moved up or down in line steps until they overlap no
    // label placed before them (widths estimated at 5.6 px per character).
    let mut placed: Vec<(f64, f64, f64, f64)> = vec![];
    for p in points {
        let (x, y) = (px(p.x), py(p.y));
        if p.filled {
            let _ = writeln!(
                s,
                "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"4\" fill=\"#1f5fa8\"/>"
            );
        } else {
            let _ = writeln!(
                s,
                "<rect x=\"{:.1}\" y=\"{:.1}\" width=\"8\" height=\"8\" fill=\"none\" stroke=\"#2a8a3a\" \
stroke-width=\"1.5\"/>",
                x - 4.0,
                y - 4.0
            );
        }
        let width = 5.6 * p.label.chars().count() as f64;
        let overlaps = |ly: f64| {
            placed
                .iter()
                .any(|&(a, b, c, d)| x + 7.0 < c && a < x + 7.0 + width && ly - 10.0 < d && b < ly)
        };
        let mut ly = y + 3.0;
        for k in 0..24 {
            let dy = 11.0 * ((k + 1) / 2) as f64 * if k % 2 == 1 { -1.0 } else { 1.0 };
            if y + 3.0 + dy > top + 10.0 && !overlaps(y + 3.0 + dy) {
                ly = y + 3.0 + dy;
                break;
            }
        }
        placed.push((x + 7.0, ly - 10.0, x + 7.0 + width, ly));
        if (ly - y - 3.0).abs() > 1.0 {
            let _ = writeln!(
                s,
                "<line x1=\"{:.1}\" y1=\"{y:.1}\" x2=\"{:.1}\" y2=\"{:.1}\" stroke=\"#999\" stroke-width=\"0.5\"/>",
                x + 4.0,
                x + 7.0,
                ly - 4.0
            );
        }
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{ly:.1}\" font-size=\"10\">{}</text>",
            x + 7.0,
            escape(&p.label)
        );
    }
    // Legend.
    let lx = w - right + 12.0;
    let _ = writeln!(
        s,
        "<circle cx=\"{}\" cy=\"{}\" r=\"4\" fill=\"#1f5fa8\"/><text x=\"{}\" y=\"{}\">f32</text>\n\
<rect x=\"{}\" y=\"{}\" width=\"8\" height=\"8\" fill=\"none\" stroke=\"#2a8a3a\" stroke-width=\"1.5\"/>\
<text x=\"{}\" y=\"{}\">f64</text>\n\
<circle cx=\"{}\" cy=\"{}\" r=\"8\" fill=\"none\" stroke=\"#c00\"/><text x=\"{}\" y=\"{}\">Pareto front</text>",
        lx + 4.0,
        top + 10.0,
        lx + 14.0,
        top + 14.0,
        lx,
        top + 26.0,
        lx + 14.0,
        top + 34.0,
        lx + 4.0,
        top + 50.0,
        lx + 16.0,
        top + 54.0
    );
    s.push_str("</svg>\n");
    s
}

fn escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
