//! Kratos' materials file (`ParticleMaterials.json`, `materials.json`) to Loam materials.
//!
//! The file holds `properties`: per body sub model part (`model_part_name`, e.g.
//! `Initial_MPM_Material.Parts_Parts_Auto1`) a `Material` with a `constitutive_law.name` and
//! `Variables`. The law name carries the law and the kinematic assumption; this module maps
//! the names of Kratos' MPM and constitutive laws applications:
//!
//! | Kratos law name (stem) | Loam `law` |
//! |---|---|
//! | `LinearElasticIsotropic…Law`, `LinearElastic…Law` (StructuralMechanics) | `linear_elastic` |
//! | `HyperElasticNeoHookean…Law`, `HyperElastic…Law` (StructuralMechanics: its isotropic Neo-Hookean) | `neo_hookean` |
//! | `HenckyMCPlastic…Law` | `mohr_coulomb` (angles from radians to degrees) |
//! | `HenckyMCStrainSofteningPlastic…Law` | `mohr_coulomb_softening`: peak values from `COHESION`, `INTERNAL_FRICTION_ANGLE`, `INTERNAL_DILATANCY_ANGLE`, residual ones from their `…_RESIDUAL`, `SHAPE_FUNCTION_BETA` the shape factor (the same exponential decay with the accumulated plastic deviatoric strain) |
//! | `HenckyBorjaCamClayPlastic…Law` | `modified_cam_clay`: `PRE_CONSOLIDATION_STRESS` (negative in Kratos, compression negative) to a positive `preconsolidation_pressure`; `OVER_CONSOLIDATION_RATIO`, `SWELLING_SLOPE`, `NORMAL_COMPRESSION_SLOPE`, `CRITICAL_STATE_LINE`, `INITIAL_SHEAR_MODULUS`, `ALPHA_SHEAR` to their Loam names (both codes use Borja's ln v – ln p slopes and `μ = μ₀ + α p₀ e^(ε_v^e/κ̂)`) |
//! | `DispNewtonianFluid…Law` | `newtonian_fluid` (`DYNAMIC_VISCOSITY`, `BULK_MODULUS`) |
//!
//! ([`LAWS`], which `loam export kratos` reads backwards) followed by `PlaneStrain2D`, `PlaneStress2D`, `Axisym2D` or `3D` (the formulation), with
//! `UP` before it for the mixed displacement–pressure form. Variables: `DENSITY`,
//! `YOUNG_MODULUS`, `POISSON_RATIO`, the laws' own variables above, `THICKNESS`,
//! `MATERIAL_POINTS_PER_ELEMENT`. Every other law (e.g. the sand hypoplasticity) is refused,
//! every other variable reported.

use serde_json::{json, Map, Value};

use super::json::{ImportError, Section};

/// One body's material as read from the materials file.
#[derive(Debug, Clone)]
pub struct BodyMaterial {
    /// The body sub model part, without the `Initial_MPM_Material.` prefix.
    pub part: String,
    /// Loam material (`law` and its parameters).
    pub material: Value,
    /// `plane_strain`, `plane_stress`, `axisymmetric` or `3d`.
    pub formulation: &'static str,
    /// Mixed displacement–pressure law (`UP`).
    pub mixed_up: bool,
    /// `THICKNESS`, if given.
    pub thickness: Option<f64>,
    /// `MATERIAL_POINTS_PER_ELEMENT`.
    pub points_per_cell: Option<usize>,
}

/// How a Kratos variable's value becomes a Loam parameter's (and back, for `loam export kratos`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Conversion {
    /// The same number in the same unit.
    Same,
    /// Kratos' angle in radians, Loam's in degrees.
    RadiansToDegrees,
    /// Kratos' stress with compression negative, Loam's positive pressure (must be a compression).
    CompressionNegative,
}

impl Conversion {
    /// The Loam value of Kratos' `x`.
    pub fn to_loam(self, x: f64) -> f64 {
        match self {
            Conversion::Same => x,
            Conversion::RadiansToDegrees => x.to_degrees(),
            Conversion::CompressionNegative => -x,
        }
    }

    /// The Kratos value of Loam's `x` (the inverse of [`Conversion::to_loam`]).
    pub fn to_kratos(self, x: f64) -> f64 {
        match self {
            Conversion::Same => x,
            Conversion::RadiansToDegrees => x.to_radians(),
            Conversion::CompressionNegative => -x,
        }
    }
}

/// One parameter of a law: its Loam key, its Kratos variable and the conversion between them.
#[derive(Debug, Clone, Copy)]
pub struct Variable {
    /// Loam key in `materials.<name>`.
    pub loam: &'static str,
    /// Kratos variable in `Material.Variables`.
    pub kratos: &'static str,
    /// How the value converts.
    pub conversion: Conversion,
}

const fn var(loam: &'static str, kratos: &'static str, conversion: Conversion) -> Variable {
    Variable { loam, kratos, conversion }
}

/// A law known to both codes: Loam's `law` name, the Kratos law name stems (the first is the
/// one `loam export kratos` writes) and the parameters.
#[derive(Debug, Clone, Copy)]
pub struct LawMap {
    /// Loam `law`.
    pub loam: &'static str,
    /// Kratos law name stems (before the formulation suffix).
    pub kratos: &'static [&'static str],
    /// Parameters, every one required by both codes.
    pub variables: &'static [Variable],
}

use Conversion::{CompressionNegative, RadiansToDegrees, Same};

/// The elastic constants every solid law has.
const DENSITY: Variable = var("density", "DENSITY", Same);
const YOUNG: Variable = var("young_modulus", "YOUNG_MODULUS", Same);
const POISSON: Variable = var("poisson_ratio", "POISSON_RATIO", Same);

/// The laws of the table in the module doc, the one mapping of import and export.
pub const LAWS: &[LawMap] = &[
    // `LinearElastic…`: StructuralMechanicsApplication's name of the same law
    LawMap {
        loam: "linear_elastic",
        kratos: &["LinearElasticIsotropic", "LinearElastic"],
        variables: &[DENSITY, YOUNG, POISSON],
    },
    // `HyperElastic…`: StructuralMechanicsApplication's isotropic Neo-Hookean
    LawMap {
        loam: "neo_hookean",
        kratos: &["HyperElasticNeoHookean", "HyperElastic"],
        variables: &[DENSITY, YOUNG, POISSON],
    },
    LawMap {
        loam: "mohr_coulomb",
        kratos: &["HenckyMCPlastic"],
        variables: &[
            DENSITY,
            YOUNG,
            POISSON,
            var("cohesion", "COHESION", Same),
            var("friction_angle", "INTERNAL_FRICTION_ANGLE", RadiansToDegrees),
            var("dilatancy_angle", "INTERNAL_DILATANCY_ANGLE", RadiansToDegrees),
        ],
    },
    LawMap {
        loam: "mohr_coulomb_softening",
        kratos: &["HenckyMCStrainSofteningPlastic"],
        variables: &[
            DENSITY,
            YOUNG,
            POISSON,
            var("peak_cohesion", "COHESION", Same),
            var("residual_cohesion", "COHESION_RESIDUAL", Same),
            var("peak_friction_angle", "INTERNAL_FRICTION_ANGLE", RadiansToDegrees),
            var("residual_friction_angle", "INTERNAL_FRICTION_ANGLE_RESIDUAL", RadiansToDegrees),
            var("peak_dilatancy_angle", "INTERNAL_DILATANCY_ANGLE", RadiansToDegrees),
            var("residual_dilatancy_angle", "INTERNAL_DILATANCY_ANGLE_RESIDUAL", RadiansToDegrees),
            var("shape_factor", "SHAPE_FUNCTION_BETA", Same),
        ],
    },
    LawMap {
        loam: "modified_cam_clay",
        kratos: &["HenckyBorjaCamClayPlastic"],
        variables: &[
            DENSITY,
            var("preconsolidation_pressure", "PRE_CONSOLIDATION_STRESS", CompressionNegative),
            var("ocr", "OVER_CONSOLIDATION_RATIO", Same),
            var("swelling_slope", "SWELLING_SLOPE", Same),
            var("compression_slope", "NORMAL_COMPRESSION_SLOPE", Same),
            var("critical_state_slope", "CRITICAL_STATE_LINE", Same),
            var("initial_shear_modulus", "INITIAL_SHEAR_MODULUS", Same),
            var("alpha_shear", "ALPHA_SHEAR", Same),
        ],
    },
    LawMap {
        loam: "newtonian_fluid",
        kratos: &["DispNewtonianFluid"],
        variables: &[DENSITY, var("viscosity", "DYNAMIC_VISCOSITY", Same), var("bulk_modulus", "BULK_MODULUS", Same)],
    },
];

/// The law whose Kratos name has the stem `stem`.
pub fn law_of_stem(stem: &str) -> Option<&'static LawMap> {
    LAWS.iter().find(|l| l.kratos.contains(&stem))
}

/// Kratos' formulation suffixes of law names (`…PlaneStrain2DLaw`) and Loam's `formulation`.
pub const FORMULATIONS: [(&str, &str); 4] =
    [("PlaneStrain2D", "plane_strain"), ("PlaneStress2D", "plane_stress"), ("Axisym2D", "axisymmetric"), ("3D", "3d")];

/// The Kratos law name of `stem` in `formulation` (a Loam name), `UP` for the mixed form:
/// the inverse of [`split_law_name`].
pub fn law_name(stem: &str, formulation: &str, mixed_up: bool) -> Option<String> {
    let (suffix, _) = FORMULATIONS.iter().find(|f| f.1 == formulation)?;
    Some(format!("{stem}{}Law", if mixed_up { up_suffix(suffix) } else { suffix.to_string() }))
}

/// The suffix of the mixed u–p form of a formulation suffix (`PlaneStrain2D` → `PlaneStrainUP2D`).
fn up_suffix(suffix: &str) -> String {
    suffix.replacen("2D", "UP2D", 1).replacen("3D", "UP3D", 1)
}

/// Reads the materials file `file` (its text `text`); notes collect what is not taken over.
pub fn read(text: &str, file: &str, notes: &mut Vec<String>) -> Result<Vec<BodyMaterial>, ImportError> {
    let root = super::json::parse_json(text, file)?;
    let top = Section::root(&root, file)?;
    let props = top.array("properties")?;
    let mut out = Vec::new();
    for (k, p) in props.iter().enumerate() {
        let s = top.child_at(p, &format!("properties[{k}]"))?;
        let part = s.string("model_part_name")?;
        // MPM bodies: `Initial_MPM_Material.NAME`; structures: `Structure.NAME`
        let part = part
            .strip_prefix("Initial_MPM_Material.")
            .or_else(|| part.strip_prefix("Structure."))
            .unwrap_or(&part)
            .to_string();
        s.take("properties_id");
        let mat = s.object("Material")?;
        let law = mat.object("constitutive_law")?;
        let name = law.string("name")?;
        law.finish(notes);
        let (stem, formulation, mixed_up) = split_law_name(&name)
            .ok_or_else(|| law.error("name", format!("Kratos law '{name}' has no Loam counterpart")))?;
        let vars = mat.object("Variables")?;
        let map = law_of_stem(stem)
            .ok_or_else(|| law.error("name", format!("Kratos law '{name}' has no Loam counterpart")))?;
        let mut material = Map::new();
        material.insert("law".into(), json!(map.loam));
        for v in map.variables {
            let x = vars.number(v.kratos)?;
            if v.conversion == Conversion::CompressionNegative && x >= 0.0 {
                return Err(
                    vars.error(v.kratos, format!("{x} is not a compression (Kratos takes compression negative)"))
                );
            }
            material.insert(v.loam.into(), json!(v.conversion.to_loam(x)));
        }
        let thickness = vars.optional_number("THICKNESS")?;
        let points_per_cell = vars.optional_number("MATERIAL_POINTS_PER_ELEMENT")?.map(|v| v as usize);
        vars.finish(notes);
        if let Some(t) = mat.take("Tables") {
            if t.as_object().is_some_and(|o| !o.is_empty()) {
                notes.push(format!("{file}: properties[{k}].Material.Tables: ignored (Loam laws take constants)"));
            }
        }
        mat.finish(notes);
        s.finish(notes);
        out.push(BodyMaterial {
            part,
            material: Value::Object(material),
            formulation,
            mixed_up,
            thickness,
            points_per_cell,
        });
    }
    top.finish(notes);
    Ok(out)
}

/// `(law stem, formulation, mixed u–p)` of a Kratos law name such as
/// `HyperElasticNeoHookeanPlaneStrainUP2DLaw`.
pub fn split_law_name(name: &str) -> Option<(&str, &'static str, bool)> {
    let body = name.strip_suffix("Law")?;
    for (suffix, formulation) in FORMULATIONS {
        if let Some(stem) = body.strip_suffix(up_suffix(suffix).as_str()) {
            return Some((stem, formulation, true));
        }
        if let Some(stem) = body.strip_suffix(suffix) {
            return Some((stem, formulation, false));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::{read, split_law_name};
    use loam_laws::material::MaterialSpec;

    /// A materials file with one body of law `name` and `variables`.
    fn materials(name: &str, variables: &str) -> String {
        format!(
            r#"{{"properties": [{{"model_part_name": "Initial_MPM_Material.Parts_Soil", "properties_id": 1,
                "Material": {{"constitutive_law": {{"name": "{name}"}}, "Variables": {{ {variables} }}, "Tables": {{}}}}}}]}}"#
        )
    }

    /// Reads one body's material and builds it as a Loam law (the keys must be Loam's).
    fn imported(name: &str, variables: &str) -> serde_json::Value {
        let mut notes = Vec::new();
        let bodies = read(&materials(name, variables), "ParticleMaterials.json", &mut notes).expect("imports");
        assert!(notes.is_empty(), "every variable taken over: {notes:?}");
        let material = bodies[0].material.clone();
        let spec: MaterialSpec = serde_json::from_value(material.clone()).expect("Loam's keys");
        spec.build().expect("a valid Loam law");
        material
    }

    #[test]
    fn softening_cam_clay_and_fluid_laws_map_to_loams() {
        let m = imported(
            "HenckyMCStrainSofteningPlasticPlaneStrain2DLaw",
            r#""DENSITY": 2000, "YOUNG_MODULUS": 1e7, "POISSON_RATIO": 0.3, "COHESION": 5000, "COHESION_RESIDUAL": 1000,
               "INTERNAL_FRICTION_ANGLE": 0.872664625997165, "INTERNAL_FRICTION_ANGLE_RESIDUAL": 0.5235987755982,
               "INTERNAL_DILATANCY_ANGLE": 0.436332312998582, "INTERNAL_DILATANCY_ANGLE_RESIDUAL": 0.0, "SHAPE_FUNCTION_BETA": 4.0"#,
        );
        assert_eq!(m["law"], "mohr_coulomb_softening");
        assert!((m["peak_friction_angle"].as_f64().unwrap() - 50.0).abs() < 1e-9);
        assert!((m["residual_friction_angle"].as_f64().unwrap() - 30.0).abs() < 1e-9);
        assert!((m["peak_dilatancy_angle"].as_f64().unwrap() - 25.0).abs() < 1e-9);
        assert_eq!(m["residual_cohesion"], 1000.0);
        assert_eq!(m["shape_factor"], 4.0);

        let m = imported(
            "HenckyBorjaCamClayPlasticPlaneStrain2DLaw",
            r#""DENSITY": 1800, "PRE_CONSOLIDATION_STRESS": -90000.0, "OVER_CONSOLIDATION_RATIO": 1.0, "SWELLING_SLOPE": 0.018,
               "NORMAL_COMPRESSION_SLOPE": 0.13, "CRITICAL_STATE_LINE": 1.05, "INITIAL_SHEAR_MODULUS": 5400000.0, "ALPHA_SHEAR": 0.0"#,
        );
        assert_eq!(m["law"], "modified_cam_clay");
        assert_eq!(m["preconsolidation_pressure"], 90000.0);
        assert_eq!(m["compression_slope"], 0.13);
        assert_eq!(m["critical_state_slope"], 1.05);

        let m = imported(
            "DispNewtonianFluidPlaneStrain2DLaw",
            r#""DENSITY": 1000, "BULK_MODULUS": 2.2e9, "DYNAMIC_VISCOSITY": 1e-3"#,
        );
        assert_eq!(m["law"], "newtonian_fluid");
        assert_eq!(m["viscosity"], 1e-3);

        // a tensile preconsolidation stress is Kratos input with the wrong sign
        let mut notes = Vec::new();
        let text = materials(
            "HenckyBorjaCamClayPlastic3DLaw",
            r#""DENSITY": 1800, "PRE_CONSOLIDATION_STRESS": 90000.0, "OVER_CONSOLIDATION_RATIO": 1.0, "SWELLING_SLOPE": 0.018,
               "NORMAL_COMPRESSION_SLOPE": 0.13, "CRITICAL_STATE_LINE": 1.05, "INITIAL_SHEAR_MODULUS": 5400000.0, "ALPHA_SHEAR": 0.0"#,
        );
        let err = read(&text, "ParticleMaterials.json", &mut notes).unwrap_err().to_string();
        assert!(err.contains("PRE_CONSOLIDATION_STRESS") && err.contains("compression negative"), "{err}");
    }

    #[test]
    fn law_names() {
        assert_eq!(
            split_law_name("HyperElasticNeoHookeanPlaneStrainUP2DLaw"),
            Some(("HyperElasticNeoHookean", "plane_strain", true))
        );
        assert_eq!(
            split_law_name("HyperElasticNeoHookeanAxisym2DLaw"),
            Some(("HyperElasticNeoHookean", "axisymmetric", false))
        );
        assert_eq!(split_law_name("HenckyMCPlasticPlaneStrain2DLaw"), Some(("HenckyMCPlastic", "plane_strain", false)));
        assert_eq!(split_law_name("Whatever"), None);
    }
}
