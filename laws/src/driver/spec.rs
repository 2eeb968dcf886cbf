//! The path file: what a laboratory test looks like in JSON.
//!
//! ```json
//! {
//!   "description": "drained triaxial compression of a Mohr-Coulomb sand",
//!   "material": {"law": "mohr_coulomb", "density": 2000, "young_modulus": 5e7,
//!                "poisson_ratio": 0.3, "friction_angle": 25, "cohesion": 5e3,
//!                "dilatancy_angle": 0},
//!   "initial_stress": {"isotropic": 1e5},
//!   "time_step": 1.0,
//!   "path": {"type": "triaxial", "drainage": "drained", "loading": "compression",
//!            "confining_pressure": 1e5, "axial_strain": 0.05, "steps": 200}
//! }
//! ```
//!
//! `initial_stress` and `time_step` are optional: without `initial_stress` the point starts
//! from the law's virgin state; without `time_step` the steps are static (`Δt = 0`).
//! Stresses are Cauchy stresses in Pa; pressures (`confining_pressure`, `final_pressure`,
//! `vertical_stress`, `isotropic`) are compression positive; strain magnitudes
//! (`axial_strain`, `shear_strain`) are positive. The axial (vertical) direction is `y`.

use serde::Deserialize;

use crate::MaterialSpec;

/// A path file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathFile {
    /// What the test shows.
    pub description: String,
    /// The material, as in a case file.
    pub material: MaterialSpec,
    /// Stress at rest before the path (optional; default: the law's virgin state).
    #[serde(default)]
    pub initial_stress: Option<InitialStress>,
    /// Time step Δt in s of every step (optional; default 0, static), used by rate laws.
    #[serde(default)]
    pub time_step: Option<f64>,
    /// The loading path.
    pub path: PathSpec,
}

/// Initial Cauchy stress at rest.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum InitialStress {
    /// Isotropic pressure p in Pa, compression positive: `σ = −p I`.
    Isotropic(f64),
    /// Geostatic state: vertical (y) effective stress σ_v in Pa (compression positive) and
    /// `σ_h = K0 σ_v` horizontally.
    Geostatic {
        /// Vertical stress σ_v in Pa, compression positive.
        vertical_stress: f64,
        /// Coefficient of earth pressure at rest K0 (> 0).
        k0: f64,
    },
    /// Full Cauchy stress `[σxx, σyy, σzz, σxy, σyz, σxz]` in Pa, tension positive.
    Components([f64; 6]),
}

/// Drainage condition of a triaxial test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drainage {
    /// Lateral Cauchy stress held at the confining pressure (mixed control).
    Drained,
    /// Isochoric (incompressible pore fluid): volume held constant, effective stresses output.
    Undrained,
}

/// Direction of the axial strain in a triaxial test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Loading {
    /// Axial shortening.
    Compression,
    /// Axial lengthening.
    Extension,
}

/// The loading path, tagged by `type`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum PathSpec {
    /// Isotropic consolidation to the confining pressure, then axial strain at constant
    /// lateral stress (drained) or constant volume (undrained).
    Triaxial {
        /// Drained or undrained.
        drainage: Drainage,
        /// Compression or extension.
        loading: Loading,
        /// Confining (cell) pressure σ₃ in Pa, compression positive.
        confining_pressure: f64,
        /// Target axial logarithmic strain magnitude, in (0, 1).
        axial_strain: f64,
        /// Number of steps of the shearing stage (≥ 1).
        steps: usize,
    },
    /// Axial compression with zero lateral strain.
    Oedometric {
        /// Target axial logarithmic strain magnitude, in (0, 1).
        axial_strain: f64,
        /// Number of steps (≥ 1).
        steps: usize,
    },
    /// Stress-controlled isotropic compression to a final pressure.
    IsotropicCompression {
        /// Final pressure p in Pa, compression positive (> 0).
        final_pressure: f64,
        /// Number of steps (≥ 1).
        steps: usize,
    },
    /// Simple shear `F = (I + γ e_x ⊗ e_y) F₀`; at constant height, or at constant vertical
    /// stress (after oedometric loading to it) when `vertical_stress` is given.
    SimpleShear {
        /// Target engineering shear strain γ, in (0, 10].
        shear_strain: f64,
        /// Number of steps (≥ 1).
        steps: usize,
        /// Constant vertical stress σ_v in Pa, compression positive (optional).
        #[serde(default)]
        vertical_stress: Option<f64>,
    },
    /// A user table of displacement-gradient increments `ΔH` (row-major 3×3), applied as
    /// `F_{n+1} = (I + ΔH) F_n`, one row per step.
    StrainIncrements {
        /// The increments.
        increments: Vec<[f64; 9]>,
    },
}
