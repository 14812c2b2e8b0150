//! The scene on the device (`sss/glsl/scene.glsl`, bindings 0–8 of every scene shader): the
//! BVH ([`GpuBvh`]), triangles, objects, materials and lights ([`GpuScene`]), the per-frame
//! [`FrameParams`] with its cameras ([`GpuCamera`]), and the G-buffer pixel ([`GpuPixel`]).
//!
//! Everything the CPU derives with a transcendental or a long reduction (Burley `d` and `r_max`,
//! the camera basis and jitter, the light selection CDF) is computed here in `f32` exactly as
//! `sss` computes it and uploaded, so the shaders never re-derive it.

use glam::Vec3;
use sss::material::Material;
use sss::scene::{Camera, GPixel, Light, Scene};

use super::{Buffer, Context, GpuBvh, Shader, VulkanError};
use crate::contract::{
    FrameParams, GpuCamera, GpuLight, GpuMaterial, GpuPixel, GpuTriangle, LightKind, MaterialKind,
};
use crate::plan::PassKernel;

/// `engine/glsl/pass_gbuffer.glsl` ([`PassKernel::GBuffer`]): [`GpuPixel`] out; its `PassParams`
/// are unused. One invocation per pixel.
pub const GBUFFER: Shader = Shader::of(PassKernel::GBuffer);

impl GpuMaterial {
    pub const LAMBERT: u32 = MaterialKind::Lambert.code();
    pub const TRANSLUCENT: u32 = MaterialKind::Translucent.code();

    pub fn new(material: &Material) -> GpuMaterial {
        match material {
            Material::Lambert(l) => GpuMaterial {
                kind: Self::LAMBERT,
                albedo: l.albedo.to_array(),
                emission: l.emission.to_array(),
                two_sided: l.two_sided as u32,
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
                    ..GpuMaterial::default()
                }
            }
        }
    }
}

impl GpuLight {
    pub const QUAD: u32 = LightKind::Quad.code();
    pub const TRIANGLE: u32 = LightKind::Triangle.code();
    pub const SPHERE: u32 = LightKind::Sphere.code();
    pub const POINT: u32 = LightKind::Point.code();
    pub const DIRECTIONAL: u32 = LightKind::Directional.code();

    pub fn new(light: &Light, cdf: f32, pmf: f32) -> GpuLight {
        let (kind, radius, [p0, p1, p2], emission) = match *light {
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => (Self::QUAD, 0.0, [corner, edge_u, edge_v], radiance),
            Light::Triangle {
                vertices, radiance, ..
            } => (Self::TRIANGLE, 0.0, vertices, radiance),
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
            two_sided: matches!(
                light,
                Light::Triangle {
                    two_sided: true,
                    ..
                }
            ) as u32,
        }
    }
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

impl GpuPixel {
    /// The CPU's G-buffer entry (`None` where `valid` is 0); `previous` is `position`, the
    /// device renders scenes at rest ([`GpuScene::upload`] refuses moving objects).
    pub fn to_cpu(&self) -> Option<GPixel> {
        (self.valid != 0).then(|| GPixel {
            position: Vec3::from_array(self.position),
            previous: Vec3::from_array(self.position),
            geometric_normal: Vec3::from_array(self.geometric_normal),
            shading_normal: Vec3::from_array(self.shading_normal),
            object: self.object,
            prim: self.prim,
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
    /// Uploads `scene`'s BVH, triangles, object materials, materials and lights; a scene with
    /// a moving object is refused.
    pub fn upload(context: &Context, scene: &Scene) -> Result<GpuScene, VulkanError> {
        if let Some(object) = scene.moving_object() {
            return Err(VulkanError::MovingScene {
                file: scene.file.display().to_string(),
                object: object.to_string(),
            });
        }
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
            (76, 4)
        );
        assert_eq!(offset_of!(GpuMaterial, d), 16);
        assert_eq!(offset_of!(GpuMaterial, r_max), 28);
        assert_eq!(offset_of!(GpuMaterial, r_max_all), 40);
        assert_eq!(offset_of!(GpuMaterial, kappa_dist), 52);
        assert_eq!(offset_of!(GpuMaterial, emission), 60);
        assert_eq!(offset_of!(GpuMaterial, two_sided), 72);
        assert_eq!((size_of::<GpuLight>(), align_of::<GpuLight>()), (68, 4));
        assert_eq!(offset_of!(GpuLight, pmf), 12);
        assert_eq!(offset_of!(GpuLight, p0), 16);
        assert_eq!(offset_of!(GpuLight, emission), 52);
        assert_eq!(offset_of!(GpuLight, two_sided), 64);
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
        assert_eq!((size_of::<GpuPixel>(), align_of::<GpuPixel>()), (64, 4));
        assert_eq!(offset_of!(GpuPixel, object), 12);
        assert_eq!(offset_of!(GpuPixel, prim), 28);
        assert_eq!(offset_of!(GpuPixel, depth), 44);
        assert_eq!(offset_of!(GpuPixel, valid), 60);
        // Every pass kernel, the G-buffer's included, takes the pass parameters (10 words).
        assert_eq!(GBUFFER.push_bytes, 40);
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
