//! `tagsplat render-mesh`: one view of a triangle mesh through the differentiable rasterizer:
//! the anti-aliased colour as PNG, optionally the anti-aliased mask and the triangle ids.

use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuContext;
use tagsplat::io::image::{write_png, Image};
use tagsplat::mesh::TriMesh;
use tagsplat::raster::{MeshRasterizer, RasterFrame, RasterMesh, RasterSettings, NO_TRIANGLE};

#[derive(clap::Args)]
pub struct RenderMeshArgs {
    /// Triangle mesh, PLY or OBJ (vertex colours from PLY red/green/blue, else grey).
    #[arg(long)]
    mesh: PathBuf,
    /// Camera JSON: {"width", "height", "fx", "fy", "cx", "cy", "world_to_camera": [16, row-major, OpenCV]}.
    #[arg(long)]
    camera: PathBuf,
    /// Anti-aliased colour (PNG, 8-bit RGB, black background).
    #[arg(long)]
    out: PathBuf,
    /// Anti-aliased coverage mask (PNG, 8-bit grey).
    #[arg(long)]
    mask: Option<PathBuf>,
    /// Triangle ids (PNG, 8-bit RGB: id = R + 256 G + 65536 B - 1, black where nothing was drawn).
    #[arg(long)]
    ids: Option<PathBuf>,
    /// Near clipping depth in scene units (default: 1/1000 of the mesh's bounding-box diagonal).
    #[arg(long)]
    near: Option<f32>,
}

/// The mesh file as the rasterizer takes it; errors name the file.
fn load_mesh(path: &Path) -> Result<RasterMesh> {
    let extension = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let mesh = match extension.as_deref() {
        Some("ply") => TriMesh::read_ply(path)?,
        Some("obj") => TriMesh::read_obj(path)?,
        _ => {
            bail!("{}: not a mesh file this command reads (expected .ply or .obj)", path.display())
        }
    };
    RasterMesh::from_mesh(mesh).with_context(|| format!("{}: unusable mesh", path.display()))
}

pub fn render_mesh(ctx: &Arc<GpuContext>, args: &RenderMeshArgs) -> Result<()> {
    let mesh = load_mesh(&args.mesh)?;
    let camera = Camera::load_json(&args.camera)?;
    let mut settings = RasterSettings::scaled_to(&mesh.positions);
    if let Some(near) = args.near {
        settings.near = near;
    }
    if mesh.faces.len() >= 1 << 24 && args.ids.is_some() {
        bail!(
            "{}: {} triangles do not fit the 24-bit id image",
            args.mesh.display(),
            mesh.faces.len()
        );
    }
    let rasterizer = MeshRasterizer::new(ctx, &mesh, camera.width, camera.height)?;
    rasterizer.render(&camera, &settings)?;
    let frame = rasterizer.read_frame()?;
    let (width, height) = (camera.width, camera.height);
    write_png(
        &args.out,
        &Image {
            width,
            height,
            channels: 3,
            data: frame.color.iter().flatten().copied().collect(),
        },
    )?;
    if let Some(path) = &args.mask {
        write_png(path, &Image { width, height, channels: 1, data: frame.mask.clone() })?;
    }
    if let Some(path) = &args.ids {
        write_png(path, &id_image(&frame))?;
    }
    let covered = frame.ids.iter().filter(|&&t| t != NO_TRIANGLE).count();
    println!(
        "rendered {} triangles to {} ({width}x{height}, {covered} pixels covered)",
        mesh.faces.len(),
        args.out.display()
    );
    Ok(())
}

/// Ids + 1 in 24-bit RGB (so 0 is no triangle), exact in 8-bit channels.
fn id_image(frame: &RasterFrame) -> Image {
    let data = frame
        .ids
        .iter()
        .flat_map(|&t| {
            let code = if t == NO_TRIANGLE { 0 } else { t + 1 };
            [code & 255, (code >> 8) & 255, (code >> 16) & 255].map(|b| b as f32 / 255.0)
        })
        .collect();
    Image { width: frame.width, height: frame.height, channels: 3, data }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes `text` to a fresh file named `name` and returns load_mesh's error for it.
    fn load_error(name: &str, text: &str) -> String {
        let dir = std::env::temp_dir()
            .join(format!("tagsplat-render-mesh-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let error = format!("{:#}", load_mesh(&path).unwrap_err());
        std::fs::remove_dir_all(&dir).unwrap();
        assert!(error.contains(name), "the error must name the file: {error}");
        error
    }

    #[test]
    fn files_that_are_not_triangle_meshes_are_refused_by_name() {
        assert!(load_error("lines.obj", "v 0 0 0\nv 1 0 0\nl 1 2\n").contains("no triangles"));
        assert!(load_error("mesh.stl", "solid x\nendsolid x\n").contains("expected .ply or .obj"));
        assert!(
            load_error("nan.obj", "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").contains("non-finite")
        );
        assert!(load_error("index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
            .contains("past the 3 vertices"));
    }

    #[test]
    fn ids_are_encoded_exactly_in_24_bits() {
        let frame = RasterFrame {
            width: 3,
            height: 1,
            ids: vec![NO_TRIANGLE, 0, 0x12_3456],
            ..Default::default()
        };
        let image = id_image(&frame);
        let bytes: Vec<u32> = image.data.iter().map(|v| (v * 255.0).round() as u32).collect();
        let decode = |p: usize| bytes[3 * p] + 256 * bytes[3 * p + 1] + 65536 * bytes[3 * p + 2];
        assert_eq!([decode(0), decode(1), decode(2)], [0, 1, 0x12_3457]);
    }
}
