//! Mohr–Coulomb elasto-plasticity at finite strain, non-associated, with the return mapping
//! of Clausen, Damkilde & Andersen (2007) in principal stress space.
//!
//! Frame: multiplicative plasticity on Hencky elasticity ([`crate::multiplicative`],
//! Simo 1992). In principal Kirchhoff stresses sorted `τ₁ ≥ τ₂ ≥ τ₃` (tension positive):
//!
//! - yield function `f = k τ₁ − τ₃ − σ_c`, `k = (1 + sin φ)/(1 − sin φ)`,
//!   `σ_c = 2 c cos φ/(1 − sin φ)` (the uniaxial compressive strength);
//! - plastic potential `g = m τ₁ − τ₃`, `m = (1 + sin ψ)/(1 − sin ψ)` (ψ ≤ φ);
//! - elasticity `τ = D ε_e`, `D = λ 1⊗1 + 2μ I` (3×3, principal).
//!
//! **Algorithm** (Clausen, Damkilde & Andersen 2007, "An efficient return algorithm for
//! non-associated plasticity with linear yield criteria in principal stress space",
//! Computers & Structures 85:1795–1807, doi:10.1016/j.compstruc.2007.04.002). With the
//! elastic trial `τ_B` and the flow direction `D b`, `b = ∂g/∂τ = (m, 0, −1)`:
//!
//! 1. return to the plane: `τ_C = τ_B − f(τ_B) D b / (aᵀ D b)`, `a = (k, 0, −1)`; accepted if
//!    it keeps the order `τ₁ ≥ τ₂ ≥ τ₃`;
//! 2. otherwise return to the edge `τ₁ = τ₂` (triaxial compression, direction
//!    `ℓ₁ = (1, 1, k)` through `(0, 0, −σ_c)`) or `τ₂ = τ₃` (triaxial extension, direction
//!    `ℓ₂ = (1, k, k)` through `(σ_c/k, 0, 0)`): `τ_C = τ₀ + t ℓ`,
//!    `t = nᵀ(τ_B − τ₀)/(nᵀ ℓ)`, `n = D b × D b'`, with `b'` the flow direction of the
//!    second active plane; accepted while the point lies on the cone side of the apex;
//! 3. otherwise return to the apex `τ_C = σ_c/(k − 1) (1, 1, 1)` (absent when φ = 0).
//!
//! The algorithmic tangent `∂τ/∂ε_tr` is the exact derivative of this algorithm, obtained
//! by forward-mode differentiation ([`crate::dual`]); with strain softening
//! ([`crate::mohr_coulomb_softening`]) the strength parameters depend on the accumulated
//! plastic deviatoric strain κ, the scalar equation `κ = κ_n + Δκ(κ)` is solved by Newton
//! and the tangent includes `∂τ/∂κ · dκ/dε_tr` (implicit function theorem).
//!
//! **u–p form** ([`crate::mixed`]; constant strength and ψ = 0, the isochoric flow of
//! undrained soil and of Tresca, φ = 0): the trial stress keeps the given pressure `p` as its
//! mean, `τ_B,a = 2μ (ε_tr,a − tr ε_tr/3) + p`. The plane and edge returns above move along
//! the flow directions `D b`, which are deviatoric for ψ = 0 (and free of λ), so they are the
//! same algorithm at the fixed mean stress `p`. Beyond the apex (`p ≥ σ_c/(k − 1) = c cot φ`)
//! no deviatoric stress is admissible: `τ = p 1`, and at the end of the step the point's
//! volume beyond `θ_apex = p_apex/K` is released as a plastic dilation (the grains separate,
//! as in the displacement form's apex return). The elastic strains are
//! `ε_e = tr ε_tr/3 + dev τ/(2μ)` (`J_e = J`), with `tr ε_tr` capped at `θ_apex` only where
//! the point's pressure is at the apex ([`crate::mixed::elastic_strain_up`]: why the
//! pressure decides, and why the cap is not part of the step's volumetric law), and
//! `∂τ_a/∂ε_tr,b`, `∂τ_a/∂p` come from the same dual numbers, seeded on `(ε_tr, p)`.

use nalgebra::Matrix3;

use crate::dual::{Dual, Real};
use crate::mixed::{dual_mixed_response, MixedPrincipalModel, MixedPrincipalResponse, MixedReturn};
use crate::multiplicative::{
    self, accumulate_plastic_strain, hencky_matrix, hencky_strain, hencky_stress, PrincipalModel, PrincipalResponse,
    PLASTIC_OUTPUT,
};
use crate::LawError;

/// Mohr–Coulomb strength at a given accumulated plastic deviatoric strain.
#[derive(Debug, Clone, Copy)]
pub struct Strength<T> {
    /// Friction angle φ in rad.
    pub friction_angle: T,
    /// Cohesion c in Pa.
    pub cohesion: T,
    /// Dilatancy angle ψ in rad.
    pub dilatancy_angle: T,
}

/// How the Mohr–Coulomb strength evolves with the accumulated plastic deviatoric strain κ.
pub trait StrengthEvolution: Send + Sync + std::fmt::Debug + Clone {
    /// Name of the law in case files.
    const NAME: &'static str;
    /// Strength at κ (generic so that `∂/∂κ` comes out of [`crate::dual`]).
    fn at<T: Real>(&self, kappa: T) -> Strength<T>;
    /// Whether the strength depends on κ at all.
    fn evolves(&self) -> bool;
    /// [`mohr_coulomb_coefficients`] of the strength at κ.
    fn coefficients<T: Real>(&self, kappa: T) -> (T, T, T) {
        mohr_coulomb_coefficients(&self.at(kappa))
    }
}

/// Constant strength: perfect Mohr–Coulomb plasticity. Its coefficients `(k, σ_c, m)` are
/// computed once (the same operations as [`mohr_coulomb_coefficients`], so the same values):
/// every point's yield check needed two sines and a cosine.
#[derive(Debug, Clone, Copy)]
pub struct ConstantStrength {
    strength: Strength<f64>,
    coefficients: (f64, f64, f64),
}

impl ConstantStrength {
    /// The constant strength `strength`.
    pub fn new(strength: Strength<f64>) -> Self {
        Self { strength, coefficients: mohr_coulomb_coefficients(&strength) }
    }
}

impl StrengthEvolution for ConstantStrength {
    const NAME: &'static str = "mohr_coulomb";
    fn at<T: Real>(&self, _kappa: T) -> Strength<T> {
        Strength {
            friction_angle: T::cst(self.strength.friction_angle),
            cohesion: T::cst(self.strength.cohesion),
            dilatancy_angle: T::cst(self.strength.dilatancy_angle),
        }
    }
    fn evolves(&self) -> bool {
        false
    }
    fn coefficients<T: Real>(&self, _kappa: T) -> (T, T, T) {
        let (k, sc, m) = self.coefficients;
        (T::cst(k), T::cst(sc), T::cst(m))
    }
}

/// Mohr–Coulomb law with Hencky elasticity and a strength evolution `S`.
#[derive(Debug, Clone)]
pub struct MohrCoulombLaw<S> {
    /// Density ρ₀ in kg/m³.
    pub density: f64,
    /// First Lamé constant λ in Pa.
    pub lambda: f64,
    /// Shear modulus μ in Pa.
    pub mu: f64,
    /// Strength and its evolution.
    pub strength: S,
}

/// Perfectly plastic Mohr–Coulomb.
pub type MohrCoulomb = MohrCoulombLaw<ConstantStrength>;

impl MohrCoulomb {
    /// From `E` (Pa), `ν`, φ (rad), c (Pa), ψ (rad).
    pub fn new(
        density: f64,
        young_modulus: f64,
        poisson_ratio: f64,
        friction_angle: f64,
        cohesion: f64,
        dilatancy_angle: f64,
    ) -> Self {
        let (lambda, mu) = crate::material::lame(young_modulus, poisson_ratio);
        Self {
            density,
            lambda,
            mu,
            strength: ConstantStrength::new(Strength { friction_angle, cohesion, dilatancy_angle }),
        }
    }
}

/// `(k, σ_c, m)` of a strength: `k = (1+sin φ)/(1−sin φ)`, `σ_c = 2c cos φ/(1−sin φ)`,
/// `m = (1+sin ψ)/(1−sin ψ)`.
pub fn mohr_coulomb_coefficients<T: Real>(s: &Strength<T>) -> (T, T, T) {
    let sphi = s.friction_angle.sin();
    let k = (sphi + 1.0) / (-sphi + 1.0);
    let sc = s.cohesion * s.friction_angle.cos() * 2.0 / (-sphi + 1.0);
    let spsi = s.dilatancy_angle.sin();
    let m = (spsi + 1.0) / (-spsi + 1.0);
    (k, sc, m)
}

fn cross<T: Real>(a: [T; 3], b: [T; 3]) -> [T; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn dot<T: Real>(a: [T; 3], b: [T; 3]) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Return region of the Clausen et al. (2007) algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// Elastic step.
    Elastic,
    /// Return to the yield plane.
    Plane,
    /// Return to the triaxial-compression edge `τ₁ = τ₂`.
    CompressionEdge,
    /// Return to the triaxial-extension edge `τ₂ = τ₃`.
    ExtensionEdge,
    /// Return to the apex.
    Apex,
}

/// The Clausen–Damkilde–Andersen return for sorted trial stresses `sb` (`sb₀ ≥ sb₁ ≥ sb₂`)
/// and a plastic trial (`f(sb) > 0`), with Hencky moduli `λ`, `μ`.
pub fn clausen_return<T: Real>(
    sb: [T; 3],
    lambda: f64,
    mu: f64,
    k: T,
    sc: T,
    m: T,
) -> Result<([T; 3], Region), LawError> {
    let z = T::cst(0.0);
    let one = T::cst(1.0);
    let de = |v: [T; 3]| hencky_stress(lambda, mu, v);
    let scale = sb.iter().fold(sc.re().abs(), |a, s| a.max(s.re().abs())).max(1.0);
    let tol = 1e-12 * scale;
    let f = k * sb[0] - sb[2] - sc;
    let db = de([m, z, -one]);
    let adb = k * db[0] - db[2];
    let ratio = f / adb;
    let sp = [sb[0] - db[0] * ratio, sb[1] - db[1] * ratio, sb[2] - db[2] * ratio];
    if sp[0].re() >= sp[1].re() - tol && sp[1].re() >= sp[2].re() - tol {
        return Ok((sp, Region::Plane));
    }
    let edge = |p: [T; 3], l: [T; 3], b2: [T; 3]| {
        let n = cross(db, de(b2));
        let t = dot(n, [sb[0] - p[0], sb[1] - p[1], sb[2] - p[2]]) / dot(n, l);
        [p[0] + l[0] * t, p[1] + l[1] * t, p[2] + l[2] * t]
    };
    let compression = || edge([z, z, -sc], [one, one, k], [z, m, -one]);
    let extension = || edge([sc / k, z, z], [one, k, k], [m, -one, z]);
    if sp[0].re() < sp[1].re() {
        let s = compression();
        if s[1].re() >= s[2].re() - tol {
            return Ok((s, Region::CompressionEdge));
        }
    }
    if sp[1].re() < sp[2].re() {
        let s = extension();
        if s[0].re() >= s[1].re() - tol {
            return Ok((s, Region::ExtensionEdge));
        }
    }
    if k.re() - 1.0 > 1e-12 {
        let a = sc / (k - 1.0);
        return Ok(([a, a, a], Region::Apex));
    }
    Err(LawError::ReturnMappingFailed { iterations: 0, residual: f.re() })
}

/// Result of the plastic return at a fixed κ, differentiated with respect to
/// `(ε_tr,1, ε_tr,2, ε_tr,3, κ)`.
struct PlasticEvaluation {
    tau: [Dual<4>; 3],
    delta_kappa: Dual<4>,
    region: Region,
}

impl<S: StrengthEvolution> MohrCoulombLaw<S> {
    /// Yield function `f = k τ₁ − τ₃ − σ_c` (Pa) at principal Kirchhoff stresses `tau`
    /// (any order) and accumulated plastic deviatoric strain `kappa`.
    pub fn yield_function(&self, tau: [f64; 3], kappa: f64) -> f64 {
        let (k, sc, _) = self.strength.coefficients(kappa);
        let max = tau.iter().cloned().fold(f64::MIN, f64::max);
        let min = tau.iter().cloned().fold(f64::MAX, f64::min);
        k * max - min - sc
    }

    /// Return region taken by the trial principal elastic log strains `eps_tr` from the
    /// committed internal variables (`[κ, ε_p^v, flag]`).
    pub fn region(&self, eps_tr: [f64; 3], committed: &[f64]) -> Region {
        let tau_b = hencky_stress(self.lambda, self.mu, eps_tr);
        if self.yield_function(tau_b, committed[0]) <= self.yield_tolerance(tau_b) {
            return Region::Elastic;
        }
        self.plastic_evaluation(eps_tr, committed[0]).map(|e| e.region).unwrap_or(Region::Elastic)
    }

    fn yield_tolerance(&self, tau: [f64; 3]) -> f64 {
        1e-10 * tau.iter().fold(1.0_f64, |a, t| a.max(t.abs()))
    }

    fn plastic_evaluation(&self, eps_tr: [f64; 3], kappa: f64) -> Result<PlasticEvaluation, LawError> {
        let eps: [Dual<4>; 3] = [Dual::seed(eps_tr[0], 0), Dual::seed(eps_tr[1], 1), Dual::seed(eps_tr[2], 2)];
        let (k, sc, m) = self.strength.coefficients(Dual::seed(kappa, 3));
        let tau_b = hencky_stress(self.lambda, self.mu, eps);
        let mut perm = [0usize, 1, 2];
        perm.sort_by(|&a, &b| tau_b[b].v.partial_cmp(&tau_b[a].v).unwrap_or(std::cmp::Ordering::Equal));
        let sorted = perm.map(|a| tau_b[a]);
        let (ts, region) = clausen_return(sorted, self.lambda, self.mu, k, sc, m)?;
        let mut tau = tau_b;
        for (i, &a) in perm.iter().enumerate() {
            tau[a] = ts[i];
        }
        let e = hencky_strain(self.lambda, self.mu, tau);
        let d = [eps[0] - e[0], eps[1] - e[1], eps[2] - e[2]];
        let vol = (d[0] + d[1] + d[2]) / 3.0;
        let n2 = d.iter().fold(Dual::cst(0.0), |acc, di| acc + (*di - vol) * (*di - vol));
        let delta_kappa = if n2.v > 1e-300 { (n2 * (2.0 / 3.0)).sqrt() } else { Dual::cst(0.0) };
        Ok(PlasticEvaluation { tau, delta_kappa, region })
    }
}

/// Maximum local Newton iterations on κ (softening).
const MAX_ITERATIONS: usize = 50;

impl<S: StrengthEvolution> PrincipalModel for MohrCoulombLaw<S> {
    fn internal_len(&self) -> usize {
        3
    }

    fn initialise_internal(&self, internal: &mut [f64]) {
        internal[..3].fill(0.0);
    }

    fn principal_update(
        &self,
        eps_tr: [f64; 3],
        _time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<PrincipalResponse, LawError> {
        let kappa_n = committed[0];
        let tau_b = hencky_stress(self.lambda, self.mu, eps_tr);
        if self.yield_function(tau_b, kappa_n) <= self.yield_tolerance(tau_b) {
            accumulate_plastic_strain(committed, trial, eps_tr, eps_tr, false);
            return Ok(PrincipalResponse { tau: tau_b, eps_e: eps_tr, dtau_deps: hencky_matrix(self.lambda, self.mu) });
        }
        let mut kappa = kappa_n;
        let mut residual = f64::INFINITY;
        for iteration in 0..=MAX_ITERATIONS {
            let ev = self.plastic_evaluation(eps_tr, kappa)?;
            // r(κ) = κ − κ_n − Δκ(κ, ε_tr)
            let r = Dual::<4>::seed(kappa, 3) - ev.delta_kappa - kappa_n;
            let converged = !self.strength.evolves() || r.v.abs() <= 1e-12 * (1.0 + kappa.abs());
            if converged {
                let kappa_new = if self.strength.evolves() { kappa } else { kappa_n + ev.delta_kappa.v };
                let dkappa = [-r.d[0] / r.d[3], -r.d[1] / r.d[3], -r.d[2] / r.d[3]];
                let dtau_deps = Matrix3::from_fn(|a, b| ev.tau[a].d[b] + ev.tau[a].d[3] * dkappa[b]);
                let tau = ev.tau.map(|t| t.v);
                let eps_e = hencky_strain(self.lambda, self.mu, tau);
                accumulate_plastic_strain(committed, trial, eps_tr, eps_e, true);
                trial[0] = kappa_new;
                return Ok(PrincipalResponse { tau, eps_e, dtau_deps });
            }
            residual = r.v;
            if iteration == MAX_ITERATIONS {
                break;
            }
            kappa = (kappa - r.v / r.d[3]).max(kappa_n);
        }
        Err(LawError::ReturnMappingFailed { iterations: MAX_ITERATIONS, residual })
    }

    fn elastic_strain(&self, tau: [f64; 3]) -> Result<[f64; 3], LawError> {
        Ok(hencky_strain(self.lambda, self.mu, tau))
    }
}

impl<S: StrengthEvolution> MohrCoulombLaw<S> {
    /// Why this law has no u–p form (strain softening, or a dilatant flow), if it has none.
    pub fn mixed_problem(&self) -> Option<String> {
        if self.strength.evolves() {
            return Some("strain softening has no u–p form in Loam (mixed_up takes mohr_coulomb)".into());
        }
        let psi = self.strength.at(0.0_f64).dilatancy_angle;
        (psi != 0.0).then(|| {
            format!("mixed_up needs an isochoric plastic flow: dilatancy_angle must be 0, got {}", psi.to_degrees())
        })
    }

    /// The elastic volumetric strain at the apex, `θ_apex = p_apex/K`, `p_apex = σ_c/(k − 1)`
    /// (`+∞` without an apex: φ = 0).
    fn apex_strain(&self) -> f64 {
        let (k, sc, _) = self.strength.coefficients(0.0_f64);
        if k - 1.0 > 1e-12 {
            sc / (k - 1.0) / (self.lambda + 2.0 * self.mu / 3.0)
        } else {
            f64::INFINITY
        }
    }

    /// The u–p return (module doc) at trial principal log strains `eps` and pressure `p`.
    fn mixed_return<T: Real>(&self, eps: [T; 3], p: T) -> Result<([T; 3], Region), LawError> {
        let (k, sc, m) = self.strength.coefficients(T::cst(0.0));
        let tau_b = crate::mixed::deviator(eps).map(|e| e * (2.0 * self.mu) + p);
        let values = tau_b.map(|t| t.re());
        if self.yield_function(values, 0.0) <= self.yield_tolerance(values) {
            return Ok((tau_b, Region::Elastic));
        }
        let apex = [p, p, p];
        if k.re() - 1.0 > 1e-12 && p.re() >= sc.re() / (k.re() - 1.0) {
            return Ok((apex, Region::Apex));
        }
        let mut perm = [0usize, 1, 2];
        perm.sort_by(|&a, &b| values[b].partial_cmp(&values[a]).unwrap_or(std::cmp::Ordering::Equal));
        // λ does not enter a return along deviatoric flow directions
        let (ts, region) = clausen_return(perm.map(|a| tau_b[a]), 0.0, self.mu, k, sc, m)?;
        if region == Region::Apex {
            return Ok((apex, Region::Apex));
        }
        let mut tau = tau_b;
        for (i, &a) in perm.iter().enumerate() {
            tau[a] = ts[i];
        }
        Ok((tau, region))
    }
}

impl<S: StrengthEvolution> MixedPrincipalModel for MohrCoulombLaw<S> {
    fn lame(&self) -> (f64, f64) {
        (self.lambda, self.mu)
    }

    fn mixed_principal_update(
        &self,
        eps_tr: [f64; 3],
        pressure: f64,
        _time_step: f64,
        committed: &[f64],
        trial: &mut [f64],
    ) -> Result<MixedPrincipalResponse, LawError> {
        dual_mixed_response(eps_tr, pressure, self.mu, committed, trial, |eps, p| {
            let (t, region) = self.mixed_return(eps, p)?;
            let apex_cap = (region == Region::Apex).then(|| self.apex_strain());
            Ok((t, MixedReturn { yielded: region != Region::Elastic, apex_cap }))
        })
    }
}

multiplicative::impl_principal_law!(impl[S: StrengthEvolution] MohrCoulombLaw<S>, name: S::NAME, outputs: &PLASTIC_OUTPUT, lame: |law| (law.lambda, law.mu),
    mixed: |law| match law.mixed_problem() { Some(problem) => Err(problem), None => Ok(law) });

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiplicative::CP_INV_LEN;
    use crate::tensor::tangent_relative_error;
    use crate::{ConstitutiveLaw, Kinematics};

    fn law() -> MohrCoulomb {
        MohrCoulomb::new(2000.0, 5.0e7, 0.3, 25f64.to_radians(), 5.0e3, 5f64.to_radians())
    }

    /// Trial principal Kirchhoff stresses (kPa) chosen to land in each return region
    /// (c cot φ = 10.7 kPa is the apex), with the region expected.
    #[test]
    fn tangent_in_every_region() {
        let law = law();
        let cases = [
            ([-50.0, -200.0, -400.0], Region::Plane),
            ([-50.0, -300.0, -300.0], Region::ExtensionEdge),
            ([-100.0, -100.0, -400.0], Region::CompressionEdge),
            ([30.0, 40.0, 35.0], Region::Apex),
            ([-100.0, -120.0, -150.0], Region::Elastic),
        ];
        let rot = nalgebra::Rotation3::from_euler_angles(0.2, 0.5, -0.3).into_inner();
        for (tau_kpa, expected) in cases {
            let eps = hencky_strain(law.lambda, law.mu, tau_kpa.map(|t| t * 1e3));
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            assert_eq!(law.region(eps, &state[CP_INV_LEN..]), expected);
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let err = tangent_relative_error(&law, &Kinematics::at(f), &state).unwrap();
            println!("mohr_coulomb {expected:?}: tangent relative error vs central FD {err:.2e} (tolerance 1e-6)");
            assert!(err < 1e-6);
        }
    }

    /// u–p form, φ = 0 (Tresca, undrained, incompressible) and φ = 25° (ψ = 0): the tangents
    /// against central differences in every region, with a deviatoric trial of the sizes
    /// below and the given pressure (kPa); the mean stress stays the pressure.
    #[test]
    fn mixed_tangent_in_every_region() {
        let rot = nalgebra::Rotation3::from_euler_angles(0.2, 0.5, -0.3).into_inner();
        let tresca = MohrCoulomb::new(2000.0, 1.0e5, 0.5, 0.0, 1.0e3, 0.0);
        let frictional = MohrCoulomb::new(2000.0, 5.0e7, 0.3, 25f64.to_radians(), 5.0e3, 0.0);
        // (law, deviatoric trial strain × 1e-3, pressure kPa, expected region)
        let cases: [(&MohrCoulomb, [f64; 3], f64, Region); 7] = [
            (&tresca, [0.5, -0.2, -0.3], -50.0, Region::Elastic),
            (&tresca, [20.0, -5.0, -15.0], -50.0, Region::Plane),
            (&tresca, [20.0, 18.0, -38.0], 10.0, Region::CompressionEdge),
            (&tresca, [24.0, -12.0, -12.0], -10.0, Region::ExtensionEdge),
            (&frictional, [2.0, -0.5, -1.5], -100.0, Region::Plane),
            (&frictional, [1.0, 1.0, -2.0], -100.0, Region::CompressionEdge),
            (&frictional, [2.0, -0.5, -1.5], 20.0, Region::Apex),
        ];
        for (law, dev, p_kpa, expected) in cases {
            let mut state = vec![0.0; law.state_len()];
            law.initialise_state(&mut state);
            let eps = dev.map(|e| e * 1e-3 + 0.002);
            let (_, region) = law.mixed_return(eps, p_kpa * 1e3).unwrap();
            assert_eq!(region, expected, "{dev:?} at {p_kpa} kPa");
            let f = rot * Matrix3::from_diagonal(&eps.map(f64::exp).into()) * rot.transpose();
            let (ea, ep) =
                crate::mixed::mixed_tangent_relative_error(law, &Kinematics::at(f), p_kpa * 1e3, &state).unwrap();
            println!("mohr_coulomb u–p {expected:?}: A error {ea:.2e}, ∂P/∂p error {ep:.2e} (tolerance 1e-6)");
            assert!(ea < 1e-6 && ep < 1e-6, "{expected:?}");
        }
        assert!(MohrCoulomb::new(2000.0, 5.0e7, 0.3, 0.5, 5.0e3, 0.1).mixed().is_err());
    }

    /// u–p form, c = 0 (apex at p = 0, `θ_apex = 0`): a point stretched by 1 % in volume
    /// (`θ = ln J = 0.01 > θ_apex`) dilates plastically only if its pressure is at the apex.
    /// Under a compressive pressure the stretch is the weak volumetric law's pointwise scatter
    /// and stays elastic: committed plastic volume change 0 and `det Cp⁻¹ = 1`, so that the
    /// next step sees `θ = ln J` again; at p ≥ 0 the whole 0.01 is plastic dilation
    /// (`det Cp⁻¹ = e^{−0.02}`) and the next step starts at the apex, `θ = 0`.
    #[test]
    fn mixed_apex_dilation_only_where_the_pressure_is_at_the_apex() {
        use crate::mixed::MixedLaw;
        let law = MohrCoulomb::new(2650.0, 8.4e5, 0.3, 19.8f64.to_radians(), 0.0, 0.0);
        let names = law.state_variables();
        let volumetric = names.iter().position(|v| *v == "accumulated_plastic_volumetric_strain").unwrap();
        let ln_j = 0.01;
        let f = Matrix3::from_diagonal_element((ln_j / 3.0f64).exp());
        for (pressure, expected) in [(-2.0e3, 0.0), (1.0, ln_j)] {
            let mut committed = vec![0.0; law.state_len()];
            law.initialise_state(&mut committed);
            let mut trial = committed.clone();
            let (mut response, mut dp) = (crate::StressResponse::default(), Matrix3::zeros());
            law.update_mixed(&Kinematics::at(f), pressure, &committed, &mut trial, &mut response, &mut dp).unwrap();
            let mut values = vec![0.0; names.len()];
            law.state_output(&trial, &mut values);
            let det = crate::multiplicative::read_sym(&trial[..CP_INV_LEN]).determinant();
            let theta = law.volumetric_strain(ln_j, &trial);
            println!(
                "u–p apex, ln J = {ln_j}, p = {pressure} Pa: plastic dilation {:.3e} (expected {expected:.3e}), \
                 det Cp⁻¹ {det:.6}, next step's θ {theta:.1e}",
                values[volumetric]
            );
            assert!((values[volumetric] - expected).abs() < 1e-12);
            assert!((det - (-2.0 * expected).exp()).abs() < 1e-12);
            assert!((theta - (ln_j - expected)).abs() < 1e-12);
        }
    }
}
