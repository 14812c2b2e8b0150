use bytemuck::{Pod, Zeroable};

twin::contract! {
    /// Hits per BSSRDF probe that the pass and path-tracer kernels keep (their `BVH_MAX_HITS`).
    /// The CPU keeps every hit; a probe with more fails a run with `VulkanError::TooManyHits`
    /// (passes) or leaves its sample out (path tracer).
    pub const KEPT_HITS: usize = 16;

    /// The diag `w` of a pixel whose loops the device cut short (`restir/glsl/loop_budget.glsl`).
    pub const LOOP_BUDGET_CUT: u32 = 0xFF;
    /// The diag `w` of a pixel with a BSSRDF probe of more than `KEPT_HITS` hits.
    pub const HIT_OVERFLOW: u32 = 0xFE;

    /// Reprojection checks of temporal reuse: the previous pixel must show the same object at a
    /// view depth within this relative tolerance of x1's, ...
    pub const TEMPORAL_DEPTH_TOLERANCE: f32 = 0.1;
    /// ... with geometric normals at least this aligned.
    pub const TEMPORAL_NORMAL_COSINE: f32 = 0.9;

    /// `GpuMaterial::kind`.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum MaterialKind in MATERIAL {
        /// Only `albedo` is set.
        Lambert,
        /// `Translucent` with its derived values.
        Translucent,
    }

    /// What a pixel sent its partner of one slot of a reciprocal spatial pass
    /// (`engine::reciprocal::Exchanged`; `engine/glsl/include/exchange.glsl`). A failed shift's
    /// status carries its `SHIFT_FAIL_*` code in bits 8–15.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum ExchangeStatus in EXCHANGE {
        Untaken,
        Unshifted,
        Sent,
        Failed,
    }

    /// `GpuLight::kind`.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum LightKind in LIGHT {
        Quad,
        Triangle,
        Sphere,
        Point,
        Directional,
    }

    /// The path tracer's `sss::integrator::pt::HitPolicy` as the kernels read it (`sss/glsl/pt.glsl`:
    /// `method_pt`'s and `method_single_scatter`'s push constants, the shade pass's opaque pixels).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum PtHits in PT_HITS {
        UniformOne,
        All,
    }

    /// One global triangle id: vertices, per-vertex shading normals and the object id
    /// (`geometry::Geometry`), binding 4 of the scene.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuTriangle {
        pub v: [f32; 9],
        pub n: [f32; 9],
        pub object: u32,
    }

    /// A material, binding 6 of the scene. Derived values are computed on the host in `f32`
    /// exactly as `Translucent::d`, `r_max` and `r_max_all` compute them, so the GPU never
    /// re-derives them with its own transcendentals. For a Lambert material only `kind`,
    /// `albedo`, `emission` and `two_sided` are set.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuMaterial {
        /// A `MaterialKind` code.
        pub kind: u32,
        /// Surface albedo A (translucent) or diffuse reflectance (Lambert) per channel.
        pub albedo: [f32; 3],
        /// `Translucent::d`: Burley d per channel [004 Eq. 5].
        pub d: [f32; 3],
        /// `Translucent::r_max` per channel.
        pub r_max: [f32; 3],
        /// `Translucent::r_max_all` = max of `r_max`.
        pub r_max_all: f32,
        pub ior: f32,
        /// Henyey–Greenstein g (random walk).
        pub g: f32,
        /// κ_dist = 2 · max d, the hybrid shift's distance criterion [001 §5.1].
        pub kappa_dist: f32,
        /// `Translucent::fresnel().normalization`, `1 − F_dr(ior)` (computed with logarithms on
        /// the host).
        pub fresnel_normalization: f32,
        /// `Lambert::emission` (zero for other materials).
        pub emission: [f32; 3],
        /// `Lambert::two_sided` (1: the back face emits too).
        pub two_sided: u32,
    }

    /// One `sss::scene::Light` with its selection CDF value and pmf, binding 7 of the scene.
    /// Points by kind: quad (corner, edge_u, edge_v), triangle (vertices), sphere (centre),
    /// point (position), directional (direction); `emission` is the radiance, intensity or
    /// irradiance; `two_sided` (1) makes a triangle emit from both faces.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuLight {
        /// A `LightKind` code.
        pub kind: u32,
        pub radius: f32,
        pub cdf: f32,
        pub pmf: f32,
        pub p0: [f32; 3],
        pub p1: [f32; 3],
        pub p2: [f32; 3],
        pub emission: [f32; 3],
        pub two_sided: u32,
    }

    /// A `sss::scene::Camera` at one frame, filled from the camera's own methods.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuCamera {
        pub eye: [f32; 3],
        pub forward: [f32; 3],
        pub right: [f32; 3],
        pub up: [f32; 3],
        pub jitter: [f32; 2],
        pub tan_half_fov: f32,
        pub width: u32,
        pub height: u32,
    }

    /// One frame's constants, binding 8 of the scene (rewritten every frame).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct FrameParams {
        pub width: u32,
        pub height: u32,
        pub frame: u32,
        pub light_count: u32,
        /// BVH nodes (`BVH_NODE_COUNT`, 0 for an empty scene).
        pub node_count: u32,
        pub object_count: u32,
        /// The run seed of `restir::rng`, low and high 32 bits.
        pub seed_lo: u32,
        pub seed_hi: u32,
        /// Unused; keeps `camera` at offset 36.
        pub pad: u32,
        pub camera: GpuCamera,
        /// The camera of the previous frame, for temporal reprojection (zeroed when there is
        /// none).
        pub previous_camera: GpuCamera,
        pub has_previous: u32,
    }

    /// A G-buffer pixel: `sss::scene::GPixel` with `valid = 0` where the CPU has `None`; 64
    /// bytes, so that a 1920×1080 G-buffer fits a 128 MiB storage-buffer range.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct GpuPixel as GPixel {
        pub position: [f32; 3],
        pub object: u32,
        pub geometric_normal: [f32; 3],
        pub prim: u32,
        pub shading_normal: [f32; 3],
        pub depth: f32,
        pub view: [f32; 3],
        pub valid: u32,
    }

    /// Push constants of every pass kernel.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct PassParams in push_constant params {
        /// The pass's index in the preset (the stream key's `pass`); the pass count for shade.
        pub pass: u32,
        /// `ShiftKind::code`.
        pub shift: u32,
        /// `MisKind::code`.
        pub mis: u32,
        pub neighbours: u32,
        /// ≤ 0: no cap (a spatial pass's `None`).
        pub confidence_cap: f32,
        pub bssrdf_samples: u32,
        pub shared_light: u32,
        pub collect_diagnostics: u32,
        /// 1 for `Shade::AllInputs`: the reuse passes write the Rao-Blackwellised value of the
        /// pixels they resample and shade paints it; 0 (`Shade::Selected`): neither touches it.
        pub shade: u32,
        /// The preset's `Target` code (`TARGET_*` of the shifts' contract): `p̂` of every
        /// domain of the pass.
        pub target: u32,
    }

    /// Push constants of `method_random_walk`.
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Pod, Zeroable)]
    pub struct MethodParams in push_constant params {
        pub spp: u32,
        /// `pad[0]`: the sample this dispatch runs.
        pub pad: [u32; 7],
    }

    /// "No pixel" in a denoiser guide's object (`engine::denoise::guide::NONE`).
    pub const NO_PIXEL: u32 = u32::MAX;

    /// `denoise_svgf`'s stages, one dispatch each (`engine::denoise::svgf`): temporal
    /// accumulation, the variance estimate, one edge-avoiding à-trous iteration.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum SvgfStage in SVGF_STAGE {
        /// Colour and luminance moments through the reprojected history [SVGF §4.1].
        Temporal,
        /// Temporal variance, or the spatial 7×7 estimate on a short history [SVGF §4.2].
        Variance,
        /// One à-trous iteration at `step` [SVGF §4.3].
        Atrous,
    }

    /// Push constants of `denoise_svgf`: the stage, the image size, the à-trous step and
    /// `engine::denoise::svgf::Params` (`feedback` = 1: this iteration's colour is the next
    /// frame's history).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SvgfParams in push_constant params {
        /// An `SvgfStage` code.
        pub stage: u32,
        pub width: u32,
        pub height: u32,
        pub step: u32,
        pub feedback: u32,
        pub alpha_colour: f32,
        pub alpha_moments: f32,
        pub variance_history: u32,
        pub variance_radius: u32,
        pub sigma_depth: f32,
        pub sigma_normal: u32,
        pub sigma_luminance: f32,
        pub epsilon_depth: f32,
        pub epsilon_luminance: f32,
        pub pad: [u32; 2],
    }

    /// A pixel's guide on the device (`engine::denoise::svgf`): the shading normal, view
    /// depth and its screen-space gradient (computed on the host), object (`NO_PIXEL`: none)
    /// and the reprojection into the previous frame (`engine::denoise::guide::Reprojection`:
    /// position in that frame's grid of samples, and the taps of its 2×2 bilinear footprint
    /// that show the same surface, bits 0–3; 0: no history).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SvgfPixel {
        pub normal: [f32; 3],
        pub depth: f32,
        pub gradient: [f32; 2],
        pub object: u32,
        pub previous: [f32; 2],
        pub taps: u32,
    }

    /// A pixel's temporal history (`engine::denoise::svgf`): the demodulated colour, the first
    /// and second luminance moments, and the frames accumulated (0: none; `length` is a GLSL
    /// method name).
    #[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
    pub struct SvgfHistory {
        pub colour: [f32; 3],
        pub moments: [f32; 2],
        pub frames: u32,
    }
}
