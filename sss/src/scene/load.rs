//! Scene file → [`Scene`]: TOML parsing with field paths in every error, semantic validation, and
//! construction of materials, meshes, lights and camera.

use std::collections::HashMap;
use std::path::Path;

use geometry::limits::MAX_COORDINATE;
use geometry::{Geometry, TriangleMesh, load_mesh, shapes};
use glam::{Affine3A, Quat, Vec3};

use super::format::{
    BoundaryDesc, CameraDesc, FitDesc, LightDesc, ManyLightsDesc, MaterialDesc, ObjectDesc,
    ScaleDesc, ShapeDesc, TransformDesc,
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
    let file = parse(text, origin)?;
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
struct Ctx<'a> {
    file: &'a Path,
}

fn finite3(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn within_coordinates(v: [f32; 3]) -> bool {
    v.iter().all(|x| x.abs() <= MAX_COORDINATE)
}

impl Ctx<'_> {
    fn err(
        &self,
        field: impl Into<String>,
        value: impl Into<String>,
        reason: impl Into<String>,
    ) -> InputError {
        InputError::new(self.file, field, value, reason)
    }

    /// A finite 3-vector within [`MAX_COORDINATE`] or an error at `field`.
    fn vec3(&self, field: &str, v: [f32; 3]) -> Result<Vec3, InputError> {
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
            let view = target[end] - eye[end];
            if view.cross(up.normalize()).length() <= 1e-6 * view.length()
                || view.length_squared() == 0.0
            {
                return Err(self.err(
                    field,
                    format!("{}", target[end]),
                    format!(
                        "view direction from eye {} is zero or parallel to up {}",
                        eye[end], up
                    ),
                ));
            }
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
mod tests {
    use super::*;
    use crate::error::MAX_MESSAGE_CHARS;
    use crate::scene::Scene;

    const ORIGIN: &str = "tests/minimal.toml";

    const MINIMAL: &str = r#"
[camera]
resolution = [32, 24]
vfov = 40.0
eye = [0.0, 0.0, 3.0]
target = [0.0, 0.0, 0.0]

[[materials]]
name = "wax"
type = "translucent"
albedo = [0.8, 0.6, 0.4]
mfp = [0.1, 0.05, 0.02]

[[materials]]
name = "floor"
type = "lambert"
albedo = [0.5, 0.5, 0.5]

[[objects]]
name = "ball"
material = "wax"
shape = { type = "sphere", radius = 0.5 }

[[lights]]
type = "point"
position = [0.0, 2.0, 2.0]
intensity = [1.0, 1.0, 1.0]
"#;

    fn load(text: &str) -> Result<Scene, InputError> {
        Scene::from_toml_str(text, Path::new(ORIGIN))
    }

    /// `MINIMAL` with `from` replaced by `to` (which must occur).
    fn edit(from: &str, to: &str) -> String {
        assert!(MINIMAL.contains(from), "test bug: {from:?} not in MINIMAL");
        MINIMAL.replacen(from, to, 1)
    }

    /// The text must fail with exactly `field`, a value containing `value`, and a message that
    /// names the file, the field and the value.
    fn assert_rejected(text: &str, field: &str, value: &str) {
        let err = match load(text) {
            Ok(_) => panic!("accepted, expected an error at {field}"),
            Err(e) => e,
        };
        let message = err.to_string();
        assert_eq!(err.field, field, "{message}");
        assert!(
            err.value.contains(value),
            "value {:?} lacks {value:?}: {message}",
            err.value
        );
        for part in [ORIGIN, field, value] {
            assert!(message.contains(part), "{message:?} does not name {part:?}");
        }
    }

    #[test]
    fn minimal_scene_loads_with_defaults() {
        let scene = load(MINIMAL).unwrap();
        assert_eq!(scene.name, "minimal");
        assert_eq!((scene.camera.width(), scene.camera.height()), (32, 24));
        assert!(scene.camera.jittered());
        assert_eq!(
            scene.objects,
            vec![Object {
                name: "ball".into(),
                material: 0
            }]
        );
        assert_eq!(scene.lights.len(), 1);
        assert_eq!(scene.dropped_degenerate, 0);
        let Material::Translucent(m) = scene.material_of_object(0) else {
            panic!("translucent")
        };
        assert_eq!(
            (m.scale, m.ior, m.g, m.fit, m.boundary),
            (1.0, 1.3, 0.0, ScaleFit::Searchlight, BoundaryKind::Diffuse)
        );
        assert_eq!(scene.file, Path::new(ORIGIN));
    }

    /// `boundary` takes each interface (and `index-matched` for `index_matched`); anything else
    /// is an error naming the material and the value (serde reports an unknown variant of the
    /// tagged material at the material's path).
    #[test]
    fn boundary_names_the_interface() {
        let cases = [
            ("diffuse", BoundaryKind::Diffuse),
            ("dielectric", BoundaryKind::Dielectric),
            ("index_matched", BoundaryKind::IndexMatched),
            ("index-matched", BoundaryKind::IndexMatched),
        ];
        for (value, kind) in cases {
            let text = edit("mfp = [", &format!("boundary = \"{value}\"\nmfp = ["));
            let scene = load(&text).unwrap();
            let Material::Translucent(m) = scene.material_of_object(0) else {
                panic!("translucent")
            };
            assert_eq!(m.boundary, kind, "{value}");
        }
        // The value is the whole material table, which the one-line message elides in its
        // middle; serde's reason still names the rejected variant.
        let Err(err) = load(&edit("mfp = [", "boundary = \"smooth\"\nmfp = [")) else {
            panic!("boundary = \"smooth\" accepted")
        };
        let message = err.to_string();
        assert_eq!(err.field, "materials[0]", "{message}");
        assert!(err.value.contains("boundary = \"smooth\""), "{message}");
        for part in [ORIGIN, "materials[0]", "unknown variant `smooth`"] {
            assert!(message.contains(part), "{message:?} does not name {part:?}");
        }
    }

    #[test]
    fn malformed_toml_names_line_and_text() {
        assert_rejected(
            &edit("vfov = 40.0", "vfov = 40.0 degrees"),
            "line 4, column 8",
            "vfov = 40.0 degrees",
        );
    }

    #[test]
    fn unknown_and_mistyped_fields_name_their_path() {
        assert_rejected(
            &edit("name = \"ball\"", "name = \"ball\"\ncolour = 3"),
            "objects[0].colour",
            "3",
        );
        assert_rejected(
            &edit("vfov = 40.0", "vfov = \"wide\""),
            "camera.vfov",
            "\"wide\"",
        );
        assert_rejected(
            &edit("radius = 0.5", "radius = 0.5, segment = 8"),
            "objects[0].shape",
            "segment = 8",
        );
    }

    #[test]
    fn unknown_names_are_rejected() {
        assert_rejected(
            &edit("material = \"wax\"", "material = \"jade\""),
            "objects[0].material",
            "\"jade\"",
        );
        assert_rejected(
            &edit("type = \"sphere\"", "type = \"cone\""),
            "objects[0].shape.type",
            "\"cone\"",
        );
        assert_rejected(
            &edit("albedo = [0.8, 0.6, 0.4]", "preset = \"granite\""),
            "materials[0].preset",
            "\"granite\"",
        );
        assert_rejected(
            &edit("type = \"point\"", "type = \"spot\""),
            "lights[0].type",
            "\"spot\"",
        );
    }

    #[test]
    fn bad_material_parameters_are_rejected() {
        assert_rejected(
            &edit("mfp = [0.1, 0.05, 0.02]", "mfp = [nan, 0.05, 0.02]"),
            "materials[0].mfp",
            "NaN",
        );
        assert_rejected(
            &edit("mfp = [0.1, 0.05, 0.02]", "mfp = [0.1, -0.05, 0.02]"),
            "materials[0].mfp",
            "-0.05",
        );
        assert_rejected(
            &edit("albedo = [0.8, 0.6, 0.4]", "albedo = [1.5, 0.6, 0.4]"),
            "materials[0].albedo",
            "1.5",
        );
        assert_rejected(
            &edit("albedo = [0.5, 0.5, 0.5]", "albedo = [0.5, -0.1, 0.5]"),
            "materials[1].albedo",
            "-0.1",
        );
        assert_rejected(
            &edit("mfp = [0.1, 0.05, 0.02]", ""),
            "materials[0].mfp",
            "(missing)",
        );
    }

    #[test]
    fn empty_scenes_and_zero_resolution_are_rejected() {
        let no_objects = edit(
            "[[objects]]\nname = \"ball\"\nmaterial = \"wax\"\nshape = { type = \"sphere\", radius = 0.5 }",
            "",
        );
        assert_rejected(&no_objects, "objects", "[]");
        let no_lights = edit(
            "[[lights]]\ntype = \"point\"\nposition = [0.0, 2.0, 2.0]\nintensity = [1.0, 1.0, 1.0]",
            "",
        );
        assert_rejected(&no_lights, "lights", "[]");
        assert_rejected(
            &edit("resolution = [32, 24]", "resolution = [0, 24]"),
            "camera.resolution",
            "0×24",
        );
        assert_rejected(
            &edit("intensity = [1.0, 1.0, 1.0]", "intensity = [0.0, 0.0, 0.0]"),
            "lights[0].intensity",
            "[0.0, 0.0, 0.0]",
        );
        assert_rejected(
            &edit("radius = 0.5", "radius = -0.5"),
            "objects[0].shape.radius",
            "-0.5",
        );
        assert_rejected(
            &edit("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 3.0]"),
            "camera.target",
            "[0, 0, 3]",
        );
    }

    /// Sizes that would allocate without bound and values that would overflow downstream are
    /// rejected at their field, before anything is built.
    #[test]
    fn sizes_and_absurd_values_are_rejected() {
        assert_rejected(
            &edit("resolution = [32, 24]", "resolution = [100000, 100000]"),
            "camera.resolution",
            "100000×100000",
        );
        assert_rejected(
            &edit("resolution = [32, 24]", "resolution = [16384, 16384]"),
            "camera.resolution",
            "16384×16384",
        );
        assert_rejected(
            &edit(
                "intensity = [1.0, 1.0, 1.0]",
                "intensity = [1e38, 1.0, 1.0]",
            ),
            "lights[0].intensity",
            "1e38",
        );
        assert_rejected(
            &edit("eye = [0.0, 0.0, 3.0]", "eye = [0.0, 0.0, 3e30]"),
            "camera.eye",
            "3e30",
        );
        assert_rejected(
            &edit("radius = 0.5", "radius = 0.5 }\ntransform = { scale = 1e30"),
            "objects[0].transform",
            "5e29",
        );
        let many = |count: &str, radius: &str| {
            format!(
                "{MINIMAL}\n[many_lights]\ncount = {count}\nseed = 1\nradius = {radius}\n\
                 total_power = 10.0\nregion = {{ min = [0.0, 0.0, 0.0], max = [1.0, 1.0, 1.0] }}\n"
            )
        };
        assert!(load(&many("16", "0.01")).is_ok());
        assert_rejected(
            &many("4000000000", "0.01"),
            "many_lights.count",
            "4000000000",
        );
        assert_rejected(&many("16", "1e-20"), "many_lights.total_power", "10");
    }

    /// A syntax error deep inside a 200 000-character line shows the text around the error,
    /// and the whole message is one line of at most 200 characters.
    #[test]
    fn syntax_errors_in_long_lines_show_an_excerpt() {
        let deep = format!("vfov = {}x", "[".repeat(200_000));
        let error = load(&edit("vfov = 40.0", &deep)).err().expect("rejected");
        assert!(error.value.chars().count() < 100, "{}", error.value);
        let message = error.to_string();
        assert!(message.chars().count() <= MAX_MESSAGE_CHARS, "{message}");
        assert!(
            message.starts_with(ORIGIN) && message.contains("line 4"),
            "{message}"
        );
    }

    /// A scratch folder for mesh files, unique to this process and test.
    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("reshift-scene-{}-{name}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn missing_mesh_is_rejected() {
        let text = edit(
            "shape = { type = \"sphere\", radius = 0.5 }",
            "mesh = \"meshes/none.obj\"",
        );
        assert_rejected(&text, "objects[0].mesh", "\"meshes/none.obj\"");
    }

    /// An OBJ with one good, one collinear and one repeated-vertex triangle loads relative to the
    /// scene file, and the two degenerate ones are dropped and counted.
    #[test]
    fn degenerate_mesh_triangles_are_dropped_and_counted() {
        let dir = scratch("degenerate");
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
        std::fs::write(dir.join("tri.obj"), obj).unwrap();
        let text = edit(
            "shape = { type = \"sphere\", radius = 0.5 }",
            "mesh = \"tri.obj\"",
        );
        let scene = Scene::from_toml_str(&text, &dir.join("scene.toml")).unwrap();
        assert_eq!(scene.dropped_degenerate, 2);
        assert_eq!(scene.geometry.triangle_count(), 1);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The example of `docs/scene-format.md` loads (with a stand-in PLY for its mesh).
    #[test]
    fn documented_example_loads() {
        let doc = include_str!("../../../docs/scene-format.md");
        let start = doc.find("```toml\n").expect("an example") + "```toml\n".len();
        let example = &doc[start..start + doc[start..].find("```").unwrap()];
        let dir = scratch("doc-example");
        std::fs::create_dir_all(dir.join("meshes")).unwrap();
        let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                   property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n\
                   0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
        std::fs::write(dir.join("meshes/bunny.ply"), ply).unwrap();
        let scene = Scene::from_toml_str(example, &dir.join("example.toml")).unwrap();
        assert_eq!(scene.objects.len(), 3);
        assert_eq!(scene.objects[1].material, 1);
        assert_eq!(
            scene.geometry.triangle_count() as usize,
            20 * 4usize.pow(5) + 4 + 2
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Transforms apply scale, then X, Y, Z rotations, then the translation.
    #[test]
    fn transform_order_is_scale_rotate_xyz_translate() {
        let ctx = Ctx {
            file: Path::new(ORIGIN),
        };
        let t = TransformDesc {
            translate: Some([1.0, 2.0, 3.0]),
            rotate: Some([90.0, 90.0, 0.0]),
            scale: Some(ScaleDesc::PerAxis([2.0, 1.0, 1.0])),
        };
        let xf = ctx.transform(&t, "t").unwrap();
        // x̂ → scale → 2x̂ → Rx(90°) → 2x̂ → Ry(90°) → −2ẑ → + (1, 2, 3).
        let p = xf.transform_point3(Vec3::X);
        assert!((p - Vec3::new(1.0, 2.0, 1.0)).length() < 1e-5, "{p}");
        // ŷ → Rx(90°) → ẑ → Ry(90°) → x̂.
        let q = xf.transform_vector3(Vec3::Y);
        assert!((q - Vec3::X).length() < 1e-5, "{q}");
        let bad = TransformDesc {
            scale: Some(ScaleDesc::Uniform(0.0)),
            ..TransformDesc::default()
        };
        assert_eq!(
            ctx.transform(&bad, "objects[3].transform")
                .unwrap_err()
                .field,
            "objects[3].transform.scale"
        );
    }
}
