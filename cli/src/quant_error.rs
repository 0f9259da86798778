//! What a quantized layout costs in accuracy, for `scion trace --stats` (paper §9.2.5; issue
//! 15's speed against error): its decoded boxes against the exact ones node by node (how much
//! larger, by surface area and by volume; that every decoded box contains its exact box, i.e.
//! quantization is conservative and can lose no hit), and the extra work per ray the larger
//! boxes cause (box tests, node visits, triangle tests of the reference traversal over the
//! decoded tree against the same traversal over the exact tree). For an eight-wide layout that
//! quantizes each node's children in the node's frame, the same over the wide tree's child
//! boxes and the wide reference traversal.

use scion_runtime::bvh::LogicalTree;
use scion_runtime::reference::closest_hit::TraversalStats;

/// Decoded against exact boxes over every node of a tree.
pub struct Inflation {
    /// Σ decoded surface area / Σ exact surface area.
    pub area: f64,
    /// Σ decoded volume / Σ exact volume (1 when every box is flat).
    pub volume: f64,
    /// Nodes whose decoded box contains the exact one.
    pub contained: usize,
    /// Nodes compared.
    pub nodes: usize,
}

fn half_area(b: &[f32; 6]) -> f64 {
    let d = [0, 1, 2].map(|a| (f64::from(b[a + 3]) - f64::from(b[a])).max(0.0));
    d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
}

fn volume(b: &[f32; 6]) -> f64 {
    (0..3)
        .map(|a| (f64::from(b[a + 3]) - f64::from(b[a])).max(0.0))
        .product()
}

/// `decoded` (the same tree with its boxes as a layout decodes them) against `exact`.
pub fn inflation(exact: &LogicalTree, decoded: &LogicalTree) -> Inflation {
    let (mut ea, mut da, mut ev, mut dv, mut contained) = (0.0, 0.0, 0.0, 0.0, 0);
    for (e, d) in exact.nodes.iter().zip(&decoded.nodes) {
        ea += half_area(&e.bounds);
        da += half_area(&d.bounds);
        ev += volume(&e.bounds);
        dv += volume(&d.bounds);
        let holds =
            (0..3).all(|a| d.bounds[a] <= e.bounds[a] && d.bounds[a + 3] >= e.bounds[a + 3]);
        contained += usize::from(holds);
    }
    let ratio = |d: f64, e: f64| if e > 0.0 { d / e } else { 1.0 };
    Inflation {
        area: ratio(da, ea),
        volume: ratio(dv, ev),
        contained,
        nodes: exact.nodes.len().min(decoded.nodes.len()),
    }
}

/// `decoded` (a wide tree with its child boxes as a layout decodes them) against `exact`, over
/// every occupied child slot.
pub fn inflation_wide<const W: usize>(
    exact: &scion_runtime::bvh::wide::WideTree<W>,
    decoded: &scion_runtime::bvh::wide::WideTree<W>,
) -> Inflation {
    let (mut ea, mut da, mut ev, mut dv, mut contained, mut nodes) = (0.0, 0.0, 0.0, 0.0, 0, 0);
    for (e, d) in exact.nodes.iter().zip(&decoded.nodes) {
        for (e, d) in e
            .bounds
            .iter()
            .zip(&d.bounds)
            .filter(|(e, _)| !e.is_empty())
        {
            let (e, d) = (e.to_array(), d.to_array());
            ea += half_area(&e);
            da += half_area(&d);
            ev += volume(&e);
            dv += volume(&d);
            let holds = (0..3).all(|a| d[a] <= e[a] && d[a + 3] >= e[a + 3]);
            contained += usize::from(holds);
            nodes += 1;
        }
    }
    let ratio = |d: f64, e: f64| if e > 0.0 { d / e } else { 1.0 };
    Inflation {
        area: ratio(da, ea),
        volume: ratio(dv, ev),
        contained,
        nodes,
    }
}

/// "+12.3 %" of `more` over `base` (per ray counts).
fn extra(more: u64, base: u64) -> String {
    if base == 0 {
        return "+0 %".into();
    }
    format!("{:+.1} %", (more as f64 / base as f64 - 1.0) * 100.0)
}

/// What a quantized layout's boxes cost on some rays: the inflation of its decoded boxes and
/// the reference traversal's work over them and over the exact ones.
pub struct QuantError {
    /// Decoded against exact boxes.
    pub inflation: Inflation,
    /// The work over the decoded boxes.
    pub decoded: TraversalStats,
    /// The work over the exact boxes.
    pub exact: TraversalStats,
}

impl QuantError {
    /// `decoded / exact - 1` of the box tests, node visits and triangle tests.
    pub fn extra(&self) -> [f64; 3] {
        let r = |d: u64, e: u64| {
            if e > 0 {
                d as f64 / e as f64 - 1.0
            } else {
                0.0
            }
        };
        [
            r(self.decoded.boxes_tested, self.exact.boxes_tested),
            r(self.decoded.nodes_visited, self.exact.nodes_visited),
            r(self.decoded.triangles_tested, self.exact.triangles_tested),
        ]
    }
}

/// What `boxes` cost against the exact boxes of `tree` on `rays`: over the binary tree for a
/// layout quantized against one frame, over the tree collapsed to eight children for one that
/// quantizes each node's children (`Boxes::node_codes`); `None` for exact boxes.
pub fn measure(
    boxes: scion_host::quantized::Boxes,
    tree: &LogicalTree,
    rays: &[scion_runtime::geom::Ray],
    driver: &scion_runtime::batch::BatchDriver,
) -> Option<QuantError> {
    use scion_host::quantized::{Boxes, DecodedTree};
    use scion_runtime::reference::{closest_hits_tree_stats, closest_hits_wide_stats};
    if matches!(boxes, Boxes::Exact) {
        return None;
    }
    if boxes.node_codes().is_some() {
        let w8 = scion_runtime::bvh::wide::collapse::<8>(tree);
        let decoded = scion_host::quantized::decoded_wide(boxes, &w8);
        return Some(QuantError {
            inflation: inflation_wide(&w8, &decoded),
            decoded: closest_hits_wide_stats(&decoded, &tree.primitives, rays, driver),
            exact: closest_hits_wide_stats(&w8, &tree.primitives, rays, driver),
        });
    }
    let traversed = boxes.decoded_tree(tree);
    Some(QuantError {
        inflation: inflation(tree, &traversed),
        decoded: closest_hits_tree_stats(&traversed, rays, driver),
        exact: closest_hits_tree_stats(tree, rays, driver),
    })
}

/// The report's lines: the boxes, then the extra work against the exact tree.
pub fn report(i: &Inflation, decoded: &TraversalStats, exact: &TraversalStats) -> [String; 2] {
    [
        format!(
            "boxes        decoded / exact: surface area x{:.4}, volume x{:.4}; {} of {} decoded boxes contain the exact one{}",
            i.area,
            i.volume,
            i.contained,
            i.nodes,
            if i.contained == i.nodes { " (conservative: no hit can be lost)" } else { " (NOT conservative)" }
        ),
        format!(
            "error/ray    box tests {}, nodes visited {}, triangle tests {} against the exact boxes",
            extra(decoded.boxes_tested, exact.boxes_tested),
            extra(decoded.nodes_visited, exact.nodes_visited),
            extra(decoded.triangles_tested, exact.triangles_tested),
        ),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_host::quantized::{Boxes, DecodedTree};
    use scion_runtime::bvh::{build_sah_binned, SahOptions};
    use scion_runtime::scene::gen;

    #[test]
    fn decoded_boxes_inflate_and_contain_the_exact_ones() {
        let scene = gen::random_soup(300, 0.1, 7);
        let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
        let same = inflation(&tree, &tree);
        assert_eq!((same.area, same.volume), (1.0, 1.0));
        assert_eq!(same.contained, tree.nodes.len());
        for boxes in [Boxes::GlobalQ16, Boxes::SnappedQ10] {
            let decoded = boxes.decoded_tree(&tree);
            let i = inflation(&tree, &decoded);
            assert_eq!(i.contained, i.nodes, "{boxes:?}: conservative");
            assert!(i.area >= 1.0 && i.volume >= 1.0, "{boxes:?}");
        }
        // Fewer bits inflate more: 10-bit snapped grid against 16-bit codes.
        let q16 = inflation(&tree, &Boxes::GlobalQ16.decoded_tree(&tree));
        let q10 = inflation(&tree, &Boxes::SnappedQ10.decoded_tree(&tree));
        assert!(q10.area > q16.area, "{} {}", q10.area, q16.area);
        // Eight-wide nodes quantized in their own frames: conservative, q8 wider than q16.
        let w8 = scion_runtime::bvh::wide::collapse::<8>(&tree);
        let i8 = inflation_wide(
            &w8,
            &scion_host::quantized::decoded_wide(Boxes::NodeQ8, &w8),
        );
        let i16 = inflation_wide(
            &w8,
            &scion_host::quantized::decoded_wide(Boxes::NodeQ16, &w8),
        );
        assert_eq!((i8.contained, i16.contained), (i8.nodes, i16.nodes));
        assert!(
            i8.area > i16.area && i16.area >= 1.0,
            "{} {}",
            i8.area,
            i16.area
        );
        assert_eq!(inflation_wide(&w8, &w8).area, 1.0);
        // A box that does not contain its exact one is reported.
        let mut shrunk = tree.clone();
        shrunk.nodes[0].bounds[0] += 0.01;
        assert_eq!(inflation(&tree, &shrunk).contained, tree.nodes.len() - 1);
    }
}
