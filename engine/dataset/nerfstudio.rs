//! nerfstudio / D-NeRF `transforms*.json`: per frame a `file_path` and an OpenGL
//! camera-to-world `transform_matrix` (x right, y up, z backward), intrinsics from
//! `fl_x fl_y cx cy w h` or `camera_angle_x` (and `camera_angle_y`), at the top level or per
//! frame, and a per-frame `time`. Views with the same `time` form one frame; a camera is a
//! distinct (intrinsics, pose) pair; the mask is the image's alpha channel.
//!
//! Conversion: cameras through [`Camera::from_opengl_camera_to_world`]; `cx, cy` default to
//! the image centre (w/2, h/2); without `w, h` the size is read from the image header; a
//! `file_path` without an extension gets `.png` (D-NeRF). `transforms_train.json` holds
//! training cameras, `transforms_val.json` and `transforms_test.json` test cameras; a lone
//! `transforms.json` holds out every eighth camera.

use super::{
    every_eighth_held_out, inside_dataset, read_json, Dataset, DatasetError, Format, Frame,
    MaskSource, View,
};
use crate::camera::Camera;
use crate::io::image::image_size;
use glam::DMat4;
use serde_json::Value;
use std::path::{Path, PathBuf};

const FILES: [(&str, bool); 4] = [
    ("transforms.json", false),
    ("transforms_train.json", false),
    ("transforms_val.json", true),
    ("transforms_test.json", true),
];

/// The transforms files present in `dir`, with whether each holds test cameras.
pub fn transform_files(dir: &Path) -> Vec<(PathBuf, bool)> {
    FILES.iter().map(|(n, test)| (dir.join(n), *test)).filter(|(p, _)| p.is_file()).collect()
}

struct Parsed {
    camera: Camera,
    time: f64,
    image: PathBuf,
    test: bool,
}

/// Reads every `transforms*.json` in `dir` (see the module docs); the intrinsics stay as written
/// and [`Dataset::load`](super::Dataset::load) is the entry point that converts them.
pub(crate) fn load(dir: &Path) -> Result<Dataset, DatasetError> {
    let files = transform_files(dir);
    let mut views = Vec::new();
    for (path, test) in &files {
        let json: Value = read_json(path)?;
        let frames = json.get("frames").and_then(Value::as_array).ok_or_else(|| {
            DatasetError::File { path: path.clone(), problem: "has no `frames` list".into() }
        })?;
        for (i, frame) in frames.iter().enumerate() {
            views.push(parse_frame(dir, path, &json, frame, i, *test)?);
        }
    }
    let meta = files.first().map(|(p, _)| p.clone()).unwrap_or_else(|| dir.join("transforms.json"));
    // Distinct cameras in order of first appearance.
    let mut cameras: Vec<(Camera, bool)> = Vec::new();
    let mut frames: Vec<Frame> = Vec::new();
    for v in views {
        let camera = match cameras.iter().position(|(c, _)| *c == v.camera) {
            Some(i) => i,
            None => {
                cameras.push((v.camera, v.test));
                cameras.len() - 1
            }
        };
        let view = View { camera, image: v.image, mask: MaskSource::Alpha };
        match frames.iter_mut().find(|f| f.time == v.time) {
            Some(f) => f.views.push(view),
            None => frames.push(Frame { time: v.time, views: vec![view] }),
        }
    }
    let single_file = files.len() == 1 && !files[0].1 && files[0].0.ends_with("transforms.json");
    let (train, test) = if single_file {
        every_eighth_held_out(cameras.len())
    } else {
        (0..cameras.len()).partition(|&i| !cameras[i].1)
    };
    let names = (0..cameras.len()).map(|i| format!("cam{i:03}")).collect();
    Dataset::assemble(
        dir,
        &meta,
        Format::Nerfstudio,
        names,
        cameras.into_iter().map(|(c, _)| c).collect(),
        frames,
        train,
        test,
    )
}

fn parse_frame(
    dir: &Path,
    path: &Path,
    top: &Value,
    frame: &Value,
    i: usize,
    test: bool,
) -> Result<Parsed, DatasetError> {
    let bad = |problem: String| DatasetError::File {
        path: path.to_owned(),
        problem: format!("frame {i}: {problem}"),
    };
    // A per-frame value overrides the top-level one.
    let number = |key: &str| -> Result<Option<f64>, DatasetError> {
        match frame.get(key).or_else(|| top.get(key)) {
            None | Some(Value::Null) => Ok(None),
            Some(v) => v
                .as_f64()
                .filter(|x| x.is_finite())
                .map(Some)
                .ok_or_else(|| bad(format!("`{key}` is not a finite number"))),
        }
    };
    let file = frame
        .get("file_path")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("has no `file_path`".into()))?;
    let relative = inside_dataset(path, &format!("frame {i}: file_path"), file)?;
    let mut image = path.parent().unwrap_or(dir).join(relative);
    if image.extension().is_none() {
        image.set_extension("png");
    }
    let (w, h) = match (number("w")?, number("h")?) {
        (Some(w), Some(h)) if w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0 => {
            (w as u32, h as u32)
        }
        (Some(w), Some(h)) => {
            return Err(bad(format!("image size {w}×{h} is not a positive integer size")))
        }
        _ if !image.is_file() => {
            return Err(bad(format!(
                "no `w` and `h`, and the image {} is missing",
                image.display()
            )))
        }
        _ => image_size(&image)?,
    };
    let fx = match (number("fl_x")?, number("camera_angle_x")?) {
        (Some(f), _) => f,
        (None, Some(angle)) => 0.5 * w as f64 / (0.5 * angle).tan(),
        (None, None) => return Err(bad("has neither `fl_x` nor `camera_angle_x`".into())),
    };
    let fy = match (number("fl_y")?, number("camera_angle_y")?) {
        (Some(f), _) => f,
        (None, Some(angle)) => 0.5 * h as f64 / (0.5 * angle).tan(),
        (None, None) => fx,
    };
    let cx = number("cx")?.unwrap_or(0.5 * w as f64);
    let cy = number("cy")?.unwrap_or(0.5 * h as f64);
    let matrix = frame
        .get("transform_matrix")
        .and_then(|m| serde_json::from_value::<[[f64; 4]; 4]>(m.clone()).ok())
        .ok_or_else(|| bad("`transform_matrix` is not a 4×4 list of numbers".into()))?;
    let c2w = DMat4::from_cols_array_2d(&matrix).transpose();
    let camera = Camera::from_opengl_camera_to_world(w, h, fx, fy, cx, cy, c2w).map_err(|e| {
        DatasetError::Camera {
            path: path.to_owned(),
            camera: format!("of frame {i} ({file})"),
            problem: e.to_string(),
        }
    })?;
    let time = number("time")?.unwrap_or(0.0);
    Ok(Parsed { camera, time, image, test })
}
