//! What error messages suggest (issue 28): the valid name nearest to a misspelt one, and an
//! example of what a key expects.

/// Edit distance between `a` and `b`: the fewest insertions, deletions, substitutions and
/// swaps of two neighbouring characters (`clmap` → `clamp` is one) that turn one into the
/// other (optimal string alignment, by characters).
pub fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b): (Vec<char>, Vec<char>) = (a.chars().collect(), b.chars().collect());
    let mut d = vec![vec![0usize; b.len() + 1]; a.len() + 1];
    for (i, row) in d.iter_mut().enumerate() {
        row[0] = i;
    }
    for j in 0..=b.len() {
        d[0][j] = j;
    }
    for i in 1..=a.len() {
        for j in 1..=b.len() {
            let cost = usize::from(a[i - 1] != b[j - 1]);
            d[i][j] = (d[i - 1][j - 1] + cost).min(d[i - 1][j] + 1).min(d[i][j - 1] + 1);
            if i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1] {
                d[i][j] = d[i][j].min(d[i - 2][j - 2] + 1);
            }
        }
    }
    d[a.len()][b.len()]
}

/// The candidate nearest to `word`, if it is near enough to be what was meant: at most a
/// third of the word's characters edited (at least one), ignoring case; the first of equal
/// ones.
pub fn nearest<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let word = word.to_lowercase();
    let limit = (word.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .map(|c| (edit_distance(&word, &c.to_lowercase()), c))
        .filter(|&(d, _)| d <= limit)
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// `did you mean "name"? ` for the candidate nearest to `word`, or nothing.
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    nearest(word, candidates).map(|c| format!("did you mean \"{c}\"? ")).unwrap_or_default()
}

/// What an array at `key` (the last key of its JSON path) holds, and an example of `dim`
/// entries: `("cells per direction", "[64, 24]")`.
pub fn example_vector(key: &str, dim: usize) -> (&'static str, &'static str) {
    let three = dim == 3;
    match key {
        "cells" => ("whole numbers of cells per direction", if three { "[10, 10, 4]" } else { "[64, 24]" }),
        "size" => ("lengths in m per direction", if three { "[1, 1, 0.5]" } else { "[8, 3]" }),
        "acceleration" => ("components in m/s²", if three { "[0, 0, -9.81]" } else { "[0, -9.81]" }),
        "displacement" => ("components in m, null for free", if three { "[0, 0, null]" } else { "[0, null]" }),
        "force" => ("components in N", if three { "[0, 0, -1000]" } else { "[0, -1000]" }),
        "traction" => ("components in Pa", if three { "[0, 0, -50]" } else { "[0, -50]" }),
        "normal" => ("components", if three { "[0, 0, 1]" } else { "[0, 1]" }),
        "uniform" | "amplitude" => ("components", if three { "[0, 0, -1]" } else { "[0, -1]" }),
        "wavenumber" => ("components in rad/m", if three { "[0.2, 0, 0]" } else { "[0.2, 0]" }),
        "origin" | "min" | "from" => ("coordinates in m", if three { "[0, 0, 0]" } else { "[0, 0]" }),
        _ => ("coordinates in m", if three { "[7, 0.5, 0.5]" } else { "[7, 0.5]" }),
    }
}

/// An example value of the scalar key `key` as it would be written in a case file, where
/// one is known (the material parameters and the common keys).
pub fn example_value(key: &str) -> Option<&'static str> {
    Some(match key {
        "description" => "\"what the case shows\"",
        "name" => "\"beam\"",
        "material" => "\"beam\"",
        "region" => "\"clamp\"",
        "law" => "\"neo_hookean\"",
        "density" => "2000",
        "young_modulus" => "1e7",
        "poisson_ratio" => "0.3",
        "friction_angle" | "peak_friction_angle" => "30",
        "residual_friction_angle" => "20",
        "cohesion" | "residual_cohesion" => "0",
        "peak_cohesion" => "1e4",
        "dilatancy_angle" | "residual_dilatancy_angle" => "0",
        "peak_dilatancy_angle" => "5",
        "shape_factor" => "10",
        "preconsolidation_pressure" => "2e5",
        "ocr" => "1",
        "swelling_slope" => "0.02",
        "compression_slope" => "0.1",
        "critical_state_slope" => "1.2",
        "initial_shear_modulus" => "5e6",
        "alpha_shear" => "0",
        "fit" => "\"plane_strain\"",
        "static_friction_coefficient" => "0.38",
        "limit_friction_coefficient" => "0.64",
        "reference_inertial_number" => "0.28",
        "grain_diameter" => "0.001",
        "grain_density" => "2500",
        "viscosity" => "0.001",
        "bulk_modulus" => "2e9",
        "time_step" => "0.01",
        "end_time" => "1.0",
        "points_per_cell" => "4",
        "spacing" => "0.05",
        "radius" => "0.5",
        "penalty_factor" => "1e13",
        "pressure" => "1000",
        "component" => "\"y\"",
        "min_time_step" => "1e-5",
        "max_time_step" => "5e-3",
        "max_iterations" => "20",
        "interval" => "1",
        "mpm_pattern_rings" => "1",
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances() {
        assert_eq!(edit_distance("", "abc"), 3);
        assert_eq!(edit_distance("kitten", "sitting"), 3);
        assert_eq!(edit_distance("youngs_modulus", "young_modulus"), 1);
        assert_eq!(edit_distance("same", "same"), 0);
        assert_eq!(edit_distance("clmap", "clamp"), 1);
    }

    #[test]
    fn nearest_names() {
        let laws = ["linear_elastic", "neo_hookean", "hencky", "mohr_coulomb"];
        assert_eq!(nearest("neohookean", laws), Some("neo_hookean"));
        assert_eq!(nearest("Neo_Hookean", laws), Some("neo_hookean"));
        assert_eq!(nearest("quad", ["tri3", "quad4", "tet4", "hex8"]), Some("quad4"));
        assert_eq!(nearest("granite", laws), None);
        assert_eq!(did_you_mean("clmap", ["clamp", "tip"]), "did you mean \"clamp\"? ");
        assert_eq!(did_you_mean("zzz", ["clamp"]), "");
    }
}
