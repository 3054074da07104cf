//! The fit configuration: a TOML file whose every key has a documented default
//! (`tagsplat fit --print-config` prints them). Unknown keys and out-of-range values are errors
//! naming the key.

use crate::dataset::CaptureStep;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The `tagsplat fit` configuration (one static frame); every key has a default.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FitConfig {
    /// Optimisation steps (one view each).
    pub iterations: u32,
    /// SH degree stored per Gaussian; the active degree rises by one every `sh_increase_every`.
    pub sh_degree: u32,
    /// Iterations between rises of the active SH degree (default 1000).
    pub sh_increase_every: u32,
    /// Colour behind the Gaussians; targets are composited over it with their masks.
    pub background: [f32; 3],
    /// Seeds view order, initial points and splits.
    pub seed: u64,
    /// Whether the training views' masks are refined along their outline from the images
    /// against each camera's background plate, as `train` does (`dataset::matte`).
    pub refine_masks: CaptureStep,
    /// Image loss weights.
    pub loss: LossWeights,
    /// Adam learning rates.
    pub learning_rates: LearningRateConfig,
    /// The 3DGS densification schedule and thresholds.
    pub densify: DensifyConfig,
    /// Random initialisation, when no initial Gaussians are given.
    pub init: InitConfig,
    /// How often the loss is read back and the held-out views evaluated.
    pub report: ReportConfig,
}

/// λ of one render's image loss (0.8 L1 + 0.2 (1 − SSIM) each): `fit`'s Gaussian render, and
/// each of `train`'s two renders (`loss.gaussians`, `loss.mesh`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LossWeights {
    /// Rendered colour against the image.
    pub color: f32,
    /// Rendered alpha against the mask (the paper's Gaussian mask weight).
    pub mask: f32,
}

/// Adam learning rates (the 3DGS values); positions are scaled by the scene extent and decay
/// exponentially from `positions` to `positions_final` over the run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LearningRateConfig {
    /// Position rate at the first iteration, × the scene extent (default 1.6e-4).
    pub positions: f32,
    /// Position rate at the last iteration, × the scene extent (default 1.6e-6).
    pub positions_final: f32,
    /// Rate of the log-scales (default 5e-3).
    pub log_scales: f32,
    /// Rate of the rotation quaternions (default 1e-3).
    pub rotations: f32,
    /// Rate of the opacity logits (default 0.05).
    pub opacity_logits: f32,
    /// Rate of the SH DC (base colour) coefficients (default 2.5e-3).
    pub sh_dc: f32,
    /// Rate of the higher SH coefficients (default 2.5e-3 / 20).
    pub sh_rest: f32,
}

/// The topology-free 3DGS densification: clone small Gaussians and split large ones whose
/// mean view-space gradient passes the threshold, prune transparent or huge ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DensifyConfig {
    /// Whether densification runs at all (default true).
    pub enabled: bool,
    /// Densification runs at iterations after this one (default 500).
    pub from: u32,
    /// Last iteration densification may run at (default 1500); it also stops `every` iterations
    /// before the run ends.
    pub until: u32,
    /// Iterations between densification steps (default 100).
    pub every: u32,
    /// Mean 2D mean-gradient norm in NDC units (3DGS: 2e-4).
    pub grad_threshold: f32,
    /// Largest scale (× extent) below which a Gaussian is cloned rather than split.
    pub percent_dense: f32,
    /// Gaussians with an opacity below this are pruned (default 0.005).
    pub prune_opacity: f32,
    /// Largest scale (× extent) beyond which a Gaussian is pruned.
    pub prune_scale: f32,
    /// Most Gaussians densification may reach.
    pub budget: u32,
}

/// Random initialisation (without `--init`): points inside every mask.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct InitConfig {
    /// Points placed inside the masks (default 5000).
    pub points: u32,
}

/// When the fit reads back its loss and evaluates.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ReportConfig {
    /// Held-out evaluation (one point of the speed-against-error curve) this often.
    pub eval_every: u32,
    /// The loss is read back (and checked for NaN) this often.
    pub stats_every: u32,
}

impl Default for FitConfig {
    fn default() -> Self {
        Self {
            iterations: 3000,
            sh_degree: 3,
            sh_increase_every: 1000,
            background: [0.0; 3],
            seed: 0,
            refine_masks: CaptureStep::Auto,
            loss: LossWeights::default(),
            learning_rates: LearningRateConfig::default(),
            densify: DensifyConfig::default(),
            init: InitConfig::default(),
            report: ReportConfig::default(),
        }
    }
}

impl Default for LossWeights {
    fn default() -> Self {
        Self { color: 1.0, mask: 3.0 }
    }
}

impl LossWeights {
    /// λ per rgba channel of the render ([`channel_weights`](super::schedule::channel_weights)).
    #[inline]
    pub fn channels(&self) -> [f32; 4] {
        super::schedule::channel_weights(self.color, self.mask)
    }
}

impl Default for LearningRateConfig {
    fn default() -> Self {
        Self {
            positions: 1.6e-4,
            positions_final: 1.6e-6,
            log_scales: 5e-3,
            rotations: 1e-3,
            opacity_logits: 0.05,
            sh_dc: 2.5e-3,
            sh_rest: 2.5e-3 / 20.0,
        }
    }
}

impl Default for DensifyConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            from: 500,
            until: 1500,
            every: 100,
            grad_threshold: 2e-4,
            percent_dense: 0.01,
            prune_opacity: 0.005,
            prune_scale: 0.1,
            budget: 200_000,
        }
    }
}

impl Default for InitConfig {
    fn default() -> Self {
        Self { points: 5000 }
    }
}

impl Default for ReportConfig {
    fn default() -> Self {
        Self { eval_every: 250, stats_every: 50 }
    }
}

/// Why a configuration could not be loaded or is invalid.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read.
    #[error("cannot read config {path}: {error}")]
    Read {
        /// The config file.
        path: PathBuf,
        /// The I/O error.
        error: std::io::Error,
    },
    /// The file is not valid TOML, has an unknown key, or a value of the wrong type.
    #[error("config {path}: {error}")]
    Parse {
        /// The config file.
        path: PathBuf,
        /// The parser's error.
        error: Box<toml::de::Error>,
    },
    /// JSON text (a front's dictionary) that is not a config: an unknown key, a value of the
    /// wrong type.
    #[error("config {path}: {error}")]
    Json {
        /// What the text came as.
        path: PathBuf,
        /// The parser's error.
        error: serde_json::Error,
    },
    /// A value is out of its range, or inconsistent with another key's.
    #[error("config{}: `{key}` {problem}", .path.as_ref().map(|p| format!(" {}", p.display())).unwrap_or_default())]
    Value {
        /// The config file (None for a config not read from a file).
        path: Option<PathBuf>,
        /// The key, dotted (`densify.every`).
        key: &'static str,
        /// What is wrong with the value.
        problem: String,
    },
}

impl FitConfig {
    /// Reads and checks a TOML config; missing keys take their defaults.
    pub fn load(path: &Path) -> Result<Self, ConfigError> {
        load_toml(path, Self::check)
    }

    /// Parses and checks a config given as text, TOML or JSON; `origin` names it in errors.
    pub fn parse(text: &str, origin: &Path, language: ConfigText) -> Result<Self, ConfigError> {
        parse_config(text, origin, language, Self::check)
    }

    /// The defaults as TOML, for `--print-config`.
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_else(|e| format!("# cannot print the config: {e}"))
    }

    /// Every value in its range; the first that is not, by key.
    pub fn check(&self) -> Result<(), ConfigError> {
        let positive = [
            ("iterations", self.iterations as f32),
            ("sh_increase_every", self.sh_increase_every as f32),
            ("learning_rates.positions", self.learning_rates.positions),
            ("learning_rates.positions_final", self.learning_rates.positions_final),
            ("densify.every", self.densify.every as f32),
            ("densify.grad_threshold", self.densify.grad_threshold),
            ("densify.percent_dense", self.densify.percent_dense),
            ("densify.prune_scale", self.densify.prune_scale),
            ("densify.budget", self.densify.budget as f32),
            ("init.points", self.init.points as f32),
            ("report.eval_every", self.report.eval_every as f32),
            ("report.stats_every", self.report.stats_every as f32),
        ];
        let non_negative = [
            ("loss.color", self.loss.color),
            ("loss.mask", self.loss.mask),
            ("learning_rates.log_scales", self.learning_rates.log_scales),
            ("learning_rates.rotations", self.learning_rates.rotations),
            ("learning_rates.opacity_logits", self.learning_rates.opacity_logits),
            ("learning_rates.sh_dc", self.learning_rates.sh_dc),
            ("learning_rates.sh_rest", self.learning_rates.sh_rest),
            ("densify.prune_opacity", self.densify.prune_opacity),
        ];
        check_ranges(&positive, &non_negative)?;
        check_appearance(self.sh_degree, self.background)?;
        if self.densify.prune_opacity.is_nan() || self.densify.prune_opacity >= 1.0 {
            return value_error(
                "densify.prune_opacity",
                format!("must be below 1 (got {})", self.densify.prune_opacity),
            );
        }
        if self.densify.from > self.densify.until {
            return value_error(
                "densify.from",
                format!(
                    "({}) must not be after densify.until ({})",
                    self.densify.from, self.densify.until
                ),
            );
        }
        Ok(())
    }
}

/// An out-of-range value of `key` (the file is added by [`load_toml`]).
pub(crate) fn value_error<T>(key: &'static str, problem: String) -> Result<T, ConfigError> {
    Err(ConfigError::Value { path: None, key, problem })
}

/// The first key of `positive` whose value is not positive and finite, or of `non_negative`
/// not zero or positive and finite, as an error naming it.
pub(crate) fn check_ranges(
    positive: &[(&'static str, f32)],
    non_negative: &[(&'static str, f32)],
) -> Result<(), ConfigError> {
    // Phrased as positive so NaN fails too.
    if let Some(&(key, v)) = positive.iter().find(|(_, v)| !(*v > 0.0 && v.is_finite())) {
        return value_error(key, format!("must be positive and finite (got {v})"));
    }
    if let Some(&(key, v)) = non_negative.iter().find(|(_, v)| !(*v >= 0.0 && v.is_finite())) {
        return value_error(key, format!("must be zero or positive and finite (got {v})"));
    }
    Ok(())
}

/// `sh_degree` at most the renderer's, `background` three values in [0, 1].
pub(crate) fn check_appearance(sh_degree: u32, background: [f32; 3]) -> Result<(), ConfigError> {
    if sh_degree > crate::splat::MAX_SH_DEGREE {
        return value_error(
            "sh_degree",
            format!("must be at most {} (got {sh_degree})", crate::splat::MAX_SH_DEGREE),
        );
    }
    if !background.iter().all(|c| (0.0..=1.0).contains(c)) {
        return value_error(
            "background",
            format!("must be three values in [0, 1] (got {background:?})"),
        );
    }
    Ok(())
}

/// Reads a TOML config of type `T` and runs `check`, naming the file in every error.
pub(crate) fn load_toml<T: serde::de::DeserializeOwned>(
    path: &Path,
    check: impl FnOnce(&T) -> Result<(), ConfigError>,
) -> Result<T, ConfigError> {
    let text = std::fs::read_to_string(path)
        .map_err(|error| ConfigError::Read { path: path.to_owned(), error })?;
    parse_config(&text, path, ConfigText::Toml, check)
}

/// The languages a config's text may be in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ConfigText {
    /// TOML, as config files are.
    Toml,
    /// JSON, as a front's dictionary arrives (`json.dumps`): the same keys and values.
    Json,
}

/// Parses a config's `text` and checks it; `origin` (a file, or a name such as
/// `the config argument`) names it in errors. Missing keys take their defaults; an unknown key
/// is refused.
pub(crate) fn parse_config<T: serde::de::DeserializeOwned>(
    text: &str,
    origin: &Path,
    language: ConfigText,
    check: impl FnOnce(&T) -> Result<(), ConfigError>,
) -> Result<T, ConfigError> {
    let path = origin.to_owned();
    let config: T = match language {
        ConfigText::Toml => toml::from_str(text)
            .map_err(|error| ConfigError::Parse { path, error: Box::new(error) })?,
        ConfigText::Json => {
            serde_json::from_str(text).map_err(|error| ConfigError::Json { path, error })?
        }
    };
    check(&config).map_err(|e| match e {
        ConfigError::Value { key, problem, .. } => {
            ConfigError::Value { path: Some(origin.to_owned()), key, problem }
        }
        other => other,
    })?;
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_round_trip_and_pass() {
        let config = FitConfig::default();
        config.check().unwrap();
        assert_eq!(toml::from_str::<FitConfig>(&config.to_toml()).unwrap(), config);
        let partial: FitConfig =
            toml::from_str("iterations = 10\n[densify]\nenabled = false\n").unwrap();
        assert_eq!(
            (partial.iterations, partial.densify.enabled, partial.densify.every),
            (10, false, 100)
        );
    }

    #[test]
    fn errors_name_the_key() {
        let unknown =
            toml::from_str::<FitConfig>("[densify]\ngrad_treshold = 1\n").unwrap_err().to_string();
        assert!(unknown.contains("grad_treshold"), "{unknown}");
        let config: FitConfig = toml::from_str("[learning_rates]\nrotations = -1\n").unwrap();
        assert!(config.check().unwrap_err().to_string().contains("learning_rates.rotations"));
        let config: FitConfig = toml::from_str("[densify]\ngrad_threshold = nan\n").unwrap();
        assert!(config.check().unwrap_err().to_string().contains("densify.grad_threshold"));
        let config: FitConfig = toml::from_str("sh_degree = 4\n").unwrap();
        assert!(config.check().unwrap_err().to_string().contains("sh_degree"));
    }
}
