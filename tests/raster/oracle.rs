//! The independent oracle for triangle ids: Vulkan's fixed-function rasterizer on the same
//! device (vertex + fragment shader writing the triangle id into an R32_SFLOAT image, depth test
//! LESS, so equal depths keep the first-drawn = lower id, as the visibility buffer does).
//!
//! The draw runs in a child process (this test binary again, its ignored test
//! `graphics_pipeline_oracle_child`) at llvmpipe's default vector width: Mesa 22.3's llvmpipe
//! graphics path corrupts the heap now and then at 128-bit vectors (`LP_NATIVE_VECTOR_WIDTH=128`,
//! the subgroup-size-4 run), which aborts the whole test binary. Measured on this oracle's
//! draws, 20 per run: 9 aborts in 80 runs of the pixel-centre grid with large cells and 1 in 80 of
//! the sphere with clutter at 128 bits, none in 300 runs of every case at 256 bits; padding the
//! attachments to whole 64-pixel tiles did not help. With an R32_UINT attachment it was worse
//! (22 aborts in 150 runs of five draws), hence the float ids.

use ash::vk;
use glam::DVec3;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;
use tagsplat::camera::Camera;
use tagsplat::gpu::GpuContext;
use tagsplat::shaders;

const COLOR_FORMAT: vk::Format = vk::Format::R32_SFLOAT;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// Clip-space corners (3 per face) for camera-space `cam`: Vulkan NDC y points down like
/// OpenCV's y, depth f (z − n) / (z (f − n)) clips at z = near.
fn clip_positions(cam: &[DVec3], faces: &[[u32; 3]], camera: &Camera, near: f64) -> Vec<[f32; 4]> {
    let far = near * 1e5;
    let (w, h) = (camera.width as f64, camera.height as f64);
    faces
        .iter()
        .flat_map(|f| f.iter().map(|&k| cam[k as usize]))
        .map(|c| {
            let x = (2.0 * camera.fx * c.x + (2.0 * camera.cx - w) * c.z) / w;
            let y = (2.0 * camera.fy * c.y + (2.0 * camera.cy - h) * c.z) / h;
            let z = far * (c.z - near) / (far - near);
            [x as f32, y as f32, z as f32, c.z as f32]
        })
        .collect()
}

struct Owned {
    ctx: Arc<GpuContext>,
    buffers: Vec<vk::Buffer>,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    allocations: Vec<Allocation>,
    modules: Vec<vk::ShaderModule>,
    render_pass: vk::RenderPass,
    framebuffer: vk::Framebuffer,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    pool: vk::CommandPool,
    fence: vk::Fence,
}

impl Drop for Owned {
    fn drop(&mut self) {
        let d = self.ctx.device();
        unsafe {
            let _ = d.device_wait_idle();
            d.destroy_fence(self.fence, None);
            d.destroy_command_pool(self.pool, None);
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_framebuffer(self.framebuffer, None);
            d.destroy_render_pass(self.render_pass, None);
            self.modules.iter().for_each(|&m| d.destroy_shader_module(m, None));
            self.views.iter().for_each(|&v| d.destroy_image_view(v, None));
            self.images.iter().for_each(|&i| d.destroy_image(i, None));
            self.buffers.iter().for_each(|&b| d.destroy_buffer(b, None));
        }
        let mut allocator = self.ctx.allocator();
        for a in self.allocations.drain(..) {
            allocator.as_mut().unwrap().free(a).unwrap();
        }
    }
}

impl Owned {
    fn allocate(
        &mut self,
        name: &str,
        requirements: vk::MemoryRequirements,
        location: MemoryLocation,
        linear: bool,
    ) -> (vk::DeviceMemory, u64) {
        let desc = AllocationCreateDesc {
            name,
            requirements,
            location,
            linear,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        };
        let allocation = self.ctx.allocator().as_mut().unwrap().allocate(&desc).unwrap();
        let bound = (unsafe { allocation.memory() }, allocation.offset());
        self.allocations.push(allocation);
        bound
    }

    fn buffer(
        &mut self,
        name: &str,
        bytes: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> vk::Buffer {
        let d = self.ctx.device().clone();
        let info = vk::BufferCreateInfo::default().size(bytes.max(16)).usage(usage);
        let buffer = unsafe { d.create_buffer(&info, None) }.unwrap();
        self.buffers.push(buffer);
        let (memory, offset) = self.allocate(
            name,
            unsafe { d.get_buffer_memory_requirements(buffer) },
            location,
            true,
        );
        unsafe { d.bind_buffer_memory(buffer, memory, offset) }.unwrap();
        buffer
    }

    fn image(
        &mut self,
        name: &str,
        format: vk::Format,
        usage: vk::ImageUsageFlags,
        aspect: vk::ImageAspectFlags,
        (w, h): (u32, u32),
    ) -> vk::ImageView {
        let d = self.ctx.device().clone();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: w, height: h, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(usage)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        let image = unsafe { d.create_image(&info, None) }.unwrap();
        self.images.push(image);
        let (memory, offset) = self.allocate(
            name,
            unsafe { d.get_image_memory_requirements(image) },
            MemoryLocation::GpuOnly,
            false,
        );
        unsafe { d.bind_image_memory(image, memory, offset) }.unwrap();
        let range = vk::ImageSubresourceRange {
            aspect_mask: aspect,
            base_mip_level: 0,
            level_count: 1,
            base_array_layer: 0,
            layer_count: 1,
        };
        let view_info = vk::ImageViewCreateInfo::default()
            .image(image)
            .view_type(vk::ImageViewType::TYPE_2D)
            .format(format)
            .subresource_range(range);
        let view = unsafe { d.create_image_view(&view_info, None) }.unwrap();
        self.views.push(view);
        view
    }

    fn mapped<T: bytemuck::Pod>(&self, allocation: usize) -> *mut T {
        self.allocations[allocation].mapped_ptr().unwrap().as_ptr() as *mut T
    }
}

fn render_pass(d: &ash::Device) -> vk::RenderPass {
    let attachments = [
        vk::AttachmentDescription::default()
            .format(COLOR_FORMAT)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
        vk::AttachmentDescription::default()
            .format(DEPTH_FORMAT)
            .samples(vk::SampleCountFlags::TYPE_1)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .initial_layout(vk::ImageLayout::UNDEFINED)
            .final_layout(vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL),
    ];
    let color_ref = [vk::AttachmentReference {
        attachment: 0,
        layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    }];
    let depth_ref = vk::AttachmentReference {
        attachment: 1,
        layout: vk::ImageLayout::DEPTH_STENCIL_ATTACHMENT_OPTIMAL,
    };
    let subpass = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&color_ref)
        .depth_stencil_attachment(&depth_ref)];
    // The copy after the pass reads what the colour attachment wrote.
    let dependencies = [vk::SubpassDependency::default()
        .src_subpass(0)
        .dst_subpass(vk::SUBPASS_EXTERNAL)
        .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .dst_stage_mask(vk::PipelineStageFlags::TRANSFER)
        .src_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)
        .dst_access_mask(vk::AccessFlags::TRANSFER_READ)];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpass)
        .dependencies(&dependencies);
    unsafe { d.create_render_pass(&info, None) }.unwrap()
}

fn pipeline(d: &ash::Device, owned: &mut Owned, (w, h): (u32, u32)) -> vk::Pipeline {
    let module = |spirv: &[u8]| {
        let code = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).unwrap();
        unsafe { d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None) }
            .unwrap()
    };
    let (vert, frag) = (
        module(shaders::RASTER_ORACLE_IDS_VERT.spirv),
        module(shaders::RASTER_ORACLE_IDS_FRAG.spirv),
    );
    owned.modules.extend([vert, frag]);
    let stages = [
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vert)
            .name(c"main"),
        vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::FRAGMENT)
            .module(frag)
            .name(c"main"),
    ];
    let bindings = [vk::VertexInputBindingDescription {
        binding: 0,
        stride: 16,
        input_rate: vk::VertexInputRate::VERTEX,
    }];
    let attributes = [vk::VertexInputAttributeDescription {
        location: 0,
        binding: 0,
        format: vk::Format::R32G32B32A32_SFLOAT,
        offset: 0,
    }];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
        .vertex_binding_descriptions(&bindings)
        .vertex_attribute_descriptions(&attributes);
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
        .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewports = [vk::Viewport {
        x: 0.0,
        y: 0.0,
        width: w as f32,
        height: h as f32,
        min_depth: 0.0,
        max_depth: 1.0,
    }];
    let scissors = [vk::Rect2D {
        offset: vk::Offset2D { x: 0, y: 0 },
        extent: vk::Extent2D { width: w, height: h },
    }];
    let viewport =
        vk::PipelineViewportStateCreateInfo::default().viewports(&viewports).scissors(&scissors);
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0);
    let multisample = vk::PipelineMultisampleStateCreateInfo::default()
        .rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(true)
        .depth_compare_op(vk::CompareOp::LESS);
    let blend_attachments = [vk::PipelineColorBlendAttachmentState::default()
        .color_write_mask(vk::ColorComponentFlags::R)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    owned.layout =
        unsafe { d.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default(), None) }
            .unwrap();
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .layout(owned.layout)
        .render_pass(owned.render_pass)
        .subpass(0);
    unsafe { d.create_graphics_pipelines(vk::PipelineCache::null(), &[info], None) }
        .map_err(|(_, e)| e)
        .unwrap()[0]
}

/// Names the job folder of a child process.
const JOB_VARIABLE: &str = "TAGSPLAT_RASTER_ORACLE_JOB";

/// Triangle id per pixel (`u32::MAX` where nothing was drawn) for camera-space vertices `cam`,
/// drawn by a child process (see the module doc).
pub fn triangle_ids(cam: &[DVec3], faces: &[[u32; 3]], camera: &Camera, near: f64) -> Vec<u32> {
    assert!(faces.len() < 1 << 24, "float ids are exact below 2^24 faces");
    static JOBS: AtomicUsize = AtomicUsize::new(0);
    let job = std::env::temp_dir().join(format!(
        "tagsplat-raster-oracle-{}-{}",
        std::process::id(),
        JOBS.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&job).unwrap();
    let corners = clip_positions(cam, faces, camera, near);
    let mut input = bytemuck::cast_slice(&[camera.width, camera.height]).to_vec();
    input.extend_from_slice(bytemuck::cast_slice(&corners));
    std::fs::write(job.join("input"), input).unwrap();
    let output = std::process::Command::new(std::env::current_exe().unwrap())
        .args(["graphics_pipeline_oracle_child", "--exact", "--ignored", "--nocapture"])
        .env(JOB_VARIABLE, &job)
        .env_remove("LP_NATIVE_VECTOR_WIDTH")
        .output()
        .unwrap();
    assert!(
        output.status.success(),
        "the oracle's child process failed ({}):\n{}{}",
        output.status,
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    let ids = bytemuck::pod_collect_to_vec(&std::fs::read(job.join("ids")).unwrap());
    std::fs::remove_dir_all(&job).unwrap();
    assert_eq!(ids.len(), camera.width as usize * camera.height as usize);
    ids
}

/// The child's side: reads the job the environment names, draws it on a validated context,
/// writes the ids. Panics when run other than by [`triangle_ids`].
pub fn serve_child() {
    let job = std::env::var_os(JOB_VARIABLE)
        .expect("only oracle::triangle_ids runs this, with the job folder in the environment");
    let job = std::path::PathBuf::from(job);
    let input = std::fs::read(job.join("input")).unwrap();
    let (size, corners) = input.split_at(8);
    let size: [u32; 2] = bytemuck::pod_read_unaligned(size);
    let corners: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(corners);
    let gpu = crate::common::gpu();
    let ids = draw_ids(gpu.ctx(), &corners, (size[0], size[1]));
    std::fs::write(job.join("ids"), bytemuck::cast_slice(&ids)).unwrap();
}

/// Draws clip-space `corners` (three per triangle) into a `size` image: the id per pixel.
fn draw_ids(ctx: &Arc<GpuContext>, corners: &[[f32; 4]], size: (u32, u32)) -> Vec<u32> {
    let d = ctx.device().clone();
    let pixels = size.0 as usize * size.1 as usize;
    let mut owned = Owned {
        ctx: ctx.clone(),
        buffers: Vec::new(),
        images: Vec::new(),
        views: Vec::new(),
        allocations: Vec::new(),
        modules: Vec::new(),
        render_pass: render_pass(&d),
        framebuffer: vk::Framebuffer::null(),
        layout: vk::PipelineLayout::null(),
        pipeline: vk::Pipeline::null(),
        pool: vk::CommandPool::null(),
        fence: vk::Fence::null(),
    };
    let vertex_buffer = owned.buffer(
        "oracle vertices",
        (corners.len() * 16) as u64,
        vk::BufferUsageFlags::VERTEX_BUFFER,
        MemoryLocation::CpuToGpu,
    );
    let corner_bytes: &[u8] = bytemuck::cast_slice(corners);
    unsafe {
        std::ptr::copy_nonoverlapping(
            corner_bytes.as_ptr(),
            owned.mapped::<u8>(0),
            corner_bytes.len(),
        )
    };
    let readback = owned.buffer(
        "oracle readback",
        (pixels * 4) as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        MemoryLocation::GpuToCpu,
    );
    let color_usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC;
    let color_view =
        owned.image("oracle ids", COLOR_FORMAT, color_usage, vk::ImageAspectFlags::COLOR, size);
    let depth_view = owned.image(
        "oracle depth",
        DEPTH_FORMAT,
        vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT,
        vk::ImageAspectFlags::DEPTH,
        size,
    );
    let views = [color_view, depth_view];
    let fb_info = vk::FramebufferCreateInfo::default()
        .render_pass(owned.render_pass)
        .attachments(&views)
        .width(size.0)
        .height(size.1)
        .layers(1);
    owned.framebuffer = unsafe { d.create_framebuffer(&fb_info, None) }.unwrap();
    owned.pipeline = pipeline(&d, &mut owned, size);
    let pool_info = vk::CommandPoolCreateInfo::default().queue_family_index(ctx.queue_family());
    owned.pool = unsafe { d.create_command_pool(&pool_info, None) }.unwrap();
    owned.fence = unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) }.unwrap();
    let cmd_info = vk::CommandBufferAllocateInfo::default()
        .command_pool(owned.pool)
        .level(vk::CommandBufferLevel::PRIMARY)
        .command_buffer_count(1);
    let cmd = unsafe { d.allocate_command_buffers(&cmd_info) }.unwrap()[0];
    unsafe {
        d.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
        let clears = [
            vk::ClearValue { color: vk::ClearColorValue { float32: [-1.0; 4] } },
            vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
        ];
        let area = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent: vk::Extent2D { width: size.0, height: size.1 },
        };
        let begin = vk::RenderPassBeginInfo::default()
            .render_pass(owned.render_pass)
            .framebuffer(owned.framebuffer)
            .render_area(area)
            .clear_values(&clears);
        d.cmd_begin_render_pass(cmd, &begin, vk::SubpassContents::INLINE);
        if !corners.is_empty() {
            d.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, owned.pipeline);
            d.cmd_bind_vertex_buffers(cmd, 0, &[vertex_buffer], &[0]);
            d.cmd_draw(cmd, corners.len() as u32, 1, 0, 0);
        }
        d.cmd_end_render_pass(cmd);
        let layers = vk::ImageSubresourceLayers {
            aspect_mask: vk::ImageAspectFlags::COLOR,
            mip_level: 0,
            base_array_layer: 0,
            layer_count: 1,
        };
        let region = vk::BufferImageCopy::default()
            .image_subresource(layers)
            .image_extent(vk::Extent3D { width: size.0, height: size.1, depth: 1 });
        d.cmd_copy_image_to_buffer(
            cmd,
            owned.images[0],
            vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
            readback,
            &[region],
        );
        let to_host = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
            .dst_access_mask(vk::AccessFlags::HOST_READ);
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &[to_host],
            &[],
            &[],
        );
        d.end_command_buffer(cmd).unwrap();
        let cmds = [cmd];
        let submit = vk::SubmitInfo::default().command_buffers(&cmds);
        d.queue_submit(*ctx.queue(), &[submit], owned.fence).unwrap();
        d.wait_for_fences(&[owned.fence], true, u64::MAX).unwrap();
    }
    let mut ids = vec![0f32; pixels];
    unsafe { std::ptr::copy_nonoverlapping(owned.mapped::<f32>(1), ids.as_mut_ptr(), pixels) };
    // The clear value −1 marks pixels nothing was drawn on.
    ids.iter().map(|&v| if v < 0.0 { u32::MAX } else { v as u32 }).collect()
}
