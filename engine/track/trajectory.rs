//! Trajectories: a bound point's position in every frame.

use super::bind::Binding;
use super::TrackError;
use glam::DVec3;

/// Position of `binding` on the mesh with `faces` and vertex `positions`: `Σ bₖ·v[face[k]]`.
/// None when the face or one of its vertices is out of range.
#[inline]
pub fn position(binding: &Binding, faces: &[[u32; 3]], positions: &[[f32; 3]]) -> Option<DVec3> {
    let face = faces.get(binding.face as usize)?;
    let mut p = DVec3::ZERO;
    for (k, &index) in face.iter().enumerate() {
        let v = positions.get(index as usize)?;
        p += DVec3::from(v.map(f64::from)) * binding.barycentric[k];
    }
    Some(p)
}

/// `result[i][t]` is the position of `bindings[i]` in frame `t` of `frames` (vertex positions
/// per frame, all sharing `faces`).
///
/// Errors: a frame with a vertex count unlike frame 0's; a binding whose face, or a vertex of
/// it, is out of range.
pub fn trajectories(
    bindings: &[Binding],
    faces: &[[u32; 3]],
    frames: &[Vec<[f32; 3]>],
) -> Result<Vec<Vec<DVec3>>, TrackError> {
    let expected = frames.first().map_or(0, Vec::len);
    if let Some((frame, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != expected) {
        return Err(TrackError::FrameVertexCount { frame, found: f.len(), expected });
    }
    bindings
        .iter()
        .enumerate()
        .map(|(i, b)| {
            frames
                .iter()
                .map(|f| {
                    position(b, faces, f).ok_or(TrackError::FaceOutOfRange {
                        binding: i,
                        face: b.face,
                        faces: faces.len(),
                    })
                })
                .collect()
        })
        .collect()
}
