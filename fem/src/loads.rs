//! Surface loads on boundary facets: equivalent nodal forces `f_a = ∫ N_a t dA` of a
//! traction `t` (or a pressure, `t = −p n`) on the reference configuration (dead loads).
//!
//! Edges are integrated with 2 Gauss points (exact for the `2πr` factor of axisymmetry),
//! quadrilateral faces with 2×2, triangular faces exactly (one third per node).

use crate::element::ElementType;
use crate::formulation::Formulation;

/// What acts on a facet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SurfaceLoad {
    /// Pressure `p` (Pa), positive pushing into the body: `t = −p n`.
    Pressure(f64),
    /// Traction vector `t` (Pa).
    Traction([f64; 3]),
}

impl SurfaceLoad {
    fn traction(self, unit_normal: [f64; 3]) -> [f64; 3] {
        match self {
            SurfaceLoad::Pressure(p) => unit_normal.map(|n| -p * n),
            SurfaceLoad::Traction(t) => t,
        }
    }
}

/// Adds the nodal forces of `load` on the facet with node coordinates `coords` (outward
/// orientation) to `forces` (one `[f64; 3]` per facet node).
pub fn facet_forces(
    formulation: Formulation,
    thickness: f64,
    coords: &[[f64; 3]],
    load: SurfaceLoad,
    forces: &mut [[f64; 3]],
) {
    let g = 1.0 / 3f64.sqrt();
    match coords.len() {
        2 => {
            let (x0, x1) = (coords[0], coords[1]);
            let (dx, dy) = (x1[0] - x0[0], x1[1] - x0[1]);
            let len = (dx * dx + dy * dy).sqrt();
            let t = load.traction([dy / len, -dx / len, 0.0]);
            for s in [-g, g] {
                let n = [0.5 * (1.0 - s), 0.5 * (1.0 + s)];
                let r = n[0] * x0[0] + n[1] * x1[0];
                let w = 0.5 * len * formulation.measure_factor(thickness, r);
                for a in 0..2 {
                    for i in 0..3 {
                        forces[a][i] += w * n[a] * t[i];
                    }
                }
            }
        }
        3 => {
            let e1 = sub(coords[1], coords[0]);
            let e2 = sub(coords[2], coords[0]);
            let c = cross(e1, e2);
            let area2 = norm(c);
            let t = load.traction(c.map(|v| v / area2));
            for f in forces.iter_mut().take(3) {
                for i in 0..3 {
                    f[i] += area2 / 6.0 * t[i];
                }
            }
        }
        4 => {
            let mut dn = [[0.0; 3]; 8];
            let mut n = [0.0; 8];
            for (sx, sy) in [(-g, -g), (g, -g), (g, g), (-g, g)] {
                let xi = [sx, sy, 0.0];
                ElementType::Quad4.shape_functions(&xi, &mut n);
                ElementType::Quad4.shape_gradients(&xi, &mut dn);
                let mut t1 = [0.0; 3];
                let mut t2 = [0.0; 3];
                for a in 0..4 {
                    for i in 0..3 {
                        t1[i] += dn[a][0] * coords[a][i];
                        t2[i] += dn[a][1] * coords[a][i];
                    }
                }
                let c = cross(t1, t2);
                let da = norm(c);
                let t = load.traction(c.map(|v| v / da));
                for a in 0..4 {
                    for i in 0..3 {
                        forces[a][i] += da * n[a] * t[i];
                    }
                }
            }
        }
        _ => unreachable!("facets have 2, 3 or 4 nodes"),
    }
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn norm(a: [f64; 3]) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pressure_on_an_edge_and_a_face_sums_to_p_times_area() {
        let mut f = [[0.0; 3]; 2];
        // bottom edge of a CCW element, outward normal −y: pressure pushes +y
        facet_forces(
            Formulation::PlaneStrain,
            2.0,
            &[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0]],
            SurfaceLoad::Pressure(10.0),
            &mut f,
        );
        assert!((f[0][1] + f[1][1] - 10.0 * 3.0 * 2.0).abs() < 1e-12);
        let mut f = [[0.0; 3]; 4];
        let face = [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [2.0, 1.0, 1.0], [0.0, 1.0, 1.0]];
        facet_forces(Formulation::ThreeD, 1.0, &face, SurfaceLoad::Pressure(5.0), &mut f);
        let fz: f64 = f.iter().map(|v| v[2]).sum();
        assert!((fz + 10.0).abs() < 1e-12);
        // axisymmetric annulus r ∈ [1, 2] at the top: force = p π (r2² − r1²)
        let mut f = [[0.0; 3]; 2];
        facet_forces(
            Formulation::Axisymmetric,
            1.0,
            &[[2.0, 1.0, 0.0], [1.0, 1.0, 0.0]],
            SurfaceLoad::Pressure(1.0),
            &mut f,
        );
        assert!((f[0][1] + f[1][1] + std::f64::consts::PI * 3.0).abs() < 1e-12);
    }
}
