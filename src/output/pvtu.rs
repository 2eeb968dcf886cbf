//! Parallel VTK output of a distributed run (issue 26, `docs/distributed.md`, "Output"): each
//! rank writes one piece of every output (`soil_000010_r0001.vtu`) and rank 0 a `.pvtu` per
//! output and step naming the pieces, which the `.pvd` series lists; ParaView, VTK and
//! vtkio read the `.pvtu` as one data set.
//!
//! ```xml
//! <VTKFile type="PUnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">
//!   <PUnstructuredGrid GhostLevel="0">
//!     <PPointData><PDataArray type="Float64" Name="velocity" NumberOfComponents="3"/></PPointData>
//!     <PCellData/>
//!     <PPoints><PDataArray type="Float64" NumberOfComponents="3"/></PPoints>
//!     <Piece Source="soil_000010_r0000.vtu"/>
//!     <Piece Source="soil_000010_r0001.vtu"/>
//!   </PUnstructuredGrid>
//! </VTKFile>
//! ```
//!
//! What a rank writes is [`DomainOutput::piece`]: a point cloud split into contiguous ranges of its points,
//! a mesh into contiguous ranges of its cells with the points they use (a point shared by
//! cells of two pieces is written in both, as VTK's pieces do; `GhostLevel` 0). The model is
//! replicated on every rank (stage 2), so any split writes each point once; ranges of the
//! storage order keep a piece compact in space (material points are stored sorted by their
//! grid cell, FEM elements in mesh order) and the pieces equal in size.

use std::path::Path;

use loam_fem::domain::{DomainOutput, Field};

use super::pvd::escape;
use super::vtk::OutputError;

/// The file name of rank `rank`'s piece of output `name` at `step`.
pub fn piece_file(name: &str, step: usize, rank: usize) -> String {
    format!("{name}_{step:06}_r{rank:04}.vtu")
}

/// The `.pvtu` file name of output `name` at `step`.
pub fn parallel_file(name: &str, step: usize) -> String {
    format!("{name}_{step:06}.pvtu")
}

/// The `<PDataArray …/>` declarations of `fields`, as the pieces' `.vtu` declare them
/// (Float64; `NumberOfComponents` unless scalar).
fn declarations(fields: &[Field]) -> String {
    fields
        .iter()
        .map(|f| {
            let components =
                if f.components == 1 { String::new() } else { format!(" NumberOfComponents=\"{}\"", f.components) };
            format!("      <PDataArray type=\"Float64\" Name=\"{}\"{components}/>\n", escape(&f.name))
        })
        .collect()
}

/// Writes the `.pvtu` at `path` for the fields of `output` (the whole output or any piece of
/// it: only the names and components are read) and the piece files `sources` (names relative
/// to the `.pvtu`'s directory, in rank order).
pub fn write_pvtu(path: &Path, output: &DomainOutput, sources: &[String]) -> Result<(), OutputError> {
    let mut xml = String::from(
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PUnstructuredGrid\" version=\"1.0\" \
         byte_order=\"LittleEndian\" header_type=\"UInt64\">\n  <PUnstructuredGrid GhostLevel=\"0\">\n",
    );
    xml.push_str("    <PPointData>\n");
    xml.push_str(&declarations(&output.point_fields));
    xml.push_str("    </PPointData>\n    <PCellData>\n");
    xml.push_str(&declarations(&output.cell_fields));
    xml.push_str("    </PCellData>\n    <PPoints>\n");
    xml.push_str("      <PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n    </PPoints>\n");
    for source in sources {
        xml.push_str(&format!("    <Piece Source=\"{}\"/>\n", escape(source)));
    }
    xml.push_str("  </PUnstructuredGrid>\n</VTKFile>\n");
    std::fs::write(path, xml).map_err(|e| OutputError::Write { file: path.to_path_buf(), reason: e.to_string() })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::vtk_output::write_output;
    use loam_fem::element::ElementType;
    use vtkio::model::{Attribute, DataSet, IOBuffer, VertexNumbers, Vtk};

    fn field(name: &str, components: usize, values: Vec<f64>) -> Field {
        Field { name: name.to_string(), components, values }
    }

    /// Three quads in a row (8 points), a vector point field and a scalar cell field.
    fn strip() -> DomainOutput {
        let points: Vec<[f64; 3]> = (0..8).map(|a| [(a / 2) as f64, (a % 2) as f64, 0.0]).collect();
        DomainOutput {
            point_fields: vec![field("u", 3, points.iter().flat_map(|x| [x[0], 10.0 * x[1], 0.5]).collect())],
            points,
            cells: Some((ElementType::Quad4, vec![0, 2, 3, 1, 2, 4, 5, 3, 4, 6, 7, 5])),
            cell_fields: vec![field("pressure", 1, vec![1.0, 2.0, 3.0])],
        }
    }

    fn write_piece(dir: &Path, file: &str, p: &DomainOutput) {
        write_output(&dir.join(file), p).unwrap();
    }

    #[test]
    fn pieces_of_a_mesh_cover_its_cells_once_with_their_points() {
        let m = strip();
        let pieces: Vec<DomainOutput> = (0..2).map(|r| m.piece(r, 2)).collect();
        // cell 0 on rank 0, cells 1 and 2 on rank 1; the points of the shared edge in both
        assert_eq!(pieces[0].cells.as_ref().unwrap().1, vec![0, 2, 3, 1]);
        assert_eq!(pieces[0].points.len(), 4);
        assert_eq!(pieces[1].points, m.points[2..8].to_vec());
        assert_eq!(pieces[1].cells.as_ref().unwrap().1, vec![0, 2, 3, 1, 2, 4, 5, 3]);
        assert_eq!(pieces[1].cell_fields[0].values, vec![2.0, 3.0]);
        assert_eq!(pieces[1].point_fields[0].values[..3], m.point_fields[0].values[6..9]);
        // more ranks than cells: empty pieces
        let many: Vec<usize> = (0..5).map(|r| m.piece(r, 5).cell_fields[0].values.len()).collect();
        assert_eq!(many.iter().sum::<usize>(), 3);
    }

    #[test]
    fn pieces_of_a_cloud_split_its_points() {
        let cloud = DomainOutput {
            points: (0..7).map(|i| [i as f64, 0.0, 0.0]).collect(),
            cells: None,
            point_fields: vec![field("mass", 1, (0..7).map(f64::from).collect())],
            cell_fields: vec![],
        };
        let sizes: Vec<usize> = (0..3).map(|r| cloud.piece(r, 3).points.len()).collect();
        assert_eq!(sizes, vec![2, 2, 3]);
        let last = cloud.piece(2, 3);
        assert_eq!(last.point_fields[0].values, vec![4.0, 5.0, 6.0]);
    }

    /// The `.pvtu` and its pieces read back with vtkio as one grid with every cell and field.
    #[test]
    fn a_pvtu_and_its_pieces_read_back_with_vtkio() {
        let dir = std::env::temp_dir().join(format!("loam-pvtu-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let m = strip();
        let sources: Vec<String> = (0..2).map(|r| piece_file("beam", 3, r)).collect();
        for (r, s) in sources.iter().enumerate() {
            write_piece(&dir, s, &m.piece(r, 2));
        }
        let path = dir.join(parallel_file("beam", 3));
        write_pvtu(&path, &m, &sources).unwrap();
        let mut vtk = Vtk::import(&path).unwrap();
        vtk.load_all_pieces().unwrap();
        let DataSet::UnstructuredGrid { pieces, .. } = vtk.data else { panic!("not an unstructured grid") };
        assert_eq!(pieces.len(), 2);
        let mut cells = 0;
        let mut pressure = Vec::new();
        for p in pieces {
            let p = p.into_loaded_piece_data(None).unwrap();
            let VertexNumbers::XML { offsets, .. } = &p.cells.cell_verts else { panic!("XML cells") };
            cells += offsets.len();
            for a in &p.data.cell {
                if let Attribute::DataArray(d) = a {
                    if let IOBuffer::F64(v) = &d.data {
                        pressure.extend_from_slice(v);
                    }
                }
            }
        }
        assert_eq!(cells, 3);
        assert_eq!(pressure, vec![1.0, 2.0, 3.0]);
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<PDataArray type=\"Float64\" Name=\"u\" NumberOfComponents=\"3\"/>"));
        assert!(text.contains("<PDataArray type=\"Float64\" Name=\"pressure\"/>"));
        std::fs::remove_dir_all(&dir).ok();
    }
}
