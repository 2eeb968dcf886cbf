//! The free surface of a body of material points seen from above (plane problems): the
//! top envelope of the points' squares, with the runout and the height at a wall that
//! column-collapse experiments report (Bui et al. 2008; Lube et al. 2005).
//!
//! Each point `p` at `(x_p, y_p)` with size `s_p` (side of the square of its current
//! volume) covers `[x_p − s_p/2, x_p + s_p/2] × [y_p − s_p/2, y_p + s_p/2]`. The surface
//! height above the base `y_b` at `x` is `h(x) = max_p (y_p + s_p/2) − y_b` over the points
//! whose square covers `x`.

/// Material points as seen by the surface: positions and sizes.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceProfile<'a> {
    points: &'a [([f64; 3], f64)],
    base: f64,
}

impl<'a> SurfaceProfile<'a> {
    /// The surface of `points` (position, size) above the base line `y = base`.
    pub fn new(points: &'a [([f64; 3], f64)], base: f64) -> Self {
        Self { points, base }
    }

    /// Surface height `h(x)` above the base (0 where no point covers `x`). A point covers
    /// `x` when `|x_p − x| ≤ s_p/2`; the bound is widened by 20 % so that the height at a
    /// wall, where the outermost squares may end a little short of it, is found.
    pub fn height_at(&self, x: f64) -> f64 {
        self.points
            .iter()
            .filter(|(p, s)| (p[0] - x).abs() <= 0.6 * s)
            .map(|(p, s)| p[1] + 0.5 * s - self.base)
            .fold(0.0, f64::max)
    }

    /// Runout measured from the wall at `x = wall` towards `+x`: the end of the connected
    /// stretch, starting at the wall, where the surface stands at least `threshold` above
    /// the base. Squares are joined across gaps up to half a point size (points of a
    /// deformed body do not tile exactly); detached points beyond a larger gap do not count.
    pub fn runout(&self, wall: f64, threshold: f64) -> f64 {
        let mut spans: Vec<(f64, f64, f64)> = self
            .points
            .iter()
            .filter(|(p, s)| p[1] + 0.5 * s - self.base >= threshold && p[0] + 0.5 * s > wall)
            .map(|(p, s)| (p[0] - 0.5 * s, p[0] + 0.5 * s, *s))
            .collect();
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut reach = wall;
        for (left, right, size) in spans {
            if left > reach + 0.5 * size {
                break;
            }
            reach = reach.max(right);
        }
        reach - wall
    }

    /// Root mean square of `h(x_k) − y_k` over a reference surface `(x_k, y_k)` (heights
    /// above the base).
    pub fn rms_distance(&self, reference: &[(f64, f64)]) -> f64 {
        if reference.is_empty() {
            return 0.0;
        }
        let sum: f64 = reference.iter().map(|&(x, y)| (self.height_at(x) - y).powi(2)).sum();
        (sum / reference.len() as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A triangle heap of unit-spaced points: height and runout are those of the staircase.
    #[test]
    fn staircase_heap() {
        // columns i = 0..10 at x = 0.5 + i, heights 10 − i points
        let mut pts = Vec::new();
        for i in 0..10 {
            for j in 0..(10 - i) {
                pts.push(([0.5 + i as f64, 0.5 + j as f64, 0.0], 1.0));
            }
        }
        let s = SurfaceProfile::new(&pts, 0.0);
        assert_eq!(s.height_at(0.0), 10.0);
        assert_eq!(s.height_at(3.5), 7.0);
        assert_eq!(s.runout(0.0, 0.5), 10.0);
        assert_eq!(s.runout(0.0, 3.0), 8.0);
        // a detached point far ahead does not extend the runout
        pts.push(([20.5, 0.5, 0.0], 1.0));
        assert_eq!(SurfaceProfile::new(&pts, 0.0).runout(0.0, 0.5), 10.0);
        let reference = [(2.5, 8.0), (4.5, 6.0)];
        assert!(SurfaceProfile::new(&pts, 0.0).rms_distance(&reference) < 1e-12);
    }
}
