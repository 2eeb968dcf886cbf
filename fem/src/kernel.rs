//! The large-deformation solid element kernel, shared by every discretisation.
//!
//! The kernel does not know who owns its integration points: FEM passes Gauss points,
//! MPM passes material points. Each point carries its shape functions and gradients with
//! respect to the *step reference configuration* `X̃` (the mesh's reference configuration
//! for total-Lagrangian FEM; the configuration at the start of the step for MPM, whose grid
//! is reset), its weight (volume in that configuration), and the deformation gradient `F0`
//! of that configuration relative to the material's stress-free state (`I` for FEM, `F_n`
//! for MPM). With nodal displacements `u_a` measured from `X̃`,
//!
//! `ΔF = I + Σ_a u_a ⊗ ∇_X̃ N_a`,  `F = ΔF F0`,  `(P, A) = law(F)`,
//!
//! and the law's stress is pulled back to `X̃` (Bonet & Wood 2008, §4.8):
//!
//! `P̃_iJ = J0⁻¹ P_iK F0_JK`,  `Ã_iJkM = J0⁻¹ A_iKkL F0_JK F0_ML`,  `J0 = det F0`.
//!
//! Internal force and consistent tangent (material + geometric stiffness, both contained in
//! `Ã`):
//!
//! `f_ai = Σ_p w_p P̃_iJ ∂N_a/∂X̃_J`,  `K_ai,bk = Σ_p w_p ∂N_a/∂X̃_J Ã_iJkL ∂N_b/∂X̃_L`,
//!
//! with the hoop term `F33 = 1 + u_r/R` added for axisymmetry and `F33` condensed out by
//! `P̃33 = 0` for plane stress.

use loam_laws::{
    idx, ConstitutiveLaw, Kinematics, LawError, StressResponse, Tangent, TangentRequest, ALL_COMPONENTS, IN_PLANE,
    IN_PLANE_AND_ZZ,
};
use nalgebra::Matrix3;

use crate::element::{ElementType, MAX_ELEMENT_NODES, MAX_NODES};
use crate::formulation::Formulation;

/// Largest number of displacement DOFs of an element block (a smooth MPM basis's
/// 3 × 3 × 3-node support in 3D: 81).
pub const MAX_DOFS: usize = 3 * MAX_NODES;

/// Displacement DOFs of the largest block of the elements (hex8 × 3) and of a 2D smooth
/// support (18): the kernels' scratch for blocks up to this size is sized by it, so that
/// their stack arrays do not grow with the 3D supports' [`MAX_DOFS`].
pub const SMALL_BLOCK_DOFS: usize = 24;

/// Geometry of one integration point in the step reference configuration.
#[derive(Debug, Clone, Copy, Default)]
pub struct PointGeometry {
    /// Shape functions `N_a` at the point.
    pub shape: [f64; MAX_NODES],
    /// Gradients `∂N_a/∂X̃` at the point.
    pub gradient: [[f64; 3]; MAX_NODES],
    /// Integration weight: the point's volume in the step reference configuration
    /// (with thickness or 2πR included).
    pub weight: f64,
    /// Radius `R` of the point (axisymmetric only; 0 otherwise).
    pub radius: f64,
}

/// The integration points of one block as the kernels read them: a slice of
/// [`PointGeometry`] records (FEM elements), or points packed to the block's nodes
/// ([`PackedPoints`](crate::packed_geometry::PackedPoints), MPM bodies).
pub trait Geometries {
    /// Storage a point may be unpacked into ([`Geometries::point`]).
    type Scratch: Default;
    /// Number of points.
    fn count(&self) -> usize;
    /// Point `k`: a reference into the store, or `scratch` filled with it (weight, radius and
    /// the entries of the block's nodes) and returned.
    fn point<'a>(&'a self, k: usize, scratch: &'a mut Self::Scratch) -> &'a PointGeometry;
}

impl Geometries for [PointGeometry] {
    type Scratch = ();

    fn count(&self) -> usize {
        self.len()
    }

    fn point<'a>(&'a self, k: usize, _: &'a mut ()) -> &'a PointGeometry {
        &self[k]
    }
}

/// Failure inside an element kernel.
#[derive(Debug, Clone, thiserror::Error, PartialEq)]
pub enum KernelError {
    /// The law failed at an integration point (e.g. `det F ≤ 0`).
    #[error("integration point {point}: {source}")]
    Law {
        /// Point index within the element.
        point: usize,
        /// What the law reported.
        source: LawError,
    },
    /// The law has no volumetric–deviatoric form for the mixed u–p element.
    #[error("mixed u–p element: {0}")]
    NoMixedForm(String),
    /// The isoparametric map is singular or inverted (`det J ≤ 0`).
    #[error("inverted element geometry (det J = {det_j:.3e})")]
    InvertedElement {
        /// Jacobian determinant of the reference map.
        det_j: f64,
    },
}

/// The Jacobian `J = ∂x/∂ξ` of an element's isoparametric map at a point, inverted, with
/// its determinant (> 0). Constant over an affine cell (tri3, tet4), which lets an MPM grid
/// keep one per cell.
#[derive(Debug, Clone, Copy)]
pub struct CellMap {
    /// `J⁻¹ = ∂ξ/∂x`.
    pub jacobian_inverse: Matrix3<f64>,
    /// `det J`.
    pub det_j: f64,
}

impl CellMap {
    /// The map of an element with node coordinates `coords` at the point where its local
    /// shape gradients are `dn`; fails if `det J ≤ 0`.
    pub fn at(element: ElementType, coords: &[[f64; 3]], dn: &[[f64; 3]]) -> Result<Self, KernelError> {
        let jac = element.jacobian(coords, dn);
        let det_j = jac.determinant();
        if det_j <= 0.0 || !det_j.is_finite() {
            return Err(KernelError::InvertedElement { det_j });
        }
        let jacobian_inverse = jac.try_inverse().ok_or(KernelError::InvertedElement { det_j })?;
        Ok(Self { jacobian_inverse, det_j })
    }
}

/// Computes [`PointGeometry`] at local coordinates `xi` of an element whose nodes sit at
/// `coords` in the step reference configuration: `∂N_a/∂x = J⁻ᵀ ∂N_a/∂ξ`, weight
/// `gauss_weight · det J` times the formulation's thickness or `2πR` factor. `map` is the
/// Jacobian at `xi` when the caller knows it (an affine cell), else it is formed from `coords`.
pub fn point_geometry(
    element: ElementType,
    formulation: Formulation,
    thickness: f64,
    coords: &[[f64; 3]],
    xi: &[f64; 3],
    gauss_weight: f64,
    map: Option<&CellMap>,
) -> Result<PointGeometry, KernelError> {
    let mut g = PointGeometry { shape: [0.0; MAX_NODES], gradient: [[0.0; 3]; MAX_NODES], weight: 0.0, radius: 0.0 };
    point_geometry_into(&mut g, element, formulation, thickness, coords, xi, gauss_weight, map)?;
    Ok(g)
}

/// [`point_geometry`] written into `g`, of which only the entries of the element's nodes are
/// set (`shape[..nn]`, `gradient[..nn]`, weight and radius; the rest keeps what it held): for
/// storage reused per call, without building and copying a whole [`PointGeometry`] (sized
/// for the largest block, 27 nodes).
#[allow(clippy::too_many_arguments)]
pub fn point_geometry_into(
    g: &mut PointGeometry,
    element: ElementType,
    formulation: Formulation,
    thickness: f64,
    coords: &[[f64; 3]],
    xi: &[f64; 3],
    gauss_weight: f64,
    map: Option<&CellMap>,
) -> Result<(), KernelError> {
    let nn = element.num_nodes();
    let dim = element.dim();
    let mut dn = [[0.0; 3]; MAX_ELEMENT_NODES];
    element.shape_functions(xi, &mut g.shape);
    element.shape_gradients(xi, &mut dn);
    g.gradient[..nn].fill([0.0; 3]);
    g.radius = 0.0;
    let formed;
    let map = match map {
        Some(map) => map,
        None => {
            formed = CellMap::at(element, coords, &dn)?;
            &formed
        }
    };
    let jinv = &map.jacobian_inverse;
    for a in 0..nn {
        for d in 0..dim {
            g.gradient[a][d] = (0..dim).map(|e| jinv[(e, d)] * dn[a][e]).sum();
        }
    }
    if formulation == Formulation::Axisymmetric {
        g.radius = (0..nn).map(|a| g.shape[a] * coords[a][0]).sum();
    }
    g.weight = gauss_weight * map.det_j * formulation.measure_factor(thickness, g.radius);
    Ok(())
}

/// Inputs shared by all points of one kernel call.
#[derive(Clone, Copy)]
pub struct KernelContext<'a> {
    /// Element shape.
    pub element: ElementType,
    /// Kinematic formulation.
    pub formulation: Formulation,
    /// The law of this element's material.
    pub law: &'a dyn ConstitutiveLaw,
    /// Time step Δt (0 for static steps), handed to rate-type laws.
    pub time_step: f64,
}

/// Per-point state handed to [`evaluate_point`].
pub struct PointState<'a> {
    /// Deformation gradient of the step reference configuration (`I` for FEM, `F_n` for MPM).
    pub f0: &'a Matrix3<f64>,
    /// Committed deformation gradient at the start of the step.
    pub f_prev: &'a Matrix3<f64>,
    /// Committed history.
    pub committed: &'a [f64],
    /// Trial history (written).
    pub trial: &'a mut [f64],
}

/// Flattened components of `F` that vary with the nodal unknowns, per formulation.
const ACTIVE_2D: [usize; 5] = IN_PLANE_AND_ZZ;
const ACTIVE_3D: [usize; 9] = ALL_COMPONENTS;

/// Flattened components of `F` that vary with the nodal unknowns: 4 in plane strain and
/// plane stress, 5 in axisymmetry (with `F33`), 9 in 3D.
pub fn active_components(formulation: Formulation) -> &'static [usize] {
    match formulation {
        Formulation::PlaneStrain | Formulation::PlaneStress => &IN_PLANE,
        Formulation::Axisymmetric => &ACTIVE_2D,
        Formulation::ThreeD => &ACTIVE_3D,
    }
}

/// The tangent's pull-back `Ã_iJkM = J0⁻¹ A_iKkL F0_JK F0_ML` (see the module doc), in place,
/// over its rows and columns `components` (`F0` is block diagonal with respect
/// to them, so the sums over `K` and `L` stay inside them too; entries outside them are
/// neither read nor written).
#[inline(always)]
fn pull_back(f0: &Matrix3<f64>, inv_j0: f64, a: &mut Tangent, components: &[usize]) {
    // `line` holds one row (then one column) of the tangent over `components`, zero elsewhere
    let mut line = [0.0; 9];
    // right-multiply the second index pair, row by row: A_iJkM ← Σ_L A_iJkL F0_ML
    for &row in components {
        for &c in components {
            line[c] = a[(row, c)];
        }
        for &col in components {
            let (k, m) = (col / 3, col % 3);
            a[(row, col)] = (0..3).map(|l| line[idx(k, l)] * f0[(m, l)]).sum();
        }
    }
    // then the first, column by column: Ã_iJkM = J0⁻¹ Σ_K A_iKkM F0_JK
    for &col in components {
        for &r in components {
            line[r] = a[(r, col)];
        }
        for &row in components {
            let (i, j) = (row / 3, row % 3);
            a[(row, col)] = inv_j0 * (0..3).map(|kk| line[idx(i, kk)] * f0[(j, kk)]).sum::<f64>();
        }
    }
}

/// The stress' pull-back `P̃ = J0⁻¹ P F0ᵀ` and the tangent's ([`pull_back`]) over `components`
/// (none for a residual).
pub(crate) fn pull_back_response(f0: &Matrix3<f64>, p: &mut Matrix3<f64>, a: &mut Tangent, components: &[usize]) {
    if *f0 == Matrix3::identity() {
        return;
    }
    let inv_j0 = 1.0 / f0.determinant();
    *p = *p * f0.transpose() * inv_j0;
    if !components.is_empty() {
        loam_laws::with_components!(components, |c| pull_back(f0, inv_j0, a, c));
    }
}

/// `ΔF = I + Σ_a u_a ⊗ ∂N_a/∂X̃` at one point for nodal displacements `disp` (from the step
/// reference configuration), with the hoop stretch `ΔF33 = 1 + u_r/R` in axisymmetry.
pub fn delta_deformation_gradient(
    ctx: &KernelContext<'_>,
    geometry: &PointGeometry,
    disp: &[[f64; 3]],
) -> Matrix3<f64> {
    let nn = disp.len();
    let dim = ctx.element.dim();
    let mut delta_f = Matrix3::<f64>::identity();
    for a in 0..nn {
        for i in 0..dim {
            for j in 0..dim {
                delta_f[(i, j)] += disp[a][i] * geometry.gradient[a][j];
            }
        }
    }
    if ctx.formulation == Formulation::Axisymmetric {
        let ur: f64 = (0..nn).map(|a| geometry.shape[a] * disp[a][0]).sum();
        delta_f[(2, 2)] = 1.0 + ur / geometry.radius;
    }
    delta_f
}

/// Evaluates the law at one point for nodal displacements `disp` (from the step reference
/// configuration). Returns `F`, the Cauchy stress and the pulled-back stress `P̃`, and leaves
/// in `response.tangent`, if `with_tangent`, the pulled-back tangent `Ã` over the
/// [`active_components`] (the only entries that enter the element: the in-plane ones in 2D,
/// with the hoop component for axisymmetry; for plane stress with `F33` condensed out,
/// `Ã_cd − Ã_c,33 Ã_33,d / Ã_33,33`, as its `P̃33 = 0` iteration always forms them). Without
/// it the law is asked for the stress alone. `response` is scratch storage the caller keeps
/// for all its points (see [`ConstitutiveLaw::update`]).
pub fn evaluate_point(
    ctx: &KernelContext<'_>,
    geometry: &PointGeometry,
    disp: &[[f64; 3]],
    state: PointState<'_>,
    with_tangent: bool,
    response: &mut StressResponse,
) -> Result<PointOutput, LawError> {
    let mut delta_f = delta_deformation_gradient(ctx, geometry, disp);
    let mut kin = Kinematics {
        deformation_gradient: delta_f * state.f0,
        previous_deformation_gradient: *state.f_prev,
        time_step: ctx.time_step,
        tangent: match ctx.formulation {
            Formulation::PlaneStress => TangentRequest::Components(&ACTIVE_2D),
            _ if with_tangent => TangentRequest::Components(active_components(ctx.formulation)),
            _ => TangentRequest::None,
        },
    };
    let components = kin.tangent.components();
    if ctx.formulation == Formulation::PlaneStress {
        // local Newton on ΔF33 such that P̃33 = 0
        let active = active_components(ctx.formulation);
        delta_f[(2, 2)] = state.f_prev[(2, 2)] / state.f0[(2, 2)];
        let c33 = idx(2, 2);
        for it in 0..30 {
            kin.deformation_gradient = delta_f * state.f0;
            ctx.law.update(&kin, state.committed, state.trial, response)?;
            let mut p = response.first_piola;
            let a = &mut response.tangent;
            pull_back_response(state.f0, &mut p, a, components);
            let scale = p.amax().max(1e-300);
            if p[(2, 2)].abs() <= 1e-12 * scale || it == 29 {
                if p[(2, 2)].abs() > 1e-8 * scale {
                    return Err(LawError::ReturnMappingFailed { iterations: it, residual: p[(2, 2)] });
                }
                // condensation in place: reads only the 33 row and column, writes the others
                for &ic in active {
                    for &id in active {
                        a[(ic, id)] -= a[(ic, c33)] * a[(c33, id)] / a[(c33, c33)];
                    }
                }
                let cauchy = cauchy_stress(&response.first_piola, &kin.deformation_gradient);
                return Ok(PointOutput { deformation_gradient: kin.deformation_gradient, stress: p, cauchy });
            }
            delta_f[(2, 2)] -= p[(2, 2)] / a[(c33, c33)];
            if delta_f[(2, 2)] <= 0.0 {
                return Err(LawError::InvertedDeformation { det_f: delta_f[(2, 2)] });
            }
        }
        unreachable!("plane-stress loop returns by its last iteration");
    }
    ctx.law.update(&kin, state.committed, state.trial, response)?;
    let mut p = response.first_piola;
    pull_back_response(state.f0, &mut p, &mut response.tangent, components);
    let cauchy = cauchy_stress(&response.first_piola, &kin.deformation_gradient);
    Ok(PointOutput { deformation_gradient: kin.deformation_gradient, stress: p, cauchy })
}

/// Cauchy stress `σ = P Fᵀ / det F`.
pub fn cauchy_stress(first_piola: &Matrix3<f64>, f: &Matrix3<f64>) -> Matrix3<f64> {
    first_piola * f.transpose() / f.determinant()
}

/// What the kernel reports per integration point for output and energy bookkeeping.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct PointOutput {
    /// Total deformation gradient `F`.
    pub deformation_gradient: Matrix3<f64>,
    /// Cauchy stress `σ`.
    pub cauchy: Matrix3<f64>,
    /// Pulled-back first Piola–Kirchhoff stress `P̃` (work conjugate to `ΔF`).
    pub stress: Matrix3<f64>,
}

impl Default for PointOutput {
    fn default() -> Self {
        Self { deformation_gradient: Matrix3::identity(), cauchy: Matrix3::zeros(), stress: Matrix3::zeros() }
    }
}

/// Rows of the discrete gradient operator at one point of a block of `nn` nodes in `dim`
/// dimensions: `b[(a, i)][c]` is `∂F̃_{ACTIVE[c]}/∂u_ai`. Returns the number of active
/// components.
pub(crate) fn gradient_operator(
    formulation: Formulation,
    nn: usize,
    dim: usize,
    geometry: &PointGeometry,
    b: &mut [[f64; 9]],
) -> usize {
    let active = active_components(formulation);
    for a in 0..nn {
        for i in 0..dim {
            let row = &mut b[a * dim + i];
            for (c, &comp) in active.iter().enumerate() {
                let (ci, cj) = (comp / 3, comp % 3);
                row[c] = if comp == idx(2, 2) && dim == 2 {
                    if i == 0 {
                        geometry.shape[a] / geometry.radius
                    } else {
                        0.0
                    }
                } else if ci == i {
                    geometry.gradient[a][cj]
                } else {
                    0.0
                };
            }
        }
    }
    active.len()
}

/// Internal force and tangent of one element whose active components of `F` are the
/// `D × D` block (plane strain, plane stress, 3D) and which has `NN` nodes. There
/// `B_(ai),(kL) = δ_ik ∂N_a/∂X̃_L`, so per point
///
/// `f_ai += w P̃_iJ ∂N_a/∂X̃_J`,  `K_ai,bk += Σ_L (w Σ_J ∂N_a/∂X̃_J Ã_iJkL) ∂N_b/∂X̃_L`:
///
/// the same products, summed in the same order, as `w Bᵀ P̃` and `w Bᵀ Ã B` in
/// [`element_general`] with the zeros of `B` skipped (2× fewer operations in 2D, 3× in 3D),
/// with sizes known at compile time and `K` accumulated on the stack
/// (`k[a][i][b][k]` is the row-major layout of the output).
fn element_tensor<const D: usize, const NN: usize, G: Geometries + ?Sized>(
    ctx: &KernelContext<'_>,
    disp: &[[f64; 3]],
    geometry: &G,
    f0: &[Matrix3<f64>],
    f_prev: &[Matrix3<f64>],
    committed: &[f64],
    trial: &mut [f64],
    point_out: &mut [PointOutput],
    f_int: &mut [f64],
    stiffness: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let stride = ctx.law.state_len();
    let mut f = [[0.0; D]; NN];
    let mut k = [[[[0.0; D]; NN]; D]; NN];
    let mut response = StressResponse::default();
    let mut scratch = G::Scratch::default();
    for p in 0..geometry.count() {
        let g = geometry.point(p, &mut scratch);
        let state = PointState {
            f0: &f0[p],
            f_prev: &f_prev[p],
            committed: &committed[p * stride..(p + 1) * stride],
            trial: &mut trial[p * stride..(p + 1) * stride],
        };
        let out = evaluate_point(ctx, g, disp, state, stiffness.is_some(), &mut response)
            .map_err(|source| KernelError::Law { point: p, source })?;
        point_out[p] = out;
        let w = g.weight;
        for a in 0..NN {
            let ga = &g.gradient[a];
            for i in 0..D {
                let mut v = 0.0;
                for j in 0..D {
                    v += out.stress[(i, j)] * ga[j];
                }
                f[a][i] += w * v;
            }
        }
        if stiffness.is_none() {
            continue;
        }
        // bt[a][i][k][l] = w Σ_J ∂N_a/∂X̃_J Ã_iJkL (the rows of w Bᵀ Ã)
        let mut bt = [[[[0.0; D]; D]; D]; NN];
        for a in 0..NN {
            let ga = &g.gradient[a];
            for i in 0..D {
                for kk in 0..D {
                    for l in 0..D {
                        let mut v = 0.0;
                        for j in 0..D {
                            v += ga[j] * response.tangent[(idx(i, j), idx(kk, l))];
                        }
                        bt[a][i][kk][l] = w * v;
                    }
                }
            }
        }
        for a in 0..NN {
            for i in 0..D {
                for b in 0..NN {
                    let gb = &g.gradient[b];
                    for kk in 0..D {
                        let mut v = 0.0;
                        for l in 0..D {
                            v += bt[a][i][kk][l] * gb[l];
                        }
                        k[a][i][b][kk] += v;
                    }
                }
            }
        }
    }
    for (dst, src) in f_int.chunks_exact_mut(D).zip(&f) {
        dst.copy_from_slice(src);
    }
    if let Some(out) = stiffness {
        for (dst, src) in out.chunks_exact_mut(D).zip(k.iter().flatten().flatten()) {
            dst.copy_from_slice(src);
        }
    }
    Ok(())
}

/// Internal force vector `f_int` (length `nn·dim`) and, if asked, the consistent tangent
/// `stiffness` (row-major, `(nn·dim)²`) of one element over its integration points. The
/// block has `nn = disp.len()` nodes: those of `ctx.element`, or the support of a smooth MPM
/// basis (9 in 2D, 27 in 3D), whose functions `geometry` carries.
///
/// `f0`, `f_prev`, `geometry`, `point_out` hold one entry per point; `committed` and `trial` hold the
/// points' histories back to back with stride `law.state_len()`. Outputs are overwritten.
pub fn solid_element<G: Geometries + ?Sized>(
    ctx: &KernelContext<'_>,
    disp: &[[f64; 3]],
    geometry: &G,
    f0: &[Matrix3<f64>],
    f_prev: &[Matrix3<f64>],
    committed: &[f64],
    trial: &mut [f64],
    point_out: &mut [PointOutput],
    f_int: &mut [f64],
    stiffness: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    use Formulation::*;
    let run = match (ctx.formulation, ctx.element.dim(), disp.len()) {
        (PlaneStrain | PlaneStress, 2, 4) => element_tensor::<2, 4, G>,
        (PlaneStrain | PlaneStress, 2, 3) => element_tensor::<2, 3, G>,
        (PlaneStrain | PlaneStress, 2, 9) => element_tensor::<2, 9, G>,
        (ThreeD, 3, 4) => element_tensor::<3, 4, G>,
        (ThreeD, 3, 8) => element_tensor::<3, 8, G>,
        (ThreeD, 3, 27) => element_tensor::<3, 27, G>,
        (_, dim, nn) if nn * dim <= SMALL_BLOCK_DOFS => element_general::<SMALL_BLOCK_DOFS, G>,
        _ => element_general::<MAX_DOFS, G>,
    };
    run(ctx, disp, geometry, f0, f_prev, committed, trial, point_out, f_int, stiffness)
}

/// [`solid_element`] through the general operator `B` of [`gradient_operator`]:
/// `f = Σ_p w Bᵀ P̃`, `K = Σ_p w Bᵀ Ã B` (axisymmetry, where the hoop row `N_a / R` breaks the
/// tensor structure that [`element_tensor`] uses).
fn element_general<const CAPACITY: usize, G: Geometries + ?Sized>(
    ctx: &KernelContext<'_>,
    disp: &[[f64; 3]],
    geometry: &G,
    f0: &[Matrix3<f64>],
    f_prev: &[Matrix3<f64>],
    committed: &[f64],
    trial: &mut [f64],
    point_out: &mut [PointOutput],
    f_int: &mut [f64],
    mut stiffness: Option<&mut [f64]>,
) -> Result<(), KernelError> {
    let (nn, dim) = (disp.len(), ctx.element.dim());
    let ndof = nn * dim;
    let stride = ctx.law.state_len();
    f_int[..ndof].fill(0.0);
    if let Some(k) = stiffness.as_deref_mut() {
        k[..ndof * ndof].fill(0.0);
    }
    let mut b = [[0.0; 9]; CAPACITY];
    let mut bt_a = [[0.0; 9]; CAPACITY];
    let active = active_components(ctx.formulation);
    let mut response = StressResponse::default();
    let mut scratch = G::Scratch::default();
    for p in 0..geometry.count() {
        let g = geometry.point(p, &mut scratch);
        let state = PointState {
            f0: &f0[p],
            f_prev: &f_prev[p],
            committed: &committed[p * stride..(p + 1) * stride],
            trial: &mut trial[p * stride..(p + 1) * stride],
        };
        let out = evaluate_point(ctx, g, disp, state, stiffness.is_some(), &mut response)
            .map_err(|source| KernelError::Law { point: p, source })?;
        point_out[p] = out;
        let nc = gradient_operator(ctx.formulation, nn, dim, g, &mut b);
        let w = g.weight;
        for r_ in 0..ndof {
            let mut v = 0.0;
            for c in 0..nc {
                v += out.stress[(active[c] / 3, active[c] % 3)] * b[r_][c];
            }
            f_int[r_] += w * v;
        }
        if let Some(k) = stiffness.as_deref_mut() {
            for r_ in 0..ndof {
                for d in 0..nc {
                    let mut v = 0.0;
                    for c in 0..nc {
                        v += b[r_][c] * response.tangent[(active[c], active[d])];
                    }
                    bt_a[r_][d] = w * v;
                }
            }
            for r_ in 0..ndof {
                let row = &mut k[r_ * ndof..(r_ + 1) * ndof];
                for s in 0..ndof {
                    let mut v = 0.0;
                    for d in 0..nc {
                        v += bt_a[r_][d] * b[s][d];
                    }
                    row[s] += v;
                }
            }
        }
    }
    Ok(())
}

/// Fixtures of the element-kernel tests (displacement and u–p).
#[cfg(test)]
pub(crate) mod test_fixtures {
    use super::*;

    /// Node coordinates of one distorted element of each type.
    pub fn element_coords(element: ElementType) -> Vec<[f64; 3]> {
        match element {
            ElementType::Tri3 => vec![[0.1, 0.2, 0.0], [1.3, 0.1, 0.0], [0.5, 1.1, 0.0]],
            ElementType::Quad4 => vec![[0.2, 0.1, 0.0], [1.4, 0.0, 0.0], [1.5, 1.2, 0.0], [0.1, 0.9, 0.0]],
            ElementType::Tet4 => vec![[0.0, 0.0, 0.0], [1.1, 0.1, 0.0], [0.1, 0.9, 0.1], [0.2, 0.1, 1.2]],
            ElementType::Hex8 => {
                let mut c = Vec::new();
                for z in [0.0, 1.0] {
                    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                        c.push([x + 0.1 * y * z, y + 0.05 * x, z + 0.1 * x * y]);
                    }
                }
                c
            }
        }
    }

    /// A deformation `F0 ≠ I` of the step reference configuration (the MPM pull-back),
    /// with the hoop stretch in axisymmetry and out-of-plane terms in 3D.
    pub fn pre_deformation(dim: usize, formulation: Formulation) -> Matrix3<f64> {
        let mut f0 = Matrix3::new(1.05, 0.03, 0.0, -0.02, 0.97, 0.0, 0.0, 0.0, 1.0);
        if dim == 3 {
            f0[(0, 2)] = 0.02;
            f0[(2, 1)] = -0.01;
            f0[(2, 2)] = 1.03;
        } else if formulation == Formulation::Axisymmetric {
            f0[(2, 2)] = 1.02;
        }
        f0
    }

    /// The initial history of `law` at `points` points.
    pub fn initial_states(law: &dyn ConstitutiveLaw, points: usize) -> Vec<f64> {
        let stride = law.state_len();
        let mut committed = vec![0.0; points * stride];
        for p in 0..points {
            law.initialise_state(&mut committed[p * stride..(p + 1) * stride]);
        }
        committed
    }
}

#[cfg(test)]
mod tests {
    use super::test_fixtures::{element_coords, initial_states, pre_deformation};
    use super::*;
    use loam_laws::mohr_coulomb::MohrCoulomb;
    use loam_laws::neo_hookean::NeoHookean;

    /// Element tangent vs central differences of the internal force, for every element and
    /// formulation, with `F0 ≠ I` (the MPM pull-back) and plane-stress condensation.
    #[test]
    fn element_tangent_matches_finite_differences_of_internal_force() {
        // hyperelastic, and elasto-plastic in the multiplicative frame (the deformation below
        // takes this weak Mohr–Coulomb material onto its yield surface): both reach the
        // kernel through the restricted tangent request, with F0 ≠ I as in MPM
        let neo_hookean = NeoHookean::new(1000.0, 1.0e6, 0.3);
        let mohr_coulomb = MohrCoulomb::new(1000.0, 1.0e6, 0.3, 0.5, 2.0e3, 0.1);
        let laws: [&dyn ConstitutiveLaw; 2] = [&neo_hookean, &mohr_coulomb];
        for law in laws {
            element_tangent_check(law);
        }
    }

    fn element_tangent_check(law: &dyn ConstitutiveLaw) {
        let cases = [
            (ElementType::Tri3, Formulation::PlaneStrain),
            (ElementType::Quad4, Formulation::PlaneStrain),
            (ElementType::Quad4, Formulation::PlaneStress),
            (ElementType::Tri3, Formulation::Axisymmetric),
            (ElementType::Quad4, Formulation::Axisymmetric),
            (ElementType::Tet4, Formulation::ThreeD),
            (ElementType::Hex8, Formulation::ThreeD),
        ];
        for (element, formulation) in cases {
            let coords = element_coords(element);
            let nn = element.num_nodes();
            let dim = element.dim();
            let nd = nn * dim;
            let geometry: Vec<PointGeometry> = element
                .gauss_points()
                .iter()
                .map(|g| point_geometry(element, formulation, 1.0, &coords, &g.xi, g.weight, None).unwrap())
                .collect();
            let np = geometry.len();
            let f0s = vec![pre_deformation(dim, formulation); np];
            let ctx = KernelContext { element, formulation, law, time_step: 0.0 };
            let stride = law.state_len();
            let committed = initial_states(law, np);
            let mut disp = vec![[0.0; 3]; nn];
            for a in 0..nn {
                for i in 0..dim {
                    disp[a][i] = 0.03 * ((a * 3 + i) as f64).sin();
                }
            }
            let internal = |d: &[[f64; 3]], k: Option<&mut [f64]>| {
                let mut f = vec![0.0; nd];
                let mut out = vec![PointOutput::default(); np];
                let mut trial = committed.clone();
                solid_element(&ctx, d, &geometry[..], &f0s, &f0s, &committed, &mut trial, &mut out, &mut f, k).unwrap();
                f
            };
            let mut k = vec![0.0; nd * nd];
            internal(&disp, Some(&mut k));
            if let Some(flag) = law.state_variables().iter().position(|v| *v == "yield_flag") {
                let mut trial = committed.clone();
                let (mut f, mut out) = (vec![0.0; nd], vec![PointOutput::default(); np]);
                solid_element(&ctx, &disp, &geometry[..], &f0s, &f0s, &committed, &mut trial, &mut out, &mut f, None)
                    .unwrap();
                let mut values = vec![0.0; law.state_variables().len()];
                let plastic = trial.chunks(stride).filter(|st| {
                    law.state_output(st, &mut values);
                    values[flag] > 0.0
                });
                assert!(plastic.count() > 0, "{element:?} {formulation:?}: the check must reach the yield surface");
            }
            let h = 1e-6;
            let mut err = 0.0f64;
            let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for s in 0..nd {
                let (mut dp, mut dm) = (disp.clone(), disp.clone());
                dp[s / dim][s % dim] += h;
                dm[s / dim][s % dim] -= h;
                let (fp, fm) = (internal(&dp, None), internal(&dm, None));
                for r in 0..nd {
                    err = err.max(((fp[r] - fm[r]) / (2.0 * h) - k[r * nd + s]).abs() / kmax);
                }
            }
            println!(
                "{} {element:?} {formulation:?}: element tangent vs central FD, relative error {err:.2e} (tolerance 1e-6)",
                law.name()
            );
            assert!(err < 1e-6, "{element:?} {formulation:?}: {err}");
        }
    }

    /// The tensor-structured kernel (`element_tensor`) reproduces the general `Bᵀ Ã B`
    /// kernel exactly (same products, same order; only multiplications by zero skipped).
    #[test]
    fn tensor_kernel_equals_general_kernel_bit_for_bit() {
        let law = NeoHookean::new(1000.0, 1.0e6, 0.3);
        let cases = [
            (ElementType::Tri3, Formulation::PlaneStrain),
            (ElementType::Quad4, Formulation::PlaneStrain),
            (ElementType::Quad4, Formulation::PlaneStress),
            (ElementType::Tet4, Formulation::ThreeD),
            (ElementType::Hex8, Formulation::ThreeD),
        ];
        for (element, formulation) in cases {
            let coords = element_coords(element);
            let (nn, dim) = (element.num_nodes(), element.dim());
            let nd = nn * dim;
            let geometry: Vec<PointGeometry> = element
                .gauss_points()
                .iter()
                .map(|g| point_geometry(element, formulation, 1.0, &coords, &g.xi, g.weight, None).unwrap())
                .collect();
            let np = geometry.len();
            let f0s = vec![Matrix3::new(1.05, 0.03, 0.0, -0.02, 0.97, 0.0, 0.0, 0.0, 1.0); np];
            let ctx = KernelContext { element, formulation, law: &law, time_step: 0.0 };
            let disp: Vec<[f64; 3]> =
                (0..nn).map(|a| [0.03 * (a as f64).sin(), -0.02 * (a as f64).cos(), 0.01 * a as f64]).collect();
            let mut out = vec![PointOutput::default(); np];
            let (mut f1, mut k1) = (vec![0.0; nd], vec![0.0; nd * nd]);
            let (mut f2, mut k2) = (vec![0.0; nd], vec![0.0; nd * nd]);
            solid_element(&ctx, &disp, &geometry[..], &f0s, &f0s, &[], &mut [], &mut out, &mut f1, Some(&mut k1))
                .unwrap();
            element_general::<MAX_DOFS, [PointGeometry]>(
                &ctx,
                &disp,
                &geometry[..],
                &f0s,
                &f0s,
                &[],
                &mut [],
                &mut out,
                &mut f2,
                Some(&mut k2),
            )
            .unwrap();
            assert_eq!(f1, f2, "{element:?} {formulation:?}: internal force");
            assert_eq!(k1, k2, "{element:?} {formulation:?}: tangent");
        }
    }
}
