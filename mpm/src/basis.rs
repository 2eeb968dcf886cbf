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
//! Both smooth bases are tensor products over a structured lattice of quad4 cells. A point
//! whose nearest node is `i_c` has non-zero functions on the nodes `i_c − 1, i_c, i_c + 1`
//! in each direction (for GIMP because `l ≤ ½`): the point's **support**, a window of 3 × 3
//! nodes whose block the point's stiffness fills. Windows start at `w = clamp(i_c − 1, 0,
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

/// Folds the functions of a support's removed nodes (`mask`, bit `3 ky + kx`) into the nodes
/// it keeps, by the extrapolation of a linear field from kept nodes (so the folded functions
/// stay a partition of unity that reproduces linear fields, as at the lattice's edge):
/// along the row or the column of the removed node, whichever leads from it towards the point
/// at local lattice coordinates `t` (`t − k` larger along it; the other if that one lacks
/// nodes), `u_k = Σ_j u_j Π (k − i)/(j − i)` over its two kept nodes; else by the rectangle
/// rule `u_(k,l) = u_(k',l) + u_(k,l') − u_(k',l')`; else (a sliver of soil narrower than the
/// support) onto the nearest kept node. The choice of direction changes only where
/// `|t_x − k_x| = |t_y − k_y|`, beside a hole's corner, where the removed function is at most
/// `N(1)² = 1/64` (B-splines): the folded basis jumps by no more there.
fn fold_missing(values: &mut [[f64; 3]; SUPPORT_NODES], mask: u16, t: [f64; 2]) {
    let kept = |k: usize| mask & (1 << k) == 0;
    for m in (0..SUPPORT_NODES).filter(|&m| !kept(m)) {
        let f = values[m];
        values[m] = [0.0; 3];
        if f == [0.0; 3] {
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
            let nearest = (0..SUPPORT_NODES)
                .filter(|&k| kept(k))
                .min_by_key(|&k| (k % 3).abs_diff(mx) + (k / 3).abs_diff(my))
                .expect("a support holding a point keeps a node");
            vec![(nearest, 1.0)]
        };
        for (k, c) in stencil {
            for i in 0..3 {
                values[k][i] += c * f[i];
            }
        }
    }
}

/// Nodes per support of a smooth basis in 2D (3 × 3).
pub const SUPPORT_NODES: usize = 9;

/// A structured, unrotated 2D lattice of quad4 cells carrying a smooth basis: its supports
/// (3 × 3-node windows) and the functions of a point (see the module doc).
#[derive(Debug, Clone)]
pub struct SmoothLattice {
    basis: Basis,
    origin: [f64; 2],
    spacing: [f64; 2],
    cells: [usize; 2],
    /// The nine grid nodes of each support, support `wy (n_x − 1) + wx` at `9 s..9 s + 9`,
    /// node `(wx + kx, wy + ky)` at local index `3 ky + kx` (a node removed with a hole: a
    /// node of the same support, whose function the fold leaves 0 there).
    nodes: Vec<usize>,
    /// Per support, the local nodes removed with a hole (bit `3 ky + kx`); empty while the
    /// lattice is whole.
    missing: Vec<u16>,
}

impl SmoothLattice {
    /// The supports of `basis` (smooth) on the lattice `origin + [0, cells · spacing]`, whose
    /// node `(i, j)` is grid node `j (n_x + 1) + i`. Needs two or more cells per direction.
    pub fn new(basis: Basis, origin: [f64; 2], spacing: [f64; 2], cells: [usize; 2]) -> Self {
        debug_assert!(basis.is_smooth() && cells[0] >= 2 && cells[1] >= 2);
        let (wx, wy) = (cells[0] - 1, cells[1] - 1);
        let mut nodes = Vec::with_capacity(wx * wy * SUPPORT_NODES);
        for j in 0..wy {
            for i in 0..wx {
                for ky in 0..3 {
                    for kx in 0..3 {
                        nodes.push((j + ky) * (cells[0] + 1) + i + kx);
                    }
                }
            }
        }
        Self { basis, origin, spacing, cells, nodes, missing: Vec::new() }
    }

    /// The lattice without the nodes of a hole: `new_node[a]` is the new index of grid node
    /// `a` (`usize::MAX` where it was removed with the cells inside a structure). A removed
    /// node's function is folded into the nodes its support keeps
    /// ([`SmoothLattice::functions_at`]).
    pub fn holed(&self, new_node: &[usize]) -> Self {
        let mut nodes = Vec::with_capacity(self.nodes.len());
        let mut missing = Vec::with_capacity(self.num_supports());
        for (support, window) in self.nodes.chunks(SUPPORT_NODES).enumerate() {
            let mut mask = self.missing.get(support).copied().unwrap_or(0);
            let kept = (0..SUPPORT_NODES)
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
    pub fn spacing(&self) -> [f64; 2] {
        self.spacing
    }

    /// The basis.
    pub fn basis(&self) -> Basis {
        self.basis
    }

    /// Number of supports.
    pub fn num_supports(&self) -> usize {
        (self.cells[0] - 1) * (self.cells[1] - 1)
    }

    /// The grid nodes of support `s`.
    pub fn support(&self, s: usize) -> &[usize] {
        &self.nodes[s * SUPPORT_NODES..(s + 1) * SUPPORT_NODES]
    }

    /// Lattice coordinates `(x − x_0)/h` of `x` on the fixed lattice, or `None` outside it.
    pub fn lattice_coordinates(&self, x: &[f64; 3]) -> Option<[f64; 2]> {
        let mut s = [0.0; 2];
        for d in 0..2 {
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
    pub fn clamped_coordinates(&self, x: [f64; 2]) -> [f64; 2] {
        std::array::from_fn(|d| ((x[d] - self.origin[d]) / self.spacing[d]).clamp(0.0, self.cells[d] as f64))
    }

    /// Lattice coordinates clamped to the lattice.
    pub fn clamp(&self, s: [f64; 2]) -> [f64; 2] {
        std::array::from_fn(|d| s[d].clamp(0.0, self.cells[d] as f64))
    }

    /// The support holding lattice coordinates `s` and, per node of it, `(N, ∂N/∂s_x,
    /// ∂N/∂s_y)` with the derivatives per lattice cell; `half_cells` is GIMP's `l_p,d / h_d`.
    pub fn functions_at(&self, s: [f64; 2], half_cells: [f64; 2]) -> (usize, [[f64; 3]; SUPPORT_NODES]) {
        self.functions_without(s, half_cells, |_| false).expect("a support holding a point keeps a node")
    }

    /// [`SmoothLattice::functions_at`] with the functions of the support's grid nodes for
    /// which `absent` holds folded into the others as those of a hole's removed nodes are
    /// (`fold_missing`: a linear field extrapolated from the nodes kept): for a point beside
    /// which the soil ends before those nodes. `None` if the support keeps no node.
    pub fn functions_without(
        &self,
        s: [f64; 2],
        half_cells: [f64; 2],
        absent: impl Fn(usize) -> bool,
    ) -> Option<(usize, [[f64; 3]; SUPPORT_NODES])> {
        let (wx, fx) = self.basis.window_1d(s[0], self.cells[0], half_cells[0]);
        let (wy, fy) = self.basis.window_1d(s[1], self.cells[1], half_cells[1]);
        let mut values = [[0.0; 3]; SUPPORT_NODES];
        for ky in 0..3 {
            for kx in 0..3 {
                values[3 * ky + kx] = [fx[kx].0 * fy[ky].0, fx[kx].1 * fy[ky].0, fx[kx].0 * fy[ky].1];
            }
        }
        let support = wy * (self.cells[0] - 1) + wx;
        let mut mask = self.missing.get(support).copied().unwrap_or(0);
        for (k, &a) in self.support(support).iter().enumerate() {
            if absent(a) {
                mask |= 1 << k;
            }
        }
        if mask == (1 << SUPPORT_NODES) - 1 {
            return None;
        }
        if mask != 0 {
            fold_missing(&mut values, mask, [s[0] - wx as f64, s[1] - wy as f64]);
        }
        Some((support, values))
    }

    /// The support holding lattice coordinates `s` of the whole lattice and, per node of it,
    /// `[N, ∂N/∂s_x, ∂N/∂s_y, ∂²N/∂s_x², ∂²N/∂s_x∂s_y, ∂²N/∂s_y²]` (derivatives per lattice
    /// cell); `None` on a lattice with holes, whose folded functions are not kept to second
    /// order.
    pub fn functions_with_hessian(
        &self,
        s: [f64; 2],
        half_cells: [f64; 2],
    ) -> Option<(usize, [[f64; 6]; SUPPORT_NODES])> {
        if !self.missing.is_empty() {
            return None;
        }
        let (wx, fx) = self.basis.window_1d_derivatives(s[0], self.cells[0], half_cells[0]);
        let (wy, fy) = self.basis.window_1d_derivatives(s[1], self.cells[1], half_cells[1]);
        let values = std::array::from_fn(|k| {
            let (x, y) = (fx[k % 3], fy[k / 3]);
            [x[0] * y[0], x[1] * y[0], x[0] * y[1], x[2] * y[0], x[1] * y[1], x[0] * y[2]]
        });
        Some((wy * (self.cells[0] - 1) + wx, values))
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
    fn evaluate_at(&self, s: [f64; 2], half_size: [f64; 3], formulation: Formulation) -> (usize, PointGeometry) {
        let half_cells = [half_size[0] / self.spacing[0], half_size[1] / self.spacing[1]];
        let (support, values) = self.functions_at(s, half_cells);
        let mut g =
            PointGeometry { shape: [0.0; MAX_NODES], gradient: [[0.0; 3]; MAX_NODES], weight: 0.0, radius: 0.0 };
        let wx = support % (self.cells[0] - 1);
        for (a, v) in values.iter().enumerate() {
            g.shape[a] = v[0];
            g.gradient[a] = [v[1] / self.spacing[0], v[2] / self.spacing[1], 0.0];
            if formulation == Formulation::Axisymmetric {
                g.radius += v[0] * (self.origin[0] + (wx + a % 3) as f64 * self.spacing[0]);
            }
        }
        (support, g)
    }

    /// The region of the lattice whose points fall into support `s`: per direction the
    /// lattice coordinates `[lo, hi]` (the nearest nodes' half cells; the edge windows reach
    /// to the edge).
    fn region(&self, s: usize) -> [[f64; 2]; 2] {
        let w = [s % (self.cells[0] - 1), s / (self.cells[0] - 1)];
        std::array::from_fn(|d| {
            let n = self.cells[d];
            let lo = if w[d] == 0 { 0.0 } else { w[d] as f64 + 0.5 };
            let hi = if w[d] == n - 2 { n as f64 } else { w[d] as f64 + 1.5 };
            [lo, hi]
        })
    }

    /// A 3 × 3 Gauss rule over the region of support `s` in lattice coordinates: per point
    /// its lattice coordinates and its weight in lattice cells (`Σ = ` the region's area in
    /// cells).
    pub fn projection_points(&self, s: usize) -> [([f64; 2], f64); SUPPORT_NODES] {
        const XI: [f64; 3] = [-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4];
        const W: [f64; 3] = [5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0];
        let region = self.region(s);
        std::array::from_fn(|q| {
            let (kx, ky) = (q % 3, q / 3);
            let t = [XI[kx], XI[ky]];
            let mut point = [0.0; 2];
            let mut weight = W[kx] * W[ky];
            for d in 0..2 {
                let [lo, hi] = region[d];
                point[d] = 0.5 * (lo + hi) + 0.5 * (hi - lo) * t[d];
                weight *= 0.5 * (hi - lo);
            }
            (point, weight)
        })
    }

    /// A 3 × 3 Gauss rule over the region of support `s` of the fixed lattice (weights: the
    /// region's volume with the formulation's thickness or `2πR`), with the basis's functions
    /// at its points (GIMP with `l = 0`): the rule on which a u–p support integrates its
    /// pressure projection ([`loam_fem::mixed_kernel`]). Writes 9 points into `rule`.
    pub fn projection_rule(&self, s: usize, formulation: Formulation, thickness: f64, rule: &mut [PointGeometry]) {
        for (g, (point, weight)) in rule.iter_mut().zip(self.projection_points(s)) {
            let (_, mut geometry) = self.evaluate_at(point, [0.0; 3], formulation);
            geometry.weight =
                weight * self.spacing[0] * self.spacing[1] * formulation.measure_factor(thickness, geometry.radius);
            *g = geometry;
        }
    }

    /// Supports sharing a node with any support of `supports` (ascending, included): the
    /// set grown by one ring.
    pub fn dilate(&self, supports: &[usize]) -> Vec<usize> {
        let nx = self.cells[0] - 1;
        let mut mark = vec![false; self.num_supports()];
        let ny = self.cells[1] - 1;
        for &s in supports {
            let (i, j) = (s % nx, s / nx);
            for jj in j.saturating_sub(2)..(j + 3).min(ny) {
                for ii in i.saturating_sub(2)..(i + 3).min(nx) {
                    mark[jj * nx + ii] = true;
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

    /// The 2D functions: partition of unity, linear reproduction, and every point's support
    /// holding the nodes its functions reach.
    #[test]
    fn supports_hold_every_node_a_point_reaches() {
        for basis in BASES {
            let lattice = SmoothLattice::new(basis, [1.0, -2.0], [0.5, 0.25], [4, 3]);
            let coords = |a: usize| [1.0 + 0.5 * (a % 5) as f64, -2.0 + 0.25 * (a / 5) as f64];
            for k in 0..400 {
                let x = [1.0 + 2.0 * ((k as f64 * 0.618).fract()), -2.0 + 0.75 * ((k as f64 * 0.382).fract()), 0.0];
                let (s, g) = lattice.evaluate(&x, [0.1, 0.05, 0.0], Formulation::PlaneStrain).unwrap();
                let nodes = lattice.support(s);
                let sum: f64 = g.shape[..9].iter().sum();
                let xs: f64 = (0..9).map(|a| g.shape[a] * coords(nodes[a])[0]).sum();
                let ys: f64 = (0..9).map(|a| g.shape[a] * coords(nodes[a])[1]).sum();
                let gx: f64 = (0..9).map(|a| g.gradient[a][0] * coords(nodes[a])[0]).sum();
                let gy: f64 = (0..9).map(|a| g.gradient[a][1] * coords(nodes[a])[1]).sum();
                assert!((sum - 1.0).abs() < 1e-12 && (xs - x[0]).abs() < 1e-12 && (ys - x[1]).abs() < 1e-12);
                assert!((gx - 1.0).abs() < 1e-12 && (gy - 1.0).abs() < 1e-12, "{basis:?}: ∇x = ({gx}, {gy})");
            }
            assert!(lattice.evaluate(&[0.9, -1.0, 0.0], [0.1; 3], Formulation::PlaneStrain).is_none());
        }
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
        use loam_fem::kernel::{solid_element, KernelContext, PointOutput};
        use loam_fem::mixed_kernel::mixed_element;
        use loam_laws::mohr_coulomb::MohrCoulomb;
        use loam_laws::neo_hookean::NeoHookean;
        use loam_laws::ConstitutiveLaw;
        use nalgebra::Matrix3;

        let nh = NeoHookean::new(1000.0, 1.0e6, 0.3);
        let mc = MohrCoulomb::new(1000.0, 1.0e6, 0.3, 25f64.to_radians(), 2.0e3, 0.0);
        let laws: [&dyn ConstitutiveLaw; 2] = [&nh, &mc];
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
            let xs = [[0.24, 0.12, 0.0], [0.71, 0.36, 0.0], [0.475, 0.58, 0.0]];
            for formulation in [Formulation::PlaneStrain, Formulation::Axisymmetric] {
                let geometry: Vec<PointGeometry> = xs
                    .iter()
                    .map(|x| {
                        let x = if moved { [x[0] - 0.05 * (x[1] - 0.8), x[1] - 0.08, 0.0] } else { *x };
                        let (s, mut g) = grid.point_functions(&x, [0.125, 0.1, 0.0], formulation, 1.0).unwrap();
                        assert_eq!(s, 0, "the points share the corner support");
                        g.weight = 0.02 * formulation.measure_factor(1.0, g.radius);
                        g
                    })
                    .collect();
                let mut rule = [geometry[0]; MAX_NODES];
                grid.projection_rule(0, formulation, 1.0, &mut rule).unwrap();
                let f0 = vec![Matrix3::new(1.05, 0.03, 0.0, -0.02, 0.97, 0.0, 0.0, 0.0, 1.02); 3];
                for law in laws {
                    let ctx = KernelContext { element: ElementType::Quad4, formulation, law, time_step: 0.0 };
                    let stride = law.state_len();
                    let mut committed = vec![0.0; 3 * stride];
                    committed.chunks_mut(stride.max(1)).for_each(|c| law.initialise_state(c));
                    for mixed in [false, true] {
                        let nd = if mixed { 27 } else { 18 };
                        let mut unknowns: Vec<f64> = (0..nd).map(|k| 0.004 * ((k * 7 + 3) as f64).sin()).collect();
                        if mixed {
                            for a in 0..9 {
                                unknowns[18 + a] = -2.0e3 + 500.0 * (a as f64).cos();
                            }
                        }
                        let residual = |v: &[f64], k: Option<&mut [f64]>| {
                            let disp: Vec<[f64; 3]> = (0..9).map(|a| [v[2 * a], v[2 * a + 1], 0.0]).collect();
                            let mut f = vec![0.0; nd];
                            let mut out = vec![PointOutput::default(); 3];
                            let mut trial = committed.clone();
                            if mixed {
                                mixed_element(
                                    &ctx,
                                    &disp,
                                    &v[18..],
                                    &geometry,
                                    &f0,
                                    &f0,
                                    &committed,
                                    &mut trial,
                                    &mut out,
                                    &mut f,
                                    k,
                                    Some(&rule[..]),
                                )
                                .unwrap();
                            } else {
                                solid_element(
                                    &ctx, &disp, &geometry, &f0, &f0, &committed, &mut trial, &mut out, &mut f, k,
                                )
                                .unwrap();
                            }
                            f
                        };
                        let mut k = vec![0.0; nd * nd];
                        residual(&unknowns, Some(&mut k));
                        if let Some(flag) = law.state_variables().iter().position(|v| *v == "yield_flag") {
                            let disp: Vec<[f64; 3]> =
                                (0..9).map(|a| [unknowns[2 * a], unknowns[2 * a + 1], 0.0]).collect();
                            let (mut f, mut out, mut trial) =
                                (vec![0.0; 18], vec![PointOutput::default(); 3], committed.clone());
                            solid_element(
                                &ctx, &disp, &geometry, &f0, &f0, &committed, &mut trial, &mut out, &mut f, None,
                            )
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
                            let h = if c < 18 { 1e-7 } else { 1e-2 };
                            let (mut p, mut m) = (unknowns.clone(), unknowns.clone());
                            p[c] += h;
                            m[c] -= h;
                            let (fp, fm) = (residual(&p, None), residual(&m, None));
                            for r in 0..nd {
                                err = err.max(((fp[r] - fm[r]) / (2.0 * h) - k[r * nd + c]).abs() / kmax);
                            }
                        }
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
}
