//! Integration-point geometries packed to the nodes a block has.
//!
//! A [`PointGeometry`] has room for the largest block (27 nodes of a 3D smooth MPM support:
//! 880 bytes), but a material point of a 2D linear grid or a Gauss point of a four-node
//! quadrilateral uses 4 of its nodes. An MPM body and an FEM domain keep one geometry per
//! point and stream all of them through every Newton iteration's kernels; at full size they
//! no longer fit the caches from a few thousand points on, and the kernels wait on memory. [`PackedGeometry`] keeps per point only
//!
//! ```text
//! [ w, R, N_0 … N_{n−1}, ∂N_0/∂X̃ (3), …, ∂N_{n−1}/∂X̃ (3) ]      (2 + 4n values)
//! ```
//!
//! for the `n` nodes of the body's supports (144 bytes for `n = 4`), and unpacks one point at a
//! time into a full record for the kernels ([`Geometries`]).

use std::ops::Range;

use crate::element::MAX_NODES;
use crate::kernel::{Geometries, PointGeometry};

/// Point geometries of `nodes` nodes each, one record per point (see the module doc).
#[derive(Debug, Clone, Default)]
pub struct PackedGeometry {
    nodes: usize,
    data: Vec<f64>,
}

/// A run of consecutive points of a [`PackedGeometry`] (the points of one block).
#[derive(Debug, Clone, Copy)]
pub struct PackedPoints<'a> {
    nodes: usize,
    data: &'a [f64],
}

/// Offset of the shape functions in a record (after `w` and `R`).
const SHAPE: usize = 2;

impl PackedGeometry {
    /// Values per point's record.
    pub fn stride(&self) -> usize {
        SHAPE + 4 * self.nodes
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.data.len() / self.stride()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Room for `n` points of `nodes` nodes each from now on. The records keep what they
    /// held (stale after a change of `n` or `nodes`): write each with [`PackedGeometry::pack`].
    pub fn resize(&mut self, nodes: usize, n: usize) {
        assert!(nodes <= MAX_NODES, "a block has at most {MAX_NODES} nodes, asked for {nodes}");
        self.nodes = nodes;
        self.data.resize(n * self.stride(), 0.0);
    }

    /// Releases the room beyond the present points (after a body lost most of its points,
    /// e.g. to other ranks); with `clear`, all of it (the records are rewritten before they
    /// are read again).
    pub fn shrink_to_fit(&mut self, clear: bool) {
        if clear {
            self.data.clear();
        }
        self.data.shrink_to_fit();
    }

    /// The records, one mutable chunk per point, in parallel (write them with
    /// [`PackedGeometry::pack`]).
    pub fn par_records_mut(&mut self) -> rayon::slice::ChunksExactMut<'_, f64> {
        use rayon::slice::ParallelSliceMut;
        let stride = self.stride();
        self.data.par_chunks_exact_mut(stride)
    }

    /// The records, one mutable chunk per point, in order (write them with
    /// [`PackedGeometry::pack`]).
    pub fn records_mut(&mut self) -> std::slice::ChunksExactMut<'_, f64> {
        let stride = self.stride();
        self.data.chunks_exact_mut(stride)
    }

    /// Writes `g`'s weight, radius and first `(record.len() − 2) / 4` nodes into `record`.
    pub fn pack(record: &mut [f64], g: &PointGeometry) {
        let nodes = (record.len() - SHAPE) / 4;
        record[0] = g.weight;
        record[1] = g.radius;
        let (shape, gradient) = record[SHAPE..].split_at_mut(nodes);
        shape.copy_from_slice(&g.shape[..nodes]);
        for (dst, src) in gradient.chunks_exact_mut(3).zip(&g.gradient[..nodes]) {
            dst.copy_from_slice(src);
        }
    }

    /// The record of point `p` (see the module doc).
    pub fn record(&self, p: usize) -> &[f64] {
        let stride = self.stride();
        &self.data[p * stride..(p + 1) * stride]
    }

    /// Integration weight of point `p`.
    pub fn weight(&self, p: usize) -> f64 {
        self.data[p * self.stride()]
    }

    /// Scales the integration weights of points `range` by `factor`.
    pub fn scale_weights(&mut self, range: Range<usize>, factor: f64) {
        let stride = self.stride();
        for record in self.data[range.start * stride..range.end * stride].chunks_exact_mut(stride) {
            record[0] *= factor;
        }
    }

    /// Shape functions `N_a` of point `p`, one per node.
    pub fn shape(&self, p: usize) -> &[f64] {
        &self.record(p)[SHAPE..SHAPE + self.nodes]
    }

    /// The points `range` as the kernels' [`Geometries`].
    pub fn points(&self, range: Range<usize>) -> PackedPoints<'_> {
        let stride = self.stride();
        PackedPoints { nodes: self.nodes, data: &self.data[range.start * stride..range.end * stride] }
    }
}

impl Geometries for PackedPoints<'_> {
    type Scratch = PointGeometry;

    fn count(&self) -> usize {
        self.data.len() / (SHAPE + 4 * self.nodes)
    }

    fn point<'a>(&'a self, k: usize, scratch: &'a mut PointGeometry) -> &'a PointGeometry {
        let stride = SHAPE + 4 * self.nodes;
        let record = &self.data[k * stride..(k + 1) * stride];
        // the block sizes of the grids as constants, so that the copy is unrolled (a point's
        // kernel is a few hundred nanoseconds: a call to copy its 18 values would show)
        match self.nodes {
            3 => unpack(record, 3, scratch),
            4 => unpack(record, 4, scratch),
            8 => unpack(record, 8, scratch),
            9 => unpack(record, 9, scratch),
            27 => unpack(record, 27, scratch),
            n => unpack(record, n, scratch),
        }
        scratch
    }
}

/// Writes a record of `n` nodes into `g` (weight, radius, `shape[..n]`, `gradient[..n]`).
#[inline(always)]
fn unpack(record: &[f64], n: usize, g: &mut PointGeometry) {
    let record = &record[..SHAPE + 4 * n];
    g.weight = record[0];
    g.radius = record[1];
    for a in 0..n {
        g.shape[a] = record[SHAPE + a];
        for i in 0..3 {
            g.gradient[a][i] = record[SHAPE + n + 3 * a + i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A packed point unpacks to the record it was packed from, on its nodes.
    #[test]
    fn packs_and_unpacks_a_point() {
        let mut g = PointGeometry::default();
        for a in 0..4 {
            g.shape[a] = 0.1 * (a + 1) as f64;
            g.gradient[a] = [a as f64, -(a as f64), 0.5 * a as f64];
        }
        (g.weight, g.radius) = (2.5, 0.75);
        let mut store = PackedGeometry::default();
        store.resize(4, 3);
        assert_eq!((store.len(), store.stride()), (3, 18));
        PackedGeometry::pack(&mut store.data[18..36], &g);
        store.scale_weights(1..2, 2.0);
        let points = store.points(1..3);
        assert_eq!(points.count(), 2);
        let mut scratch = PointGeometry::default();
        let unpacked = points.point(0, &mut scratch);
        assert_eq!(unpacked.weight, 5.0);
        assert_eq!(unpacked.radius, 0.75);
        assert_eq!(unpacked.shape[..4], g.shape[..4]);
        assert_eq!(unpacked.gradient[..4], g.gradient[..4]);
        assert_eq!(store.shape(1), &g.shape[..4]);
        assert_eq!(store.weight(2), 0.0);
    }
}
