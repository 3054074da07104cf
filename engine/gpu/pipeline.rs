//! Compute pipelines from embedded shaders. A pipeline's layout comes from its shader's
//! reflected interface ([`Shader`], built by build.rs), never from numbers written beside it:
//! the storage buffers of set 0 at the bindings the shader declares (pushed per dispatch with
//! VK_KHR_push_descriptor, so there are no descriptor pools to size), and a push-constant range
//! of the shader's block size. This is the contract a kernel's Rust side keeps:
//! - its push-constant struct is the shader's block, asserted at compile time by
//!   `push_layout!` (engine/gpu/shader.rs), and the dispatch checks the size it pushes;
//! - its dispatches name each buffer by the shader's name for that binding (the buffer block's
//!   member, `keys_in` for `buffer KeysIn { uint keys_in[]; }`); a name the shader lacks, or a
//!   binding left out or given twice, panics naming the shader and binding.
//!
//! Specialization constant `i` takes `specialization[i]`; by convention constant 0 is the
//! workgroup size.

use super::context::GpuContext;
use super::error::{GpuError, GpuResult, VkContext};
use super::shader::Shader;
use ash::vk;
use std::sync::Arc;

/// What a compute pipeline is made of.
pub struct PipelineDesc<'a> {
    /// Name for error messages and panics.
    pub name: &'static str,
    /// The shader, from `crate::shaders`.
    pub shader: &'static Shader,
    /// Value of specialization constant `i` at index `i`; constant 0 is the workgroup size by
    /// convention.
    pub specialization: &'a [u32],
}

/// A compute pipeline with its layout, built from a [`Shader`]'s reflected interface.
pub struct ComputePipeline {
    ctx: Arc<GpuContext>,
    pub(crate) pipeline: vk::Pipeline,
    pub(crate) layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    pub(crate) name: &'static str,
    pub(crate) shader: &'static Shader,
}

impl ComputePipeline {
    /// Builds the pipeline (through the context's pipeline cache). Asks for full subgroups where
    /// the device supports them and the workgroup size is a multiple of the largest subgroup size.
    /// Fails with [`GpuError::Pipeline`] when the driver refuses it, or [`GpuError::Vulkan`].
    pub fn new(ctx: &Arc<GpuContext>, desc: &PipelineDesc) -> GpuResult<Self> {
        let device = ctx.device();
        let shader = desc.shader;
        let code = ash::util::read_spv(&mut std::io::Cursor::new(shader.spirv)).map_err(|_| {
            GpuError::Vulkan {
                call: "read_spv (corrupt embedded SPIR-V)",
                result: vk::Result::ERROR_INVALID_SHADER_NV,
            }
        })?;
        let bindings: Vec<_> = shader
            .binding_numbers()
            .into_iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b)
                    .descriptor_type(vk::DescriptorType::STORAGE_BUFFER)
                    .descriptor_count(1)
                    .stage_flags(vk::ShaderStageFlags::COMPUTE)
            })
            .collect();
        let set_layout_info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&bindings);
        // Build bottom-up; `Self`'s Drop destroys whatever was made if a later step fails.
        let mut pipeline = Self {
            ctx: ctx.clone(),
            pipeline: vk::Pipeline::null(),
            layout: vk::PipelineLayout::null(),
            set_layout: vk::DescriptorSetLayout::null(),
            name: desc.name,
            shader,
        };
        pipeline.set_layout =
            unsafe { device.create_descriptor_set_layout(&set_layout_info, None) }
                .during("vkCreateDescriptorSetLayout")?;
        let push_ranges = [vk::PushConstantRange::default()
            .stage_flags(vk::ShaderStageFlags::COMPUTE)
            .size(shader.push_size as u32)];
        let set_layouts = [pipeline.set_layout];
        let mut layout_info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if shader.push_size > 0 {
            layout_info = layout_info.push_constant_ranges(&push_ranges);
        }
        pipeline.layout = unsafe { device.create_pipeline_layout(&layout_info, None) }
            .during("vkCreatePipelineLayout")?;

        let module = unsafe {
            device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&code), None)
        }
        .during("vkCreateShaderModule")?;
        let entries: Vec<_> = (0..desc.specialization.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 })
            .collect();
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(desc.specialization));
        // Subgroup code sizes shared arrays by the subgroup count: ask for full subgroups where
        // the device can promise them (the workgroup size must then be a multiple of the
        // largest subgroup size).
        let limits = ctx.limits();
        let workgroup_size = desc.specialization.first().copied().unwrap_or(1);
        let full = limits.full_subgroups && workgroup_size % limits.max_subgroup_size == 0;
        let flags = if full {
            vk::PipelineShaderStageCreateFlags::REQUIRE_FULL_SUBGROUPS
        } else {
            Default::default()
        };
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .flags(flags)
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(c"main")
            .specialization_info(&specialization);
        let info = vk::ComputePipelineCreateInfo::default().stage(stage).layout(pipeline.layout);
        let created =
            unsafe { device.create_compute_pipelines(ctx.pipeline_cache(), &[info], None) };
        unsafe { device.destroy_shader_module(module, None) };
        pipeline.pipeline =
            created.map_err(|(_, result)| GpuError::Pipeline { name: desc.name, result })?[0];
        Ok(pipeline)
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        self.ctx.settle();
        self.ctx.replays().resource_destroyed();
        let device = self.ctx.device();
        unsafe {
            device.destroy_pipeline(self.pipeline, None);
            device.destroy_pipeline_layout(self.layout, None);
            device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}
