//! The free surface of a body of material points seen from above (plane problems): the
//! top envelope of the points' squares, with the runout and the height at a wall that
//! column-collapse experiments report (Bui et al. 2008; Lube et al. 2005).
//!
//! Each point `p` at `(x_p, y_p)` with size `s_p` (side of the square of its current
//! volume) and initial size `s₀_p` covers `[x_p − s_p/2, x_p + s_p/2]` and stands up to
//! `y_p + min(s_p, s₀_p)/2` (a point whose volume has grown spreads, it does not rise:
//! [`PointExtent`]). The surface height above the base `y_b` at `x` is
//! `h(x) = max_p (y_p + min(s_p, s₀_p)/2) − y_b` over the points that cover `x`.
//!
//! The inclination of a heap's flank ([`SurfaceProfile::slope_fit`]) is the least-squares
//! line through `h(x)` sampled over the part of the flank between two fractions of the heap
//! height, which leaves out the rounded crest and the toe.

use loam_fem::domain::PointExtent;

/// A straight line fitted to the free surface: `h(x) ≈ intercept + slope · x`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlopeFit {
    /// Height of the line at `x = 0` above the base (m).
    pub intercept: f64,
    /// `dh/dx` (negative on a flank that falls towards `+x`).
    pub slope: f64,
    /// Inclination from the horizontal, `atan |dh/dx|` in degrees.
    pub angle: f64,
    /// Heap height `H`: the largest `h(x_k)` over the sampled range (m).
    pub height: f64,
    /// First and last abscissa of the fitted samples (m).
    pub x_span: [f64; 2],
    /// Number of fitted samples.
    pub samples: usize,
    /// Root mean square of the residuals `h(x_k) − (intercept + slope x_k)` (m).
    pub rms_residual: f64,
}

/// A stretch of the surface along `x`: `(left, right, size)` of a point's square, or of a run
/// of overlapping squares with the size of its first ([`SurfaceProfile::runout_runs`]).
pub type Span = (f64, f64, f64);

/// The runout from the wall at `x = wall` over `spans` (see [`SurfaceProfile::runout`]):
/// sorted by their left ends, they are joined from the wall across gaps up to half the size
/// of the span that follows the gap.
pub fn runout_of_spans(mut spans: Vec<Span>, wall: f64) -> f64 {
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

/// The material beyond a wall at `x = wall`, binned along `x`: bin `k` sums `amount(p)` over
/// the points whose centres lie in `[wall + k·bin, wall + (k + 1)·bin)`, and the last bin is
/// empty (one past the farthest point). With `amount` a point's area (plane problems) the
/// bins divided by `bin` are the deposit's thickness `t_k` that
/// [`runout_of_thickness`] reads.
pub fn binned_along_x(points: &[PointExtent], wall: f64, bin: f64, amount: impl Fn(&PointExtent) -> f64) -> Vec<f64> {
    let mut bins = Vec::new();
    for p in points.iter().filter(|p| p.position[0] >= wall) {
        let k = ((p.position[0] - wall) / bin) as usize;
        if bins.len() < k + 2 {
            bins.resize(k + 2, 0.0);
        }
        bins[k] += amount(p);
    }
    bins
}

/// The runout from the wall read from the deposit's thickness `t_k` in bins of width `bin`
/// from the wall ([`binned_along_x`]): where the profile through the bin centres
/// `x_k = (k + ½)·bin`, linear between them, falls to `threshold` for the last time,
///
/// $$ L = x_k + \frac{t_k - t_\text{thr}}{t_k - t_{k+1}}\,\text{bin}, \qquad
///    k = \max\{k : t_k \ge t_\text{thr}\}, $$
///
/// 0 if no bin reaches the threshold. Unlike [`SurfaceProfile::runout`] it does not depend on
/// how the points are stacked (a sheet one or two points thick gives the same thickness), and
/// a detached clump counts where it is that thick; a sharp end is placed to within half a bin.
pub fn runout_of_thickness(thickness: &[f64], bin: f64, threshold: f64) -> f64 {
    let Some(k) = thickness.iter().rposition(|&t| t >= threshold) else { return 0.0 };
    let next = thickness.get(k + 1).copied().unwrap_or(0.0);
    (k as f64 + 0.5) * bin + (thickness[k] - threshold) / (thickness[k] - next) * bin
}

/// Material points as seen by the surface: positions and sizes.
#[derive(Debug, Clone, Copy)]
pub struct SurfaceProfile<'a> {
    points: &'a [PointExtent],
    base: f64,
}

impl<'a> SurfaceProfile<'a> {
    /// The surface of `points` above the base line `y = base`.
    pub fn new(points: &'a [PointExtent], base: f64) -> Self {
        Self { points, base }
    }

    /// Surface height `h(x)` above the base (0 where no point covers `x`). A point covers
    /// `x` when `|x_p − x| ≤ s_p/2`; the bound is widened by 20 % so that the height at a
    /// wall, where the outermost squares may end a little short of it, is found.
    pub fn height_at(&self, x: f64) -> f64 {
        self.points
            .iter()
            .filter(|p| (p.position[0] - x).abs() <= 0.6 * p.size)
            .map(|p| p.position[1] + p.half_height() - self.base)
            .fold(0.0, f64::max)
    }

    /// Runout measured from the wall at `x = wall` towards `+x`: the end of the connected
    /// stretch, starting at the wall, where the surface stands at least `threshold` above
    /// the base. Squares are joined across gaps up to half a point size (points of a
    /// deformed body do not tile exactly); detached points beyond a larger gap do not count.
    pub fn runout(&self, wall: f64, threshold: f64) -> f64 {
        runout_of_spans(self.spans(wall, threshold), wall)
    }

    /// The squares that [`SurfaceProfile::runout`] joins, `(left, right, size)`, sorted by
    /// their left ends.
    fn spans(&self, wall: f64, threshold: f64) -> Vec<Span> {
        let mut spans: Vec<Span> = self
            .points
            .iter()
            .filter(|p| p.position[1] + p.half_height() - self.base >= threshold && p.position[0] + 0.5 * p.size > wall)
            .map(|p| (p.position[0] - 0.5 * p.size, p.position[0] + 0.5 * p.size, p.size))
            .collect();
        spans.sort_by(|a, b| a.0.total_cmp(&b.0));
        spans
    }

    /// These points' part of [`SurfaceProfile::runout`] for a runout over several sets of
    /// points (the ranks' shares of a body): their squares joined where they overlap, each
    /// run of overlapping squares as `(left, right, size)` of its first square and its
    /// farthest right end. [`runout_of_spans`] over every set's runs (in any order) is the
    /// runout of all the points together, bit for bit: an accepted first square makes its
    /// whole run accepted in the one sweep as in the other (each next square starts within
    /// the reach of those before it, and so does every square of another set that starts
    /// among them), and a run is rejected only where no square before it reaches its start.
    pub fn runout_runs(&self, wall: f64, threshold: f64) -> Vec<Span> {
        let mut runs: Vec<Span> = Vec::new();
        for (left, right, size) in self.spans(wall, threshold) {
            match runs.last_mut() {
                Some(run) if left <= run.1 => run.1 = run.1.max(right),
                _ => runs.push((left, right, size)),
            }
        }
        runs
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

    /// Inclination of a heap's flank. The surface is sampled at `x_k = x_range[0] + k ·
    /// spacing` up to `x_range[1]`; with the heap height `H = max_k h(x_k)`, the flank is the
    /// stretch from the first to the last sample whose height lies in
    /// `[band[0] · H, band[1] · H]` (e.g. `[0.2, 0.8]`: without the crest and the toe), and
    /// every sample of that stretch is fitted by least squares,
    ///
    /// $$ b = \frac{\sum_k (x_k - \bar x)(h_k - \bar h)}{\sum_k (x_k - \bar x)^2}, \qquad
    ///    a = \bar h - b \bar x, \qquad \beta = \arctan |b| . $$
    ///
    /// The stretch is chosen by the heights at its ends only, so that a rough surface is not
    /// filtered by height inside it (selecting samples on `h` would bias `b` towards zero).
    /// `x_range` should hold one flank (a monotonic surface); `None` if there is no surface
    /// or fewer than two samples fall in the band.
    pub fn slope_fit(&self, x_range: [f64; 2], spacing: f64, band: [f64; 2]) -> Option<SlopeFit> {
        assert!(spacing > 0.0, "slope_fit: spacing must be positive");
        let n = ((x_range[1] - x_range[0]) / spacing).floor().max(0.0) as usize + 1;
        let samples: Vec<(f64, f64)> = (0..n)
            .map(|k| {
                let x = x_range[0] + k as f64 * spacing;
                (x, self.height_at(x))
            })
            .collect();
        let height = samples.iter().map(|s| s.1).fold(0.0, f64::max);
        if height <= 0.0 {
            return None;
        }
        let in_band = |h: f64| h >= band[0] * height && h <= band[1] * height;
        let first = samples.iter().position(|s| in_band(s.1))?;
        let last = samples.iter().rposition(|s| in_band(s.1))?;
        let flank = &samples[first..=last];
        if flank.len() < 2 {
            return None;
        }
        let m = flank.len() as f64;
        let (mx, mh) = (flank.iter().map(|s| s.0).sum::<f64>() / m, flank.iter().map(|s| s.1).sum::<f64>() / m);
        let sxh: f64 = flank.iter().map(|s| (s.0 - mx) * (s.1 - mh)).sum();
        let sxx: f64 = flank.iter().map(|s| (s.0 - mx).powi(2)).sum();
        let slope = sxh / sxx;
        let intercept = mh - slope * mx;
        let rss: f64 = flank.iter().map(|s| (s.1 - intercept - slope * s.0).powi(2)).sum();
        Some(SlopeFit {
            intercept,
            slope,
            angle: slope.abs().atan().to_degrees(),
            height,
            x_span: [flank[0].0, flank[flank.len() - 1].0],
            samples: flank.len(),
            rms_residual: (rss / m).sqrt(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The thickness runout of a block of unit squares against a wall (1 m thick, 10 m long,
    /// points of side 0.5 m): the bins of 1 m hold 1 m of thickness up to x = 10 m, so the
    /// profile falls from 1 to 0 between the centres 9.5 and 10.5 and reaches 0.25 m at
    /// 10.25 m; a sheet of the same area stacked differently (two points of side 0.2/√2 on top of
    /// each other against one point of side 0.2) gives the same thickness.
    #[test]
    fn thickness_runout_of_a_block_and_of_a_sheet() {
        let block: Vec<PointExtent> = (0..20)
            .flat_map(|i| {
                (0..2).map(move |j| PointExtent::new([0.25 + 0.5 * i as f64, 0.25 + 0.5 * j as f64, 0.0], 0.5))
            })
            .collect();
        let area = |p: &PointExtent| p.size * p.size;
        let t = binned_along_x(&block, 0.0, 1.0, area); // bins of 1 m: areas are thicknesses
        assert_eq!(t.len(), 11);
        assert!(t[..10].iter().all(|&v| (v - 1.0).abs() < 1e-15) && t[10] == 0.0, "{t:?}");
        assert!((runout_of_thickness(&t, 1.0, 0.25) - 10.25).abs() < 1e-12);
        assert_eq!(runout_of_thickness(&t, 1.0, 2.0), 0.0);
        // a wall at x = 2: the bins start there
        let from_two: Vec<f64> = binned_along_x(&block, 2.0, 1.0, area);
        assert_eq!(from_two.len(), 9);
        assert!((runout_of_thickness(&from_two, 1.0, 0.5) - 8.0).abs() < 1e-12);
        // one layer of points of side 0.2 against two layers of side 0.2/√2 (the same area per bin)
        let one: Vec<PointExtent> = (0..5).map(|i| PointExtent::new([0.1 + 0.2 * i as f64, 0.1, 0.0], 0.2)).collect();
        let side = 0.2 / 2f64.sqrt();
        let two: Vec<PointExtent> = (0..5)
            .flat_map(|i| {
                (0..2).map(move |j| PointExtent::new([0.1 + 0.2 * i as f64, side * (0.5 + j as f64), 0.0], side))
            })
            .collect();
        let (a, b) = (binned_along_x(&one, 0.0, 0.5, area), binned_along_x(&two, 0.0, 0.5, area));
        let (ra, rb) = (runout_of_thickness(&a, 0.5, 0.01), runout_of_thickness(&b, 0.5, 0.01));
        assert!((ra - rb).abs() < 1e-12, "{ra} {rb}");
    }

    /// Unit points in columns i = 0..10 at x = 0.5 + i, 10 − i points high.
    fn staircase() -> Vec<PointExtent> {
        (0..10)
            .flat_map(|i| (0..10 - i).map(move |j| PointExtent::new([0.5 + i as f64, 0.5 + j as f64, 0.0], 1.0)))
            .collect()
    }

    /// A triangle heap of unit-spaced points: height and runout are those of the staircase.
    #[test]
    fn staircase_heap() {
        let mut pts = staircase();
        let s = SurfaceProfile::new(&pts, 0.0);
        assert_eq!(s.height_at(0.0), 10.0);
        assert_eq!(s.height_at(3.5), 7.0);
        assert_eq!(s.runout(0.0, 0.5), 10.0);
        assert_eq!(s.runout(0.0, 3.0), 8.0);
        // a detached point far ahead does not extend the runout
        pts.push(PointExtent::new([20.5, 0.5, 0.0], 1.0));
        assert_eq!(SurfaceProfile::new(&pts, 0.0).runout(0.0, 0.5), 10.0);
        let reference = [(2.5, 8.0), (4.5, 6.0)];
        assert!(SurfaceProfile::new(&pts, 0.0).rms_distance(&reference) < 1e-12);
    }

    /// The runout over several sets of points from their runs equals that of all the points:
    /// the staircase split by the parity of its points' index (so that the sets interleave
    /// along x), with points of other sizes and gaps joined across half a size, for every
    /// threshold.
    #[test]
    fn runout_from_the_runs_of_several_sets_is_the_whole_runout() {
        let mut pts = staircase();
        pts.push(PointExtent::new([10.6, 0.3, 0.0], 0.4));
        pts.push(PointExtent::new([11.15, 0.3, 0.0], 0.3));
        pts.push(PointExtent::new([12.0, 0.5, 0.0], 1.0));
        pts.push(PointExtent::new([13.2, 0.2, 0.0], 0.2));
        let split_equals_whole = |pts: &[PointExtent], threshold: f64, sets: usize, of: &dyn Fn(usize) -> usize| {
            let whole = SurfaceProfile::new(pts, 0.0).runout(0.0, threshold);
            let runs: Vec<Span> = (0..sets)
                .flat_map(|k| {
                    let set: Vec<PointExtent> = (0..pts.len()).filter(|&p| of(p) == k).map(|p| pts[p]).collect();
                    SurfaceProfile::new(&set, 0.0).runout_runs(0.0, threshold)
                })
                .collect();
            assert_eq!(runout_of_spans(runs, 0.0).to_bits(), whole.to_bits(), "threshold {threshold}, {sets} sets");
        };
        for threshold in [0.1, 0.3, 0.5, 2.0, 3.0, 9.5] {
            for sets in [2, 3] {
                split_equals_whole(&pts, threshold, sets, &|p| p % sets);
            }
        }
        // scattered squares of many sizes with gaps of every width, dealt at random
        let mut seed = 12345u64;
        let mut random = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let pts: Vec<PointExtent> =
                (0..60).map(|_| PointExtent::new([12.0 * random(), random(), 0.0], 0.05 + 0.5 * random())).collect();
            let owner: Vec<usize> = (0..pts.len()).map(|_| (4.0 * random()) as usize).collect();
            split_equals_whole(&pts, 0.2 * random(), 4, &|p| owner[p]);
        }
    }

    /// A point whose volume has grown a hundredfold (size 10, initial size 1) at the toe of
    /// a unit layer covers its current width but stands no higher than its packed size.
    #[test]
    fn dilated_point_spreads_without_rising() {
        let mut pts: Vec<PointExtent> = (0..5).map(|i| PointExtent::new([0.5 + i as f64, 0.5, 0.0], 1.0)).collect();
        pts.push(PointExtent { position: [10.0, 0.5, 0.0], size: 10.0, initial_size: 1.0 });
        let s = SurfaceProfile::new(&pts, 0.0);
        assert_eq!(s.height_at(8.0), 1.0);
        assert_eq!(s.runout(0.0, 0.5), 15.0);
    }

    /// Points on a fine lattice filling a heap with a flat crest (height 1 for x < 1) and a
    /// 30° flank down to the base: the fit between 20 % and 80 % of the height finds 30°,
    /// the height and the flank's line; the unit staircase of `staircase_heap` gives 45°.
    #[test]
    fn slope_of_a_heap_flank() {
        let (beta, s) = (30f64.to_radians(), 0.01);
        let toe = 1.0 + 1.0 / beta.tan();
        let mut pts = Vec::new();
        for i in 0..(toe / s).ceil() as usize {
            let x = (i as f64 + 0.5) * s;
            let top = if x < 1.0 { 1.0 } else { (toe - x) * beta.tan() };
            for j in 0..(top / s).round() as usize {
                pts.push(PointExtent::new([x, (j as f64 + 0.5) * s, 0.0], s));
            }
        }
        let fit = SurfaceProfile::new(&pts, 0.0).slope_fit([0.0, toe + 0.1], 0.001, [0.2, 0.8]).expect("a flank");
        assert!((fit.angle - 30.0).abs() < 0.3, "angle {}", fit.angle);
        assert!((fit.height - 1.0).abs() < s, "height {}", fit.height);
        // the line meets the base at the toe and the crest where the flank starts
        assert!((-fit.intercept / fit.slope - toe).abs() < 2.0 * s, "toe {}", -fit.intercept / fit.slope);
        assert!((fit.x_span[0] - (1.0 + 0.2 / beta.tan())).abs() < 2.0 * s, "span {:?}", fit.x_span);
        assert!(fit.rms_residual < s, "residual {}", fit.rms_residual);

        let stairs = staircase();
        let fit = SurfaceProfile::new(&stairs, 0.0).slope_fit([0.0, 11.0], 0.01, [0.2, 0.8]).expect("a flank");
        assert!((fit.angle - 45.0).abs() < 1.0, "staircase angle {}", fit.angle);
        // nothing to fit on a bare base
        assert!(SurfaceProfile::new(&[], 0.0).slope_fit([0.0, 1.0], 0.1, [0.2, 0.8]).is_none());
    }
}
