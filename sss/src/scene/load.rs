//! Scene file → [`Scene`]: TOML parsing with field paths in every error, semantic validation, and
//! construction of materials, meshes, lights and camera.

use std::collections::HashMap;
use std::path::Path;

use geometry::limits::MAX_COORDINATE;
use geometry::{Geometry, TriangleMesh, load_mesh, shapes};
use glam::{Affine3A, Quat, Vec3};

use super::format::{
    BoundaryDesc, CameraDesc, FitDesc, LightDesc, ManyLightsDesc, MaterialDesc, ObjectDesc,
    ScaleDesc, SceneFile, ShapeDesc, TransformDesc,
};
use super::light::{Light, Lights};
use super::many_lights::ManyLights;
use super::parse::parse;
use super::{Camera, Object, Scene};
use crate::InputError;
use crate::limits::{self, MAX_EMISSION, MAX_LIGHTS, MAX_SCENE_TRIANGLES, MAX_SHAPE_TRIANGLES};
use crate::material::{BoundaryKind, Lambert, MEASURED_NAMES, Material, Translucent, measured};
use crate::profile::ScaleFit;

/// Parses and builds a scene; `origin` names the file in errors and anchors relative mesh paths.
pub fn scene_from_toml(text: &str, origin: &Path) -> Result<Scene, InputError> {
    let file: SceneFile = parse(text, origin)?;
    let ctx = Ctx { file: origin };
    let camera = ctx.camera(&file.camera)?;
    let (materials, material_ids) = ctx.materials(&file.materials)?;
    let (objects, meshes, dropped_degenerate) = ctx.objects(&file.objects, &material_ids)?;
    if file.lights.len() as u64 > MAX_LIGHTS {
        return Err(ctx.err(
            "lights",
            format!("{} lights", file.lights.len()),
            format!("more than {MAX_LIGHTS} lights"),
        ));
    }
    let mut lights = ctx.lights(&file.lights)?;
    if let Some(many) = &file.many_lights {
        lights.extend(ctx.many_lights(many, lights.len())?.generate());
    }
    if lights.is_empty() {
        return Err(ctx.err(
            "lights",
            "[]",
            "the scene has no lights (add [[lights]] or [many_lights])",
        ));
    }
    let (lo, hi) = meshes
        .iter()
        .map(TriangleMesh::bounds)
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        });
    let scene_radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE);
    let total_power: f32 = lights.iter().map(|l| l.power(scene_radius)).sum();
    let lights = Lights::new(lights, scene_radius).ok_or_else(|| {
        ctx.err(
            "lights",
            format!("total power {total_power}"),
            "the total light power is not positive and finite",
        )
    })?;
    let name = origin
        .file_stem()
        .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned());
    Ok(Scene {
        name,
        file: origin.to_path_buf(),
        camera,
        materials,
        objects,
        geometry: Geometry::new(&meshes),
        lights,
        dropped_degenerate,
    })
}

/// Validation context: the file named in every error.
pub(super) struct Ctx<'a> {
    pub(super) file: &'a Path,
}

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn within_coordinates(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.abs() <= MAX_COORDINATE)
}

impl Ctx<'_> {
    pub(super) fn err(
        &self,
        field: impl Into<String>,
        value: impl Into<String>,
        reason: impl Into<String>,
    ) -> InputError {
        InputError::new(self.file, field, value, reason)
    }

    /// A finite 3-vector within [`MAX_COORDINATE`] or an error at `field`.
    pub(super) fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, InputError> {
        if finite3(v) && within_coordinates(v) {
            Ok(Vec3::from_array(v))
        } else {
            Err(self.err(
                field,
                format!("{v:?}"),
                format!("must be finite, each |component| ≤ {MAX_COORDINATE:e}"),
            ))
        }
    }

    /// A view from `eye` to `target` (the error at `field`, the target's) that a camera with `up`
    /// can frame: not zero, not parallel to `up`; `up` itself non-zero (an error at `up_field`).
    pub(super) fn view(
        &self,
        field: &str,
        eye: Vec3,
        target: Vec3,
        up: Vec3,
    ) -> Result<(), InputError> {
        let view = target - eye;
        if view.cross(up.normalize()).length() <= 1e-6 * view.length()
            || view.length_squared() == 0.0
        {
            return Err(self.err(
                field,
                format!("{target}"),
                format!("view direction from eye {eye} is zero or parallel to up {up}"),
            ));
        }
        Ok(())
    }

    /// A positive number (a length) no larger than [`MAX_COORDINATE`], or an error at `field`.
    fn positive(&self, field: &str, x: f32) -> Result<f32, InputError> {
        if x > 0.0 && x <= MAX_COORDINATE {
            Ok(x)
        } else {
            Err(self.err(
                field,
                x.to_string(),
                format!("must be > 0 and ≤ {MAX_COORDINATE:e}"),
            ))
        }
    }

    /// An emitted quantity: each channel in [0, [`MAX_EMISSION`]], not all zero.
    fn emission(&self, field: &str, v: [f32; 3]) -> Result<Vec3, InputError> {
        if v.iter().all(|x| (0.0..=MAX_EMISSION).contains(x)) && v.iter().any(|&x| x > 0.0) {
            Ok(Vec3::from_array(v))
        } else {
            Err(self.err(
                field,
                format!("{v:?}"),
                format!("each channel must lie in [0, {MAX_EMISSION:e}], and one be > 0"),
            ))
        }
    }

    fn camera(&self, c: &CameraDesc) -> Result<Camera, InputError> {
        let [width, height] = c.resolution;
        limits::resolution(self.file, "camera.resolution", width, height)?;
        if !(c.vfov > 0.0 && c.vfov < 180.0) {
            return Err(self.err(
                "camera.vfov",
                c.vfov.to_string(),
                "must lie in (0, 180) degrees",
            ));
        }
        let eye = [
            self.vec3("camera.eye", c.eye)?,
            self.vec3("camera.eye_end", c.eye_end.unwrap_or(c.eye))?,
        ];
        let target = [
            self.vec3("camera.target", c.target)?,
            self.vec3("camera.target_end", c.target_end.unwrap_or(c.target))?,
        ];
        let up = self.vec3("camera.up", c.up.unwrap_or([0.0, 1.0, 0.0]))?;
        if up.length_squared() == 0.0 {
            return Err(self.err("camera.up", format!("{up}"), "must be non-zero"));
        }
        for (end, field) in [(0, "camera.target"), (1, "camera.target_end")] {
            self.view(field, eye[end], target[end], up)?;
        }
        Ok(Camera::new(
            c.resolution,
            c.vfov,
            eye,
            target,
            up,
            c.jitter.unwrap_or(true),
        ))
    }

    fn materials(
        &self,
        descs: &[MaterialDesc],
    ) -> Result<(Vec<Material>, HashMap<String, u32>), InputError> {
        let mut ids = HashMap::new();
        let mut materials = Vec::with_capacity(descs.len());
        for (i, desc) in descs.iter().enumerate() {
            let field = format!("materials[{i}]");
            if ids.insert(desc.name().to_string(), i as u32).is_some() {
                return Err(self.err(
                    format!("{field}.name"),
                    format!("{:?}", desc.name()),
                    "duplicate material name",
                ));
            }
            materials.push(self.material(desc, &field)?);
        }
        Ok((materials, ids))
    }

    fn material(&self, desc: &MaterialDesc, field: &str) -> Result<Material, InputError> {
        match desc {
            MaterialDesc::Lambert { albedo, .. } => {
                if !albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
                    return Err(self.err(
                        format!("{field}.albedo"),
                        format!("{albedo:?}"),
                        "each channel must lie in [0, 1]",
                    ));
                }
                Ok(Material::Lambert(Lambert {
                    albedo: Vec3::from_array(*albedo),
                }))
            }
            MaterialDesc::Translucent {
                preset,
                albedo,
                mfp,
                scale,
                ior,
                g,
                fit,
                boundary,
                ..
            } => {
                let base = match preset {
                    Some(p) => measured(p).ok_or_else(|| {
                        self.err(
                            format!("{field}.preset"),
                            format!("{p:?}"),
                            format!("unknown preset; known: {}", MEASURED_NAMES.join(", ")),
                        )
                    })?,
                    None => {
                        let missing = |member: &str| {
                            self.err(
                                format!("{field}.{member}"),
                                "(missing)",
                                "required unless `preset` is given",
                            )
                        };
                        Translucent {
                            albedo: Vec3::from_array(albedo.ok_or_else(|| missing("albedo"))?),
                            mfp: Vec3::from_array(mfp.ok_or_else(|| missing("mfp"))?),
                            scale: 1.0,
                            ior: 1.3,
                            g: 0.0,
                            fit: ScaleFit::Searchlight,
                            boundary: BoundaryKind::Diffuse,
                        }
                    }
                };
                let m = Translucent {
                    albedo: albedo.map_or(base.albedo, Vec3::from_array),
                    mfp: mfp.map_or(base.mfp, Vec3::from_array),
                    scale: scale.unwrap_or(base.scale),
                    ior: ior.unwrap_or(base.ior),
                    g: g.unwrap_or(base.g),
                    fit: fit.map_or(base.fit, |f| match f {
                        FitDesc::Searchlight => ScaleFit::Searchlight,
                        FitDesc::DiffuseTransmission => ScaleFit::DiffuseTransmission,
                        FitDesc::Dmfp => ScaleFit::Dmfp,
                    }),
                    boundary: boundary.map_or(base.boundary, |b| match b {
                        BoundaryDesc::Diffuse => BoundaryKind::Diffuse,
                        BoundaryDesc::Dielectric => BoundaryKind::Dielectric,
                        BoundaryDesc::IndexMatched => BoundaryKind::IndexMatched,
                    }),
                };
                m.validate(self.file, field)?;
                Ok(Material::Translucent(m))
            }
        }
    }

    /// Objects, their world-space meshes (degenerate triangles dropped), and the dropped count.
    fn objects(
        &self,
        descs: &[ObjectDesc],
        material_ids: &HashMap<String, u32>,
    ) -> Result<(Vec<Object>, Vec<TriangleMesh>, usize), InputError> {
        if descs.is_empty() {
            return Err(self.err("objects", "[]", "the scene has no objects"));
        }
        let mut names = HashMap::new();
        let mut objects = Vec::with_capacity(descs.len());
        let mut meshes = Vec::with_capacity(descs.len());
        let (mut dropped, mut triangles) = (0, 0u64);
        for (i, desc) in descs.iter().enumerate() {
            let field = format!("objects[{i}]");
            if names.insert(desc.name.as_str(), i).is_some() {
                return Err(self.err(
                    format!("{field}.name"),
                    format!("{:?}", desc.name),
                    "duplicate object name",
                ));
            }
            let material = *material_ids.get(&desc.material).ok_or_else(|| {
                let mut known: Vec<&str> = material_ids.keys().map(String::as_str).collect();
                known.sort_unstable();
                self.err(
                    format!("{field}.material"),
                    format!("{:?}", desc.material),
                    format!("no material of that name; defined: [{}]", known.join(", ")),
                )
            })?;
            let local = match (&desc.shape, &desc.mesh) {
                (Some(shape), None) => self.shape(shape, &format!("{field}.shape"))?,
                (None, Some(mesh)) => self.mesh(mesh, &format!("{field}.mesh"))?,
                _ => {
                    return Err(self.err(
                        &field,
                        format!("{:?}", desc.name),
                        "give exactly one of `shape` and `mesh`",
                    ));
                }
            };
            let transform = format!("{field}.transform");
            let mut mesh = local.transformed(&self.transform(&desc.transform, &transform)?);
            if let Some(p) = mesh
                .positions
                .iter()
                .find(|p| !(p.is_finite() && within_coordinates(p.to_array())))
            {
                return Err(self.err(
                    transform,
                    format!("{:?}", p.to_array()),
                    format!("moves a vertex beyond |coordinate| ≤ {MAX_COORDINATE:e}"),
                ));
            }
            dropped += mesh.drop_degenerate();
            if mesh.indices.is_empty() {
                return Err(self.err(
                    &field,
                    format!("{:?}", desc.name),
                    "no non-degenerate triangles",
                ));
            }
            triangles += mesh.triangle_count() as u64;
            if triangles > MAX_SCENE_TRIANGLES {
                return Err(self.err(
                    &field,
                    format!("{triangles} triangles so far"),
                    format!("the scene has more than {MAX_SCENE_TRIANGLES} triangles"),
                ));
            }
            objects.push(Object {
                name: desc.name.clone(),
                material,
            });
            meshes.push(mesh);
        }
        Ok((objects, meshes, dropped))
    }

    fn transform(&self, t: &TransformDesc, field: &str) -> Result<Affine3A, InputError> {
        let translate = self.vec3(
            &format!("{field}.translate"),
            t.translate.unwrap_or([0.0; 3]),
        )?;
        let rotate = self.vec3(&format!("{field}.rotate"), t.rotate.unwrap_or([0.0; 3]))?;
        let scale = match t.scale {
            None => Vec3::ONE,
            Some(ScaleDesc::Uniform(s)) => Vec3::splat(s),
            Some(ScaleDesc::PerAxis(s)) => Vec3::from_array(s),
        };
        if !(scale.is_finite() && scale.cmpne(Vec3::ZERO).all()) {
            return Err(self.err(
                format!("{field}.scale"),
                format!("{scale}"),
                "must be finite and non-zero",
            ));
        }
        let r = rotate * (std::f32::consts::PI / 180.0);
        // X first, then Y, then Z (extrinsic).
        let rotation =
            Quat::from_rotation_z(r.z) * Quat::from_rotation_y(r.y) * Quat::from_rotation_x(r.x);
        Ok(Affine3A::from_scale_rotation_translation(
            scale, rotation, translate,
        ))
    }

    fn shape(&self, shape: &ShapeDesc, field: &str) -> Result<TriangleMesh, InputError> {
        let pos = |member: &str, x: f32| self.positive(&format!("{field}.{member}"), x);
        let at_least = |member: &str, x: u32, min: u32| {
            if x >= min {
                Ok(x)
            } else {
                Err(self.err(
                    format!("{field}.{member}"),
                    x.to_string(),
                    format!("must be ≥ {min}"),
                ))
            }
        };
        let budget = |triangles: u64| {
            if triangles <= MAX_SHAPE_TRIANGLES {
                Ok(())
            } else {
                Err(self.err(
                    field,
                    format!("{triangles} triangles"),
                    format!("more than {MAX_SHAPE_TRIANGLES} triangles"),
                ))
            }
        };
        Ok(match *shape {
            ShapeDesc::Sphere {
                radius,
                segments,
                rings,
            } => {
                let (s, r) = (
                    at_least("segments", segments.unwrap_or(64), 3)?,
                    at_least("rings", rings.unwrap_or(32), 2)?,
                );
                budget(2 * s as u64 * r as u64)?;
                shapes::uv_sphere(pos("radius", radius)?, s, r)
            }
            ShapeDesc::Box { size } => {
                let size = Vec3::from_array(size);
                if !(size.is_finite() && size.cmpgt(Vec3::ZERO).all()) {
                    return Err(self.err(
                        format!("{field}.size"),
                        format!("{size}"),
                        "each extent must be finite and > 0",
                    ));
                }
                shapes::cuboid(0.5 * size)
            }
            ShapeDesc::Slab { size, thickness } => shapes::slab(
                pos("size[0]", size[0])?,
                pos("size[1]", size[1])?,
                pos("thickness", thickness)?,
            ),
            ShapeDesc::Quad { size } => {
                shapes::quad(pos("size[0]", size[0])?, pos("size[1]", size[1])?)
            }
            ShapeDesc::Torus {
                major_radius,
                minor_radius,
                segments,
                sides,
            } => {
                let (s, k) = (
                    at_least("segments", segments.unwrap_or(96), 3)?,
                    at_least("sides", sides.unwrap_or(32), 3)?,
                );
                budget(2 * s as u64 * k as u64)?;
                shapes::torus(
                    pos("major_radius", major_radius)?,
                    pos("minor_radius", minor_radius)?,
                    s,
                    k,
                )
            }
            ShapeDesc::TorusKnot {
                p,
                q,
                radius,
                tube_radius,
                segments,
                sides,
            } => {
                let (s, k) = (
                    at_least("segments", segments.unwrap_or(384), 3)?,
                    at_least("sides", sides.unwrap_or(24), 3)?,
                );
                budget(2 * s as u64 * k as u64)?;
                let (p, q) = (at_least("p", p, 1)?, at_least("q", q, 1)?);
                shapes::torus_knot(
                    p,
                    q,
                    pos("radius", radius)?,
                    pos("tube_radius", tube_radius)?,
                    s,
                    k,
                )
            }
            ShapeDesc::BumpySphere {
                radius,
                amplitude,
                frequency,
                seed,
                subdivisions,
            } => {
                let subdivisions = subdivisions.unwrap_or(5);
                budget(20u64.saturating_mul(4u64.saturating_pow(subdivisions)))?;
                if !(amplitude.is_finite() && amplitude >= 0.0 && amplitude < radius) {
                    return Err(self.err(
                        format!("{field}.amplitude"),
                        amplitude.to_string(),
                        "must be finite, ≥ 0 and < radius",
                    ));
                }
                shapes::bumpy_sphere(
                    pos("radius", radius)?,
                    amplitude,
                    pos("frequency", frequency)?,
                    seed.unwrap_or(0),
                    subdivisions,
                )
            }
        })
    }

    /// A mesh file relative to the scene file's folder. A missing file is reported against the
    /// scene field; errors inside the mesh name the mesh file.
    fn mesh(&self, mesh: &str, field: &str) -> Result<TriangleMesh, InputError> {
        let path = self.file.parent().unwrap_or(Path::new("")).join(mesh);
        if !path.is_file() {
            return Err(self.err(
                field,
                format!("{mesh:?}"),
                format!("mesh file not found at {}", path.display()),
            ));
        }
        load_mesh(&path)
    }

    fn lights(&self, descs: &[LightDesc]) -> Result<Vec<Light>, InputError> {
        descs
            .iter()
            .enumerate()
            .map(|(i, desc)| {
                let f = |member: &str| format!("lights[{i}].{member}");
                Ok(match *desc {
                    LightDesc::Quad {
                        corner,
                        edge_u,
                        edge_v,
                        radiance,
                    } => {
                        let (u, v) = (
                            self.vec3(&f("edge_u"), edge_u)?,
                            self.vec3(&f("edge_v"), edge_v)?,
                        );
                        if u.cross(v).length_squared() == 0.0 {
                            return Err(self.err(
                                f("edge_v"),
                                format!("{v}"),
                                format!("parallel to edge_u {u}: zero area"),
                            ));
                        }
                        Light::Quad {
                            corner: self.vec3(&f("corner"), corner)?,
                            edge_u: u,
                            edge_v: v,
                            radiance: self.emission(&f("radiance"), radiance)?,
                        }
                    }
                    LightDesc::Triangle { vertices, radiance } => {
                        let v0 = self.vec3(&f("vertices[0]"), vertices[0])?;
                        let v1 = self.vec3(&f("vertices[1]"), vertices[1])?;
                        let v2 = self.vec3(&f("vertices[2]"), vertices[2])?;
                        if (v1 - v0).cross(v2 - v0).length_squared() == 0.0 {
                            return Err(self.err(
                                f("vertices"),
                                format!("{vertices:?}"),
                                "degenerate triangle: zero area",
                            ));
                        }
                        Light::Triangle {
                            vertices: [v0, v1, v2],
                            radiance: self.emission(&f("radiance"), radiance)?,
                        }
                    }
                    LightDesc::Sphere {
                        center,
                        radius,
                        radiance,
                    } => Light::Sphere {
                        center: self.vec3(&f("center"), center)?,
                        radius: self.positive(&f("radius"), radius)?,
                        radiance: self.emission(&f("radiance"), radiance)?,
                    },
                    LightDesc::Point {
                        position,
                        intensity,
                    } => Light::Point {
                        position: self.vec3(&f("position"), position)?,
                        intensity: self.emission(&f("intensity"), intensity)?,
                    },
                    LightDesc::Directional {
                        direction,
                        irradiance,
                    } => {
                        let d = self.vec3(&f("direction"), direction)?;
                        let direction = d.try_normalize().ok_or_else(|| {
                            self.err(f("direction"), format!("{d}"), "must be non-zero")
                        })?;
                        Light::Directional {
                            direction,
                            irradiance: self.emission(&f("irradiance"), irradiance)?,
                        }
                    }
                })
            })
            .collect()
    }

    /// The `[many_lights]` generator; `lights` lights are already defined.
    fn many_lights(&self, m: &ManyLightsDesc, lights: usize) -> Result<ManyLights, InputError> {
        let room = MAX_LIGHTS.saturating_sub(lights as u64).max(1);
        limits::count(self.file, "many_lights.count", m.count as u64, 1, room)?;
        let min = self.vec3("many_lights.region.min", m.region.min)?;
        let max = self.vec3("many_lights.region.max", m.region.max)?;
        if !min.cmple(max).all() {
            return Err(self.err(
                "many_lights.region.max",
                format!("{max}"),
                format!("must be ≥ region.min {min} per axis"),
            ));
        }
        let color = self.emission("many_lights.color", m.color.unwrap_or([1.0; 3]))?;
        let many = ManyLights {
            count: m.count,
            seed: m.seed,
            min,
            max,
            radius: self.positive("many_lights.radius", m.radius)?,
            total_power: m.total_power,
            color,
        };
        let radiance = many.radiance();
        if !(m.total_power > 0.0 && radiance.is_finite() && radiance.max_element() <= MAX_EMISSION)
        {
            return Err(self.err(
                "many_lights.total_power",
                m.total_power.to_string(),
                format!(
                    "must be > 0 and give each light a radiance ≤ {MAX_EMISSION:e} (gives {radiance})"
                ),
            ));
        }
        Ok(many)
    }
}

#[cfg(test)]
mod tests;
