//! Topology-consistent mesh sequences: one face list, vertex positions per frame, and the
//! file layouts animation tools open.
//!
//! - A folder of per-frame PLY (binary, vertex colours) or OBJ files, natural order
//!   ([`folder`]).
//! - A base OBJ plus a PC2 or MDD point cache beside it (`anim.obj` + `anim.pc2`, [`crate::io::mdd`]).
//! - glTF 2.0 (`.gltf`, `.glb`): skins, morph targets and node animation evaluated as the
//!   specification says ([`gltf`]); written as a base mesh, one morph target per frame and a
//!   stepping animation ([`glb`]).
//! - USD: a `Mesh` prim's time-sampled points under its xforms ([`usd_read`]); written as text
//!   ([`usd`]).
//! - Alembic (Ogawa): a PolyMesh's time-sampled `P` under its Xforms ([`alembic`]).
//! - FBX: skins, blend shapes and point caches evaluated by ufbx ([`fbx`]).
//!
//! The animation readers return a [`SourceSequence`] (polygons, frames, times, axes), which
//! [`SourceSequence::into_sequence`] checks and fans into triangles the same way for every
//! format ([`crate::mesh::polygon`]).
//!
//! Reading any of them checks that every frame has frame 0's vertex count and face list, and
//! names the first frame that differs. Colours: a folder keeps them per frame; the OBJ + PC2
//! and GLB layouts store the frame-0 colours only, and read them back for every frame.

pub mod alembic;
pub mod bench;
pub mod fbx;
pub mod folder;
mod folder_read;
pub mod glb;
pub mod gltf;
pub mod orient;
mod point_cache;
pub mod source;
pub mod usd;
pub mod usd_read;
mod usdc_check;

use crate::io::pc2::Pc2Error;
use crate::mesh::{MeshError, TriMesh};
use glb::GlbError;
pub use source::{ReadOptions, SequenceInfo, SourceSequence};
use std::path::{Path, PathBuf};

/// What can go wrong reading or writing a sequence; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    /// Reading or writing a frame's PLY or OBJ file (or the PC2 layout's base OBJ) failed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// Reading or writing the PC2 point cache failed.
    #[error(transparent)]
    Pc2(#[from] Pc2Error),
    /// Reading or writing the GLB file failed.
    #[error(transparent)]
    Glb(#[from] GlbError),
    /// An animation file (glTF, USD, Alembic, FBX, MDD) does not read as its format says, or
    /// holds no usable sequence (the frames disagree, the topology changes, the choice of
    /// animation or mesh is missing or names nothing).
    #[error("{}: {problem}", path.display())]
    Format {
        /// The file concerned.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
    /// The path is no sequence, a file is missing, the frames disagree with frame 0, or the
    /// sequence cannot be written.
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The file or folder concerned.
        path: PathBuf,
        /// What is wrong with it.
        problem: String,
    },
}

fn invalid(path: &Path, problem: impl Into<String>) -> SequenceError {
    SequenceError::Invalid { path: path.to_path_buf(), problem: problem.into() }
}

/// A mesh sequence: the same faces in every frame, vertex positions per frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshSequence {
    /// Triangles as vertex indices, shared by every frame.
    pub faces: Vec<[u32; 3]>,
    /// Vertex positions of each frame, all of one length.
    pub frames: Vec<Vec<[f32; 3]>>,
    /// Vertex colours of each frame, when the source has them.
    pub colors: Option<Vec<Vec<[u8; 3]>>>,
}

/// The file kind of a frame in a folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameFormat {
    /// Binary PLY (vertex colours when present).
    Ply,
    /// Wavefront OBJ.
    Obj,
}

impl MeshSequence {
    /// Reads a sequence with the default [`ReadOptions`] (see [`Self::read_with`]).
    pub fn read(path: &Path) -> Result<Self, SequenceError> {
        Ok(Self::read_with(path, &ReadOptions::default())?.0)
    }

    /// Reads a folder of frames, a `.pc2` or `.mdd` (with the `.obj` of the same name beside
    /// it), glTF (`.gltf`, `.glb`), USD (`.usda`, `.usdc`, `.usd`, `.usdz`), Alembic (`.abc`) or
    /// FBX, and what the file says beside its frames (times, rate, up axis, units, which
    /// polygon each triangle came from). An option the format has no use for is an error naming
    /// it, never silently ignored.
    pub fn read_with(
        path: &Path,
        options: &ReadOptions,
    ) -> Result<(Self, SequenceInfo), SequenceError> {
        if !path.exists() {
            return Err(invalid(path, "no such file or folder"));
        }
        if let Some(fps) = options.fps.filter(|f| !(f.is_finite() && *f > 0.0)) {
            return Err(invalid(path, format!("--fps {fps}: must be a positive number")));
        }
        let kind =
            if path.is_dir() { "folder".to_owned() } else { extension(path).unwrap_or_default() };
        // A format without a clock takes --fps as its frame rate.
        let clockless = |sequence: Self| {
            Ok((sequence, SequenceInfo { fps: options.fps, ..SequenceInfo::default() }))
        };
        match kind.as_str() {
            "folder" => refuse_options(path, &kind, options, [false, true, false]).and_then(|()| {
                let (sequence, polygon_of) = folder_read::read_frames(path)?;
                let (sequence, info) = clockless(sequence)?;
                Ok((sequence, SequenceInfo { polygon_of, ..info }))
            }),
            "pc2" => refuse_options(path, &kind, options, [false, true, false])
                .and_then(|()| clockless(Self::read_pc2(path)?)),
            "glb" | "gltf" => refuse_options(path, &kind, options, [true, true, true])
                .and_then(|()| from_source(path, gltf::read(path, options))),
            "abc" => refuse_options(path, &kind, options, [false, false, true])
                .and_then(|()| from_source(path, alembic::read(path, options))),
            "fbx" => refuse_options(path, &kind, options, [true; 3])
                .and_then(|()| from_source(path, fbx::read(path, options))),
            "usda" | "usdc" | "usd" | "usdz" => {
                refuse_options(path, &kind, options, [false, false, true])
                    .and_then(|()| from_source(path, usd_read::read(path, options)))
            }
            "mdd" => refuse_options(path, &kind, options, [false; 3])
                .and_then(|()| point_cache::read_mdd(path)),
            _ => Err(invalid(
                path,
                "not a sequence: expected a folder of .ply/.obj frames, or a .pc2, .mdd, .gltf, \
                 .glb, .usda, .usdc, .usd, .usdz, .abc or .fbx file",
            )),
        }
    }

    /// Writes to a `.pc2` (and its base `.obj`), a `.glb` (`fps` frames per second), or
    /// otherwise a folder of `frame_NNNNNN` files in `format`.
    pub fn write(&self, path: &Path, format: FrameFormat, fps: f64) -> Result<(), SequenceError> {
        match extension(path).as_deref() {
            Some("pc2") => self.write_pc2(path),
            Some("mdd") => point_cache::write_mdd(path, self, fps),
            Some("glb") => Ok(glb::write_glb(path, self, fps)?),
            _ => self.write_folder(path, format),
        }
    }

    /// Writes the sequence as `tagsplat convert` does, turned by `orientation` onto the file's
    /// up axis: a `.usda` (time-sampled at `fps`), or any form [`Self::write`] writes.
    pub fn export(
        &self,
        path: &Path,
        format: FrameFormat,
        fps: f64,
        orientation: orient::Orientation,
    ) -> Result<(), SequenceError> {
        if extension(path).as_deref() == Some("usda") {
            let failed = |e: usd::UsdError| invalid(path, e.problem);
            return usd::write_usda(path, self, fps, orientation, None).map_err(failed);
        }
        orientation.sequence(self).write(path, format, fps)
    }

    /// Frame `t` as a mesh (its colours when the sequence has them). None past the end.
    pub fn frame_mesh(&self, t: usize) -> Option<TriMesh> {
        Some(TriMesh {
            positions: self.frames.get(t)?.clone(),
            faces: self.faces.clone(),
            colors: self.colors.as_ref().and_then(|c| c.get(t).cloned()),
        })
    }

    /// The first reason this is not a usable sequence: no frames, frames of different vertex
    /// counts, colours that do not match, a face index out of range, a non-finite position.
    pub fn problem(&self) -> Option<String> {
        let n = self.frames.first().map(Vec::len)?;
        if let Some(t) = self.frames.iter().position(|f| f.len() != n) {
            return Some(format!(
                "frame {t} has {} vertices, frame 0 has {n}",
                self.frames[t].len()
            ));
        }
        if let Some(colors) = &self.colors {
            if colors.len() != self.frames.len() || colors.iter().any(|c| c.len() != n) {
                return Some("the colours do not match the frames and vertices".into());
            }
        }
        // Faces and colour counts are the same in every frame, so they are checked in frame 0
        // only: a file of many frames and many faces must not cost frames × faces.
        let first = self.frame_mesh(0)?.problem().map(|p| format!("frame 0: {p}"));
        first.or_else(|| {
            (1..self.frames.len()).find_map(|t| {
                let mesh = TriMesh { positions: self.frames[t].clone(), ..TriMesh::default() };
                mesh.problem().map(|p| format!("frame {t}: {p}"))
            })
        })
    }

    /// Reads the frames of a folder (see [`folder`]), checking them against frame 0: every
    /// frame has its vertex count and faces, or the error names the first frame that differs.
    pub fn read_folder(dir: &Path) -> Result<Self, SequenceError> {
        Ok(folder_read::read_frames(dir)?.0)
    }

    /// Writes `frame_000000.ply` (or `.obj`), … into `dir`, creating it. Refuses a folder that
    /// already holds frame files, so old frames never mix with new ones.
    pub fn write_folder(&self, dir: &Path, format: FrameFormat) -> Result<(), SequenceError> {
        self.check(dir)?;
        std::fs::create_dir_all(dir)
            .map_err(|e| invalid(dir, format!("cannot create the folder: {e}")))?;
        if let Some(existing) = folder::frame_names(dir)?.first() {
            return Err(invalid(
                dir,
                format!("already holds frame files ({existing}, ...): choose an empty folder"),
            ));
        }
        let ext = match format {
            FrameFormat::Ply => "ply",
            FrameFormat::Obj => "obj",
        };
        for t in 0..self.frames.len() {
            let mesh = self.frame_mesh(t).ok_or_else(|| invalid(dir, "frame out of range"))?;
            let path = dir.join(format!("frame_{t:06}.{ext}"));
            match format {
                FrameFormat::Ply => mesh.write_ply(&path)?,
                FrameFormat::Obj => mesh.write_obj(&path)?,
            }
        }
        Ok(())
    }

    /// [`MeshSequence::problem`] as an error naming `path`.
    pub fn check(&self, path: &Path) -> Result<(), SequenceError> {
        if self.frames.is_empty() {
            return Err(invalid(path, "the sequence has no frames"));
        }
        self.problem().map_or(Ok(()), |p| Err(invalid(path, p)))
    }
}

/// Frame `t` (read from `file`) must have frame 0's vertex count and faces.
pub(crate) fn check_same_topology(
    sequence: &MeshSequence,
    mesh: &TriMesh,
    t: usize,
    file: &Path,
    first: &Path,
) -> Result<(), SequenceError> {
    check_vertex_count(sequence, mesh.positions.len(), t, file, first)?;
    let first_name = file_name(first);
    if mesh.faces.len() != sequence.faces.len() {
        return Err(invalid(
            file,
            format!(
                "frame {t} has {} faces, frame 0 ({first_name}) has {}",
                mesh.faces.len(),
                sequence.faces.len()
            ),
        ));
    }
    if let Some(f) = (0..mesh.faces.len()).find(|&f| mesh.faces[f] != sequence.faces[f]) {
        return Err(invalid(
            file,
            format!(
                "frame {t} differs from frame 0 ({first_name}) at face {f}: {:?} instead of {:?}",
                mesh.faces[f], sequence.faces[f]
            ),
        ));
    }
    Ok(())
}

/// Frame `t` (read from `file`) must have frame 0's vertex count.
pub(crate) fn check_vertex_count(
    sequence: &MeshSequence,
    vertices: usize,
    t: usize,
    file: &Path,
    first: &Path,
) -> Result<(), SequenceError> {
    let n = sequence.frames.first().map_or(vertices, Vec::len);
    if vertices == n {
        return Ok(());
    }
    let problem =
        format!("frame {t} has {vertices} vertices, frame 0 ({}) has {n}", file_name(first));
    Err(invalid(file, problem))
}

fn file_name(path: &Path) -> String {
    path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()
}

/// The triangulated sequence of a reader's result, its errors naming `path`.
fn from_source(
    path: &Path,
    read: Result<SourceSequence, String>,
) -> Result<(MeshSequence, SequenceInfo), SequenceError> {
    read.and_then(SourceSequence::into_sequence)
        .map_err(|problem| SequenceError::Format { path: path.to_path_buf(), problem })
}

/// Refuses an option of `options` that a `kind` file has no use for: `uses` says whether it
/// uses the animation, the frame rate and the mesh choice.
fn refuse_options(
    path: &Path,
    kind: &str,
    options: &ReadOptions,
    uses: [bool; 3],
) -> Result<(), SequenceError> {
    let given = [
        ("--animation", options.animation.is_some()),
        ("--fps", options.fps.is_some()),
        ("--mesh", options.mesh.is_some()),
    ];
    match given.iter().zip(uses).find(|((_, given), used)| *given && !used) {
        Some(((option, _), _)) => {
            Err(invalid(path, format!("{option} has no meaning for a {kind}")))
        }
        None => Ok(()),
    }
}

fn extension(path: &Path) -> Option<String> {
    Some(path.extension()?.to_str()?.to_ascii_lowercase())
}
