//! The scene file as written: serde structs for the TOML format (documented field by field in
//! `docs/scene-format.md`). Unknown fields are rejected everywhere; semantic checks (ranges,
//! names, files) happen in `load`.

use serde::Deserialize;

/// A whole scene file.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: CameraDesc,
    #[serde(default)]
    pub materials: Vec<MaterialDesc>,
    #[serde(default)]
    pub objects: Vec<ObjectDesc>,
    #[serde(default)]
    pub lights: Vec<LightDesc>,
    pub many_lights: Option<ManyLightsDesc>,
    pub emitter_field: Option<EmitterFieldDesc>,
}

/// `[camera]`: the start (`eye`, `target`) and end (`eye_end`, `target_end`, default: the start)
/// of the linear trajectory over the 16 frames.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    pub resolution: [u32; 2],
    /// Vertical field of view in degrees.
    pub vfov: f32,
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub eye_end: Option<[f32; 3]>,
    pub target_end: Option<[f32; 3]>,
    pub up: Option<[f32; 3]>,
    pub jitter: Option<bool>,
}

/// `[[materials]]`: `type = "translucent"` (parameters, or a measured `preset` with optional
/// overrides) or `type = "lambert"` (albedo, and an emission that makes the object an emitter).
/// A material named like a material of a glTF object overrides it there; the fields it leaves
/// out that the glTF material has (`ior`; `emission`, `two_sided`) come from the glTF file.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum MaterialDesc {
    Translucent {
        name: String,
        preset: Option<String>,
        albedo: Option<[f32; 3]>,
        mfp: Option<[f32; 3]>,
        scale: Option<f32>,
        ior: Option<f32>,
        g: Option<f32>,
        fit: Option<FitDesc>,
        boundary: Option<BoundaryDesc>,
    },
    Lambert {
        name: String,
        albedo: [f32; 3],
        /// Emitted radiance `L_e`; an object of this material is an emitter that is geometry.
        emission: Option<[f32; 3]>,
        /// Whether the back face emits too.
        two_sided: Option<bool>,
    },
}

impl MaterialDesc {
    pub fn name(&self) -> &str {
        match self {
            MaterialDesc::Translucent { name, .. } | MaterialDesc::Lambert { name, .. } => name,
        }
    }
}

/// `fit`: which Christensen–Burley fit relates `mfp` to `d`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FitDesc {
    Searchlight,
    DiffuseTransmission,
    Dmfp,
}

/// `boundary`: the interface of path-traced volumetric transport (`BoundaryKind`);
/// `index-matched` is accepted for `index_matched`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundaryDesc {
    Diffuse,
    Dielectric,
    #[serde(alias = "index-matched")]
    IndexMatched,
}

/// `[[objects]]`: a procedural `shape`, a `mesh` file or an `asset` file, placed by
/// `transform`. `material` is required but for glTF files, whose primitives otherwise keep the
/// file's own materials.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub name: String,
    pub material: Option<String>,
    pub shape: Option<ShapeDesc>,
    /// OBJ, PLY or glTF file, relative to the scene file's folder.
    pub mesh: Option<String>,
    /// A mesh file relative to the asset directory (`--assets`, `RESHIFT_ASSETS`).
    pub asset: Option<String>,
    #[serde(default)]
    pub transform: TransformDesc,
    /// Keyframed rigid motion along the frames (`motion::Keyframes`); absent: at rest.
    pub motion: Option<Vec<KeyDesc>>,
}

/// `motion = [{ frame, translate, rotate }, …]`: the object's pose at `frame`, a rotation about
/// its pivot (the centre of its placed bounds) and then a translation, both relative to where
/// `transform` placed it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeyDesc {
    pub frame: u32,
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<RotateDesc>,
}

/// `transform = { translate, rotate, scale }`: scale, then rotate (about X, then Y, then Z, or
/// about one axis; degrees), then translate.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TransformDesc {
    pub translate: Option<[f32; 3]>,
    pub rotate: Option<RotateDesc>,
    pub scale: Option<ScaleDesc>,
}

/// Euler angles (`rotate = [x, y, z]`, degrees, applied X then Y then Z) or a rotation about
/// one axis (`rotate = { axis = [x, y, z], degrees = a }`, right-handed).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum RotateDesc {
    Euler([f32; 3]),
    Axis(AxisAngleDesc),
}

/// A rotation of `degrees` about `axis` (any non-zero length).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AxisAngleDesc {
    pub axis: [f32; 3],
    pub degrees: f32,
}

/// A uniform (`scale = 2`) or per-axis (`scale = [1, 2, 1]`) scale.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(untagged)]
pub enum ScaleDesc {
    Uniform(f32),
    PerAxis([f32; 3]),
}

/// `shape = { type = …, … }`: the procedural shapes of `geometry::shapes`, centred at the origin.
/// Tessellation fields are optional (defaults in `load`).
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ShapeDesc {
    Sphere {
        radius: f32,
        segments: Option<u32>,
        rings: Option<u32>,
    },
    /// `size`: full extents along x, y, z.
    Box { size: [f32; 3] },
    /// `size`: extents along x and z; `thickness` along y.
    Slab { size: [f32; 2], thickness: f32 },
    /// One-sided rectangle at y = 0 facing +y; `size`: extents along x and z.
    Quad { size: [f32; 2] },
    Torus {
        major_radius: f32,
        minor_radius: f32,
        segments: Option<u32>,
        sides: Option<u32>,
    },
    TorusKnot {
        p: u32,
        q: u32,
        radius: f32,
        tube_radius: f32,
        segments: Option<u32>,
        sides: Option<u32>,
    },
    BumpySphere {
        radius: f32,
        amplitude: f32,
        frequency: f32,
        seed: Option<u64>,
        subdivisions: Option<u32>,
    },
}

/// `[[lights]]`.
#[derive(Debug, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum LightDesc {
    Quad {
        corner: [f32; 3],
        edge_u: [f32; 3],
        edge_v: [f32; 3],
        radiance: [f32; 3],
    },
    Triangle {
        vertices: [[f32; 3]; 3],
        radiance: [f32; 3],
        two_sided: Option<bool>,
    },
    Sphere {
        center: [f32; 3],
        radius: f32,
        radiance: [f32; 3],
    },
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
    },
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
    },
}

/// `[many_lights]`: `count` small sphere lights placed uniformly at random in the box `region`,
/// sharing `total_power` equally, coloured `color` (normalised to unit luminance).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ManyLightsDesc {
    pub count: u32,
    pub seed: u64,
    pub region: RegionDesc,
    pub radius: f32,
    pub total_power: f32,
    pub color: Option<[f32; 3]>,
}

/// `[emitter_field]`: `count` emissive rectangles (objects, hence geometry, and lights): each
/// the 2 × 2 square `[−1, 1]²` of the xz-plane scaled per axis by draws in `scale`, rotated by
/// a draw in [0, π) about a random axis of the positive octant, centred uniformly in `region`,
/// emitting one of `colors` (chosen uniformly) times a strength uniform in [0, `strength`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmitterFieldDesc {
    pub count: u32,
    pub seed: u64,
    pub region: RegionDesc,
    /// `[min, max]` of the per-axis scale of the 2 × 2 square.
    pub scale: [f32; 2],
    /// The upper end of the strength that multiplies a colour.
    pub strength: f32,
    /// Emission colours (default: red, green, blue, yellow, magenta, cyan, white).
    pub colors: Option<Vec<[f32; 3]>>,
    /// Diffuse reflectance of the rectangles (default 1).
    pub albedo: Option<[f32; 3]>,
    /// Whether both faces emit (default true).
    pub two_sided: Option<bool>,
    /// A box that no rectangle may reach into (rectangles drawn there are drawn again).
    pub exclude: Option<RegionDesc>,
}

/// An axis-aligned box.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RegionDesc {
    pub min: [f32; 3],
    pub max: [f32; 3],
}
