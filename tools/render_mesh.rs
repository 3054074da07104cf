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
        _ => bail!("{}: not a mesh file this command reads (expected .ply or .obj)", path.display()),
    };
    if mesh.faces.is_empty() {
        bail!("{}: has no triangles (faces) to render", path.display());
    }
    let colors = match &mesh.colors {
        Some(colors) => colors.iter().map(|c| c.map(|v| v as f32 / 255.0)).collect(),
        None => vec![[0.8; 3]; mesh.positions.len()],
    };
    RasterMesh::new(mesh.positions, mesh.faces, colors).with_context(|| format!("{}: unusable mesh", path.display()))
}

pub fn render_mesh(ctx: &Arc<GpuContext>, args: &RenderMeshArgs) -> Result<()> {
    let mesh = load_mesh(&args.mesh)?;
    let camera = Camera::load_json(&args.camera)?;
    let mut settings = RasterSettings::scaled_to(&mesh.positions);
    if let Some(near) = args.near {
        settings.near = near;
    }
    if mesh.faces.len() >= 1 << 24 && args.ids.is_some() {
        bail!("{}: {} triangles do not fit the 24-bit id image", args.mesh.display(), mesh.faces.len());
    }
    let rasterizer = MeshRasterizer::new(ctx, &mesh, camera.width, camera.height)?;
    rasterizer.render(&camera, &settings)?;
    let frame = rasterizer.read_frame()?;
    let (width, height) = (camera.width, camera.height);
    write_png(&args.out, &Image { width, height, channels: 3, data: frame.color.iter().flatten().copied().collect() })?;
    if let Some(path) = &args.mask {
        write_png(path, &Image { width, height, channels: 1, data: frame.mask.clone() })?;
    }
    if let Some(path) = &args.ids {
        write_png(path, &id_image(&frame))?;
    }
    let covered = frame.ids.iter().filter(|&&t| t != NO_TRIANGLE).count();
    println!("rendered {} triangles to {} ({width}x{height}, {covered} pixels covered)", mesh.faces.len(), args.out.display());
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
