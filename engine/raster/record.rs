//! Recording the forward and backward passes of [`MeshRasterizer`], and reading results back.

use super::kernels::linear_groups;
use super::params::{RasterParams, RasterSettings};
use super::rasterizer::{MeshRasterizer, RasterFrame};
use super::RasterError;
use crate::camera::Camera;
use crate::gpu::{GpuBuffer, PassTimes, Recorder};

/// Loss gradients per vertex, read back.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexGradients {
    /// dL/dposition per vertex (world space).
    pub positions: Vec<[f32; 3]>,
    /// dL/dcolour per vertex.
    pub colors: Vec<[f32; 3]>,
}

impl MeshRasterizer {
    /// Records the forward pass for `params` (from [`Self::params`]): afterwards the colour,
    /// mask, id, barycentric, depth and normal buffers hold this view.
    pub fn record_forward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &RasterParams,
    ) -> Result<(), RasterError> {
        self.record_forward_from(rec, params, &self.mesh.positions)
    }

    /// [`Self::record_forward`] with vertex positions from the caller's buffer (3 floats per
    /// vertex, e.g. the Gaussian positions an optimizer updates), for the same faces. The
    /// backward needs no positions buffer: it reads what this forward transformed.
    pub fn record_forward_from<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &RasterParams,
        positions: &'a GpuBuffer<f32>,
    ) -> Result<(), RasterError> {
        self.check_params(params)?;
        check_len("vertex positions", positions.len(), 3 * self.vertices)?;
        self.record_visibility(rec, params, positions)?;
        self.record_shading(rec, params);
        Ok(())
    }

    /// Clear, transform, outline flags and both raster paths: the visibility buffer.
    fn record_visibility<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &RasterParams,
        positions: &'a GpuBuffer<f32>,
    ) -> Result<(), RasterError> {
        let (m, im, k) = (&self.mesh, &self.image, &self.kernels);
        rec.begin_pass("raster clear");
        rec.fill_buffer(&im.visibility, u32::MAX);
        rec.fill_buffer(&m.counters, 0);
        rec.fill_buffer(&im.tile_counts, 0);
        if params.counts_writes() {
            rec.fill_buffer(&im.write_counts, 0);
        }
        rec.end_pass();
        rec.begin_pass("raster transform");
        rec.dispatch_1d(
            &k.transform,
            &[
                ("positions", positions.binding()),
                ("camera_positions", m.camera_positions.binding()),
            ],
            params,
            linear_groups(self.vertices),
        )?;
        rec.end_pass();
        rec.begin_pass("raster outline");
        let outline = [
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("adjacency", m.adjacency.binding()),
            ("outline_flags", m.outline_flags.binding()),
        ];
        rec.dispatch_1d(&k.outline, &outline, params, linear_groups(self.triangles))?;
        rec.end_pass();
        rec.begin_pass("raster setup + small");
        let setup = [
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("subs", m.subs.binding()),
            ("visibility", im.visibility.binding()),
            ("large_list", m.large.binding()),
            ("counters", m.counters.binding()),
            ("write_counts", im.write_counts.binding()),
            ("tile_counts", im.tile_counts.binding()),
            ("tile_lists", im.tile_lists.binding()),
        ];
        rec.dispatch_1d(&k.setup, &setup, params, linear_groups(self.triangles))?;
        rec.end_pass();
        rec.begin_pass("raster large");
        let large = [
            ("subs", m.subs.binding()),
            ("visibility", im.visibility.binding()),
            ("large_list", m.large.binding()),
            ("counters", m.counters.binding()),
            ("write_counts", im.write_counts.binding()),
            ("tile_counts", im.tile_counts.binding()),
            ("tile_lists", im.tile_lists.binding()),
        ];
        rec.dispatch(&k.raster_large, &large, params, params.tiles());
        rec.end_pass();
        Ok(())
    }

    /// Resolve and anti-aliasing: the images.
    fn record_shading<'a>(&'a self, rec: &mut Recorder<'a>, params: &RasterParams) {
        let (m, im, k) = (&self.mesh, &self.image, &self.kernels);
        rec.begin_pass("raster resolve");
        let resolve = [
            ("visibility", im.visibility.binding()),
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("colors", m.colors.binding()),
            ("ids_out", im.ids.binding()),
            ("barycentrics", im.barycentrics.binding()),
            ("rgba", im.rgba.binding()),
            ("depth", im.depth.binding()),
            ("normals", im.normals.binding()),
        ];
        rec.dispatch(&k.resolve, &resolve, params, params.tiles());
        rec.end_pass();
        rec.begin_pass("raster antialias");
        let pairs = [
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("outline_flags", m.outline_flags.binding()),
            ("ids", im.ids.binding()),
            ("depth", im.depth.binding()),
            ("pairs", im.pairs.binding()),
        ];
        rec.dispatch(&k.aa_pairs, &pairs, params, params.tiles());
        let aa = [
            ("pairs", im.pairs.binding()),
            ("rgba", im.rgba.binding()),
            ("color_out", im.color.binding()),
            ("mask_out", im.mask.binding()),
        ];
        rec.dispatch(&k.aa_forward, &aa, params, params.tiles());
        rec.end_pass();
    }

    /// Records the backward pass of the last forward with the same `params`: from dL/dcolour
    /// (`grad_color`, RGB per pixel, 3 floats each) and dL/dmask (`grad_mask`, one per pixel) of
    /// the anti-aliased image, ADDS dL/dposition and dL/dcolour (3 floats per vertex) to
    /// `grad_positions` and `grad_colors`.
    pub fn record_backward<'a>(
        &'a self,
        rec: &mut Recorder<'a>,
        params: &RasterParams,
        (grad_color, grad_mask): (&'a GpuBuffer<f32>, &'a GpuBuffer<f32>),
        (grad_positions, grad_colors): (&'a GpuBuffer<f32>, &'a GpuBuffer<f32>),
    ) -> Result<(), RasterError> {
        self.check_params(params)?;
        let pixels = self.image.pixels();
        check_len("dL/dcolour image", grad_color.len(), 3 * pixels)?;
        check_len("dL/dmask image", grad_mask.len(), pixels)?;
        check_len("position gradients", grad_positions.len(), 3 * self.vertices)?;
        check_len("colour gradients", grad_colors.len(), 3 * self.vertices)?;
        let (m, im, k) = (&self.mesh, &self.image, &self.kernels);
        rec.begin_pass("raster antialias backward");
        let aa = [
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("pairs", im.pairs.binding()),
            ("rgba", im.rgba.binding()),
            ("grad_color", grad_color.binding()),
            ("grad_mask", grad_mask.binding()),
            ("grad_rgba", im.grad_rgba.binding()),
            ("grad_position_sums", m.grad_position_sums.binding()),
        ];
        rec.dispatch(&k.aa_backward, &aa, params, params.tiles());
        rec.end_pass();
        rec.begin_pass("raster interior backward");
        let interior = [
            ("faces", m.faces.binding()),
            ("camera_positions", m.camera_positions.binding()),
            ("colors", m.colors.binding()),
            ("ids", im.ids.binding()),
            ("grad_rgba", im.grad_rgba.binding()),
            ("grad_position_sums", m.grad_position_sums.binding()),
            ("grad_color_sums", m.grad_color_sums.binding()),
        ];
        rec.dispatch(&k.interior_backward, &interior, params, params.tiles());
        let count = 3 * self.vertices;
        k.resolve_sums.record(rec, &m.grad_position_sums, grad_positions, count)?;
        k.resolve_sums.record(rec, &m.grad_color_sums, grad_colors, count)?;
        rec.end_pass();
        Ok(())
    }

    /// Forward for one camera in its own submission; returns the pass times.
    pub fn render(
        &self,
        camera: &Camera,
        settings: &RasterSettings,
    ) -> Result<PassTimes, RasterError> {
        let params = self.params(camera, settings)?;
        let mut rec = Recorder::new(&self.ctx)?;
        self.record_forward(&mut rec, &params)?;
        Ok(rec.submit_and_wait()?)
    }

    /// Backward of [`Self::render`] with the same camera and settings, in its own submission:
    /// returns dL/dposition and dL/dcolour per vertex from host-side image gradients.
    pub fn gradients(
        &self,
        camera: &Camera,
        settings: &RasterSettings,
        grad_color: &[[f32; 3]],
        grad_mask: &[f32],
    ) -> Result<VertexGradients, RasterError> {
        let params = self.params(camera, settings)?;
        let pixels = self.image.pixels();
        check_len("dL/dcolour image", grad_color.len(), pixels)?;
        let grad_color =
            GpuBuffer::from_slice(&self.ctx, "dL/dcolour", bytemuck::cast_slice(grad_color))?;
        let grad_mask = GpuBuffer::from_slice(&self.ctx, "dL/dmask", grad_mask)?;
        let grad_positions = GpuBuffer::<f32>::new(&self.ctx, "dL/dposition", 3 * self.vertices)?;
        let grad_colors = GpuBuffer::<f32>::new(&self.ctx, "dL/dvertex colour", 3 * self.vertices)?;
        let mut rec = Recorder::new(&self.ctx)?;
        rec.fill_buffer(&grad_positions, 0);
        rec.fill_buffer(&grad_colors, 0);
        self.record_backward(
            &mut rec,
            &params,
            (&grad_color, &grad_mask),
            (&grad_positions, &grad_colors),
        )?;
        rec.submit_and_wait()?;
        let unflat = |v: Vec<f32>| v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(VertexGradients {
            positions: unflat(grad_positions.read()?),
            colors: unflat(grad_colors.read()?),
        })
    }

    /// Reads every image of the last forward.
    pub fn read_frame(&self) -> Result<RasterFrame, RasterError> {
        let im = &self.image;
        let xyz = |v: Vec<[f32; 4]>| v.into_iter().map(|p| [p[0], p[1], p[2]]).collect();
        let color: Vec<f32> = im.color.read()?;
        Ok(RasterFrame {
            width: im.width,
            height: im.height,
            ids: im.ids.read()?,
            barycentrics: xyz(im.barycentrics.read()?),
            resolved: im.rgba.read()?,
            depth: im.depth.read()?,
            normals: xyz(im.normals.read()?),
            color: color.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
            mask: im.mask.read()?,
        })
    }

    /// Covering writes per pixel of the last forward rendered with `count_writes`.
    pub fn read_write_counts(&self) -> Result<Vec<u32>, RasterError> {
        Ok(self.image.write_counts.read()?)
    }

    /// (large sub-triangles, sub-triangles dropped outside the guard band) of the last forward.
    pub fn read_counters(&self) -> Result<[u32; 2], RasterError> {
        let c = self.mesh.counters.read()?;
        Ok([c[0], c[1]])
    }

    /// The anti-aliased colour (RGB per pixel, 3 floats) and mask of the last forward, for a
    /// loss kernel in the same submission.
    pub fn color_image(&self) -> &GpuBuffer<f32> {
        &self.image.color
    }

    /// The anti-aliased mask of the last forward (one float per pixel), for a loss kernel in the
    /// same submission.
    pub fn mask_image(&self) -> &GpuBuffer<f32> {
        &self.image.mask
    }

    fn check_params(&self, params: &RasterParams) -> Result<(), RasterError> {
        let images = (self.image.width, self.image.height);
        if (params.width(), params.height()) != images {
            return Err(RasterError::CameraSize {
                camera: (params.width(), params.height()),
                images,
            });
        }
        if (params.vertices(), params.triangles()) != (self.vertices, self.triangles) {
            return Err(RasterError::Settings("parameters were made for another mesh".into()));
        }
        Ok(())
    }
}

fn check_len(what: &'static str, len: usize, expected: usize) -> Result<(), RasterError> {
    if len != expected {
        return Err(RasterError::Length { what, len, expected });
    }
    Ok(())
}
