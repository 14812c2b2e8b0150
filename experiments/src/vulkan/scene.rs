//! The scene on the device (`sss/glsl/scene.glsl`, bindings 0–8 of every scene shader): the
//! BVH ([`GpuBvh`]), triangles, objects, materials and lights ([`GpuScene`]), the per-frame
//! [`FrameParams`] with its cameras ([`GpuCamera`]), and the G-buffer pixel ([`GpuPixel`]).
//!
//! Everything the CPU derives with a transcendental or a long reduction (Burley `d` and `r_max`,
//! the camera basis and jitter, the light selection CDF) is computed here in `f32` exactly as
//! `sss` computes it and uploaded, so the shaders never re-derive it.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use sss::geometry::Geometry;
use sss::material::Material;
use sss::scene::{Camera, GPixel, Light, Lights, Scene};

use super::{Buffer, Context, GpuBvh, Shader, VulkanError};

/// `experiments/glsl/pass_gbuffer.glsl`: the scene (0–8), 9 [`GpuPixel`] out; `PassParams`
/// push constants (unused). One invocation per pixel.
pub const GBUFFER: Shader = Shader::new("pass_gbuffer", 10, 32);

/// `scene.glsl`'s `GpuTriangle` (std430, 76 bytes): vertices, per-vertex shading normals and
/// the object id of one global triangle id.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    pub v: [f32; 9],
    pub n: [f32; 9],
    pub object: u32,
}

/// `material.glsl`'s `GpuMaterial` (std430, 56 bytes). `kind` 0 is Lambert (only `albedo` set),
/// 1 is translucent with `Translucent`'s derived values.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub kind: u32,
    pub albedo: [f32; 3],
    /// `Translucent::d`.
    pub d: [f32; 3],
    /// `Translucent::r_max`.
    pub r_max: [f32; 3],
    /// `Translucent::r_max_all`.
    pub r_max_all: f32,
    pub ior: f32,
    pub g: f32,
    /// κ_dist = 2 · max d, the hybrid shift's distance criterion [001 §5.1].
    pub kappa_dist: f32,
}

impl GpuMaterial {
    pub const LAMBERT: u32 = 0;
    pub const TRANSLUCENT: u32 = 1;

    pub fn new(material: &Material) -> GpuMaterial {
        match material {
            Material::Lambert(l) => GpuMaterial {
                kind: Self::LAMBERT,
                albedo: l.albedo.to_array(),
                ..GpuMaterial::default()
            },
            Material::Translucent(t) => {
                let d = t.d();
                GpuMaterial {
                    kind: Self::TRANSLUCENT,
                    albedo: t.albedo.to_array(),
                    d: d.to_array(),
                    r_max: t.r_max().to_array(),
                    r_max_all: t.r_max_all(),
                    ior: t.ior,
                    g: t.g,
                    kappa_dist: 2.0 * d.max_element(),
                }
            }
        }
    }
}

/// `light.glsl`'s `GpuLight` (std430, 64 bytes): one [`Light`] with its selection CDF value and
/// pmf. Points by kind: quad (corner, edge_u, edge_v), triangle (vertices), sphere (centre),
/// point (position), directional (direction); `emission` is the radiance, intensity or
/// irradiance.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub kind: u32,
    pub radius: f32,
    pub cdf: f32,
    pub pmf: f32,
    pub p0: [f32; 3],
    pub p1: [f32; 3],
    pub p2: [f32; 3],
    pub emission: [f32; 3],
}

impl GpuLight {
    pub const QUAD: u32 = 0;
    pub const TRIANGLE: u32 = 1;
    pub const SPHERE: u32 = 2;
    pub const POINT: u32 = 3;
    pub const DIRECTIONAL: u32 = 4;

    pub fn new(light: &Light, cdf: f32, pmf: f32) -> GpuLight {
        let (kind, radius, [p0, p1, p2], emission) = match *light {
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => (Self::QUAD, 0.0, [corner, edge_u, edge_v], radiance),
            Light::Triangle { vertices, radiance } => (Self::TRIANGLE, 0.0, vertices, radiance),
            Light::Sphere {
                center,
                radius,
                radiance,
            } => (
                Self::SPHERE,
                radius,
                [center, Vec3::ZERO, Vec3::ZERO],
                radiance,
            ),
            Light::Point {
                position,
                intensity,
            } => (
                Self::POINT,
                0.0,
                [position, Vec3::ZERO, Vec3::ZERO],
                intensity,
            ),
            Light::Directional {
                direction,
                irradiance,
            } => (
                Self::DIRECTIONAL,
                0.0,
                [direction, Vec3::ZERO, Vec3::ZERO],
                irradiance,
            ),
        };
        GpuLight {
            kind,
            radius,
            cdf,
            pmf,
            p0: p0.to_array(),
            p1: p1.to_array(),
            p2: p2.to_array(),
            emission: emission.to_array(),
        }
    }
}

/// `camera.glsl`'s `GpuCamera` (std430, 68 bytes): a [`Camera`] at one frame, filled from the
/// camera's own methods.
#[repr(C)]
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

impl GpuCamera {
    /// `camera` at `frame`.
    pub fn new(camera: &Camera, frame: u32) -> GpuCamera {
        let (right, up) = camera.right_up(frame);
        GpuCamera {
            eye: camera.eye(frame).to_array(),
            forward: camera.forward(frame).to_array(),
            right: right.to_array(),
            up: up.to_array(),
            jitter: camera.jitter(frame).to_array(),
            tan_half_fov: tan_half_fov(camera),
            width: camera.width(),
            height: camera.height(),
        }
    }
}

/// `tan(vfov / 2)` of `camera`, bit for bit. `Camera` keeps it private and has no accessor, so
/// it is read back from the derived `Debug` text, whose `f32` is the shortest string that
/// round-trips (replace with an accessor when `Camera` gets one).
fn tan_half_fov(camera: &Camera) -> f32 {
    let text = format!("{camera:?}");
    text.split_once("tan_half_fov: ")
        .and_then(|(_, rest)| rest.split(',').next())
        .and_then(|value| value.trim().parse().ok())
        .unwrap_or_else(|| panic!("Camera's Debug text lacks tan_half_fov: {text}"))
}

/// `scene.glsl`'s `FrameParams` (std430, 176 bytes), binding 8: one frame's constants. The host
/// pipeline rewrites it each frame ([`FrameParams::buffer`]).
#[repr(C)]
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
    /// The radius of the scene's bounding sphere (directional lights' power).
    pub scene_radius: f32,
    pub camera: GpuCamera,
    /// The camera at `previous` (zeroed when there is none).
    pub previous_camera: GpuCamera,
    pub has_previous: u32,
}

impl FrameParams {
    /// The constants of `frame` of `scene` under run seed `seed`; `previous` is the frame whose
    /// G-buffer and reservoirs temporal reuse reads, if any.
    pub fn new(scene: &Scene, frame: u32, previous: Option<u32>, seed: u64) -> FrameParams {
        FrameParams {
            width: scene.camera.width(),
            height: scene.camera.height(),
            frame,
            light_count: scene.lights.len() as u32,
            node_count: scene.geometry.bvh().nodes.len() as u32,
            object_count: scene.geometry.object_count(),
            seed_lo: seed as u32,
            seed_hi: (seed >> 32) as u32,
            scene_radius: scene_radius(&scene.geometry),
            camera: GpuCamera::new(&scene.camera, frame),
            previous_camera: previous
                .map_or(GpuCamera::default(), |p| GpuCamera::new(&scene.camera, p)),
            has_previous: u32::from(previous.is_some()),
        }
    }

    /// The binding-8 buffer holding these constants.
    pub fn buffer(&self, context: &Context) -> Result<Buffer, VulkanError> {
        Buffer::from_slice(context, std::slice::from_ref(self))
    }
}

/// `scene.glsl`'s `GPixel` (std430, 80 bytes): [`GPixel`] with `valid = 0` for `None`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPixel {
    pub position: [f32; 3],
    pub object: u32,
    pub geometric_normal: [f32; 3],
    pub prim: u32,
    pub shading_normal: [f32; 3],
    pub depth: f32,
    pub view: [f32; 3],
    pub valid: u32,
    pub bary: [f32; 2],
    pub pad0: u32,
    pub pad1: u32,
}

impl GpuPixel {
    /// The CPU's G-buffer entry (`None` where `valid` is 0).
    pub fn to_cpu(&self) -> Option<GPixel> {
        (self.valid != 0).then(|| GPixel {
            position: Vec3::from_array(self.position),
            geometric_normal: Vec3::from_array(self.geometric_normal),
            shading_normal: Vec3::from_array(self.shading_normal),
            object: self.object,
            prim: self.prim,
            bary: Vec2::from_array(self.bary),
            depth: self.depth,
            view: Vec3::from_array(self.view),
        })
    }

    /// The device layout of a CPU entry (`None` → `valid = 0`, all zero).
    pub fn from_cpu(pixel: Option<&GPixel>) -> GpuPixel {
        pixel.map_or(GpuPixel::default(), |g| GpuPixel {
            position: g.position.to_array(),
            object: g.object,
            geometric_normal: g.geometric_normal.to_array(),
            prim: g.prim,
            shading_normal: g.shading_normal.to_array(),
            depth: g.depth,
            view: g.view.to_array(),
            valid: 1,
            bary: g.bary.to_array(),
            pad0: 0,
            pad1: 0,
        })
    }
}

/// Half the diagonal of the bounding box of `geometry`'s triangles (at least the smallest
/// positive normal `f32`), as the scene loader computes it from the meshes.
fn scene_radius(geometry: &Geometry) -> f32 {
    let (lo, hi) = (0..geometry.triangle_count())
        .flat_map(|prim| geometry.vertices(prim))
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE)
}

/// The selection CDF of `lights`, rebuilt as `Lights::new` builds it (power in f64, running
/// sums divided by the total, the last value forced to 1), checked against the pmf the CPU
/// samples with: an error if any probability differs in a single bit.
fn selection_cdf(lights: &Lights, scene_radius: f32) -> Result<Vec<f32>, VulkanError> {
    let powers: Vec<f64> = lights
        .iter()
        .map(|l| l.power(scene_radius).max(0.0) as f64)
        .collect();
    let total: f64 = powers.iter().sum();
    let mut running = 0.0f64;
    let mut cdf: Vec<f32> = powers
        .iter()
        .map(|p| {
            running += p;
            (running / total) as f32
        })
        .collect();
    if let Some(last) = cdf.last_mut() {
        *last = 1.0;
    }
    for (i, &c) in cdf.iter().enumerate() {
        let pmf = c - if i == 0 { 0.0 } else { cdf[i - 1] };
        if pmf.to_bits() != lights.selection_pmf(i as u32).to_bits() {
            return Err(VulkanError::Binding(format!(
                "light {i}: the rebuilt selection pmf {pmf} differs from the scene's {}",
                lights.selection_pmf(i as u32)
            )));
        }
    }
    Ok(cdf)
}

/// The per-vertex shading normals of triangle `prim` as `Geometry::shading_normal` returns
/// them at the corners. `Geometry` keeps the raw normals private; at a corner the interpolation
/// is exact, so these are the stored normals renormalised (the stored ones are unit already,
/// so they differ by at most a rounding of `x · (1/‖x‖)`).
fn corner_normals(geometry: &Geometry, prim: u32) -> [Vec3; 3] {
    [Vec2::ZERO, Vec2::X, Vec2::Y].map(|bary| geometry.shading_normal(prim, bary))
}

/// A scene's buffers on the device, bindings 0–7 of `scene.glsl` (binding 8 is
/// [`FrameParams::buffer`]).
pub struct GpuScene {
    bvh: GpuBvh,
    triangles: Buffer,
    objects: Buffer,
    materials: Buffer,
    lights: Buffer,
}

impl GpuScene {
    /// Uploads `scene`'s BVH, triangles, object materials, materials and lights.
    pub fn upload(context: &Context, scene: &Scene) -> Result<GpuScene, VulkanError> {
        let geometry = &scene.geometry;
        let mut triangles: Vec<GpuTriangle> = (0..geometry.triangle_count())
            .map(|prim| GpuTriangle {
                v: flatten(geometry.vertices(prim)),
                n: flatten(corner_normals(geometry, prim)),
                object: geometry.object_of(prim),
            })
            .collect();
        // Vulkan buffers cannot be empty; a scene without triangles gets one that is never read.
        if triangles.is_empty() {
            triangles.push(GpuTriangle::default());
        }
        let objects: Vec<u32> = scene.objects.iter().map(|o| o.material).collect();
        let objects = if objects.is_empty() { vec![0] } else { objects };
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(GpuMaterial::new).collect();
        let materials = if materials.is_empty() {
            vec![GpuMaterial::default()]
        } else {
            materials
        };
        let cdf = selection_cdf(&scene.lights, scene_radius(geometry))?;
        let lights: Vec<GpuLight> = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, light)| GpuLight::new(light, cdf[i], scene.lights.selection_pmf(i as u32)))
            .collect();
        Ok(GpuScene {
            bvh: GpuBvh::upload(context, geometry)?,
            triangles: Buffer::from_slice(context, &triangles)?,
            objects: Buffer::from_slice(context, &objects)?,
            materials: Buffer::from_slice(context, &materials)?,
            lights: Buffer::from_slice(context, &lights)?,
        })
    }

    /// The buffers of bindings 0–7 in binding order.
    pub fn buffers(&self) -> [&Buffer; 8] {
        let [nodes, leaf_triangles, leaf_prims, leaf_objects] = self.bvh.buffers();
        [
            nodes,
            leaf_triangles,
            leaf_prims,
            leaf_objects,
            &self.triangles,
            &self.objects,
            &self.materials,
            &self.lights,
        ]
    }

    pub fn bvh(&self) -> &GpuBvh {
        &self.bvh
    }
}

fn flatten(v: [Vec3; 3]) -> [f32; 9] {
    let [a, b, c] = v.map(|p| p.to_array());
    [a[0], a[1], a[2], b[0], b[1], b[2], c[0], c[1], c[2]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::offset_of;

    /// std430 of structs of 4-byte scalars: alignment 4, no padding, fields in order.
    #[test]
    fn structs_match_std430() {
        assert_eq!(
            (size_of::<GpuTriangle>(), align_of::<GpuTriangle>()),
            (76, 4)
        );
        assert_eq!(offset_of!(GpuTriangle, n), 36);
        assert_eq!(offset_of!(GpuTriangle, object), 72);
        assert_eq!(
            (size_of::<GpuMaterial>(), align_of::<GpuMaterial>()),
            (56, 4)
        );
        assert_eq!(offset_of!(GpuMaterial, d), 16);
        assert_eq!(offset_of!(GpuMaterial, r_max), 28);
        assert_eq!(offset_of!(GpuMaterial, r_max_all), 40);
        assert_eq!(offset_of!(GpuMaterial, kappa_dist), 52);
        assert_eq!((size_of::<GpuLight>(), align_of::<GpuLight>()), (64, 4));
        assert_eq!(offset_of!(GpuLight, pmf), 12);
        assert_eq!(offset_of!(GpuLight, p0), 16);
        assert_eq!(offset_of!(GpuLight, emission), 52);
        assert_eq!((size_of::<GpuCamera>(), align_of::<GpuCamera>()), (68, 4));
        assert_eq!(offset_of!(GpuCamera, jitter), 48);
        assert_eq!(offset_of!(GpuCamera, tan_half_fov), 56);
        assert_eq!(offset_of!(GpuCamera, height), 64);
        assert_eq!(
            (size_of::<FrameParams>(), align_of::<FrameParams>()),
            (176, 4)
        );
        assert_eq!(offset_of!(FrameParams, seed_hi), 28);
        assert_eq!(offset_of!(FrameParams, scene_radius), 32);
        assert_eq!(offset_of!(FrameParams, camera), 36);
        assert_eq!(offset_of!(FrameParams, previous_camera), 104);
        assert_eq!(offset_of!(FrameParams, has_previous), 172);
        assert_eq!((size_of::<GpuPixel>(), align_of::<GpuPixel>()), (80, 4));
        assert_eq!(offset_of!(GpuPixel, object), 12);
        assert_eq!(offset_of!(GpuPixel, prim), 28);
        assert_eq!(offset_of!(GpuPixel, depth), 44);
        assert_eq!(offset_of!(GpuPixel, valid), 60);
        assert_eq!(offset_of!(GpuPixel, bary), 64);
        assert_eq!(GBUFFER.push_bytes, 32);
    }

    /// The rebuilt selection CDF reproduces every built-in scene's pmf bit for bit (the check
    /// inside `selection_cdf`); negative control: a directional light (whose power depends on
    /// the scene radius) beside a point light, rebuilt with a doubled radius, is refused.
    #[test]
    fn selection_cdf_reproduces_the_cpu_pmf() {
        for &(name, _) in Scene::BUILTIN {
            let scene = Scene::builtin(name).unwrap();
            let cdf = selection_cdf(&scene.lights, scene_radius(&scene.geometry))
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(cdf.len(), scene.lights.len(), "{name}");
            assert_eq!(cdf.last(), Some(&1.0), "{name}");
        }
        let lights = Lights::new(
            vec![
                Light::Directional {
                    direction: Vec3::NEG_Y,
                    irradiance: Vec3::ONE,
                },
                Light::Point {
                    position: Vec3::Y,
                    intensity: Vec3::ONE,
                },
            ],
            1.5,
        )
        .unwrap();
        assert!(selection_cdf(&lights, 1.5).is_ok());
        assert!(selection_cdf(&lights, 3.0).is_err());
    }

    /// `tan_half_fov` read back from the Debug text is the value `Camera::new` computed; a
    /// camera with another field of view gives another value.
    #[test]
    fn tan_half_fov_is_read_back_exactly() {
        let camera = |vfov: f32| {
            Camera::new(
                [64, 48],
                vfov,
                [Vec3::new(0.0, 1.0, 4.0); 2],
                [Vec3::ZERO; 2],
                Vec3::Y,
                true,
            )
        };
        for vfov in [1.0f32, 33.3, 40.0, 90.0, 179.0] {
            let want = (0.5 * vfov.to_radians()).tan();
            assert_eq!(
                tan_half_fov(&camera(vfov)).to_bits(),
                want.to_bits(),
                "{vfov}"
            );
        }
        assert_ne!(tan_half_fov(&camera(40.0)), tan_half_fov(&camera(40.001)));
    }

    /// G-buffer entries round-trip through the device layout, misses included.
    #[test]
    fn pixels_round_trip() {
        let scene = Scene::builtin("slab").unwrap();
        let scene = Scene {
            camera: scene.camera.with_resolution(16, 12),
            ..scene
        };
        let gbuffer = sss::scene::GBuffer::render(&scene, 2);
        assert!(gbuffer.pixels.iter().any(Option::is_some));
        for pixel in &gbuffer.pixels {
            assert_eq!(GpuPixel::from_cpu(pixel.as_ref()).to_cpu(), *pixel);
        }
        assert_eq!(GpuPixel::from_cpu(None).to_cpu(), None);
    }
}
