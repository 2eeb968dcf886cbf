//! Material definitions as written in case files, their parameter checks, and the
//! construction of the law objects.
//!
//! A material is a JSON object tagged by `"law"`:
//! `{"law": "neo_hookean", "density": 1000, "young_modulus": 9e7, "poisson_ratio": 0.0}`.
//! Unknown keys are rejected by serde; ranges are checked by [`MaterialSpec::build`].
//! Angles are in degrees in the case file and radians inside the laws.
//!
//! **Physical bounds.** Besides its sign, every modulus-like parameter must lie in a range
//! that any material on Earth fits with orders of magnitude to spare ([`Range`]): moduli,
//! pressures and cohesions in [1e-3, 1e15] Pa ([`MODULUS`], [`PRESSURE`], [`COHESION`]),
//! densities in [1e-3, 1e5] kg/m³ ([`DENSITY`]), viscosities up to 1e15 Pa·s
//! ([`VISCOSITY`]), and the dimensionless ones of Cam Clay and of softening likewise. A
//! value outside is a typing error or a hostile input, and it fails later with a message
//! that hides the cause (issue 31: `E = 1e-320`, a subnormal, gave `det F = NaN`;
//! `E = 1e308` an initial stress "outside the yield surface"): it is refused when the case
//! is loaded, naming the key.

use serde::Deserialize;

use crate::drucker_prager::{DruckerPrager, DruckerPragerFit};
use crate::hencky::Hencky;
use crate::linear_elastic::LinearElastic;
use crate::modified_cam_clay::ModifiedCamClay;
use crate::mohr_coulomb::{MohrCoulomb, Strength};
use crate::mohr_coulomb_softening::{ExponentialSoftening, MohrCoulombSoftening};
use crate::mu_i::MuI;
use crate::neo_hookean::NeoHookean;
use crate::newtonian_fluid::NewtonianFluid;
use crate::saint_venant_kirchhoff::SaintVenantKirchhoff;
use crate::{ConstitutiveLaw, ParameterError};

/// Lamé constants `(λ, μ)` from Young's modulus and Poisson's ratio:
/// `λ = E ν / ((1+ν)(1−2ν))`, `μ = E / (2(1+ν))`.
pub fn lame(young_modulus: f64, poisson_ratio: f64) -> (f64, f64) {
    let (e, nu) = (young_modulus, poisson_ratio);
    (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)))
}

/// Isotropic elastic parameters shared by the elastic and elasto-plastic laws.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElasticParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Young's modulus E in Pa (> 0).
    pub young_modulus: f64,
    /// Poisson's ratio ν in (−1, 0.5).
    pub poisson_ratio: f64,
}

impl ElasticParameters {
    /// Range checks: ρ in [`DENSITY`], E in [`MODULUS`], −1 < ν < 0.5.
    pub fn check(&self) -> Result<(), ParameterError> {
        in_range("density", self.density, DENSITY)?;
        in_range("young_modulus", self.young_modulus, MODULUS)?;
        let nu = self.poisson_ratio;
        if !(nu > -1.0 && nu < 0.5) {
            return Err(ParameterError::new("poisson_ratio", format!("must lie in (-1, 0.5), got {nu}")));
        }
        Ok(())
    }

    /// Range checks of a law with a u–p form: as [`ElasticParameters::check`], and `ν = 0.5`
    /// (incompressible, `λ = ∞`; only the mixed u–p formulation accepts it).
    pub fn check_up_to_incompressible(&self) -> Result<(), ParameterError> {
        if self.poisson_ratio == 0.5 {
            return ElasticParameters { poisson_ratio: 0.0, ..*self }.check();
        }
        self.check().map_err(|e| match e.parameter {
            "poisson_ratio" => ParameterError::new(
                "poisson_ratio",
                format!("must lie in (-1, 0.5] (0.5: incompressible, mixed_up only), got {}", self.poisson_ratio),
            ),
            _ => e,
        })
    }
}

/// Checks that a parameter is finite and strictly positive.
pub fn positive(parameter: &'static str, value: f64) -> Result<(), ParameterError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ParameterError::new(parameter, format!("must be > 0, got {value}")))
    }
}

/// Checks that a parameter is finite and non-negative.
pub fn non_negative(parameter: &'static str, value: f64) -> Result<(), ParameterError> {
    if value >= 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ParameterError::new(parameter, format!("must be >= 0, got {value}")))
    }
}

/// The values a material parameter may take: `[min, max]` in `unit`, and 0 if `zero`
/// (see the module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    /// Smallest nonzero value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Whether 0 is allowed (then the parameter is ≥ 0, else > 0).
    pub zero: bool,
    /// Unit, for the message (empty when dimensionless).
    pub unit: &'static str,
    /// Why values below `min` are refused.
    pub why_min: &'static str,
    /// Why values above `max` are refused.
    pub why_max: &'static str,
}

/// Young's, bulk and shear moduli (Pa): the softest gels have about 10 Pa, diamond 1.2e12 Pa.
pub const MODULUS: Range = Range {
    min: 1e-3,
    max: 1e15,
    zero: false,
    unit: "Pa",
    why_min: "softer than any solid by orders of magnitude: the stresses would underflow",
    why_max: "a thousand times stiffer than diamond",
};

/// A shear modulus that may be 0 when another term gives the stiffness (Pa).
pub const MODULUS_OR_ZERO: Range = Range { zero: true, ..MODULUS };

/// Pressures of a law (Pa), e.g. the preconsolidation pressure.
pub const PRESSURE: Range = Range {
    why_min: "far below any stress of a soil: the stiffness, proportional to it, would underflow",
    why_max: "a thousand times the pressure at the centre of the Earth",
    ..MODULUS
};

/// Cohesions (Pa): 0 for a granular material; any normal positive value up to `max`.
pub const COHESION: Range = Range {
    min: f64::MIN_POSITIVE,
    max: 1e15,
    zero: true,
    unit: "Pa",
    why_min: "a subnormal number",
    why_max: "a thousand times the strength of diamond",
};

/// Densities (kg/m³): air has 1.2, osmium 22 590.
pub const DENSITY: Range = Range {
    min: 1e-3,
    max: 1e5,
    zero: false,
    unit: "kg/m³",
    why_min: "a thousandth of the density of air",
    why_max: "four times the densest element",
};

/// Dynamic viscosities (Pa·s): air has 1.8e-5, pitch about 1e8, glacier ice 1e13.
pub const VISCOSITY: Range = Range {
    min: 1e-9,
    max: 1e15,
    zero: true,
    unit: "Pa·s",
    why_min: "ten thousand times less viscous than any gas",
    why_max: "a hundred times more viscous than glacier ice",
};

/// Dimensionless slopes and factors of Cam Clay and of softening.
pub const FACTOR: Range = Range {
    min: 1e-6,
    max: 1e6,
    zero: false,
    unit: "",
    why_min: "too small to compute with",
    why_max: "too large to compute with",
};

/// Slopes `κ̂`, `λ̂` of Cam Clay in ln v – ln p′: clays have 0.005 to 0.5.
pub const SLOPE: Range =
    Range { max: 10.0, why_max: "a specific volume that would change e¹⁰-fold per e-fold of pressure", ..FACTOR };

/// The critical state slope `M = 6 sin φ/(3 − sin φ)` of Cam Clay, below 3 for φ < 90°.
pub const CRITICAL_STATE_SLOPE: Range =
    Range { max: 3.0, why_max: "M = 6 sin φ/(3 − sin φ) < 3 for any friction angle", ..FACTOR };

/// Friction coefficients `μ = tan θ` of the μ(I) law: above 0 (a cohesionless material
/// without friction has no strength at rest), at most 10 (θ = 84°; no granular material
/// comes near, and an angle in degrees typed by mistake is refused).
pub const FRICTION_COEFFICIENT: Range = Range {
    min: 1e-3,
    max: 10.0,
    zero: false,
    unit: "",
    why_min: "a friction angle below 0.06°: a granular material without strength at rest",
    why_max: "tan 84°: a coefficient tan θ, not an angle in degrees",
};

/// Grain diameters (m): fine powders have 1e-6, boulders 1.
pub const GRAIN_DIAMETER: Range = Range {
    min: 1e-9,
    max: 100.0,
    zero: false,
    unit: "m",
    why_min: "a nanometre: a molecule, not a grain",
    why_max: "larger than any boulder",
};

/// Checks that `value` lies in `range` (see [`Range`]); the message says which bound it
/// breaks and why.
pub fn in_range(parameter: &'static str, value: f64, range: Range) -> Result<(), ParameterError> {
    if value == 0.0 && range.zero {
        return Ok(());
    }
    let unit = if range.unit.is_empty() { String::new() } else { format!(" {}", range.unit) };
    let got = number(value);
    let problem = if !(value > 0.0 && value.is_finite()) {
        format!("must be {} 0, got {got}", if range.zero { ">=" } else { ">" })
    } else if value < range.min {
        let zero = if range.zero { "0 or " } else { "" };
        format!("must be {zero}at least {}{unit} ({}), got {got}", number(range.min), range.why_min)
    } else if value > range.max {
        format!("must be at most {}{unit} ({}), got {got}", number(range.max), range.why_max)
    } else {
        return Ok(());
    };
    Err(ParameterError::new(parameter, problem))
}

/// A number for a message: as written if short (`0.02`, `3`), in exponent form otherwise
/// (`1e-320`, `1e308`, `2.2e-308`; Rust prints 1e308 with 308 zeros).
fn number(v: f64) -> String {
    let plain = format!("{v}");
    if plain.len() <= 6 {
        return plain;
    }
    let exp = format!("{v:e}");
    if exp.len() <= 10 {
        exp
    } else {
        format!("{v:.1e}")
    }
}

/// Mohr–Coulomb strength parameters (angles in degrees) and their checks:
/// `0 ≤ φ < 90°`, `c ≥ 0`, not both zero, `0 ≤ ψ ≤ φ`.
fn check_strength(
    (friction_key, friction_angle): (&'static str, f64),
    (cohesion_key, cohesion): (&'static str, f64),
    (dilatancy_key, dilatancy_angle): (&'static str, f64),
) -> Result<Strength<f64>, ParameterError> {
    if !(0.0..90.0).contains(&friction_angle) {
        return Err(ParameterError::new(friction_key, format!("must lie in [0, 90) degrees, got {friction_angle}")));
    }
    in_range(cohesion_key, cohesion, COHESION)?;
    if friction_angle == 0.0 && cohesion == 0.0 {
        return Err(ParameterError::new(
            friction_key,
            format!("must be > 0 when {cohesion_key} = 0 (the material would have no strength)"),
        ));
    }
    if dilatancy_angle.is_nan() || dilatancy_angle < 0.0 {
        return Err(ParameterError::new(dilatancy_key, format!("must be >= 0 degrees, got {dilatancy_angle}")));
    }
    if dilatancy_angle > friction_angle {
        return Err(ParameterError::new(
            dilatancy_key,
            format!("must not exceed {friction_key} ({friction_angle}), got {dilatancy_angle}"),
        ));
    }
    Ok(Strength {
        friction_angle: friction_angle.to_radians(),
        cohesion,
        dilatancy_angle: dilatancy_angle.to_radians(),
    })
}

/// Mohr–Coulomb parameters (`law: "mohr_coulomb"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MohrCoulombParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Young's modulus E in Pa (> 0).
    pub young_modulus: f64,
    /// Poisson's ratio ν in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Friction angle φ in degrees, [0, 90).
    pub friction_angle: f64,
    /// Cohesion c in Pa (≥ 0; > 0 if φ = 0).
    pub cohesion: f64,
    /// Dilatancy angle ψ in degrees, [0, φ].
    pub dilatancy_angle: f64,
}

/// Mohr–Coulomb strain-softening parameters (`law: "mohr_coulomb_softening"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MohrCoulombSofteningParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Young's modulus E in Pa (> 0).
    pub young_modulus: f64,
    /// Poisson's ratio ν in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Peak friction angle in degrees.
    pub peak_friction_angle: f64,
    /// Residual friction angle in degrees (≤ peak).
    pub residual_friction_angle: f64,
    /// Peak cohesion in Pa.
    pub peak_cohesion: f64,
    /// Residual cohesion in Pa (≤ peak).
    pub residual_cohesion: f64,
    /// Peak dilatancy angle in degrees.
    pub peak_dilatancy_angle: f64,
    /// Residual dilatancy angle in degrees (≤ peak).
    pub residual_dilatancy_angle: f64,
    /// Shape factor β of the exponential decay with the accumulated plastic deviatoric strain (≥ 0).
    pub shape_factor: f64,
}

/// Modified Cam Clay parameters (`law: "modified_cam_clay"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModifiedCamClayParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Preconsolidation pressure p′c in Pa (> 0, compression positive).
    pub preconsolidation_pressure: f64,
    /// Overconsolidation ratio OCR = p′c/p₀ (≥ 1); `p₀ = p′c/OCR` is the reference pressure.
    pub ocr: f64,
    /// Swelling slope κ̂ in ln v – ln p′ (> 0).
    pub swelling_slope: f64,
    /// Compression slope λ̂ in ln v – ln p′ (> κ̂).
    pub compression_slope: f64,
    /// Critical state slope M (> 0).
    pub critical_state_slope: f64,
    /// Initial shear modulus μ₀ in Pa (≥ 0; μ₀ + α p₀ > 0).
    pub initial_shear_modulus: f64,
    /// Pressure coupling α of the shear modulus (≥ 0), `μ = μ₀ + α p₀ exp(ε_v^e/κ̂)`.
    pub alpha_shear: f64,
}

/// Drucker–Prager parameters (`law: "drucker_prager"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DruckerPragerParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Young's modulus E in Pa (> 0).
    pub young_modulus: f64,
    /// Poisson's ratio ν in (−1, 0.5).
    pub poisson_ratio: f64,
    /// Mohr–Coulomb friction angle φ in degrees, [0, 90).
    pub friction_angle: f64,
    /// Mohr–Coulomb cohesion c in Pa (≥ 0).
    pub cohesion: f64,
    /// Mohr–Coulomb dilatancy angle ψ in degrees, [0, φ].
    pub dilatancy_angle: f64,
    /// Fit of the cone to Mohr–Coulomb: `outer`, `inner` or `plane_strain`.
    pub fit: DruckerPragerFit,
}

/// μ(I) granular-flow parameters (`law: "mu_i"`, Jop, Forterre & Pouliquen 2006).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MuIParameters {
    /// Bulk density ρ₀ of the granular material in kg/m³ (> 0).
    pub density: f64,
    /// Young's modulus E of the solid-like (elastic) response in Pa (> 0).
    pub young_modulus: f64,
    /// Poisson's ratio ν in (−1, 0.5] (0.5 in mixed_up only).
    pub poisson_ratio: f64,
    /// Static friction coefficient μ_s = tan θ_s (the ratio τ̄/p at rest), in (0, 10].
    pub static_friction_coefficient: f64,
    /// Limit friction coefficient μ₂ = tan θ₂ of fast flow (> μ_s), at most 10.
    pub limit_friction_coefficient: f64,
    /// Reference inertial number I₀ (> 0) at which μ is halfway between μ_s and μ₂.
    pub reference_inertial_number: f64,
    /// Grain diameter d in m (> 0).
    pub grain_diameter: f64,
    /// Grain (solid) density ρ_s in kg/m³ (> 0).
    pub grain_density: f64,
}

/// Newtonian fluid parameters (`law: "newtonian_fluid"`).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewtonianFluidParameters {
    /// Density ρ₀ in kg/m³ (> 0).
    pub density: f64,
    /// Dynamic viscosity η in Pa·s (≥ 0).
    pub viscosity: f64,
    /// Bulk modulus K in Pa (> 0).
    pub bulk_modulus: f64,
}

/// A material as written in a case file, tagged by its `law`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// Small-strain linear elasticity ([`LinearElastic`]).
    LinearElastic(ElasticParameters),
    /// St Venant–Kirchhoff, large rotations ([`SaintVenantKirchhoff`]).
    SaintVenantKirchhoff(ElasticParameters),
    /// Compressible Neo-Hookean hyperelasticity ([`NeoHookean`]).
    NeoHookean(ElasticParameters),
    /// Hencky (logarithmic strain) hyperelasticity ([`Hencky`]).
    Hencky(ElasticParameters),
    /// Mohr–Coulomb at finite strain ([`MohrCoulomb`]).
    MohrCoulomb(MohrCoulombParameters),
    /// Mohr–Coulomb with exponential strain softening ([`MohrCoulombSoftening`]).
    MohrCoulombSoftening(MohrCoulombSofteningParameters),
    /// Modified Cam Clay at finite strain ([`ModifiedCamClay`]).
    ModifiedCamClay(ModifiedCamClayParameters),
    /// Drucker–Prager matched to Mohr–Coulomb ([`DruckerPrager`]).
    DruckerPrager(DruckerPragerParameters),
    /// The μ(I) rheology of dense granular flow ([`MuI`]).
    MuI(MuIParameters),
    /// Newtonian fluid ([`NewtonianFluid`]).
    NewtonianFluid(NewtonianFluidParameters),
}

impl MaterialSpec {
    /// Checks the parameters and builds the law. The error names the offending key.
    pub fn build(&self) -> Result<Box<dyn ConstitutiveLaw>, ParameterError> {
        let elastic = |density, young_modulus, poisson_ratio| {
            ElasticParameters { density, young_modulus, poisson_ratio }.check_up_to_incompressible()
        };
        Ok(match *self {
            MaterialSpec::LinearElastic(p) => {
                p.check()?;
                Box::new(LinearElastic::new(p.density, p.young_modulus, p.poisson_ratio))
            }
            MaterialSpec::SaintVenantKirchhoff(p) => {
                p.check()?;
                Box::new(SaintVenantKirchhoff::new(p.density, p.young_modulus, p.poisson_ratio))
            }
            MaterialSpec::NeoHookean(p) => {
                p.check_up_to_incompressible()?;
                Box::new(NeoHookean::new(p.density, p.young_modulus, p.poisson_ratio))
            }
            MaterialSpec::Hencky(p) => {
                p.check_up_to_incompressible()?;
                Box::new(Hencky::new(p.density, p.young_modulus, p.poisson_ratio))
            }
            MaterialSpec::MohrCoulomb(p) => {
                elastic(p.density, p.young_modulus, p.poisson_ratio)?;
                let s = check_strength(
                    ("friction_angle", p.friction_angle),
                    ("cohesion", p.cohesion),
                    ("dilatancy_angle", p.dilatancy_angle),
                )?;
                Box::new(MohrCoulomb::new(
                    p.density,
                    p.young_modulus,
                    p.poisson_ratio,
                    s.friction_angle,
                    s.cohesion,
                    s.dilatancy_angle,
                ))
            }
            MaterialSpec::MohrCoulombSoftening(p) => {
                elastic(p.density, p.young_modulus, p.poisson_ratio)?;
                let peak = check_strength(
                    ("peak_friction_angle", p.peak_friction_angle),
                    ("peak_cohesion", p.peak_cohesion),
                    ("peak_dilatancy_angle", p.peak_dilatancy_angle),
                )?;
                let residual = check_strength(
                    ("residual_friction_angle", p.residual_friction_angle),
                    ("residual_cohesion", p.residual_cohesion),
                    ("residual_dilatancy_angle", p.residual_dilatancy_angle),
                )?;
                for (key, r, pk) in [
                    ("residual_friction_angle", p.residual_friction_angle, p.peak_friction_angle),
                    ("residual_cohesion", p.residual_cohesion, p.peak_cohesion),
                    ("residual_dilatancy_angle", p.residual_dilatancy_angle, p.peak_dilatancy_angle),
                ] {
                    if r > pk {
                        return Err(ParameterError::new(key, format!("must not exceed its peak value {pk}, got {r}")));
                    }
                }
                in_range("shape_factor", p.shape_factor, Range { zero: true, ..FACTOR })?;
                Box::new(MohrCoulombSoftening::new(
                    p.density,
                    p.young_modulus,
                    p.poisson_ratio,
                    ExponentialSoftening { peak, residual, shape_factor: p.shape_factor },
                ))
            }
            MaterialSpec::ModifiedCamClay(p) => {
                in_range("density", p.density, DENSITY)?;
                in_range("preconsolidation_pressure", p.preconsolidation_pressure, PRESSURE)?;
                if !(p.ocr >= 1.0 && p.ocr <= FACTOR.max) {
                    return Err(ParameterError::new(
                        "ocr",
                        format!("must lie in [1, {:e}], got {}", FACTOR.max, p.ocr),
                    ));
                }
                in_range("swelling_slope", p.swelling_slope, SLOPE)?;
                if !(p.compression_slope > p.swelling_slope && p.compression_slope.is_finite()) {
                    return Err(ParameterError::new(
                        "compression_slope",
                        format!("must exceed swelling_slope ({}), got {}", p.swelling_slope, p.compression_slope),
                    ));
                }
                in_range("compression_slope", p.compression_slope, SLOPE)?;
                in_range("critical_state_slope", p.critical_state_slope, CRITICAL_STATE_SLOPE)?;
                in_range("initial_shear_modulus", p.initial_shear_modulus, MODULUS_OR_ZERO)?;
                in_range("alpha_shear", p.alpha_shear, Range { zero: true, ..FACTOR })?;
                if p.initial_shear_modulus + p.alpha_shear * p.preconsolidation_pressure / p.ocr <= 0.0 {
                    return Err(ParameterError::new(
                        "initial_shear_modulus",
                        "must be > 0 when alpha_shear = 0 (no shear stiffness)",
                    ));
                }
                Box::new(ModifiedCamClay {
                    density: p.density,
                    preconsolidation_pressure: p.preconsolidation_pressure,
                    ocr: p.ocr,
                    swelling_slope: p.swelling_slope,
                    compression_slope: p.compression_slope,
                    critical_state_slope: p.critical_state_slope,
                    initial_shear_modulus: p.initial_shear_modulus,
                    alpha_shear: p.alpha_shear,
                })
            }
            MaterialSpec::DruckerPrager(p) => {
                elastic(p.density, p.young_modulus, p.poisson_ratio)?;
                let s = check_strength(
                    ("friction_angle", p.friction_angle),
                    ("cohesion", p.cohesion),
                    ("dilatancy_angle", p.dilatancy_angle),
                )?;
                Box::new(DruckerPrager::new(
                    p.density,
                    p.young_modulus,
                    p.poisson_ratio,
                    s.friction_angle,
                    s.cohesion,
                    s.dilatancy_angle,
                    p.fit,
                ))
            }
            MaterialSpec::MuI(p) => {
                elastic(p.density, p.young_modulus, p.poisson_ratio)?;
                in_range("static_friction_coefficient", p.static_friction_coefficient, FRICTION_COEFFICIENT)?;
                in_range("limit_friction_coefficient", p.limit_friction_coefficient, FRICTION_COEFFICIENT)?;
                if p.limit_friction_coefficient <= p.static_friction_coefficient {
                    return Err(ParameterError::new(
                        "limit_friction_coefficient",
                        format!(
                            "must exceed static_friction_coefficient ({}), got {}",
                            p.static_friction_coefficient, p.limit_friction_coefficient
                        ),
                    ));
                }
                in_range("reference_inertial_number", p.reference_inertial_number, FACTOR)?;
                in_range("grain_diameter", p.grain_diameter, GRAIN_DIAMETER)?;
                in_range("grain_density", p.grain_density, DENSITY)?;
                Box::new(MuI::new(
                    p.density,
                    p.young_modulus,
                    p.poisson_ratio,
                    p.static_friction_coefficient,
                    p.limit_friction_coefficient,
                    p.reference_inertial_number,
                    p.grain_diameter,
                    p.grain_density,
                ))
            }
            MaterialSpec::NewtonianFluid(p) => {
                in_range("density", p.density, DENSITY)?;
                in_range("viscosity", p.viscosity, VISCOSITY)?;
                in_range("bulk_modulus", p.bulk_modulus, MODULUS)?;
                Box::new(NewtonianFluid { density: p.density, viscosity: p.viscosity, bulk_modulus: p.bulk_modulus })
            }
        })
    }
}
