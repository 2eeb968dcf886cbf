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
