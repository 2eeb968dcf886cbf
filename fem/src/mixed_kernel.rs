//! The mixed displacement–pressure (u–p) element kernel for nearly and exactly
//! incompressible materials, shared by FEM (Gauss points) and MPM (material points) through
//! the same seam as [`crate::kernel::solid_element`].
//!
//! **Unknowns.** Equal-order nodal displacements `u_a` (from the step reference
//! configuration `X̃`, as in [`crate::kernel`]) and nodal pressures `p_a` (total values of
//! the mean Kirchhoff stress, [`loam_laws::mixed`]): P1–P1 on tri3 and tet4, Q1–Q1 on quad4
//! and hex8, in plane strain, axisymmetry and 3D. An element block lists the displacement
//! DOFs node by node, then the `nn` pressure DOFs.
//!
//! **Point kinematics and stress.** At each integration point (weight `w` = its volume in
//! `X̃`, `F0` the deformation of `X̃`, `J0 = det F0`, `w0 = w/J0` its volume in the
//! stress-free configuration):
//!
//! `ΔF = I + Σ_a u_a ⊗ ∇_X̃ N_a`, `F = ΔF F0`, `J = det F`, `p = Σ_a N_a p_a`,
//! `(P, A, ∂P/∂p) = law(F, p)` (u–p form), pulled back to `X̃` as in [`crate::kernel`]:
//! `P̃ = J0⁻¹ P F0ᵀ`, `Ã`, `B̃ = J0⁻¹ (∂P/∂p) F0ᵀ`.
//!
//! **Weak form.** Stationarity of the saddle-point functional
//!
//! `Π(u, p) = ∫_Ω0 [W_dev(F) + p ln J − p²/(2K)] dV0 − 1/(2μ) ∫_Ω0 (p − Π₀p)² dV0 − W_ext`,
//!
//! whose first two terms give `τ = τ_dev + p 1` and the volumetric law `p = K ln J` weakly,
//! and whose last term is the **polynomial pressure projection** stabilisation of Dohrmann &
//! Bochev (2004), "A stabilized finite element method for the Stokes problem based on
//! polynomial pressure projections", Int. J. Numer. Meth. Fluids 46:183–201,
//! doi:10.1002/fld.752 (the seed's choice, and Kratos' u–p MPM element after Iaconeta,
//! Larese, Rossi & Oñate 2019, doi:10.1007/s00466-018-1647-9): `Π₀` is the L2 projection onto
//! constants per element (per grid cell and body in MPM), `Π₀p = Σ_b m_b p_b / V`,
//! `m_b = ∫ N_b dV0`, `V = ∫ dV0`. It penalises the part of the equal-order pressure that
//! the piecewise-constant space — inf–sup stable with these displacements in the sense of
//! Dohrmann & Bochev — cannot represent, with the weight `1/μ` (elasticity in place of the
//! viscosity of Stokes flow; White & Borja 2008, doi:10.1016/j.cma.2008.06.008). It needs
//! no tuning parameter and vanishes for element-wise constant pressures (patch test).
//! Residuals:
//!
//! `r_u,ai = Σ_p w P̃_iJ ∂N_a/∂X̃_J` (as the displacement element),
//!
//! `r_p,a = Σ_p w0 N_a (θ − p/K) − (1/μ) Σ_p w0 N_a (p − Π₀p)`, `θ = ln J_e`
//! (`ln J` unless the history carries an elastic prestrain or a committed plastic dilation,
//! [`loam_laws::mixed::MixedLaw::volumetric_strain`]; the apex of a frictional law is a
//! return at the end of the step, not a cap here: [`loam_laws::mixed::elastic_strain_up`]),
//!
//! and the consistent tangent (symmetric for the hyperelastic laws and the
//! pressure-independent plasticity, where `B̃ = J0⁻¹ ΔF⁻ᵀ`):
//!
//! `K_uu = Σ_p w ∇N_a · Ã · ∇N_b`, `K_up,(ai)b = Σ_p w B̃_iJ ∂N_a/∂X̃_J N_b`,
//! `K_pu,a(bk) = Σ_p w0 N_a ΔF⁻ᵀ_kL ∂N_b/∂X̃_L` (`∂ ln J/∂ΔF = ΔF⁻ᵀ`),
//! `K_pp = −Σ_p w0 N_a N_b / K − (1/μ) (M − m mᵀ / V)`, `M_ab = Σ_p w0 N_a N_b`.
//!
//! With `K = ∞` (incompressible) `ln J = 0` holds weakly and `K_pp` is the stabilisation
//! alone. FEM integrates everything on a rule exact for `N_a N_b` (3 points on tri3, 4 on
//! tet4, 2×2(×2) on quads and hexes). An MPM cell integrates the momentum, the volumetric law
//! and `K_up`, `K_pu` on its material points, but its projection term (`M`, `m`, `V`) on the
//! cell's own Gauss rule scaled by the cell's fill fraction `φ = Σ_p w0_p / V_cell`: with its
//! points alone a cell holding one or two points would have `M − m mᵀ/V ≈ 0` and leave its
//! pressures unstabilised (observed: Newton stalling on the footing, whose surface cells
//! empty as the soil flows), while the fill-weighted cell rule keeps the projection's
//! kernel the element-wise constants whatever the points.
//! Components of `F` follow [`crate::kernel::active_components`] through the general gradient
//! operator (axisymmetry adds the hoop row `N_a/R`); plane stress has no incompressibility
//! constraint and no u–p form.

use loam_laws::mixed::MixedLaw;
use loam_laws::{idx, StressResponse, TangentRequest};
use nalgebra::Matrix3;

use crate::element::MAX_NODES;
use crate::formulation::Formulation;
use crate::kernel::{
    active_components, cauchy_stress, delta_deformation_gradient, gradient_operator, pull_back_response, Geometries,
    KernelContext, KernelError, PointGeometry, PointOutput, MAX_DOFS, SMALL_BLOCK_DOFS,
};

/// Largest u–p element block (a 3D smooth MPM support: 27 × (3 + 1) DOFs).
pub const MAX_MIXED_DOFS: usize = MAX_DOFS + MAX_NODES;

/// Number of DOFs of a u–p block of `ctx.element` (`nn · (dim + 1)`).
pub fn mixed_block_len(ctx: &KernelContext<'_>) -> usize {
    ctx.element.num_nodes() * (ctx.element.dim() + 1)
}

/// The u–p law of `ctx.law`, or why it has none.
fn mixed_law<'a>(ctx: &KernelContext<'a>) -> Result<&'a dyn MixedLaw, KernelError> {
    if ctx.formulation == Formulation::PlaneStress {
        return Err(KernelError::NoMixedForm("plane stress has no incompressibility constraint".into()));
    }
    ctx.law.mixed().map_err(KernelError::NoMixedForm)
}

/// Residual `[r_u; r_p]` (length `nn·(dim+1)`, see the module doc) and, if asked, the
/// consistent tangent (row-major) of one u–p element over its integration points, for nodal
/// displacements `disp` and nodal pressures `pressure`.
///
/// Arguments as [`crate::kernel::solid_element`] (`nn = disp.len()` nodes); outputs are
/// overwritten.
/// `projection`: the integrals of the basis over the cell's own region ([`CellProjection`])
/// with which an MPM cell integrates the pressure projection, scaled by its fill fraction;
/// `None` integrates it on the integration points (FEM).
pub fn mixed_element<G: Geometries + ?Sized>(
    ctx: &KernelContext<'_>,
    disp: &[[f64; 3]],
    pressure: &[f64],
    geometry: &G,
    f0: &[Matrix3<f64>],
    f_prev: &[Matrix3<f64>],
    committed: &[f64],
    trial: &mut [f64],
    point_out: &mut [PointOutput],
    residual: &mut [f64],
    stiffness: Option<&mut [f64]>,
    projection: Option<&CellProjection>,
) -> Result<(), KernelError> {
    // scratch sized by the block: the elements and 2D supports, or a 3D smooth support; the
    // grids' node counts compiled with `nn` a constant (their loops over the nodes unrolled)
    const SMALL: usize = SMALL_BLOCK_DOFS;
    let run = match (disp.len(), disp.len() * ctx.element.dim() <= SMALL) {
        (3, true) => mixed_element_in::<SMALL, { SMALL / 2 }, 3, G>,
        (4, true) => mixed_element_in::<SMALL, { SMALL / 2 }, 4, G>,
        (8, true) => mixed_element_in::<SMALL, { SMALL / 2 }, 8, G>,
        (9, true) => mixed_element_in::<SMALL, { SMALL / 2 }, 9, G>,
        (_, true) => mixed_element_in::<SMALL, { SMALL / 2 }, 0, G>,
        (27, false) => mixed_element_in::<MAX_DOFS, MAX_NODES, 27, G>,
        (_, false) => mixed_element_in::<MAX_DOFS, MAX_NODES, 0, G>,
    };
    run(ctx, disp, pressure, geometry, f0, f_prev, committed, trial, point_out, residual, stiffness, projection, false)
}

/// [`mixed_element`] with scratch for `DOFS` displacement DOFs and `NODES` nodes, for blocks
/// of `NN` nodes (`0`: any number, `disp.len()`); every formulation through the general
/// gradient operator if `general_operator` (the check of the tensor form, [`tensor_form`]).
#[allow(clippy::too_many_arguments)]
fn mixed_element_in<const DOFS: usize, const NODES: usize, const NN: usize, G: Geometries + ?Sized>(
    ctx: &KernelContext<'_>,
    disp: &[[f64; 3]],
    pressure: &[f64],
    geometry: &G,
    f0: &[Matrix3<f64>],
    f_prev: &[Matrix3<f64>],
    committed: &[f64],
    trial: &mut [f64],
    point_out: &mut [PointOutput],
    residual: &mut [f64],
    mut stiffness: Option<&mut [f64]>,
    projection: Option<&CellProjection>,
    general_operator: bool,
) -> Result<(), KernelError> {
    let law = mixed_law(ctx)?;
    let tensor = if general_operator { None } else { tensor_form::<NN>(ctx.formulation) };
    debug_assert!(NN == 0 || NN == disp.len(), "a block of {} nodes in the kernel of {NN}", disp.len());
    let nn = if NN == 0 { disp.len() } else { NN };
    let dim = ctx.element.dim();
    let nu = nn * dim;
    let nd = nu + nn;
    let stride = ctx.law.state_len();
    let inv_k = 1.0 / law.bulk_modulus();
    let inv_mu = 1.0 / law.shear_modulus();
    residual[..nd].fill(0.0);
    if let Some(k) = stiffness.as_deref_mut() {
        k[..nd * nd].fill(0.0);
    }
    let active = active_components(ctx.formulation);
    let request = if stiffness.is_some() { TangentRequest::Components(active) } else { TangentRequest::None };
    // the general operator's scratch `B` and `w Bᵀ Ã`, zeroed only where that path runs
    let mut operator = if tensor.is_none() { Some(([[0.0; 9]; DOFS], [[0.0; 9]; DOFS])) } else { None };
    let mut response = StressResponse::default();
    let mut dp_df = Matrix3::zeros();
    // the projection's moments: m_a = Σ w0 N_a, V = Σ w0, and Σ w0 N_a p (for Π₀p)
    let mut moments = [0.0; NODES];
    let mut volume = 0.0;
    let mut scratch = G::Scratch::default();
    for q in 0..geometry.count() {
        let g = geometry.point(q, &mut scratch);
        let delta_f = delta_deformation_gradient(ctx, g, disp);
        let f = delta_f * f0[q];
        let p: f64 = (0..nn).map(|a| g.shape[a] * pressure[a]).sum();
        let kin = loam_laws::Kinematics {
            deformation_gradient: f,
            previous_deformation_gradient: f_prev[q],
            time_step: ctx.time_step,
            tangent: request,
        };
        law.update_mixed(
            &kin,
            p,
            &committed[q * stride..(q + 1) * stride],
            &mut trial[q * stride..(q + 1) * stride],
            &mut response,
            &mut dp_df,
        )
        .map_err(|source| KernelError::Law { point: q, source })?;
        let mut stress = response.first_piola;
        pull_back_response(&f0[q], &mut stress, &mut response.tangent, request.components());
        let j0 = f0[q].determinant();
        let dp_tilde = dp_df * f0[q].transpose() / j0;
        point_out[q] =
            PointOutput { deformation_gradient: f, stress, cauchy: cauchy_stress(&response.first_piola, &f) };
        let (w, w0) = (g.weight, g.weight / j0);
        let det_f = f.determinant();
        if det_f <= 0.0 || !det_f.is_finite() {
            return Err(KernelError::Law { point: q, source: loam_laws::LawError::InvertedDeformation { det_f } });
        }
        let theta = law.volumetric_strain(det_f.ln(), &committed[q * stride..(q + 1) * stride]);
        let volumetric = theta - p * inv_k;
        if let Some(add) = tensor {
            let terms = PointTerms { w, w0, stress: &stress, dp_tilde: &dp_tilde, volumetric, inv_k };
            let tangent = stiffness.is_some().then_some(&response.tangent);
            add(nn, g, &terms, &delta_f, tangent, residual, stiffness.as_deref_mut());
            volume += w0;
            continue;
        }
        let (b, bt_a) = operator.as_mut().expect("the general operator's scratch where there is no tensor form");
        let nc = gradient_operator(ctx.formulation, nn, dim, g, b);
        for r in 0..nu {
            let v: f64 = (0..nc).map(|c| stress[(active[c] / 3, active[c] % 3)] * b[r][c]).sum();
            residual[r] += w * v;
        }
        for a in 0..nn {
            residual[nu + a] += w0 * g.shape[a] * volumetric;
        }
        volume += w0;
        let Some(k) = stiffness.as_deref_mut() else { continue };
        // ∂ ln J/∂ΔF = ΔF⁻ᵀ over the active components
        let dfi = delta_f.try_inverse().unwrap_or_else(Matrix3::zeros).transpose();
        for r in 0..nu {
            for d in 0..nc {
                let v: f64 = (0..nc).map(|c| b[r][c] * response.tangent[(active[c], active[d])]).sum();
                bt_a[r][d] = w * v;
            }
        }
        for r in 0..nu {
            let row = &mut k[r * nd..(r + 1) * nd];
            for s in 0..nu {
                row[s] += (0..nc).map(|d| bt_a[r][d] * b[s][d]).sum::<f64>();
            }
            // K_up
            let bp: f64 = (0..nc).map(|c| b[r][c] * dp_tilde[(active[c] / 3, active[c] % 3)]).sum();
            for a in 0..nn {
                row[nu + a] += w * bp * g.shape[a];
            }
        }
        for s in 0..nu {
            let dj: f64 = (0..nc).map(|c| dfi[(active[c] / 3, active[c] % 3)] * b[s][c]).sum::<f64>();
            for a in 0..nn {
                k[(nu + a) * nd + s] += w0 * g.shape[a] * dj;
            }
        }
        for a in 0..nn {
            for c in 0..nn {
                k[(nu + a) * nd + nu + c] -= w0 * g.shape[a] * g.shape[c] * inv_k;
            }
        }
    }
    if volume <= 0.0 {
        return Ok(());
    }
    // the projection term −(1/μ) (M p − m Π₀p), Π₀p = mᵀp / V, on the points (FEM) or on the
    // cell's region scaled by the fill fraction (MPM)
    let mut mass = [[0.0; NODES]; NODES];
    match projection {
        None => {
            for (q, f) in f0.iter().enumerate().take(geometry.count()) {
                let g = geometry.point(q, &mut scratch);
                let w = g.weight / f.determinant();
                for a in 0..nn {
                    moments[a] += w * g.shape[a];
                    for c in 0..nn {
                        mass[a][c] += w * g.shape[a] * g.shape[c];
                    }
                }
            }
        }
        Some(cell) => {
            let fill = volume / cell.volume;
            for a in 0..nn {
                moments[a] = fill * cell.moments[a];
                for c in 0..nn {
                    mass[a][c] = fill * cell.mass[a * nn + c];
                }
            }
        }
    }
    let mean: f64 = (0..nn).map(|b| moments[b] * pressure[b]).sum::<f64>() / volume;
    for a in 0..nn {
        let mp: f64 = (0..nn).map(|c| mass[a][c] * pressure[c]).sum();
        residual[nu + a] -= inv_mu * (mp - moments[a] * mean);
    }
    if let Some(k) = stiffness {
        for a in 0..nn {
            for c in 0..nn {
                k[(nu + a) * nd + nu + c] -= inv_mu * (mass[a][c] - moments[a] * moments[c] / volume);
            }
        }
    }
    Ok(())
}

/// The integrals of a block's `nn` functions over an MPM cell's own region (its Gauss rule
/// in the step's configuration, or their closed form on a fixed lattice), with which a u–p
/// cell integrates its pressure projection (module doc): `M_ab = ∫ N_a N_b dV` (row stride
/// `nn`), `m_a = ∫ N_a dV` and `V = ∫ dV`, the thickness or `2πR` included.
#[derive(Debug, Clone)]
pub struct CellProjection {
    /// `M_ab` at `a · nn + b`.
    pub mass: [f64; MAX_NODES * MAX_NODES],
    /// `m_a`.
    pub moments: [f64; MAX_NODES],
    /// `V`.
    pub volume: f64,
}

impl Default for CellProjection {
    fn default() -> Self {
        Self { mass: [0.0; MAX_NODES * MAX_NODES], moments: [0.0; MAX_NODES], volume: 0.0 }
    }
}

impl CellProjection {
    /// The integrals on the Gauss rule `rule` of the cell (weights: the points' shares of the
    /// cell's volume), for the first `nn` functions.
    pub fn integrate(&mut self, nn: usize, rule: &[PointGeometry]) {
        self.mass[..nn * nn].fill(0.0);
        self.moments[..nn].fill(0.0);
        self.volume = 0.0;
        for g in rule {
            self.volume += g.weight;
            for a in 0..nn {
                self.moments[a] += g.weight * g.shape[a];
                for c in 0..nn {
                    self.mass[a * nn + c] += g.weight * g.shape[a] * g.shape[c];
                }
            }
        }
    }
}

/// A point's own values in the residual and tangent of [`mixed_element_in`].
struct PointTerms<'a> {
    /// Its weight in `X̃` and in the stress-free configuration.
    w: f64,
    w0: f64,
    /// `P̃` and `B̃ = J0⁻¹ (∂P/∂p) F0ᵀ`.
    stress: &'a Matrix3<f64>,
    dp_tilde: &'a Matrix3<f64>,
    /// `θ − p/K`, and `1/K`.
    volumetric: f64,
    inv_k: f64,
}

/// One point's terms in tensor form ([`add_tensor_point`]).
type TensorPointFn = fn(
    usize,
    &PointGeometry,
    &PointTerms<'_>,
    &Matrix3<f64>,
    Option<&loam_laws::Tangent>,
    &mut [f64],
    Option<&mut [f64]>,
);

/// Plane strain (`D` = 2) and 3D (`D` = 3), where the active components of `F` are the
/// `D × D` block and the gradient operator is `B_(ai),(kL) = δ_ik ∂N_a/∂X̃_L`: one point's
/// terms with the zeros of `B` skipped (the tensor form of [`crate::kernel::solid_element`]),
/// each sum over the same nonzero products in the same order as the general operator's, so
/// that both give the same values bit for bit. Axisymmetry (the hoop row `N_a/R`) takes the
/// general operator (`None`).
fn tensor_form<const NN: usize>(formulation: Formulation) -> Option<TensorPointFn> {
    match formulation {
        Formulation::PlaneStrain => Some(add_tensor_point::<2, NN>),
        Formulation::ThreeD => Some(add_tensor_point::<3, NN>),
        Formulation::Axisymmetric | Formulation::PlaneStress => None,
    }
}

/// [`tensor_form`] in `D` dimensions: `r_u,ai += w P̃_iJ ∂N_a/∂X̃_J`, `r_p,a += w0 N_a (θ −
/// p/K)` and, with the tangent `Ã`, `K_uu,(ai)(bk) += Σ_L (w Σ_J ∂N_a/∂X̃_J Ã_iJkL) ∂N_b/∂X̃_L`,
/// `K_up,(ai)b += w (Σ_J ∂N_a/∂X̃_J B̃_iJ) N_b`, `K_pu,a(bk) += w0 N_a Σ_L ΔF⁻ᵀ_kL ∂N_b/∂X̃_L`,
/// `K_pp,ab −= w0 N_a N_b / K`.
///
/// Compiled for blocks of `NN` nodes (`0`: any number, `nn`), as [`mixed_element_in`]: with
/// `nn` a constant the loops over the nodes are unrolled and their independent outputs
/// vectorised, the same products summed in the same order (bit for bit the run-time loop).
fn add_tensor_point<const D: usize, const NN: usize>(
    nn: usize,
    g: &PointGeometry,
    terms: &PointTerms<'_>,
    delta_f: &Matrix3<f64>,
    tangent: Option<&loam_laws::Tangent>,
    residual: &mut [f64],
    stiffness: Option<&mut [f64]>,
) {
    let nn = if NN == 0 { nn } else { NN };
    let PointTerms { w, w0, stress, dp_tilde, volumetric, inv_k } = *terms;
    let nu = nn * D;
    let nd = nu + nn;
    for a in 0..nn {
        let ga = &g.gradient[a];
        for i in 0..D {
            let v: f64 = (0..D).map(|j| stress[(i, j)] * ga[j]).sum();
            residual[a * D + i] += w * v;
        }
    }
    for a in 0..nn {
        residual[nu + a] += w0 * g.shape[a] * volumetric;
    }
    let (Some(k), Some(tangent)) = (stiffness, tangent) else { return };
    let dfi = delta_f.try_inverse().unwrap_or_else(Matrix3::zeros).transpose();
    for a in 0..nn {
        let ga = &g.gradient[a];
        for i in 0..D {
            // bt[k][l] = w Σ_J ∂N_a/∂X̃_J Ã_iJkL (a row of w Bᵀ Ã)
            let mut bt = [[0.0; D]; D];
            for (kk, row) in bt.iter_mut().enumerate() {
                for (l, value) in row.iter_mut().enumerate() {
                    let v: f64 = (0..D).map(|j| ga[j] * tangent[(idx(i, j), idx(kk, l))]).sum();
                    *value = w * v;
                }
            }
            let r = a * D + i;
            let row = &mut k[r * nd..(r + 1) * nd];
            for b in 0..nn {
                let gb = &g.gradient[b];
                for kk in 0..D {
                    row[b * D + kk] += (0..D).map(|l| bt[kk][l] * gb[l]).sum::<f64>();
                }
            }
            let bp: f64 = (0..D).map(|j| ga[j] * dp_tilde[(i, j)]).sum();
            for b in 0..nn {
                row[nu + b] += w * bp * g.shape[b];
            }
        }
    }
    for b in 0..nn {
        let gb = &g.gradient[b];
        for kk in 0..D {
            let dj: f64 = (0..D).map(|l| dfi[(kk, l)] * gb[l]).sum();
            let s = b * D + kk;
            for a in 0..nn {
                k[(nu + a) * nd + s] += w0 * g.shape[a] * dj;
            }
        }
    }
    for a in 0..nn {
        for c in 0..nn {
            k[(nu + a) * nd + nu + c] -= w0 * g.shape[a] * g.shape[c] * inv_k;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::ElementType;
    use crate::kernel::point_geometry;
    use crate::kernel::test_fixtures::{element_coords, initial_states, pre_deformation};
    use loam_laws::mohr_coulomb::MohrCoulomb;
    use loam_laws::neo_hookean::NeoHookean;
    use loam_laws::ConstitutiveLaw;

    /// The coupled u–p element tangent against central differences of its residual in every
    /// displacement and pressure, for every element and formulation, with `F0 ≠ I` (the MPM
    /// pull-back): Neo-Hookean (ν = 0.4999 and exactly incompressible), and Mohr–Coulomb
    /// with φ = 0 (Tresca) and φ = 25° (ψ = 0: the unsymmetric coupling) on its yield
    /// surface. Relative error < 1e-6 of the largest entry. In plane strain and 3D the
    /// element's tensor form ([`tensor_form`]) also equals the general operator's, bit for bit.
    #[test]
    fn mixed_tangent_matches_finite_differences_of_residual() {
        let nh = NeoHookean::new(1000.0, 1.0e6, 0.4999);
        let nh_incompressible = NeoHookean::new(1000.0, 1.0e6, 0.5);
        let tresca = MohrCoulomb::new(1000.0, 1.0e6, 0.5, 0.0, 2.0e3, 0.0);
        let frictional = MohrCoulomb::new(1000.0, 1.0e6, 0.3, 25f64.to_radians(), 2.0e3, 0.0);
        let laws: [(&dyn ConstitutiveLaw, bool); 4] =
            [(&nh, false), (&nh_incompressible, false), (&tresca, true), (&frictional, true)];
        let cases = [
            (ElementType::Tri3, Formulation::PlaneStrain),
            (ElementType::Quad4, Formulation::PlaneStrain),
            (ElementType::Tri3, Formulation::Axisymmetric),
            (ElementType::Quad4, Formulation::Axisymmetric),
            (ElementType::Tet4, Formulation::ThreeD),
            (ElementType::Hex8, Formulation::ThreeD),
        ];
        for (law, plastic) in laws {
            for (element, formulation) in cases {
                for cell_rule in [false, true] {
                    let err = check(law, element, formulation, plastic, cell_rule);
                    println!(
                        "{} (K = {:.3e}) {element:?} {formulation:?}{}: u–p element tangent vs central FD, relative \
                         error {err:.2e} (tolerance 1e-6)",
                        law.name(),
                        law.mixed().unwrap().bulk_modulus(),
                        if cell_rule { ", projection on the cell rule" } else { "" }
                    );
                    assert!(err < 1e-6, "{element:?} {formulation:?}: {err}");
                }
            }
        }
    }

    fn check(
        law: &dyn ConstitutiveLaw,
        element: ElementType,
        formulation: Formulation,
        plastic: bool,
        cell_rule: bool,
    ) -> f64 {
        let coords = element_coords(element);
        let (nn, dim) = (element.num_nodes(), element.dim());
        let nd = nn * (dim + 1);
        let rule = if matches!(element, ElementType::Tri3 | ElementType::Tet4) {
            element.gauss_points_high()
        } else {
            element.gauss_points()
        };
        let geometry: Vec<PointGeometry> = rule
            .iter()
            .map(|g| point_geometry(element, formulation, 1.0, &coords, &g.xi, g.weight, None).unwrap())
            .collect();
        let np = geometry.len();
        // as an MPM cell would: the projection on the cell's standard rule
        let projection: Option<CellProjection> = cell_rule.then(|| {
            let rule: Vec<PointGeometry> = element
                .gauss_points_mixed()
                .iter()
                .map(|g| point_geometry(element, formulation, 1.0, &coords, &g.xi, g.weight, None).unwrap())
                .collect();
            let mut cell = CellProjection::default();
            cell.integrate(nn, &rule);
            cell
        });
        let f0s = vec![pre_deformation(dim, formulation); np];
        let ctx = KernelContext { element, formulation, law, time_step: 0.0 };
        let stride = law.state_len();
        let committed = initial_states(law, np);
        // displacements of a few per cent (plastic for the weak soils), pressures of the
        // order of the shear modulus
        let scale = if plastic { 0.05 } else { 0.03 };
        let mut x = vec![0.0; nd];
        for (s, v) in x.iter_mut().enumerate() {
            *v =
                if s < nn * dim { scale * ((s * 3 + 1) as f64).sin() } else { -3.0e3 * (1.0 + 0.3 * (s as f64).cos()) };
        }
        // the element through the tensor form (plane strain, 3D) or the general operator
        let evaluate = |x: &[f64], k: Option<&mut [f64]>, general_operator: bool| {
            let disp: Vec<[f64; 3]> =
                (0..nn).map(|a| std::array::from_fn(|i| if i < dim { x[a * dim + i] } else { 0.0 })).collect();
            let mut r = vec![0.0; nd];
            let mut out = vec![PointOutput::default(); np];
            let mut trial = committed.clone();
            mixed_element_in::<MAX_DOFS, MAX_NODES, 0, [PointGeometry]>(
                &ctx,
                &disp,
                &x[nn * dim..],
                &geometry[..],
                &f0s,
                &f0s,
                &committed,
                &mut trial,
                &mut out,
                &mut r,
                k,
                projection.as_ref(),
                general_operator,
            )
            .unwrap();
            (r, trial)
        };
        let residual = |x: &[f64], k: Option<&mut [f64]>| evaluate(x, k, false);
        let mut k = vec![0.0; nd * nd];
        let (r, trial) = residual(&x, Some(&mut k));
        if tensor_form::<0>(formulation).is_some() {
            // the tensor form against the general operator, bit for bit
            let mut k2 = vec![0.0; nd * nd];
            let (r2, _) = evaluate(&x, Some(&mut k2), true);
            let same = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same(&r, &r2), "{element:?} {formulation:?}: residual");
            assert!(same(&k, &k2), "{element:?} {formulation:?}: tangent");
        }
        if plastic {
            let flag = law.state_variables().iter().position(|v| *v == "yield_flag").unwrap();
            let mut values = vec![0.0; law.state_variables().len()];
            let yielded = trial.chunks(stride).filter(|st| {
                law.state_output(st, &mut values);
                values[flag] > 0.0
            });
            assert!(yielded.count() > 0, "{element:?} {formulation:?}: the check must reach the yield surface");
        }
        // rows and columns in the physical units of each; compare per block against the
        // block's largest entry
        let mut err = 0.0f64;
        let kmax = |rows: std::ops::Range<usize>, cols: std::ops::Range<usize>| {
            rows.flat_map(|r| cols.clone().map(move |c| (r, c))).fold(0.0f64, |m, (r, c)| m.max(k[r * nd + c].abs()))
        };
        let nu = nn * dim;
        let blocks = [(0..nu, 0..nu), (0..nu, nu..nd), (nu..nd, 0..nu), (nu..nd, nu..nd)];
        let maxes: Vec<f64> = blocks.iter().map(|(r, c)| kmax(r.clone(), c.clone())).collect();
        for s in 0..nd {
            let h = if s < nu { 1e-6 } else { 1e-3 };
            let (mut xp, mut xm) = (x.clone(), x.clone());
            xp[s] += h;
            xm[s] -= h;
            let (rp, rm) = (residual(&xp, None).0, residual(&xm, None).0);
            for r in 0..nd {
                let block = usize::from(r >= nu) * 2 + usize::from(s >= nu);
                let fd = (rp[r] - rm[r]) / (2.0 * h);
                err = err.max((fd - k[r * nd + s]).abs() / maxes[block].max(1e-300));
            }
        }
        err
    }
}
