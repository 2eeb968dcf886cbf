//! `loam check`: builds a case without running it and prints what it holds.

use std::path::Path;
use std::process::ExitCode;

use super::bad_input;
use crate::simulation::Simulation;

/// Parses and builds `case` (parameters, meshes, regions, interfaces); prints its size and
/// interfaces, or the one-line error (exit 2).
pub fn check_command(case: &Path) -> ExitCode {
    match Simulation::from_file(case) {
        Ok(sim) => {
            println!(
                "{}: ok — {} nodes, {} domains, {} DOFs, {} steps, monitors: {}",
                case.display(),
                sim.model.coords.len(),
                sim.model.domains.len(),
                sim.model.num_dofs(),
                sim.total_steps(),
                sim.monitor_names().join(", ")
            );
            let measure = if sim.model.dim == 2 { ("length", "m") } else { ("area", "m²") };
            for i in &sim.interfaces {
                println!(
                    "  interface '{}': {}, {} nodes, {} {:.6} {}",
                    i.name,
                    match (i.law, i.slip) {
                        (Some(law), _) => law.to_string(),
                        (None, true) => "frictionless slip".into(),
                        (None, false) => "tied".into(),
                    },
                    i.nodes,
                    measure.0,
                    i.measure,
                    measure.1
                );
            }
            for r in &sim.rigid_bodies {
                let names = ["u_x", "u_y", "θ"];
                let held: Vec<&str> = (0..3).filter(|&k| r.held[k]).map(|k| names[k]).collect();
                let motion = match held.len() {
                    0 => "free".to_string(),
                    3 => "driven (u_x, u_y, θ prescribed)".to_string(),
                    _ => format!("{} prescribed, the rest free", held.join(", ")),
                };
                println!(
                    "  rigid body '{}': mass {:.6e} kg, moment of inertia {:.6e} kg m² about its centroid ({:.6}, {:.6}) m; {motion}",
                    r.name, r.mass, r.inertia, r.centre[0], r.centre[1]
                );
            }
            ExitCode::SUCCESS
        }
        Err(e) => bad_input(&e),
    }
}
