//! Synchronized multi-view video: cameras (pinhole, OpenCV world-to-camera), frames in time
//! order, per frame and view an image and a mask, and a train/test split of the cameras.
//!
//! Loaders convert at load time and nowhere else:
//! - [`own`]: this project's layout (`dataset.json`, written by `tagsplat synth`);
//! - [`panoptic`]: Dynamic 3D Gaussians / CMU Panoptic (`train_meta.json`, `ims/`, `seg/`);
//! - [`nerfstudio`]: nerfstudio / D-NeRF `transforms*.json` (OpenGL camera-to-world).
//!
//! Loading reads only the metadata and checks that every file exists; images are decoded on
//! demand through a bounded cache ([`cache::ImageCache`], 1 GiB by default).

pub mod background;
pub mod cache;
pub mod matte;
pub mod nerfstudio;
pub mod own;
pub mod panoptic;

use crate::camera::Camera;
use crate::io::host::parallel_map;
use crate::io::image::{read_image, Image, ImageError};
use crate::io::resample::resample_area;
use background::{MaskCounts, BACKGROUND_SHARE};
use cache::ImageCache;
use matte::{Plate, MIN_PLATE_FRAMES, PLATE_FRAMES};
use std::path::{Component, Path, PathBuf};
use std::sync::Arc;

/// Default budget of decoded pixel data kept in memory.
pub const DEFAULT_CACHE_BYTES: usize = 1 << 30;

/// Why a dataset could not be loaded, or one of its files read.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A metadata file cannot be read, is not valid JSON, or holds values the layout does not
    /// allow.
    #[error("{}: {problem}", path.display())]
    File {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// A camera is missing or invalid.
    #[error("{}: camera {camera}: {problem}", path.display())]
    Camera {
        /// The file the camera was read from.
        path: PathBuf,
        /// The camera's name in the dataset.
        camera: String,
        /// What is wrong with it.
        problem: String,
    },
    /// An image or mask file named by the metadata does not exist.
    #[error("missing image {}", .0.display())]
    MissingImage(PathBuf),
    /// An image or mask's size differs from its camera's.
    #[error("{}: image is {width}×{height} but camera {camera} is {camera_width}×{camera_height}", path.display())]
    SizeMismatch {
        /// The image or mask file.
        path: PathBuf,
        /// The camera's name in the dataset.
        camera: String,
        /// Width of the image, in pixels.
        width: u32,
        /// Height of the image, in pixels.
        height: u32,
        /// Width of the camera, in pixels.
        camera_width: u32,
        /// Height of the camera, in pixels.
        camera_height: u32,
    },
    /// An image or mask file does not decode.
    #[error(transparent)]
    Image(#[from] ImageError),
    /// The layout takes masks from the alpha channel, and this image has none.
    #[error("{}: has no alpha channel to use as the mask", .0.display())]
    NoMask(PathBuf),
    /// Images composited over black show subject outside this view's mask: the mask cuts off
    /// `percent` of what the image shows (lit pixels outside the mask over the mask's area).
    #[error("frame {frame}, camera {camera}: {} leaves out {percent:.0} % of the subject its image shows", mask.display())]
    MaskCutsSubject {
        /// Index of the frame, in time order.
        frame: usize,
        /// The camera's name.
        camera: String,
        /// The mask file (the image's when masks come from its alpha).
        mask: PathBuf,
        /// Lit pixels outside the mask, percent of the mask's area.
        percent: f64,
    },
    /// Every view's mask of a frame is empty (no pixel above 0.5).
    #[error("frame {frame}: the mask is empty in every view")]
    EmptyMasks {
        /// Index of the frame, in time order.
        frame: usize,
    },
    /// A frame's cameras differ from the first frame's (in a dataset that is not monocular).
    #[error("{}: frame {frame} has cameras [{found}] but frame {first} has [{expected}]", path.display())]
    CameraSets {
        /// The metadata file.
        path: PathBuf,
        /// Index of the frame that differs, in time order.
        frame: usize,
        /// Index of the frame it is compared with (the first).
        first: usize,
        /// Names of the cameras in `frame`, comma-separated.
        found: String,
        /// Names of the cameras in `first`, comma-separated.
        expected: String,
    },
    /// The folder holds none of the metadata files of a known layout.
    #[error("{}: no dataset here (looked for dataset.json, train_meta.json, transforms*.json)", .0.display())]
    Unknown(PathBuf),
}

/// Which layout a dataset came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// This project's own layout ([`own`]).
    Own,
    /// Dynamic 3D Gaussians / CMU Panoptic ([`panoptic`]).
    Panoptic,
    /// nerfstudio / D-NeRF `transforms*.json` ([`nerfstudio`]).
    Nerfstudio,
}

impl Format {
    /// The layout's name in messages: "own", "Panoptic", "nerfstudio".
    pub fn name(self) -> &'static str {
        match self {
            Format::Own => "own",
            Format::Panoptic => "Panoptic",
            Format::Nerfstudio => "nerfstudio",
        }
    }
}

/// Where a layout's intrinsics put the centre of pixel (i, j). The engine's cameras use
/// `HalfInteger` (docs/conventions.md); intrinsics in the other convention are shifted by +0.5
/// in cx and cy at load time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PixelCenters {
    /// At (i, j): OpenCV calibrations, so the default for K matrices (Panoptic).
    Integer,
    /// At (i + 0.5, j + 0.5): nerfstudio, and this project's own `cam.json`.
    HalfInteger,
}

impl PixelCenters {
    /// What to add to cx and cy to reach the engine's convention.
    pub fn shift(self) -> f64 {
        match self {
            PixelCenters::Integer => 0.5,
            PixelCenters::HalfInteger => 0.0,
        }
    }

    /// The convention a layout's intrinsics follow unless told otherwise.
    pub fn default_for(format: Format) -> PixelCenters {
        match format {
            Format::Panoptic => PixelCenters::Integer,
            Format::Own | Format::Nerfstudio => PixelCenters::HalfInteger,
        }
    }
}

/// How to read a dataset where its files do not say.
#[derive(Clone, Copy, Debug, Default)]
pub struct LoadOptions {
    /// The pixel-centre convention of the layout's intrinsics; None takes the layout's default
    /// ([`PixelCenters::default_for`]).
    pub pixel_centers: Option<PixelCenters>,
    /// Scales every view's images, masks and intrinsics together by this factor in (0, 1]
    /// (a 4K capture at 0.25 trains at 1K); None keeps the files' size.
    pub scale: Option<f64>,
}

/// Where a view's mask comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum MaskSource {
    /// A separate PNG; its first channel (> 0.5 is foreground).
    File(PathBuf),
    /// The alpha channel of the image itself.
    Alpha,
}

/// One image of one camera at one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct View {
    /// Index into [`Dataset::cameras`].
    pub camera: usize,
    /// The image file.
    pub image: PathBuf,
    /// Where the view's mask comes from.
    pub mask: MaskSource,
}

/// The views captured at one time (seconds, or the frame index where the source has no clock).
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Capture time in seconds, or the frame index where the source has no clock.
    pub time: f64,
    /// The views of the frame, sorted by camera index.
    pub views: Vec<View>,
}

/// When a step meant for a studio's capture runs: refining the masks from the images
/// ([`Dataset::refine_masks_when`]), learning each camera's colour response.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CaptureStep {
    /// Where the images carry a background ([`background::background_share`]): renders over
    /// black come from one virtual camera, and a plate says nothing the masks do not.
    Auto,
    /// Always.
    Always,
    /// Never (the masks as given, the colours as seen).
    Never,
}

impl CaptureStep {
    /// Whether the step runs on `dataset`; `Auto` looks at frame `frame`'s images.
    pub fn applies(self, dataset: &Dataset, frame: usize) -> Result<bool, DatasetError> {
        Ok(match self {
            Self::Auto => background::background_share(dataset, frame)? > BACKGROUND_SHARE,
            Self::Always => true,
            Self::Never => false,
        })
    }
}

/// A loaded multi-view dataset: cameras in the engine's convention, frames in time order, and
/// the file of every view. Images are decoded on demand through a bounded cache.
#[derive(Debug)]
pub struct Dataset {
    /// The dataset folder.
    pub root: PathBuf,
    /// The layout it was read from.
    pub format: Format,
    /// The convention the intrinsics were read in (the cameras are converted from it).
    pub pixel_centers: PixelCenters,
    /// Name of each camera, parallel to `cameras`.
    pub camera_names: Vec<String>,
    /// The cameras, with pixel centres at half-integers.
    pub cameras: Vec<Camera>,
    /// In time order.
    pub frames: Vec<Frame>,
    /// Camera indices for training and for held-out evaluation.
    pub train: Vec<usize>,
    /// Camera indices held out for evaluation.
    pub test: Vec<usize>,
    /// Frames per second where the layout says: the own layout's `fps`; Panoptic's HD cameras'
    /// 29.97 (its files carry none). None for nerfstudio / D-NeRF, whose times are normalised.
    pub fps: Option<f64>,
    /// Each camera's size in the files when the views are scaled ([`LoadOptions::scale`]).
    source_sizes: Option<Vec<(u32, u32)>>,
    /// Each camera's background plate where its masks are refined ([`Dataset::refine_masks`]).
    plates: Vec<Option<Plate>>,
    cache: ImageCache,
}

impl Dataset {
    /// Detects the layout of `dir` and loads it: `dataset.json` (own), `train_meta.json`
    /// (Panoptic), `transforms*.json` (nerfstudio / D-NeRF).
    pub fn load(dir: &Path) -> Result<Self, DatasetError> {
        Self::load_with(dir, &LoadOptions::default())
    }

    /// [`Dataset::load`] with `options` for what the files leave open.
    pub fn load_with(dir: &Path, options: &LoadOptions) -> Result<Self, DatasetError> {
        let mut dataset = if dir.join(own::META).is_file() {
            own::load(dir)
        } else if dir.join(panoptic::TRAIN_META).is_file() {
            panoptic::load(dir)
        } else if !nerfstudio::transform_files(dir).is_empty() {
            nerfstudio::load(dir)
        } else {
            Err(DatasetError::Unknown(dir.to_owned()))
        }?;
        // Loaders keep the intrinsics as written; the one conversion happens here.
        dataset.pixel_centers =
            options.pixel_centers.unwrap_or(PixelCenters::default_for(dataset.format));
        let shift = dataset.pixel_centers.shift();
        for camera in &mut dataset.cameras {
            camera.cx += shift;
            camera.cy += shift;
        }
        if let Some(scale) = options.scale {
            if !(scale.is_finite() && scale > 0.0 && scale <= 1.0) {
                let problem = format!("scale {scale} is outside (0, 1]");
                return Err(DatasetError::File { path: dir.to_owned(), problem });
            }
            if scale != 1.0 {
                dataset.source_sizes = Some(scale_cameras(&mut dataset.cameras, scale));
            }
        }
        Ok(dataset)
    }

    /// Assembles a dataset, sorting frames by time and checking that every frame has the
    /// same set of cameras (unless every frame has exactly one view: a monocular sequence).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn assemble(
        root: &Path,
        meta: &Path,
        format: Format,
        camera_names: Vec<String>,
        cameras: Vec<Camera>,
        mut frames: Vec<Frame>,
        train: Vec<usize>,
        test: Vec<usize>,
    ) -> Result<Self, DatasetError> {
        if frames.is_empty() {
            return Err(DatasetError::File {
                path: meta.to_owned(),
                problem: "has no frames".into(),
            });
        }
        frames.sort_by(|a, b| a.time.total_cmp(&b.time));
        for f in &mut frames {
            f.views.sort_by_key(|v| v.camera);
        }
        let monocular = frames.iter().all(|f| f.views.len() == 1);
        let set = |f: &Frame| {
            f.views.iter().map(|v| camera_names[v.camera].as_str()).collect::<Vec<_>>().join(", ")
        };
        if !monocular {
            let first: Vec<usize> = frames[0].views.iter().map(|v| v.camera).collect();
            for (t, f) in frames.iter().enumerate() {
                if !f.views.iter().map(|v| v.camera).eq(first.iter().copied()) {
                    return Err(DatasetError::CameraSets {
                        path: meta.to_owned(),
                        frame: t,
                        first: 0,
                        found: set(f),
                        expected: set(&frames[0]),
                    });
                }
            }
        }
        Ok(Self {
            root: root.to_owned(),
            format,
            pixel_centers: PixelCenters::default_for(format),
            camera_names,
            cameras,
            frames,
            train,
            test,
            fps: None,
            source_sizes: None,
            plates: Vec::new(),
            cache: ImageCache::new(DEFAULT_CACHE_BYTES),
        })
    }

    /// Camera `camera`'s image size in the files (before any [`LoadOptions::scale`]).
    pub fn file_size(&self, camera: usize) -> (u32, u32) {
        let c = &self.cameras[camera];
        self.source_sizes.as_ref().map_or((c.width, c.height), |sizes| sizes[camera])
    }

    /// Replaces the image cache with one of `bytes` capacity.
    pub fn with_cache_bytes(mut self, bytes: usize) -> Self {
        self.cache = ImageCache::new(bytes);
        self
    }

    /// Bytes of decoded pixels held in the cache now.
    pub fn cached_bytes(&self) -> usize {
        self.cache.bytes()
    }

    /// Image files and mask files that do not exist.
    pub fn missing_files(&self) -> Vec<PathBuf> {
        let mut missing = Vec::new();
        for v in self.frames.iter().flat_map(|f| &f.views) {
            if !v.image.is_file() {
                missing.push(v.image.clone());
            }
            if let MaskSource::File(m) = &v.mask {
                if !m.is_file() {
                    missing.push(m.clone());
                }
            }
        }
        missing
    }

    fn view(&self, frame: usize, view: usize) -> &View {
        &self.frames[frame].views[view]
    }

    /// The image of view `view` (index into the frame's views) of `frame`, decoded (cached);
    /// its size must match the camera's.
    pub fn image(&self, frame: usize, view: usize) -> Result<Arc<Image>, DatasetError> {
        let v = self.view(frame, view);
        self.load_checked(&v.image, v.camera)
    }

    /// The mask of a view as one value per pixel in [0, 1] (> 0.5 is foreground): refined
    /// along its outline where its camera's masks are ([`Dataset::refine_masks`]), else as
    /// given.
    pub fn mask(&self, frame: usize, view: usize) -> Result<Vec<f32>, DatasetError> {
        let given = self.given_mask(frame, view)?;
        match self.plates.get(self.view(frame, view).camera) {
            Some(Some(plate)) => {
                Ok(matte::refine(self.image(frame, view)?.as_ref(), &given, plate))
            }
            _ => Ok(given),
        }
    }

    /// The mask of a view as its file (or its image's alpha) gives it.
    pub fn given_mask(&self, frame: usize, view: usize) -> Result<Vec<f32>, DatasetError> {
        let v = self.view(frame, view);
        match &v.mask {
            MaskSource::File(path) => Ok(self.load_checked(path, v.camera)?.first_channel()),
            MaskSource::Alpha => self
                .load_checked(&v.image, v.camera)?
                .alpha()
                .ok_or_else(|| DatasetError::NoMask(v.image.clone())),
        }
    }

    /// Refines the training masks ([`Self::refine_masks`]) when `when` says so: `Auto` where
    /// frame `frame`'s images carry a background. Returns the cameras refined, None when the
    /// masks stay as given.
    pub fn refine_masks_when(
        &mut self,
        when: CaptureStep,
        frame: usize,
        done: &mut dyn FnMut(usize, usize),
    ) -> Result<Option<usize>, DatasetError> {
        when.applies(self, frame)?.then(|| self.refine_masks(done)).transpose()
    }

    /// Refines the training cameras' masks along their outline from the images, against each
    /// camera's background plate ([`matte`]), taken from up to [`PLATE_FRAMES`] frames spread
    /// evenly over the capture. A camera seen in fewer than [`MIN_PLATE_FRAMES`] frames (a
    /// moving camera), or whose masks leave no pixel clear, keeps its masks. Held-out cameras
    /// keep theirs, so held-out scores grade against the capture as delivered. Holds one
    /// camera's frames decoded at a time; calls `done(cameras done, cameras)` after each.
    /// Returns the number of cameras refined.
    pub fn refine_masks(
        &mut self,
        done: &mut dyn FnMut(usize, usize),
    ) -> Result<usize, DatasetError> {
        let train = self.train.clone();
        self.plates = self.plates_of(&train, 1, done)?;
        Ok(self.plates.iter().flatten().count())
    }

    /// The background plate of each camera of `cameras` (None for the others, and for one
    /// seen in fewer than [`MIN_PLATE_FRAMES`] frames or whose masks leave no pixel clear),
    /// indexed by camera, each pixel from at least `min_seen` frames ([`Plate::from_frames`]);
    /// `done(cameras done, cameras)` after each.
    fn plates_of(
        &self,
        cameras: &[usize],
        min_seen: usize,
        done: &mut dyn FnMut(usize, usize),
    ) -> Result<Vec<Option<Plate>>, DatasetError> {
        let count = self.frames.len().min(PLATE_FRAMES);
        let picked: Vec<usize> = (0..count).map(|i| i * self.frames.len() / count).collect();
        let mut plates = vec![None; self.cameras.len()];
        for (i, &camera) in cameras.iter().enumerate() {
            done(i, cameras.len());
            let views: Vec<(usize, usize)> = picked
                .iter()
                .filter_map(|&t| {
                    let k = self.frames[t].views.iter().position(|v| v.camera == camera)?;
                    Some((t, k))
                })
                .collect();
            if views.len() < MIN_PLATE_FRAMES {
                continue;
            }
            let decoded = parallel_map(&views, |&(t, k)| {
                Ok::<_, DatasetError>((self.image(t, k)?, self.given_mask(t, k)?))
            })?;
            let pairs: Vec<(&Image, &[f32])> =
                decoded.iter().map(|(i, m)| (i.as_ref(), m.as_slice())).collect();
            plates[camera] = Plate::from_frames(&pairs, min_seen);
        }
        done(cameras.len(), cameras.len());
        Ok(plates)
    }

    fn load_checked(&self, path: &Path, camera: usize) -> Result<Arc<Image>, DatasetError> {
        if !path.is_file() {
            return Err(DatasetError::MissingImage(path.to_owned()));
        }
        self.cache.get_or_load(path, |path| {
            let image = read_image(path)?;
            self.check_size(path, camera, (image.width, image.height))?;
            let c = &self.cameras[camera];
            Ok(match self.source_sizes {
                Some(_) => resample_area(&image, c.width, c.height),
                None => image,
            })
        })
    }

    /// Checks a file's size against its camera's as the files have it (before any scaling).
    fn check_size(
        &self,
        path: &Path,
        camera: usize,
        (width, height): (u32, u32),
    ) -> Result<(), DatasetError> {
        let (camera_width, camera_height) = self.file_size(camera);
        if (width, height) != (camera_width, camera_height) {
            return Err(DatasetError::SizeMismatch {
                path: path.to_owned(),
                camera: self.camera_names[camera].clone(),
                width,
                height,
                camera_width,
                camera_height,
            });
        }
        Ok(())
    }

    /// Every problem found by reading every file: missing files, sizes that disagree with
    /// their camera, files that do not decode, masks missing, frames whose masks are empty in
    /// every view, and, when the images are composited over black (under 5 % of the pixels
    /// outside the masks lit), masks that leave out more than 10 % of the subject their image
    /// shows. Decodes every image and mask through the cache (memory stays bounded).
    pub fn check(&self) -> Vec<DatasetError> {
        let mut problems = Vec::new();
        let mut counts: Vec<(usize, usize, MaskCounts)> = Vec::new();
        for (t, frame) in self.frames.iter().enumerate() {
            let mut any_foreground = false;
            let mut masks_read = 0;
            for (k, v) in frame.views.iter().enumerate() {
                if !v.image.is_file() {
                    problems.push(DatasetError::MissingImage(v.image.clone()));
                    continue;
                }
                let image = match self.image(t, k) {
                    Ok(image) => image,
                    Err(e) => {
                        problems.push(e);
                        continue;
                    }
                };
                match self.given_mask(t, k) {
                    Ok(m) => {
                        masks_read += 1;
                        any_foreground |= m.iter().any(|&x| x > 0.5);
                        let mask_counts = MaskCounts::of(&image.data, image.channels as usize, &m);
                        counts.push((t, k, mask_counts));
                    }
                    Err(e) => problems.push(e),
                }
            }
            if masks_read == frame.views.len() && !any_foreground {
                problems.push(DatasetError::EmptyMasks { frame: t });
            }
        }
        match self.masks_cutting_the_subject(&counts) {
            Ok(cut) => problems.extend(cut),
            Err(e) => problems.push(e),
        }
        problems
    }

    /// The views of `counts` (frame, view, counts) whose mask leaves out over 10 % of the
    /// subject: over black, the lit pixels outside the mask; over a background, the pixels
    /// well outside it whose colour is not the camera's plate ([`matte::off_plate`]).
    fn masks_cutting_the_subject(
        &self,
        counts: &[(usize, usize, MaskCounts)],
    ) -> Result<Vec<DatasetError>, DatasetError> {
        let (outside, lit) =
            counts.iter().fold((0, 0), |(o, l), (_, _, c)| (o + c.outside, l + c.lit_outside));
        let cut: Vec<(usize, usize, u64, u64)> = if lit as f64 > BACKGROUND_SHARE * outside as f64 {
            let cameras: Vec<usize> = (0..self.cameras.len()).collect();
            let plates = self.plates_of(&cameras, 2, &mut |_, _| {})?;
            let mut cut = Vec::new();
            for &(frame, k, _) in counts {
                if let Some(plate) = &plates[self.view(frame, k).camera] {
                    let (image, mask) = (self.image(frame, k)?, self.given_mask(frame, k)?);
                    let (inside, off) = matte::off_plate(&image, &mask, plate);
                    cut.push((frame, k, inside, off));
                }
            }
            cut
        } else {
            counts.iter().map(|&(t, k, c)| (t, k, c.inside, c.lit_outside)).collect()
        };
        let percent = |inside: u64, off: u64| 100.0 * off as f64 / inside.max(1) as f64;
        Ok(cut
            .into_iter()
            .filter(|&(_, _, inside, off)| percent(inside, off) > 10.0)
            .map(|(frame, k, inside, off)| {
                let v = self.view(frame, k);
                let mask = match &v.mask {
                    MaskSource::File(path) => path.clone(),
                    MaskSource::Alpha => v.image.clone(),
                };
                let camera = self.camera_names[v.camera].clone();
                DatasetError::MaskCutsSubject { frame, camera, mask, percent: percent(inside, off) }
            })
            .collect())
    }
}

/// Camera `index % 8 == 7` is held out for testing (every eighth camera), the rest train.
pub fn every_eighth_held_out(count: usize) -> (Vec<usize>, Vec<usize>) {
    (0..count).partition(|i| i % 8 != 7)
}

/// A file or folder name read from the metadata file `meta`, as a path relative to the dataset
/// folder (`.` components dropped). Every layout's metadata names go through here: an absolute
/// name or a `..` would reach files outside the dataset (a downloaded dataset must not read
/// `/etc/passwd`), so they are refused, as is an empty name, naming `meta` and `what` it is.
pub(crate) fn inside_dataset(meta: &Path, what: &str, name: &str) -> Result<PathBuf, DatasetError> {
    let components = Path::new(name).components();
    let inside = components.clone().all(|c| matches!(c, Component::Normal(_) | Component::CurDir));
    let relative: PathBuf = components.filter(|c| matches!(c, Component::Normal(_))).collect();
    if !inside || relative.as_os_str().is_empty() {
        return Err(DatasetError::File {
            path: meta.to_owned(),
            problem: format!(
                "{what} `{name}` is not a path inside the dataset folder (empty, absolute, or \
                 with `..`)"
            ),
        });
    }
    Ok(relative)
}

/// Reads a JSON file into `T`, naming the file on failure.
pub(crate) fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, DatasetError> {
    let text = std::fs::read_to_string(path).map_err(|e| DatasetError::File {
        path: path.to_owned(),
        problem: format!("cannot read: {e}"),
    })?;
    serde_json::from_str(&text).map_err(|e| DatasetError::File {
        path: path.to_owned(),
        problem: format!("invalid JSON: {e}"),
    })
}

/// Scales each camera to `scale` × its size (rounded, at least 1 pixel) and its intrinsics by
/// the size's actual ratio per axis (pixel centres at half-integers, so coordinates scale as
/// they are); returns the sizes before.
/// An image's size scaled by `scale` as the loader scales it: each side rounded, at least 1.
pub fn scaled_size((width, height): (u32, u32), scale: f64) -> (u32, u32) {
    let side = |n: u32| ((n as f64 * scale).round() as u32).max(1);
    (side(width), side(height))
}

fn scale_cameras(cameras: &mut [Camera], scale: f64) -> Vec<(u32, u32)> {
    cameras
        .iter_mut()
        .map(|c| {
            let before = (c.width, c.height);
            let (width, height) = scaled_size(before, scale);
            let (sx, sy) = (width as f64 / c.width as f64, height as f64 / c.height as f64);
            (c.fx, c.cx, c.fy, c.cy) = (c.fx * sx, c.cx * sx, c.fy * sy, c.cy * sy);
            (c.width, c.height) = (width, height);
            before
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn metadata_names_stay_inside_the_dataset() {
        let meta = Path::new("d/meta.json");
        let inside = |name| inside_dataset(meta, "image", name);
        assert_eq!(inside("./a/./b.png").unwrap(), Path::new("a/b.png"));
        for name in ["", ".", "/etc/passwd", "../x.png", "a/../../x.png", "a/.."] {
            let message = inside(name).unwrap_err().to_string();
            let expected = format!("d/meta.json: image `{name}` is not a path inside");
            assert!(message.starts_with(&expected), "{message}");
        }
    }
}
