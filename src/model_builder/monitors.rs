//! Monitors: named scalar time histories resolved to nodes, material points, regions,
//! walls and interfaces.

use std::collections::BTreeMap;

use loam_fem::domain::{PointQuantity, PointTensor};
use loam_fem::model::Model;
use loam_fem::rigid_body::RigidFrame;

use super::meshes::ResolvedInterface;
use super::regions::{nearest_node, region, select_points};
use super::{check_len, check_positive, component_index};
use crate::case::{Case, CaseError, MonitorSpec, RunoutMeasure};
use crate::monitor::{Monitor, MonitorKind};

/// The monitors of the case, in case order.
pub(super) fn build(
    case: &Case,
    model: &Model,
    regions: &BTreeMap<String, Vec<usize>>,
    interfaces: &[ResolvedInterface],
    rigid_frames: &BTreeMap<String, RigidFrame>,
) -> Result<Vec<Monitor>, CaseError> {
    let dim = case.formulation.dim();
    let mut monitor_names = std::collections::BTreeSet::new();
    let mut monitors = Vec::new();
    for (k, m) in case.monitors.iter().enumerate() {
        let loc = format!("monitors[{k}]");
        // a column of monitors.csv: a comma, a quote or a line break would break the file
        if m.name() == "time" || m.name().is_empty() || m.name().chars().any(|c| c == ',' || c == '"' || c.is_control())
        {
            return Err(CaseError::new(
                format!("{loc}.name"),
                format!(
                    "{:?} names a column of monitors.csv: it must be non-empty, not 'time', without commas, quotes or control characters",
                    m.name()
                ),
            ));
        }
        if !monitor_names.insert(m.name().to_string()) {
            return Err(CaseError::new(format!("{loc}.name"), format!("duplicate monitor name '{}'", m.name())));
        }
        let kind = match m {
            MonitorSpec::Displacement { point, component, .. }
            | MonitorSpec::Velocity { point, component, .. }
            | MonitorSpec::Acceleration { point, component, .. } => {
                check_len(&format!("{loc}.point"), point, dim)?;
                let node = nearest_node(&model.coords, point).expect("model has nodes");
                let c = component_index(&format!("{loc}.component"), *component, dim)?;
                match m {
                    MonitorSpec::Displacement { .. } => MonitorKind::Displacement { node, component: c },
                    MonitorSpec::Velocity { .. } => MonitorKind::Velocity { node, component: c },
                    _ => MonitorKind::Acceleration { node, component: c },
                }
            }
            MonitorSpec::Reaction { region: r, component, .. } => MonitorKind::Reaction {
                nodes: region(regions, format!("{loc}.region"), r)?.clone(),
                component: component_index(&format!("{loc}.component"), *component, dim)?,
            },
            MonitorSpec::MaterialPointDisplacement { point, component, .. }
            | MonitorSpec::MaterialPointVelocity { point, component, .. } => {
                check_len(&format!("{loc}.point"), point, dim)?;
                let nearest = model
                    .domains
                    .iter()
                    .enumerate()
                    .filter_map(|(k, d)| d.nearest_point(point).map(|(id, dist)| (k, id, dist)))
                    .min_by(|a, b| a.2.total_cmp(&b.2))
                    .ok_or_else(|| CaseError::new(format!("{loc}.type"), "the model has no material points"))?;
                let quantity = match m {
                    MonitorSpec::MaterialPointDisplacement { .. } => PointQuantity::Displacement,
                    _ => PointQuantity::Velocity,
                };
                MonitorKind::MaterialPoint {
                    domain: nearest.0,
                    id: nearest.1,
                    quantity,
                    component: component_index(&format!("{loc}.component"), *component, dim)?,
                }
            }
            MonitorSpec::Runout { wall, base, threshold, measure, bin, depth, .. } => {
                check_surface_monitor(&loc, model)?;
                check_positive(&format!("{loc}.threshold"), *threshold)?;
                let thickness = *measure == RunoutMeasure::Thickness;
                let bin = thickness_key(&loc, "bin", *bin, thickness, "the width of the bins along x, e.g. 0.005")?;
                let depth = if model.dim == 3 {
                    thickness_key(&loc, "depth", *depth, thickness, "the depth across y over which the points spread")?
                } else if depth.is_some() {
                    return Err(CaseError::new(format!("{loc}.depth"), "applies to 3D cases only"));
                } else {
                    Some(1.0)
                };
                match (bin, depth) {
                    (Some(bin), Some(depth)) => {
                        MonitorKind::ThicknessRunout { wall: *wall, threshold: *threshold, bin, depth }
                    }
                    _ => MonitorKind::Runout { wall: *wall, base: *base, threshold: *threshold },
                }
            }
            MonitorSpec::SurfaceHeight { x, base, .. } => {
                check_surface_monitor(&loc, model)?;
                MonitorKind::SurfaceHeight { x: *x, base: *base }
            }
            MonitorSpec::MaterialPointStress { point, within, component, .. } => MonitorKind::MaterialPointTensor {
                points: select_points(model, &loc, dim, None, point.as_deref(), within.as_ref())?,
                quantity: PointTensor::CauchyStress,
                component: *component,
            },
            MonitorSpec::WallForce { wall, component, .. } => MonitorKind::WallForce {
                domain: model.domains.iter().position(|d| d.wall_force(wall).is_some()).ok_or_else(|| {
                    CaseError::new(
                        format!("{loc}.wall"),
                        format!("no penalty wall named '{wall}' in boundary_conditions"),
                    )
                })?,
                wall: wall.clone(),
                component: component_index(&format!("{loc}.component"), *component, dim)?,
            },
            MonitorSpec::InterfaceForce { interface, component, .. } => {
                let k = case.interfaces.iter().position(|i| i.name == *interface).ok_or_else(|| {
                    CaseError::new(
                        format!("{loc}.interface"),
                        format!("no interface named '{interface}' in interfaces"),
                    )
                })?;
                MonitorKind::InterfaceForce {
                    nodes: interfaces[k].soil_nodes.clone(),
                    component: component_index(&format!("{loc}.component"), *component, dim)?,
                }
            }
            MonitorSpec::RigidBody { domain, quantity, component, .. } => {
                let frame = rigid_frames.get(domain).ok_or_else(|| {
                    let message = match case.domains.iter().any(|d| d.name == *domain) {
                        true => format!("'{domain}' is not a rigid domain (\"type\": \"rigid\")"),
                        false => crate::model_builder::unknown_name(
                            "rigid domain",
                            domain,
                            "domains",
                            rigid_frames.keys().map(String::as_str),
                        ),
                    };
                    CaseError::new(format!("{loc}.domain"), message)
                })?;
                let component = match (quantity.is_vector(), component) {
                    (true, Some(c)) => component_index(&format!("{loc}.component"), *c, dim)?,
                    (true, None) => {
                        return Err(CaseError::new(
                            format!("{loc}.component"),
                            "a vector quantity of the centroid needs a component (\"x\", \"y\" or \"magnitude\")",
                        ))
                    }
                    (false, Some(_)) => {
                        return Err(CaseError::new(
                            format!("{loc}.component"),
                            "a rotational quantity is one angle: omit component",
                        ))
                    }
                    (false, None) => None,
                };
                MonitorKind::RigidBody { dofs: frame.dofs(), quantity: *quantity, component }
            }
            MonitorSpec::MaterialVolume { within, .. } | MonitorSpec::MaterialMass { within, .. } => {
                if model.domains.iter().all(|d| d.point_extents().is_empty()) {
                    return Err(CaseError::new(format!("{loc}.type"), "the model has no material points"));
                }
                let (min, max) = match within {
                    Some(b) => {
                        check_len(&format!("{loc}.box.min"), &b.min, dim)?;
                        check_len(&format!("{loc}.box.max"), &b.max, dim)?;
                        if let Some(d) = (0..dim).find(|&d| b.max[d] < b.min[d]) {
                            return Err(CaseError::new(
                                format!("{loc}.box.max[{d}]"),
                                format!("must not lie below box.min[{d}] = {}, got {}", b.min[d], b.max[d]),
                            ));
                        }
                        (b.min.clone(), b.max.clone())
                    }
                    None => (vec![f64::NEG_INFINITY; dim], vec![f64::INFINITY; dim]),
                };
                match m {
                    MonitorSpec::MaterialVolume { .. } => MonitorKind::MaterialVolume { min, max },
                    _ => MonitorKind::MaterialMass { min, max },
                }
            }
            MonitorSpec::KineticEnergy { domain, .. } => {
                MonitorKind::KineticEnergy { domain: named_domain(model, &loc, domain.as_deref())? }
            }
            MonitorSpec::Momentum { domain, component, .. } => MonitorKind::Momentum {
                domain: named_domain(model, &loc, domain.as_deref())?,
                component: component_index(&format!("{loc}.component"), *component, dim)?,
            },
            MonitorSpec::StrainEnergy { domain, .. } => {
                MonitorKind::StrainEnergy { domain: named_domain(model, &loc, domain.as_deref())? }
            }
        };
        if !m.scale().is_finite() {
            return Err(CaseError::new(format!("{loc}.scale"), format!("must be finite, got {}", m.scale())));
        }
        monitors.push(Monitor { name: m.name().to_string(), kind, scale: m.scale() });
    }
    Ok(monitors)
}

/// The `(domain index, name)` of the domain or body named `name` for an energy or momentum monitor at
/// `loc` (`None`: every domain).
fn named_domain(model: &Model, loc: &str, name: Option<&str>) -> Result<Option<(usize, String)>, CaseError> {
    let Some(name) = name else { return Ok(None) };
    model
        .domains
        .iter()
        .position(|d| d.energies(name, &model.committed.v).is_some())
        .map(|k| Some((k, name.to_string())))
        .ok_or_else(|| CaseError::new(format!("{loc}.domain"), format!("no domain named '{name}' in domains")))
}

/// Surface monitors need material points (plane problems, or 3D seen from the side:
/// [`crate::monitor::point_extents`]).
fn check_surface_monitor(loc: &str, model: &Model) -> Result<(), CaseError> {
    if model.domains.iter().all(|d| d.point_extents().is_empty()) {
        return Err(CaseError::new(format!("{loc}.type"), "the model has no material points"));
    }
    Ok(())
}

/// A length key of the thickness runout (`bin`, `depth`): required and positive where
/// `thickness` (the measure is `"thickness"`), refused otherwise; `None` where it does not
/// apply.
fn thickness_key(
    loc: &str,
    key: &str,
    value: Option<f64>,
    thickness: bool,
    what: &str,
) -> Result<Option<f64>, CaseError> {
    match (thickness, value) {
        (true, Some(v)) => {
            check_positive(&format!("{loc}.{key}"), v)?;
            Ok(Some(v))
        }
        (true, None) => Err(CaseError::new(
            format!("{loc}.{key}"),
            format!("is required with \"measure\": \"thickness\" (m: {what})"),
        )),
        (false, Some(_)) => Err(CaseError::new(format!("{loc}.{key}"), "applies to \"measure\": \"thickness\" only")),
        (false, None) => Ok(None),
    }
}

/// SI unit of a monitor's value.
pub fn monitor_unit(kind: &MonitorKind) -> &'static str {
    match kind {
        MonitorKind::Displacement { .. } => "m",
        MonitorKind::Velocity { .. } => "m/s",
        MonitorKind::Acceleration { .. } => "m/s2",
        MonitorKind::Reaction { .. } | MonitorKind::WallForce { .. } | MonitorKind::InterfaceForce { .. } => "N",
        MonitorKind::Runout { .. } | MonitorKind::ThicknessRunout { .. } | MonitorKind::SurfaceHeight { .. } => "m",
        MonitorKind::MaterialPoint { quantity, .. } => match quantity {
            PointQuantity::Position | PointQuantity::Displacement => "m",
            PointQuantity::Velocity => "m/s",
            PointQuantity::Acceleration => "m/s2",
        },
        MonitorKind::MaterialPointTensor { quantity, .. } => match quantity {
            PointTensor::CauchyStress => "Pa",
            PointTensor::DeformationGradient => "1",
        },
        MonitorKind::MaterialVolume { .. } => "m3",
        MonitorKind::MaterialMass { .. } => "kg",
        MonitorKind::KineticEnergy { .. } | MonitorKind::StrainEnergy { .. } => "J",
        MonitorKind::Momentum { .. } => "kg m/s",
        MonitorKind::RigidBody { quantity, .. } => quantity.unit(),
    }
}
