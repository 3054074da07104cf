//! What a frame does with the cameras' colour responses (`[camera_colour]`,
//! `loss::colour_map`): frame 0 learns a map per training camera, later frames score their
//! renders through frame 0's maps, found by camera name.

use crate::gpu::GpuContext;
use crate::loss::colour_map::affine::IDENTITY;
use crate::loss::colour_map::ColourMap;
use crate::splat::GaussianScene;
use crate::train::{TrainError, Trainer, ViewTarget};
use std::collections::BTreeMap;
use std::sync::Arc;

/// The maps frame 0 learned, by camera name.
pub type CameraMaps = BTreeMap<String, ColourMap>;

/// How a frame's renders meet the cameras' colour responses.
#[derive(Clone, Copy, Debug)]
pub enum ColourUse<'a> {
    /// As they are.
    Off,
    /// Through a map per training camera learned from the identity (frame 0).
    Learn,
    /// Through these maps (a camera without one: the identity).
    Apply(&'a CameraMaps),
}

/// A trainer for `views` (two renders a step) scoring its renders as `colour` says, over
/// `background`.
pub fn trainer_for(
    ctx: &Arc<GpuContext>,
    scene: &GaussianScene,
    views: &[ViewTarget],
    colour: ColourUse,
    background: [f32; 3],
) -> Result<Trainer, TrainError> {
    let trainer = Trainer::new(ctx, scene, views)?.with_second_render()?;
    match colour {
        ColourUse::Off => Ok(trainer),
        ColourUse::Learn => {
            trainer.with_camera_colour(&vec![IDENTITY; views.len()], background, true)
        }
        ColourUse::Apply(maps) => {
            let maps: Vec<ColourMap> =
                views.iter().map(|v| maps.get(&v.name).copied().unwrap_or(IDENTITY)).collect();
            trainer.with_camera_colour(&maps, background, false)
        }
    }
}

/// The trainer's learned maps by its views' names (empty without camera colour).
pub fn learned_maps(trainer: &Trainer, views: &[ViewTarget]) -> Result<CameraMaps, TrainError> {
    let maps = trainer.camera_colour()?.unwrap_or_default();
    Ok(views.iter().map(|v| v.name.clone()).zip(maps).collect())
}
