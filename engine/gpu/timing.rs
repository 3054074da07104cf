//! GPU timestamps around named passes. Query pools grow in chunks as passes are recorded, so
//! there is no fixed cap on the number of passes.

use super::context::GpuContext;
use super::error::{GpuResult, VkContext};
use ash::vk;

const QUERIES_PER_POOL: u32 = 128;

/// The GPU time of one recorded pass.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PassTime {
    /// The name given to [`Recorder::begin_pass`](super::Recorder::begin_pass).
    pub name: String,
    /// GPU time between the pass's begin and end, in milliseconds.
    pub ms: f64,
    /// Nesting level: 0 for a top-level pass, 1 inside one, …
    pub depth: u32,
}

/// The pass times of one submission, in the order the passes began.
#[derive(Clone, Debug, Default)]
pub struct PassTimes {
    /// One entry per timed pass; empty where the queue cannot write timestamps.
    pub passes: Vec<PassTime>,
}

pub(crate) struct Timestamps {
    period_ns: Option<f64>,
    valid_mask: u64,
    pools: Vec<vk::QueryPool>,
    used: u32,
    /// (name, depth, start query, end query) per pass; a query is `None` where no timestamp
    /// could be written, and that pass goes untimed (begins and ends still pair up).
    passes: Vec<(String, u32, Option<u32>, Option<u32>)>,
    open: Vec<usize>,
    /// Queries at the submission's first and last command (its device span).
    span: [Option<u32>; 2],
}

impl Timestamps {
    pub(crate) fn new(ctx: &GpuContext) -> Self {
        let bits = ctx.limits().timestamp_valid_bits;
        Self {
            period_ns: ctx.limits().timestamp_period_ns,
            valid_mask: if bits >= 64 { u64::MAX } else { (1u64 << bits) - 1 },
            pools: Vec::new(),
            used: 0,
            passes: Vec::new(),
            open: Vec::new(),
            span: [None, None],
        }
    }

    /// Marks the submission's first (`end` false) or last command for its device span.
    pub(crate) fn mark_span(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, end: bool) {
        self.span[end as usize] = self.write(device, cmd);
    }

    pub(crate) fn begin(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, name: &str) {
        let start = self.write(device, cmd);
        let depth = self.open.len() as u32;
        self.open.push(self.passes.len());
        self.passes.push((name.to_string(), depth, start, None));
    }

    pub(crate) fn end(&mut self, device: &ash::Device, cmd: vk::CommandBuffer) {
        let Some(pass) = self.open.pop() else { return };
        self.passes[pass].3 = self.write(device, cmd);
    }

    /// Writes one timestamp once all earlier commands are done; `None` without timestamps.
    fn write(&mut self, device: &ash::Device, cmd: vk::CommandBuffer) -> Option<u32> {
        self.period_ns?;
        if self.used == self.pools.len() as u32 * QUERIES_PER_POOL {
            let info = vk::QueryPoolCreateInfo::default()
                .query_type(vk::QueryType::TIMESTAMP)
                .query_count(QUERIES_PER_POOL);
            // Without a pool the pass simply goes untimed.
            let pool = unsafe { device.create_query_pool(&info, None) }.ok()?;
            unsafe { device.cmd_reset_query_pool(cmd, pool, 0, QUERIES_PER_POOL) };
            self.pools.push(pool);
        }
        let query = self.used;
        let pool = self.pools[(query / QUERIES_PER_POOL) as usize];
        unsafe {
            device.cmd_write_timestamp(
                cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                pool,
                query % QUERIES_PER_POOL,
            )
        };
        self.used += 1;
        Some(query)
    }

    /// Reads the timestamps of a finished submission: its passes, and its device span in ms
    /// (None without timestamps).
    pub(crate) fn read(&self, device: &ash::Device) -> GpuResult<(PassTimes, Option<f64>)> {
        let Some(period_ns) = self.period_ns else { return Ok((PassTimes::default(), None)) };
        let mut ticks = vec![0u64; self.used as usize];
        for (i, chunk) in ticks.chunks_mut(QUERIES_PER_POOL as usize).enumerate() {
            unsafe {
                device.get_query_pool_results(
                    self.pools[i],
                    0,
                    chunk,
                    vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
                )
            }
            .during("vkGetQueryPoolResults")?;
        }
        let ms = |start: Option<u32>, end: Option<u32>| {
            let elapsed =
                ticks[end? as usize].wrapping_sub(ticks[start? as usize]) & self.valid_mask;
            Some(elapsed as f64 * period_ns * 1e-6)
        };
        let passes = self
            .passes
            .iter()
            .filter_map(|(name, depth, start, end)| {
                Some(PassTime { name: name.clone(), ms: ms(*start, *end)?, depth: *depth })
            })
            .collect();
        Ok((PassTimes { passes }, ms(self.span[0], self.span[1])))
    }

    pub(crate) fn destroy(&mut self, device: &ash::Device) {
        for pool in self.pools.drain(..) {
            unsafe { device.destroy_query_pool(pool, None) };
        }
    }
}
