//! Interfaces between a background grid (soil) and FEM meshes (structures): detection and
//! every check of consistency, before any node is numbered.
//!
//! An interface is a named region of a structure's boundary: the boundary facets of the
//! structure's mesh whose nodes all lie in the region. Coupling through shared nodes needs
//! the grid to conform to it:
//!
//! 1. the grid has **no cells inside the structure**: the cells whose centre lies in an
//!    element of a coupled structure are removed ([`Grid::without_cells`]);
//! 2. every node of the interface **is a node of the remaining grid** (within a millionth of
//!    a cell), and that grid node becomes the structure's node (tied) or its partner (slip);
//! 3. no other node of a coupled structure coincides with a grid node or lies in a remaining
//!    cell (the region must cover all of the boundary that faces the soil);
//! 4. no material point starts inside a coupled structure ([`check_points_outside`]);
//! 5. an FEM mesh that no interface joins to the grid does not reach into it
//!    ([`check_no_overlap`]): nodes that merely coincide never couple silently.
//!
//! Errors name the interface (or both domains) and a coordinate.

use std::collections::HashMap;

use loam_fem::mesh::Mesh;
use loam_mpm::grid::Grid;

/// A structure: an FEM domain's mesh (its own node numbering).
pub struct Structure<'a> {
    /// Domain name.
    pub name: &'a str,
    /// Its mesh in the reference configuration.
    pub mesh: &'a Mesh,
}

/// An interface as the case declares it, resolved to a structure and its region's nodes.
pub struct InterfaceRequest<'a> {
    /// Interface name.
    pub name: &'a str,
    /// Index of the structure in the list handed to [`couple`].
    pub structure: usize,
    /// Nodes of the structure's mesh in the interface region (mesh numbering).
    pub region: Vec<usize>,
    /// Frictionless slip (only the normal component shared) instead of tied.
    pub slip: bool,
}

/// What `loam check` reports of an interface.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceSummary {
    /// Interface name.
    pub name: String,
    /// Number of interface nodes.
    pub nodes: usize,
    /// Length (2D, m) or area (3D, m²) of the interface facets.
    pub measure: f64,
    /// Whether it is a slip interface.
    pub slip: bool,
    /// The law of a non-conforming tie or contact ([`crate::interface_points`]); `None` for
    /// shared nodes.
    pub law: Option<crate::interface_law::InterfaceLaw>,
}

/// A grid node on an interface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceNode {
    /// Index of the structure.
    pub structure: usize,
    /// The structure's node it coincides with (mesh numbering).
    pub node: usize,
    /// Index of the interface (in the requests).
    pub interface: usize,
    /// Unit normal of the interface at the node, pointing out of the structure into the soil.
    pub normal: [f64; 3],
}

/// A grid attached to structures by interfaces.
pub struct CoupledGrid {
    /// The grid without the cells inside the structures.
    pub grid: Grid,
    /// Per node of `grid`: its index in the grid handed to [`couple`].
    pub kept: Vec<usize>,
    /// Per node of `grid`: the structure node it coincides with, if on an interface.
    pub on_interface: Vec<Option<InterfaceNode>>,
    /// Per interface request.
    pub summaries: Vec<InterfaceSummary>,
}

/// An inconsistency, with the interface it concerns (index into the requests) if any.
#[derive(Debug, Clone, PartialEq)]
pub struct InterfaceError {
    /// Index of the interface request, or `None` if the error concerns no declared interface.
    pub interface: Option<usize>,
    /// What is wrong, with the domains and a coordinate.
    pub message: String,
}

fn at(x: &[f64; 3], dim: usize) -> String {
    x[..dim].iter().map(|v| format!("{v}")).collect::<Vec<_>>().join(", ")
}

/// Unit outward normal and measure of a boundary facet (outward orientation).
fn facet_normal_and_measure(coords: &[[f64; 3]], facet: &[usize], dim: usize) -> ([f64; 3], f64) {
    let x: Vec<[f64; 3]> = facet.iter().map(|&a| coords[a]).collect();
    let n = if dim == 2 {
        [x[1][1] - x[0][1], x[0][0] - x[1][0], 0.0]
    } else {
        // area vector: ½ (x₁ − x₀) × (x₂ − x₀) of a triangle, ½ (x₂ − x₀) × (x₃ − x₁) of a
        // quadrilateral
        let (a, b) = if x.len() == 4 {
            ([0, 1, 2].map(|d| x[2][d] - x[0][d]), [0, 1, 2].map(|d| x[3][d] - x[1][d]))
        } else {
            ([0, 1, 2].map(|d| x[1][d] - x[0][d]), [0, 1, 2].map(|d| x[2][d] - x[0][d]))
        };
        [0.5 * (a[1] * b[2] - a[2] * b[1]), 0.5 * (a[2] * b[0] - a[0] * b[2]), 0.5 * (a[0] * b[1] - a[1] * b[0])]
    };
    let len = n.iter().map(|v| v * v).sum::<f64>().sqrt();
    (n.map(|v| v / len), len)
}

/// Nodes of several point sets hashed by position, found within a tolerance.
struct PositionIndex {
    quantum: f64,
    cells: HashMap<[i64; 3], Vec<(usize, usize)>>,
}

impl PositionIndex {
    fn new(quantum: f64) -> Self {
        Self { quantum, cells: HashMap::new() }
    }

    fn key(&self, x: &[f64; 3]) -> [i64; 3] {
        x.map(|v| (v / self.quantum).floor() as i64)
    }

    fn insert(&mut self, x: &[f64; 3], item: (usize, usize)) {
        self.cells.entry(self.key(x)).or_default().push(item);
    }

    /// An item within `quantum` of `x` (in every coordinate), with its position.
    fn find(&self, x: &[f64; 3], position: impl Fn((usize, usize)) -> [f64; 3]) -> Option<(usize, usize)> {
        let k = self.key(x);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let Some(items) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else { continue };
                    for &item in items {
                        let y = position(item);
                        if (0..3).all(|d| (x[d] - y[d]).abs() <= self.quantum) {
                            return Some(item);
                        }
                    }
                }
            }
        }
        None
    }
}

/// A typical cell size of a grid: the mean edge of its first cell's bounding box.
fn cell_size(grid: &Grid) -> f64 {
    let dim = grid.mesh.element.dim();
    grid.cell_extent(0)[..dim].iter().sum::<f64>() / dim as f64
}

/// Attaches `grid` (the soil domain `soil`) to `structures` by the `interfaces` (see the
/// module doc for what is checked).
pub fn couple(
    soil: &str,
    grid: &Grid,
    structures: &[Structure<'_>],
    interfaces: &[InterfaceRequest<'_>],
) -> Result<CoupledGrid, InterfaceError> {
    let dim = grid.mesh.element.dim();
    let fail = |k: usize, message: String| InterfaceError { interface: Some(k), message };
    // interface facets, nodes and normals
    let mut on_interface: Vec<HashMap<usize, (usize, [f64; 3])>> = vec![HashMap::new(); structures.len()];
    let mut summaries = Vec::with_capacity(interfaces.len());
    for (k, req) in interfaces.iter().enumerate() {
        let s = &structures[req.structure];
        let region: std::collections::HashSet<usize> = req.region.iter().copied().collect();
        let facets: Vec<Vec<usize>> =
            s.mesh.boundary_facets().into_iter().filter(|f| f.iter().all(|a| region.contains(a))).collect();
        if facets.is_empty() {
            return Err(fail(k, format!("its region contains no boundary edge or face of the mesh of '{}'", s.name)));
        }
        let mut measure = 0.0;
        let mut nodes = std::collections::BTreeSet::new();
        for f in &facets {
            let (n, m) = facet_normal_and_measure(&s.mesh.coords, f, dim);
            measure += m;
            for &a in f {
                nodes.insert(a);
                let entry = on_interface[req.structure].entry(a).or_insert((k, [0.0; 3]));
                if entry.0 != k {
                    return Err(fail(
                        k,
                        format!(
                            "node ({}) of '{}' is also on interface '{}': give each node one interface",
                            at(&s.mesh.coords[a], dim),
                            s.name,
                            interfaces[entry.0].name
                        ),
                    ));
                }
                for d in 0..3 {
                    entry.1[d] += m * n[d];
                }
            }
        }
        summaries.push(InterfaceSummary {
            name: req.name.to_string(),
            nodes: nodes.len(),
            measure,
            slip: req.slip,
            law: None,
        });
    }
    for map in &mut on_interface {
        for (_, n) in map.values_mut() {
            let len = n.iter().map(|v| v * v).sum::<f64>().sqrt();
            *n = n.map(|v| v / len);
        }
    }
    // no cells inside the structures
    let coupled: Vec<usize> = {
        let mut v: Vec<usize> = interfaces.iter().map(|r| r.structure).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let locators: Vec<(usize, Grid)> =
        coupled.iter().map(|&s| (s, Grid::unstructured(structures[s].mesh.clone()))).collect();
    let remove: Vec<bool> = (0..grid.mesh.num_cells())
        .map(|c| {
            let centre = grid.reference_centre(c);
            locators.iter().any(|(_, l)| l.locate(&centre).is_some())
        })
        .collect();
    let (holed, kept) = grid.without_cells(&remove);
    // the grid nodes on the structures
    let tol = 1e-6 * cell_size(grid);
    let mut index = PositionIndex::new(tol);
    for &s in &coupled {
        for (a, x) in structures[s].mesh.coords.iter().enumerate() {
            index.insert(x, (s, a));
        }
    }
    let first_interface_of = |s: usize| interfaces.iter().position(|r| r.structure == s).expect("coupled");
    let mut grid_node_on: Vec<Option<InterfaceNode>> = vec![None; holed.mesh.coords.len()];
    let mut matched: Vec<HashMap<usize, usize>> = vec![HashMap::new(); structures.len()];
    for (g, x) in holed.reference_coords().iter().enumerate() {
        let Some((s, a)) = index.find(x, |(s, a)| structures[s].mesh.coords[a]) else { continue };
        match on_interface[s].get(&a) {
            Some(&(k, normal)) => {
                grid_node_on[g] = Some(InterfaceNode { structure: s, node: a, interface: k, normal });
                matched[s].insert(a, g);
            }
            None => {
                return Err(fail(
                    first_interface_of(s),
                    format!(
                        "the grid of '{soil}' and the mesh of '{}' share a node at ({}) that is on no interface: extend the interface region over all of the boundary that faces the soil, or move the grid",
                        structures[s].name,
                        at(x, dim)
                    ),
                ));
            }
        }
    }
    for (s, map) in on_interface.iter().enumerate() {
        let mut missing: Vec<(usize, usize)> =
            map.iter().filter(|(a, _)| !matched[s].contains_key(a)).map(|(&a, &(k, _))| (a, k)).collect();
        missing.sort_unstable();
        if let Some(&(a, k)) = missing.first() {
            return Err(fail(
                k,
                format!(
                    "node ({}) of '{}' is not a node of the grid of '{soil}' ({} interface nodes are not): shared-node coupling needs a grid node at every node of the interface",
                    at(&structures[s].mesh.coords[a], dim),
                    structures[s].name,
                    missing.len()
                ),
            ));
        }
    }
    // no other structure node in a remaining cell
    for &s in &coupled {
        for (a, x) in structures[s].mesh.coords.iter().enumerate() {
            if on_interface[s].contains_key(&a) {
                continue;
            }
            if holed.locate(x).is_some() {
                return Err(fail(
                    first_interface_of(s),
                    format!(
                        "the mesh of '{}' reaches into a cell of the grid of '{soil}' at ({}) off the interface: the interface region must cover all of the boundary that faces the soil",
                        structures[s].name,
                        at(x, dim)
                    ),
                ));
            }
        }
    }
    Ok(CoupledGrid { grid: holed, kept, on_interface: grid_node_on, summaries })
}

/// Checks that no node of the mesh of `structure` lies in a cell of `grid`, whose soil
/// domain is `soil`, when no interface joins them.
pub fn check_no_overlap(soil: &str, grid: &Grid, structure: &Structure<'_>) -> Result<(), InterfaceError> {
    let dim = grid.mesh.element.dim();
    match structure.mesh.coords.iter().find(|x| grid.locate(x).is_some()) {
        Some(x) => Err(InterfaceError {
            interface: None,
            message: format!(
                "the mesh of '{}' and the grid of '{soil}' overlap at ({}) but no interface joins them: declare one in interfaces (soil '{soil}', structure '{}'), or move the mesh off the grid",
                structure.name,
                at(x, dim),
                structure.name
            ),
        }),
        None => Ok(()),
    }
}

/// Checks that no material point (at `positions`) of the body `body` starts inside one of
/// the coupled `structures`.
pub fn check_points_outside(
    body: &str,
    positions: &[[f64; 3]],
    structures: &[Structure<'_>],
) -> Result<(), InterfaceError> {
    for s in structures {
        let locator = Grid::unstructured(s.mesh.clone());
        let dim = s.mesh.element.dim();
        let boundary = s.mesh.boundary_facets();
        let tol = 1e-9 * cell_size(&locator);
        // on the boundary (a point touching the structure is outside it)
        let on_boundary = |x: &[f64; 3]| {
            boundary.iter().any(|f| {
                let (a, b) = (s.mesh.coords[f[0]], s.mesh.coords[f[f.len() - 1]]);
                let d: Vec<f64> = (0..dim).map(|i| b[i] - a[i]).collect();
                let l2: f64 = d.iter().map(|v| v * v).sum();
                let t = ((0..dim).map(|i| (x[i] - a[i]) * d[i]).sum::<f64>() / l2).clamp(0.0, 1.0);
                (0..dim).map(|i| (x[i] - a[i] - t * d[i]).powi(2)).sum::<f64>().sqrt() <= tol
            })
        };
        let inside = |x: &&[f64; 3]| locator.locate(x).is_some() && (dim != 2 || !on_boundary(x));
        if let Some(x) = positions.iter().find(inside) {
            return Err(InterfaceError {
                interface: None,
                message: format!(
                    "material point at ({}) of '{body}' starts inside the structure '{}'",
                    at(x, dim),
                    s.name
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use loam_fem::element::ElementType;

    use super::*;

    /// A plate standing in a grid: its cells are removed, its three faces above the base
    /// are the interface; a region that misses the top face, a plate off the grid's nodes
    /// and an uncoupled overlap are each refused with the domains and a coordinate.
    #[test]
    fn plate_in_grid_is_coupled_and_inconsistencies_are_refused() {
        let grid = Grid::new([0.0; 3], [1.0, 1.0, 0.0], [10, 10, 1], ElementType::Quad4);
        let plate = Mesh::rectangle([0.4, 0.0], [0.2, 0.5], [2, 5], ElementType::Quad4);
        let faces: Vec<usize> = (0..plate.coords.len())
            .filter(|&a| {
                let x = plate.coords[a];
                (x[0] - 0.4).abs() < 1e-12 || (x[0] - 0.6).abs() < 1e-12 || (x[1] - 0.5).abs() < 1e-12
            })
            .collect();
        let structures = [Structure { name: "wall", mesh: &plate }];
        let request = |region: Vec<usize>| [InterfaceRequest { name: "i", structure: 0, region, slip: false }];
        let coupled = couple("soil", &grid, &structures, &request(faces.clone())).expect("conforming");
        assert_eq!(coupled.grid.mesh.num_cells(), 100 - 10);
        let s = &coupled.summaries[0];
        assert_eq!(s.nodes, 5 + 5 + 1 + 2);
        assert!((s.measure - (0.5 + 0.5 + 0.2)).abs() < 1e-12, "{}", s.measure);
        let on: Vec<&InterfaceNode> = coupled.on_interface.iter().flatten().collect();
        assert_eq!(on.len(), 13);
        // the top-left corner's normal bisects the left and top normals
        let corner = on.iter().find(|n| plate.coords[n.node] == [0.4, 0.5, 0.0]).unwrap();
        assert!((corner.normal[0] + 0.5f64.sqrt()).abs() < 1e-12 && (corner.normal[1] - 0.5f64.sqrt()).abs() < 1e-12);
        // a region without the top face: the top nodes are shared without an interface
        let sides: Vec<usize> =
            faces.iter().copied().filter(|&a| plate.coords[a][1] < 0.5 - 1e-12 || plate.coords[a][0] != 0.5).collect();
        let err = couple("soil", &grid, &structures, &request(sides)).err().expect("top face missing");
        assert!(err.message.contains("(0.5, 0.5)") && err.message.contains("on no interface"), "{}", err.message);
        // a plate whose nodes are off the grid's
        let off = Mesh::rectangle([0.45, 0.0], [0.2, 0.5], [2, 5], ElementType::Quad4);
        let all: Vec<usize> = (0..off.coords.len()).collect();
        let err = couple("soil", &grid, &[Structure { name: "wall", mesh: &off }], &request(all)).err().unwrap();
        assert!(err.message.contains("not a node of the grid"), "{}", err.message);
        // no interface at all
        let err = check_no_overlap("soil", &grid, &structures[0]).err().unwrap();
        assert!(err.message.contains("'wall'") && err.message.contains("'soil'"), "{}", err.message);
        // material points inside the plate
        assert!(check_points_outside("sand", &[[0.5, 0.2, 0.0]], &structures).is_err());
        assert!(check_points_outside("sand", &[[0.3, 0.2, 0.0]], &structures).is_ok());
    }
}
