//! Pruning: a Gaussian picked by the 3DGS criteria merges into the 1-ring neighbour of
//! cheapest legal collapse, C = w_g·‖pᵢ − pⱼ‖ / mean edge + w_a·‖cᵢ − cⱼ‖ (seed eq. after 8).

use super::densify::check_rows;
use super::gaussians::dc_colors;
use super::mesh::{ManifoldMesh, NONE};
use super::scene_remap::remap_scene;
use super::TopologyError;
use crate::splat::GaussianScene;

/// Pruning settings (scale-free: lengths relative to the extent or the mean edge).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PruneConfig {
    /// Prune when sigmoid(opacity logit) is below this (3DGS: 0.005).
    pub min_opacity: f32,
    /// Prune when the largest scale exceeds this fraction of the bounding-box diagonal
    /// (3DGS: 0.1 of the scene extent).
    pub max_scale: f32,
    /// Weight of the distance term, in units of the mean edge length.
    pub w_g: f32,
    /// Weight of the colour term (linear RGB distance of the SH DC colours).
    pub w_a: f32,
}

impl Default for PruneConfig {
    fn default() -> Self {
        Self { min_opacity: 0.005, max_scale: 0.1, w_g: 1.0, w_a: 1.0 }
    }
}

/// What a pruning step did, and the remap it applied.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PruneReport {
    /// The vertex remap applied to the mesh and scene: the old row of each kept row.
    pub old_of_new: Vec<u32>,
    /// Gaussians picked by the criteria.
    pub candidates: usize,
    /// Picked Gaussians merged into a neighbour and removed.
    pub pruned: usize,
    /// Picked Gaussians that stay because none of their edges could collapse legally.
    pub kept_no_legal_edge: usize,
}

/// Whether Gaussian `i` meets the pruning criteria.
pub fn should_prune(scene: &GaussianScene, i: usize, config: &PruneConfig, extent: f32) -> bool {
    let opacity = 1.0 / (1.0 + (-scene.opacity_logits[i]).exp());
    let largest = scene.log_scales[i].iter().copied().fold(f32::NEG_INFINITY, f32::max).exp();
    opacity < config.min_opacity || largest > config.max_scale * extent
}

/// Merges every Gaussian meeting the criteria into its cheapest legal 1-ring neighbour (which
/// keeps its own position and parameters), compacts, and remaps `scene` (rows = the mesh's
/// vertex rows) in place. The caller applies the returned `old_of_new` to its other per-vertex
/// arrays. `mesh` must be compact.
pub fn prune(
    mesh: &mut ManifoldMesh,
    scene: &mut GaussianScene,
    config: &PruneConfig,
) -> Result<PruneReport, TopologyError> {
    check_rows(mesh, scene)?;
    let extent = crate::mesh::bounding_diagonal(&mesh.positions) as f32;
    let mean_edge = mean_edge_length(mesh);
    let colors = dc_colors(scene);
    let mut report = PruneReport::default();
    for i in 0..scene.len() as u32 {
        if !should_prune(scene, i as usize, config, extent) {
            continue;
        }
        report.candidates += 1;
        if !mesh.is_vertex_live(i) {
            continue;
        }
        let cost = |j: u32| {
            let dp = (mesh.point(i) - mesh.point(j)).length() as f32;
            let dc = (0..3)
                .map(|k| (colors[i as usize][k] - colors[j as usize][k]).powi(2))
                .sum::<f32>()
                .sqrt();
            config.w_g * dp / mean_edge + config.w_a * dc
        };
        let mut ring: Vec<(f32, u32)> = mesh.ring(i).into_iter().map(|j| (cost(j), j)).collect();
        ring.sort_by(|a, b| a.0.total_cmp(&b.0));
        let merged = ring.iter().any(|&(_, j)| {
            let h = mesh.find_edge(i, j).unwrap_or(NONE);
            h != NONE && mesh.merge(h, i, mesh.positions[j as usize]).is_ok()
        });
        if merged {
            report.pruned += 1;
        } else {
            report.kept_no_legal_edge += 1;
        }
    }
    report.old_of_new = mesh.compact();
    *scene = remap_scene(scene, &report.old_of_new, &[]);
    Ok(report)
}

/// Mean length of the live edges (1 for a mesh without edges, so costs stay finite).
pub fn mean_edge_length(mesh: &ManifoldMesh) -> f32 {
    let (sum, count) = mesh.edges().fold((0.0f64, 0usize), |(s, c), h| {
        (s + (mesh.point(mesh.origin(h)) - mesh.point(mesh.dest(h))).length(), c + 1)
    });
    if count > 0 && sum > 0.0 {
        (sum / count as f64) as f32
    } else {
        1.0
    }
}
