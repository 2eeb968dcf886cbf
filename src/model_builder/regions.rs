//! Named node sets (`regions`) and selections of material points.

use std::collections::BTreeMap;

use loam_fem::model::Model;

use super::{check_len, unknown_name};
use crate::case::{Case, CaseError, PointBox, RegionSpec};

/// Every region of the case, selected among `coords` (the global nodes).
pub(super) fn select_all(
    case: &Case,
    coords: &[[f64; 3]],
    groups: &BTreeMap<String, Vec<usize>>,
) -> Result<BTreeMap<String, Vec<usize>>, CaseError> {
    let dim = case.formulation.dim();
    let tol = line_tolerance(coords);
    // a rigid body's mesh nodes are not model nodes: a region naming its interface facets
    // is selected on its mesh alone (model_builder::meshes, couple_grids)
    let rigid = |name: &str| {
        case.interfaces
            .iter()
            .filter(|i| i.region == name)
            .any(|i| case.domains.iter().any(|d| d.name == i.structure && d.kind == crate::case::DomainKind::Rigid))
    };
    let mut regions = BTreeMap::new();
    for (name, spec) in &case.regions {
        let nodes = match select_region(name, spec, coords, dim, groups, tol) {
            Err(e) if rigid(name) && e.message.starts_with("selects no node") => Vec::new(),
            selected => selected?,
        };
        regions.insert(name.clone(), nodes);
    }
    Ok(regions)
}

/// Distance within which a node lies on a region's line: a millionth of the model's size.
pub(crate) fn line_tolerance(coords: &[[f64; 3]]) -> f64 {
    let (mut lo, mut hi) = ([f64::MAX; 3], [f64::MIN; 3]);
    for c in coords {
        for d in 0..3 {
            lo[d] = lo[d].min(c[d]);
            hi[d] = hi[d].max(c[d]);
        }
    }
    1e-6 * (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max)
}

/// The region named `name` in the case (`loc` the JSON path that names it).
pub(super) fn region<'a>(
    regions: &'a BTreeMap<String, Vec<usize>>,
    loc: String,
    name: &str,
) -> Result<&'a Vec<usize>, CaseError> {
    regions
        .get(name)
        .ok_or_else(|| CaseError::new(loc, unknown_name("region", name, "regions", regions.keys().map(String::as_str))))
}

/// Distance from `c` to the segment `[a, b]` (first `dim` coordinates).
fn distance_to_segment(c: &[f64; 3], a: &[f64], b: &[f64], dim: usize) -> f64 {
    let d: Vec<f64> = (0..dim).map(|i| b[i] - a[i]).collect();
    let l2: f64 = d.iter().map(|x| x * x).sum();
    let s = if l2 > 0.0 { ((0..dim).map(|i| (c[i] - a[i]) * d[i]).sum::<f64>() / l2).clamp(0.0, 1.0) } else { 0.0 };
    (0..dim).map(|i| (c[i] - a[i] - s * d[i]).powi(2)).sum::<f64>().sqrt()
}

/// The nodes (indices into `coords`) of region `name` (`regions.<name>`); `groups` are the
/// Gmsh physical groups by name, `tol` the distance within which a node lies on a line.
pub(crate) fn select_region(
    name: &str,
    spec: &RegionSpec,
    coords: &[[f64; 3]],
    dim: usize,
    groups: &BTreeMap<String, Vec<usize>>,
    tol: f64,
) -> Result<Vec<usize>, CaseError> {
    let loc = format!("regions.{name}");
    let pick = |f: &dyn Fn(&[f64; 3]) -> bool| (0..coords.len()).filter(|&n| f(&coords[n])).collect::<Vec<_>>();
    let nodes = match spec {
        RegionSpec::X(v) => pick(&|c| (c[0] - v).abs() <= tol),
        RegionSpec::Y(v) => pick(&|c| (c[1] - v).abs() <= tol),
        RegionSpec::Z(v) => {
            if dim < 3 {
                return Err(CaseError::new(format!("{loc}.z"), "z does not exist in a 2D model"));
            }
            pick(&|c| (c[2] - v).abs() <= tol)
        }
        RegionSpec::Box { min, max } => {
            check_len(&format!("{loc}.box.min"), min, dim)?;
            check_len(&format!("{loc}.box.max"), max, dim)?;
            pick(&|c| (0..dim).all(|d| c[d] >= min[d] - tol && c[d] <= max[d] + tol))
        }
        RegionSpec::Segment { from, to } => {
            check_len(&format!("{loc}.segment.from"), from, dim)?;
            check_len(&format!("{loc}.segment.to"), to, dim)?;
            pick(&|c| distance_to_segment(c, from, to, dim) <= tol)
        }
        RegionSpec::Polyline(points) => {
            if points.len() < 2 {
                return Err(CaseError::new(format!("{loc}.polyline"), "needs at least two points"));
            }
            for (k, p) in points.iter().enumerate() {
                check_len(&format!("{loc}.polyline[{k}]"), p, dim)?;
            }
            pick(&|c| points.windows(2).any(|w| distance_to_segment(c, &w[0], &w[1], dim) <= tol))
        }
        RegionSpec::Nearest(p) => {
            check_len(&format!("{loc}.nearest"), p, dim)?;
            nearest_node(coords, p).into_iter().collect()
        }
        RegionSpec::Group(g) => groups
            .get(g)
            .cloned()
            .ok_or_else(|| CaseError::new(format!("{loc}.group"), format!("no Gmsh physical group named '{g}'")))?,
        RegionSpec::All(true) => (0..coords.len()).collect(),
        RegionSpec::All(false) => Vec::new(),
    };
    if nodes.is_empty() {
        return Err(CaseError::new(loc, format!("selects no node: {}", where_nodes_are(spec, coords, dim))));
    }
    Ok(nodes)
}

/// Where the nodes are, for a selection that found none: the span of their coordinates, and
/// for a coordinate plane (`{"x": v}`) the nearest coordinate a node has, as an example.
fn where_nodes_are(spec: &RegionSpec, coords: &[[f64; 3]], dim: usize) -> String {
    let axes = ["x", "y", "z"];
    let span: Vec<String> = (0..dim)
        .map(|d| {
            let (lo, hi) =
                coords.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), c| (l.min(c[d]), h.max(c[d])));
            format!("{} in [{lo}, {hi}]", axes[d])
        })
        .collect();
    let plane = match spec {
        RegionSpec::X(v) => Some((0, *v)),
        RegionSpec::Y(v) => Some((1, *v)),
        RegionSpec::Z(v) => Some((2, *v)),
        _ => None,
    };
    let nearest = plane.and_then(|(d, v)| {
        let c = coords.iter().map(|c| c[d]).min_by(|a, b| (a - v).abs().total_cmp(&(b - v).abs()))?;
        Some((axes[d], v, c))
    });
    match nearest {
        Some((axis, v, c)) => {
            format!(
                "no node has {axis} = {v} (the nodes lie at {}), e.g. {{\"{axis}\": {c}}} (the nearest)",
                span.join(", ")
            )
        }
        None => format!("the nodes lie at {}; check the coordinates against the mesh", span.join(", ")),
    }
}

/// Material points (domain index, id) selected at `loc` by `point` (the nearest one) or
/// `box` (every one inside), of the body named `body` or of any body; an empty selection
/// is an error.
pub(super) fn select_points(
    model: &Model,
    loc: &str,
    dim: usize,
    body: Option<&str>,
    point: Option<&[f64]>,
    within: Option<&PointBox>,
) -> Result<Vec<(usize, usize)>, CaseError> {
    let ranges: Vec<Option<std::ops::Range<usize>>> =
        model.domains.iter().map(|d| body.and_then(|b| d.point_set(b))).collect();
    let candidates = |k: &usize| body.is_none() || ranges[*k].is_some();
    let of_body = |k: usize, id: usize| ranges[k].as_ref().is_none_or(|r| r.contains(&id));
    let selected: Vec<(usize, usize)> = match (point, within) {
        (Some(p), None) => {
            check_len(&format!("{loc}.point"), p, dim)?;
            model
                .domains
                .iter()
                .enumerate()
                .filter(|(k, _)| candidates(k))
                .filter_map(|(k, d)| match &ranges[k] {
                    // the nearest of the body's points
                    Some(r) => {
                        let far = [f64::NEG_INFINITY; 3];
                        let near = [f64::INFINITY; 3];
                        d.points_in_box(&far[..dim], &near[..dim])
                            .into_iter()
                            .filter(|id| r.contains(id))
                            .filter_map(|id| {
                                let x = d.point_quantity(id, loam_fem::domain::PointQuantity::Position)?;
                                Some((k, id, (0..dim).map(|i| (x[i] - p[i]).powi(2)).sum::<f64>().sqrt()))
                            })
                            .min_by(|a, b| a.2.total_cmp(&b.2))
                    }
                    None => d.nearest_point(p).map(|(id, dist)| (k, id, dist)),
                })
                .min_by(|a, b| a.2.total_cmp(&b.2))
                .map(|(k, id, _)| vec![(k, id)])
                .unwrap_or_default()
        }
        (None, Some(b)) => {
            check_len(&format!("{loc}.box.min"), &b.min, dim)?;
            check_len(&format!("{loc}.box.max"), &b.max, dim)?;
            model
                .domains
                .iter()
                .enumerate()
                .filter(|(k, _)| candidates(k))
                .flat_map(|(k, d)| {
                    d.points_in_box(&b.min, &b.max).into_iter().filter(move |&id| of_body(k, id)).map(move |id| (k, id))
                })
                .collect()
        }
        _ => return Err(CaseError::new(loc, "give either point or box")),
    };
    if selected.is_empty() {
        let place = match body {
            Some(b) => format!("domain '{b}'"),
            None => "the model".into(),
        };
        return Err(CaseError::new(
            format!("{loc}.{}", if point.is_some() { "point" } else { "box" }),
            format!("selects no material point ({place} has none there)"),
        ));
    }
    Ok(selected)
}

/// Index of the node nearest to `p` (first `p.len()` coordinates).
pub fn nearest_node(coords: &[[f64; 3]], p: &[f64]) -> Option<usize> {
    let dist = |c: &[f64; 3]| p.iter().enumerate().map(|(d, v)| (c[d] - v).powi(2)).sum::<f64>();
    (0..coords.len()).min_by(|&a, &b| dist(&coords[a]).total_cmp(&dist(&coords[b])))
}

/// Area-weighted mean outward normal of the boundary `facets` (global node ids) whose nodes
/// all lie in `nodes`.
pub(super) fn mean_boundary_normal(coords: &[[f64; 3]], facets: &[Vec<usize>], nodes: &[usize]) -> Option<[f64; 3]> {
    let set: std::collections::HashSet<usize> = nodes.iter().copied().collect();
    let mut sum = [0.0; 3];
    let mut found = false;
    for f in facets {
        if !f.iter().all(|n| set.contains(n)) {
            continue;
        }
        found = true;
        let x: Vec<[f64; 3]> = f.iter().map(|&n| coords[n]).collect();
        let n = match x.len() {
            2 => [x[1][1] - x[0][1], x[0][0] - x[1][0], 0.0],
            _ => {
                let (a, b) = ([0, 1, 2].map(|d| x[1][d] - x[0][d]), [0, 1, 2].map(|d| x[2][d] - x[0][d]));
                [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
            }
        };
        for d in 0..3 {
            sum[d] += n[d];
        }
    }
    found.then_some(sum)
}
