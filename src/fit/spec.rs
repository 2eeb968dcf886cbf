//! The fit file (`loam fit FIT.json`): a material block with starting values, the
//! parameters to fit with their bounds, and the laboratory tests with their measured curves.
//!
//! ```json
//! {
//!   "description": "three drained triaxial tests on a sand",
//!   "material": {"law": "mohr_coulomb", "density": 2000, "young_modulus": 3e7,
//!                "poisson_ratio": 0.3, "friction_angle": 25, "cohesion": 5e3,
//!                "dilatancy_angle": 0},
//!   "fit": [{"name": "friction_angle", "min": 10, "max": 50},
//!           {"name": "cohesion", "min": 0, "max": 1e5}],
//!   "tests": [{
//!     "name": "s3_100kPa",
//!     "path": {"type": "triaxial", "drainage": "drained", "loading": "compression",
//!              "confining_pressure": 1e5, "axial_strain": 0.1, "steps": 200},
//!     "data": "s3_100kPa.csv",
//!     "x": {"column": "axial_strain_percent", "quantity": "axial_strain", "unit": "%", "sign": -1},
//!     "curves": [{"column": "q_kPa", "quantity": "q", "unit": "kPa"}],
//!     "weight": 1
//!   }]
//! }
//! ```
//!
//! The starting value of each fitted parameter is its value in `material`; every other key
//! of `material` is held fixed. A test is a `loam law` path (`path`, and optionally
//! `initial_stress`, `time_step`) with a CSV file (`data`, relative to the fit file). Each
//! column names the `path.csv` column it measures (`quantity`), the unit of the CSV values
//! and their sign: CSV value = `sign` × driver value / unit (the driver's strains are
//! extension positive, so a compression-positive axial strain has `"sign": -1`).

use serde::Deserialize;
use serde_json::{Map, Value};

use loam_laws::driver::{InitialStress, PathSpec};

/// A fit file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitFile {
    /// What is fitted to what, and where the data come from.
    pub description: String,
    /// The material block, as in a case file; the fitted parameters' values are the starting point.
    pub material: Map<String, Value>,
    /// The parameters to fit, with their bounds.
    pub fit: Vec<FitParameter>,
    /// The laboratory tests.
    pub tests: Vec<LabTest>,
    /// Settings of the least-squares solver (optional).
    #[serde(default)]
    pub solver: SolverSettings,
}

/// A fitted parameter: a numeric key of the material block and its bounds `[min, max]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitParameter {
    /// The material key, e.g. `friction_angle`.
    pub name: String,
    /// Lower bound, in the key's unit.
    pub min: f64,
    /// Upper bound (> min), in the key's unit.
    pub max: f64,
}

/// One laboratory test: a `loam law` path and its measured curves.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabTest {
    /// A name for the test (reports, fit.csv, legends).
    pub name: String,
    /// Stress at rest before the path (optional, as in a path file).
    #[serde(default)]
    pub initial_stress: Option<InitialStress>,
    /// Δt of every step in s (optional, as in a path file).
    #[serde(default)]
    pub time_step: Option<f64>,
    /// The loading path, as in a path file.
    pub path: PathSpec,
    /// The measured CSV file, relative to the fit file.
    pub data: String,
    /// The abscissa: the CSV column and the driver quantity it measures.
    pub x: Column,
    /// The measured ordinates (at least one).
    pub curves: Vec<Column>,
    /// Weight `w` of the test in the sum of squares (> 0).
    pub weight: f64,
}

/// A CSV column and the `path.csv` quantity it measures.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Column {
    /// Name of the column in the CSV header.
    pub column: String,
    /// Name of the `path.csv` column, e.g. `axial_strain`, `q`, `volumetric_strain`.
    pub quantity: String,
    /// Unit of the CSV values.
    pub unit: Unit,
    /// CSV value = sign × driver value / unit: `1` (default) or `-1`.
    #[serde(default = "plus_one")]
    pub sign: f64,
}

fn plus_one() -> f64 {
    1.0
}

/// Units of measured columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
pub enum Unit {
    /// A dimensionless quantity (strain, J, state variables) as a number.
    #[serde(rename = "1")]
    One,
    /// A dimensionless quantity in per cent.
    #[serde(rename = "%")]
    Percent,
    /// Pascal.
    #[serde(rename = "Pa")]
    Pa,
    /// Kilopascal.
    #[serde(rename = "kPa")]
    KPa,
    /// Megapascal.
    #[serde(rename = "MPa")]
    MPa,
}

impl Unit {
    /// The unit in SI: value in SI = CSV value × factor.
    pub fn factor(self) -> f64 {
        match self {
            Unit::One | Unit::Pa => 1.0,
            Unit::Percent => 0.01,
            Unit::KPa => 1e3,
            Unit::MPa => 1e6,
        }
    }

    /// Whether the unit is a stress.
    pub fn is_stress(self) -> bool {
        matches!(self, Unit::Pa | Unit::KPa | Unit::MPa)
    }

    /// The unit as written in the fit file.
    pub fn label(self) -> &'static str {
        match self {
            Unit::One => "1",
            Unit::Percent => "%",
            Unit::Pa => "Pa",
            Unit::KPa => "kPa",
            Unit::MPa => "MPa",
        }
    }
}

/// Whether the `path.csv` column `quantity` is a stress (Pa): `p`, `q`, `sigma_*` and the
/// pressures among the state variables; all other columns are dimensionless.
pub fn is_stress_quantity(quantity: &str) -> bool {
    matches!(quantity, "p" | "q" | "preconsolidation_pressure") || quantity.starts_with("sigma_")
}

/// Settings of the Levenberg–Marquardt solver; every key is optional.
#[derive(Debug, Clone, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SolverSettings {
    /// Most residual evaluations per fitted parameter and one (MINPACK's `maxfev =
    /// patience (n + 1)`); default 100.
    pub max_iterations: usize,
    /// Relative tolerance on the sum of squares and on the parameters (MINPACK's `ftol`,
    /// `xtol`); default 1e-10: far below the noise of any laboratory curve, far above the
    /// driver's round-off.
    pub tolerance: f64,
    /// Relative step `h` of the finite differences (module doc of [`super`]); default 1e-6.
    pub finite_difference_step: f64,
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self { max_iterations: 100, tolerance: 1e-10, finite_difference_step: 1e-6 }
    }
}
