//! Reader of Kratos Multiphysics' `.mdpa` model part files.
//!
//! The format (Kratos' `ModelPartIO`) is a sequence of `Begin NAME [args] ... End NAME`
//! blocks; `//` starts a comment anywhere on a line. This reader takes:
//!
//! - `Begin Nodes`: `id x y z` per line;
//! - `Begin Elements TYPE` and `Begin Conditions TYPE`: `id properties_id node...` per line;
//! - `Begin SubModelPart NAME` with its `SubModelPartNodes`, `SubModelPartElements` and
//!   `SubModelPartConditions` id lists (nested sub model parts are named `PARENT.CHILD`);
//! - `ModelPartData` and `Properties` blocks, which must be empty (Kratos' GiD interface
//!   writes them so; values in them would be ignored, so each one is reported).
//!
//! Any other block (`NodalData`, `ElementalData`, `Table`, `Geometries`, ...) is skipped and
//! reported with its line. Malformed lines give a [`MdpaError`] naming the file and line.

use std::collections::BTreeMap;
use std::path::Path;

/// A malformed `.mdpa` file: one line, `FILE:LINE: problem`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}{}: {message}", if *line > 0 { format!(":{line}") } else { String::new() })]
pub struct MdpaError {
    /// File name as given.
    pub file: String,
    /// 1-based line number (0 when the file could not be read).
    pub line: usize,
    /// What is wrong.
    pub message: String,
}

/// One `Begin Elements TYPE` or `Begin Conditions TYPE` block.
#[derive(Debug, Clone, Default)]
pub struct EntityBlock {
    /// Kratos' element or condition name, e.g. `MPMUpdatedLagrangian2D4N`.
    pub kind: String,
    /// Line of the `Begin`.
    pub line: usize,
    /// `(id, properties id, node ids)` per entity.
    pub entities: Vec<(usize, usize, Vec<usize>)>,
}

/// One sub model part: the ids it lists.
#[derive(Debug, Clone, Default)]
pub struct SubModelPart {
    /// Full name, nested ones as `PARENT.CHILD`.
    pub name: String,
    /// Node ids.
    pub nodes: Vec<usize>,
    /// Element ids.
    pub elements: Vec<usize>,
    /// Condition ids.
    pub conditions: Vec<usize>,
}

/// The content of one `.mdpa` file.
#[derive(Debug, Clone, Default)]
pub struct Mdpa {
    /// Node coordinates by id.
    pub nodes: BTreeMap<usize, [f64; 3]>,
    /// Element blocks in file order.
    pub elements: Vec<EntityBlock>,
    /// Condition blocks in file order.
    pub conditions: Vec<EntityBlock>,
    /// Sub model parts in file order.
    pub sub_model_parts: Vec<SubModelPart>,
    /// What was skipped, one line each (`FILE:LINE: ...`).
    pub notes: Vec<String>,
}

impl Mdpa {
    /// The element `id` with its block's kind, if any block holds it.
    pub fn element(&self, id: usize) -> Option<(&str, &[usize])> {
        find(&self.elements, id)
    }

    /// The condition `id` with its block's kind.
    pub fn condition(&self, id: usize) -> Option<(&str, &[usize])> {
        find(&self.conditions, id)
    }

    /// The sub model part named `name` (full dotted name).
    pub fn sub_model_part(&self, name: &str) -> Option<&SubModelPart> {
        self.sub_model_parts.iter().find(|s| s.name == name)
    }
}

fn find(blocks: &[EntityBlock], id: usize) -> Option<(&str, &[usize])> {
    blocks.iter().find_map(|b| b.entities.iter().find(|e| e.0 == id).map(|e| (b.kind.as_str(), &e.2[..])))
}

/// Reads and parses `path`.
pub fn read(path: &Path) -> Result<Mdpa, MdpaError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| MdpaError {
        file: file.clone(),
        line: 0,
        message: format!("cannot read: {e}"),
    })?;
    parse(&text, &file)
}

/// What the parser is inside of.
enum Block {
    Nodes,
    Entities {
        conditions: bool,
    },
    /// A sub model part, by index into `sub_model_parts`.
    Part(usize),
    /// An id list of the innermost sub model part: 0 nodes, 1 elements, 2 conditions.
    PartList(usize, u8),
    /// `ModelPartData` / `Properties`: reported per line.
    Data,
    /// Skipped up to `End NAME`.
    Skip,
}

/// Parses the text of a `.mdpa` file named `file` (for messages).
pub fn parse(text: &str, file: &str) -> Result<Mdpa, MdpaError> {
    let mut m = Mdpa::default();
    // (block name as in Begin/End, what it is, line)
    let mut stack: Vec<(String, Block, usize)> = Vec::new();
    let err = |line: usize, message: String| MdpaError { file: file.to_string(), line, message };
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let content = raw.split("//").next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let mut words = content.split_whitespace();
        let first = words.next().unwrap_or("");
        if first == "Begin" {
            let name = words.next().ok_or_else(|| err(line, "`Begin` without a block name".into()))?;
            let arg = words.next();
            let parent = stack.last().map(|s| &s.1);
            let skipping = matches!(parent, Some(Block::Skip));
            let block = match (name, parent) {
                _ if skipping => Block::Skip,
                ("Nodes", None) => Block::Nodes,
                ("Elements" | "Conditions", None) => {
                    let kind = arg.ok_or_else(|| err(line, format!("`Begin {name}` without an element type")))?;
                    let b = EntityBlock { kind: kind.to_string(), line, entities: Vec::new() };
                    let conditions = name == "Conditions";
                    if conditions {
                        m.conditions.push(b);
                    } else {
                        m.elements.push(b);
                    }
                    Block::Entities { conditions }
                }
                ("SubModelPart", None | Some(Block::Part(_))) => {
                    let own = arg.ok_or_else(|| err(line, "`Begin SubModelPart` without a name".into()))?;
                    let full = match parent {
                        Some(Block::Part(p)) => format!("{}.{own}", m.sub_model_parts[*p].name),
                        _ => own.to_string(),
                    };
                    m.sub_model_parts.push(SubModelPart { name: full, ..Default::default() });
                    Block::Part(m.sub_model_parts.len() - 1)
                }
                ("SubModelPartNodes", Some(Block::Part(p))) => Block::PartList(*p, 0),
                ("SubModelPartElements", Some(Block::Part(p))) => Block::PartList(*p, 1),
                ("SubModelPartConditions", Some(Block::Part(p))) => Block::PartList(*p, 2),
                ("ModelPartData" | "Properties", None) => Block::Data,
                _ => {
                    m.notes.push(format!("{file}:{line}: block `Begin {name}` ignored (not read by the importer)"));
                    Block::Skip
                }
            };
            stack.push((name.to_string(), block, line));
            continue;
        }
        if first == "End" {
            let name = words.next().unwrap_or("");
            match stack.pop() {
                Some((open, _, _)) if open == name => continue,
                Some((open, _, at)) => {
                    return Err(err(line, format!("`End {name}` closes `Begin {open}` of line {at}")));
                }
                None => return Err(err(line, format!("`End {name}` without a `Begin {name}`"))),
            }
        }
        let Some((_, block, _)) = stack.last() else {
            return Err(err(line, format!("`{content}` outside any Begin/End block")));
        };
        let ids = |line: usize| -> Result<Vec<usize>, MdpaError> {
            content
                .split_whitespace()
                .map(|w| w.parse::<usize>().map_err(|_| err(line, format!("`{w}` is not an id (a whole number)"))))
                .collect()
        };
        match block {
            Block::Nodes => {
                let w: Vec<&str> = content.split_whitespace().collect();
                if w.len() != 4 {
                    return Err(err(line, format!("a node needs `id x y z`, got {} values", w.len())));
                }
                let id = w[0]
                    .parse::<usize>()
                    .map_err(|_| err(line, format!("node id `{}` is not a whole number", w[0])))?;
                let mut x = [0.0; 3];
                for d in 0..3 {
                    x[d] = w[d + 1]
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| err(line, format!("coordinate `{}` is not a finite number", w[d + 1])))?;
                }
                if m.nodes.insert(id, x).is_some() {
                    return Err(err(line, format!("node {id} is defined twice")));
                }
            }
            Block::Entities { conditions } => {
                let v = ids(line)?;
                if v.len() < 3 {
                    return Err(err(line, "an element or condition needs `id properties_id node...`".into()));
                }
                let b = if *conditions { m.conditions.last_mut() } else { m.elements.last_mut() };
                let b = b.expect("block pushed at Begin");
                b.entities.push((v[0], v[1], v[2..].to_vec()));
            }
            Block::PartList(p, which) => {
                let v = ids(line)?;
                let part = &mut m.sub_model_parts[*p];
                match which {
                    0 => part.nodes.extend(v),
                    1 => part.elements.extend(v),
                    _ => part.conditions.extend(v),
                }
            }
            Block::Part(_) => {
                return Err(err(line, format!("`{content}` inside a SubModelPart but outside its id lists")));
            }
            Block::Data => m.notes.push(format!(
                "{file}:{line}: `{content}` ignored (model part data and properties are read from the materials file)"
            )),
            Block::Skip => {}
        }
    }
    if let Some((name, _, at)) = stack.last() {
        return Err(err(*at, format!("`Begin {name}` is never closed by `End {name}`")));
    }
    // every id a block or sub model part refers to exists
    for b in m.elements.iter().chain(&m.conditions) {
        for (id, _, nodes) in &b.entities {
            if let Some(n) = nodes.iter().find(|n| !m.nodes.contains_key(n)) {
                return Err(err(
                    b.line,
                    format!("{} {id} refers to node {n}, which `Begin Nodes` does not define", b.kind),
                ));
            }
        }
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_blocks_and_names_bad_lines() {
        let text = "Begin Nodes\n 1 0 0 0\n 2 1 0 0\n 3 1 1 0 // c\nEnd Nodes\nBegin Elements Element2D3N// x\n 1 0 1 2 3\nEnd Elements\n\
                    Begin SubModelPart A // g\n Begin SubModelPartNodes\n 1\n 2\n End SubModelPartNodes\n Begin SubModelPart B\n Begin SubModelPartNodes\n 3\n End SubModelPartNodes\n End SubModelPart\nEnd SubModelPart\n";
        let m = parse(text, "g.mdpa").unwrap();
        assert_eq!(m.nodes.len(), 3);
        assert_eq!(m.element(1), Some(("Element2D3N", &[1, 2, 3][..])));
        assert_eq!(m.sub_model_part("A").unwrap().nodes, vec![1, 2]);
        assert_eq!(m.sub_model_part("A.B").unwrap().nodes, vec![3]);
        let e = parse("Begin Nodes\n 1 0 0\nEnd Nodes\n", "g.mdpa").unwrap_err();
        assert_eq!(e.to_string(), "g.mdpa:2: a node needs `id x y z`, got 3 values");
        let e = parse("Begin Nodes\n 1 0 0 0\n", "g.mdpa").unwrap_err();
        assert_eq!(e.line, 1);
    }
}
