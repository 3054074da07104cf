//! The pipeline's output folder. Each finished frame is written at once — `gaussians/<t>.ply`
//! (3DGS layout) and then `meshes/<t>.ply` (vertex colours, the one face list), each under a
//! temporary name and renamed — so the mesh marks a frame complete and a stopped run resumes
//! after the last complete frame. The sequence formats come last, from the meshes on disk.

use super::TrainError;
use crate::dataset::own::frame_name;
use crate::mesh::TriMesh;
use crate::sequence::orient::{Orientation, SignedAxis, UpAxis};
use crate::sequence::usd::write_usda;
use crate::sequence::{FrameFormat, MeshSequence};
use crate::splat::GaussianScene;
use std::path::{Path, PathBuf};

/// `root/meshes/<t>.ply`: frame `t`'s mesh in an output folder (also where `eval` reads it).
pub fn mesh_path(root: &Path, t: usize) -> PathBuf {
    root.join("meshes").join(format!("{}.ply", frame_name(t)))
}

/// A pipeline output folder (see the module docs): per-frame Gaussians and meshes, then the
/// sequence exports.
pub struct SequenceOutput {
    root: PathBuf,
}

fn io_error(path: &Path) -> impl FnOnce(std::io::Error) -> TrainError + '_ {
    move |error| TrainError::Io { path: path.to_owned(), error }
}

impl SequenceOutput {
    /// Opens (creating when needed) `root` with its `meshes/` and `gaussians/` folders.
    pub fn create(root: &Path) -> Result<Self, TrainError> {
        for dir in [root.join("meshes"), root.join("gaussians")] {
            std::fs::create_dir_all(&dir).map_err(io_error(&dir))?;
        }
        Ok(Self { root: root.to_owned() })
    }

    /// The folder itself.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// `root/meshes/<t>.ply`: frame `t`'s mesh (`<t>` six digits).
    pub fn mesh_path(&self, t: usize) -> PathBuf {
        mesh_path(&self.root, t)
    }

    /// `root/gaussians/<t>.ply`: frame `t`'s Gaussians (`<t>` six digits).
    pub fn gaussians_path(&self, t: usize) -> PathBuf {
        self.root.join("gaussians").join(format!("{}.ply", frame_name(t)))
    }

    /// `root/camera_colour.json`: each training camera's colour map frame 0 learned, by name
    /// (written before frame 0's files, when learned; later frames and a resumed run read it).
    pub fn camera_colour_path(&self) -> PathBuf {
        self.root.join("camera_colour.json")
    }

    /// Whether frame `t` was finished (its mesh, written last, exists).
    pub fn is_complete(&self, t: usize) -> bool {
        self.mesh_path(t).is_file() && self.gaussians_path(t).is_file()
    }

    /// Writes frame `t`: the Gaussians, then the mesh.
    pub fn write_frame(
        &self,
        t: usize,
        mesh: &TriMesh,
        scene: &GaussianScene,
    ) -> Result<(), TrainError> {
        scene.write_ply(&self.gaussians_path(t))?;
        Ok(mesh.write_ply(&self.mesh_path(t))?)
    }

    /// A finished frame's mesh and Gaussians, as written.
    pub fn read_frame(&self, t: usize) -> Result<(TriMesh, GaussianScene), TrainError> {
        let mesh = TriMesh::read_ply(&self.mesh_path(t))?;
        let scene = GaussianScene::read_ply(&self.gaussians_path(t))?;
        if mesh.positions.len() != scene.len() {
            let problem = format!(
                "{} vertices but {} has {} Gaussians",
                mesh.positions.len(),
                self.gaussians_path(t).display(),
                scene.len()
            );
            return Err(TrainError::Invalid { path: self.mesh_path(t), problem });
        }
        Ok((mesh, scene))
    }

    /// Writes `sequence.obj` + `sequence.pc2`, `sequence.glb` and `sequence.usda` (`fps`
    /// frames per second) from the meshes of `frames`, turned from the capture's up `source`
    /// onto `up` ([`Orientation::for_export`]: by default GLB Y-up, the others following the
    /// capture); returns the paths and a sentence saying how each was turned. The frames in
    /// `meshes/` stay in the dataset's world, where its ground truth is.
    pub fn export(
        &self,
        frames: std::ops::Range<usize>,
        fps: f64,
        source: SignedAxis,
        up: Option<UpAxis>,
    ) -> Result<(Vec<PathBuf>, String), TrainError> {
        let mut sequence = MeshSequence::default();
        for t in frames {
            let mesh = TriMesh::read_ply(&self.mesh_path(t))?;
            if sequence.frames.is_empty() {
                sequence.faces = mesh.faces.clone();
                sequence.colors = mesh.colors.as_ref().map(|_| Vec::new());
            } else if mesh.faces != sequence.faces {
                let problem = "its faces differ from the first frame's".into();
                return Err(TrainError::Invalid { path: self.mesh_path(t), problem });
            }
            if let (Some(all), Some(c)) = (sequence.colors.as_mut(), mesh.colors) {
                all.push(c);
            }
            sequence.frames.push(mesh.positions);
        }
        let (others, gltf) =
            (Orientation::for_export(source, up, false), Orientation::for_export(source, up, true));
        let (pc2, glb) = (self.root.join("sequence.pc2"), self.root.join("sequence.glb"));
        let usd = self.root.join("sequence.usda");
        let turned = others.sequence(&sequence);
        turned.write(&pc2, FrameFormat::Ply, fps)?;
        gltf.sequence(&sequence).write(&glb, FrameFormat::Ply, fps)?;
        write_usda(&usd, &sequence, fps, others, None)?;
        let said = format!("USD, OBJ + PC2: {}; GLB: {}", others.describe(), gltf.describe());
        Ok((vec![self.root.join("sequence.obj"), pc2, glb, usd], said))
    }
}

/// Vertex colours of a mesh from the Gaussians' SH DC term (`0.5 + C0 · DC`, clamped).
pub fn dc_vertex_colors(scene: &GaussianScene) -> Vec<[u8; 3]> {
    const SH_C0: f32 = 0.282_094_8;
    let stride = scene.sh.len() / scene.len().max(1);
    (0..scene.len())
        .map(|i| {
            [0, 1, 2].map(|c| {
                ((0.5 + SH_C0 * scene.sh[i * stride + c]).clamp(0.0, 1.0) * 255.0).round() as u8
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::train::init::gaussians_at_points;

    #[test]
    fn frames_round_trip_mark_completion_and_export() {
        let root = std::env::temp_dir().join(format!("tagsplat-output-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let out = SequenceOutput::create(&root).unwrap();
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let faces = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        for t in 0..2 {
            let moved: Vec<[f32; 3]> =
                positions.iter().map(|p| [p[0] + t as f32, p[1], p[2]]).collect();
            let scene = gaussians_at_points(&moved, Some(&[[0.2, 0.4, 0.6]; 4]), 0);
            let mesh = TriMesh {
                positions: moved,
                faces: faces.clone(),
                colors: Some(dc_vertex_colors(&scene)),
            };
            assert!(!out.is_complete(t));
            out.write_frame(t, &mesh, &scene).unwrap();
            assert!(out.is_complete(t));
            let (back, back_scene) = out.read_frame(t).unwrap();
            assert_eq!((back.faces, back_scene), (faces.clone(), scene));
            assert_eq!(back.colors.unwrap()[0], [51, 102, 153]);
        }
        // A Z-up capture: GLB turned Y-up, the others kept Z-up, meshes/ untouched.
        let z_up = SignedAxis { axis: 2, negative: false };
        let (written, said) = out.export(0..2, 10.0, z_up, None).unwrap();
        assert!(written.iter().all(|p| p.is_file()));
        assert!(said.contains("GLB: Y up (the capture's up +Z turned onto +Y)"), "{said}");
        let glb = MeshSequence::read(&root.join("sequence.glb")).unwrap();
        let pc2 = MeshSequence::read(&root.join("sequence.pc2")).unwrap();
        assert_eq!(glb.frames.len(), 2);
        assert_eq!(glb.frames[1][3], [1.0, 1.0, 0.0], "(x, y, z) -> (x, z, -y)");
        assert_eq!(pc2.frames[1][3], [1.0, 0.0, 1.0]);
        assert_eq!(out.read_frame(1).unwrap().0.positions[3], [1.0, 0.0, 1.0]);
        // Asked for Y up, every export is.
        out.export(0..2, 10.0, z_up, Some(UpAxis::Y)).unwrap();
        let pc2 = MeshSequence::read(&root.join("sequence.pc2")).unwrap();
        assert_eq!(pc2.frames[1][3], [1.0, 1.0, 0.0]);
        std::fs::remove_file(out.mesh_path(1)).unwrap();
        assert!(!out.is_complete(1));
        let _ = std::fs::remove_dir_all(&root);
    }
}
