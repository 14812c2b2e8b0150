/// The scene's bindings, `0..SCENE_BINDINGS` of every pass kernel (`sss/glsl/scene.glsl`: the
/// BVH, triangles, objects, materials, lights and `FrameParams`); a pass kernel's own buffers
/// follow.
pub const SCENE_BINDINGS: u32 = 9;

/// The kernels a plan's steps run (`engine/glsl/pass_*.glsl`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PassKernel {
    GBuffer,
    Candidates,
    Temporal,
    Spatial,
    Shade,
}

/// How a kernel uses one of its buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Access {
    Read,
    Write,
}

/// What a kernel's buffer holds, relative to the frame and pass it runs in; a plan step binds
/// each role to one of the frame's buffers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Role {
    /// This frame's G-buffer, `GPixel` per pixel.
    GBuffer,
    /// The previous frame's G-buffer.
    PreviousGBuffer,
    /// The reservoirs the previous pass of this frame wrote, `PixelReservoir` per pixel.
    ReservoirsIn,
    /// The previous frame's final reservoirs.
    PreviousReservoirs,
    /// The reservoirs this pass writes.
    ReservoirsOut,
    /// This pass's diagnostics, `uvec4` per pixel: its counters and its error code in `w`.
    Diag,
    /// The shaded image, `vec4` per pixel (`w` = 1 where a value was written as 0).
    Image,
    /// Per pixel, the Rao-Blackwellised value of this frame's last reuse pass that resampled it
    /// (`Shade::AllInputs`), `vec4`: the value in `xyz`, `w` = 1 where a pass wrote one. The
    /// reuse passes write it and shade reads it only when `PassParams::shade` is set.
    RaoBlackwellised,
}

/// One storage buffer of a kernel: its role, its access, and its GLSL declaration, an array
/// `name[]` of `element`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KernelBuffer {
    pub role: Role,
    pub access: Access,
    pub element: &'static str,
    pub name: &'static str,
}

const fn buffer(
    role: Role,
    access: Access,
    element: &'static str,
    name: &'static str,
) -> KernelBuffer {
    KernelBuffer {
        role,
        access,
        element,
        name,
    }
}

const G_BUFFER_OUT: KernelBuffer = buffer(Role::GBuffer, Access::Write, "GPixel", "gpixels");
const G_BUFFER_IN: KernelBuffer = buffer(Role::GBuffer, Access::Read, "GPixel", "gpixels");
const PREVIOUS_G_BUFFER: KernelBuffer = buffer(
    Role::PreviousGBuffer,
    Access::Read,
    "GPixel",
    "previous_gpixels",
);
const RESERVOIRS_IN: KernelBuffer = buffer(
    Role::ReservoirsIn,
    Access::Read,
    "PixelReservoir",
    "reservoirs_in",
);
const PREVIOUS_RESERVOIRS: KernelBuffer = buffer(
    Role::PreviousReservoirs,
    Access::Read,
    "PixelReservoir",
    "previous_reservoirs",
);
const RESERVOIRS_OUT: KernelBuffer = buffer(
    Role::ReservoirsOut,
    Access::Write,
    "PixelReservoir",
    "reservoirs_out",
);
const DIAG: KernelBuffer = buffer(Role::Diag, Access::Write, "uvec4", "diag");
const IMAGE: KernelBuffer = buffer(Role::Image, Access::Write, "vec4", "image");
const RAO_BLACKWELLISED_OUT: KernelBuffer = buffer(
    Role::RaoBlackwellised,
    Access::Write,
    "vec4",
    "rao_blackwellised",
);
const RAO_BLACKWELLISED_IN: KernelBuffer = buffer(
    Role::RaoBlackwellised,
    Access::Read,
    "vec4",
    "rao_blackwellised",
);

const G_BUFFER_BUFFERS: [KernelBuffer; 1] = [G_BUFFER_OUT];
const CANDIDATES_BUFFERS: [KernelBuffer; 3] = [G_BUFFER_IN, RESERVOIRS_OUT, DIAG];
const TEMPORAL_BUFFERS: [KernelBuffer; 7] = [
    G_BUFFER_IN,
    RESERVOIRS_IN,
    PREVIOUS_G_BUFFER,
    PREVIOUS_RESERVOIRS,
    RESERVOIRS_OUT,
    DIAG,
    RAO_BLACKWELLISED_OUT,
];
const SPATIAL_BUFFERS: [KernelBuffer; 5] = [
    G_BUFFER_IN,
    RESERVOIRS_IN,
    RESERVOIRS_OUT,
    DIAG,
    RAO_BLACKWELLISED_OUT,
];
const SHADE_BUFFERS: [KernelBuffer; 4] = [G_BUFFER_IN, RESERVOIRS_IN, IMAGE, RAO_BLACKWELLISED_IN];

impl PassKernel {
    pub const ALL: [PassKernel; 5] = [
        PassKernel::GBuffer,
        PassKernel::Candidates,
        PassKernel::Temporal,
        PassKernel::Spatial,
        PassKernel::Shade,
    ];

    /// The GLSL file stem.
    pub const fn name(self) -> &'static str {
        match self {
            PassKernel::GBuffer => "pass_gbuffer",
            PassKernel::Candidates => "pass_candidates",
            PassKernel::Temporal => "pass_temporal",
            PassKernel::Spatial => "pass_spatial",
            PassKernel::Shade => "pass_shade",
        }
    }

    /// The kernel's buffers after the scene's, in binding order (`SCENE_BINDINGS`, …). This is
    /// the only statement of them: `build.rs` writes the kernels' GLSL declarations
    /// (`contract/<name>_bindings.glsl`) from it and the Vulkan backend binds by it.
    pub const fn buffers(self) -> &'static [KernelBuffer] {
        match self {
            PassKernel::GBuffer => &G_BUFFER_BUFFERS,
            PassKernel::Candidates => &CANDIDATES_BUFFERS,
            PassKernel::Temporal => &TEMPORAL_BUFFERS,
            PassKernel::Spatial => &SPATIAL_BUFFERS,
            PassKernel::Shade => &SHADE_BUFFERS,
        }
    }
}
