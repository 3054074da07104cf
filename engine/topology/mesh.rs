//! The manifold mesh: positions beside an implicit-half-edge connectivity.
//!
//! Face `f` owns half-edges `3f, 3f + 1, 3f + 2`; half-edge `3f + k` runs from corner `k` to
//! corner `k + 1` of `faces[f]`. `next`/`prev` are arithmetic, `twin` is stored (`NONE` on the
//! boundary), and each vertex stores one outgoing half-edge, its *anchor*: for a boundary vertex
//! the one whose twin is `NONE`, so walking [`ManifoldMesh::rotate`] from it visits the whole fan.
//! Removed faces and vertices stay as tombstones until [`ManifoldMesh::compact`].

use super::TopologyError;
use std::collections::HashMap;

/// "No half-edge / no vertex / no row".
pub const NONE: u32 = u32::MAX;

/// A manifold, consistently oriented triangle mesh: vertex positions beside implicit half-edge
/// connectivity, with removed faces and vertices kept as tombstones until [`Self::compact`].
#[derive(Clone, Debug)]
pub struct ManifoldMesh {
    /// One row per vertex index (tombstoned rows keep stale values until compaction). Callers
    /// may move vertices freely; only the local operations add rows.
    pub positions: Vec<[f32; 3]>,
    pub(super) faces: Vec<[u32; 3]>,
    pub(super) twins: Vec<u32>,
    pub(super) anchors: Vec<u32>,
    pub(super) live_faces: usize,
    pub(super) live_vertices: usize,
    /// Vertex rows below this existed at the last construction or compaction.
    pub(super) synced_vertices: usize,
}

/// The next half-edge in the same face: `3f + (k + 1) % 3` for `h = 3f + k`.
#[inline]
pub fn next(h: u32) -> u32 {
    if h % 3 == 2 {
        h - 2
    } else {
        h + 1
    }
}

/// The previous half-edge in the same face: `3f + (k + 2) % 3` for `h = 3f + k`.
#[inline]
pub fn prev(h: u32) -> u32 {
    if h.is_multiple_of(3) {
        h + 2
    } else {
        h - 1
    }
}

/// The face that owns half-edge `h` (`h / 3`).
#[inline]
pub fn face_of(h: u32) -> u32 {
    h / 3
}

impl ManifoldMesh {
    /// Builds the connectivity of consistently oriented triangles. Errors (first one found):
    /// a face indexing past `positions`, a repeated corner, a directed edge used twice (an edge
    /// with more than two faces or inconsistent orientation — see [`super::orient_faces`]), a
    /// vertex used by no face, a vertex whose faces form more than one fan (pinched), or a
    /// non-finite position.
    pub fn new(positions: Vec<[f32; 3]>, faces: Vec<[u32; 3]>) -> Result<Self, TopologyError> {
        if let Some(v) = positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Err(TopologyError::NonFinite { vertex: v as u32 });
        }
        let n = positions.len();
        check_indices(n, &faces)?;
        let twins = twins_of(&faces)?;
        let mut mesh = Self {
            positions,
            anchors: vec![NONE; n],
            twins,
            live_faces: faces.len(),
            live_vertices: n,
            synced_vertices: n,
            faces,
        };
        for h in 0..mesh.twins.len() as u32 {
            let v = mesh.origin(h) as usize;
            if mesh.anchors[v] == NONE || mesh.twins[h as usize] == NONE {
                mesh.anchors[v] = h;
            }
        }
        if let Some(v) = mesh.anchors.iter().position(|&a| a == NONE) {
            return Err(TopologyError::UnusedVertex { vertex: v as u32 });
        }
        mesh.check_fans()?;
        Ok(mesh)
    }

    /// Every vertex's faces form one fan: the fan walked from its anchor has all its faces.
    fn check_fans(&self) -> Result<(), TopologyError> {
        let mut degree = vec![0u32; self.positions.len()];
        for face in &self.faces {
            for &v in face {
                degree[v as usize] += 1;
            }
        }
        for v in 0..self.positions.len() as u32 {
            if self.outgoing(v).count() as u32 != degree[v as usize] {
                return Err(TopologyError::PinchedVertex { vertex: v });
            }
        }
        Ok(())
    }

    /// The vertex half-edge `h` starts at.
    #[inline]
    pub fn origin(&self, h: u32) -> u32 {
        self.faces[(h / 3) as usize][(h % 3) as usize]
    }

    /// The vertex half-edge `h` ends at.
    #[inline]
    pub fn dest(&self, h: u32) -> u32 {
        self.origin(next(h))
    }

    /// Position of `v` in f64.
    #[inline]
    pub fn point(&self, v: u32) -> glam::DVec3 {
        super::geometry::vec(self.positions[v as usize])
    }

    /// The opposite half-edge, `NONE` on the boundary.
    #[inline]
    pub fn twin(&self, h: u32) -> u32 {
        self.twins[h as usize]
    }

    /// Next outgoing half-edge around `origin(h)` (counter-clockwise), `NONE` past the boundary.
    #[inline]
    pub fn rotate(&self, h: u32) -> u32 {
        self.twin(prev(h))
    }

    /// Corners of face `f` (counter-clockwise); `[NONE; 3]` for a removed face.
    #[inline]
    pub fn face(&self, f: u32) -> [u32; 3] {
        self.faces[f as usize]
    }

    /// Whether face row `f` has not been removed.
    #[inline]
    pub fn is_face_live(&self, f: u32) -> bool {
        self.faces[f as usize][0] != NONE
    }

    /// Whether vertex row `v` has not been removed.
    #[inline]
    pub fn is_vertex_live(&self, v: u32) -> bool {
        self.anchors[v as usize] != NONE
    }

    /// Number of vertex rows, removed ones included (indices run below this).
    pub fn vertex_rows(&self) -> usize {
        self.positions.len()
    }

    /// Number of face rows, removed ones included.
    pub fn face_rows(&self) -> usize {
        self.faces.len()
    }

    /// Number of live vertices.
    pub fn vertex_count(&self) -> usize {
        self.live_vertices
    }

    /// Number of live faces.
    pub fn face_count(&self) -> usize {
        self.live_faces
    }

    /// Live face indices.
    pub fn faces(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.faces.len() as u32).filter(|&f| self.is_face_live(f))
    }

    /// Live vertex indices.
    pub fn vertices(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.anchors.len() as u32).filter(|&v| self.is_vertex_live(v))
    }

    /// One half-edge per undirected live edge (the one with the larger index among a pair, or
    /// the only one on the boundary).
    pub fn edges(&self) -> impl Iterator<Item = u32> + '_ {
        self.faces().flat_map(|f| 3 * f..3 * f + 3).filter(|&h| {
            let t = self.twin(h);
            t == NONE || h > t
        })
    }

    /// Number of live undirected edges (counts [`Self::edges`], O(F)).
    pub fn edge_count(&self) -> usize {
        self.edges().count()
    }

    /// Outgoing half-edges of `v`, counter-clockwise, starting at its anchor.
    pub fn outgoing(&self, v: u32) -> Outgoing<'_> {
        let start = self.anchors[v as usize];
        Outgoing { mesh: self, start, at: start }
    }

    /// The 1-ring: neighbour vertices counter-clockwise (a boundary vertex also gets the far end
    /// of its last boundary edge).
    pub fn ring(&self, v: u32) -> Vec<u32> {
        let mut ring: Vec<u32> = self.outgoing(v).map(|h| self.dest(h)).collect();
        if let Some(last) = self.outgoing(v).last() {
            if self.twin(prev(last)) == NONE {
                ring.push(self.origin(prev(last)));
            }
        }
        ring
    }

    /// Whether `a` and `b` share an edge (no allocation, unlike [`Self::ring`]).
    pub fn are_neighbours(&self, a: u32, b: u32) -> bool {
        self.find_edge(a, b).is_some()
    }

    /// Number of neighbours of `v`.
    pub fn valence(&self, v: u32) -> usize {
        self.ring(v).len()
    }

    /// Whether `v` lies on a boundary.
    #[inline]
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        let a = self.anchors[v as usize];
        a != NONE && self.twin(a) == NONE
    }

    /// Whether half-edge `h` has no twin (its edge has one face).
    #[inline]
    pub fn is_boundary_edge(&self, h: u32) -> bool {
        self.twin(h) == NONE
    }

    /// The half-edge from `a` to `b`, if that edge exists (either direction: the returned one
    /// starts at `a` when it has a face on that side, else it runs `b → a`).
    pub fn find_edge(&self, a: u32, b: u32) -> Option<u32> {
        if let Some(h) = self.outgoing(a).find(|&h| self.dest(h) == b) {
            return Some(h);
        }
        self.outgoing(b).find(|&h| self.dest(h) == a)
    }

    /// Sets `v`'s anchor from any outgoing half-edge `h`: walks clockwise to the boundary (or
    /// round the full fan).
    pub(super) fn reanchor(&mut self, v: u32, h: u32) {
        debug_assert_eq!(self.origin(h), v);
        let mut at = h;
        loop {
            let t = self.twin(at);
            if t == NONE {
                break;
            }
            at = next(t);
            if at == h {
                break;
            }
        }
        self.anchors[v as usize] = at;
    }

    /// Sets the twin links of `a` and `b` to each other (either may be `NONE`).
    #[inline]
    pub(super) fn link(&mut self, a: u32, b: u32) {
        if a != NONE {
            self.twins[a as usize] = b;
        }
        if b != NONE {
            self.twins[b as usize] = a;
        }
    }

    /// Appends a face, returns its index; twins start as `NONE`.
    pub(super) fn push_face(&mut self, corners: [u32; 3]) -> u32 {
        self.faces.push(corners);
        self.twins.extend([NONE; 3]);
        self.live_faces += 1;
        self.faces.len() as u32 - 1
    }

    pub(super) fn push_vertex(&mut self, p: [f32; 3]) -> u32 {
        self.positions.push(p);
        self.anchors.push(NONE);
        self.live_vertices += 1;
        self.positions.len() as u32 - 1
    }

    pub(super) fn remove_face(&mut self, f: u32) {
        self.faces[f as usize] = [NONE; 3];
        for k in 0..3 {
            self.twins[(3 * f + k) as usize] = NONE;
        }
        self.live_faces -= 1;
    }

    pub(super) fn remove_vertex(&mut self, v: u32) {
        self.anchors[v as usize] = NONE;
        self.live_vertices -= 1;
    }

    /// Live faces as plain arrays (tombstones skipped, vertex indices unchanged).
    pub fn live_faces(&self) -> Vec<[u32; 3]> {
        self.faces().map(|f| self.face(f)).collect()
    }
}

/// Iterator over the outgoing half-edges of a vertex; see [`ManifoldMesh::outgoing`].
pub struct Outgoing<'a> {
    mesh: &'a ManifoldMesh,
    start: u32,
    at: u32,
}

impl Iterator for Outgoing<'_> {
    type Item = u32;

    fn next(&mut self) -> Option<u32> {
        if self.at == NONE {
            return None;
        }
        let h = self.at;
        let r = self.mesh.rotate(h);
        self.at = if r == self.start { NONE } else { r };
        Some(h)
    }
}

fn check_indices(n: usize, faces: &[[u32; 3]]) -> Result<(), TopologyError> {
    for (f, face) in faces.iter().enumerate() {
        if face.iter().any(|&v| v as usize >= n) {
            return Err(TopologyError::IndexOutOfRange {
                face: f as u32,
                corners: *face,
                vertices: n,
            });
        }
        if face[0] == face[1] || face[1] == face[2] || face[2] == face[0] {
            return Err(TopologyError::DegenerateFace { face: f as u32, corners: *face });
        }
    }
    Ok(())
}

/// Twin of every half-edge by matching `(a, b)` with `(b, a)`.
fn twins_of(faces: &[[u32; 3]]) -> Result<Vec<u32>, TopologyError> {
    let mut directed: HashMap<(u32, u32), u32> = HashMap::with_capacity(faces.len() * 3);
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            let key = (face[k], face[(k + 1) % 3]);
            if let Some(&other) = directed.get(&key) {
                return Err(TopologyError::NonManifoldEdge {
                    a: key.0,
                    b: key.1,
                    faces: vec![other / 3, f as u32],
                });
            }
            directed.insert(key, (3 * f + k) as u32);
        }
    }
    let mut twins = vec![NONE; faces.len() * 3];
    for (&(a, b), &h) in &directed {
        if let Some(&t) = directed.get(&(b, a)) {
            twins[h as usize] = t;
        }
    }
    Ok(twins)
}
