//! Triangle meshes as plain arrays: positions, counter-clockwise faces (seen from outside),
//! optional vertex colours. File formats live beside the type (`read_ply`, `write_ply`).

mod bounds;
pub mod obj;
pub mod polygon;
pub mod skinning;

pub use bounds::{bounding_box, bounding_diagonal};

use crate::io::ply::{write_ply, ColumnOut, ElementOut, Ply, PlyError};
use std::path::{Path, PathBuf};

/// Why a mesh file could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// A PLY file cannot be read, parsed or written, or lacks a required element or property.
    #[error(transparent)]
    Ply(#[from] PlyError),
    /// Any other problem with a mesh file: the mesh is invalid ([`TriMesh::problem`]), a face has
    /// fewer than 3 vertices, or (OBJ) the file cannot be read, parsed or written.
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        problem: String,
    },
}

/// A triangle mesh as plain arrays: positions, counter-clockwise faces (seen from outside),
/// optional vertex colours. Not checked on construction; see [`TriMesh::problem`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions, world units.
    pub positions: Vec<[f32; 3]>,
    /// Vertex indices of each triangle, counter-clockwise seen from outside.
    pub faces: Vec<[u32; 3]>,
    /// Per-vertex sRGB-free 8-bit colours (values in [0, 255] mapping to [0, 1]).
    pub colors: Option<Vec<[u8; 3]>>,
}

impl TriMesh {
    /// The first problem that makes this mesh unusable, if any: a non-finite position, a face
    /// index out of range, or a colour count that differs from the vertex count.
    pub fn problem(&self) -> Option<String> {
        if let Some(v) = self.positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
            return Some(format!("vertex {v} has a non-finite position {:?}", self.positions[v]));
        }
        let n = self.positions.len();
        if let Some(f) = self.faces.iter().position(|face| face.iter().any(|&i| i as usize >= n)) {
            return Some(format!("face {f} {:?} indexes past the {n} vertices", self.faces[f]));
        }
        match &self.colors {
            Some(colors) if colors.len() != n => {
                Some(format!("{} colours for {n} vertices", colors.len()))
            }
            _ => None,
        }
    }

    /// [`TriMesh::problem`] as an error naming `path`.
    pub fn validate(&self, path: &Path) -> Result<(), MeshError> {
        match self.problem() {
            Some(problem) => Err(MeshError::Invalid { path: path.to_path_buf(), problem }),
            None => Ok(()),
        }
    }

    /// Reads `x y z` (and `red green blue` when present) of `vertex` and the `vertex_indices`
    /// (or `vertex_index`) lists of `face`; polygons are fanned into triangles. Validated.
    pub fn read_ply(path: &Path) -> Result<Self, MeshError> {
        let ply = Ply::read(path)?;
        let vertex = ply.require("vertex")?;
        let (x, y, z) = (vertex.column_f32("x")?, vertex.column_f32("y")?, vertex.column_f32("z")?);
        let positions = (0..vertex.len()).map(|i| [x[i], y[i], z[i]]).collect();
        let colors = if vertex.has("red") {
            let [r, g, b] =
                [vertex.column_u8("red")?, vertex.column_u8("green")?, vertex.column_u8("blue")?];
            Some((0..vertex.len()).map(|i| [r[i], g[i], b[i]]).collect())
        } else {
            None
        };
        let faces = match ply.element("face") {
            Some(face) => {
                let property =
                    if face.has("vertex_indices") { "vertex_indices" } else { "vertex_index" };
                fan_triangles(path, &face.lists_u32(property)?, vertex.len())?
            }
            None => Vec::new(),
        };
        let mesh = Self { positions, faces, colors };
        mesh.validate(path)?;
        Ok(mesh)
    }

    /// Writes a binary PLY (vertex colours when present), atomically.
    pub fn write_ply(&self, path: &Path) -> Result<(), MeshError> {
        self.validate(path)?;
        let coordinate = |c: usize| ColumnOut::F32(self.positions.iter().map(|p| p[c]).collect());
        let mut vertex = ElementOut::new("vertex")
            .with("x", coordinate(0))
            .with("y", coordinate(1))
            .with("z", coordinate(2));
        if let Some(colors) = &self.colors {
            for (c, name) in ["red", "green", "blue"].into_iter().enumerate() {
                vertex =
                    vertex.with(name, ColumnOut::U8(colors.iter().map(|rgb| rgb[c]).collect()));
            }
        }
        let face = ElementOut::new("face")
            .with("vertex_indices", ColumnOut::Triangles(self.faces.clone()));
        Ok(write_ply(path, &["tagsplat triangle mesh"], &[vertex, face])?)
    }
}

/// Polygons as triangle fans ([`polygon::fan_triangulate`]), every index below `vertices`.
fn fan_triangles(
    path: &Path,
    polygons: &[Vec<u32>],
    vertices: usize,
) -> Result<Vec<[u32; 3]>, MeshError> {
    let counts: Vec<u32> = polygons.iter().map(|p| p.len() as u32).collect();
    let (faces, _) = polygon::fan_triangulate(&counts, &polygons.concat(), vertices)
        .map_err(|problem| MeshError::Invalid { path: path.to_path_buf(), problem })?;
    Ok(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ply_round_trip_and_quads() {
        let path = std::env::temp_dir().join(format!("tagsplat-mesh-{}.ply", std::process::id()));
        let mesh = TriMesh {
            positions: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.1, 0.2, 1e-30]],
            faces: vec![[0, 1, 2], [0, 2, 3]],
            colors: Some(vec![[255, 0, 0], [0, 255, 0], [0, 0, 255], [1, 2, 3]]),
        };
        mesh.write_ply(&path).unwrap();
        assert_eq!(TriMesh::read_ply(&path).unwrap(), mesh);
        let quad = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
            element face 1\nproperty list uchar uint vertex_index\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        std::fs::write(&path, quad).unwrap();
        let read = TriMesh::read_ply(&path).unwrap();
        assert_eq!(read.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(read.colors, None);
        std::fs::write(&path, quad.replace("4 0 1 2 3", "3 0 1 9")).unwrap();
        let message = TriMesh::read_ply(&path).unwrap_err().to_string();
        assert!(
            message.contains("polygon 0") && message.contains("past the 4 vertices"),
            "{message}"
        );
        std::fs::write(&path, quad.replace("property float z\n", "").replace("0 0 0\n", "0 0\n"))
            .unwrap();
        assert!(TriMesh::read_ply(&path).unwrap_err().to_string().contains("no property 'z'"));
        std::fs::remove_file(&path).unwrap();
    }
}
