//! The case's FMU variables: inputs resolved to loads, boundary conditions, rigid bodies'
//! motions or gravity, outputs to monitors.

use std::collections::BTreeMap;

use super::monitors::monitor_unit;
use super::{InputSlot, ModelInput, ModelOutput};
use crate::case::{Case, CaseError, InputTarget};
use crate::monitor::Monitor;

/// Resolves `fmu.inputs` to loads, constraints (of boundary conditions and of rigid bodies'
/// `motion`, `motion_of` by domain name) or gravity, and `fmu.outputs` (default: every
/// monitor) to monitors; names must be unique, non-empty and not `time`. A contact wall built
/// as a rigid structure (`walls`) is driven through its body's motion.
pub(super) fn resolve(
    case: &Case,
    constraint_of_bc: &[usize],
    load_of_load: &[usize],
    motion_of: &BTreeMap<String, usize>,
    monitors: &[Monitor],
) -> Result<(Vec<ModelInput>, Vec<ModelOutput>), CaseError> {
    let mut bc_names = BTreeMap::new();
    for (k, bc) in case.boundary_conditions.iter().enumerate() {
        if let Some(name) = &bc.name {
            let slot = match motion_of.get(name) {
                Some(&c) if bc.as_rigid_wall => c,
                _ => constraint_of_bc[k],
            };
            if bc_names.insert(name.as_str(), slot).is_some() {
                return Err(CaseError::new(
                    format!("boundary_conditions[{k}].name"),
                    format!("duplicate boundary condition name '{name}'"),
                ));
            }
        }
    }
    let mut load_names = BTreeMap::new();
    for (k, l) in case.loads.iter().enumerate() {
        if let Some(name) = l.name() {
            if load_names.insert(name, load_of_load[k]).is_some() {
                return Err(CaseError::new(format!("loads[{k}].name"), format!("duplicate load name '{name}'")));
            }
        }
    }
    let Some(fmu) = &case.fmu else {
        let outputs = monitors
            .iter()
            .enumerate()
            .map(|(i, m)| ModelOutput {
                name: m.name.clone(),
                monitor: i,
                unit: monitor_unit(&m.kind).into(),
                description: String::new(),
            })
            .collect();
        return Ok((Vec::new(), outputs));
    };
    let mut names = std::collections::BTreeSet::new();
    let mut check_name = |loc: String, name: &str| -> Result<(), CaseError> {
        if name.is_empty() || name == "time" || name.chars().any(char::is_control) {
            return Err(CaseError::new(loc, "must be non-empty, not 'time', without control characters"));
        }
        if !names.insert(name.to_string()) {
            return Err(CaseError::new(loc, format!("duplicate FMU variable name '{name}'")));
        }
        Ok(())
    };
    let mut inputs = Vec::new();
    for (k, i) in fmu.inputs.iter().enumerate() {
        let loc = format!("fmu.inputs[{k}]");
        check_name(format!("{loc}.name"), &i.name)?;
        if !i.start.is_finite() {
            return Err(CaseError::new(format!("{loc}.start"), format!("must be finite, got {}", i.start)));
        }
        let slot = match &i.drives {
            InputTarget::Load(n) => InputSlot::Load(*load_names.get(n.as_str()).ok_or_else(|| {
                CaseError::new(format!("{loc}.drives.load"), format!("no load named '{n}' in loads"))
            })?),
            InputTarget::BoundaryCondition(n) => InputSlot::Constraint(*bc_names.get(n.as_str()).ok_or_else(|| {
                CaseError::new(
                    format!("{loc}.drives.boundary_condition"),
                    format!("no boundary condition named '{n}' in boundary_conditions"),
                )
            })?),
            InputTarget::Motion(n) => InputSlot::Constraint(*motion_of.get(n.as_str()).ok_or_else(|| {
                let message = match case.domains.iter().find(|d| d.name == *n) {
                    Some(d) if d.kind == crate::case::DomainKind::Rigid => {
                        format!("the rigid domain '{n}' prescribes no motion (give it \"motion\")")
                    }
                    Some(_) => format!("'{n}' is not a rigid domain (\"type\": \"rigid\")"),
                    None => format!("no domain named '{n}' in domains"),
                };
                CaseError::new(format!("{loc}.drives.motion"), message)
            })?),
            InputTarget::Gravity => {
                if case.gravity.is_none() {
                    return Err(CaseError::new(format!("{loc}.drives"), "the case has no gravity to scale"));
                }
                InputSlot::Gravity
            }
        };
        if inputs.iter().any(|j: &ModelInput| j.slot == slot) {
            return Err(CaseError::new(format!("{loc}.drives"), "another input already drives this target"));
        }
        inputs.push(ModelInput {
            name: i.name.clone(),
            slot,
            unit: i.unit.clone().unwrap_or_else(|| "1".into()),
            start: i.start,
            description: i.description.clone().unwrap_or_default(),
        });
    }
    let mut outputs = Vec::new();
    match &fmu.outputs {
        None => {
            for (i, m) in monitors.iter().enumerate() {
                check_name(format!("monitors[{i}].name"), &m.name)?;
                outputs.push(ModelOutput {
                    name: m.name.clone(),
                    monitor: i,
                    unit: monitor_unit(&m.kind).into(),
                    description: String::new(),
                });
            }
        }
        Some(list) => {
            for (k, o) in list.iter().enumerate() {
                let loc = format!("fmu.outputs[{k}]");
                check_name(format!("{loc}.name"), &o.name)?;
                let monitor_name = o.monitor.as_deref().unwrap_or(&o.name);
                let monitor = monitors.iter().position(|m| m.name == monitor_name).ok_or_else(|| {
                    CaseError::new(
                        format!("{loc}.{}", if o.monitor.is_some() { "monitor" } else { "name" }),
                        format!("no monitor named '{monitor_name}' in monitors"),
                    )
                })?;
                outputs.push(ModelOutput {
                    name: o.name.clone(),
                    monitor,
                    unit: o.unit.clone().unwrap_or_else(|| monitor_unit(&monitors[monitor].kind).into()),
                    description: o.description.clone().unwrap_or_default(),
                });
            }
        }
    }
    Ok((inputs, outputs))
}
