//! Compaction: tombstones out, plain arrays and the vertex remap back.

use super::mesh::{ManifoldMesh, NONE};
use super::remap::NEW_ROW;

impl ManifoldMesh {
    /// Drops removed faces and vertices in place, keeping the order of what is left. Returns
    /// `old_of_new` for the vertices relative to the rows at the previous compaction (or
    /// construction): rows added since then map to [`NEW_ROW`]. Vertices added since the last
    /// compaction and removed again simply vanish.
    pub fn compact(&mut self) -> Vec<u32> {
        let mut new_vertex = vec![NONE; self.positions.len()];
        let mut old_of_new = Vec::with_capacity(self.live_vertices);
        for (v, &anchor) in self.anchors.iter().enumerate() {
            if anchor != NONE {
                new_vertex[v] = old_of_new.len() as u32;
                old_of_new.push(if v < self.synced_vertices { v as u32 } else { NEW_ROW });
            }
        }
        let mut new_face = vec![NONE; self.faces.len()];
        let mut kept = 0;
        for (f, face) in self.faces.iter().enumerate() {
            if face[0] != NONE {
                new_face[f] = kept;
                kept += 1;
            }
        }
        let half_edge =
            |h: u32| if h == NONE { NONE } else { 3 * new_face[(h / 3) as usize] + h % 3 };
        let faces = self.faces().map(|f| self.face(f).map(|v| new_vertex[v as usize])).collect();
        let twins =
            self.faces().flat_map(|f| 3 * f..3 * f + 3).map(|h| half_edge(self.twin(h))).collect();
        let mut anchors = Vec::with_capacity(old_of_new.len());
        let mut positions = Vec::with_capacity(old_of_new.len());
        for v in self.vertices() {
            anchors.push(half_edge(self.anchors[v as usize]));
            positions.push(self.positions[v as usize]);
        }
        self.faces = faces;
        self.twins = twins;
        self.anchors = anchors;
        self.positions = positions;
        self.synced_vertices = old_of_new.len();
        old_of_new
    }

    /// Compacts and hands back the plain arrays: positions, faces and `old_of_new` (see
    /// [`Self::compact`]).
    pub fn into_arrays(mut self) -> (Vec<[f32; 3]>, Vec<[u32; 3]>, Vec<u32>) {
        let old_of_new = self.compact();
        (self.positions, self.faces, old_of_new)
    }
}
