//! Writing Kratos model parts (`.mdpa`): the inverse of [`crate::import::kratos::mdpa`].
//!
//! The same [`Mdpa`] data the reader fills is written back: `Begin Nodes` (`id x y z`), one
//! `Begin Elements TYPE` / `Begin Conditions TYPE` block per entity kind (`id properties_id
//! node...`) and `Begin SubModelPart NAME` with its node, element and condition ids. Numbers
//! are written with 17 significant digits, so that a re-import reads the same `f64`.

use std::fmt::Write;

use crate::import::kratos::mdpa::{EntityBlock, Mdpa};

/// The text of the `.mdpa` file of `m`.
pub fn write(m: &Mdpa) -> String {
    let mut s =
        String::from("Begin ModelPartData\nEnd ModelPartData\n\nBegin Properties 0\nEnd Properties\n\nBegin Nodes\n");
    for (id, x) in &m.nodes {
        let _ = writeln!(s, "{id} {:.16e} {:.16e} {:.16e}", x[0], x[1], x[2]);
    }
    s.push_str("End Nodes\n\n");
    blocks(&mut s, "Elements", &m.elements);
    blocks(&mut s, "Conditions", &m.conditions);
    for p in &m.sub_model_parts {
        let _ = writeln!(s, "Begin SubModelPart {}", p.name);
        for (what, ids) in [("Nodes", &p.nodes), ("Elements", &p.elements), ("Conditions", &p.conditions)] {
            let _ = writeln!(s, "  Begin SubModelPart{what}");
            for id in ids {
                let _ = writeln!(s, "    {id}");
            }
            let _ = writeln!(s, "  End SubModelPart{what}");
        }
        s.push_str("End SubModelPart\n\n");
    }
    s
}

/// `Begin KEYWORD KIND` blocks of `blocks`.
fn blocks(s: &mut String, keyword: &str, blocks: &[EntityBlock]) {
    for b in blocks {
        let _ = writeln!(s, "Begin {keyword} {}", b.kind);
        for (id, property, nodes) in &b.entities {
            let _ = write!(s, "{id} {property}");
            for n in nodes {
                let _ = write!(s, " {n}");
            }
            s.push('\n');
        }
        let _ = writeln!(s, "End {keyword}\n");
    }
}

/// Kratos' suffix of a linear entity of `nodes` nodes in `dim` dimensions (`2D4N`).
pub(super) fn entity_suffix(dim: usize, nodes: usize) -> String {
    format!("{dim}D{nodes}N")
}

/// An entity block of `kind` numbering `cells` (0-based node indices) from `first + 1`.
pub(super) fn block(kind: &str, cells: impl Iterator<Item = Vec<usize>>, first: usize) -> EntityBlock {
    let entities = cells.enumerate().map(|(e, c)| (first + e + 1, 0, c.iter().map(|n| n + 1).collect())).collect();
    EntityBlock { kind: kind.into(), line: 0, entities }
}
