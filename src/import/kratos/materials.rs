//! Kratos' materials file (`ParticleMaterials.json`, `materials.json`) to Loam materials.
//!
//! The file holds `properties`: per body sub model part (`model_part_name`, e.g.
//! `Initial_MPM_Material.Parts_Parts_Auto1`) a `Material` with a `constitutive_law.name` and
//! `Variables`. The law name carries the law and the kinematic assumption; this module maps
//! the names of Kratos' MPM and constitutive laws applications:
//!
//! | Kratos law name (stem) | Loam `law` |
//! |---|---|
//! | `LinearElasticIsotropic…Law` | `linear_elastic` |
//! | `HyperElasticNeoHookean…Law` | `neo_hookean` |
//! | `HenckyMCPlastic…Law` | `mohr_coulomb` (angles from radians to degrees) |
//!
//! followed by `PlaneStrain2D`, `PlaneStress2D`, `Axisym2D` or `3D` (the formulation), with
//! `UP` before it for the mixed displacement–pressure form. Variables: `DENSITY`,
//! `YOUNG_MODULUS`, `POISSON_RATIO`, `COHESION`, `INTERNAL_FRICTION_ANGLE`,
//! `INTERNAL_DILATANCY_ANGLE`, `THICKNESS`, `MATERIAL_POINTS_PER_ELEMENT`. Every other law is
//! refused (Hencky–Cam Clay and Mohr–Coulomb with softening have different parameters in
//! Loam), every other variable reported.

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

/// Reads the materials file `file` (its text `text`); notes collect what is not taken over.
pub fn read(text: &str, file: &str, notes: &mut Vec<String>) -> Result<Vec<BodyMaterial>, ImportError> {
    let root = super::json::parse_json(text, file)?;
    let top = Section::root(&root, file)?;
    let props = top.array("properties")?;
    let mut out = Vec::new();
    for (k, p) in props.iter().enumerate() {
        let s = top.child_at(p, &format!("properties[{k}]"))?;
        let part = s.string("model_part_name")?;
        let part = part.strip_prefix("Initial_MPM_Material.").unwrap_or(&part).to_string();
        s.take("properties_id");
        let mat = s.object("Material")?;
        let law = mat.object("constitutive_law")?;
        let name = law.string("name")?;
        law.finish(notes);
        let (stem, formulation, mixed_up) = split_law_name(&name)
            .ok_or_else(|| law.error("name", format!("Kratos law '{name}' has no Loam counterpart")))?;
        let vars = mat.object("Variables")?;
        let num = |key: &str| vars.number(key);
        let elastic = |law: &str| -> Result<Map<String, Value>, ImportError> {
            let mut m = Map::new();
            m.insert("law".into(), json!(law));
            m.insert("density".into(), json!(num("DENSITY")?));
            m.insert("young_modulus".into(), json!(num("YOUNG_MODULUS")?));
            m.insert("poisson_ratio".into(), json!(num("POISSON_RATIO")?));
            Ok(m)
        };
        let material = match stem {
            "LinearElasticIsotropic" => elastic("linear_elastic")?,
            "HyperElasticNeoHookean" => elastic("neo_hookean")?,
            "HenckyMCPlastic" => {
                let mut m = elastic("mohr_coulomb")?;
                m.insert("cohesion".into(), json!(num("COHESION")?));
                m.insert("friction_angle".into(), json!(num("INTERNAL_FRICTION_ANGLE")?.to_degrees()));
                m.insert("dilatancy_angle".into(), json!(num("INTERNAL_DILATANCY_ANGLE")?.to_degrees()));
                m
            }
            _ => return Err(law.error("name", format!("Kratos law '{name}' has no Loam counterpart"))),
        };
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
    for (suffix, formulation) in [
        ("PlaneStrain2D", "plane_strain"),
        ("PlaneStress2D", "plane_stress"),
        ("Axisym2D", "axisymmetric"),
        ("3D", "3d"),
    ] {
        let with_up = suffix.replacen("2D", "UP2D", 1).replacen("3D", "UP3D", 1);
        if let Some(stem) = body.strip_suffix(with_up.as_str()) {
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
    use super::split_law_name;

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
