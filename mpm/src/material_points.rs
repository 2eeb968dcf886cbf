//! Material points in struct-of-arrays storage, and their generation from body geometry.

use loam_fem::element::{ElementType, GaussPoint};
use loam_fem::formulation::Formulation;
use loam_fem::kernel::point_geometry;
use loam_fem::mesh::Mesh;
use nalgebra::Matrix3;

/// Material points (struct of arrays). Index order changes every step (points are sorted
/// by cell); `id` is stable.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct MaterialPoints {
    /// Stable identifier (index at creation).
    pub id: Vec<usize>,
    /// Current position.
    pub position: Vec<[f64; 3]>,
    /// Displacement from the initial position.
    pub displacement: Vec<[f64; 3]>,
    /// Velocity.
    pub velocity: Vec<[f64; 3]>,
    /// Acceleration.
    pub acceleration: Vec<[f64; 3]>,
    /// Mass (kg; per unit thickness × thickness, or the full ring in axisymmetry).
    pub mass: Vec<f64>,
    /// Current volume (m³, same convention as the mass).
    pub volume: Vec<f64>,
    /// Initial volume.
    pub initial_volume: Vec<f64>,
    /// Deformation gradient `F`.
    pub deformation_gradient: Vec<Matrix3<f64>>,
    /// Cauchy stress `σ`.
    pub cauchy: Vec<Matrix3<f64>>,
    /// Accumulated work of the stress per point (J).
    pub work: Vec<f64>,
    /// Committed law history, `state_len` values per point.
    pub state: Vec<f64>,
}

impl MaterialPoints {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.id.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.id.is_empty()
    }

    /// Appends a point at rest at `x` with volume `volume` and density `density`.
    pub fn push(&mut self, x: [f64; 3], volume: f64, density: f64) {
        self.id.push(self.id.len());
        self.position.push(x);
        self.displacement.push([0.0; 3]);
        self.velocity.push([0.0; 3]);
        self.acceleration.push([0.0; 3]);
        self.mass.push(density * volume);
        self.volume.push(volume);
        self.initial_volume.push(volume);
        self.deformation_gradient.push(Matrix3::identity());
        self.cauchy.push(Matrix3::zeros());
        self.work.push(0.0);
    }

    /// Values of a point's record ([`MaterialPoints::pack`]) besides its law history.
    pub const RECORD_LEN: usize = 35;

    /// Appends point `p` as a record of [`MaterialPoints::RECORD_LEN`] `+ stride` values
    /// (its id, position, displacement, velocity, acceleration, mass, volume, initial volume,
    /// deformation gradient, Cauchy stress, work and the law's `stride` history values): every
    /// field a point carries from step to step, copied bit for bit, so that a point sent to
    /// another rank ([`MaterialPoints::push_record`]) is the same point there.
    pub fn pack(&self, p: usize, stride: usize, out: &mut Vec<f64>) {
        out.push(self.id[p] as f64);
        for v in [&self.position[p], &self.displacement[p], &self.velocity[p], &self.acceleration[p]] {
            out.extend_from_slice(v);
        }
        out.extend_from_slice(&[self.mass[p], self.volume[p], self.initial_volume[p]]);
        out.extend_from_slice(self.deformation_gradient[p].as_slice());
        out.extend_from_slice(self.cauchy[p].as_slice());
        out.push(self.work[p]);
        out.extend_from_slice(&self.state[p * stride..(p + 1) * stride]);
    }

    /// Appends the point of a record of [`MaterialPoints::pack`].
    pub fn push_record(&mut self, record: &[f64], stride: usize) {
        debug_assert_eq!(record.len(), Self::RECORD_LEN + stride);
        let vec3 = |k: usize| [record[k], record[k + 1], record[k + 2]];
        self.id.push(record[0] as usize);
        self.position.push(vec3(1));
        self.displacement.push(vec3(4));
        self.velocity.push(vec3(7));
        self.acceleration.push(vec3(10));
        self.mass.push(record[13]);
        self.volume.push(record[14]);
        self.initial_volume.push(record[15]);
        self.deformation_gradient.push(Matrix3::from_column_slice(&record[16..25]));
        self.cauchy.push(Matrix3::from_column_slice(&record[25..34]));
        self.work.push(record[34]);
        self.state.extend_from_slice(&record[Self::RECORD_LEN..]);
    }

    /// Keeps the points `order[k]` in that order (a permutation or a subset); `stride` is
    /// the law's history length.
    pub fn reorder(&mut self, order: &[usize], stride: usize) {
        fn pick<T: Copy>(v: &mut Vec<T>, order: &[usize]) {
            *v = order.iter().map(|&k| v[k]).collect();
        }
        pick(&mut self.id, order);
        pick(&mut self.position, order);
        pick(&mut self.displacement, order);
        pick(&mut self.velocity, order);
        pick(&mut self.acceleration, order);
        pick(&mut self.mass, order);
        pick(&mut self.volume, order);
        pick(&mut self.initial_volume, order);
        pick(&mut self.deformation_gradient, order);
        pick(&mut self.cauchy, order);
        pick(&mut self.work, order);
        self.state = order.iter().flat_map(|&k| self.state[k * stride..(k + 1) * stride].iter().copied()).collect();
    }
}

/// Gauss–Legendre abscissae and weights of order `k` on [−1, 1].
fn gauss_legendre(k: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    Some(match k {
        1 => (vec![0.0], vec![2.0]),
        2 => {
            let g = 1.0 / 3f64.sqrt();
            (vec![-g, g], vec![1.0, 1.0])
        }
        3 => {
            let g = 0.6f64.sqrt();
            (vec![-g, 0.0, g], vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0])
        }
        4 => {
            let (a, b) = (0.339_981_043_584_856_3, 0.861_136_311_594_052_6);
            let (wa, wb) = (0.652_145_154_862_546_1, 0.347_854_845_137_453_9);
            (vec![-b, -a, a, b], vec![wb, wa, wa, wb])
        }
        _ => return None,
    })
}

/// Positions (local) and weights of `n` points per cell of `element`: Gauss positions
/// (k×k or k×k×k for quads and hexes; 1, 3 for triangles; 1, 4 for tetrahedra).
pub fn points_per_cell(element: ElementType, n: usize) -> Result<Vec<GaussPoint>, String> {
    let bad = || {
        format!(
            "{n} points per cell is not available for {} (use {})",
            element.name(),
            match element {
                ElementType::Quad4 => "1, 4, 9 or 16",
                ElementType::Hex8 => "1, 8, 27 or 64",
                ElementType::Tri3 => "1 or 3",
                ElementType::Tet4 => "1 or 4",
            }
        )
    };
    match element {
        ElementType::Quad4 | ElementType::Hex8 => {
            let dim = element.dim();
            let k = (n as f64).powf(1.0 / dim as f64).round() as usize;
            if k.pow(dim as u32) != n {
                return Err(bad());
            }
            let (x, w) = gauss_legendre(k).ok_or_else(bad)?;
            let mut out = Vec::new();
            for c in 0..(if dim == 3 { k } else { 1 }) {
                for b in 0..k {
                    for a in 0..k {
                        let (z, wz) = if dim == 3 { (x[c], w[c]) } else { (0.0, 1.0) };
                        out.push(GaussPoint { xi: [x[a], x[b], z], weight: w[a] * w[b] * wz });
                    }
                }
            }
            Ok(out)
        }
        ElementType::Tri3 | ElementType::Tet4 => match n {
            1 => Ok(element.gauss_points()),
            3 if element == ElementType::Tri3 => Ok(element.gauss_points_high()),
            4 if element == ElementType::Tet4 => Ok(element.gauss_points_high()),
            _ => Err(bad()),
        },
    }
}

/// Material points at `n` Gauss positions of every cell of `mesh`, with the cell's volume
/// shared by the Gauss weights (thickness or 2πr included).
pub fn from_mesh(
    mesh: &Mesh,
    n: usize,
    formulation: Formulation,
    thickness: f64,
    density: f64,
) -> Result<MaterialPoints, String> {
    let rule = points_per_cell(mesh.element, n)?;
    let mut mp = MaterialPoints::default();
    for e in 0..mesh.num_cells() {
        let coords: Vec<[f64; 3]> = mesh.cell(e).iter().map(|&a| mesh.coords[a]).collect();
        for gp in &rule {
            let g = point_geometry(mesh.element, formulation, thickness, &coords, &gp.xi, gp.weight, None)
                .map_err(|err| format!("body cell {e}: {err}"))?;
            let mut x = [0.0; 3];
            for (a, c) in coords.iter().enumerate() {
                for d in 0..3 {
                    x[d] += g.shape[a] * c[d];
                }
            }
            mp.push(x, g.weight, density);
        }
    }
    Ok(mp)
}

/// Material points on a square lattice of spacing `s` inside a 2D shape `inside`, each
/// carrying `s²` times the thickness (or `2πr s²` in axisymmetry).
pub fn from_lattice_2d(
    lower: [f64; 2],
    upper: [f64; 2],
    s: f64,
    formulation: Formulation,
    thickness: f64,
    density: f64,
    inside: impl Fn(f64, f64) -> bool,
) -> MaterialPoints {
    let mut mp = MaterialPoints::default();
    let nx = ((upper[0] - lower[0]) / s).ceil() as usize;
    let ny = ((upper[1] - lower[1]) / s).ceil() as usize;
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (lower[0] + (i as f64 + 0.5) * s, lower[1] + (j as f64 + 0.5) * s);
            if inside(x, y) {
                mp.push([x, y, 0.0], s * s * formulation.measure_factor(thickness, x), density);
            }
        }
    }
    mp
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point packed and pushed back is the same point, bit for bit, in every field.
    #[test]
    fn a_packed_point_is_pushed_back_bit_for_bit() {
        let mut pts = MaterialPoints::default();
        for k in 0..3 {
            pts.push([0.1 * k as f64, 0.2, -0.3], 1e-3 * (k + 1) as f64, 2650.0);
        }
        let stride = 2;
        pts.state = (0..3 * stride).map(|v| 0.7 * v as f64 - 1.0).collect();
        pts.velocity[1] = [1.0 / 3.0, -2.0 / 7.0, 5e-17];
        pts.deformation_gradient[1] = Matrix3::new(1.1, 0.2, 0.0, -0.1, 0.9, 0.3, 0.0, 0.05, 1.0);
        pts.cauchy[1] = Matrix3::new(-1e3, 12.5, 0.0, 12.5, -2e3, 0.0, 0.0, 0.0, -1.5e3);
        pts.work[1] = 0.125;
        pts.id[1] = 41;
        let mut record = Vec::new();
        pts.pack(1, stride, &mut record);
        assert_eq!(record.len(), MaterialPoints::RECORD_LEN + stride);
        let mut other = MaterialPoints::default();
        other.push_record(&record, stride);
        let mut back = Vec::new();
        other.pack(0, stride, &mut back);
        assert_eq!(
            record.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
            back.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
        );
        assert_eq!(other.id, vec![41]);
        assert_eq!(other.deformation_gradient[0], pts.deformation_gradient[1]);
        assert_eq!(other.state, pts.state[stride..2 * stride].to_vec());
    }
}
