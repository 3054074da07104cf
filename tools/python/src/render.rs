//! `render_splats` and `render_mesh`: one view into an array, through the engine calls of
//! `tagsplat render` and `tagsplat render-mesh`.

use crate::arrays;
use crate::camera::camera_arg;
use crate::context::Context;
use crate::errors::{bad_input, failure, run, run_failing};
use crate::sequence::Sequence;
use numpy::PyArrayDyn;
use pyo3::prelude::*;
use std::path::PathBuf;
use tagsplat::raster::{MeshRasterizer, RasterMesh, RasterSettings};
use tagsplat::splat::{GaussianBuffers, GaussianScene, RenderSettings, Splatter};
use tagsplat::{MeshSequence, TriMesh};

/// Renders the 3DGS PLY scene at `scene` through `camera` (a Camera or a cam.json path):
/// (H, W, 4) float32, RGB and accumulated alpha in [0, 1], over `background`.
#[pyfunction]
#[pyo3(signature = (ctx, scene, camera, *, background = (0.0, 0.0, 0.0), sh_degree = 3, near = 0.01, far = 1e4, mask = false))]
#[allow(clippy::too_many_arguments)] // the CLI's options, one keyword each
pub fn render_splats<'py>(
    py: Python<'py>,
    ctx: &Context,
    scene: PathBuf,
    camera: &Bound<'py, PyAny>,
    background: (f32, f32, f32),
    sh_degree: u32,
    near: f32,
    far: f32,
    mask: bool,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let camera = camera_arg(py, camera)?;
    if sh_degree > 3 {
        return Err(bad_input(py, format!("sh_degree: {sh_degree} is not in 0..=3")));
    }
    let background = [background.0, background.1, background.2];
    let settings = RenderSettings { background, near, far, sh_degree, mask_mode: mask };
    let rgba = run_failing(py, || {
        let scene = GaussianScene::read_ply(&scene).map_err(failure)?;
        let buffers = GaussianBuffers::from_scene(&ctx.inner, &scene).map_err(failure)?;
        let mut splatter = Splatter::renderer(&ctx.inner).map_err(failure)?;
        splatter.forward(&buffers, &camera, &settings).map_err(failure)?;
        splatter.read_rgba().map_err(failure)
    })?;
    let shape = [camera.height as usize, camera.width as usize, 4];
    arrays::owned(py, rgba.into_flattened(), &shape)
}

/// Renders frame `frame` of `mesh` (a Sequence, the path of a sequence, or a .ply/.obj mesh)
/// through `camera` with the differentiable rasterizer: (H, W, 4) float32, the anti-aliased
/// colour (vertex colours, grey without) and coverage, black background.
#[pyfunction]
#[pyo3(signature = (ctx, mesh, camera, frame = 0, *, near = None))]
pub fn render_mesh<'py>(
    py: Python<'py>,
    ctx: &Context,
    mesh: &Bound<'py, PyAny>,
    camera: &Bound<'py, PyAny>,
    frame: usize,
    near: Option<f32>,
) -> PyResult<Bound<'py, PyArrayDyn<f32>>> {
    let camera = camera_arg(py, camera)?;
    let mesh = raster_mesh(py, mesh_frame(py, mesh, frame)?)?;
    let mut settings = RasterSettings::scaled_to(&mesh.positions);
    if let Some(near) = near {
        settings.near = near;
    }
    let image = run_failing(py, || {
        let (width, height) = (camera.width, camera.height);
        let rasterizer = MeshRasterizer::new(&ctx.inner, &mesh, width, height).map_err(failure)?;
        rasterizer.render(&camera, &settings).map_err(failure)?;
        rasterizer.read_frame().map_err(failure)
    })?;
    let rgba = image.color.iter().zip(&image.mask).flat_map(|(c, &m)| [c[0], c[1], c[2], m]);
    let shape = [camera.height as usize, camera.width as usize, 4];
    arrays::owned(py, rgba.collect(), &shape)
}

/// Frame `frame` of a Sequence, a sequence file or folder, or a single mesh file (frame 0).
fn mesh_frame(py: Python<'_>, mesh: &Bound<'_, PyAny>, frame: usize) -> PyResult<TriMesh> {
    let from_sequence = |s: &Sequence| -> PyResult<TriMesh> {
        let positions = s.frame(frame).ok_or_else(|| {
            bad_input(
                py,
                format!("frame: {frame} is past the sequence's {} frames", s.frame_count()),
            )
        })?;
        Ok(TriMesh {
            positions: positions.to_vec(),
            faces: s.face_list().to_vec(),
            colors: s.frame_colors(frame).map(<[_]>::to_vec),
        })
    };
    if let Ok(held) = mesh.cast::<Sequence>() {
        return from_sequence(held.get());
    }
    let path: PathBuf = mesh.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(
            "mesh: expected a Sequence or the path of a sequence or of a .ply/.obj mesh",
        )
    })?;
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match extension.as_deref() {
        Some("ply") if path.is_file() => run(py, || TriMesh::read_ply(&path)),
        Some("obj") if path.is_file() => run(py, || TriMesh::read_obj(&path)),
        _ => from_sequence(&Sequence::of(run(py, || MeshSequence::read(&path))?)),
    }
}

/// The mesh as the rasterizer takes it, as `tagsplat render-mesh` does.
fn raster_mesh(py: Python<'_>, mesh: TriMesh) -> PyResult<RasterMesh> {
    run(py, || RasterMesh::from_mesh(mesh))
}
