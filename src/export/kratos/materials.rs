//! Loam materials as Kratos' `ParticleMaterials.json`: the importer's table
//! ([`crate::import::kratos::materials::LAWS`]) read backwards.
//!
//! A Loam law with a Kratos MPM counterpart becomes `<stem><formulation suffix>Law` (e.g.
//! `mohr_coulomb` in plane strain: `HenckyMCPlasticPlaneStrain2DLaw`) with its variables
//! converted (degrees to radians, a positive pressure to a negative stress). A law Kratos' MPM
//! does not have, a Loam parameter it has no variable for, or one the case leaves at Loam's
//! default (Kratos needs every variable) is refused, naming `materials.<name>.<key>`.

use serde_json::{json, Map, Value};

use super::ExportError;
use crate::import::kratos::materials::{law_name, LAWS};

/// What a body adds to its materials entry beside the law.
pub struct BodyKinematics<'a> {
    /// Kratos sub model part of the body (`Parts_<domain>`).
    pub part: &'a str,
    /// Loam formulation name (`plane_strain`, …).
    pub formulation: &'a str,
    /// Mixed u–p elements.
    pub mixed_up: bool,
    /// `THICKNESS` (plane problems).
    pub thickness: Option<f64>,
    /// `MATERIAL_POINTS_PER_ELEMENT`.
    pub points_per_cell: usize,
}

/// The `properties` entry (number `id`) of Loam material `name` (its case JSON `material`)
/// on the body `body`.
pub fn properties(name: &str, material: &Value, id: usize, body: &BodyKinematics) -> Result<Value, ExportError> {
    let loc = format!("materials.{name}");
    let m = material.as_object().ok_or_else(|| ExportError(format!("{loc}: must be an object")))?;
    let law = m.get("law").and_then(Value::as_str).unwrap_or_default();
    let map = LAWS.iter().find(|l| l.loam == law).ok_or_else(|| {
        let known: Vec<&str> = LAWS.iter().map(|l| l.loam).collect();
        ExportError(format!("{loc}.law: \"{law}\" has no Kratos MPM counterpart (exported: {})", known.join(", ")))
    })?;
    // combinations Kratos 10.4.4's MPM application does not register
    if body.formulation == "plane_stress" && law != "linear_elastic" {
        return Err(ExportError(format!(
            "{loc}.law: \"{law}\" in plane stress: Kratos' MPM has plane stress for LinearElasticIsotropic only"
        )));
    }
    if body.mixed_up && law == "linear_elastic" {
        return Err(ExportError(format!(
            "{loc}.law: \"linear_elastic\" with mixed_up: Kratos' MPM has no UP form of LinearElasticIsotropic"
        )));
    }
    if let Some(key) = m.keys().find(|k| *k != "law" && !map.variables.iter().any(|v| v.loam == k.as_str())) {
        return Err(ExportError(format!("{loc}.{key}: Kratos' {} law has no such parameter: refused", map.kratos[0])));
    }
    let mut vars = Map::new();
    for v in map.variables {
        let x = m.get(v.loam).and_then(Value::as_f64).ok_or_else(|| {
            ExportError(format!(
                "{loc}.{}: not given (Loam's default): Kratos needs {}, give it in the case",
                v.loam, v.kratos
            ))
        })?;
        vars.insert(v.kratos.into(), json!(v.conversion.to_kratos(x)));
    }
    if let Some(t) = body.thickness {
        vars.insert("THICKNESS".into(), json!(t));
    }
    vars.insert("MATERIAL_POINTS_PER_ELEMENT".into(), json!(body.points_per_cell));
    let law_name = law_name(map.kratos[0], body.formulation, body.mixed_up)
        .ok_or_else(|| ExportError(format!("formulation: \"{}\" has no Kratos law suffix", body.formulation)))?;
    Ok(json!({
        "model_part_name": format!("Initial_MPM_Material.{}", body.part),
        "properties_id": id,
        "Material": { "constitutive_law": { "name": law_name }, "Variables": vars, "Tables": {} }
    }))
}

#[cfg(test)]
mod tests {
    use super::{properties, BodyKinematics};
    use crate::import::kratos::materials::{read, LAWS};
    use serde_json::{json, Value};

    /// Every law of the shared table goes to Kratos and back unchanged, in every formulation:
    /// `import ∘ export` is the identity on Loam's materials (angles through radians, the
    /// preconsolidation pressure through a negative stress), and the Kratos name is the one
    /// the importer reads.
    #[test]
    fn every_law_round_trips() {
        for law in LAWS {
            let mut m = serde_json::Map::new();
            m.insert("law".into(), json!(law.loam));
            for (k, v) in law.variables.iter().enumerate() {
                m.insert(v.loam.into(), json!(0.1 + 0.37 * k as f64));
            }
            let material = Value::Object(m);
            for (formulation, thickness) in [("plane_strain", Some(2.0)), ("axisymmetric", None), ("3d", None)] {
                let body =
                    BodyKinematics { part: "Parts_soil", formulation, mixed_up: false, thickness, points_per_cell: 4 };
                let p = properties("soil", &material, 1, &body).expect("exports");
                let file = json!({ "properties": [p] }).to_string();
                let mut notes = Vec::new();
                let back = read(&file, "ParticleMaterials.json", &mut notes).expect("imports");
                assert!(notes.is_empty(), "{}: {notes:?}", law.loam);
                assert_eq!(back[0].part, "Parts_soil");
                assert_eq!(back[0].formulation, formulation);
                assert_eq!(back[0].thickness, thickness);
                assert_eq!(back[0].points_per_cell, Some(4));
                for (key, v) in material.as_object().unwrap() {
                    let (a, b) = (v.as_f64(), back[0].material[key].as_f64());
                    match (a, b) {
                        (Some(a), Some(b)) => {
                            assert!((a - b).abs() <= 1e-14 * a.abs(), "{}.{key}: {a} → {b}", law.loam)
                        }
                        _ => assert_eq!(v, &back[0].material[key], "{}.{key}", law.loam),
                    }
                }
            }
        }
    }

    /// A law Kratos' MPM lacks, an unknown parameter and one left at Loam's default are refused
    /// naming `materials.<name>.<key>`.
    #[test]
    fn unexpressed_materials_refused() {
        let body = BodyKinematics {
            part: "Parts_soil",
            formulation: "plane_strain",
            mixed_up: false,
            thickness: None,
            points_per_cell: 1,
        };
        let refuse = |m: Value| properties("soil", &m, 1, &body).unwrap_err().to_string();
        let e = refuse(json!({ "law": "hencky", "density": 1.0, "young_modulus": 1.0, "poisson_ratio": 0.0 }));
        assert!(e.starts_with("materials.soil.law: \"hencky\" has no Kratos MPM counterpart"), "{e}");
        let e = refuse(
            json!({ "law": "linear_elastic", "density": 1.0, "young_modulus": 1.0, "poisson_ratio": 0.0, "damping": 0.1 }),
        );
        assert!(
            e.starts_with("materials.soil.damping: Kratos' LinearElasticIsotropic law has no such parameter"),
            "{e}"
        );
        let e = refuse(
            json!({ "law": "mohr_coulomb", "density": 1.0, "young_modulus": 1.0, "poisson_ratio": 0.0, "cohesion": 1.0, "friction_angle": 30.0 }),
        );
        assert!(e.starts_with("materials.soil.dilatancy_angle: not given"), "{e}");
    }
}
