//! The local operations: edge split, face split 1→3, edge flip, edge collapse. Each rewrites a
//! few faces and then re-links twins and anchors of just those faces ([`ManifoldMesh::relink`]),
//! so every operation keeps the mesh manifold and consistently oriented by construction; the
//! legality checks refuse what would not.

use super::geometry::{area_vector, faces_agree, vec, GeometryRefusal};
use super::mesh::{face_of, next, prev, ManifoldMesh, NONE};
use glam::DVec3;

/// Why a split was refused: a new triangle would be degenerate or face against the old face
/// (the point lies outside it, or on one of its edges).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SplitRefusal {
    /// A new triangle's area would be at or below `1e-5` × its longest squared edge.
    #[error("a new triangle would be degenerate")]
    Degenerate,
    /// A new triangle's normal would point away from the old face's.
    #[error("a new triangle would face against the old one (point outside the face)")]
    FoldsOver,
}

impl From<GeometryRefusal> for SplitRefusal {
    fn from(g: GeometryRefusal) -> Self {
        match g {
            GeometryRefusal::Degenerate => SplitRefusal::Degenerate,
            GeometryRefusal::FoldsOver => SplitRefusal::FoldsOver,
        }
    }
}

impl From<GeometryRefusal> for FlipRefusal {
    fn from(g: GeometryRefusal) -> Self {
        match g {
            GeometryRefusal::Degenerate => FlipRefusal::Degenerate,
            GeometryRefusal::FoldsOver => FlipRefusal::FoldsOver,
        }
    }
}

/// Why an edge flip was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FlipRefusal {
    /// The edge has only one face.
    #[error("boundary edges cannot flip")]
    Boundary,
    /// The two opposite vertices are already joined by an edge.
    #[error("the new diagonal already exists")]
    EdgeExists,
    /// A new triangle's area would be at or below `1e-5` × its longest squared edge.
    #[error("a new triangle would be degenerate")]
    Degenerate,
    /// A new triangle's normal would point away from the summed normal of the old pair.
    #[error("a new triangle would face against the old ones (non-convex quad)")]
    FoldsOver,
}

/// Why an edge collapse was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CollapseRefusal {
    /// The mesh has 5 live vertices or fewer.
    #[error("the mesh would keep 4 vertices or fewer")]
    TooFewVertices,
    /// The 1-rings of the two ends share other than exactly one (boundary edge) or two
    /// (interior edge) vertices.
    #[error("the link condition fails (the collapse would pinch two sheets)")]
    LinkCondition,
    /// The edge is interior but both its ends lie on a boundary.
    #[error(
        "an interior edge joins two boundary vertices (the collapse would pinch the boundary)"
    )]
    BoundaryPinch,
    /// A face of the edge has its two other edges on the boundary, so its far corner would
    /// keep no face.
    #[error("a vertex would keep no face")]
    DanglingVertex,
    /// A face kept around either end would point its normal away from its old normal.
    #[error("face {face} would flip its normal")]
    FlipsNormal {
        /// The face that would flip.
        face: u32,
    },
    /// A face kept around either end would become degenerate.
    #[error("face {face} would degenerate")]
    Degenerate {
        /// The face that would degenerate.
        face: u32,
    },
}

impl ManifoldMesh {
    /// Whether splitting the edge of `h` at `point` is legal: each new triangle non-degenerate
    /// and facing the same side as the face it comes from.
    pub fn can_split_edge(&self, h: u32, point: [f32; 3]) -> Result<(), SplitRefusal> {
        let q = vec(point);
        for e in [h, self.twin(h)] {
            if e != NONE {
                let [a, b, c] =
                    [self.origin(e), self.dest(e), self.origin(prev(e))].map(|v| self.point(v));
                faces_agree(&[[a, q, c], [q, b, c]], area_vector(a, b, c))?;
            }
        }
        Ok(())
    }

    /// Splits the edge of half-edge `h` at `point` (the caller's choice, normally on the edge)
    /// when [`Self::can_split_edge`] allows it: its one or two faces become two or four. Returns
    /// the new vertex. Adds 1 vertex, 3 edges, 2 faces (interior edge) or 1 vertex, 2 edges,
    /// 1 face (boundary edge).
    pub fn split_edge(&mut self, h: u32, point: [f32; 3]) -> Result<u32, SplitRefusal> {
        self.can_split_edge(h, point)?;
        let t = self.twin(h);
        let m = self.push_vertex(point);
        let mut touched = Vec::with_capacity(4);
        for e in [h, t] {
            if e == NONE {
                continue;
            }
            let (a, b, c) = (self.origin(e), self.dest(e), self.origin(prev(e)));
            let f = face_of(e);
            self.faces[f as usize] = [a, m, c];
            touched.extend([f, self.push_face([m, b, c])]);
        }
        self.relink(&touched);
        Ok(m)
    }

    /// Whether splitting face `f` at `point` is legal: the three new triangles non-degenerate
    /// and facing the same side as `f` (so `point` lies inside it).
    pub fn can_split_face(&self, f: u32, point: [f32; 3]) -> Result<(), SplitRefusal> {
        let [a, b, c] = self.face(f).map(|v| self.point(v));
        let q = vec(point);
        Ok(faces_agree(&[[a, b, q], [b, c, q], [c, a, q]], area_vector(a, b, c))?)
    }

    /// Splits face `f` 1→3 at `point` (the centroid for densification) when
    /// [`Self::can_split_face`] allows it. Returns the new vertex. Adds 1 vertex, 3 edges,
    /// 2 faces.
    pub fn split_face(&mut self, f: u32, point: [f32; 3]) -> Result<u32, SplitRefusal> {
        self.can_split_face(f, point)?;
        let [a, b, c] = self.face(f);
        let m = self.push_vertex(point);
        self.faces[f as usize] = [a, b, m];
        let touched = [f, self.push_face([b, c, m]), self.push_face([c, a, m])];
        self.relink(&touched);
        Ok(m)
    }

    /// Whether flipping the edge of `h` is legal: interior, the new diagonal not already an
    /// edge, and both new triangles non-degenerate and facing the same side as the old pair.
    pub fn can_flip(&self, h: u32) -> Result<(), FlipRefusal> {
        let t = self.twin(h);
        if t == NONE {
            return Err(FlipRefusal::Boundary);
        }
        let (a, b, c, d) =
            (self.origin(h), self.dest(h), self.origin(prev(h)), self.origin(prev(t)));
        if self.are_neighbours(c, d) {
            return Err(FlipRefusal::EdgeExists);
        }
        let [a, b, c, d] = [a, b, c, d].map(|v| self.point(v));
        let old = area_vector(a, b, c) + area_vector(b, a, d);
        Ok(faces_agree(&[[a, d, c], [d, b, c]], old)?)
    }

    /// Flips the edge of `h` (faces (a, b, c), (b, a, d) become (a, d, c), (d, b, c)) when
    /// [`Self::can_flip`] allows it. Vertex, edge and face counts are unchanged.
    pub fn flip_edge(&mut self, h: u32) -> Result<(), FlipRefusal> {
        self.can_flip(h)?;
        let t = self.twin(h);
        let (a, b, c, d) =
            (self.origin(h), self.dest(h), self.origin(prev(h)), self.origin(prev(t)));
        let (f0, f1) = (face_of(h), face_of(t));
        self.faces[f0 as usize] = [a, d, c];
        self.faces[f1 as usize] = [d, b, c];
        self.relink(&[f0, f1]);
        Ok(())
    }

    /// Whether collapsing `h` (its origin merged into its destination, which moves to
    /// `point`) is legal; see [`Self::can_merge`].
    pub fn can_collapse(&self, h: u32, point: [f32; 3]) -> Result<(), CollapseRefusal> {
        self.can_merge(h, self.origin(h), point)
    }

    /// Whether merging `removed` (either end of the edge of `h`) into the other end, which
    /// moves to `point`, is legal: more than 4 vertices remain, the link condition holds, an
    /// interior edge does not join two boundary vertices, no vertex is left without a face, and
    /// no remaining face around either end flips its normal or degenerates.
    pub fn can_merge(&self, h: u32, removed: u32, point: [f32; 3]) -> Result<(), CollapseRefusal> {
        if self.live_vertices <= 5 {
            return Err(CollapseRefusal::TooFewVertices);
        }
        let (a, b) = self.ends(h, removed);
        let t = self.twin(h);
        let mut opposite = 1;
        if t != NONE {
            opposite = 2;
            if self.is_boundary_vertex(a) && self.is_boundary_vertex(b) {
                return Err(CollapseRefusal::BoundaryPinch);
            }
        }
        let ring_b = self.ring(b);
        if self.ring(a).into_iter().filter(|v| ring_b.contains(v)).count() != opposite {
            return Err(CollapseRefusal::LinkCondition);
        }
        for e in [h, t] {
            if e != NONE && self.twin(next(e)) == NONE && self.twin(prev(e)) == NONE {
                return Err(CollapseRefusal::DanglingVertex);
            }
        }
        self.check_moved_faces(a, b, point)?;
        self.check_moved_faces(b, a, point)
    }

    /// `(removed, kept)` ends of the edge of `h`.
    #[inline]
    fn ends(&self, h: u32, removed: u32) -> (u32, u32) {
        let (o, d) = (self.origin(h), self.dest(h));
        debug_assert!(removed == o || removed == d, "vertex {removed} is not on edge {o}–{d}");
        if removed == o {
            (o, d)
        } else {
            (d, o)
        }
    }

    /// Faces around `v` that do not contain `other`, with `v` moved to `point`.
    fn check_moved_faces(
        &self,
        v: u32,
        other: u32,
        point: [f32; 3],
    ) -> Result<(), CollapseRefusal> {
        let q = vec(point);
        for e in self.outgoing(v) {
            let f = face_of(e);
            let corners = self.face(f);
            if corners.contains(&other) {
                continue;
            }
            let old: [DVec3; 3] = corners.map(|c| self.point(c));
            let new: [DVec3; 3] = corners.map(|c| if c == v { q } else { self.point(c) });
            faces_agree(&[new], area_vector(old[0], old[1], old[2])).map_err(|g| match g {
                GeometryRefusal::Degenerate => CollapseRefusal::Degenerate { face: f },
                GeometryRefusal::FoldsOver => CollapseRefusal::FlipsNormal { face: f },
            })?;
        }
        Ok(())
    }

    /// Collapses `h` when [`Self::can_collapse`] allows it: `origin(h)` is removed, its faces
    /// are re-attached to `dest(h)`, which moves to `point`; returns `dest(h)`. Removes 1
    /// vertex, 3 edges, 2 faces (interior edge) or 1 vertex, 2 edges, 1 face (boundary edge).
    pub fn collapse_edge(&mut self, h: u32, point: [f32; 3]) -> Result<u32, CollapseRefusal> {
        self.merge(h, self.origin(h), point)
    }

    /// Like [`Self::collapse_edge`] with the removed end chosen: `removed` (either end of the
    /// edge of `h`) merges into the other, which moves to `point` and is returned. This is the
    /// pruning step (a boundary edge has one half-edge, so its direction cannot choose).
    pub fn merge(&mut self, h: u32, removed: u32, point: [f32; 3]) -> Result<u32, CollapseRefusal> {
        self.can_merge(h, removed, point)?;
        let (a, b) = self.ends(h, removed);
        let t = self.twin(h);
        let removed: Vec<u32> = [h, t].into_iter().filter(|&e| e != NONE).map(face_of).collect();
        let mut touched: Vec<u32> = self
            .outgoing(a)
            .chain(self.outgoing(b))
            .map(face_of)
            .filter(|f| !removed.contains(f))
            .collect();
        touched.sort_unstable();
        touched.dedup();
        for &f in &touched {
            for corner in &mut self.faces[f as usize] {
                if *corner == a {
                    *corner = b;
                }
            }
        }
        for f in removed {
            self.remove_face(f);
        }
        self.remove_vertex(a);
        self.positions[b as usize] = point;
        self.relink(&touched);
        Ok(b)
    }

    /// Re-links twins of every half-edge of `touched` (faces just rewritten, their old twin
    /// links still in place) by matching directed edges among themselves and their former
    /// outside twins, then re-anchors their vertices.
    pub(super) fn relink(&mut self, touched: &[u32]) {
        let inside: Vec<u32> = touched.iter().flat_map(|&f| 3 * f..3 * f + 3).collect();
        let mut outside: Vec<u32> = inside.iter().map(|&e| self.twin(e)).collect();
        outside.retain(|&e| {
            e != NONE && !touched.contains(&face_of(e)) && self.is_face_live(face_of(e))
        });
        for &e in &outside {
            self.twins[e as usize] = NONE;
        }
        for &e in &inside {
            self.twins[e as usize] = NONE;
        }
        for (i, &e) in inside.iter().enumerate() {
            let (from, to) = (self.origin(e), self.dest(e));
            let matches = |g: &u32| self.origin(*g) == to && self.dest(*g) == from;
            let partner = inside[i + 1..]
                .iter()
                .chain(outside.iter())
                .copied()
                .find(|g| matches(g) && self.twin(*g) == NONE);
            if let Some(g) = partner {
                self.link(e, g);
            }
        }
        for &e in &inside {
            self.reanchor(self.origin(e), e);
        }
    }
}
