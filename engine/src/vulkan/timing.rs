//! GPU timestamps around the passes of a recorded frame: one query before and one after each
//! pass, read after the frame's fence.

use std::sync::Arc;

use ash::vk;

use super::device::{Context, Shared};
use super::error::{VulkanError, api};

/// A timestamp query pool with two queries per timed section.
pub(crate) struct Timestamps {
    shared: Arc<Shared>,
    pool: vk::QueryPool,
    sections: u32,
    /// Nanoseconds per tick.
    period: f64,
}

impl Timestamps {
    /// A pool for `sections` timed sections, or `None` when the queue writes no timestamps.
    pub(crate) fn new(context: &Context, sections: u32) -> Result<Option<Timestamps>, VulkanError> {
        let Some(period) = context.timestamp_period else {
            return Ok(None);
        };
        let info = vk::QueryPoolCreateInfo::default()
            .query_type(vk::QueryType::TIMESTAMP)
            .query_count(2 * sections.max(1));
        // SAFETY: valid create info on a live device.
        let pool = unsafe { context.shared.device.create_query_pool(&info, None) }
            .map_err(api("vkCreateQueryPool"))?;
        Ok(Some(Timestamps {
            shared: context.shared.clone(),
            pool,
            sections,
            period,
        }))
    }

    /// Records the reset of every query (before the first section of a submission).
    pub(crate) fn reset(&self, cb: vk::CommandBuffer) {
        // SAFETY: `cb` is recording; the range is the pool's.
        unsafe {
            self.shared
                .device
                .cmd_reset_query_pool(cb, self.pool, 0, 2 * self.sections.max(1))
        };
    }

    /// Records the timestamp before section `i`.
    pub(crate) fn begin(&self, cb: vk::CommandBuffer, i: u32) {
        // SAFETY: `cb` is recording; the query was reset in it.
        unsafe {
            self.shared.device.cmd_write_timestamp(
                cb,
                vk::PipelineStageFlags::TOP_OF_PIPE,
                self.pool,
                2 * i,
            )
        };
    }

    /// Records the timestamp after section `i`.
    pub(crate) fn end(&self, cb: vk::CommandBuffer, i: u32) {
        // SAFETY: as `begin`.
        unsafe {
            self.shared.device.cmd_write_timestamp(
                cb,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                self.pool,
                2 * i + 1,
            )
        };
    }

    /// Seconds of each section of the last completed submission.
    pub(crate) fn seconds(&self) -> Result<Vec<f64>, VulkanError> {
        let mut ticks = vec![0u64; 2 * self.sections as usize];
        // SAFETY: the submission that wrote the queries was waited on.
        unsafe {
            self.shared.device.get_query_pool_results(
                self.pool,
                0,
                &mut ticks,
                vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
            )
        }
        .map_err(api("vkGetQueryPoolResults"))?;
        Ok(ticks
            .chunks_exact(2)
            .map(|t| t[1].wrapping_sub(t[0]) as f64 * self.period * 1e-9)
            .collect())
    }
}

impl Drop for Timestamps {
    fn drop(&mut self) {
        // SAFETY: submissions using the pool were waited on.
        unsafe { self.shared.device.destroy_query_pool(self.pool, None) };
    }
}
