//! The full invariant check: what every operation must preserve. O(V + F); tests run it after
//! every operation, callers may run it after loading or editing.

use super::geometry::{is_degenerate, vec};
use super::mesh::{face_of, ManifoldMesh, NONE};

impl ManifoldMesh {
    /// The first broken invariant, if any: twins mutual and reversed (so every edge has one or
    /// two faces and orientation is consistent), every live vertex's fan (walked from its
    /// anchor) holds all its faces and starts on the boundary when it has one (its link is a
    /// disk or half-disk), no live face references a removed vertex, no face is degenerate, the
    /// live counts are right.
    pub fn problem(&self) -> Option<String> {
        let mut incident = vec![0usize; self.positions.len()];
        let mut faces = 0;
        for f in self.faces() {
            faces += 1;
            let corners = self.face(f);
            for &v in &corners {
                if !self.is_vertex_live(v) {
                    return Some(format!("face {f} {corners:?} uses removed vertex {v}"));
                }
                incident[v as usize] += 1;
            }
            let [a, b, c] = corners.map(|v| vec(self.positions[v as usize]));
            if is_degenerate(a, b, c) {
                return Some(format!("face {f} {corners:?} is degenerate"));
            }
            if let Some(problem) = self.twin_problem(f) {
                return Some(problem);
            }
        }
        if faces != self.live_faces {
            return Some(format!("{faces} live faces counted, {} recorded", self.live_faces));
        }
        let mut vertices = 0;
        for v in self.vertices() {
            vertices += 1;
            if let Some(problem) = self.fan_problem(v, incident[v as usize]) {
                return Some(problem);
            }
        }
        (vertices != self.live_vertices)
            .then(|| format!("{vertices} live vertices counted, {} recorded", self.live_vertices))
    }

    fn twin_problem(&self, f: u32) -> Option<String> {
        for h in 3 * f..3 * f + 3 {
            let t = self.twin(h);
            if t == NONE {
                continue;
            }
            if !self.is_face_live(face_of(t))
                || self.twin(t) != h
                || self.origin(t) != self.dest(h)
                || self.dest(t) != self.origin(h)
            {
                return Some(format!(
                    "half-edge {h} ({}→{}) and its twin {t} do not match",
                    self.origin(h),
                    self.dest(h)
                ));
            }
        }
        None
    }

    fn fan_problem(&self, v: u32, incident: usize) -> Option<String> {
        let anchor = self.anchors[v as usize];
        if !self.is_face_live(face_of(anchor)) || self.origin(anchor) != v {
            return Some(format!("vertex {v}: anchor {anchor} is not one of its half-edges"));
        }
        let boundary_edges = self.outgoing(v).filter(|&h| self.twin(h) == NONE).count();
        let fan = self.outgoing(v).count();
        if fan != incident {
            return Some(format!(
                "vertex {v}: its fan has {fan} of its {incident} faces (pinched)"
            ));
        }
        let starts_on_boundary = self.twin(anchor) == NONE;
        if boundary_edges > 1 || (boundary_edges == 1 && !starts_on_boundary) {
            return Some(format!("vertex {v}: boundary fan does not start at its anchor"));
        }
        None
    }

    /// V − E + F of the live mesh.
    pub fn euler_characteristic(&self) -> i64 {
        self.vertex_count() as i64 - self.edge_count() as i64 + self.face_count() as i64
    }
}
