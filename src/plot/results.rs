//! Reading a run's VTK output: the `.pvd` series of each domain and the `.vtu` files they
//! list (docs/cli.md, "Output"; `crate::output` writes them).
//!
//! A series is one of four kinds, told apart by what its files hold:
//! - **material points**: vertex cells with a `volume` field (MPM domains);
//! - **mesh**: cells of a 2D or 3D element type (FEM domains, in their reference
//!   configuration, with the point field `displacement`);
//! - **wall points**: vertex cells without `volume` (the penalty points of a wall);
//! - **background grid**: `<domain>_grid.pvd` (with `output.grid`).

use std::path::{Path, PathBuf};

use vtkio::model::{Attribute, CellType, DataSet, Piece as VtkPiece, VertexNumbers};

use super::PlotError;

/// A `.pvd` series: its name (file stem) and its steps (time, `.vtu` path).
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// File stem of the `.pvd` (the domain's or wall's name).
    pub name: String,
    /// (time, file) per output step, as listed.
    pub steps: Vec<(f64, PathBuf)>,
    /// Whether the name says it is a background grid (`<domain>_grid.pvd`).
    pub is_grid: bool,
}

/// The value of attribute `name` in the attributes text of one XML tag.
fn attribute(tag: &str, name: &str) -> Option<String> {
    let mut rest = tag;
    while let Some(i) = rest.find(name) {
        let before = rest[..i].chars().last();
        let after = rest[i + name.len()..].trim_start();
        rest = &rest[i + name.len()..];
        if before.is_some_and(|c| !c.is_whitespace()) {
            continue;
        }
        let Some(after) = after.strip_prefix('=') else { continue };
        let after = after.trim_start();
        let quote = after.chars().next()?;
        if quote != '"' && quote != '\'' {
            return None;
        }
        let end = after[1..].find(quote)?;
        let raw = &after[1..1 + end];
        return Some(
            raw.replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&apos;", "'")
                .replace("&amp;", "&"),
        );
    }
    None
}

/// Reads a `.pvd` collection: the `timestep` and `file` of every `DataSet`, in file order
/// (paths relative to the `.pvd`'s directory). A collection of several parts (the
/// `<case>.pvd` that lists every output of a run for ParaView) is not a series of its own:
/// `None`.
pub fn read_pvd(path: &Path) -> Result<Option<Series>, PlotError> {
    let bad = |reason: String| PlotError::Read { file: path.to_path_buf(), reason };
    let text = std::fs::read_to_string(path).map_err(|e| bad(e.to_string()))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut steps = Vec::new();
    for chunk in text.split("<DataSet").skip(1) {
        let tag = &chunk[..chunk.find('>').ok_or_else(|| bad("unterminated DataSet tag".into()))?];
        let time = attribute(tag, "timestep")
            .ok_or_else(|| bad("a DataSet has no timestep".into()))?
            .trim()
            .parse::<f64>()
            .map_err(|e| bad(format!("timestep: {e}")))?;
        let file = attribute(tag, "file").ok_or_else(|| bad("a DataSet has no file".into()))?;
        if attribute(tag, "part").is_some_and(|p| p.trim() != "0") {
            return Ok(None);
        }
        steps.push((time, dir.join(file)));
    }
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(Some(Series { is_grid: name.ends_with("_grid"), name, steps }))
}

/// The `.pvd` series in `dir`, sorted by name.
pub fn find_series(dir: &Path) -> Result<Vec<Series>, PlotError> {
    let entries =
        std::fs::read_dir(dir).map_err(|e| PlotError::Read { file: dir.to_path_buf(), reason: e.to_string() })?;
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "pvd"))
        .collect();
    paths.sort();
    Ok(paths.iter().map(|p| read_pvd(p)).collect::<Result<Vec<_>, _>>()?.into_iter().flatten().collect())
}

/// A named field: `components` values per point or cell, back to back.
#[derive(Debug, Clone, PartialEq)]
pub struct FieldData {
    /// Name as written.
    pub name: String,
    /// Values per entry: 1 scalar, 3 vector, 9 tensor (row-major 3×3).
    pub components: usize,
    /// The values.
    pub values: Vec<f64>,
}

/// Element shape of a mesh's cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Shape {
    /// 3-node triangle.
    Triangle,
    /// 4-node quadrilateral.
    Quad,
    /// 4-node tetrahedron.
    Tetra,
    /// 8-node hexahedron.
    Hexahedron,
}

impl Shape {
    /// Nodes per cell.
    pub fn nodes(self) -> usize {
        match self {
            Shape::Triangle => 3,
            Shape::Quad | Shape::Tetra => 4,
            Shape::Hexahedron => 8,
        }
    }
}

/// The cells of a piece.
#[derive(Debug, Clone, PartialEq)]
pub enum Cells {
    /// One vertex per point (a point cloud).
    Vertices,
    /// Cells of one shape, `shape.nodes()` point indices each, back to back.
    Mesh {
        /// Their shape.
        shape: Shape,
        /// Point indices.
        connectivity: Vec<usize>,
    },
}

/// One `.vtu` file: points, cells and fields.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Point coordinates.
    pub points: Vec<[f64; 3]>,
    /// Cells.
    pub cells: Cells,
    /// Fields per point.
    pub point_fields: Vec<FieldData>,
    /// Fields per cell.
    pub cell_fields: Vec<FieldData>,
}

/// What a series shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesKind {
    /// MPM material points.
    MaterialPoints,
    /// An FEM mesh.
    Mesh,
    /// The penalty points of a wall.
    WallPoints,
    /// An MPM background grid.
    Grid,
}

impl Piece {
    /// A field by name, on points or (else) on cells, with whether it is a cell field.
    pub fn field(&self, name: &str) -> Option<(&FieldData, bool)> {
        self.point_fields
            .iter()
            .find(|f| f.name == name)
            .map(|f| (f, false))
            .or_else(|| self.cell_fields.iter().find(|f| f.name == name).map(|f| (f, true)))
    }

    /// The kind of series this piece belongs to (`is_grid` from the series' name).
    pub fn kind(&self, is_grid: bool) -> SeriesKind {
        match (&self.cells, is_grid) {
            (Cells::Mesh { .. }, true) => SeriesKind::Grid,
            (Cells::Mesh { .. }, false) => SeriesKind::Mesh,
            (Cells::Vertices, _) if self.field("volume").is_some() => SeriesKind::MaterialPoints,
            (Cells::Vertices, _) => SeriesKind::WallPoints,
        }
    }
}

fn fields(attributes: Vec<Attribute>, count: usize, file: &Path) -> Result<Vec<FieldData>, PlotError> {
    let mut out = Vec::new();
    for a in attributes {
        let Attribute::DataArray(d) = a else { continue };
        let components = d.elem.num_comp() as usize;
        let values: Vec<f64> = d.data.cast_into().ok_or_else(|| PlotError::Read {
            file: file.to_path_buf(),
            reason: format!("field `{}` is not numeric", d.name),
        })?;
        if components == 0 || values.len() != components * count {
            return Err(PlotError::Read {
                file: file.to_path_buf(),
                reason: format!("field `{}` has {} values for {count} entries", d.name, values.len()),
            });
        }
        out.push(FieldData { name: d.name, components, values });
    }
    Ok(out)
}

/// Reads a `.vtu` unstructured grid of one cell type (vertices, triangles, quads, tetrahedra
/// or hexahedra) with its fields — or a `.pvtu` (a distributed run's output: one `.vtu` piece
/// per rank, docs/distributed.md), its pieces joined into one: points back to back, cells
/// renumbered, fields joined (the pieces must share their cell shape and fields).
pub fn read_vtu(path: &Path) -> Result<Piece, PlotError> {
    let bad = |reason: String| PlotError::Read { file: path.to_path_buf(), reason };
    let first_line = |e: &dyn std::fmt::Display| e.to_string().lines().next().unwrap_or("").to_string();
    let mut vtk = vtkio::Vtk::import(path).map_err(|e| bad(first_line(&e)))?;
    vtk.load_all_pieces().map_err(|e| bad(format!("its pieces: {}", first_line(&e))))?;
    let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else {
        return Err(bad("not an unstructured grid".into()));
    };
    let mut joined: Option<Piece> = None;
    for piece in pieces {
        let VtkPiece::Inline(piece) = piece else { return Err(bad("piece not inline".into())) };
        let piece = read_piece(*piece, path)?;
        joined = Some(match joined {
            None => piece,
            Some(whole) => whole.join(piece).map_err(bad)?,
        });
    }
    joined.ok_or_else(|| bad("no piece".into()))
}

impl Piece {
    /// `self` followed by `next` (the next piece of a `.pvtu`): `next`'s cells renumbered
    /// past `self`'s points; an error naming what differs if the two do not match.
    fn join(mut self, next: Piece) -> Result<Piece, String> {
        let offset = self.points.len();
        match (&mut self.cells, next.cells) {
            (Cells::Vertices, Cells::Vertices) => {}
            (Cells::Mesh { shape, connectivity }, Cells::Mesh { shape: s, connectivity: c }) if *shape == s => {
                connectivity.extend(c.into_iter().map(|a| a + offset));
            }
            _ => return Err("its pieces have different cell shapes".into()),
        }
        self.points.extend(next.points);
        let join_fields = |a: &mut Vec<FieldData>, b: Vec<FieldData>, on: &str| {
            if a.len() != b.len() || a.iter().zip(&b).any(|(x, y)| x.name != y.name || x.components != y.components) {
                return Err(format!("its pieces have different {on} fields"));
            }
            for (x, y) in a.iter_mut().zip(b) {
                x.values.extend(y.values);
            }
            Ok(())
        };
        join_fields(&mut self.point_fields, next.point_fields, "point")?;
        join_fields(&mut self.cell_fields, next.cell_fields, "cell")?;
        Ok(self)
    }
}

/// One inline piece of a `.vtu` (or of a `.pvtu`'s piece files) read from `path`.
fn read_piece(piece: vtkio::model::UnstructuredGridPiece, path: &Path) -> Result<Piece, PlotError> {
    let bad = |reason: String| PlotError::Read { file: path.to_path_buf(), reason };
    let coords: Vec<f64> = piece.points.cast_into().ok_or_else(|| bad("points are not numeric".into()))?;
    if coords.len() % 3 != 0 {
        return Err(bad("point coordinates are not triples".into()));
    }
    let points: Vec<[f64; 3]> = coords.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let n = points.len();
    let types = &piece.cells.types;
    let num_cells = types.len();
    let (connectivity, offsets) = match piece.cells.cell_verts {
        VertexNumbers::XML { connectivity, offsets } => (connectivity, offsets),
        legacy => legacy.into_xml(),
    };
    let shape = match types.first() {
        None | Some(CellType::Vertex) => None,
        Some(CellType::Triangle) => Some(Shape::Triangle),
        Some(CellType::Quad) => Some(Shape::Quad),
        Some(CellType::Tetra) => Some(Shape::Tetra),
        Some(CellType::Hexahedron) => Some(Shape::Hexahedron),
        Some(t) => {
            return Err(bad(format!("cell type {t:?} is not drawn (vertex, triangle, quad, tetra, hexahedron)")))
        }
    };
    if types.iter().any(|t| Some(t) != types.first()) {
        return Err(bad("cells of several types".into()));
    }
    let cells = match shape {
        None => Cells::Vertices,
        Some(shape) => {
            let nn = shape.nodes();
            let regular = offsets.iter().enumerate().all(|(c, &o)| o as usize == (c + 1) * nn);
            if !regular || connectivity.len() != num_cells * nn {
                return Err(bad(format!("cells are not all {nn}-node {shape:?}s")));
            }
            let connectivity: Vec<usize> = connectivity.iter().map(|&a| a as usize).collect();
            if let Some(a) = connectivity.iter().find(|&&a| a >= n) {
                return Err(bad(format!("a cell refers to point {a} of {n}")));
            }
            Cells::Mesh { shape, connectivity }
        }
    };
    let point_fields = fields(piece.data.point, n, path)?;
    let cell_fields = fields(piece.data.cell, num_cells, path)?;
    Ok(Piece { points, cells, point_fields, cell_fields })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pvd_attributes_in_any_order_and_escaped() {
        let dir = std::env::temp_dir().join(format!("loam-plot-pvd-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("soil.pvd");
        std::fs::write(
            &path,
            "<VTKFile type=\"Collection\"><Collection>\n\
             <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"soil_000000.vtu\"/>\n\
             <DataSet file='a&amp;b.vtu' part=\"0\" timestep=\"1.5e-2\"/>\n\
             </Collection></VTKFile>",
        )
        .unwrap();
        let s = read_pvd(&path).unwrap().unwrap();
        assert_eq!(s.name, "soil");
        assert!(!s.is_grid);
        assert_eq!(s.steps, vec![(0.0, dir.join("soil_000000.vtu")), (0.015, dir.join("a&b.vtu"))]);
        std::fs::write(&path, "<DataSet file=\"x.vtu\"/>").unwrap();
        assert!(read_pvd(&path).unwrap_err().to_string().contains("no timestep"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A `.pvtu` of a distributed run reads as one piece: a mesh of three quads in two pieces
    /// (the shared edge's points in both) and a cloud of seven points in three.
    #[test]
    fn a_pvtu_reads_as_its_pieces_joined() {
        use crate::output::pvtu::{parallel_file, piece_file, write_pvtu};
        use crate::output::vtk_output::write_output;
        use loam_fem::domain::{DomainOutput, Field};
        use loam_fem::element::ElementType;
        let dir = std::env::temp_dir().join(format!("loam-plot-pvtu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let field = |name: &str, components, values| Field { name: name.into(), components, values };
        let mesh_points: Vec<[f64; 3]> = (0..8).map(|a| [(a / 2) as f64, (a % 2) as f64, 0.0]).collect();
        let mesh = DomainOutput {
            point_fields: vec![field("u", 3, mesh_points.iter().flat_map(|x| [x[0], x[1], 0.0]).collect())],
            points: mesh_points,
            cells: Some((ElementType::Quad4, vec![0, 2, 3, 1, 2, 4, 5, 3, 4, 6, 7, 5])),
            cell_fields: vec![field("pressure", 1, vec![1.0, 2.0, 3.0])],
        };
        let cloud = DomainOutput {
            points: (0..7).map(|i| [i as f64, 0.5, 0.0]).collect(),
            cells: None,
            point_fields: vec![field("volume", 1, (0..7).map(f64::from).collect())],
            cell_fields: vec![],
        };
        for (name, output, ranks) in [("plate", &mesh, 2), ("soil", &cloud, 3)] {
            let sources: Vec<String> = (0..ranks).map(|r| piece_file(name, 4, r)).collect();
            for (r, file) in sources.iter().enumerate() {
                write_output(&dir.join(file), &output.piece(r, ranks)).unwrap();
            }
            write_pvtu(&dir.join(parallel_file(name, 4)), output, &sources).unwrap();
        }
        let plate = read_vtu(&dir.join(parallel_file("plate", 4))).unwrap();
        let Cells::Mesh { shape, connectivity } = &plate.cells else { panic!("a mesh") };
        assert_eq!((*shape, connectivity.len(), plate.points.len()), (Shape::Quad, 12, 10));
        for (c, cell) in connectivity.chunks_exact(4).enumerate() {
            let x: Vec<[f64; 3]> = cell.iter().map(|&a| plate.points[a]).collect();
            let want: Vec<[f64; 3]> =
                mesh.cells.as_ref().unwrap().1[4 * c..4 * c + 4].iter().map(|&a| mesh.points[a]).collect();
            assert_eq!(x, want, "cell {c}'s corners");
        }
        assert_eq!(plate.field("pressure").unwrap().0.values, vec![1.0, 2.0, 3.0]);
        let soil = read_vtu(&dir.join(parallel_file("soil", 4))).unwrap();
        assert_eq!(soil.points, cloud.points);
        assert_eq!(soil.kind(false), SeriesKind::MaterialPoints);
        assert_eq!(soil.field("volume").unwrap().0.values, cloud.point_fields[0].values);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
