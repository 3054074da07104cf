//! The mesh as the rasterizer takes it: validated positions, faces and colours, plus the edge
//! adjacency the anti-aliasing uses to tell outline edges from inner ones.

use super::RasterError;
use std::collections::HashMap;

/// Positions (world units), counter-clockwise faces and linear RGB colours per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RasterMesh {
    /// Vertex positions, world units.
    pub positions: Vec<[f32; 3]>,
    /// Triangles as vertex indices, counter-clockwise.
    pub faces: Vec<[u32; 3]>,
    /// Linear RGB colour per vertex.
    pub colors: Vec<[f32; 3]>,
}

impl RasterMesh {
    /// Checks finiteness, indices and the colour count; the first problem is the error.
    pub fn new(
        positions: Vec<[f32; 3]>,
        faces: Vec<[u32; 3]>,
        colors: Vec<[f32; 3]>,
    ) -> Result<Self, RasterError> {
        check_positions(&positions)?;
        let vertices = positions.len();
        if let Some(face) = faces.iter().position(|f| f.iter().any(|&i| i as usize >= vertices)) {
            return Err(RasterError::FaceIndex { face, indices: faces[face], vertices });
        }
        let max = (u32::MAX / 2) as usize;
        if faces.len() > max {
            return Err(RasterError::TooManyTriangles { triangles: faces.len(), max });
        }
        if colors.len() != vertices {
            return Err(RasterError::Length {
                what: "vertex colours",
                len: colors.len(),
                expected: vertices,
            });
        }
        Ok(Self { positions, faces, colors })
    }

    /// `mesh` as `tagsplat render-mesh` draws it: its vertex colours scaled to [0, 1], light grey
    /// (0.8) without any; a mesh with no triangles is refused, as is anything [`Self::new`]
    /// refuses.
    pub fn from_mesh(mesh: crate::mesh::TriMesh) -> Result<Self, RasterError> {
        if mesh.faces.is_empty() {
            return Err(RasterError::NoTriangles);
        }
        let colors = match &mesh.colors {
            Some(colors) => colors.iter().map(|c| c.map(|v| v as f32 / 255.0)).collect(),
            None => vec![[0.8; 3]; mesh.positions.len()],
        };
        Self::new(mesh.positions, mesh.faces, colors)
    }

    /// A mesh of one colour.
    pub fn uniform(
        positions: Vec<[f32; 3]>,
        faces: Vec<[u32; 3]>,
        color: [f32; 3],
    ) -> Result<Self, RasterError> {
        let colors = vec![color; positions.len()];
        Self::new(positions, faces, colors)
    }
}

/// The first non-finite position, as an error.
pub(crate) fn check_positions(positions: &[[f32; 3]]) -> Result<(), RasterError> {
    match positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        Some(vertex) => Err(RasterError::NonFinite { vertex, position: positions[vertex] }),
        None => Ok(()),
    }
}

/// For face f and edge k (corner k to corner k + 1), the face across that edge, or -1 when
/// there is none or the edge is not manifold (more than two faces, or two faces running it the
/// same way); the anti-aliasing then treats it as an outline edge.
pub fn edge_adjacency(faces: &[[u32; 3]]) -> Vec<i32> {
    let mut directed: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
    for (f, face) in faces.iter().enumerate() {
        for k in 0..3 {
            directed.entry((face[k], face[(k + 1) % 3])).or_default().push(f as u32);
        }
    }
    let mut adjacency = Vec::with_capacity(3 * faces.len());
    for face in faces {
        for k in 0..3 {
            let (a, b) = (face[k], face[(k + 1) % 3]);
            let across = match (directed.get(&(a, b)).map(Vec::len), directed.get(&(b, a))) {
                (Some(1), Some(other)) if other.len() == 1 => other[0] as i32,
                _ => -1,
            };
            adjacency.push(across);
        }
    }
    adjacency
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_of_a_quad_and_of_a_non_manifold_edge() {
        let quad = [[0, 1, 2], [0, 2, 3]];
        assert_eq!(edge_adjacency(&quad), vec![-1, -1, 1, 0, -1, -1]);
        // Three faces on edge (0, 1): no neighbour for any of them.
        let fan = [[0, 1, 2], [1, 0, 3], [1, 0, 4]];
        assert!(edge_adjacency(&fan).iter().all(|&a| a == -1));
    }

    #[test]
    fn bad_meshes_are_refused_with_the_culprit() {
        let p = vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let e = RasterMesh::uniform(p.clone(), vec![[0, 1, 3]], [1.0; 3]).unwrap_err();
        assert!(e.to_string().contains("face 0"), "{e}");
        let mut nan = p.clone();
        nan[2][1] = f32::NAN;
        let e = RasterMesh::uniform(nan, vec![[0, 1, 2]], [1.0; 3]).unwrap_err();
        assert!(e.to_string().contains("vertex 2"), "{e}");
        let e = RasterMesh::new(p, vec![[0, 1, 2]], vec![[1.0; 3]]).unwrap_err();
        assert!(e.to_string().contains("colours"), "{e}");
    }
}
