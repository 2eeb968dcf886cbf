//! Writing Kratos model parts as Gmsh MSH 4.1 (ASCII) files that Loam reads
//! (`{"gmsh": FILE}` meshes, `loam_fem::gmsh`).
//!
//! All nodes and cells go into one surface entity; every named node set becomes a physical
//! group of its own point entity holding one point element (Gmsh type 15) per node, so that
//! Loam's reader makes it a node group, a region `{"group": NAME}`. Kratos' node ids are kept
//! as node tags.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write;

/// The text of an MSH 4.1 file with `cells` of dimension `dim` (all of one type: in 2D 3
/// nodes → triangles, 4 → quadrangles; in 3D 4 → tetrahedra, 8 → hexahedra, Kratos' and
/// Gmsh's node orders being the same) over `nodes` and the node sets `groups`. Only nodes
/// that a cell or a group uses are written.
pub fn write(
    nodes: &BTreeMap<usize, [f64; 3]>,
    cells: &[Vec<usize>],
    dim: usize,
    groups: &[(String, BTreeSet<usize>)],
) -> String {
    let mut used: BTreeSet<usize> = cells.iter().flatten().copied().collect();
    groups.iter().for_each(|(_, g)| used.extend(g));
    let (min, max) = bounds(nodes, &used);
    let mut s = String::new();
    s.push_str("$MeshFormat\n4.1 0 8\n$EndMeshFormat\n");
    if !groups.is_empty() {
        let _ = writeln!(s, "$PhysicalNames\n{}", groups.len());
        for (k, (name, _)) in groups.iter().enumerate() {
            let _ = writeln!(s, "0 {} \"{}\"", k + 1, name);
        }
        s.push_str("$EndPhysicalNames\n");
    }
    s.push_str("$Entities\n");
    let (surfaces, volumes) = if dim == 3 { (0, 1) } else { (1, 0) };
    let _ = writeln!(s, "{} 0 {surfaces} {volumes}", groups.len());
    for (k, (_, g)) in groups.iter().enumerate() {
        let x = g.iter().next().and_then(|n| nodes.get(n)).copied().unwrap_or_default();
        let _ = writeln!(s, "{} {} {} {} 1 {}", k + 1, x[0], x[1], x[2], k + 1);
    }
    let _ = writeln!(s, "1 {} {} {} {} {} {} 0 0", min[0], min[1], min[2], max[0], max[1], max[2]);
    s.push_str("$EndEntities\n");
    let (lo, hi) = (used.first().copied().unwrap_or(0), used.last().copied().unwrap_or(0));
    let _ = writeln!(s, "$Nodes\n1 {} {lo} {hi}\n{dim} 1 0 {}", used.len(), used.len());
    for n in &used {
        let _ = writeln!(s, "{n}");
    }
    for n in &used {
        let x = nodes[n];
        let _ = writeln!(s, "{} {} {}", x[0], x[1], x[2]);
    }
    s.push_str("$EndNodes\n");
    let points: usize = groups.iter().map(|(_, g)| g.len()).sum();
    let total = cells.len() + points;
    let blocks = 1 + groups.len();
    let _ = writeln!(s, "$Elements\n{blocks} {total} 1 {total}");
    // Gmsh element types: 2 triangle, 3 quadrangle, 4 tetrahedron, 5 hexahedron
    let kind = match (dim, cells.first().map_or(0, Vec::len)) {
        (3, 8) => 5,
        (3, _) => 4,
        (_, 4) => 3,
        _ => 2,
    };
    let _ = writeln!(s, "{dim} 1 {kind} {}", cells.len());
    let mut tag = 0;
    for c in cells {
        tag += 1;
        let _ = write!(s, "{tag}");
        c.iter().for_each(|n| {
            let _ = write!(s, " {n}");
        });
        s.push('\n');
    }
    for (k, (_, g)) in groups.iter().enumerate() {
        let _ = writeln!(s, "0 {} 15 {}", k + 1, g.len());
        for n in g {
            tag += 1;
            let _ = writeln!(s, "{tag} {n}");
        }
    }
    s.push_str("$EndElements\n");
    s
}

fn bounds(nodes: &BTreeMap<usize, [f64; 3]>, used: &BTreeSet<usize>) -> ([f64; 3], [f64; 3]) {
    let mut min = [f64::INFINITY; 3];
    let mut max = [f64::NEG_INFINITY; 3];
    for x in used.iter().filter_map(|n| nodes.get(n)) {
        for d in 0..3 {
            min[d] = min[d].min(x[d]);
            max[d] = max[d].max(x[d]);
        }
    }
    if used.is_empty() {
        return ([0.0; 3], [0.0; 3]);
    }
    (min, max)
}
