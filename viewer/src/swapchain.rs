//! The window's Vulkan presentation: an instance with the window system's surface extensions
//! (`ash-window`), a device and queue that can present to the surface, the swapchain with its
//! render pass and framebuffers, and egui drawn into it by `egui-ash-renderer`. A frame can be
//! captured from the swapchain image it presents (what the window shows, [`Readback`]), for
//! screenshots.
//!
//! This is a device of its own, apart from the engine's [`engine::vulkan::Context`]: the engine
//! renders (on any device, lavapipe included) and the displayed image is uploaded as an egui
//! texture. On a GPU the copy through the host could be replaced by sharing the engine's image
//! with this device; at the sizes lavapipe renders interactively it costs little.

use ash::vk;
use egui_ash_renderer::allocator::DefaultAllocator;
use egui_ash_renderer::{Options, RenderMode, Renderer};
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use winit::window::Window;

use crate::capture::{Capture, Readback};
use crate::vulkan_failure as fail;

/// What [`Presenter::draw`] did.
pub enum Presented {
    /// The frame was shown (with its capture if one was asked for).
    Shown(Option<Capture>),
    /// The swapchain was out of date and has been recreated: draw the frame again.
    Skipped,
}

/// The swapchain images and what is built on them (recreated when the window changes size).
struct Chain {
    swapchain: vk::SwapchainKHR,
    extent: vk::Extent2D,
    images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    framebuffers: Vec<vk::Framebuffer>,
    /// Signalled when rendering into image `i` is done; presenting it waits on it.
    rendered: Vec<vk::Semaphore>,
}

/// The presentation device, swapchain and egui renderer of one window.
pub struct Presenter {
    // Dropped first: it destroys its pipeline and buffers on `device`.
    egui: Option<Renderer<DefaultAllocator>>,
    _entry: ash::Entry,
    instance: ash::Instance,
    surface_fn: ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    swapchain_fn: ash::khr::swapchain::Device,
    format: vk::SurfaceFormatKHR,
    render_pass: vk::RenderPass,
    pool: vk::CommandPool,
    command: vk::CommandBuffer,
    acquired: vk::Semaphore,
    fence: vk::Fence,
    chain: Option<Chain>,
    /// The surface must be recreated before the next frame (resized, suboptimal).
    stale: bool,
}

impl Presenter {
    /// Presentation for `window`, preferring the physical device named `preferred` (the
    /// engine's) among those that can present to it.
    pub fn new(window: &Window, preferred: Option<&str>) -> Result<Presenter, String> {
        let display = window
            .display_handle()
            .map_err(|e| format!("window presentation: display handle: {e}"))?
            .as_raw();
        let handle = window
            .window_handle()
            .map_err(|e| format!("window presentation: window handle: {e}"))?
            .as_raw();
        // SAFETY: loading the system's Vulkan loader, as the engine does.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| format!("window presentation: no Vulkan loader: {e}"))?;
        let extensions = ash_window::enumerate_required_extensions(display)
            .map_err(fail("surface extensions"))?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"reshift view")
            .api_version(vk::API_VERSION_1_1);
        let info = vk::InstanceCreateInfo::default()
            .application_info(&app)
            .enabled_extension_names(extensions);
        // SAFETY: valid create info; the instance is destroyed in `Drop`.
        let instance =
            unsafe { entry.create_instance(&info, None) }.map_err(fail("create instance"))?;
        let surface_fn = ash::khr::surface::Instance::new(&entry, &instance);
        // SAFETY: the handles come from a live window, which outlives the presenter (the
        // viewer drops the presenter first).
        let surface =
            unsafe { ash_window::create_surface(&entry, &instance, display, handle, None) }
                .map_err(fail("create surface"))?;
        let (physical, family) = choose(&instance, &surface_fn, surface, preferred)?;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let device_extensions = [ash::khr::swapchain::NAME.as_ptr()];
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&device_extensions);
        // SAFETY: `physical` supports the queue family and the swapchain extension.
        let device = unsafe { instance.create_device(physical, &info, None) }
            .map_err(fail("create device"))?;
        // SAFETY: queue 0 of a family the device was created with.
        let queue = unsafe { device.get_device_queue(family, 0) };
        let swapchain_fn = ash::khr::swapchain::Device::new(&instance, &device);
        // SAFETY: a live surface and physical device.
        let formats = unsafe { surface_fn.get_physical_device_surface_formats(physical, surface) }
            .map_err(fail("surface formats"))?;
        let format = pick_format(&formats)?;
        let render_pass = render_pass(&device, format.format)?;
        let pool_info = vk::CommandPoolCreateInfo::default()
            .queue_family_index(family)
            .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER);
        // SAFETY: valid create infos on a live device; all destroyed in `Drop`.
        let (pool, acquired, fence) = unsafe {
            (
                device.create_command_pool(&pool_info, None),
                device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None),
                device.create_fence(&vk::FenceCreateInfo::default(), None),
            )
        };
        let pool = pool.map_err(fail("command pool"))?;
        let (acquired, fence) = (
            acquired.map_err(fail("semaphore"))?,
            fence.map_err(fail("fence"))?,
        );
        let alloc = vk::CommandBufferAllocateInfo::default()
            .command_pool(pool)
            .command_buffer_count(1);
        // SAFETY: one primary buffer from a live pool.
        let command =
            unsafe { device.allocate_command_buffers(&alloc) }.map_err(fail("command buffer"))?[0];
        let srgb = format.format == vk::Format::B8G8R8A8_SRGB
            || format.format == vk::Format::R8G8B8A8_SRGB;
        let egui = Renderer::with_default_allocator(
            &instance,
            physical,
            device.clone(),
            RenderMode::RenderPass(render_pass),
            Options {
                srgb_framebuffer: srgb,
                ..Options::default()
            },
        )
        .map_err(|e| format!("window presentation: egui renderer: {e}"))?;
        let mut presenter = Presenter {
            egui: Some(egui),
            _entry: entry,
            instance,
            surface_fn,
            surface,
            physical,
            device,
            queue,
            swapchain_fn,
            format,
            render_pass,
            pool,
            command,
            acquired,
            fence,
            chain: None,
            stale: true,
        };
        let size = window.inner_size();
        presenter.recreate(size.width, size.height)?;
        Ok(presenter)
    }

    /// The name of the presenting device.
    pub fn device_name(&self) -> String {
        // SAFETY: a live physical device.
        let properties = unsafe { self.instance.get_physical_device_properties(self.physical) };
        properties
            .device_name_as_c_str()
            .map_or_else(|_| "?".into(), |n| n.to_string_lossy().into_owned())
    }

    /// Recreates the swapchain at the next frame (the window changed size).
    pub fn resized(&mut self) {
        self.stale = true;
    }

    /// (Re)creates the swapchain for a `width × height` window.
    fn recreate(&mut self, width: u32, height: u32) -> Result<(), String> {
        // SAFETY: nothing is in flight after the wait; the old chain's objects are destroyed
        // once the new swapchain (created from the old one) exists.
        unsafe {
            self.device.device_wait_idle().map_err(fail("wait idle"))?;
            let caps = self
                .surface_fn
                .get_physical_device_surface_capabilities(self.physical, self.surface)
                .map_err(fail("surface capabilities"))?;
            let extent = if caps.current_extent.width != u32::MAX {
                caps.current_extent
            } else {
                vk::Extent2D {
                    width: width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                    height: height
                        .clamp(caps.min_image_extent.height, caps.max_image_extent.height),
                }
            };
            if !caps
                .supported_usage_flags
                .contains(vk::ImageUsageFlags::TRANSFER_SRC)
            {
                return Err("window presentation: the surface's images cannot be copied from (no screenshots)".into());
            }
            let count = match caps.max_image_count {
                0 => caps.min_image_count + 1,
                max => (caps.min_image_count + 1).min(max),
            };
            let alpha = [
                vk::CompositeAlphaFlagsKHR::OPAQUE,
                vk::CompositeAlphaFlagsKHR::INHERIT,
                vk::CompositeAlphaFlagsKHR::PRE_MULTIPLIED,
                vk::CompositeAlphaFlagsKHR::POST_MULTIPLIED,
            ]
            .into_iter()
            .find(|&a| caps.supported_composite_alpha.contains(a))
            .unwrap_or(vk::CompositeAlphaFlagsKHR::OPAQUE);
            let old = self.chain.take();
            let info = vk::SwapchainCreateInfoKHR::default()
                .surface(self.surface)
                .min_image_count(count)
                .image_format(self.format.format)
                .image_color_space(self.format.color_space)
                .image_extent(extent)
                .image_array_layers(1)
                .image_usage(
                    vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
                )
                .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
                .pre_transform(caps.current_transform)
                .composite_alpha(alpha)
                // FIFO: always supported; on a display it paces frames to its refresh.
                .present_mode(vk::PresentModeKHR::FIFO)
                .clipped(true)
                .old_swapchain(
                    old.as_ref()
                        .map_or(vk::SwapchainKHR::null(), |c| c.swapchain),
                );
            let created = self.swapchain_fn.create_swapchain(&info, None);
            if let Some(old) = old {
                self.destroy_chain(old);
            }
            let swapchain = created.map_err(fail("create swapchain"))?;
            self.chain = Some(self.build_chain(swapchain, extent)?);
        }
        self.stale = false;
        Ok(())
    }

    /// The views, framebuffers and semaphores of a new `swapchain`.
    fn build_chain(
        &self,
        swapchain: vk::SwapchainKHR,
        extent: vk::Extent2D,
    ) -> Result<Chain, String> {
        // SAFETY: a live swapchain of this device; every object is destroyed in `destroy_chain`.
        unsafe {
            let images = self
                .swapchain_fn
                .get_swapchain_images(swapchain)
                .map_err(fail("swapchain images"))?;
            let mut chain = Chain {
                swapchain,
                extent,
                images: images.clone(),
                views: Vec::new(),
                framebuffers: Vec::new(),
                rendered: Vec::new(),
            };
            for image in images {
                let range = vk::ImageSubresourceRange::default()
                    .aspect_mask(vk::ImageAspectFlags::COLOR)
                    .level_count(1)
                    .layer_count(1);
                let info = vk::ImageViewCreateInfo::default()
                    .image(image)
                    .view_type(vk::ImageViewType::TYPE_2D)
                    .format(self.format.format)
                    .subresource_range(range);
                let view = self.device.create_image_view(&info, None);
                let view = view.map_err(fail("image view"))?;
                chain.views.push(view);
                let attachments = [view];
                let info = vk::FramebufferCreateInfo::default()
                    .render_pass(self.render_pass)
                    .attachments(&attachments)
                    .width(extent.width)
                    .height(extent.height)
                    .layers(1);
                let framebuffer = self.device.create_framebuffer(&info, None);
                chain
                    .framebuffers
                    .push(framebuffer.map_err(fail("framebuffer"))?);
                let semaphore = self
                    .device
                    .create_semaphore(&vk::SemaphoreCreateInfo::default(), None);
                chain.rendered.push(semaphore.map_err(fail("semaphore"))?);
            }
            Ok(chain)
        }
    }

    /// Destroys `chain` (nothing of it may be in flight).
    fn destroy_chain(&self, chain: Chain) {
        // SAFETY: the caller waited for the device to be idle.
        unsafe {
            for framebuffer in chain.framebuffers {
                self.device.destroy_framebuffer(framebuffer, None);
            }
            for view in chain.views {
                self.device.destroy_image_view(view, None);
            }
            for semaphore in chain.rendered {
                self.device.destroy_semaphore(semaphore, None);
            }
            self.swapchain_fn.destroy_swapchain(chain.swapchain, None);
        }
    }

    /// Draws egui's `output` (tessellated at `pixels_per_point`) into the next swapchain image
    /// and presents it; with `capture`, the presented pixels are returned too. `size` is the
    /// window's inner size, for a swapchain that must be recreated.
    pub fn draw(
        &mut self,
        textures: &egui::TexturesDelta,
        primitives: &[egui::ClippedPrimitive],
        pixels_per_point: f32,
        capture: bool,
        size: (u32, u32),
    ) -> Result<Presented, String> {
        if self.stale || self.chain.is_none() {
            self.recreate(size.0, size.1)?;
        }
        let egui = self.egui.as_mut().expect("the renderer lives until Drop");
        for (id, deltas) in &textures.set {
            for delta in deltas {
                egui.set_texture(self.queue, self.pool, *id, delta)
                    .map_err(|e| format!("window presentation: texture upload: {e}"))?;
            }
        }
        let chain = self.chain.as_ref().expect("recreated above");
        // SAFETY: a live swapchain; the semaphore is unsignalled (the last submit waited on it
        // and completed).
        let acquired = unsafe {
            self.swapchain_fn.acquire_next_image(
                chain.swapchain,
                u64::MAX,
                self.acquired,
                vk::Fence::null(),
            )
        };
        let index = match acquired {
            Ok((index, _)) => index as usize,
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(Presented::Skipped);
            }
            Err(e) => return Err(fail("acquire image")(e)),
        };
        let (extent, image) = (chain.extent, chain.images[index]);
        let readback = if capture {
            Some(Readback::new(
                &self.instance,
                self.physical,
                &self.device,
                extent,
            )?)
        } else {
            None
        };
        let cmd = self.command;
        // SAFETY: the command buffer is idle (the previous submit was waited for); every
        // handle recorded is live.
        unsafe {
            let begin = vk::CommandBufferBeginInfo::default()
                .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT);
            self.device
                .begin_command_buffer(cmd, &begin)
                .map_err(fail("begin commands"))?;
            let clear = [vk::ClearValue {
                color: vk::ClearColorValue {
                    float32: [0.1, 0.1, 0.1, 1.0],
                },
            }];
            let pass = vk::RenderPassBeginInfo::default()
                .render_pass(self.render_pass)
                .framebuffer(chain.framebuffers[index])
                .render_area(vk::Rect2D {
                    offset: vk::Offset2D::default(),
                    extent,
                })
                .clear_values(&clear);
            self.device
                .cmd_begin_render_pass(cmd, &pass, vk::SubpassContents::INLINE);
            egui.cmd_draw(cmd, extent, pixels_per_point, primitives)
                .map_err(|e| format!("window presentation: egui draw: {e}"))?;
            self.device.cmd_end_render_pass(cmd);
            if let Some(readback) = &readback {
                readback.record(&self.device, cmd, image, extent);
            }
            self.device
                .end_command_buffer(cmd)
                .map_err(fail("end commands"))?;
            let waits = [self.acquired];
            let stages = [vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT];
            let signals = [chain.rendered[index]];
            let commands = [cmd];
            let submit = vk::SubmitInfo::default()
                .wait_semaphores(&waits)
                .wait_dst_stage_mask(&stages)
                .command_buffers(&commands)
                .signal_semaphores(&signals);
            self.device
                .queue_submit(self.queue, &[submit], self.fence)
                .map_err(fail("submit"))?;
            self.device
                .wait_for_fences(&[self.fence], true, u64::MAX)
                .map_err(fail("wait"))?;
            self.device
                .reset_fences(&[self.fence])
                .map_err(fail("reset fence"))?;
        }
        let captured = readback.map(|r| r.finish(&self.device, extent, self.format.format));
        let (swapchains, indices, waits) =
            ([chain.swapchain], [index as u32], [chain.rendered[index]]);
        let present = vk::PresentInfoKHR::default()
            .wait_semaphores(&waits)
            .swapchains(&swapchains)
            .image_indices(&indices);
        // SAFETY: image `index` was acquired and its rendering is signalled on the semaphore.
        match unsafe { self.swapchain_fn.queue_present(self.queue, &present) } {
            Ok(false) => {}
            Ok(true) | Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
            Err(e) => return Err(fail("present")(e)),
        }
        for &id in &textures.free {
            egui.free_texture(id)
                .map_err(|e| format!("window presentation: texture free: {e}"))?;
        }
        Ok(Presented::Shown(captured.transpose()?))
    }
}

impl Drop for Presenter {
    fn drop(&mut self) {
        // SAFETY: after the wait nothing is in flight; children are destroyed before parents.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.egui = None;
            if let Some(chain) = self.chain.take() {
                self.destroy_chain(chain);
            }
            self.device.destroy_fence(self.fence, None);
            self.device.destroy_semaphore(self.acquired, None);
            self.device.destroy_command_pool(self.pool, None);
            self.device.destroy_render_pass(self.render_pass, None);
            self.device.destroy_device(None);
            self.surface_fn.destroy_surface(self.surface, None);
            self.instance.destroy_instance(None);
        }
    }
}

/// The physical device and queue family that present to `surface` with graphics: the one named
/// like `preferred` if it can, else the first that can.
fn choose(
    instance: &ash::Instance,
    surface_fn: &ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    preferred: Option<&str>,
) -> Result<(vk::PhysicalDevice, u32), String> {
    // SAFETY: queries on a live instance and surface.
    unsafe {
        let devices = instance
            .enumerate_physical_devices()
            .map_err(fail("enumerate devices"))?;
        let mut usable = Vec::new();
        for device in devices {
            let families = instance.get_physical_device_queue_family_properties(device);
            let family = (0..families.len() as u32).find(|&i| {
                families[i as usize]
                    .queue_flags
                    .contains(vk::QueueFlags::GRAPHICS)
                    && surface_fn
                        .get_physical_device_surface_support(device, i, surface)
                        .unwrap_or(false)
            });
            if let Some(family) = family {
                let name = instance
                    .get_physical_device_properties(device)
                    .device_name_as_c_str()
                    .map_or_else(|_| String::new(), |n| n.to_string_lossy().into_owned());
                usable.push((device, family, name));
            }
        }
        let named = usable
            .iter()
            .position(|(_, _, name)| preferred.is_some_and(|p| p == name));
        let (device, family, _) = match named {
            Some(i) => usable.swap_remove(i),
            None => usable
                .into_iter()
                .next()
                .ok_or("window presentation: no Vulkan device can present to this window")?,
        };
        Ok((device, family))
    }
}

/// An 8-bit format egui draws into: UNORM preferred (egui's shader encodes sRGB itself).
fn pick_format(formats: &[vk::SurfaceFormatKHR]) -> Result<vk::SurfaceFormatKHR, String> {
    [
        vk::Format::B8G8R8A8_UNORM,
        vk::Format::R8G8B8A8_UNORM,
        vk::Format::B8G8R8A8_SRGB,
        vk::Format::R8G8B8A8_SRGB,
    ]
    .into_iter()
    .find_map(|wanted| formats.iter().find(|f| f.format == wanted).copied())
    .ok_or_else(|| format!("window presentation: no 8-bit RGBA surface format among {formats:?}"))
}

/// A render pass of one colour attachment, cleared, left ready to present.
fn render_pass(device: &ash::Device, format: vk::Format) -> Result<vk::RenderPass, String> {
    let attachments = [vk::AttachmentDescription::default()
        .format(format)
        .samples(vk::SampleCountFlags::TYPE_1)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .initial_layout(vk::ImageLayout::UNDEFINED)
        .final_layout(vk::ImageLayout::PRESENT_SRC_KHR)];
    let colour = [vk::AttachmentReference::default()
        .attachment(0)
        .layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)];
    let subpasses = [vk::SubpassDescription::default()
        .pipeline_bind_point(vk::PipelineBindPoint::GRAPHICS)
        .color_attachments(&colour)];
    let dependencies = [vk::SubpassDependency::default()
        .src_subpass(vk::SUBPASS_EXTERNAL)
        .dst_subpass(0)
        .src_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .dst_stage_mask(vk::PipelineStageFlags::COLOR_ATTACHMENT_OUTPUT)
        .dst_access_mask(vk::AccessFlags::COLOR_ATTACHMENT_WRITE)];
    let info = vk::RenderPassCreateInfo::default()
        .attachments(&attachments)
        .subpasses(&subpasses)
        .dependencies(&dependencies);
    // SAFETY: a valid create info on a live device; destroyed in `Presenter::drop`.
    unsafe { device.create_render_pass(&info, None) }.map_err(fail("render pass"))
}
