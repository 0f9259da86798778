//! Plots of `scion explore`'s results (plotters, SVG): for every context (scene, query kind,
//! query set, size, backend, threads, builder) the layouts measured in it as points of time per
//! query against bytes per triangle, the Pareto-optimal ones (no other layout both smaller and
//! faster) filled and joined by the frontier's steps, every point named; and for the contexts
//! with quantized layouts, their speed against error: the extra box tests of the reference
//! traversal over their decoded boxes against time per query. `index.md` lists every context
//! with its frontier and links the figures. The same rows give `scion tune` its choice
//! ([`frontier`]).

use crate::explore::Row;
use crate::CliError;
use plotters::prelude::*;
use std::collections::BTreeMap;
use std::path::Path;

/// One measured layout of a context.
#[derive(Clone, Debug)]
pub struct Point {
    /// The layout's name.
    pub layout: String,
    /// Packed bytes per triangle.
    pub bytes_per_triangle: f64,
    /// Nanoseconds per query.
    pub ns_per_query: f64,
    /// Extra box tests over the decoded boxes against the exact ones (quantized layouts).
    pub extra_box_tests: Option<f64>,
    /// Whether its answers equalled the reference's.
    pub identical: bool,
}

/// The fields that make a context.
pub const CONTEXT_FIELDS: [&str; 7] = [
    "scene", "kind", "queries", "n", "backend", "threads", "builder",
];

/// The rows grouped by context (the fields of [`CONTEXT_FIELDS`], in order), the latest row of
/// a layout winning when it was measured more than once.
pub fn contexts(rows: &[Row]) -> BTreeMap<Vec<String>, Vec<Point>> {
    let mut out: BTreeMap<Vec<String>, BTreeMap<String, Point>> = BTreeMap::new();
    for r in rows {
        let get = |f: &str| r.get(f).cloned().unwrap_or_default();
        let num = |f: &str| get(f).parse::<f64>().ok();
        let (Some(b), Some(t)) = (num("bytes_per_triangle"), num("ns_per_query")) else {
            continue;
        };
        let ctx: Vec<String> = CONTEXT_FIELDS.iter().map(|f| get(f)).collect();
        out.entry(ctx).or_default().insert(
            get("layout"),
            Point {
                layout: get("layout"),
                bytes_per_triangle: b,
                ns_per_query: t,
                extra_box_tests: num("extra_box_tests"),
                identical: get("check") == "identical",
            },
        );
    }
    out.into_iter()
        .map(|(k, v)| (k, v.into_values().collect()))
        .collect()
}

/// The Pareto-optimal points of a context (none both smaller and faster), smallest first.
pub fn frontier(points: &[Point]) -> Vec<Point> {
    let mut sorted: Vec<&Point> = points.iter().collect();
    sorted.sort_by(|a, b| {
        a.bytes_per_triangle
            .total_cmp(&b.bytes_per_triangle)
            .then(a.ns_per_query.total_cmp(&b.ns_per_query))
    });
    let mut out: Vec<Point> = Vec::new();
    for p in sorted {
        if out.last().is_none_or(|q| p.ns_per_query < q.ns_per_query) {
            out.push(p.clone());
        }
    }
    out
}

/// A context's file stem: its fields joined, safe for a file name.
fn stem(ctx: &[String]) -> String {
    ctx.iter()
        .take(6)
        .map(|f| {
            f.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect::<String>()
        })
        .collect::<Vec<_>>()
        .join("-")
}

fn title(ctx: &[String]) -> String {
    format!(
        "{}: {} ({} {}), {}, {} thread(s)",
        ctx[0], ctx[1], ctx[3], ctx[2], ctx[4], ctx[5]
    )
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::new(format!("cannot draw {}: {e}", path.display()))
}

/// Draws the Pareto plot of one context into `path` (SVG).
fn pareto_svg(path: &Path, ctx: &[String], points: &[Point]) -> Result<(), CliError> {
    let front = frontier(points);
    let (xmin, xmax, ymax) = points.iter().fold((f64::MAX, 0f64, 0f64), |(a, x, y), p| {
        (
            a.min(p.bytes_per_triangle),
            x.max(p.bytes_per_triangle),
            y.max(p.ns_per_query),
        )
    });
    // The bytes axis spans the layouts (they differ by tens of percent); time starts at 0.
    let pad = ((xmax - xmin) * 0.1).max(1.0);
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title(ctx), ("sans-serif", 20))
        .margin(20)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (xmin - pad).max(0.0)..xmax + 2.0 * pad,
            0f64..ymax * 1.15 + 1e-9,
        )
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("bytes per triangle (packed tree)")
        .y_desc("ns per query (mean of the middle runs)")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    let steps: Vec<(f64, f64)> = front
        .iter()
        .map(|p| (p.bytes_per_triangle, p.ns_per_query))
        .collect();
    chart
        .draw_series(LineSeries::new(steps, BLUE.stroke_width(2)))
        .map_err(|e| plot_err(path, e))?;
    for p in points {
        let on = front.iter().any(|q| q.layout == p.layout);
        let style = if on {
            BLUE.filled()
        } else if p.identical {
            RGBColor(150, 150, 150).filled()
        } else {
            RED.filled()
        };
        let (x, y) = (p.bytes_per_triangle, p.ns_per_query);
        chart
            .draw_series(std::iter::once(Circle::new((x, y), 5, style)))
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(std::iter::once(Text::new(
                p.layout.clone(),
                (x, y),
                ("sans-serif", 13).into_font(),
            )))
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))
}

/// Draws speed against error of the quantized layouts of one context into `path` (SVG).
fn error_svg(path: &Path, ctx: &[String], points: &[Point]) -> Result<(), CliError> {
    let q: Vec<(&Point, f64)> = points
        .iter()
        .filter_map(|p| p.extra_box_tests.map(|e| (p, 100.0 * e)))
        .collect();
    let xmax = q.iter().fold(1f64, |m, (_, e)| m.max(*e));
    let ymax = points.iter().fold(0f64, |m, p| m.max(p.ns_per_query));
    let root = SVGBackend::new(path, (900, 600)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{}: quantized layouts", title(ctx)),
            ("sans-serif", 20),
        )
        .margin(20)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..xmax * 1.2, 0f64..ymax * 1.15 + 1e-9)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("extra box tests over the decoded boxes (%)")
        .y_desc("ns per query")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (p, e) in q {
        chart
            .draw_series(std::iter::once(Circle::new(
                (e, p.ns_per_query),
                5,
                BLUE.filled(),
            )))
            .map_err(|e| plot_err(path, e))?;
        chart
            .draw_series(std::iter::once(Text::new(
                p.layout.clone(),
                (e, p.ns_per_query),
                ("sans-serif", 13).into_font(),
            )))
            .map_err(|e| plot_err(path, e))?;
    }
    root.present().map_err(|e| plot_err(path, e))
}

/// Writes every context's figures and `index.md` into `dir`; returns the files written.
pub fn write_all(rows: &[Row], dir: &Path) -> Result<usize, CliError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::new(format!("cannot create {}: {e}", dir.display())))?;
    let mut index = String::from(
        "# Design-space exploration\n\nWritten by `scion explore --plots` from its results: per \
         context, time per query against bytes per triangle of every layout measured, the Pareto \
         frontier in blue (no other layout both smaller and faster), layouts whose answers \
         differed from the reference in red.\n\n",
    );
    let mut files = 0;
    for (ctx, points) in contexts(rows) {
        let s = stem(&ctx);
        let pareto = dir.join(format!("{s}.svg"));
        pareto_svg(&pareto, &ctx, &points)?;
        files += 1;
        index.push_str(&format!("## {}\n\n![{s}]({s}.svg)\n\n", title(&ctx)));
        index.push_str(
            "| layout | bytes/triangle | ns/query | Pareto-optimal |\n|---|---:|---:|---|\n",
        );
        let front = frontier(&points);
        let mut sorted = points.clone();
        sorted.sort_by(|a, b| a.ns_per_query.total_cmp(&b.ns_per_query));
        for p in &sorted {
            index.push_str(&format!(
                "| {} | {:.1} | {:.1} | {} |\n",
                p.layout,
                p.bytes_per_triangle,
                p.ns_per_query,
                if front.iter().any(|q| q.layout == p.layout) {
                    "yes"
                } else {
                    ""
                }
            ));
        }
        index.push('\n');
        if points.iter().any(|p| p.extra_box_tests.is_some()) {
            let err = dir.join(format!("{s}-error.svg"));
            error_svg(&err, &ctx, &points)?;
            files += 1;
            index.push_str(&format!("![{s} speed against error]({s}-error.svg)\n\n"));
        }
    }
    let path = dir.join("index.md");
    std::fs::write(&path, index)
        .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))?;
    Ok(files + 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(layout: &str, b: f64, t: f64) -> Point {
        Point {
            layout: layout.into(),
            bytes_per_triangle: b,
            ns_per_query: t,
            extra_box_tests: None,
            identical: true,
        }
    }

    #[test]
    fn the_frontier_keeps_what_nothing_beats() {
        let pts = [
            p("big-fast", 80.0, 50.0),
            p("small-slow", 40.0, 90.0),
            p("dominated", 85.0, 95.0),
            p("middle", 60.0, 70.0),
            p("tie-bytes-slower", 60.0, 75.0),
        ];
        let f: Vec<String> = frontier(&pts).into_iter().map(|p| p.layout).collect();
        assert_eq!(f, ["small-slow", "middle", "big-fast"]);
    }
}
