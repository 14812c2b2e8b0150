//! The scene on the device (`sss/glsl/scene.glsl`, bindings 0–8 of every scene shader): the
//! BVH ([`GpuBvh`]), triangles, objects, materials and lights ([`GpuScene`]), the per-frame
//! [`FrameParams`] with its cameras ([`GpuCamera`]), and the G-buffer pixel ([`GpuPixel`]).
//!
//! Everything the CPU derives with a transcendental or a long reduction (Burley `d` and `r_max`,
//! the camera basis and jitter, the light selection CDF) is computed here in `f32` exactly as
//! `sss` computes it and uploaded, so the shaders never re-derive it.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use sss::material::Material;
use sss::scene::{Camera, GPixel, Light, Scene};

use super::{Buffer, Context, GpuBvh, Shader, VulkanError};

/// `engine/glsl/pass_gbuffer.glsl`: the scene (0–8), 9 [`GpuPixel`] out; `PassParams`
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

/// `material.glsl`'s `GpuMaterial` (std430, 60 bytes). `kind` 0 is Lambert (only `albedo` set),
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
    /// `Translucent::fresnel().normalization`, `1 − F_dr(ior)` (computed with logarithms).
    pub fresnel_normalization: f32,
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
                    fresnel_normalization: t.fresnel().normalization,
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
            tan_half_fov: camera.tan_half_fov(),
            width: camera.width(),
            height: camera.height(),
        }
    }
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
    /// Keeps `camera` at offset 36 (std430 needs no padding here; the word is unused).
    pub pad: u32,
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
            pad: 0,
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
                n: flatten(geometry.vertex_normals(prim)),
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
        let cdf = scene.lights.selection_cdf();
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
            (60, 4)
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
        assert_eq!(offset_of!(FrameParams, pad), 32);
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
