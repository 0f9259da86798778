//! Plots of `scion explore`'s results (plotters): for every context (scene, query kind,
//! query set, size, backend, threads, builder) the layouts measured in it as points of time per
//! query against bytes per triangle, the Pareto-optimal ones (no other layout both smaller and
//! faster) filled and joined by the frontier's steps, every point named; and for the contexts
//! with quantized layouts, their speed against error: the extra box tests of the reference
//! traversal over their decoded boxes against time per query. `index.md` lists every context
//! with its frontier and links the figures. Every figure is written as SVG and as PNG (its
//! text drawn with the embedded DejaVu Sans, so a PNG needs no font from the system). The same
//! rows give `scion tune` its choice ([`frontier`]).

use crate::results::Row;
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

/// A peer library measured on a context's queries (`--peers`), placed on its plot.
#[derive(Clone, Debug)]
pub struct Peer {
    /// The peer's name (`embree`, `tinybvh bvh2`, ...).
    pub name: String,
    /// Bytes per triangle of its structure, when the peer says.
    pub bytes_per_triangle: Option<f64>,
    /// Its time per query scaled to the exploration's run: the anchor layout's time in the
    /// context times the peer's time over the anchor's in the peer's own run (a ratio measured
    /// in one run, as every comparison with a peer is).
    pub ns_per_query: f64,
}

pub use scion_runtime::timing::PEER_FIELDS;

/// The peers of every context of `rows` found in the peers file's rows: those with the
/// context's scene, kind, query set, size and threads whose anchor (`BACKEND LAYOUT`, e.g.
/// `llvm-O3 pbrt`) was measured in the context.
pub fn peers_of(
    ctxs: &BTreeMap<Vec<String>, Vec<Point>>,
    peer_rows: &[Row],
) -> BTreeMap<Vec<String>, Vec<Peer>> {
    let mut out: BTreeMap<Vec<String>, Vec<Peer>> = BTreeMap::new();
    for (ctx, points) in ctxs {
        for r in peer_rows {
            let get = |f: &str| r.get(f).map(String::as_str).unwrap_or_default();
            let num = |f: &str| get(f).parse::<f64>().ok();
            // The explorer names scenes as given (`bunny`); the benchmarks by file (`bunny.obj`).
            let scene = get("scene");
            let scene = scene.strip_suffix(".gz").unwrap_or(scene);
            let scene = scene.strip_suffix(".obj").unwrap_or(scene);
            let same = scene == ctx[0]
                && get("kind") == ctx[1]
                && get("queries") == ctx[2]
                && get("n") == ctx[3]
                && get("threads") == ctx[5];
            let Some((backend, layout)) = get("anchor").split_once(' ') else {
                continue;
            };
            let anchor = points.iter().find(|p| p.layout == layout);
            let (Some(anchor), Some(t), Some(at)) =
                (anchor, num("ns_per_query"), num("anchor_ns_per_query"))
            else {
                continue;
            };
            if !same || backend != ctx[4] || at <= 0.0 {
                continue;
            }
            let tris = num("triangles").filter(|&n| n > 0.0);
            let peers = out.entry(ctx.clone()).or_default();
            // A later row of the same peer replaces an earlier one.
            peers.retain(|p| p.name != get("peer"));
            peers.push(Peer {
                name: get("peer").to_string(),
                bytes_per_triangle: num("bytes").zip(tris).map(|(b, n)| b / n),
                ns_per_query: anchor.ns_per_query * t / at,
            });
        }
    }
    out
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

/// The font every plot's text is drawn with, embedded so that a PNG needs nothing from the
/// system (cli/assets/DejaVuSans.LICENSE); registered once, before the first figure.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
const FAMILY: &str = "sans-serif";

fn register_font() -> Result<(), CliError> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE
        .get_or_init(|| plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(CliError::new(
            "the embedded font (cli/assets/DejaVuSans.ttf) is not a font plotters can read",
        ))
    }
}

/// The size of every figure, in pixels (SVG units).
const SIZE: (u32, u32) = (900, 600);

type Area<DB> = DrawingArea<DB, plotters::coord::Shift>;

/// Draws one figure as `STEM.svg` and `STEM.png` in `dir` (the same drawing on each backend).
fn svg_and_png(
    dir: &Path,
    stem: &str,
    svg: impl FnOnce(Area<SVGBackend>) -> Result<(), String>,
    png: impl FnOnce(Area<BitMapBackend>) -> Result<(), String>,
) -> Result<(), CliError> {
    register_font()?;
    let path = dir.join(format!("{stem}.svg"));
    svg(SVGBackend::new(&path, SIZE).into_drawing_area()).map_err(|e| plot_err(&path, e))?;
    let path = dir.join(format!("{stem}.png"));
    png(BitMapBackend::new(&path, SIZE).into_drawing_area()).map_err(|e| plot_err(&path, e))
}

/// The colours of the plots: Pareto-optimal layouts, the others, those whose answers differed
/// from the reference, and the peers.
const FRONT: RGBColor = RGBColor(31, 90, 200);
const OTHER: RGBColor = RGBColor(150, 150, 150);
const WRONG: RGBColor = RGBColor(210, 40, 40);
const PEER: RGBColor = RGBColor(230, 120, 0);

/// A peer's letter on the plots (A, B, ...).
fn letter(k: usize) -> String {
    char::from_u32('A' as u32 + k as u32).map_or_else(|| format!("P{k}"), String::from)
}

/// The Pareto plot of one context: time per query (log scale) against bytes per triangle, each
/// layout a numbered point and each peer a lettered triangle (a dashed line across when its
/// bytes are unknown), with a legend to the right naming them.
fn pareto<DB: DrawingBackend>(
    root: Area<DB>,
    ctx: &[String],
    points: &[Point],
    peers: &[Peer],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let front = frontier(points);
    let xs = points
        .iter()
        .map(|p| p.bytes_per_triangle)
        .chain(peers.iter().filter_map(|p| p.bytes_per_triangle));
    let ys = points
        .iter()
        .map(|p| p.ns_per_query)
        .chain(peers.iter().map(|p| p.ns_per_query));
    let (xmin, xmax) = xs.fold((f64::MAX, 0f64), |(a, b), x| (a.min(x), b.max(x)));
    let (ymin, ymax) = ys.fold((f64::MAX, 0f64), |(a, b), y| (a.min(y), b.max(y)));
    let pad = ((xmax - xmin) * 0.06).max(1.0);
    root.fill(&WHITE).map_err(e)?;
    let root = root.titled(&title(ctx), (FAMILY, 20)).map_err(e)?;
    let (plot, legend) = root.split_horizontally(SIZE.0 - 250);
    let mut chart = ChartBuilder::on(&plot)
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(
            (xmin - pad).max(0.0)..xmax + pad,
            // Time on a log scale, drawn as log10 on a linear axis for evenly spaced labels.
            (ymin.max(1e-3) / 1.15).log10()..(ymax.max(1e-3) * 1.15).log10(),
        )
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("bytes per triangle (packed tree)")
        .y_desc("ns per query (log scale)")
        .y_labels(12)
        .y_label_formatter(&|y| format!("{:.0}", 10f64.powf(*y)))
        .draw()
        .map_err(e)?;
    // The frontier as the staircase of what it dominates.
    let mut steps: Vec<(f64, f64)> = Vec::new();
    for p in &front {
        if let Some(&(_, y)) = steps.last() {
            steps.push((p.bytes_per_triangle, y));
        }
        steps.push((p.bytes_per_triangle, p.ns_per_query.log10()));
    }
    chart
        .draw_series(LineSeries::new(steps, FRONT.stroke_width(2)))
        .map_err(e)?;
    let mut sorted: Vec<&Point> = points.iter().collect();
    sorted.sort_by(|a, b| a.ns_per_query.total_cmp(&b.ns_per_query));
    let colour = |p: &Point| {
        if !p.identical {
            WRONG
        } else if front.iter().any(|q| q.layout == p.layout) {
            FRONT
        } else {
            OTHER
        }
    };
    let label = (FAMILY, 12).into_font();
    for (k, p) in sorted.iter().enumerate() {
        let at = (p.bytes_per_triangle, p.ns_per_query.log10());
        chart
            .draw_series(std::iter::once(Circle::new(at, 4, colour(p).filled())))
            .map_err(e)?;
        chart
            .draw_series(std::iter::once(
                EmptyElement::at(at) + Text::new(format!("{}", k + 1), (5, -13), label.clone()),
            ))
            .map_err(e)?;
    }
    let (x0, x1) = ((xmin - pad).max(0.0), xmax + pad);
    for (k, p) in peers.iter().enumerate() {
        let tag = letter(k);
        match p.bytes_per_triangle {
            Some(b) => {
                let at = (b, p.ns_per_query.log10());
                chart
                    .draw_series(std::iter::once(TriangleMarker::new(at, 6, PEER.filled())))
                    .map_err(e)?;
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at(at) + Text::new(tag, (6, -14), label.clone()),
                    ))
                    .map_err(e)?;
            }
            None => {
                let y = p.ns_per_query.log10();
                let line = [(x0, y), (x1, y)];
                chart
                    .draw_series(DashedLineSeries::new(line, 6, 4, PEER.stroke_width(1)))
                    .map_err(e)?;
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at((x0, y)) + Text::new(tag, (4, -14), label.clone()),
                    ))
                    .map_err(e)?;
            }
        }
    }
    // The legend: every layout by time, then the peers, in columns.
    let small = (FAMILY, 12).into_font();
    let mut y = 10;
    let mut row = |cells: [String; 4], colour: RGBColor| -> Result<(), String> {
        for (cell, x) in cells.into_iter().zip([4, 26, 86, 136]) {
            legend
                .draw(&Text::new(cell, (x, y), small.clone().color(&colour)))
                .map_err(e)?;
        }
        y += 16;
        Ok(())
    };
    let bytes = |b: Option<f64>| b.map_or("?".to_string(), |b| format!("{b:.1}"));
    row(
        [
            "".into(),
            "ns/query".into(),
            "B/tri".into(),
            "layout".into(),
        ],
        BLACK,
    )?;
    for (k, p) in sorted.iter().enumerate() {
        row(
            [
                format!("{}", k + 1),
                format!("{:.1}", p.ns_per_query),
                bytes(Some(p.bytes_per_triangle)),
                p.layout.clone(),
            ],
            colour(p),
        )?;
    }
    for (k, p) in peers.iter().enumerate() {
        row(
            [
                letter(k),
                format!("{:.1}", p.ns_per_query),
                bytes(p.bytes_per_triangle),
                p.name.clone(),
            ],
            PEER,
        )?;
    }
    root.present().map_err(e)
}

/// Speed against error of the quantized layouts of one context.
fn error<DB: DrawingBackend>(
    root: Area<DB>,
    ctx: &[String],
    points: &[Point],
) -> Result<(), String> {
    let e = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
    let q: Vec<(&Point, f64)> = points
        .iter()
        .filter_map(|p| p.extra_box_tests.map(|e| (p, 100.0 * e)))
        .collect();
    let xmax = q.iter().fold(1f64, |m, (_, e)| m.max(*e));
    let ymax = points.iter().fold(0f64, |m, p| m.max(p.ns_per_query));
    root.fill(&WHITE).map_err(e)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(format!("{}: quantized layouts", title(ctx)), (FAMILY, 20))
        .margin(20)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(0f64..xmax * 1.2, 0f64..ymax * 1.15 + 1e-9)
        .map_err(e)?;
    chart
        .configure_mesh()
        .x_desc("extra box tests over the decoded boxes (%)")
        .y_desc("ns per query")
        .draw()
        .map_err(e)?;
    for (p, x) in q {
        chart
            .draw_series(std::iter::once(Circle::new(
                (x, p.ns_per_query),
                5,
                BLUE.filled(),
            )))
            .map_err(e)?;
        chart
            .draw_series(std::iter::once(Text::new(
                p.layout.clone(),
                (x, p.ns_per_query),
                (FAMILY, 13).into_font(),
            )))
            .map_err(e)?;
    }
    root.present().map_err(e)
}

/// Writes every context's figures and `index.md` into `dir`, with the peers of `peer_rows`
/// (the rows of a peers file, [`PEER_FIELDS`]) on the Pareto plots; returns the files written.
pub fn write_all(rows: &[Row], peer_rows: &[Row], dir: &Path) -> Result<usize, CliError> {
    std::fs::create_dir_all(dir)
        .map_err(|e| CliError::new(format!("cannot create {}: {e}", dir.display())))?;
    let mut index = String::from(
        "# Design-space exploration\n\nWritten by `scion explore --plots` from its results: per \
         context, time per query against bytes per triangle of every layout measured, the Pareto \
         frontier in blue (no other layout both smaller and faster), layouts whose answers \
         differed from the reference in red, peer libraries (when a peers file was given) as \
         orange triangles, their time scaled to this sweep by the ratio to a Scion layout \
         measured in their own run. Every figure is also a PNG of the same name.\n\n",
    );
    let mut files = 0;
    let ctxs = contexts(rows);
    let peers = peers_of(&ctxs, peer_rows);
    for (ctx, points) in ctxs {
        let no_peers = Vec::new();
        let peers = peers.get(&ctx).unwrap_or(&no_peers);
        let s = stem(&ctx);
        svg_and_png(
            dir,
            &s,
            |a| pareto(a, &ctx, &points, peers),
            |a| pareto(a, &ctx, &points, peers),
        )?;
        files += 2;
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
        for p in peers {
            index.push_str(&format!(
                "| peer: {} | {} | {:.1} | |\n",
                p.name,
                p.bytes_per_triangle
                    .map_or("?".to_string(), |b| format!("{b:.1}")),
                p.ns_per_query
            ));
        }
        index.push('\n');
        if points.iter().any(|p| p.extra_box_tests.is_some()) {
            svg_and_png(
                dir,
                &format!("{s}-error"),
                |a| error(a, &ctx, &points),
                |a| error(a, &ctx, &points),
            )?;
            files += 2;
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
