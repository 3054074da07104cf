//! What a frame does with the cameras' colour responses (`[camera_colour]`,
//! `loss::colour_map`): frame 0 learns a map per training camera, later frames score their
//! renders through frame 0's maps, found by camera name.

use crate::gpu::GpuContext;
use crate::io::write_json_atomically;
use crate::loss::colour_map::affine::IDENTITY;
use crate::loss::colour_map::ColourMap;
use crate::splat::GaussianScene;
use crate::train::{TrainError, Trainer, ViewTarget};
use std::collections::BTreeMap;
use std::path::Path;
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

/// The trainer's learned maps by its views' names (empty without camera colour). A view
/// whose colours were left out ([`ViewTarget::appearance_flaw`]) taught its map nothing, so it
/// has none: later frames score that camera through the identity.
pub fn learned_maps(trainer: &Trainer, views: &[ViewTarget]) -> Result<CameraMaps, TrainError> {
    let maps = trainer.camera_colour()?.unwrap_or_default();
    let matched = views.iter().zip(maps).filter(|(v, _)| v.appearance_flaw().is_none());
    Ok(matched.map(|(v, map)| (v.name.clone(), map)).collect())
}

/// Writes `maps` to `path` (JSON, atomically).
pub fn write_maps(path: &Path, maps: &CameraMaps) -> Result<(), TrainError> {
    write_json_atomically(path, maps)
        .map_err(|error| TrainError::Io { path: path.to_owned(), error })
}

/// The maps at `path`; none when there is no such file (frame 0 learned none).
pub fn read_maps(path: &Path) -> Result<CameraMaps, TrainError> {
    let text = match std::fs::read_to_string(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(CameraMaps::new()),
        read => read.map_err(|error| TrainError::Read { path: path.to_owned(), error })?,
    };
    let maps: CameraMaps = serde_json::from_str(&text).map_err(|e| TrainError::Invalid {
        path: path.to_owned(),
        problem: format!("not camera colour maps by camera name: {e}"),
    })?;
    match maps.iter().find(|(_, m)| !m.iter().flatten().all(|v| v.is_finite())) {
        Some((name, _)) => Err(TrainError::Invalid {
            path: path.to_owned(),
            problem: format!("camera {name}'s map is not finite"),
        }),
        None => Ok(maps),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn maps_round_trip_and_a_bad_file_is_named() {
        let dir = std::env::temp_dir().join(format!("tagsplat-maps-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("camera_colour.json");
        assert!(read_maps(&path).unwrap().is_empty(), "no file: no maps");
        let mut maps = CameraMaps::new();
        maps.insert("c03".into(), [[1.1, 0.0, 0.0, 0.0], [0.0, 0.9, 0.0, 0.0], IDENTITY[2]]);
        write_maps(&path, &maps).unwrap();
        assert_eq!(read_maps(&path).unwrap(), maps);
        std::fs::write(&path, "{\"c03\": [[1, 0, 0]]}").unwrap();
        let error = read_maps(&path).unwrap_err().to_string();
        assert!(
            error.contains("camera_colour.json") && error.contains("camera colour maps"),
            "{error}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
