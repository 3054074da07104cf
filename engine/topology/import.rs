//! Import of a [`TriMesh`] (PLY/OBJ) into a [`ManifoldMesh`], with the documented repairs:
//! duplicate positions welded, faces that lose a corner to the weld dropped, unused vertices
//! dropped, orientation made consistent. Everything else is an error naming the file.

use super::remap::{compose, remap_rows};
use super::{orient_faces, weld, ManifoldMesh, TopologyError, TriMesh};
use std::path::Path;

/// Weld tolerance relative to the bounding-box diagonal (scale-free).
pub const WELD_TOLERANCE: f32 = 1e-6;

/// What [`import`] repaired.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ImportReport {
    /// Vertex rows merged into an earlier one by the weld.
    pub welded_vertices: usize,
    /// Faces dropped because the weld merged two of their corners.
    pub dropped_faces: usize,
    /// Welded vertices used by no remaining face, dropped.
    pub unused_vertices: usize,
    /// Faces reversed to make the orientation consistent.
    pub flipped_faces: usize,
}

/// An imported mesh, the repairs made, and `old_of_new` from the file's vertex rows to the
/// mesh's (apply it to per-vertex colours with [`super::remap_rows`]).
#[derive(Clone, Debug)]
pub struct Imported {
    /// The manifold mesh built from the repaired arrays.
    pub mesh: ManifoldMesh,
    /// The repairs made.
    pub report: ImportReport,
    /// For each vertex row of `mesh`, the file's vertex row it comes from.
    pub old_of_new: Vec<u32>,
}

/// Imports `mesh` read from `path` (named in every error). Errors: non-finite positions, bad
/// indices, non-manifold edges or vertices, a non-orientable surface, fewer than 4 faces, and
/// an open surface when `require_closed`.
pub fn import(
    mesh: &TriMesh,
    path: &Path,
    require_closed: bool,
) -> Result<Imported, TopologyError> {
    import_arrays(mesh, require_closed)
        .map_err(|e| TopologyError::InFile { path: path.to_path_buf(), source: Box::new(e) })
}

fn import_arrays(mesh: &TriMesh, require_closed: bool) -> Result<Imported, TopologyError> {
    if let Some(v) = mesh.positions.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(TopologyError::NonFinite { vertex: v as u32 });
    }
    let n = mesh.positions.len();
    if let Some(f) = mesh.faces.iter().position(|face| face.iter().any(|&v| v as usize >= n)) {
        return Err(TopologyError::IndexOutOfRange {
            face: f as u32,
            corners: mesh.faces[f],
            vertices: n,
        });
    }
    let welded = weld(
        &mesh.positions,
        &mesh.faces,
        WELD_TOLERANCE * crate::mesh::bounding_diagonal(&mesh.positions) as f32,
    );
    let mut used = vec![false; welded.positions.len()];
    welded.faces.iter().flatten().for_each(|&v| used[v as usize] = true);
    let kept: Vec<u32> = (0..used.len() as u32).filter(|&v| used[v as usize]).collect();
    let mut new_of_welded = vec![0u32; used.len()];
    kept.iter().enumerate().for_each(|(new, &old)| new_of_welded[old as usize] = new as u32);
    let mut faces: Vec<[u32; 3]> =
        welded.faces.iter().map(|f| f.map(|v| new_of_welded[v as usize])).collect();
    let positions =
        remap_rows(&welded.positions, &kept, |_| unreachable!("compaction adds no rows"));
    if faces.len() < 4 {
        return Err(TopologyError::TooSmall { faces: faces.len() });
    }
    let flipped_faces = orient_faces(&positions, &mut faces)?;
    let built = ManifoldMesh::new(positions, faces)?;
    if require_closed {
        if let Some(h) = built.edges().find(|&h| built.is_boundary_edge(h)) {
            return Err(TopologyError::Open { a: built.origin(h), b: built.dest(h) });
        }
    }
    let report = ImportReport {
        welded_vertices: n - welded.positions.len(),
        dropped_faces: welded.dropped_faces,
        unused_vertices: welded.positions.len() - kept.len(),
        flipped_faces,
    };
    Ok(Imported { mesh: built, report, old_of_new: compose(&welded.old_of_new, &kept) })
}
