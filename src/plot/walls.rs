//! Penalty walls as lines, from the case file that `summary.json` names.
//!
//! A wall's output series holds its penalty points: the boundary particles along it
//! (Dirichlet form) or the material points near it (contact form), neither of which is the
//! wall itself. Its line comes from the case: the segment or polyline moved by its
//! `displacement` × `amplitude(t)`.

use std::path::Path;

use loam_fem::amplitude::Amplitude;

use crate::case::Case;

/// A rigid wall: name, vertices at t = 0 and motion.
#[derive(Debug, Clone, PartialEq)]
pub struct WallLine {
    /// The boundary condition's name (its output series is `<name>.pvd`).
    pub name: Option<String>,
    /// Vertices at t = 0 (m).
    pub vertices: Vec<[f64; 2]>,
    /// Displacement at amplitude 1 (m).
    pub displacement: [f64; 2],
    /// Time function scaling the displacement.
    pub amplitude: Amplitude,
}

impl WallLine {
    /// The vertices at time `t`.
    pub fn at(&self, t: f64) -> Vec<[f64; 2]> {
        let a = self.amplitude.at(t);
        self.vertices.iter().map(|v| [v[0] + a * self.displacement[0], v[1] + a * self.displacement[1]]).collect()
    }
}

/// The penalty walls of the case file at `path` (2D cases).
pub fn walls_of_case(path: &Path) -> Result<Vec<WallLine>, String> {
    let case = Case::load(path).map_err(|e| e.to_string())?;
    Ok(case
        .boundary_conditions
        .iter()
        .filter_map(|bc| {
            let p = bc.penalty.as_ref()?;
            let vertices = match (&p.segment, &p.polyline) {
                (Some(s), _) => s.to_vec(),
                (None, Some(line)) => line.clone(),
                (None, None) => return None,
            };
            let d = |k: usize| bc.displacement.get(k).copied().flatten().unwrap_or(0.0);
            Some(WallLine {
                name: bc.name.clone(),
                vertices,
                displacement: [d(0), d(1)],
                amplitude: bc.amplitude.clone(),
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_repose_gate_moves_with_its_amplitude() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/repose_phi20.json");
        let walls = walls_of_case(&path).unwrap();
        let gate = walls.iter().find(|w| w.name.as_deref() == Some("gate")).expect("the gate wall");
        let (start, later) = (gate.at(0.0), gate.at(1.0));
        assert_eq!(start, gate.vertices);
        // cases/repose_phi20.json: 0.3 m to the right over 6 s, linearly
        assert!((later[0][0] - start[0][0] - 0.05).abs() < 1e-12 && later[0][1] == start[0][1], "{start:?} {later:?}");
    }
}
