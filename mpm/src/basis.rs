//! Shape functions of an MPM grid: the cell's linear (Lagrange) functions, or a smooth basis
//! whose functions reach over neighbouring cells so that their gradients do not jump where a
//! material point crosses a cell edge (case key `grid.basis`).
//!
//! - **Linear** (`"linear"`): `N_I` of the cell that holds the point (tri3, quad4, tet4,
//!   hex8), Kratos' and Sulsky's MPM. The gradient jumps when a point changes cells
//!   ("cell-crossing error"), and a cell's few points are a poor quadrature rule.
//! - **uGIMP** (`"gimp"`): the generalized interpolation material point method of
//!   Bardenhagen & Kober (2004), "The generalized interpolation material point method",
//!   CMES 5(6):477–496, undeformed: `S_Ip = (1/V_p) ∫_Ωp N_I dx` over the point's domain
//!   `Ωp`, the square of the point's initial volume around it (half size `l_p`). The
//!   contiguous-particle form, whose domain follows `F` (`l_p,d = l_p0 |F e_d|`), was measured
//!   and not kept: on the compaction column of tests/mpm_bases.rs, where the domains shrink
//!   to 0.4 of their size at the base and the functions there approach the linear hat, its
//!   stress error was 2.5–2.9 % against uGIMP's 1.4–1.9 %. Per direction, with
//!   `r = (x_p − x_I)/h` and `l = l_p/h ≤ ½` (larger points are clamped to ½):
//!   `S = 1 − (r² + l²)/(2l)` for `|r| < l`, `1 − |r|` for `l ≤ |r| < 1 − l`,
//!   `(1 + l − |r|)²/(4l)` for `1 − l ≤ |r| < 1 + l`, 0 beyond (C¹ in `x_p`).
//! - **Quadratic B-splines** (`"bspline2"`): per direction `N = ¾ − r²` for `|r| < ½`,
//!   `(3/2 − |r|)²/2` for `½ ≤ |r| < 3/2`, 0 beyond (C¹; Steffen, Kirby & Berzins 2008,
//!   "Analysis and reduction of quadrature errors in the material point method (MPM)",
//!   IJNME 76:922–948).
//!
//! Both smooth bases are tensor products over a structured lattice of quad4 (2D) or hex8 (3D)
//! cells. A point whose nearest node is `i_c` has non-zero functions on the nodes
//! `i_c − 1, i_c, i_c + 1` in each direction (for GIMP because `l ≤ ½`): the point's
//! **support**, a window of 3 × 3 (3 × 3 × 3) nodes whose block the point's stiffness fills. Windows start at `w = clamp(i_c − 1, 0,
//! n − 2)`, so every support holds grid nodes only.
//!
//! **Boundaries.** At the lattice's edge the function of the missing node `−1` (or `n + 1`)
//! is folded into its neighbours by linear extrapolation of its value,
//! `u_{−1} = 2 u_0 − u_1`: `N_0 += 2 N_{−1}`, `N_1 −= N_{−1}`. The folded basis keeps the
//! partition of unity and reproduces linear fields, stays non-negative and C¹, and is
//! interpolatory on the edge (`N_0 = 1`, the others 0, at `x_0`): for B-splines it is the
//! boundary modification of Steffen, Kirby & Berzins (2008), linear on the first half cell
//! (`N_0 = 1 − r`, `N_1 = r`). A displacement fixed at the edge's nodes therefore holds on the
//! whole edge, as with the linear basis; Dirichlet and slip conditions act on grid nodes
//! unchanged.
//!
//! **A lattice that moves with a structure** (a grid coupled to an FEM structure by shared
//! interface nodes on its edge, moved each step by the mesh motion): the functions stay those
//! of the lattice coordinates `s`, and the lattice's position is mapped by the same functions,
//! `x(s) = Σ_I N_I(s) x_I` over the nodes' current positions (isoparametric, as in
//! isogeometric analysis: Hughes, Cottrell & Bazilevs 2005, "Isogeometric analysis", CMAME
//! 194:4135–4195; GIMP maps by its `l = 0` functions, the cells' bilinear map). A point's `s`
//! is the inverse of that map (Newton from its cell's bilinear map,
//! [`crate::grid::Grid::point_functions`]) and `∂N/∂x = (∂x/∂s)⁻ᵀ ∂N/∂s`, so the functions
//! reproduce the moved configuration's linear fields exactly and stay C¹. On the fixed
//! lattice the map is `x_0 + h s` and nothing changes. A structure inside the grid removes
//! the cells and nodes inside it; the functions of a support's removed nodes are folded into
//! the nodes it keeps ([`SmoothLattice::holed`], `fold_missing`), as the lattice's edge folds
//! its missing outer node.

use loam_fem::element::MAX_NODES;
use loam_fem::formulation::Formulation;
use loam_fem::kernel::PointGeometry;
use loam_fem::mixed_kernel::CellProjection;

/// The shape functions of a grid (see the module doc; the names are the case file's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Basis {
    /// The cell's linear functions.
    #[default]
    Linear,
    /// Undeformed GIMP (particle domain of the initial size).
    Gimp,
    /// Quadratic B-splines.
    Bspline2,
}

impl Basis {
    /// The case file's name of the basis.
    pub fn name(self) -> &'static str {
        match self {
            Self::Linear => "linear",
            Self::Gimp => "gimp",
            Self::Bspline2 => "bspline2",
        }
    }

    /// Whether the functions reach over neighbouring cells (GIMP, B-splines).
    pub fn is_smooth(self) -> bool {
        self != Self::Linear
    }

    /// `(N, dN/dr)` of the function of a node at distance `r = (x − x_I)/h` (in cells);
    /// `half_length` is GIMP's `l = l_p/h` (clamped to ½; 0 gives the linear hat).
    pub fn function_1d(self, r: f64, half_length: f64) -> (f64, f64) {
        let (a, sign) = (r.abs(), if r < 0.0 { -1.0 } else { 1.0 });
        match self {
            Self::Bspline2 => {
                if a < 0.5 {
                    (0.75 - r * r, -2.0 * r)
                } else if a < 1.5 {
                    let t = 1.5 - a;
                    (0.5 * t * t, -sign * t)
                } else {
                    (0.0, 0.0)
                }
            }
            Self::Gimp | Self::Linear => {
                let l = if self == Self::Gimp { half_length.clamp(0.0, 0.5) } else { 0.0 };
                if l == 0.0 {
                    // the hat, its slope taken from the right at the kinks (so that the
                    // slopes of a point on a node sum to zero)
                    return if (-1.0..1.0).contains(&r) { (1.0 - a, -sign) } else { (0.0, 0.0) };
                }
                if a < l {
                    (1.0 - (r * r + l * l) / (2.0 * l), -r / l)
                } else if a < 1.0 - l {
                    (1.0 - a, -sign)
                } else if a < 1.0 + l {
                    let t = 1.0 + l - a;
                    (t * t / (4.0 * l), -sign * t / (2.0 * l))
                } else {
                    (0.0, 0.0)
                }
            }
        }
    }

    /// `d²N/dr²` of the function of a node at distance `r` (as [`Basis::function_1d`]):
    /// B-splines `−2` for `|r| < ½`, `1` for `½ ≤ |r| < 3/2`; GIMP `−1/l`, `0`, `1/(2l)` on
    /// its three pieces; 0 for the hat (its kinks carry no second derivative).
    pub fn second_derivative_1d(self, r: f64, half_length: f64) -> f64 {
        let a = r.abs();
        match self {
            Self::Bspline2 => {
                if a < 0.5 {
                    -2.0
                } else if a < 1.5 {
                    1.0
                } else {
                    0.0
                }
            }
            Self::Gimp | Self::Linear => {
                let l = if self == Self::Gimp { half_length.clamp(0.0, 0.5) } else { 0.0 };
                if l == 0.0 || (l..1.0 - l).contains(&a) || a >= 1.0 + l {
                    0.0
                } else if a < l {
                    -1.0 / l
                } else {
                    0.5 / l
                }
            }
        }
    }

    /// The three functions of a point at lattice coordinate `s = (x − x_0)/h ∈ [0, n]` on a
    /// lattice of `n ≥ 2` cells in one direction: the window's first node `w` and
    /// `(N_k, dN_k/ds)` of the nodes `w + k`, with the edges folded (module doc).
    pub fn window_1d(self, s: f64, cells: usize, half_length: f64) -> (usize, [(f64, f64); 3]) {
        let (w, values) = self.window_1d_derivatives(s, cells, half_length);
        (w, values.map(|v| (v[0], v[1])))
    }

    /// [`Basis::window_1d`] with the second derivatives: `[N_k, dN_k/ds, d²N_k/ds²]`.
    pub fn window_1d_derivatives(self, s: f64, cells: usize, half_length: f64) -> (usize, [[f64; 3]; 3]) {
        let nearest = (s.round().max(0.0) as usize).min(cells);
        let w = nearest.saturating_sub(1).min(cells - 2);
        let at = |r: f64| {
            let (n, dn) = self.function_1d(r, half_length);
            [n, dn, self.second_derivative_1d(r, half_length)]
        };
        let mut values: [[f64; 3]; 3] = std::array::from_fn(|k| at(s - (w + k) as f64));
        let mut fold = |ghost: f64, edge: usize, inner: usize| {
            let f = at(s - ghost);
            for i in 0..3 {
                values[edge][i] += 2.0 * f[i];
                values[inner][i] -= f[i];
            }
        };
        if nearest == 0 {
            fold(-1.0, 0, 1);
        }
        if nearest == cells {
            fold(cells as f64 + 1.0, 2, 1);
        }
        (w, values)
    }
}

/// Per node of a support: `[N, ∂N/∂s_x, ∂N/∂s_y, ∂N/∂s_z]` (derivatives per lattice cell;
/// `∂/∂s_z` zero in 2D), in the support's local order (`(3 k_z + k_y) 3 + k_x`); the first
/// `3^dim` entries are used.
pub type SupportValues = [[f64; 4]; MAX_SUPPORT_NODES];

/// The support's functions as tensor products of the 1D windows' `(N_k, dN_k/ds)` per
/// direction: `[N, ∂N/∂s_x, ∂N/∂s_y, ∂N/∂s_z]` for the first `m` local nodes.
fn tensor_values([fx, fy, fz]: [[(f64, f64); 3]; 3], m: usize) -> SupportValues {
    let mut values = [[0.0; 4]; MAX_SUPPORT_NODES];
    for (k, v) in values.iter_mut().enumerate().take(m) {
        let (x, y, z) = (fx[k % 3], fy[(k / 3) % 3], fz[k / 9]);
        *v = [x.0 * y.0 * z.0, x.1 * y.0 * z.0, x.0 * y.1 * z.0, x.0 * y.0 * z.1];
    }
    values
}

/// Folds the functions of a support's removed nodes (`mask`, bit `3 ky + kx`; 2D) into the
/// nodes it keeps, by the extrapolation of a linear field from kept nodes (so the folded
/// functions stay a partition of unity that reproduces linear fields, as at the lattice's
/// edge): along the row or the column of the removed node, whichever leads from it towards
/// the point at local lattice coordinates `t` (`t − k` larger along it; the other if that one
/// lacks nodes), `u_k = Σ_j u_j Π (k − i)/(j − i)` over its two kept nodes; else by the
/// rectangle rule `u_(k,l) = u_(k',l) + u_(k,l') − u_(k',l')`; else (a sliver of soil narrower
/// than the support) onto the nearest kept node. The choice of direction changes only where
/// `|t_x − k_x| = |t_y − k_y|`, beside a hole's corner, where the removed function is at most
/// `N(1)² = 1/64` (B-splines): the folded basis jumps by no more there.
fn fold_missing(values: &mut SupportValues, mask: u32, t: [f64; 2]) {
    const NODES_2D: usize = 9;
    let kept = |k: usize| mask & (1 << k) == 0;
    for m in (0..NODES_2D).filter(|&m| !kept(m)) {
        let f = values[m];
        values[m] = [0.0; 4];
        if f == [0.0; 4] {
            continue;
        }
        let (mx, my) = (m % 3, m / 3);
        // along x (the row) or y (the column): the other two local indices and their nodes
        let line = |along_x: bool| -> Option<[(usize, f64); 2]> {
            let p = if along_x { mx } else { my };
            let others: Vec<usize> = (0..3).filter(|&i| i != p).collect();
            let node = |i: usize| if along_x { 3 * my + i } else { 3 * i + mx };
            let (a, b) = (others[0], others[1]);
            (kept(node(a)) && kept(node(b))).then(|| {
                let (pa, pb, pp) = (a as f64, b as f64, p as f64);
                [(node(a), (pp - pb) / (pa - pb)), (node(b), (pp - pa) / (pb - pa))]
            })
        };
        let x_first = (t[0] - mx as f64).abs() >= (t[1] - my as f64).abs();
        let stencil: Vec<(usize, f64)> = if let Some(l) = line(x_first).or_else(|| line(!x_first)) {
            l.to_vec()
        } else if let Some((kx, ky)) = (0..3)
            .flat_map(|kx| (0..3).map(move |ky| (kx, ky)))
            .find(|&(kx, ky)| kx != mx && ky != my && kept(3 * my + kx) && kept(3 * ky + mx) && kept(3 * ky + kx))
        {
            vec![(3 * my + kx, 1.0), (3 * ky + mx, 1.0), (3 * ky + kx, -1.0)]
        } else {
            let nearest = (0..NODES_2D)
                .filter(|&k| kept(k))
                .min_by_key(|&k| (k % 3).abs_diff(mx) + (k / 3).abs_diff(my))
                .expect("a support holding a point keeps a node");
            vec![(nearest, 1.0)]
        };
        for (k, c) in stencil {
            for i in 0..4 {
                values[k][i] += c * f[i];
            }
        }
    }
}

/// Most nodes of a support of a smooth basis (3 × 3 × 3 in 3D; 3 × 3 in 2D).
pub const MAX_SUPPORT_NODES: usize = 27;

/// A structured, unrotated lattice of quad4 (2D) or hex8 (3D) cells carrying a smooth basis:
/// its supports (3 × 3 or 3 × 3 × 3-node windows) and the functions of a point (see the
/// module doc). In 3D the lattice is fixed and whole: the structures that move a grid or cut
/// holes in it are 2D.
#[derive(Debug, Clone)]
pub struct SmoothLattice {
    basis: Basis,
    dim: usize,
    origin: [f64; 3],
    spacing: [f64; 3],
    /// Cells per direction (1 along z in 2D).
    cells: [usize; 3],
    /// The grid nodes of each support, support `(wz n_y + wy) n_x + wx` (`n_d`: windows per
    /// direction, `cells_d − 1`) at `m s..m s + m` (`m = 3^dim`), node
    /// `(wx + kx, wy + ky, wz + kz)` at local index `(3 kz + ky) 3 + kx` (a node removed with a
    /// hole: a node of the same support, whose function the fold leaves 0 there).
    nodes: Vec<usize>,
    /// Per support, the local nodes removed with a hole (bit `3 ky + kx`, 2D); empty while the
    /// lattice is whole.
    missing: Vec<u32>,
    /// Per direction and window, the 1D functions `(N_k, dN_k/ds)` of the window's three nodes
    /// at the three Gauss points of [`SmoothLattice::projection_points`]: the factors of the
    /// projection rule, which a u–p support evaluates at every assembly
    /// ([`SmoothLattice::projection_rule`]).
    projection_1d: [Vec<GaussWindow>; 3],
    /// Per direction and window, the 1D integrals of the window's functions over its region on
    /// the same rule: the factors of a whole support's [`CellProjection`]
    /// ([`SmoothLattice::projection_moments`]).
    projection_moments_1d: [Vec<WindowMoments>; 3],
}

/// A window's three 1D functions `(N_k, dN_k/ds)` at each of its three Gauss points.
type GaussWindow = [[(f64, f64); 3]; 3];

/// The 1D integrals over a window's region (in lattice cells) of its functions' products
/// `∫ N_k N_l ds`, of its functions `∫ N_k ds`, and its length `∫ ds`.
#[derive(Debug, Clone, Copy, Default)]
struct WindowMoments {
    mass: [[f64; 3]; 3],
    moments: [f64; 3],
    length: f64,
}

/// The abscissae of the 3-point Gauss rule on `[−1, 1]` and their weights.
const GAUSS_3: ([f64; 3], [f64; 3]) =
    ([-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4], [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]);

impl SmoothLattice {
    /// The supports of `basis` (smooth) on the lattice `origin + [0, cells · spacing]` in
    /// `dim` dimensions (2D: the first two entries), whose node `(i, j, k)` is grid node
    /// `(k (n_y + 1) + j)(n_x + 1) + i`. Needs two or more cells per direction.
    pub fn new(basis: Basis, dim: usize, origin: [f64; 3], spacing: [f64; 3], cells: [usize; 3]) -> Self {
        let cells = if dim == 2 { [cells[0], cells[1], 1] } else { cells };
        debug_assert!(basis.is_smooth() && (0..dim).all(|d| cells[d] >= 2));
        let mut lattice = Self {
            basis,
            dim,
            origin,
            spacing,
            cells,
            nodes: Vec::new(),
            missing: Vec::new(),
            projection_1d: Default::default(),
            projection_moments_1d: Default::default(),
        };
        let [wx, wy, wz] = lattice.windows();
        let m = lattice.support_len();
        let layers = if dim == 3 { 3 } else { 1 };
        let mut nodes = Vec::with_capacity(wx * wy * wz * m);
        for k in 0..wz {
            for j in 0..wy {
                for i in 0..wx {
                    for kz in 0..layers {
                        for ky in 0..3 {
                            for kx in 0..3 {
                                nodes.push(((k + kz) * (cells[1] + 1) + j + ky) * (cells[0] + 1) + i + kx);
                            }
                        }
                    }
                }
            }
        }
        lattice.nodes = nodes;
        lattice.projection_1d = std::array::from_fn(|d| {
            (0..if d < dim { cells[d] - 1 } else { 0 })
                .map(|w| {
                    lattice.gauss_1d(d, w).map(|(point, _)| {
                        let (window, values) = basis.window_1d(point, cells[d], 0.0);
                        debug_assert_eq!(window, w, "a Gauss point of a window's region lies in the window");
                        values
                    })
                })
                .collect()
        });
        lattice.projection_moments_1d = std::array::from_fn(|d| {
            (0..lattice.projection_1d[d].len())
                .map(|w| {
                    let mut m = WindowMoments::default();
                    for ((_, weight), values) in lattice.gauss_1d(d, w).iter().zip(&lattice.projection_1d[d][w]) {
                        m.length += weight;
                        for k in 0..3 {
                            m.moments[k] += weight * values[k].0;
                            for l in 0..3 {
                                m.mass[k][l] += weight * values[k].0 * values[l].0;
                            }
                        }
                    }
                    m
                })
                .collect()
        });
        lattice
    }

    /// Supports per direction (one along z in 2D).
    fn windows(&self) -> [usize; 3] {
        std::array::from_fn(|d| if d < self.dim { self.cells[d] - 1 } else { 1 })
    }

    /// Nodes per support: 9 in 2D, 27 in 3D.
    pub fn support_len(&self) -> usize {
        if self.dim == 3 {
            27
        } else {
            9
        }
    }

    /// The window `[wx, wy, wz]` of support `s`.
    fn window(&self, s: usize) -> [usize; 3] {
        let [nx, ny, _] = self.windows();
        [s % nx, (s / nx) % ny, s / (nx * ny)]
    }

    /// The support of window `w`.
    fn support_of(&self, w: [usize; 3]) -> usize {
        let [nx, ny, _] = self.windows();
        (w[2] * ny + w[1]) * nx + w[0]
    }

    /// The lattice without the nodes of a hole (2D): `new_node[a]` is the new index of grid
    /// node `a` (`usize::MAX` where it was removed with the cells inside a structure). A
    /// removed node's function is folded into the nodes its support keeps
    /// ([`SmoothLattice::functions_at`]).
    pub fn holed(&self, new_node: &[usize]) -> Self {
        debug_assert_eq!(self.dim, 2, "holes are cut by 2D structures");
        let m = self.support_len();
        let mut nodes = Vec::with_capacity(self.nodes.len());
        let mut missing = Vec::with_capacity(self.num_supports());
        for (support, window) in self.nodes.chunks(m).enumerate() {
            let mut mask = self.missing.get(support).copied().unwrap_or(0);
            let kept = (0..m)
                .filter(|&k| mask & (1 << k) == 0)
                .map(|k| new_node[window[k]])
                .find(|&a| a != usize::MAX)
                .unwrap_or(0);
            for (k, &a) in window.iter().enumerate() {
                if mask & (1 << k) != 0 || new_node[a] == usize::MAX {
                    mask |= 1 << k;
                    nodes.push(kept);
                } else {
                    nodes.push(new_node[a]);
                }
            }
            missing.push(mask);
        }
        let missing = if missing.iter().any(|&m| m != 0) { missing } else { Vec::new() };
        Self { nodes, missing, ..self.clone() }
    }

    /// The lattice's cell size per direction (reference configuration).
    pub fn spacing(&self) -> [f64; 3] {
        self.spacing
    }

    /// `half_size` in lattice cells per direction (GIMP's `l_p,d / h_d`).
    pub fn in_cells(&self, half_size: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|d| if d < self.dim { half_size[d] / self.spacing[d] } else { 0.0 })
    }

    /// The basis.
    pub fn basis(&self) -> Basis {
        self.basis
    }

    /// Number of supports.
    pub fn num_supports(&self) -> usize {
        self.windows().iter().product()
    }

    /// The grid nodes of support `s`.
    pub fn support(&self, s: usize) -> &[usize] {
        let m = self.support_len();
        &self.nodes[s * m..(s + 1) * m]
    }

    /// Lattice coordinates `(x − x_0)/h` of `x` on the fixed lattice (0 along z in 2D), or
    /// `None` outside it.
    pub fn lattice_coordinates(&self, x: &[f64; 3]) -> Option<[f64; 3]> {
        let mut s = [0.0; 3];
        for d in 0..self.dim {
            s[d] = (x[d] - self.origin[d]) / self.spacing[d];
            let n = self.cells[d] as f64;
            if !(s[d] >= -1e-9 && s[d] <= n * (1.0 + 1e-12) + 1e-9) {
                return None;
            }
            s[d] = s[d].clamp(0.0, n);
        }
        Some(s)
    }

    /// Lattice coordinates of a position `x` of the reference (fixed) lattice, clamped to it.
    pub fn clamped_coordinates(&self, x: [f64; 3]) -> [f64; 3] {
        self.clamp(std::array::from_fn(|d| if d < self.dim { (x[d] - self.origin[d]) / self.spacing[d] } else { 0.0 }))
    }

    /// Lattice coordinates clamped to the lattice.
    pub fn clamp(&self, s: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|d| if d < self.dim { s[d].clamp(0.0, self.cells[d] as f64) } else { 0.0 })
    }

    /// The support holding lattice coordinates `s` and, per node of it, `(N, ∂N/∂s)` with the
    /// derivatives per lattice cell; `half_cells` is GIMP's `l_p,d / h_d`.
    pub fn functions_at(&self, s: [f64; 3], half_cells: [f64; 3]) -> (usize, SupportValues) {
        self.functions_without(s, half_cells, |_| false).expect("a support holding a point keeps a node")
    }

    /// The 1D windows of `s` per direction (the third a single node of function 1 in 2D).
    fn windows_1d(&self, s: [f64; 3], half_cells: [f64; 3]) -> [(usize, [(f64, f64); 3]); 3] {
        std::array::from_fn(|d| {
            if d < self.dim {
                self.basis.window_1d(s[d], self.cells[d], half_cells[d])
            } else {
                (0, [(1.0, 0.0), (0.0, 0.0), (0.0, 0.0)])
            }
        })
    }

    /// [`SmoothLattice::functions_at`] with the functions of the support's grid nodes for
    /// which `absent` holds folded into the others as those of a hole's removed nodes are
    /// (`fold_missing`, 2D: a linear field extrapolated from the nodes kept): for a point
    /// beside which the soil ends before those nodes. `None` if the support keeps no node (or,
    /// in 3D, lacks one).
    pub fn functions_without(
        &self,
        s: [f64; 3],
        half_cells: [f64; 3],
        absent: impl Fn(usize) -> bool,
    ) -> Option<(usize, SupportValues)> {
        let [(wx, fx), (wy, fy), (wz, fz)] = self.windows_1d(s, half_cells);
        let m = self.support_len();
        let mut values = tensor_values([fx, fy, fz], m);
        let support = self.support_of([wx, wy, wz]);
        let mut mask = self.missing.get(support).copied().unwrap_or(0);
        for (k, &a) in self.support(support).iter().enumerate() {
            if absent(a) {
                mask |= 1 << k;
            }
        }
        if mask == (1 << m) - 1 || (self.dim == 3 && mask != 0) {
            return None;
        }
        if mask != 0 {
            fold_missing(&mut values, mask, [s[0] - wx as f64, s[1] - wy as f64]);
        }
        Some((support, values))
    }

    /// The support holding lattice coordinates `s` of the whole 2D lattice and, per node of
    /// it, `[N, ∂N/∂s_x, ∂N/∂s_y, ∂²N/∂s_x², ∂²N/∂s_x∂s_y, ∂²N/∂s_y²]` (derivatives per lattice
    /// cell); `None` on a lattice with holes, whose folded functions are not kept to second
    /// order, and in 3D.
    pub fn functions_with_hessian(&self, s: [f64; 3], half_cells: [f64; 3]) -> Option<(usize, [[f64; 6]; 9])> {
        if !self.missing.is_empty() || self.dim != 2 {
            return None;
        }
        let (wx, fx) = self.basis.window_1d_derivatives(s[0], self.cells[0], half_cells[0]);
        let (wy, fy) = self.basis.window_1d_derivatives(s[1], self.cells[1], half_cells[1]);
        let values = std::array::from_fn(|k| {
            let (x, y) = (fx[k % 3], fy[k / 3]);
            [x[0] * y[0], x[1] * y[0], x[0] * y[1], x[2] * y[0], x[1] * y[1], x[0] * y[2]]
        });
        Some((self.support_of([wx, wy, 0]), values))
    }

    /// The support of a point at `x` of the fixed lattice whose domain has the half lengths
    /// `half_size` along the axes (GIMP's `l_p,d`) and its functions there: shape values,
    /// gradients `∂N/∂x`, and the radius `Σ N_I x_I` in axisymmetry (weight 0: the caller's).
    /// `None` outside the lattice.
    pub fn evaluate(
        &self,
        x: &[f64; 3],
        half_size: [f64; 3],
        formulation: Formulation,
    ) -> Option<(usize, PointGeometry)> {
        let s = self.lattice_coordinates(x)?;
        Some(self.evaluate_at(s, half_size, formulation))
    }

    /// [`SmoothLattice::evaluate`] at lattice coordinates `s` of the fixed lattice.
    fn evaluate_at(&self, s: [f64; 3], half_size: [f64; 3], formulation: Formulation) -> (usize, PointGeometry) {
        let (support, values) = self.functions_at(s, self.in_cells(half_size));
        (support, self.geometry_of(support, &values, formulation))
    }

    /// The point geometry of the functions `values` of `support`: shape values, gradients
    /// `∂N/∂x`, and the radius `Σ N_I x_I` in axisymmetry (weight 0: the caller's).
    fn geometry_of(&self, support: usize, values: &SupportValues, formulation: Formulation) -> PointGeometry {
        let mut g =
            PointGeometry { shape: [0.0; MAX_NODES], gradient: [[0.0; 3]; MAX_NODES], weight: 0.0, radius: 0.0 };
        self.geometry_into(support, values, formulation, &mut g);
        g
    }

    /// [`SmoothLattice::geometry_of`] written into `g` in place (its entries past the support's
    /// nodes untouched, its weight 0).
    fn geometry_into(&self, support: usize, values: &SupportValues, formulation: Formulation, g: &mut PointGeometry) {
        g.weight = 0.0;
        g.radius = 0.0;
        let wx = self.window(support)[0];
        let h = self.spacing;
        for (a, v) in values.iter().enumerate().take(self.support_len()) {
            g.shape[a] = v[0];
            g.gradient[a] = [v[1] / h[0], v[2] / h[1], if self.dim == 3 { v[3] / h[2] } else { 0.0 }];
            if formulation == Formulation::Axisymmetric {
                g.radius += v[0] * (self.origin[0] + (wx + a % 3) as f64 * h[0]);
            }
        }
    }

    /// The span of the lattice whose points fall into window `w` along direction `d`, in
    /// lattice coordinates `[lo, hi]` (the nearest nodes' half cells; the edge windows reach
    /// to the edge).
    fn span(&self, d: usize, w: usize) -> [f64; 2] {
        let n = self.cells[d];
        let lo = if w == 0 { 0.0 } else { w as f64 + 0.5 };
        let hi = if w == n - 2 { n as f64 } else { w as f64 + 1.5 };
        [lo, hi]
    }

    /// The 3-point Gauss rule over [`SmoothLattice::span`] `(d, w)`: per point its lattice
    /// coordinate and its weight in lattice cells.
    fn gauss_1d(&self, d: usize, w: usize) -> [(f64, f64); 3] {
        let [lo, hi] = self.span(d, w);
        let (xi, weight) = GAUSS_3;
        std::array::from_fn(|k| (0.5 * (lo + hi) + 0.5 * (hi - lo) * xi[k], weight[k] * 0.5 * (hi - lo)))
    }

    /// A 3-point-per-direction Gauss rule over the region of support `s` in lattice
    /// coordinates (9 points in 2D, 27 in 3D: the first [`SmoothLattice::support_len`]
    /// entries): per point its lattice coordinates and its weight in lattice cells (`Σ = ` the
    /// region's area or volume in cells).
    pub fn projection_points(&self, s: usize) -> [([f64; 3], f64); MAX_SUPPORT_NODES] {
        let w = self.window(s);
        let rules: [[(f64, f64); 3]; 3] =
            std::array::from_fn(|d| if d < self.dim { self.gauss_1d(d, w[d]) } else { [(0.0, 1.0); 3] });
        std::array::from_fn(|q| {
            let k = [q % 3, (q / 3) % 3, q / 9];
            let mut point = [0.0; 3];
            let mut weight = 1.0;
            for d in 0..self.dim {
                let (coordinate, factor) = rules[d][k[d]];
                point[d] = coordinate;
                weight *= factor;
            }
            (point, weight)
        })
    }

    /// The cell volume (area in 2D) of the fixed lattice, `Π h_d`.
    pub fn cell_measure(&self) -> f64 {
        self.spacing[..self.dim].iter().product()
    }

    /// The Gauss rule of [`SmoothLattice::projection_points`] over the region of support `s`
    /// of the fixed lattice (weights: the region's volume with the formulation's thickness or
    /// `2πR`), with the basis's functions at its points (GIMP with `l = 0`): the rule on which
    /// a u–p support integrates its pressure projection ([`loam_fem::mixed_kernel`]). Writes
    /// [`SmoothLattice::support_len`] points into `rule`.
    pub fn projection_rule(&self, s: usize, formulation: Formulation, thickness: f64, rule: &mut [PointGeometry]) {
        let points = self.projection_points(s);
        if self.missing.get(s).is_some_and(|&mask| mask != 0) {
            for (g, (point, weight)) in rule.iter_mut().zip(points).take(self.support_len()) {
                let (_, mut geometry) = self.evaluate_at(point, [0.0; 3], formulation);
                geometry.weight = weight * self.cell_measure() * formulation.measure_factor(thickness, geometry.radius);
                *g = geometry;
            }
            return;
        }
        // the whole support: the tensor products of the cached 1D factors, the same products
        // as `functions_without` forms (bit for bit the evaluation at the points)
        let w = self.window(s);
        let flat = [(1.0, 0.0), (0.0, 0.0), (0.0, 0.0)];
        for (q, (g, (_, weight))) in rule.iter_mut().zip(points).take(self.support_len()).enumerate() {
            let k = [q % 3, (q / 3) % 3, q / 9];
            let factors = std::array::from_fn(|d| if d < self.dim { self.projection_1d[d][w[d]][k[d]] } else { flat });
            self.geometry_into(s, &tensor_values(factors, self.support_len()), formulation, g);
            g.weight = weight * self.cell_measure() * formulation.measure_factor(thickness, g.radius);
        }
    }

    /// The integrals of support `s`'s functions over its region ([`CellProjection`]) as the
    /// tensor products of the 1D integrals on the rule of [`SmoothLattice::projection_rule`]
    /// (the same rule, factorised: `Σ_q Π_d w_qd N_ad N_bd = Π_d Σ_qd w_qd N_ad N_bd`), times
    /// the cell's measure and the thickness: no point's functions formed at an assembly.
    /// `false` (and `out` untouched) where the integrand does not factorise, which the caller
    /// integrates on the rule: a support with removed nodes (folded functions) and
    /// axisymmetry (the weight `2πR`).
    pub fn projection_moments(
        &self,
        s: usize,
        formulation: Formulation,
        thickness: f64,
        out: &mut CellProjection,
    ) -> bool {
        if formulation == Formulation::Axisymmetric || self.missing.get(s).is_some_and(|&mask| mask != 0) {
            return false;
        }
        let w = self.window(s);
        let unit = WindowMoments { mass: [[1.0; 3]; 3], moments: [1.0; 3], length: 1.0 };
        let factors: [WindowMoments; 3] =
            std::array::from_fn(|d| if d < self.dim { self.projection_moments_1d[d][w[d]] } else { unit });
        let [x, y, z] = factors;
        let scale = self.cell_measure() * formulation.measure_factor(thickness, 0.0);
        let m = self.support_len();
        let local = |a: usize| (a % 3, (a / 3) % 3, if m == 27 { a / 9 } else { 0 });
        for a in 0..m {
            let (ax, ay, az) = local(a);
            out.moments[a] = scale * x.moments[ax] * y.moments[ay] * z.moments[az];
            for b in 0..m {
                let (bx, by, bz) = local(b);
                out.mass[a * m + b] = scale * x.mass[ax][bx] * y.mass[ay][by] * z.mass[az][bz];
            }
        }
        out.volume = scale * x.length * y.length * z.length;
        true
    }

    /// Supports whose window is within `reach` node rows of a window of `supports`
    /// (ascending, included) along every axis: `reach = 2` gives the supports sharing a node
    /// with one of `supports` (the set grown by one ring), `reach = 1` those overlapping one
    /// by two node rows (half the ring's width).
    pub fn dilate(&self, supports: &[usize], reach: usize) -> Vec<usize> {
        let n = self.windows();
        let mut mark = vec![false; self.num_supports()];
        let reach = |w: usize, d: usize| w.saturating_sub(reach)..(w + reach + 1).min(n[d]);
        for &s in supports {
            let w = self.window(s);
            for kk in reach(w[2], 2) {
                for jj in reach(w[1], 1) {
                    for ii in reach(w[0], 0) {
                        mark[self.support_of([ii, jj, kk])] = true;
                    }
                }
            }
        }
        (0..mark.len()).filter(|&s| mark[s]).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const BASES: [Basis; 2] = [Basis::Gimp, Basis::Bspline2];

    /// Partition of unity, reproduction of linear fields and non-negativity over a lattice of
    /// 5 cells, edges included, for GIMP (l = ¼, ½) and B-splines; the functions' derivatives
    /// against central differences; and continuity of the derivative across cell edges and
    /// half-cell breakpoints (no jump larger than the step's own change).
    #[test]
    fn smooth_windows_are_a_partition_of_unity_reproducing_linear_fields() {
        let n = 5;
        for basis in BASES {
            for l in [0.25, 0.5] {
                let at = |s: f64| {
                    let (w, v) = basis.window_1d(s, n, l);
                    let mut full = vec![(0.0, 0.0); n + 1];
                    for (k, &f) in v.iter().enumerate() {
                        full[w + k] = f;
                    }
                    full
                };
                let samples = 2001;
                let mut previous: Option<Vec<(f64, f64)>> = None;
                for k in 0..samples {
                    let s = n as f64 * k as f64 / (samples - 1) as f64;
                    let f = at(s);
                    let sum: f64 = f.iter().map(|v| v.0).sum();
                    let first: f64 = f.iter().enumerate().map(|(i, v)| v.0 * i as f64).sum();
                    let slope: f64 = f.iter().map(|v| v.1).sum();
                    let slope1: f64 = f.iter().enumerate().map(|(i, v)| v.1 * i as f64).sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{basis:?} l={l}: Σ N = {sum} at s = {s}");
                    assert!((first - s).abs() < 1e-12, "{basis:?} l={l}: Σ N x = {first} at s = {s}");
                    assert!(slope.abs() < 1e-12 && (slope1 - 1.0).abs() < 1e-12, "{basis:?} at s = {s}");
                    assert!(f.iter().all(|v| v.0 >= -1e-14), "{basis:?} l={l}: a negative function at s = {s}");
                    // derivative against central differences (off the breakpoints)
                    let h = 1e-6;
                    if s > 2.0 * h && s < n as f64 - 2.0 * h {
                        let (p, m) = (at(s + h), at(s - h));
                        for i in 0..=n {
                            let fd = (p[i].0 - m[i].0) / (2.0 * h);
                            assert!(
                                (fd - f[i].1).abs() < 1e-5,
                                "{basis:?} l={l}: dN_{i}/ds {} vs FD {fd} at s = {s}",
                                f[i].1
                            );
                        }
                    }
                    if let Some(prev) = &previous {
                        let ds = n as f64 / (samples - 1) as f64;
                        for i in 0..=n {
                            let jump = (f[i].1 - prev[i].1).abs();
                            // C¹: the derivative changes by at most (max |N''|) ds
                            let bound = ds * if basis == Basis::Gimp { 1.0 / l } else { 2.0 } + 1e-12;
                            assert!(jump <= bound, "{basis:?} l={l}: dN_{i}/ds jumps by {jump} at s = {s}");
                        }
                    }
                    previous = Some(f);
                }
            }
        }
        // interpolatory on the edges
        for basis in BASES {
            let (w, v) = basis.window_1d(0.0, n, 0.5);
            assert_eq!((w, v[0].0, v[1].0, v[2].0), (0, 1.0, 0.0, 0.0), "{basis:?} at the lower edge");
            let (w, v) = basis.window_1d(n as f64, n, 0.5);
            assert_eq!((w, v[2].0, v[1].0, v[0].0), (n - 2, 1.0, 0.0, 0.0), "{basis:?} at the upper edge");
        }
    }

    /// The projection rule from the cached 1D factors ([`SmoothLattice::projection_rule`]) is
    /// the basis evaluated at the rule's points, bit for bit: every support of a 2D and a 3D
    /// lattice (edges included), both bases, plane strain, axisymmetry and 3D.
    #[test]
    fn cached_projection_rule_is_the_evaluation_at_its_points() {
        for basis in BASES {
            for dim in [2, 3] {
                let lattice = SmoothLattice::new(basis, dim, [1.0, -2.0, 0.5], [0.5, 0.25, 0.4], [5, 4, 3]);
                let formulations: &[Formulation] = if dim == 3 {
                    &[Formulation::ThreeD]
                } else {
                    &[Formulation::PlaneStrain, Formulation::Axisymmetric]
                };
                for &formulation in formulations {
                    for s in 0..lattice.num_supports() {
                        let mut rule = [PointGeometry::default(); MAX_NODES];
                        lattice.projection_rule(s, formulation, 0.7, &mut rule);
                        for (q, (point, weight)) in
                            lattice.projection_points(s).iter().take(lattice.support_len()).enumerate()
                        {
                            let (support, g) = lattice.evaluate_at(*point, [0.0; 3], formulation);
                            let weight = weight * lattice.cell_measure() * formulation.measure_factor(0.7, g.radius);
                            let cached = &rule[q];
                            assert_eq!(support, s);
                            assert!(
                                cached.shape == g.shape
                                    && cached.gradient == g.gradient
                                    && cached.radius.to_bits() == g.radius.to_bits()
                                    && cached.weight.to_bits() == weight.to_bits(),
                                "{basis:?} {dim}D {formulation:?}: support {s}, point {q}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The closed-form projection integrals ([`SmoothLattice::projection_moments`]) against
    /// the same integrals summed on the projection rule's points, every support of a 2D and a
    /// 3D lattice (edges included), both bases, plane strain and 3D: relative difference
    /// below 1e-13 (round-off of the factorised sums); the partition of unity `Σ_a m_a = V`
    /// and `Σ_b M_ab = m_a`; axisymmetry and holed supports declined (left to the rule).
    #[test]
    fn projection_moments_are_the_rule_factorised() {
        for basis in BASES {
            for dim in [2, 3] {
                let lattice = SmoothLattice::new(basis, dim, [1.0, -2.0, 0.5], [0.5, 0.25, 0.4], [5, 4, 3]);
                let formulation = if dim == 3 { Formulation::ThreeD } else { Formulation::PlaneStrain };
                let m = lattice.support_len();
                for s in 0..lattice.num_supports() {
                    let mut rule = [PointGeometry::default(); MAX_NODES];
                    lattice.projection_rule(s, formulation, 0.7, &mut rule);
                    let mut on_rule = CellProjection::default();
                    on_rule.integrate(m, &rule[..m]);
                    let mut closed = CellProjection::default();
                    assert!(lattice.projection_moments(s, formulation, 0.7, &mut closed));
                    let scale = on_rule.volume;
                    let pairs = closed.mass[..m * m]
                        .iter()
                        .zip(&on_rule.mass[..m * m])
                        .chain(closed.moments[..m].iter().zip(&on_rule.moments[..m]))
                        .chain(std::iter::once((&closed.volume, &on_rule.volume)));
                    let diff = pairs.fold(0.0f64, |d, (a, b)| d.max((a - b).abs() / scale));
                    assert!(diff < 1e-13, "{basis:?} {dim}D support {s}: {diff:e}");
                    let total: f64 = closed.moments[..m].iter().sum();
                    assert!((total - closed.volume).abs() < 1e-13 * scale, "{basis:?} {dim}D support {s}");
                    for a in 0..m {
                        let row: f64 = closed.mass[a * m..(a + 1) * m].iter().sum();
                        assert!((row - closed.moments[a]).abs() < 1e-13 * scale, "{basis:?} {dim}D support {s}");
                    }
                }
                if dim == 2 {
                    let mut out = CellProjection::default();
                    assert!(!lattice.projection_moments(0, Formulation::Axisymmetric, 0.7, &mut out));
                    // a hole at grid node (2, 2) (of 6 × 5): declined exactly where it is missing
                    let removed = 2 * 6 + 2;
                    let new_node: Vec<usize> =
                        (0..30).map(|a| if a == removed { usize::MAX } else { a - usize::from(a > removed) }).collect();
                    let holed = lattice.holed(&new_node);
                    for s in 0..lattice.num_supports() {
                        let has_hole = lattice.support(s).contains(&removed);
                        assert_eq!(holed.projection_moments(s, formulation, 0.7, &mut out), !has_hole, "support {s}");
                    }
                }
            }
        }
    }

    /// The 2D and 3D functions: partition of unity, reproduction of linear fields (values and
    /// gradients), and every point's support holding the nodes its functions reach.
    #[test]
    fn supports_hold_every_node_a_point_reaches() {
        for basis in BASES {
            for dim in [2, 3] {
                let (origin, spacing, cells) = ([1.0, -2.0, 0.5], [0.5, 0.25, 0.4], [4, 3, 3]);
                let lattice = SmoothLattice::new(basis, dim, origin, spacing, cells);
                let m = lattice.support_len();
                let coords = |a: usize| -> [f64; 3] {
                    let (i, j, k) = (a % 5, (a / 5) % 4, a / 20);
                    [origin[0] + 0.5 * i as f64, origin[1] + 0.25 * j as f64, origin[2] + 0.4 * k as f64]
                };
                let formulation = if dim == 3 { Formulation::ThreeD } else { Formulation::PlaneStrain };
                for k in 0..400 {
                    let t = [(k as f64 * 0.618).fract(), (k as f64 * 0.382).fract(), (k as f64 * 0.271).fract()];
                    let x: [f64; 3] = std::array::from_fn(|d| {
                        if d < dim {
                            origin[d] + spacing[d] * cells[d] as f64 * t[d]
                        } else {
                            0.0
                        }
                    });
                    let (s, g) = lattice.evaluate(&x, [0.1, 0.05, 0.08], formulation).unwrap();
                    let nodes = lattice.support(s);
                    assert_eq!(nodes.len(), m);
                    let sum: f64 = g.shape[..m].iter().sum();
                    assert!((sum - 1.0).abs() < 1e-12, "{basis:?} {dim}D: Σ N = {sum}");
                    for d in 0..dim {
                        let xd: f64 = (0..m).map(|a| g.shape[a] * coords(nodes[a])[d]).sum();
                        assert!((xd - x[d]).abs() < 1e-12, "{basis:?} {dim}D: Σ N x_{d} = {xd} at {x:?}");
                        for e in 0..dim {
                            let grad: f64 = (0..m).map(|a| g.gradient[a][e] * coords(nodes[a])[d]).sum();
                            let expected = if d == e { 1.0 } else { 0.0 };
                            assert!((grad - expected).abs() < 1e-12, "{basis:?} {dim}D: ∂x_{d}/∂x_{e} = {grad}");
                        }
                    }
                }
                assert!(lattice.evaluate(&[0.9, -1.0, 0.6], [0.1; 3], formulation).is_none());
            }
        }
    }

    /// Relative error (of the largest entry) of the consistent tangent of support 0's block
    /// against central finite differences of its residual, for the points at `xs` (all in
    /// support 0 of `grid`), `F0 ≠ I`, the displacement kernel or the u–p kernel with the
    /// support's projection rule; asserts that a Mohr–Coulomb check reaches the yield surface.
    fn support_tangent_error(
        grid: &crate::grid::Grid,
        xs: &[[f64; 3]],
        formulation: Formulation,
        law: &dyn loam_laws::ConstitutiveLaw,
        mixed: bool,
    ) -> f64 {
        use loam_fem::element::ElementType;
        use loam_fem::kernel::{solid_element, KernelContext, PointOutput};
        use loam_fem::mixed_kernel::mixed_element;
        use nalgebra::Matrix3;

        let dim = grid.mesh.element.dim();
        let nn = grid.support_len();
        let nu = nn * dim;
        let np = xs.len();
        let geometry: Vec<PointGeometry> = xs
            .iter()
            .map(|x| {
                let (s, mut g) = grid.point_functions(x, [0.125, 0.1, 0.08], formulation, 1.0).unwrap();
                assert_eq!(s, 0, "the points share the corner support");
                g.weight = 0.02 * formulation.measure_factor(1.0, g.radius);
                g
            })
            .collect();
        let mut rule = [geometry[0]; MAX_NODES];
        let mut projection = loam_fem::mixed_kernel::CellProjection::default();
        grid.projection_moments(0, formulation, 1.0, &mut rule, &mut projection).unwrap();
        // F0 ≠ I (in 3D with all nine components; in 2D without the out-of-plane coupling)
        let off = if dim == 3 { 1.0 } else { 0.0 };
        let f0 = vec![Matrix3::new(1.05, 0.03, 0.01 * off, -0.02, 0.97, 0.015 * off, 0.0, -0.01 * off, 1.02); np];
        let element = if dim == 3 { ElementType::Hex8 } else { ElementType::Quad4 };
        let ctx = KernelContext { element, formulation, law, time_step: 0.0 };
        let stride = law.state_len();
        let mut committed = vec![0.0; np * stride];
        committed.chunks_mut(stride.max(1)).for_each(|c| law.initialise_state(c));
        let nd = if mixed { nu + nn } else { nu };
        let mut unknowns: Vec<f64> = (0..nd).map(|k| 0.004 * ((k * 7 + 3) as f64).sin()).collect();
        if mixed {
            for a in 0..nn {
                unknowns[nu + a] = -2.0e3 + 500.0 * (a as f64).cos();
            }
        }
        let disp_of = |v: &[f64]| -> Vec<[f64; 3]> {
            (0..nn).map(|a| std::array::from_fn(|i| if i < dim { v[dim * a + i] } else { 0.0 })).collect()
        };
        let residual = |v: &[f64], k: Option<&mut [f64]>| {
            let disp = disp_of(v);
            let mut f = vec![0.0; nd];
            let mut out = vec![PointOutput::default(); np];
            let mut trial = committed.clone();
            if mixed {
                mixed_element(
                    &ctx,
                    &disp,
                    &v[nu..],
                    &geometry[..],
                    &f0,
                    &f0,
                    &committed,
                    &mut trial,
                    &mut out,
                    &mut f,
                    k,
                    Some(&projection),
                )
                .unwrap();
            } else {
                solid_element(&ctx, &disp, &geometry[..], &f0, &f0, &committed, &mut trial, &mut out, &mut f, k)
                    .unwrap();
            }
            f
        };
        let mut k = vec![0.0; nd * nd];
        residual(&unknowns, Some(&mut k));
        if let Some(flag) = law.state_variables().iter().position(|v| *v == "yield_flag") {
            let disp = disp_of(&unknowns);
            let (mut f, mut out, mut trial) = (vec![0.0; nu], vec![PointOutput::default(); np], committed.clone());
            solid_element(&ctx, &disp, &geometry[..], &f0, &f0, &committed, &mut trial, &mut out, &mut f, None)
                .unwrap();
            let mut values = vec![0.0; law.state_variables().len()];
            let yielded = trial.chunks(stride).filter(|st| {
                law.state_output(st, &mut values);
                values[flag] > 0.0
            });
            assert!(yielded.count() > 0, "the check must reach the yield surface");
        }
        let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let mut err = 0.0f64;
        for c in 0..nd {
            let h = if c < nu { 1e-7 } else { 1e-2 };
            let (mut p, mut m) = (unknowns.clone(), unknowns.clone());
            p[c] += h;
            m[c] -= h;
            let (fp, fm) = (residual(&p, None), residual(&m, None));
            for r in 0..nd {
                err = err.max(((fp[r] - fm[r]) / (2.0 * h) - k[r * nd + c]).abs() / kmax);
            }
        }
        err
    }

    /// The Neo-Hookean and the Mohr–Coulomb (on its yield surface) laws of the tangent checks.
    fn tangent_laws() -> [Box<dyn loam_laws::ConstitutiveLaw>; 2] {
        use loam_laws::mohr_coulomb::MohrCoulomb;
        use loam_laws::neo_hookean::NeoHookean;
        [
            Box::new(NeoHookean::new(1000.0, 1.0e6, 0.3)),
            Box::new(MohrCoulomb::new(1000.0, 1.0e6, 0.3, 25f64.to_radians(), 2.0e3, 0.0)),
        ]
    }

    /// The consistent tangent of a smooth support's 9-node block against central finite
    /// differences of its residual (relative error < 1e-6 of the largest entry), for the
    /// displacement kernel and the u–p kernel (with the support's projection rule), in plane
    /// strain and axisymmetry, `F0 ≠ I`, Neo-Hookean and Mohr–Coulomb on its yield surface:
    /// the support at the lattice's corner holds a point next to the edge nodes (folded
    /// functions), one straddling a cell edge (its GIMP domain on both sides) and one near a
    /// half-cell breakpoint of the B-splines; on the fixed lattice and on the lattice moved by
    /// a structure on its edge (points next to the interface).
    #[test]
    fn smooth_support_tangents_match_finite_differences() {
        use loam_fem::element::ElementType;
        for (basis, moved) in BASES.iter().flat_map(|&b| [(b, false), (b, true)]) {
            // the lattice fixed, or moved as a structure on its edge x = 0.2 moves it (the
            // edge's nodes down and turned, the motion decaying into the grid): the points
            // then lie next to the interface
            let mut grid = crate::grid::Grid::new([0.2, 0.0, 0.0], [2.0, 1.6, 0.0], [4, 4, 1], ElementType::Quad4);
            grid.set_basis(basis).unwrap();
            if moved {
                let motion: Vec<[f64; 3]> = grid
                    .reference_coords()
                    .iter()
                    .map(|x| {
                        let decay = (1.0 - (x[0] - 0.2) / 2.0).powi(2);
                        [-0.05 * (x[1] - 0.8) * decay, -0.08 * decay, 0.0]
                    })
                    .collect();
                grid.move_nodes(&motion).unwrap();
            }
            // lattice coordinates near (0.08, 0.3), (1.02, 0.9), (0.55, 1.45): all in support 0
            let xs: Vec<[f64; 3]> = [[0.24, 0.12, 0.0], [0.71, 0.36, 0.0], [0.475, 0.58, 0.0]]
                .iter()
                .map(|x| if moved { [x[0] - 0.05 * (x[1] - 0.8), x[1] - 0.08, 0.0] } else { *x })
                .collect();
            for formulation in [Formulation::PlaneStrain, Formulation::Axisymmetric] {
                for law in tangent_laws() {
                    for mixed in [false, true] {
                        let err = support_tangent_error(&grid, &xs, formulation, law.as_ref(), mixed);
                        println!(
                            "{basis:?}{} {formulation:?} {}{}: 9-node support tangent vs central FD, relative error {err:.2e} (tolerance 1e-6)",
                            if moved { " (moved by a structure)" } else { "" },
                            law.name(),
                            if mixed { " u–p" } else { "" }
                        );
                        assert!(err < 1e-6, "{basis:?} {formulation:?} {}: {err}", law.name());
                    }
                }
            }
        }
    }

    /// The 27-node blocks of the 3D smooth supports: their consistent tangents against central
    /// finite differences (relative error < 1e-6), displacement and u–p, Neo-Hookean and
    /// Mohr–Coulomb on its yield surface, for the corner support of a hex8 lattice holding a
    /// point next to the boundary nodes (folded functions), one straddling a cell edge (its
    /// GIMP domain on both sides) and one near a half-cell breakpoint of the B-splines.
    #[test]
    fn smooth_support_tangents_match_finite_differences_in_3d() {
        use loam_fem::element::ElementType;
        for basis in BASES {
            let mut grid = crate::grid::Grid::new([0.2, 0.0, -0.3], [2.0, 1.6, 1.2], [4, 4, 3], ElementType::Hex8);
            grid.set_basis(basis).unwrap();
            assert_eq!(grid.support_len(), 27);
            // lattice coordinates (0.08, 0.3, 0.2), (1.02, 0.9, 0.99), (0.55, 1.45, 1.3)
            let xs = [[0.24, 0.12, -0.22], [0.71, 0.36, 0.096], [0.475, 0.58, 0.22]];
            for law in tangent_laws() {
                for mixed in [false, true] {
                    let err = support_tangent_error(&grid, &xs, Formulation::ThreeD, law.as_ref(), mixed);
                    println!(
                        "{basis:?} 3D {}{}: 27-node support tangent vs central FD, relative error {err:.2e} (tolerance 1e-6)",
                        law.name(),
                        if mixed { " u–p" } else { "" }
                    );
                    assert!(err < 1e-6, "{basis:?} 3D {}: {err}", law.name());
                }
            }
        }
    }
}
