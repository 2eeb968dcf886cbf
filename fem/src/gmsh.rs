//! Gmsh MSH 4.1 import (ASCII and binary) into a [`Mesh`].
//!
//! The file is parsed by the `mshio` crate; this module turns its sections into Loam's mesh:
//!
//! - **Cells** are the elements of the highest dimension present: linear triangles
//!   (Gmsh type 2), quadrangles (3), tetrahedra (4) or hexahedra (5). Gmsh's node orderings
//!   for these four are VTK's (and [`ElementType`]'s), so connectivity is copied as is, except
//!   that an inverted cell (negative area in the xy-plane, or negative volume) has its
//!   orientation reversed: Gmsh orients 2D elements by the surface normal, which may point
//!   to −z. All cells must be of one type.
//! - **Node groups**: every physical group becomes a node group named as in `$PhysicalNames`
//!   (`group_<tag>` when unnamed) holding every node of every element of the entities tagged
//!   with it, and every node Gmsh classifies on those entities. Lower-dimensional elements
//!   (lines, boundary triangles, points) serve only this purpose. Groups of different
//!   dimensions that share a name are merged.
//! - **Nodes** are renumbered to `0..n` in ascending Gmsh tag order. Nodes that no cell and no
//!   group uses are dropped.
//!
//! MSH 2.2 files are rejected with the `gmsh` command that converts them. No input makes this
//! module panic: malformed files give a [`GmshError`].

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

use mshio::{ElementType as MshElementType, MshFile};

use crate::element::ElementType;
use crate::mesh::Mesh;

/// Why a Gmsh file could not be turned into a [`Mesh`]. Each message is one line that starts
/// with the file name.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GmshError {
    /// The file could not be read from disk.
    #[error("{file}: cannot open: {reason}")]
    Io {
        /// File name as given.
        file: String,
        /// Operating system's reason.
        reason: String,
    },
    /// The file is not MSH 4.1 (e.g. the older 2.2 format).
    #[error(
        "{file}: version {version} is not supported (MSH 4.1 required: convert with \
         `gmsh OLD.msh -save -format msh41 -o NEW.msh`)"
    )]
    UnsupportedVersion {
        /// File name as given.
        file: String,
        /// Version as written in `$MeshFormat`.
        version: String,
    },
    /// The highest-dimensional elements are of a type Loam has no element for.
    #[error(
        "{file}: unsupported element type {code} ({name}); Loam reads linear triangles, \
         quadrangles, tetrahedra and hexahedra (Gmsh types 2 to 5)"
    )]
    UnsupportedElement {
        /// File name as given.
        file: String,
        /// Gmsh element type number.
        code: i32,
        /// What that type is.
        name: &'static str,
    },
    /// The highest-dimensional elements are of more than one type.
    #[error(
        "{file}: mixed {} and {} cells; a Loam mesh holds one element type",
        first.name(),
        second.name()
    )]
    MixedElements {
        /// File name as given.
        file: String,
        /// Type of the first cells.
        first: ElementType,
        /// The other type found.
        second: ElementType,
    },
    /// The file has no 2D or 3D elements.
    #[error("{file}: no cells (the file has no 2D or 3D elements)")]
    NoCells {
        /// File name as given.
        file: String,
    },
    /// The file, or the mesh it declares, is larger than the [`GmshLimits`] allow.
    #[error("{file}: {what}")]
    TooLarge {
        /// File name as given.
        file: String,
        /// What exceeds which limit.
        what: String,
    },
    /// The file is malformed, truncated or inconsistent.
    #[error("{file}: cannot read: {reason}")]
    Parse {
        /// File name as given.
        file: String,
        /// What is wrong, with the line (ASCII) or byte offset (binary) where known.
        reason: String,
    },
}

/// Bounds on what [`read_gmsh_limited`] reads, checked before the file is read (its size)
/// and before its sections are parsed (the counts their headers declare), so that a huge
/// or hostile file (`/dev/zero`, a header declaring 10¹⁸ nodes) is refused instead of
/// exhausting memory.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GmshLimits {
    /// Largest file in bytes (default 2 GiB; an ASCII mesh of two million hexahedra is
    /// about 0.3 GB). Only regular files are read: a device or pipe is refused.
    pub max_bytes: u64,
    /// Largest number of nodes, and of elements (of any dimension), the file may declare
    /// (default: no bound).
    pub max_entries: u64,
}

impl Default for GmshLimits {
    fn default() -> Self {
        Self { max_bytes: 2 << 30, max_entries: u64::MAX }
    }
}

/// Read a Gmsh MSH 4.1 file (ASCII or binary) into a [`Mesh`], within the default
/// [`GmshLimits`].
pub fn read_gmsh(path: &Path) -> Result<Mesh, GmshError> {
    read_gmsh_limited(path, &GmshLimits::default())
}

/// Read a Gmsh MSH 4.1 file (ASCII or binary) into a [`Mesh`], refusing files and meshes
/// larger than `limits`.
pub fn read_gmsh_limited(path: &Path, limits: &GmshLimits) -> Result<Mesh, GmshError> {
    let file = path.display().to_string();
    let io = |e: std::io::Error| GmshError::Io { file: file.clone(), reason: e.to_string() };
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(GmshError::Io { file: file.clone(), reason: "not a regular file".into() });
    }
    if meta.len() > limits.max_bytes {
        return Err(GmshError::TooLarge {
            file: file.clone(),
            what: format!("{} bytes, more than the limit of {} bytes for a mesh file", meta.len(), limits.max_bytes),
        });
    }
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| std::io::Read::read_to_end(&mut std::io::Read::take(f, limits.max_bytes), &mut bytes))
        .map_err(io)?;
    parse_limited(&bytes, &file, limits)
}

/// Parse the contents of a Gmsh MSH 4.1 file (ASCII or binary) into a [`Mesh`]. Errors name
/// the input `<msh data>`.
pub fn parse_gmsh(bytes: &[u8]) -> Result<Mesh, GmshError> {
    parse_limited(bytes, "<msh data>", &GmshLimits::default())
}

/// `$MeshFormat` as far as this module needs it.
struct Format {
    binary: bool,
    /// Little-endian binary data (only meaningful when `binary`).
    little_endian: bool,
    /// Bytes of a `size_t` in binary sections.
    size_t: usize,
}

fn parse_limited(bytes: &[u8], file: &str, limits: &GmshLimits) -> Result<Mesh, GmshError> {
    let parse_err = |reason: String| GmshError::Parse { file: file.to_string(), reason };
    let format = read_format(bytes, file)?;
    let names = read_physical_names(bytes).map_err(parse_err)?;

    // mshio keeps the node tags only when they are sparse, and otherwise assumes they run
    // consecutively in file order, which converted or hand-made files need not do. Marking
    // the tags as sparse (largest tag = size_t::MAX in the section header) makes it keep
    // them. The same look at the headers rejects empty sections, on which mshio underflows.
    let mut patched = bytes.to_vec();
    let mut has_nodes = false;
    if let Some(at) = section_body(bytes, b"$Nodes") {
        has_nodes = true;
        let num_nodes = patch_section_header(&mut patched, at, &format, true).map_err(parse_err)?;
        if num_nodes == 0 {
            return Err(GmshError::NoCells { file: file.to_string() });
        }
        check_count(file, "nodes", num_nodes, limits)?;
    }
    if let Some(at) = section_body(&patched, b"$Elements") {
        let num_elements = patch_section_header(&mut patched, at, &format, false).map_err(parse_err)?;
        if num_elements == 0 {
            return Err(GmshError::NoCells { file: file.to_string() });
        }
        check_count(file, "elements", num_elements, limits)?;
    } else {
        return Err(GmshError::NoCells { file: file.to_string() });
    }
    if !has_nodes {
        return Err(parse_err("no $Nodes section".into()));
    }

    // mshio 0.4 still has a few `unimplemented!`/`expect` on malformed input; a panic there
    // must not take the caller down with it.
    let parsed = std::panic::catch_unwind(|| {
        mshio::parse_msh_bytes(&patched).map_err(|e| describe_msh_error(&e, &patched, format.binary))
    });
    let msh = match parsed {
        Ok(Ok(msh)) => msh,
        Ok(Err(reason)) => return Err(parse_err(reason)),
        Err(_) => return Err(parse_err("malformed file (the MSH parser gave up)".into())),
    };
    build_mesh(&msh, &names, file)
}

/// A section header may declare at most `limits.max_entries` entries.
fn check_count(file: &str, what: &str, declared: u64, limits: &GmshLimits) -> Result<(), GmshError> {
    if declared > limits.max_entries {
        let n = if declared < 1_000_000 { declared.to_string() } else { format!("{:.3e}", declared as f64) };
        return Err(GmshError::TooLarge {
            file: file.to_string(),
            what: format!("declares {n} {what}, more than the limit of {}", limits.max_entries),
        });
    }
    Ok(())
}

/// Check `$MeshFormat`: version 4.1, file type, `size_t` width and, for binary files, the
/// byte order.
fn read_format(bytes: &[u8], file: &str) -> Result<Format, GmshError> {
    let parse_err = |reason: &str| GmshError::Parse { file: file.to_string(), reason: reason.to_string() };
    let start = bytes.iter().position(|b| !b.is_ascii_whitespace()).unwrap_or(bytes.len());
    let rest = &bytes[start..];
    let Some(rest) = rest.strip_prefix(b"$MeshFormat") else {
        return Err(parse_err("no $MeshFormat header (not a Gmsh .msh file?)"));
    };
    let (line, after) = next_line(skip_line_end(rest));
    let line = std::str::from_utf8(line).map_err(|_| parse_err("invalid $MeshFormat line"))?;
    let tokens: Vec<&str> = line.split_whitespace().collect();
    let [version, file_type, size_t] = tokens[..] else {
        return Err(parse_err("invalid $MeshFormat line (expected `4.1 <file-type> <data-size>`)"));
    };
    if version.parse::<f64>().ok() != Some(4.1) {
        return Err(GmshError::UnsupportedVersion { file: file.to_string(), version: version.to_string() });
    }
    let binary = match file_type {
        "0" => false,
        "1" => true,
        _ => return Err(parse_err("invalid $MeshFormat file type (0 for ASCII or 1 for binary)")),
    };
    let size_t = match size_t {
        "4" => 4,
        "8" => 8,
        _ => return Err(parse_err("invalid $MeshFormat data size (4 or 8 bytes)")),
    };
    let little_endian = if binary {
        match after.get(..4) {
            Some([1, 0, 0, 0]) => true,
            Some([0, 0, 0, 1]) => false,
            _ => return Err(parse_err("binary $MeshFormat without the integer 1 that gives the byte order")),
        }
    } else {
        true
    };
    Ok(Format { binary, little_endian, size_t })
}

/// `$PhysicalNames` (always ASCII): `(dimension, tag) → name`.
fn read_physical_names(bytes: &[u8]) -> Result<BTreeMap<(i32, i32), String>, String> {
    let mut names = BTreeMap::new();
    // The section comes before $Entities and $Nodes; do not search binary data after them.
    let end = [b"$Entities".as_slice(), b"$Nodes"]
        .iter()
        .filter_map(|tag| find_line(bytes, tag))
        .min()
        .unwrap_or(bytes.len());
    let Some(at) = section_body(&bytes[..end], b"$PhysicalNames") else {
        return Ok(names);
    };
    let mut rest = &bytes[at..];
    let (line, r) = next_line(rest);
    rest = r;
    let count: usize = std::str::from_utf8(line)
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .ok_or("invalid number of physical names in $PhysicalNames")?;
    for i in 0..count {
        let (line, r) = next_line(rest);
        rest = r;
        let invalid = || format!("invalid physical name {} of {count} in $PhysicalNames", i + 1);
        let line = std::str::from_utf8(line).map_err(|_| invalid())?.trim();
        let (open, close) = (line.find('"').ok_or_else(invalid)?, line.rfind('"').ok_or_else(invalid)?);
        if close <= open {
            return Err(invalid());
        }
        let mut head = line[..open].split_whitespace().map(str::parse::<i32>);
        let (Some(Ok(dim)), Some(Ok(tag)), None) = (head.next(), head.next(), head.next()) else {
            return Err(invalid());
        };
        names.insert((dim, tag), line[open + 1..close].to_string());
    }
    Ok(names)
}

/// Check the header of `$Nodes` (`nodes = true`) or `$Elements` starting at `at`, return its
/// entry count and, for `$Nodes`, set its largest tag to the largest `size_t` (see the call).
fn patch_section_header(bytes: &mut Vec<u8>, at: usize, format: &Format, nodes: bool) -> Result<u64, String> {
    let section = if nodes { "$Nodes" } else { "$Elements" };
    if format.binary {
        let n = format.size_t;
        let field = |k: usize, bytes: &[u8]| -> Result<u64, String> {
            let b = bytes.get(at + k * n..at + (k + 1) * n).ok_or(format!("truncated {section} header"))?;
            let mut v = 0u64;
            for i in 0..n {
                let byte = if format.little_endian { b[n - 1 - i] } else { b[i] };
                v = (v << 8) | u64::from(byte);
            }
            Ok(v)
        };
        let count = field(1, bytes)?;
        field(3, bytes)?;
        if nodes {
            bytes[at + 3 * n..at + 4 * n].fill(0xff);
        }
        Ok(count)
    } else {
        // four whitespace-separated numbers: blocks, count, min tag, max tag
        let mut spans = Vec::with_capacity(4);
        let mut i = at;
        while spans.len() < 4 {
            while i < bytes.len() && bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            let start = i;
            while i < bytes.len() && !bytes[i].is_ascii_whitespace() {
                i += 1;
            }
            if start == i {
                return Err(format!("truncated {section} header"));
            }
            spans.push(start..i);
        }
        let value = |k: usize| -> Result<u64, String> {
            std::str::from_utf8(&bytes[spans[k].clone()])
                .ok()
                .and_then(|s| s.parse().ok())
                .ok_or(format!("invalid {section} header"))
        };
        let count = value(1)?;
        value(3)?;
        if nodes {
            bytes.splice(spans[3].clone(), u64::MAX.to_string().into_bytes());
        }
        Ok(count)
    }
}

/// One line of the mshio error backtrace: contexts from outside in, the error, and where.
fn describe_msh_error(err: &mshio::MshParserError<&[u8]>, input: &[u8], binary: bool) -> String {
    let trace = err.filtered_backtrace();
    let Some((at, kind)) = trace.first() else {
        return "malformed file".into();
    };
    let mut parts: Vec<String> = trace[1..].iter().rev().map(|(_, k)| k.to_string()).collect();
    parts.push(kind.to_string());
    let mut reason = parts.iter().map(|p| p.trim().trim_end_matches('.')).collect::<Vec<_>>().join(": ");
    let offset = input.len().saturating_sub(at.len());
    if binary {
        reason += &format!(" (at byte {offset})");
    } else {
        let line = input[..offset].iter().filter(|&&b| b == b'\n').count() + 1;
        reason += &format!(" (line {line})");
    }
    reason
}

/// What a Gmsh element type is, for error messages.
fn element_name(code: i32) -> &'static str {
    match code {
        1 => "2-node line",
        2 => "linear triangle",
        3 => "linear quadrangle",
        4 => "linear tetrahedron",
        5 => "linear hexahedron",
        6 => "6-node prism",
        7 => "5-node pyramid",
        8 => "quadratic line",
        9 => "quadratic triangle",
        10 => "9-node quadratic quadrangle",
        11 => "quadratic tetrahedron",
        12 => "27-node quadratic hexahedron",
        13 => "18-node quadratic prism",
        14 => "14-node quadratic pyramid",
        15 => "point",
        16 => "8-node quadratic quadrangle",
        17 => "20-node quadratic hexahedron",
        18 => "15-node quadratic prism",
        19 => "13-node quadratic pyramid",
        _ => "higher-order or special element",
    }
}

fn loam_element(t: MshElementType) -> Option<ElementType> {
    match t {
        MshElementType::Tri3 => Some(ElementType::Tri3),
        MshElementType::Qua4 => Some(ElementType::Quad4),
        MshElementType::Tet4 => Some(ElementType::Tet4),
        MshElementType::Hex8 => Some(ElementType::Hex8),
        _ => None,
    }
}

fn build_mesh(
    msh: &MshFile<u64, i32, f64>,
    names: &BTreeMap<(i32, i32), String>,
    file: &str,
) -> Result<Mesh, GmshError> {
    let parse_err = |reason: String| GmshError::Parse { file: file.to_string(), reason };

    // node tag → coordinates
    let mut node_coords: HashMap<u64, [f64; 3]> = HashMap::new();
    // (entity dim, entity tag) → node tags classified on it
    let mut entity_nodes: Vec<((i32, i32), Vec<u64>)> = Vec::new();
    if let Some(nodes) = &msh.data.nodes {
        let mut next_tag = nodes.min_node_tag;
        for block in &nodes.node_blocks {
            let tags: Vec<u64> = match &block.node_tags {
                Some(map) => {
                    let mut tags = vec![0u64; block.nodes.len()];
                    let mut seen = vec![false; block.nodes.len()];
                    for (&tag, &i) in map {
                        if i < tags.len() && !seen[i] {
                            tags[i] = tag;
                            seen[i] = true;
                        }
                    }
                    if map.len() != block.nodes.len() || seen.contains(&false) {
                        return Err(parse_err(format!(
                            "$Nodes block of entity ({}, {}) repeats a node tag",
                            block.entity_dim, block.entity_tag
                        )));
                    }
                    tags
                }
                // only if the header patch was not applied: mshio's consecutive tags
                None => (0..block.nodes.len() as u64).map(|k| next_tag + k).collect(),
            };
            next_tag += block.nodes.len() as u64;
            for (&tag, n) in tags.iter().zip(&block.nodes) {
                if node_coords.insert(tag, [n.x, n.y, n.z]).is_some() {
                    return Err(parse_err(format!("node tag {tag} is defined twice in $Nodes")));
                }
            }
            entity_nodes.push(((block.entity_dim, block.entity_tag), tags));
        }
    }

    // physical groups: (entity dim, entity tag) → names of its groups; every named group exists
    let mut groups: BTreeMap<String, BTreeSet<u64>> = names.values().map(|n| (n.clone(), BTreeSet::new())).collect();
    let mut entity_groups: HashMap<(i32, i32), Vec<String>> = HashMap::new();
    if let Some(entities) = &msh.data.entities {
        let mut add = |dim: i32, tag: i32, physical: &[i32]| {
            for &p in physical {
                let name = names.get(&(dim, p)).cloned().unwrap_or_else(|| format!("group_{p}"));
                groups.entry(name.clone()).or_default();
                entity_groups.entry((dim, tag)).or_default().push(name);
            }
        };
        entities.points.iter().for_each(|e| add(0, e.tag, &e.physical_tags));
        entities.curves.iter().for_each(|e| add(1, e.tag, &e.physical_tags));
        entities.surfaces.iter().for_each(|e| add(2, e.tag, &e.physical_tags));
        entities.volumes.iter().for_each(|e| add(3, e.tag, &e.physical_tags));
    }
    for (entity, tags) in &entity_nodes {
        for name in entity_groups.get(entity).into_iter().flatten() {
            if let Some(group) = groups.get_mut(name) {
                group.extend(tags.iter().copied());
            }
        }
    }

    // cells: the elements of the highest dimension
    let blocks: &[_] = msh.data.elements.as_ref().map_or(&[], |e| &e.element_blocks[..]);
    let dim = blocks.iter().filter(|b| !b.elements.is_empty()).map(|b| b.entity_dim).max();
    let dim = match dim {
        Some(d) if d >= 2 => d,
        _ => return Err(GmshError::NoCells { file: file.to_string() }),
    };
    let mut element: Option<ElementType> = None;
    let mut cell_tags: Vec<u64> = Vec::new();
    for block in blocks {
        if block.entity_dim == dim && !block.elements.is_empty() {
            let this = loam_element(block.element_type).ok_or_else(|| {
                let code = block.element_type as i32;
                GmshError::UnsupportedElement { file: file.to_string(), code, name: element_name(code) }
            })?;
            match element {
                Some(first) if first != this => {
                    return Err(GmshError::MixedElements { file: file.to_string(), first, second: this })
                }
                _ => element = Some(this),
            }
            for e in &block.elements {
                cell_tags.extend_from_slice(&e.nodes);
            }
        }
        for name in entity_groups.get(&(block.entity_dim, block.entity_tag)).into_iter().flatten() {
            if let Some(group) = groups.get_mut(name) {
                block.elements.iter().for_each(|e| group.extend(e.nodes.iter().copied()));
            }
        }
    }
    let element = element.ok_or_else(|| GmshError::NoCells { file: file.to_string() })?;

    // renumber the used nodes in ascending tag order
    let mut used: BTreeSet<u64> = cell_tags.iter().copied().collect();
    groups.values().for_each(|g| used.extend(g.iter().copied()));
    let mut index: HashMap<u64, usize> = HashMap::with_capacity(used.len());
    let mut coords = Vec::with_capacity(used.len());
    for &tag in &used {
        let x = node_coords
            .get(&tag)
            .ok_or_else(|| parse_err(format!("$Elements refers to node {tag}, which $Nodes does not define")))?;
        index.insert(tag, coords.len());
        coords.push(*x);
    }
    let mut connectivity: Vec<usize> = cell_tags.iter().map(|t| index[t]).collect();
    orient_cells(element, &coords, &mut connectivity);
    let node_groups = groups.into_iter().map(|(name, tags)| (name, tags.iter().map(|t| index[t]).collect())).collect();
    Ok(Mesh { element, coords, connectivity, node_groups })
}

/// Reverse every cell whose area (xy-plane) or volume is negative.
fn orient_cells(element: ElementType, coords: &[[f64; 3]], connectivity: &mut [usize]) {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let det = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])
    };
    let nn = element.num_nodes();
    for cell in connectivity.chunks_exact_mut(nn) {
        let x = |a: usize| coords[cell[a]];
        let measure = match element {
            // shoelace formula
            ElementType::Tri3 | ElementType::Quad4 => {
                (0..nn).map(|a| x(a)[0] * x((a + 1) % nn)[1] - x((a + 1) % nn)[0] * x(a)[1]).sum::<f64>()
            }
            ElementType::Tet4 => det(sub(x(1), x(0)), sub(x(2), x(0)), sub(x(3), x(0))),
            // Jacobian at the centre, up to a positive factor
            ElementType::Hex8 => {
                let s = |plus: [usize; 4], minus: [usize; 4]| {
                    let mut v = [0.0; 3];
                    for d in 0..3 {
                        v[d] = plus.iter().map(|&a| x(a)[d]).sum::<f64>() - minus.iter().map(|&a| x(a)[d]).sum::<f64>();
                    }
                    v
                };
                det(s([1, 2, 5, 6], [0, 3, 4, 7]), s([2, 3, 6, 7], [0, 1, 4, 5]), s([4, 5, 6, 7], [0, 1, 2, 3]))
            }
        };
        if measure < 0.0 {
            match element {
                ElementType::Tri3 | ElementType::Tet4 => cell.swap(1, 2),
                ElementType::Quad4 => cell.swap(1, 3),
                ElementType::Hex8 => {
                    cell.swap(1, 3);
                    cell.swap(5, 7);
                }
            }
        }
    }
}

/// Offset of the line after the first line that reads exactly `tag`, if any.
fn section_body(bytes: &[u8], tag: &[u8]) -> Option<usize> {
    let start = find_line(bytes, tag)?;
    let after = start + tag.len();
    Some(after + (bytes.len() - after - skip_line_end(&bytes[after..]).len()))
}

/// Offset of the first line that consists of `tag` (optionally followed by `\r`).
fn find_line(bytes: &[u8], tag: &[u8]) -> Option<usize> {
    let mut from = 0;
    while from + tag.len() <= bytes.len() {
        let pos = from + bytes[from..].windows(tag.len()).position(|w| w == tag)?;
        let line_start = pos == 0 || bytes[pos - 1] == b'\n';
        let end = &bytes[pos + tag.len()..];
        let line_end = matches!(end, [] | [b'\n', ..] | [b'\r', b'\n', ..]);
        if line_start && line_end {
            return Some(pos);
        }
        from = pos + 1;
    }
    None
}

/// `bytes` after an optional `\r` and `\n`.
fn skip_line_end(bytes: &[u8]) -> &[u8] {
    let bytes = bytes.strip_prefix(b"\r").unwrap_or(bytes);
    bytes.strip_prefix(b"\n").unwrap_or(bytes)
}

/// The next line (without its line end) and what follows it.
fn next_line(bytes: &[u8]) -> (&[u8], &[u8]) {
    match bytes.iter().position(|&b| b == b'\n') {
        Some(i) => (&bytes[..i], &bytes[i + 1..]),
        None => (bytes, &[]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two quads on [0, 2] × [0, 1], a physical line "left", a physical surface "soil" and an
    /// unnamed physical point (tag 3) on node 77, which no cell uses. Node tags are sparse and
    /// out of order; node 99 (on a point entity of no physical group) must be dropped.
    const TWO_QUADS: &str = r#"$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
1 1 "left"
2 2 "soil"
$EndPhysicalNames
$Entities
2 1 1 0
8 7 7 7 0
9 5 5 0 1 3
4 0 0 0 0 1 0 1 1 0
1 0 0 0 2 1 0 1 2 0
$EndEntities
$Nodes
4 8 10 99
0 9 0 1
77
5 5 0
0 8 0 1
99
7 7 7
1 4 0 2
10
40
0 0 0
0 1 0
2 1 0 4
60
20
50
30
2 1 0
1 0 0
1 1 0
2 0 0
$EndNodes
$Elements
3 4 1 5
1 4 1 1
1 10 40
2 1 3 2
2 10 20 50 40
3 20 30 60 50
0 9 15 1
5 77
$EndElements
"#;

    #[test]
    fn hand_written_two_quads_with_groups() {
        let mesh = parse_gmsh(TWO_QUADS.as_bytes()).unwrap();
        assert_eq!(mesh.element, ElementType::Quad4);
        // ascending tags 10, 20, 30, 40, 50, 60, 77 → 0..7; 99 dropped
        let expected = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, 1.0], [2.0, 1.0], [5.0, 5.0]];
        assert_eq!(mesh.coords.len(), expected.len());
        for (x, e) in mesh.coords.iter().zip(&expected) {
            assert_eq!(*x, [e[0], e[1], 0.0]);
        }
        assert_eq!(mesh.connectivity, vec![0, 1, 4, 3, 1, 2, 5, 4]);
        let groups: Vec<(&str, &[usize])> = mesh.node_groups.iter().map(|(k, v)| (k.as_str(), &v[..])).collect();
        assert_eq!(groups, vec![("group_3", &[6][..]), ("left", &[0, 3][..]), ("soil", &[0, 1, 2, 3, 4, 5][..])]);
    }

    /// Encode `mesh` as MSH 4.1 with node `i` tagged `tag(i)`: one domain entity (physical
    /// "domain") and a boundary entity (physical "bottom") with the facets on `min y` (2D) or
    /// `min z` (3D) as lower-dimensional elements.
    fn encode(mesh: &Mesh, binary: bool, tag: impl Fn(usize) -> u64) -> Vec<u8> {
        let dim = mesh.element.dim();
        let axis = dim - 1;
        let low = mesh.coords.iter().map(|x| x[axis]).fold(f64::INFINITY, f64::min);
        let bottom: Vec<Vec<usize>> =
            mesh.boundary_facets().into_iter().filter(|f| f.iter().all(|&a| mesh.coords[a][axis] == low)).collect();
        let (cell_type, facet_type) = match mesh.element {
            ElementType::Tri3 => (2, 1),
            ElementType::Quad4 => (3, 1),
            ElementType::Tet4 => (4, 2),
            ElementType::Hex8 => (5, 3),
        };
        let mut out = Vec::new();
        let text = |out: &mut Vec<u8>, s: &str| out.extend_from_slice(s.as_bytes());
        // binary: int = i32, size_t = u64, little-endian; ASCII: space-separated
        let int = |out: &mut Vec<u8>, v: i32| {
            if binary {
                out.extend_from_slice(&v.to_le_bytes())
            } else {
                out.extend_from_slice(format!("{v} ").as_bytes())
            }
        };
        let size = |out: &mut Vec<u8>, v: u64| {
            if binary {
                out.extend_from_slice(&v.to_le_bytes())
            } else {
                out.extend_from_slice(format!("{v} ").as_bytes())
            }
        };
        let float = |out: &mut Vec<u8>, v: f64| {
            if binary {
                out.extend_from_slice(&v.to_le_bytes())
            } else {
                out.extend_from_slice(format!("{v:?} ").as_bytes())
            }
        };
        let newline = |out: &mut Vec<u8>| {
            if !binary {
                out.push(b'\n')
            }
        };
        text(&mut out, &format!("$MeshFormat\n4.1 {} 8\n", u8::from(binary)));
        if binary {
            out.extend_from_slice(&1i32.to_le_bytes());
            out.push(b'\n');
        }
        text(&mut out, "$EndMeshFormat\n$PhysicalNames\n2\n");
        text(&mut out, &format!("{} 1 \"domain\"\n{} 2 \"bottom\"\n$EndPhysicalNames\n", dim, dim - 1));
        text(&mut out, "$Entities\n");
        let mut counts = [0u64; 4];
        counts[dim] = 1;
        counts[dim - 1] = 1;
        counts.iter().for_each(|&c| size(&mut out, c));
        newline(&mut out);
        for (physical, bounding) in [(2, 0), (1, 0)] {
            // the boundary entity (dim − 1) comes first in the file
            let _ = bounding;
            int(&mut out, 1);
            for _ in 0..6 {
                float(&mut out, 0.0);
            }
            size(&mut out, 1);
            int(&mut out, physical);
            size(&mut out, 0);
            newline(&mut out);
        }
        text(&mut out, if binary { "\n$EndEntities\n$Nodes\n" } else { "$EndEntities\n$Nodes\n" });
        let n = mesh.coords.len();
        let tags: Vec<u64> = (0..n).map(&tag).collect();
        for v in [1, n as u64, *tags.iter().min().unwrap(), *tags.iter().max().unwrap()] {
            size(&mut out, v);
        }
        newline(&mut out);
        for v in [dim as i32, 1, 0] {
            int(&mut out, v);
        }
        size(&mut out, n as u64);
        newline(&mut out);
        for &t in &tags {
            size(&mut out, t);
            newline(&mut out);
        }
        for x in &mesh.coords {
            x.iter().for_each(|&c| float(&mut out, c));
            newline(&mut out);
        }
        text(&mut out, if binary { "\n$EndNodes\n$Elements\n" } else { "$EndNodes\n$Elements\n" });
        let total = (bottom.len() + mesh.num_cells()) as u64;
        for v in [2, total, 1, total] {
            size(&mut out, v);
        }
        newline(&mut out);
        let mut element_tag = 0;
        for (d, kind, cells) in [
            (dim - 1, facet_type, bottom.clone()),
            (dim, cell_type, (0..mesh.num_cells()).map(|e| mesh.cell(e).to_vec()).collect()),
        ] {
            for v in [d as i32, 1, kind] {
                int(&mut out, v);
            }
            size(&mut out, cells.len() as u64);
            newline(&mut out);
            for cell in cells {
                element_tag += 1;
                size(&mut out, element_tag);
                cell.iter().for_each(|&a| size(&mut out, tags[a]));
                newline(&mut out);
            }
        }
        text(&mut out, if binary { "\n$EndElements\n" } else { "$EndElements\n" });
        out
    }

    /// `mesh` read back equals `original` up to the node numbering.
    fn assert_same_mesh(read: &Mesh, original: &Mesh, axis: usize) {
        assert_eq!(read.element, original.element);
        assert_eq!(read.num_cells(), original.num_cells());
        assert_eq!(read.coords.len(), original.coords.len());
        for e in 0..original.num_cells() {
            let a: Vec<[f64; 3]> = read.cell(e).iter().map(|&i| read.coords[i]).collect();
            let b: Vec<[f64; 3]> = original.cell(e).iter().map(|&i| original.coords[i]).collect();
            assert_eq!(a, b, "cell {e}");
        }
        let low = original.coords.iter().map(|x| x[axis]).fold(f64::INFINITY, f64::min);
        let bottom = &read.node_groups["bottom"];
        let expected = original.coords.iter().filter(|x| x[axis] == low).count();
        assert_eq!(bottom.len(), expected);
        assert!(bottom.iter().all(|&i| read.coords[i][axis] == low));
        assert_eq!(read.node_groups["domain"].len(), original.coords.len());
    }

    #[test]
    fn quad_and_triangle_meshes_ascii_and_binary() {
        for element in [ElementType::Quad4, ElementType::Tri3] {
            let mesh = Mesh::rectangle([1.0, -2.0], [3.0, 2.0], [4, 3], element);
            let n = mesh.coords.len() as u64;
            for binary in [false, true] {
                // consecutive tags in descending order: mshio would misplace them unpatched
                let bytes = encode(&mesh, binary, |i| n - i as u64);
                let read = parse_gmsh(&bytes).unwrap_or_else(|e| panic!("{e}"));
                assert_same_mesh(&read, &mesh, 1);
                // sparse tags in ascending order keep the numbering
                let read = parse_gmsh(&encode(&mesh, binary, |i| 3 * i as u64 + 5)).unwrap();
                assert_eq!(read, Mesh { node_groups: read.node_groups.clone(), ..mesh.clone() });
            }
        }
    }

    #[test]
    fn tet_and_hex_meshes() {
        for element in [ElementType::Tet4, ElementType::Hex8] {
            let mesh = Mesh::cuboid([0.0; 3], [1.0, 2.0, 3.0], [2, 2, 2], element);
            for binary in [false, true] {
                let read = parse_gmsh(&encode(&mesh, binary, |i| i as u64 + 1)).unwrap();
                assert_same_mesh(&read, &mesh, 2);
            }
        }
    }

    #[test]
    fn clockwise_cells_are_reversed() {
        let mut mesh = Mesh::rectangle([0.0, 0.0], [1.0, 1.0], [2, 2], ElementType::Quad4);
        for cell in mesh.connectivity.chunks_exact_mut(4) {
            cell.reverse();
        }
        let read = parse_gmsh(&encode(&mesh, false, |i| i as u64 + 1)).unwrap();
        for e in 0..read.num_cells() {
            let x: Vec<[f64; 3]> = read.cell(e).iter().map(|&i| read.coords[i]).collect();
            let area: f64 =
                (0..4).map(|a| x[a][0] * x[(a + 1) % 4][1] - x[(a + 1) % 4][0] * x[a][1]).sum::<f64>() / 2.0;
            assert!((area - 0.25).abs() < 1e-12, "cell {e} area {area}");
        }
    }

    #[test]
    fn version_2_2_is_rejected_with_the_conversion_command() {
        let err = parse_gmsh(b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n1\n1 0 0 0\n$EndNodes\n").unwrap_err();
        assert!(matches!(err, GmshError::UnsupportedVersion { ref version, .. } if version == "2.2"));
        let message = err.to_string();
        assert!(message.starts_with("<msh data>: version 2.2 is not supported"), "{message}");
        assert!(message.contains("-format msh41"), "{message}");
    }

    #[test]
    fn truncated_files_are_rejected_without_panic() {
        let mesh = Mesh::rectangle([0.0, 0.0], [1.0, 1.0], [2, 1], ElementType::Tri3);
        for bytes in [TWO_QUADS.as_bytes().to_vec(), encode(&mesh, true, |i| i as u64 + 1)] {
            let end = bytes.windows(12).position(|w| w == b"$EndElements").unwrap();
            for len in 0..end {
                let result = parse_gmsh(&bytes[..len]);
                assert!(result.is_err(), "prefix of {len} bytes accepted");
            }
        }
        let cut = &TWO_QUADS[..TWO_QUADS.find("2 10 20 50").unwrap() + 5];
        let message = parse_gmsh(cut.as_bytes()).unwrap_err().to_string();
        assert!(message.starts_with("<msh data>: cannot read: "), "{message}");
        assert!(!message.contains('\n'), "{message}");
    }

    #[test]
    fn unsupported_mixed_empty_and_missing() {
        let quadratic = TWO_QUADS.replace("2 1 3 2\n2 10 20 50 40\n3 20 30 60 50", "2 1 9 1\n2 10 20 50 40 60 30");
        let message = parse_gmsh(quadratic.as_bytes()).unwrap_err().to_string();
        assert!(message.starts_with("<msh data>: unsupported element type 9 (quadratic triangle)"), "{message}");

        let mixed =
            TWO_QUADS.replace("3 4 1 5\n", "4 5 1 6\n").replace("$EndElements", "2 1 2 1\n6 10 20 50\n$EndElements");
        let err = parse_gmsh(mixed.as_bytes()).unwrap_err();
        assert_eq!(err.to_string(), "<msh data>: mixed quad4 and tri3 cells; a Loam mesh holds one element type");

        let lines_only =
            TWO_QUADS.replace("3 4 1 5\n", "2 2 1 5\n").replace("2 1 3 2\n2 10 20 50 40\n3 20 30 60 50\n", "");
        assert!(matches!(parse_gmsh(lines_only.as_bytes()), Err(GmshError::NoCells { .. })));

        let missing_node = TWO_QUADS.replace("3 20 30 60 50", "3 20 30 60 55");
        let message = parse_gmsh(missing_node.as_bytes()).unwrap_err().to_string();
        assert!(message.contains("node 55"), "{message}");

        let err = read_gmsh(Path::new("/nonexistent/mesh.msh")).unwrap_err();
        assert!(err.to_string().starts_with("/nonexistent/mesh.msh: cannot open: "), "{err}");
    }

    /// A header declaring more nodes or elements than the limits allow is refused before the
    /// sections are parsed (issue 16).
    #[test]
    fn declared_sizes_beyond_the_limits_are_refused() {
        let limits = GmshLimits { max_entries: 5, ..GmshLimits::default() };
        let err = parse_limited(TWO_QUADS.as_bytes(), "m.msh", &limits).unwrap_err();
        assert_eq!(err.to_string(), "m.msh: declares 8 nodes, more than the limit of 5");
        let huge = TWO_QUADS.replace("4 8 10 99", "4 100000000000000000 10 99");
        let err = parse_limited(huge.as_bytes(), "m.msh", &GmshLimits { max_entries: 1000, ..GmshLimits::default() });
        assert_eq!(err.unwrap_err().to_string(), "m.msh: declares 1.000e17 nodes, more than the limit of 1000");
        let err = read_gmsh(Path::new("/dev/zero")).unwrap_err();
        assert_eq!(err.to_string(), "/dev/zero: cannot open: not a regular file");
    }

    mod properties {
        use proptest::prelude::*;

        use super::*;

        /// An edit of a valid file: a byte replaced, a run deleted, digits inserted, or the
        /// file truncated.
        #[derive(Debug, Clone)]
        enum Edit {
            Replace(usize, u8),
            Delete(usize, usize),
            Insert(usize, String),
            Truncate(usize),
        }

        fn edit() -> impl Strategy<Value = Edit> {
            prop_oneof![
                (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Edit::Replace(i, b)),
                (any::<usize>(), 1usize..40).prop_map(|(i, n)| Edit::Delete(i, n)),
                (any::<usize>(), "[0-9 .e\\-\\n$]{1,12}").prop_map(|(i, s)| Edit::Insert(i, s)),
                any::<usize>().prop_map(Edit::Truncate),
            ]
        }

        fn apply(mut bytes: Vec<u8>, edits: &[Edit]) -> Vec<u8> {
            for e in edits {
                let n = bytes.len().max(1);
                match e {
                    Edit::Replace(i, b) => {
                        if !bytes.is_empty() {
                            bytes[i % n] = *b
                        }
                    }
                    Edit::Delete(i, k) => {
                        let start = (i % n).min(bytes.len());
                        let end = (start + k).min(bytes.len());
                        bytes.drain(start..end);
                    }
                    Edit::Insert(i, s) => {
                        let at = (i % n).min(bytes.len());
                        bytes.splice(at..at, s.bytes());
                    }
                    Edit::Truncate(i) => bytes.truncate(i % n),
                }
            }
            bytes
        }

        fn one_line(result: Result<Mesh, GmshError>) -> Result<(), TestCaseError> {
            if let Err(e) = result {
                let m = e.to_string();
                prop_assert!(!m.contains('\n'), "message of more than one line: {m:?}");
            }
            Ok(())
        }

        proptest! {
            #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

            /// Issue 16: no byte string makes the reader panic.
            #[test]
            fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..2048)) {
                one_line(parse_gmsh(&bytes))?;
                let mut with_header = b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n".to_vec();
                with_header.extend_from_slice(&bytes);
                one_line(parse_gmsh(&with_header))?;
            }

            /// Issue 16: edits of valid ASCII and binary files (headers, counts, tags,
            /// coordinates, truncations) give a mesh or a one-line error, never a panic.
            #[test]
            fn edited_files_never_panic(edits in proptest::collection::vec(edit(), 1..6), binary in any::<bool>()) {
                let base = if binary {
                    let mesh = Mesh::rectangle([0.0, 0.0], [2.0, 1.0], [2, 2], ElementType::Quad4);
                    encode(&mesh, true, |i| 7 * i as u64 + 3)
                } else {
                    TWO_QUADS.as_bytes().to_vec()
                };
                let bytes = apply(base, &edits);
                let limits = GmshLimits { max_entries: 10_000, ..GmshLimits::default() };
                one_line(parse_limited(&bytes, "edited.msh", &limits))?;
            }
        }
    }
}
