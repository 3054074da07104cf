//! Dynamic 3D Gaussians / CMU Panoptic layout: `train_meta.json` (and `test_meta.json`) with
//! `w`, `h`, `k[t][c]` (3×3 intrinsics), `w2c[t][c]` (4×4 world-to-camera, OpenCV axes),
//! `fn[t][c]` (image path under `ims/`), `cam_id[t][c]`; masks under `seg/` with the same
//! relative name and a `.png` extension.
//!
//! The intrinsics are kept as written: they are OpenCV calibrations (pixel centres at integer
//! coordinates) unless the caller says otherwise, and [`super::Dataset::load_with`] converts
//! them ([`super::PixelCenters`]). Cameras are a static rig: a camera's k and w2c must be the
//! same in every frame.

use super::{inside_dataset, read_json, Dataset, DatasetError, Format, Frame, MaskSource, View};
use crate::camera::Camera;
use glam::DMat4;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Metadata of the training cameras; its presence marks the layout.
pub const TRAIN_META: &str = "train_meta.json";
/// Metadata of the test cameras (optional).
pub const TEST_META: &str = "test_meta.json";

#[derive(Deserialize)]
struct Meta {
    w: u32,
    h: u32,
    k: Vec<Vec<[[f64; 3]; 3]>>,
    w2c: Vec<Vec<[[f64; 4]; 4]>>,
    #[serde(rename = "fn")]
    files: Vec<Vec<String>>,
    cam_id: Vec<Vec<i64>>,
}

/// Per camera id: its camera, whether it is a test camera.
type Rig = BTreeMap<i64, (Camera, bool)>;

/// Frames per second of the Panoptic studio's HD cameras; the layout's files carry no rate.
pub const PANOPTIC_HD_FPS: f64 = 29.97;

/// Reads the layout from `dir`: cameras from both metadata files (sorted by camera id, named by
/// it), one frame per time step with time = frame index. The intrinsics stay as written
/// (integer pixel centres); [`Dataset::load`](super::Dataset::load) is the entry point that
/// converts them.
pub(crate) fn load(dir: &Path) -> Result<Dataset, DatasetError> {
    let mut rig: Rig = BTreeMap::new();
    let mut per_frame: Vec<Vec<(i64, PathBuf)>> = Vec::new();
    let train_path = dir.join(TRAIN_META);
    for (name, test) in [(TRAIN_META, false), (TEST_META, true)] {
        let path = dir.join(name);
        if test && !path.is_file() {
            continue;
        }
        let meta: Meta = read_json(&path)?;
        read_meta(&path, &meta, test, &mut rig, &mut per_frame)?;
    }
    let ids: Vec<i64> = rig.keys().copied().collect();
    let index = |id: i64| ids.iter().position(|&i| i == id).expect("every id is in the rig");
    let frames = per_frame
        .into_iter()
        .enumerate()
        .map(|(t, views)| Frame {
            time: t as f64,
            views: views
                .into_iter()
                .map(|(id, file)| View {
                    camera: index(id),
                    image: dir.join("ims").join(&file),
                    mask: MaskSource::File(dir.join("seg").join(&file).with_extension("png")),
                })
                .collect(),
        })
        .collect();
    let names = ids.iter().map(|id| id.to_string()).collect();
    let (test, train): (Vec<usize>, Vec<usize>) = (0..ids.len()).partition(|&i| rig[&ids[i]].1);
    let cameras = rig.into_values().map(|(c, _)| c).collect();
    let dataset =
        Dataset::assemble(dir, &train_path, Format::Panoptic, names, cameras, frames, train, test)?;
    Ok(Dataset { fps: Some(PANOPTIC_HD_FPS), ..dataset })
}

fn read_meta(
    path: &Path,
    meta: &Meta,
    test: bool,
    rig: &mut Rig,
    per_frame: &mut Vec<Vec<(i64, PathBuf)>>,
) -> Result<(), DatasetError> {
    let bad = |problem: String| DatasetError::File { path: path.to_owned(), problem };
    let t_count = meta.cam_id.len();
    if meta.k.len() != t_count || meta.w2c.len() != t_count || meta.files.len() != t_count {
        return Err(bad(format!(
            "k, w2c, fn and cam_id list {}, {}, {}, {} frames",
            meta.k.len(),
            meta.w2c.len(),
            meta.files.len(),
            t_count
        )));
    }
    if per_frame.is_empty() {
        per_frame.resize(t_count, Vec::new());
    } else if per_frame.len() != t_count {
        return Err(bad(format!("has {t_count} frames but {TRAIN_META} has {}", per_frame.len())));
    }
    for (t, frame) in per_frame.iter_mut().enumerate() {
        let n = meta.cam_id[t].len();
        if meta.k[t].len() != n || meta.w2c[t].len() != n || meta.files[t].len() != n {
            return Err(bad(format!("frame {t}: k, w2c, fn and cam_id differ in length")));
        }
        for c in 0..n {
            let id = meta.cam_id[t][c];
            let camera_error = |problem: String| DatasetError::Camera {
                path: path.to_owned(),
                camera: id.to_string(),
                problem: format!("frame {t}: {problem}"),
            };
            let k = meta.k[t][c];
            if k[0][1] != 0.0 || k[1][0] != 0.0 || k[2] != [0.0, 0.0, 1.0] {
                return Err(camera_error(format!(
                    "intrinsics {k:?} are not a pinhole K (zero skew, last row 0 0 1)"
                )));
            }
            let w2c = DMat4::from_cols_array_2d(&meta.w2c[t][c]).transpose();
            let camera = Camera::new(meta.w, meta.h, k[0][0], k[1][1], k[0][2], k[1][2], w2c)
                .map_err(|e| camera_error(e.to_string()))?;
            match rig.get(&id) {
                None => {
                    rig.insert(id, (camera, test));
                }
                Some((first, was_test)) => {
                    if *was_test != test {
                        return Err(camera_error(
                            "appears in both the train and the test split".into(),
                        ));
                    }
                    if !same_camera(first, &camera) {
                        return Err(camera_error(
                            "differs from its first frame (a moving camera is not supported)"
                                .into(),
                        ));
                    }
                }
            }
            let file = inside_dataset(path, &format!("frame {t}: image name"), &meta.files[t][c])?;
            frame.push((id, file));
        }
    }
    Ok(())
}

fn same_camera(a: &Camera, b: &Camera) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0);
    close(a.fx, b.fx)
        && close(a.fy, b.fy)
        && close(a.cx, b.cx)
        && close(a.cy, b.cy)
        && a.world_to_camera
            .to_cols_array()
            .iter()
            .zip(b.world_to_camera.to_cols_array())
            .all(|(&x, y)| close(x, y))
}
