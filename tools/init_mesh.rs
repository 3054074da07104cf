//! `tagsplat init-mesh`: the first mesh of a frame from the dataset's masks (visual hull).

use crate::dataset::PixelCentersArg;
use anyhow::{Context, Result};
use std::path::PathBuf;
use tagsplat::dataset::{Dataset, LoadOptions};
use tagsplat::init::{init_mesh, InitOptions};

#[derive(clap::Args)]
pub struct InitMeshArgs {
    /// Dataset folder (own layout, Panoptic or nerfstudio).
    #[arg(long)]
    data: PathBuf,
    /// Frame index.
    #[arg(long, default_value_t = 0)]
    frame: usize,
    /// Output PLY (positions, CCW faces, vertex colours).
    #[arg(long)]
    out: PathBuf,
    /// Wanted vertex count (overrides --edge-pixels).
    #[arg(long)]
    vertices: Option<usize>,
    /// Target edge length of the remeshed surface, pixels of the typical view.
    #[arg(long, default_value_t = InitOptions::default().edge_pixels)]
    edge_pixels: f64,
    /// The most pixels the subject's box diagonal counts when the voxel and edge lengths are
    /// set (a finer capture adds no vertices).
    #[arg(long, default_value_t = InitOptions::default().max_subject_pixels)]
    max_subject_pixels: f64,
    /// Isotropic remeshing rounds (0: keep the marching-tetrahedra mesh).
    #[arg(long, default_value_t = InitOptions::default().remesh_rounds)]
    remesh_rounds: usize,
    /// Views allowed to disagree at a kept point (noisy masks).
    #[arg(long, default_value_t = 0)]
    tolerance: usize,
    /// Voxel width in pixels of the typical view.
    #[arg(long, default_value_t = InitOptions::default().voxel_pixels)]
    voxel_pixels: f64,
    /// Memory budget of the sampled grid, MiB.
    #[arg(long, default_value_t = InitOptions::default().max_grid_bytes >> 20)]
    grid_mib: usize,
    /// Skip vertex colours (no images are read).
    #[arg(long)]
    no_colors: bool,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
    /// Where the dataset's intrinsics put pixel centres (default: the layout's own, see
    /// `tagsplat dataset info`).
    #[arg(long, value_enum)]
    pixel_centers: Option<PixelCentersArg>,
}

pub fn run(a: InitMeshArgs) -> Result<()> {
    let load = LoadOptions { pixel_centers: a.pixel_centers.map(Into::into), scale: None };
    let data = Dataset::load_with(&a.data, &load)
        .with_context(|| format!("cannot load the dataset {}", a.data.display()))?;
    let options = InitOptions {
        tolerance: a.tolerance,
        voxel_pixels: a.voxel_pixels,
        max_grid_bytes: a.grid_mib.saturating_mul(1 << 20),
        vertices: a.vertices,
        edge_pixels: a.edge_pixels,
        max_subject_pixels: a.max_subject_pixels,
        remesh_rounds: a.remesh_rounds,
        colors: !a.no_colors,
        ..InitOptions::default()
    };
    let built = init_mesh(&data, a.frame, &options)
        .with_context(|| format!("init-mesh --data {} --frame {}", a.data.display(), a.frame))?;
    built.mesh.write_ply(&a.out).with_context(|| format!("cannot write {}", a.out.display()))?;
    let r = &built.report;
    if a.json {
        println!("{}", serde_json::to_string_pretty(r)?);
        return Ok(());
    }
    println!(
        "wrote {}: {} vertices, {} faces (closed manifold, one component)",
        a.out.display(),
        r.vertices,
        r.faces
    );
    println!(
        "views {}, pixel {:.4e} scene units, voxel {:.4e} scene units, grid {}×{}×{}",
        r.views, r.pixel, r.voxel, r.grid[0], r.grid[1], r.grid[2]
    );
    println!("remeshed {} → {} vertices at edge length {:.4e} scene units ({} splits, {} collapses, {} flips)", r.extracted_vertices, r.vertices, r.edge_length, r.remesh.splits, r.remesh.collapses, r.remesh.flips);
    println!("mask hole pixels filled {}, cavity samples filled {}, components dropped {}, unseen vertices {}", r.mask_hole_pixels, r.cavity_samples, r.components_dropped, r.unseen_vertices);
    let t = &r.seconds;
    println!("{:.2} s: silhouettes {:.2} s, field + extraction {:.2} s, remeshing {:.2} s, colours {:.2} s", t.total, t.silhouettes, t.extract, t.remesh, t.color);
    Ok(())
}
