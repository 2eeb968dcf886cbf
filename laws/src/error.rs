//! Errors of constitutive laws: failures during a stress update and bad parameters.

use thiserror::Error;

/// A stress update that could not be carried out at one integration point.
#[derive(Debug, Clone, Error, PartialEq)]
pub enum LawError {
    /// `det F ≤ 0`: the material point or element has been inverted.
    #[error("inverted deformation gradient (det F = {det_f:.3e})")]
    InvertedDeformation {
        /// The offending Jacobian.
        det_f: f64,
    },
    /// The local return mapping did not converge.
    #[error("return mapping did not converge after {iterations} iterations (residual {residual:.3e})")]
    ReturnMappingFailed {
        /// Local iterations spent.
        iterations: usize,
        /// Last local residual.
        residual: f64,
    },
    /// An initial stress that the law cannot represent or that violates its yield condition.
    #[error("initial stress: {problem}")]
    InitialStress {
        /// What is wrong.
        problem: String,
    },
}

/// A material parameter outside its admissible range, found when a case is loaded.
#[derive(Debug, Clone, Error, PartialEq)]
#[error("{parameter}: {problem}")]
pub struct ParameterError {
    /// The parameter's key in the case file, e.g. `poisson_ratio`.
    pub parameter: &'static str,
    /// What is wrong with it, e.g. `must lie in (-1, 0.5), got 0.5`.
    pub problem: String,
}

impl ParameterError {
    /// Shorthand used by the parameter checks.
    pub fn new(parameter: &'static str, problem: impl Into<String>) -> Self {
        Self { parameter, problem: problem.into() }
    }
}
