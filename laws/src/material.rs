//! Material definitions as written in case files, their parameter checks, and the
//! construction of the law objects.
//!
//! A material is a JSON object tagged by `"law"`:
//! `{"law": "neo_hookean", "density": 1000, "young_modulus": 9e7, "poisson_ratio": 0.0}`.
//! Unknown keys are rejected by serde; ranges are checked by [`MaterialSpec::build`].
//! Angles are in degrees in the case file and radians inside the laws.

use serde::Deserialize;

use crate::drucker_prager::{DruckerPrager, DruckerPragerFit};
use crate::hencky::Hencky;
use crate::linear_elastic::LinearElastic;
use crate::modified_cam_clay::ModifiedCamClay;
use crate::mohr_coulomb::{MohrCoulomb, Strength};
use crate::mohr_coulomb_softening::{ExponentialSoftening, MohrCoulombSoftening};
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
    /// Range checks: ρ > 0, E > 0, −1 < ν < 0.5.
    pub fn check(&self) -> Result<(), ParameterError> {
        positive("density", self.density)?;
        positive("young_modulus", self.young_modulus)?;
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
    non_negative(cohesion_key, cohesion)?;
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
                non_negative("shape_factor", p.shape_factor)?;
                Box::new(MohrCoulombSoftening::new(
                    p.density,
                    p.young_modulus,
                    p.poisson_ratio,
                    ExponentialSoftening { peak, residual, shape_factor: p.shape_factor },
                ))
            }
            MaterialSpec::ModifiedCamClay(p) => {
                positive("density", p.density)?;
                positive("preconsolidation_pressure", p.preconsolidation_pressure)?;
                if !(p.ocr >= 1.0 && p.ocr.is_finite()) {
                    return Err(ParameterError::new("ocr", format!("must be >= 1, got {}", p.ocr)));
                }
                positive("swelling_slope", p.swelling_slope)?;
                if !(p.compression_slope > p.swelling_slope && p.compression_slope.is_finite()) {
                    return Err(ParameterError::new(
                        "compression_slope",
                        format!("must exceed swelling_slope ({}), got {}", p.swelling_slope, p.compression_slope),
                    ));
                }
                positive("critical_state_slope", p.critical_state_slope)?;
                non_negative("initial_shear_modulus", p.initial_shear_modulus)?;
                non_negative("alpha_shear", p.alpha_shear)?;
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
            MaterialSpec::NewtonianFluid(p) => {
                positive("density", p.density)?;
                non_negative("viscosity", p.viscosity)?;
                positive("bulk_modulus", p.bulk_modulus)?;
                Box::new(NewtonianFluid { density: p.density, viscosity: p.viscosity, bulk_modulus: p.bulk_modulus })
            }
        })
    }
}
