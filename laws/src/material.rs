//! Material definitions as written in case files, their parameter checks, and the
//! construction of the law objects.
//!
//! A material is a JSON object tagged by `"law"`:
//! `{"law": "neo_hookean", "density": 1000, "young_modulus": 9e7, "poisson_ratio": 0.0}`.
//! Unknown keys are rejected by serde; ranges are checked by [`MaterialSpec::build`].

use serde::Deserialize;

use crate::neo_hookean::NeoHookean;
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
}

/// Checks that a parameter is finite and strictly positive.
pub fn positive(parameter: &'static str, value: f64) -> Result<(), ParameterError> {
    if value > 0.0 && value.is_finite() {
        Ok(())
    } else {
        Err(ParameterError::new(parameter, format!("must be > 0, got {value}")))
    }
}

/// A material as written in a case file, tagged by its `law`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialSpec {
    /// Compressible Neo-Hookean hyperelasticity ([`NeoHookean`]).
    NeoHookean(ElasticParameters),
}

impl MaterialSpec {
    /// Checks the parameters and builds the law. The error names the offending key.
    pub fn build(&self) -> Result<Box<dyn ConstitutiveLaw>, ParameterError> {
        match self {
            MaterialSpec::NeoHookean(p) => {
                p.check()?;
                Ok(Box::new(NeoHookean::new(p.density, p.young_modulus, p.poisson_ratio)))
            }
        }
    }
}
