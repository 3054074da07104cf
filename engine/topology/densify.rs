//! Densification: faces whose gradient statistic passes a threshold split 1→3 at their
//! centroid; then edge flips raise the minimum angle so repeated splits do not breed slivers.

use super::flips::improve_angles;
use super::remap::NEW_ROW;
use super::scene_remap::remap_scene;
use super::{ManifoldMesh, TopologyError};
use crate::splat::GaussianScene;

/// Densification settings. Lengths are relative to the bounding-box diagonal (scale-free).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DensifyConfig {
    /// A face splits when its score (see [`face_scores`]) exceeds this.
    pub threshold: f32,
    /// At most this many faces split per step, highest scores first (the budget).
    pub max_splits: usize,
    /// The paper's scale rule: a new Gaussian whose mean scale exceeds this fraction of the
    /// extent has its scales halved, and so do its three corners.
    pub large_scale: f32,
}

impl Default for DensifyConfig {
    fn default() -> Self {
        // 3DGS: gradient threshold 2e-4 (NDC; ours is in pixels, see the splat docs), dense
        // fraction 1%.
        Self { threshold: 2e-4, max_splits: usize::MAX, large_scale: 0.01 }
    }
}

/// What a densification step did, and the remap it applied.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DensifyReport {
    /// The vertex remap applied to the mesh and scene: the old row of each new row,
    /// [`NEW_ROW`] for the Gaussians added by splits.
    pub old_of_new: Vec<u32>,
    /// Faces split 1→3 at their centroid.
    pub split_faces: usize,
    /// Faces over the threshold that could not split (a centroid split would make a
    /// degenerate triangle).
    pub refused_splits: usize,
    /// Edge flips made by [`improve_angles`] after the splits.
    pub flips: usize,
    /// Gaussians whose scales the scale rule halved (new ones and their corners).
    pub halved: usize,
}

/// Per-face score: the mean of its corners' scores (e.g. accumulated |dL/dmean| over the views
/// that saw the Gaussian), one entry per face row (0 for removed faces).
pub fn face_scores(mesh: &ManifoldMesh, vertex_scores: &[f32]) -> Vec<f32> {
    (0..mesh.face_rows() as u32)
        .map(|f| {
            if mesh.is_face_live(f) {
                mesh.face(f).iter().map(|&v| vertex_scores[v as usize]).sum::<f32>() / 3.0
            } else {
                0.0
            }
        })
        .collect()
}

/// Splits the faces of `mesh` whose `scores` pass the threshold, flips for angles, compacts,
/// and remaps `scene` (whose rows must be the mesh's vertex rows) in place. Faces split in
/// decreasing score order (ties by face index), and the new rows come in that order after the
/// kept ones. The caller applies the returned `old_of_new` to its other per-vertex arrays.
/// `mesh` must be compact.
pub fn densify(
    mesh: &mut ManifoldMesh,
    scene: &mut GaussianScene,
    scores: &[f32],
    config: &DensifyConfig,
) -> Result<DensifyReport, TopologyError> {
    check_rows(mesh, scene)?;
    if scores.len() != mesh.face_rows() {
        return Err(TopologyError::Mismatch(format!(
            "{} face scores for {} faces",
            scores.len(),
            mesh.face_rows()
        )));
    }
    let mut chosen: Vec<u32> =
        mesh.faces().filter(|&f| scores[f as usize] > config.threshold).collect();
    chosen.sort_by(|&a, &b| scores[b as usize].total_cmp(&scores[a as usize]));
    chosen.truncate(config.max_splits);
    let mut parents = Vec::with_capacity(chosen.len());
    let mut report = DensifyReport::default();
    let mut touched = Vec::with_capacity(chosen.len() * 3);
    for f in chosen {
        let corners = mesh.face(f);
        let c = corners.map(|v| mesh.positions[v as usize]);
        let centroid = [0, 1, 2].map(|k| (c[0][k] + c[1][k] + c[2][k]) / 3.0);
        let before = mesh.face_rows() as u32;
        match mesh.split_face(f, centroid) {
            Ok(_) => {
                parents.push(corners);
                touched.extend([f, before, before + 1]);
                report.split_faces += 1;
            }
            Err(_) => report.refused_splits += 1,
        }
    }
    report.flips = improve_angles(mesh, &touched);
    report.old_of_new = mesh.compact();
    let mut remapped = remap_scene(scene, &report.old_of_new, &parents);
    report.halved = halve_large(
        &mut remapped,
        &report.old_of_new,
        &parents,
        config.large_scale * crate::mesh::bounding_diagonal(&mesh.positions) as f32,
    );
    *scene = remapped;
    Ok(report)
}

/// The mesh is compact and the scene has one row per vertex.
pub(super) fn check_rows(mesh: &ManifoldMesh, scene: &GaussianScene) -> Result<(), TopologyError> {
    if mesh.vertex_rows() != mesh.vertex_count() || mesh.face_rows() != mesh.face_count() {
        return Err(TopologyError::Mismatch(
            "the mesh has removed rows: compact() it first".into(),
        ));
    }
    if scene.len() != mesh.vertex_count() {
        return Err(TopologyError::Mismatch(format!(
            "{} Gaussians for {} mesh vertices",
            scene.len(),
            mesh.vertex_count()
        )));
    }
    scene.check().map_err(|e| TopologyError::Mismatch(e.to_string()))
}

/// The scale rule on the remapped scene: each new Gaussian whose mean scale exceeds `large`
/// gets its log-scales lowered by ln 2, and so does each of its corners (once). Returns how
/// many Gaussians were halved.
fn halve_large(
    scene: &mut GaussianScene,
    old_of_new: &[u32],
    parents: &[[u32; 3]],
    large: f32,
) -> usize {
    let mut new_of_old = vec![
        NEW_ROW;
        old_of_new
            .iter()
            .filter(|&&r| r != NEW_ROW)
            .map(|&r| r as usize + 1)
            .max()
            .unwrap_or(0)
    ];
    old_of_new
        .iter()
        .enumerate()
        .filter(|(_, &r)| r != NEW_ROW)
        .for_each(|(row, &r)| new_of_old[r as usize] = row as u32);
    let mut halve = vec![false; scene.len()];
    let new_rows = old_of_new.iter().enumerate().filter(|(_, &r)| r == NEW_ROW).map(|(row, _)| row);
    for (row, corners) in new_rows.zip(parents) {
        let mean = scene.log_scales[row].iter().map(|s| s.exp()).sum::<f32>() / 3.0;
        if mean > large {
            halve[row] = true;
            corners.iter().for_each(|&c| halve[new_of_old[c as usize] as usize] = true);
        }
    }
    for (row, _) in halve.iter().enumerate().filter(|(_, &h)| h) {
        scene.log_scales[row].iter_mut().for_each(|s| *s -= std::f32::consts::LN_2);
    }
    halve.iter().filter(|&&h| h).count()
}
