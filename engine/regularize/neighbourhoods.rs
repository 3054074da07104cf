//! The 1-ring neighbourhoods the regularizer kernels read, as CSR arrays built from the mesh
//! after each topology change.

use crate::topology::{mean_edge_length, ManifoldMesh};

/// Set in the count of a boundary vertex: its fan is open (one face fewer than neighbours).
pub const BOUNDARY_BIT: u32 = 1 << 31;

/// Vertex `i`'s neighbours are `ring[start..start + count]` with `[start, count] = ranges[i]`
/// (`count` masked by `!BOUNDARY_BIT`), counter-clockwise, so its faces are
/// `(i, ring[k], ring[k + 1])` for consecutive entries, plus `(i, last, first)` unless the
/// vertex is on the boundary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Neighbourhoods {
    /// Per vertex, `[start, count]` into `ring`; `count` carries [`BOUNDARY_BIT`] on the boundary.
    pub ranges: Vec<[u32; 2]>,
    /// Every vertex's neighbours, concatenated.
    pub ring: Vec<u32>,
    /// Mean edge length when built: the length scale of the temporal weights.
    pub mean_edge_length: f32,
    /// Per vertex, a factor on its temporal edge-length and rigidity terms (1 from
    /// [`Self::from_mesh`]; see [`super::stiffness`]).
    pub stiffness: Vec<f32>,
}

impl Neighbourhoods {
    /// From a compacted mesh (one row per vertex).
    pub fn from_mesh(mesh: &ManifoldMesh) -> Self {
        let mut ranges = Vec::with_capacity(mesh.vertex_rows());
        let mut ring = Vec::with_capacity(mesh.vertex_rows() * 6);
        for v in 0..mesh.vertex_rows() as u32 {
            let neighbours = if mesh.is_vertex_live(v) { mesh.ring(v) } else { Vec::new() };
            let flag = if mesh.is_boundary_vertex(v) { BOUNDARY_BIT } else { 0 };
            ranges.push([ring.len() as u32, neighbours.len() as u32 | flag]);
            ring.extend(neighbours);
        }
        let stiffness = vec![1.0; ranges.len()];
        Self { ranges, ring, mean_edge_length: mean_edge_length(mesh), stiffness }
    }

    /// The number of vertex rows (dead vertices have empty neighbourhoods).
    pub fn len(&self) -> usize {
        self.ranges.len()
    }

    /// Whether there are no vertex rows.
    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    /// Neighbours of `i`.
    #[inline]
    pub fn neighbours(&self, i: usize) -> &[u32] {
        let [start, count] = self.ranges[i];
        &self.ring[start as usize..(start + (count & !BOUNDARY_BIT)) as usize]
    }

    /// Faces around `i` as `(ring[k], ring[k + 1])` pairs, counter-clockwise.
    pub fn fan(&self, i: usize) -> impl Iterator<Item = (u32, u32)> + '_ {
        let ring = self.neighbours(i);
        let open = self.ranges[i][1] & BOUNDARY_BIT != 0;
        let faces = if open { ring.len().saturating_sub(1) } else { ring.len() };
        (0..faces).map(move |k| (ring[k], ring[(k + 1) % ring.len()]))
    }
}
