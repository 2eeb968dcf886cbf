//! One output time as flat geometry in the plane of the picture: material points as
//! squares, FEM cells as deformed polygons, walls as polylines, each with the value of the
//! selected field.
//!
//! A material point is drawn as the square of its current volume `V`: side `√(V/t)` in plane
//! problems (thickness `t`), `√(V/(2πr))` in axisymmetry (the volume is the full ring at
//! radius `r`) and `∛V` in 3D. A 3D model is projected on a coordinate plane and drawn from
//! the far side to the near one (nearer material hides what lies behind it); of a 3D mesh
//! only the boundary faces are drawn. With a `max_stretch` R a point is drawn no larger
//! than R times the side of its initial volume `V₀ = V / det F`: a degenerate point (det F
//! in the thousands in the toe of a granular flow) otherwise covers its neighbours.

use std::collections::HashMap;

use super::field::FieldSelection;
use super::results::{Cells, Piece, SeriesKind, Shape};

/// The coordinate plane a model is drawn in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Plane {
    /// x to the right, y up, seen from +z (2D models always).
    #[default]
    Xy,
    /// x to the right, z up, seen from −y.
    Xz,
    /// y to the right, z up, seen from +x.
    Yz,
}

impl Plane {
    /// Coordinate indices of the horizontal and vertical axes, the depth axis, and the sign
    /// that makes a larger depth value nearer to the viewer.
    pub fn axes(self) -> (usize, usize, usize, f64) {
        match self {
            Plane::Xy => (0, 1, 2, 1.0),
            Plane::Xz => (0, 2, 1, -1.0),
            Plane::Yz => (1, 2, 0, 1.0),
        }
    }

    /// How the projection is stated in a title.
    pub fn describe(self) -> &'static str {
        match self {
            Plane::Xy => "projection on the x–y plane, seen from +z",
            Plane::Xz => "projection on the x–z plane, seen from −y",
            Plane::Yz => "projection on the y–z plane, seen from +x",
        }
    }
}

/// How a model's geometry maps to the picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Geometry {
    /// `plane_strain`, `plane_stress`, `axisymmetric` or `3d` (as in `summary.json`).
    pub formulation: ModelKind,
    /// Out-of-plane thickness of plane problems (m).
    pub thickness: f64,
    /// Plane of the picture (3D only; 2D models are drawn in x–y).
    pub plane: Plane,
    /// Largest side of a drawn material point as a multiple of the side of its initial
    /// volume `V/det F` (`None`: the current volume's side whatever it is).
    pub max_stretch: Option<f64>,
}

/// The formulation as it matters for drawing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelKind {
    /// Plane strain or plane stress: volumes per thickness.
    Plane,
    /// Axisymmetric: x is r, y is z; volumes are full rings.
    Axisymmetric,
    /// 3D.
    ThreeD,
}

impl Geometry {
    /// Names of the horizontal and vertical axes.
    pub fn axis_names(&self) -> (&'static str, &'static str) {
        match (self.formulation, self.plane) {
            (ModelKind::Axisymmetric, _) => ("r", "z"),
            (ModelKind::ThreeD, Plane::Xz) => ("x", "z"),
            (ModelKind::ThreeD, Plane::Yz) => ("y", "z"),
            _ => ("x", "y"),
        }
    }

    fn axes(&self) -> (usize, usize, usize, f64) {
        match self.formulation {
            ModelKind::ThreeD => self.plane.axes(),
            _ => Plane::Xy.axes(),
        }
    }

    /// Side of the square (or cube) of a material point of volume `volume` at `x`.
    pub fn point_side(&self, volume: f64, x: &[f64; 3]) -> f64 {
        let v = volume.max(0.0);
        match self.formulation {
            ModelKind::Plane => (v / self.thickness).sqrt(),
            ModelKind::Axisymmetric => (v / (2.0 * std::f64::consts::PI * x[0].abs().max(1e-300))).sqrt(),
            ModelKind::ThreeD => v.cbrt(),
        }
    }
}

/// A material point: centre, half its side, value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Square {
    /// Centre (m).
    pub centre: [f64; 2],
    /// Half the side (m).
    pub half: f64,
    /// Field value (`None`: the domain has no such field).
    pub value: Option<f64>,
}

/// A mesh cell or a boundary face of a 3D mesh, deformed.
#[derive(Debug, Clone, PartialEq)]
pub struct Polygon {
    /// Corners in order (m).
    pub vertices: Vec<[f64; 2]>,
    /// Field value.
    pub value: Option<f64>,
}

/// Everything drawn at one output time.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Time of the output (s).
    pub time: f64,
    /// Material points, in drawing order.
    pub squares: Vec<Square>,
    /// Mesh cells (faces), in drawing order.
    pub polygons: Vec<Polygon>,
    /// Penalty points of walls not drawn as lines.
    pub wall_points: Vec<[f64; 2]>,
    /// Walls as polylines.
    pub walls: Vec<Vec<[f64; 2]>>,
    /// Background grid cells (reference position), outlines only.
    pub grid: Vec<Vec<[f64; 2]>>,
}

impl Scene {
    /// Smallest box `[xmin, xmax, ymin, ymax]` holding everything but the grid (`None` if
    /// empty).
    pub fn bounds(&self) -> Option<[f64; 4]> {
        let mut b = [f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY, f64::NEG_INFINITY];
        let mut add = |p: [f64; 2], h: f64| {
            if p[0].is_finite() && p[1].is_finite() {
                b = [b[0].min(p[0] - h), b[1].max(p[0] + h), b[2].min(p[1] - h), b[3].max(p[1] + h)];
            }
        };
        self.squares.iter().for_each(|s| add(s.centre, s.half));
        self.polygons.iter().flat_map(|p| &p.vertices).for_each(|&v| add(v, 0.0));
        self.walls.iter().flatten().for_each(|&v| add(v, 0.0));
        self.wall_points.iter().for_each(|&v| add(v, 0.0));
        (b[0] <= b[1]).then_some(b)
    }

    /// Smallest and largest finite value.
    pub fn value_range(&self) -> Option<(f64, f64)> {
        let values = self.squares.iter().map(|s| s.value).chain(self.polygons.iter().map(|p| p.value));
        values.flatten().filter(|v| v.is_finite()).fold(None, |r, v| match r {
            None => Some((v, v)),
            Some((a, b)) => Some((a.min(v), b.max(v))),
        })
    }
}

/// The faces of a 3D cell (VTK node order), outward.
fn faces(shape: Shape) -> &'static [&'static [usize]] {
    match shape {
        Shape::Tetra => &[&[0, 2, 1], &[0, 1, 3], &[1, 2, 3], &[0, 3, 2]],
        Shape::Hexahedron => {
            &[&[0, 3, 2, 1], &[4, 5, 6, 7], &[0, 1, 5, 4], &[1, 2, 6, 5], &[2, 3, 7, 6], &[3, 0, 4, 7]]
        }
        Shape::Triangle | Shape::Quad => &[],
    }
}

/// Adds one piece (one domain at one time) to `scene`, coloured by `field` where the piece
/// has it.
pub fn add_piece(
    scene: &mut Scene,
    piece: &Piece,
    kind: SeriesKind,
    field: &FieldSelection,
    geometry: &Geometry,
) -> Result<(), String> {
    let (h, v, d, sign) = geometry.axes();
    let project = |x: &[f64; 3]| [x[h], x[v]];
    match kind {
        SeriesKind::MaterialPoints => {
            let volume = piece.field("volume").map(|(f, _)| f.values.as_slice()).unwrap_or(&[]);
            let jacobian = piece.field("deformation_gradient").filter(|(f, _)| f.components == 9).map(|(f, _)| {
                f.values
                    .chunks_exact(9)
                    .map(|m| {
                        m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
                            + m[2] * (m[3] * m[7] - m[4] * m[6])
                    })
                    .collect::<Vec<f64>>()
            });
            let side = |p: usize, x: &[f64; 3]| {
                let v = volume.get(p).copied().unwrap_or(0.0);
                let side = geometry.point_side(v, x);
                match (geometry.max_stretch, &jacobian) {
                    (Some(r), Some(j)) if j[p] > 0.0 => side.min(r * geometry.point_side(v / j[p], x)),
                    _ => side,
                }
            };
            let values = match piece.field(&field.name) {
                Some((f, _)) => Some(field.values(f)?),
                None => None,
            };
            let mut order: Vec<usize> = (0..piece.points.len()).collect();
            if geometry.formulation == ModelKind::ThreeD {
                order.sort_by(|&a, &b| (sign * piece.points[a][d]).total_cmp(&(sign * piece.points[b][d])));
            }
            scene.squares.extend(order.into_iter().map(|p| {
                let x = &piece.points[p];
                Square { centre: project(x), half: 0.5 * side(p, x), value: values.as_ref().map(|v| v[p]) }
            }));
        }
        SeriesKind::Mesh => {
            let Cells::Mesh { shape, connectivity } = &piece.cells else { return Ok(()) };
            let nn = shape.nodes();
            let displacement = piece.field("displacement").filter(|(f, cell)| !cell && f.components == 3);
            let current: Vec<[f64; 3]> = match displacement {
                Some((u, _)) => piece
                    .points
                    .iter()
                    .zip(u.values.chunks_exact(3))
                    .map(|(x, u)| [x[0] + u[0], x[1] + u[1], x[2] + u[2]])
                    .collect(),
                None => piece.points.clone(),
            };
            let cell_values: Option<Vec<f64>> = match piece.field(&field.name) {
                Some((f, true)) => Some(field.values(f)?),
                Some((f, false)) => {
                    let nodal = field.values(f)?;
                    Some(
                        connectivity
                            .chunks_exact(nn)
                            .map(|c| c.iter().map(|&a| nodal[a]).sum::<f64>() / nn as f64)
                            .collect(),
                    )
                }
                None => None,
            };
            let value = |cell: usize| cell_values.as_ref().map(|v| v[cell]);
            match shape {
                Shape::Triangle | Shape::Quad => {
                    scene.polygons.extend(connectivity.chunks_exact(nn).enumerate().map(|(c, nodes)| Polygon {
                        vertices: nodes.iter().map(|&a| project(&current[a])).collect(),
                        value: value(c),
                    }))
                }
                Shape::Tetra | Shape::Hexahedron => {
                    // boundary faces: those of one cell only
                    let mut count: HashMap<Vec<usize>, (usize, usize, usize)> = HashMap::new();
                    for (c, nodes) in connectivity.chunks_exact(nn).enumerate() {
                        for (k, f) in faces(*shape).iter().enumerate() {
                            let mut key: Vec<usize> = f.iter().map(|&i| nodes[i]).collect();
                            key.sort_unstable();
                            count.entry(key).and_modify(|e| e.0 += 1).or_insert((1, c, k));
                        }
                    }
                    let mut boundary: Vec<(f64, Polygon)> = count
                        .into_values()
                        .filter(|e| e.0 == 1)
                        .map(|(_, c, k)| {
                            let nodes: Vec<usize> =
                                faces(*shape)[k].iter().map(|&i| connectivity[c * nn + i]).collect();
                            let depth = nodes.iter().map(|&a| sign * current[a][d]).sum::<f64>() / nodes.len() as f64;
                            (
                                depth,
                                Polygon {
                                    vertices: nodes.iter().map(|&a| project(&current[a])).collect(),
                                    value: value(c),
                                },
                            )
                        })
                        .collect();
                    boundary.sort_by(|a, b| a.0.total_cmp(&b.0));
                    scene.polygons.extend(boundary.into_iter().map(|(_, p)| p));
                }
            }
        }
        SeriesKind::WallPoints => scene.wall_points.extend(piece.points.iter().map(project)),
        SeriesKind::Grid => {
            let Cells::Mesh { shape, connectivity } = &piece.cells else { return Ok(()) };
            if matches!(shape, Shape::Triangle | Shape::Quad) {
                let nn = shape.nodes();
                scene.grid.extend(
                    connectivity.chunks_exact(nn).map(|c| c.iter().map(|&a| project(&piece.points[a])).collect()),
                );
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::results::FieldData;

    fn geometry(formulation: ModelKind) -> Geometry {
        Geometry { formulation, thickness: 2.0, plane: Plane::Xy, max_stretch: None }
    }

    #[test]
    fn point_sides_per_formulation() {
        let x = [0.5, 0.0, 0.0];
        assert!((geometry(ModelKind::Plane).point_side(8.0, &x) - 2.0).abs() < 1e-15);
        let ring = 2.0 * std::f64::consts::PI * 0.5 * 0.01;
        assert!((geometry(ModelKind::Axisymmetric).point_side(ring, &x) - 0.1).abs() < 1e-15);
        assert!((geometry(ModelKind::ThreeD).point_side(8.0, &x) - 2.0).abs() < 1e-15);
    }

    #[test]
    fn stretched_points_are_capped_by_their_initial_volume() {
        // a point of volume 4 (side 2) whose F = diag(4, 1, 1): initial volume 1 (side 1)
        let f = vec![4.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
        let piece = Piece {
            points: vec![[0.0; 3]],
            cells: Cells::Vertices,
            point_fields: vec![
                FieldData { name: "volume".into(), components: 1, values: vec![4.0] },
                FieldData { name: "deformation_gradient".into(), components: 9, values: f },
            ],
            cell_fields: vec![],
        };
        let field = FieldSelection::parse("volume");
        for (cap, half) in [(None, 1.0), (Some(1.5), 0.75), (Some(3.0), 1.0)] {
            let g = Geometry { formulation: ModelKind::Plane, thickness: 1.0, plane: Plane::Xy, max_stretch: cap };
            let mut scene = Scene::default();
            add_piece(&mut scene, &piece, SeriesKind::MaterialPoints, &field, &g).unwrap();
            assert_eq!(scene.squares[0].half, half, "{cap:?}");
        }
    }

    #[test]
    fn hex_mesh_shows_its_boundary_faces_only() {
        // two unit hexahedra side by side: 10 boundary faces, the shared one hidden
        let mut points = Vec::new();
        for z in [0.0, 1.0] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.0), (0.0, 1.0)] {
                points.push([x, y, z]);
            }
        }
        let connectivity = vec![0, 1, 4, 5, 6, 7, 10, 11, 1, 2, 3, 4, 7, 8, 9, 10];
        let piece = Piece {
            points,
            cells: Cells::Mesh { shape: Shape::Hexahedron, connectivity },
            point_fields: vec![],
            cell_fields: vec![FieldData { name: "p".into(), components: 1, values: vec![1.0, 2.0] }],
        };
        let mut scene = Scene::default();
        let g = Geometry { formulation: ModelKind::ThreeD, thickness: 1.0, plane: Plane::Xy, max_stretch: None };
        add_piece(&mut scene, &piece, SeriesKind::Mesh, &FieldSelection::parse("p"), &g).unwrap();
        assert_eq!(scene.polygons.len(), 10);
        // seen from +z: the top faces (z = 1) come last
        assert!(scene.polygons[8..].iter().all(|p| p.vertices.len() == 4));
        assert_eq!(scene.bounds(), Some([0.0, 2.0, 0.0, 1.0]));
        assert_eq!(scene.value_range(), Some((1.0, 2.0)));
    }
}
