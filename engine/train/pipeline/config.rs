//! The reconstruction pipeline's configuration: one TOML file, every key optional with a
//! documented default (`tagsplat train --print-config`), errors naming the file and key.

pub use crate::dataset::CaptureStep;
use crate::train::config::{
    check_appearance, check_ranges, load_toml, parse_config, value_error, ConfigError, ConfigText,
    LearningRateConfig, LossWeights,
};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `tagsplat train` configuration (the whole pipeline); every key has a default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainConfig {
    /// SH degree per Gaussian (its colour's view dependence); the active degree rises by one
    /// every `sh_increase_every` canonical iterations.
    pub sh_degree: u32,
    /// Canonical iterations between rises of the active SH degree (default 500).
    pub sh_increase_every: u32,
    /// Colour behind the subject; targets are composited over it with their masks.
    pub background: [f32; 3],
    /// Seeds each frame's view order (mixed with the frame index) and the graph stage.
    pub seed: u64,
    /// Frame 0's optimisation.
    pub canonical: CanonicalConfig,
    /// Every later frame's optimisation.
    pub temporal: TemporalConfig,
    /// Loss and regularizer weights.
    pub loss: PipelineWeights,
    /// The 3DGS learning rates (positions × scene extent, decaying over each frame's iterations).
    pub learning_rates: LearningRateConfig,
    /// Multiplies the position learning rates: each frame here runs 200–1000 iterations, not
    /// 3DGS's 30 000, so positions need longer steps (measured on the demo sequence: ×10 cut the
    /// tracking RMSE from 0.090 to 0.059 and raised the last frame's PSNR from 23 to 30 dB;
    /// ×25 gained nothing more).
    pub position_lr_scale: f32,
    /// Whether the training views' masks are refined along their outline from the images
    /// against each camera's background plate (`dataset::matte`): `auto` (the default) where
    /// the images carry a background, `always`, or `never`.
    pub refine_masks: CaptureStep,
    /// Each training camera's own exposure and white balance, learned on frame 0.
    pub camera_colour: CameraColourConfig,
    /// The initial mesh built from the masks when none is given.
    pub init: InitMeshConfig,
    /// How often losses are read back.
    pub report: PipelineReportConfig,
}

/// Each training camera's colour response (`loss::colour_map`): frame 0's renders are scored
/// as each camera sees them, through a gain and offset per channel refitted from the renders
/// at the end of every statistics interval; later frames keep frame 0's maps.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CameraColourConfig {
    /// `auto` (the default) where the images carry a background (a studio's cameras; renders
    /// over black share one virtual camera), `always`, or `never`.
    pub learn: CaptureStep,
    /// Frame 0's first iteration whose interval refits the maps (before it, the colours are
    /// still far from any camera's, and a fit would explain the mismatch as a camera's).
    pub from_iteration: u32,
    /// Pull of each fit toward the identity, × the subject's summed coverage (default 0.1: at
    /// 0.01 the gains also absorbed what the model got wrong in a view).
    pub ridge: f32,
}

/// Frame 0: the Gaussians on the initial mesh, topology-preserving densification and pruning.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct CanonicalConfig {
    /// Frame 0's iterations, all run (default 1000).
    pub iterations: u32,
    /// Densification runs only after this iteration (default 200).
    pub densify_from: u32,
    /// Densification runs at no iteration after this one (default 700), nor in the last
    /// `densify_every` iterations.
    pub densify_until: u32,
    /// Iterations between densify-and-prune steps (default 100).
    pub densify_every: u32,
    /// A face splits when the mean view-space gradient of its corners (NDC units, as 3DGS's
    /// 2e-4) passes this.
    pub densify_threshold: f32,
    /// Most Gaussians densification may reach; 0: the covered pixels of the median training
    /// view (one Gaussian per pixel the subject covers: model only what the images resolve).
    pub budget: u32,
    /// A Gaussian whose opacity is below this is merged away (default 0.005).
    pub prune_opacity: f32,
    /// Largest scale, as a fraction of the mesh's bounding-box diagonal, beyond which a
    /// Gaussian is merged away.
    pub prune_scale: f32,
}

/// Frames 1..T: topology frozen, frame t − 1 extrapolated at constant velocity, then the
/// deformation graph solved coarse to fine, then the per-vertex refinement. Every stage stops
/// when its loss stops improving (see `tolerance`) or at its iteration cap.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TemporalConfig {
    /// Most per-vertex refinement iterations per frame.
    pub iterations: u32,
    /// Fewest per-vertex refinement iterations per frame.
    pub min_iterations: u32,
    /// A stage stops when its mean loss over one pass through the training views improved on
    /// the pass before by less than this fraction (0: run while it falls at all).
    pub tolerance: f32,
    /// Keep colour, opacity and scale of frame 0 (only positions and rotations move).
    pub freeze_appearance: bool,
    /// Iterations that fit the frame's colours (SH) alone once its shape is found, everything
    /// else held, so each frame's mesh and Gaussians carry the shading of that frame; the next
    /// frame starts from them (0: frame 0's colours throughout, with `freeze_appearance`).
    pub colour_iterations: u32,
    /// The colour fit's SH rates, × `learning_rates.sh_dc` and `sh_rest` (a few dozen steps
    /// must reach a change of light: 3DGS's rates move a colour by about 0.001 per step).
    pub colour_lr_scale: f32,
    /// Weight of the long-range silhouette term (every vertex inside every mask; 0: off).
    pub silhouette: f32,
    /// Weight of the coverage term (mask pixels the render leaves uncovered pull the nearest
    /// vertex within `coverage_radius`; 0: off).
    pub coverage: f32,
    /// How far the coverage term searches for a vertex, pixels at the level's resolution
    /// (default 24).
    pub coverage_radius: u32,
    /// Weight of the optical-flow term: each vertex a training view saw at frame t − 1 pulled
    /// to where Lucas–Kanade follows its pixel into that view's image at t (0: off).
    pub flow: f32,
    /// Weight of the anchor term: each vertex a training view saw at frame 0 pulled to where
    /// that view's image track of its frame-0 pixel is at t (Lucas–Kanade frame to frame, held
    /// to the frame-0 image, revived near the starting pose when lost), so a slide along the
    /// surface does not add up (0: off).
    pub anchor: f32,
    /// The pose the temporal regularizers (edge length, rigidity, rotation) compare against.
    pub regularizer_reference: ReferencePose,
    /// Thickness, × the subject's thickest parts (the 95th percentile of vertex thickness), up
    /// to which the temporal edge-length and rigidity terms keep their full weight; a thicker
    /// part gets l / t of it (`regularize::stiffness`), so a torso may stretch with its legs
    /// while the legs keep their shape (0: the same weight everywhere; default 0.3).
    pub limb_thickness: f32,
    /// The deformation graph stage.
    pub graph: GraphConfig,
}

/// The coarse deformation model solved first in every later frame (`crate::deform`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GraphConfig {
    /// Graph nodes (0: no graph stage).
    pub nodes: u32,
    /// Nodes of every level but the last (0: the same graph as the last). A coarser graph
    /// first carries motion into regions the images cannot see move (a leg's root, where it
    /// overlaps the body and has its colour) as a smooth blend of its few nodes, as a skeleton's bones would; the last level then
    /// starts a graph of `nodes` on the pose it reached.
    pub coarse_nodes: u32,
    /// Image downsampling factor of each level, coarse first (1: full resolution).
    pub levels: Vec<u32>,
    /// Most iterations per level (default 120; 150 tracked fox_walk 0.04 points better for
    /// 7.7 s more a frame, docs/log/2026-11-27-time-per-later-frame.md).
    pub iterations: u32,
    /// Fewest iterations per level (default 30).
    pub min_iterations: u32,
    /// Adam step of node translations, × the mesh's bounding-box diagonal (default 2e-3);
    /// decays tenfold over a level's cap.
    pub translation_lr: f32,
    /// Adam step of node rotations, quaternion units (default 5e-3); decays as `translation_lr`.
    pub rotation_lr: f32,
    /// Weight of the as-rigid-as-possible term (mean squared residual in node spacings).
    pub arap: f32,
    /// The pose the graph deforms and its rigidity term holds to: `previous` (the extrapolated
    /// previous frame, nodes at identity) or `frame0` (frame 0's surface, each node started at
    /// the best rigid fit of its vertices to the extrapolated previous frame).
    pub rest: ReferencePose,
}

impl GraphConfig {
    /// The node count of level `level` (an index into `levels`).
    #[inline]
    pub fn nodes_at(&self, level: usize) -> u32 {
        if self.coarse_nodes > 0 && level + 1 < self.levels.len() {
            self.coarse_nodes
        } else {
            self.nodes
        }
    }
}

/// The pose a later frame's graph or temporal regularizers compare against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferencePose {
    /// Frame t − 1.
    Previous,
    /// Frame 0: shape errors of earlier frames do not carry over.
    Frame0,
}

impl ReferencePose {
    /// `previous` or `frame0`, whichever this names.
    #[inline]
    pub fn pick<T>(self, previous: T, frame0: T) -> T {
        match self {
            ReferencePose::Previous => previous,
            ReferencePose::Frame0 => frame0,
        }
    }
}

/// Loss weights and the temporal falloff λ_w (per mean edge length). The regularizers' defaults
/// (`regularize::Weights`), but the temporal terms at a tenth of them (edge length 0.4, rigidity 0.4, rotation 2): measured on
/// the demo sequence, the table's 4/4/20 held the surface back (tracking RMSE 0.059 scene units),
/// none at all let it drift (0.050), a tenth did best (0.043); see
/// docs/log/2026-11-22-pipeline-defaults-and-demo.md.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineWeights {
    /// The Gaussian render's colour against the image and alpha against the mask (default 1
    /// and 3), the same weights `fit` has.
    pub gaussians: LossWeights,
    /// The mesh render's (default 1 and 3).
    pub mesh: LossWeights,
    /// Flatness term (default 1).
    pub scale_2d: f32,
    /// Laplacian smoothness term, its offsets measured in the subject's bounding-box diagonals
    /// (default 200: the 5 per scene unit² that the demo's 6.6-unit subject had before).
    pub laplacian: f32,
    /// Normal-consistency term (default 1).
    pub normal: f32,
    /// Temporal edge-length term (default 0.4).
    pub edge_length: f32,
    /// Temporal local-rigidity term (default 0.4).
    pub rigidity: f32,
    /// Temporal rotation-similarity term (default 2).
    pub rotation: f32,
    /// Falloff λ_w of the temporal neighbour weights, per mean edge length (default 1).
    pub lambda_w: f32,
    /// Huber δ of the temporal edge-length and rigidity residuals, in mean edge lengths
    /// (default 0.25; 0: the paper's absolute values). Below δ the penalty is quadratic, so a
    /// stretch the images leave open spreads evenly along the skin instead of anywhere.
    pub huber: f32,
}

/// The initial mesh when none is given (built from the masks).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InitMeshConfig {
    /// Target vertex count; 0: an edge length of `edge_pixels` pixels of the typical view.
    pub vertices: u32,
    /// Target edge length, pixels of the typical view, when `vertices` is 0 (default 3).
    pub edge_pixels: f64,
    /// The most pixels the subject's diagonal counts when `edge_pixels` is converted (default
    /// 400): a capture finer than that gets no denser first mesh.
    pub max_subject_pixels: f64,
}

/// How often the pipeline reads its losses back.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PipelineReportConfig {
    /// Losses are read back (and checked for NaN) this often.
    pub stats_every: u32,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            sh_degree: 1,
            sh_increase_every: 500,
            background: [0.0; 3],
            seed: 0,
            canonical: CanonicalConfig::default(),
            temporal: TemporalConfig::default(),
            loss: PipelineWeights::default(),
            learning_rates: LearningRateConfig::default(),
            position_lr_scale: 10.0,
            refine_masks: CaptureStep::Auto,
            camera_colour: CameraColourConfig::default(),
            init: InitMeshConfig::default(),
            report: PipelineReportConfig::default(),
        }
    }
}

impl Default for CameraColourConfig {
    fn default() -> Self {
        Self { learn: CaptureStep::Auto, from_iteration: 200, ridge: 0.1 }
    }
}

impl Default for CanonicalConfig {
    fn default() -> Self {
        Self {
            iterations: 1000,
            densify_from: 200,
            densify_until: 700,
            densify_every: 100,
            densify_threshold: 2e-4,
            budget: 0,
            prune_opacity: 0.005,
            prune_scale: 0.1,
        }
    }
}

impl Default for TemporalConfig {
    fn default() -> Self {
        Self {
            iterations: 300,
            min_iterations: 60,
            tolerance: 0.02,
            freeze_appearance: true,
            colour_iterations: 16,
            colour_lr_scale: 20.0,
            silhouette: 10.0,
            coverage: 0.01,
            coverage_radius: 24,
            flow: 0.0,
            anchor: 0.0,
            regularizer_reference: ReferencePose::Previous,
            limb_thickness: 0.3,
            graph: GraphConfig::default(),
        }
    }
}

impl Default for GraphConfig {
    fn default() -> Self {
        Self {
            nodes: 200,
            coarse_nodes: 24,
            levels: vec![2, 1],
            iterations: 120,
            min_iterations: 30,
            translation_lr: 2e-3,
            rotation_lr: 5e-3,
            arap: 0.25,
            rest: ReferencePose::Previous,
        }
    }
}

impl Default for PipelineWeights {
    fn default() -> Self {
        Self {
            gaussians: LossWeights { color: 1.0, mask: 3.0 },
            mesh: LossWeights { color: 1.0, mask: 3.0 },
            scale_2d: 1.0,
            laplacian: 200.0,
            normal: 1.0,
            edge_length: 0.4,
            rigidity: 0.4,
            rotation: 2.0,
            lambda_w: 1.0,
            huber: 0.25,
        }
    }
}

impl Default for InitMeshConfig {
    fn default() -> Self {
        Self { vertices: 0, edge_pixels: 3.0, max_subject_pixels: 400.0 }
    }
}

impl Default for PipelineReportConfig {
    fn default() -> Self {
        Self { stats_every: 50 }
    }
}

impl PipelineWeights {
    /// The regularizer weights in the kernels' form for `gaussians` Gaussians on a subject whose
    /// bounding-box diagonal is `diagonal` scene units. The paper writes L_2d, normal
    /// consistency, edge length, rigidity and rotation as sums, but its weights come from code
    /// that averages them (Luiten et al.): applied as sums they grow with the Gaussian count
    /// and, against image losses that are means over pixels, freeze the surface (measured: a
    /// temporal frame moved 0.0006 instead of 0.03 scene units). So every sum is divided by the
    /// count; the Laplacian is a mean already. Its offsets δ are squared lengths, so in scene
    /// units the same weight smoothed a 175-unit fox 700 times harder than the 6.6-unit demo
    /// subject; measured in diagonals it means the same in any units.
    pub fn regularizers(&self, gaussians: usize, diagonal: f32) -> crate::regularize::Weights {
        let per = 1.0 / gaussians.max(1) as f32;
        // Phrased as positive so that a NaN or empty subject keeps the weight as given.
        let per_area = if diagonal > 0.0 && diagonal.is_finite() { diagonal.powi(-2) } else { 1.0 };
        crate::regularize::Weights {
            scale_2d: self.scale_2d * per,
            laplacian: self.laplacian * per_area,
            normal: self.normal * per,
            edge_length: self.edge_length * per,
            rigidity: self.rigidity * per,
            rotation: self.rotation * per,
            lambda_w: self.lambda_w,
            huber: self.huber,
        }
    }
}

impl TrainConfig {
    /// Reads and checks a TOML config; missing keys take their defaults. Errors name the file and
    /// the key.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        load_toml(path, Self::check)
    }

    /// Parses and checks a config given as text: TOML as in a file, or JSON (a front's
    /// dictionary); `origin` names it in errors.
    pub fn parse(text: &str, origin: &Path, language: ConfigText) -> Result<Self, ConfigError> {
        parse_config(text, origin, language, Self::check)
    }

    /// The defaults as TOML, for `--print-config`.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the config: {e}"))
    }

    /// Every value in its range; the first that is not, by key.
    pub fn check(&self) -> Result<(), ConfigError> {
        let (c, l, r) = (&self.canonical, &self.loss, &self.learning_rates);
        let positive = [
            ("sh_increase_every", self.sh_increase_every as f32),
            ("canonical.densify_every", c.densify_every as f32),
            ("canonical.densify_threshold", c.densify_threshold),
            ("canonical.prune_scale", c.prune_scale),
            ("learning_rates.positions", r.positions),
            ("learning_rates.positions_final", r.positions_final),
            ("init.edge_pixels", self.init.edge_pixels as f32),
            ("init.max_subject_pixels", self.init.max_subject_pixels as f32),
            ("position_lr_scale", self.position_lr_scale),
            ("report.stats_every", self.report.stats_every as f32),
            ("temporal.graph.translation_lr", self.temporal.graph.translation_lr),
            ("temporal.graph.rotation_lr", self.temporal.graph.rotation_lr),
        ];
        let non_negative = [
            ("canonical.prune_opacity", c.prune_opacity),
            ("loss.gaussians.color", l.gaussians.color),
            ("loss.gaussians.mask", l.gaussians.mask),
            ("loss.mesh.color", l.mesh.color),
            ("loss.mesh.mask", l.mesh.mask),
            ("loss.scale_2d", l.scale_2d),
            ("loss.laplacian", l.laplacian),
            ("loss.normal", l.normal),
            ("loss.edge_length", l.edge_length),
            ("loss.rigidity", l.rigidity),
            ("loss.rotation", l.rotation),
            ("loss.lambda_w", l.lambda_w),
            ("loss.huber", l.huber),
            ("camera_colour.ridge", self.camera_colour.ridge),
            ("temporal.tolerance", self.temporal.tolerance),
            ("temporal.silhouette", self.temporal.silhouette),
            ("temporal.coverage", self.temporal.coverage),
            ("temporal.flow", self.temporal.flow),
            ("temporal.anchor", self.temporal.anchor),
            ("temporal.limb_thickness", self.temporal.limb_thickness),
            ("temporal.colour_lr_scale", self.temporal.colour_lr_scale),
            ("temporal.graph.arap", self.temporal.graph.arap),
            ("learning_rates.log_scales", r.log_scales),
            ("learning_rates.rotations", r.rotations),
            ("learning_rates.opacity_logits", r.opacity_logits),
            ("learning_rates.sh_dc", r.sh_dc),
            ("learning_rates.sh_rest", r.sh_rest),
        ];
        check_ranges(&positive, &non_negative)?;
        check_appearance(self.sh_degree, self.background)?;
        if c.prune_opacity.is_nan() || c.prune_opacity >= 1.0 {
            return value_error(
                "canonical.prune_opacity",
                format!("must be below 1 (got {})", c.prune_opacity),
            );
        }
        let (t, g) = (&self.temporal, &self.temporal.graph);
        if t.min_iterations > t.iterations || g.min_iterations > g.iterations {
            return value_error(
                "temporal.min_iterations",
                format!(
                    "({} / graph {}) must not exceed temporal.iterations ({} / graph {})",
                    t.min_iterations, g.min_iterations, t.iterations, g.iterations
                ),
            );
        }
        if g.nodes > 0 && (g.levels.is_empty() || g.levels.iter().any(|&f| f == 0 || f > 16)) {
            return value_error(
                "temporal.graph.levels",
                format!(
                    "must be downsampling factors from 1 to 16, at least one (got {:?})",
                    g.levels
                ),
            );
        }
        if c.densify_from > c.densify_until {
            return value_error(
                "canonical.densify_from",
                format!(
                    "({}) must not be after canonical.densify_until ({})",
                    c.densify_from, c.densify_until
                ),
            );
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_and_errors_name_keys() {
        let config = TrainConfig::default();
        config.check().unwrap();
        assert_eq!(toml::from_str::<TrainConfig>(&config.to_toml()).unwrap(), config);
        let unknown =
            toml::from_str::<TrainConfig>("[temporal]\niters = 3\n").unwrap_err().to_string();
        assert!(unknown.contains("iters"), "{unknown}");
        let config: TrainConfig = toml::from_str("[loss]\nrigidity = -4\n").unwrap();
        assert!(config.check().unwrap_err().to_string().contains("loss.rigidity"));
    }

    #[test]
    fn coarse_nodes_serve_every_level_but_the_last() {
        let graph = GraphConfig {
            nodes: 200,
            coarse_nodes: 24,
            levels: vec![4, 2, 1],
            ..Default::default()
        };
        assert_eq!((0..3).map(|l| graph.nodes_at(l)).collect::<Vec<_>>(), [24, 24, 200]);
        let single = GraphConfig { levels: vec![1], ..graph.clone() };
        assert_eq!(single.nodes_at(0), 200);
        let off = GraphConfig { coarse_nodes: 0, ..graph };
        assert_eq!((0..3).map(|l| off.nodes_at(l)).collect::<Vec<_>>(), [200, 200, 200]);
    }

    #[test]
    fn laplacian_is_per_diagonal_squared_and_the_rest_per_gaussian() {
        let weights = PipelineWeights::default();
        let fox = weights.regularizers(1000, 200.0);
        assert_eq!(fox.laplacian, weights.laplacian / 40_000.0);
        assert_eq!(fox.edge_length, weights.edge_length / 1000.0);
        // A diagonal ten times shorter: a hundred times the weight per scene unit², the same
        // per diagonal.
        assert_eq!(weights.regularizers(1000, 20.0).laplacian, weights.laplacian / 400.0);
        for unusable in [0.0, -1.0, f32::NAN, f32::INFINITY] {
            assert_eq!(weights.regularizers(1000, unusable).laplacian, weights.laplacian);
        }
    }
}
