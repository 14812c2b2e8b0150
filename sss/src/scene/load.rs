//! Scene file → [`Scene`]: TOML parsing with field paths in every error, semantic validation, and
//! construction of materials ([`material`]), objects and their meshes ([`objects`], [`shape`]),
//! lights (the file's, the generated ones and the emitters' triangles) and camera.

mod material;
mod objects;
mod shape;

use std::path::Path;
use std::sync::Arc;

use geometry::limits::MAX_COORDINATE;
use geometry::{Geometry, TriangleMesh};
use glam::Vec3;

use super::emitter_field::{DEFAULT_COLORS, EmitterField, MAX_DRAWS};
use super::format::{CameraDesc, EmitterFieldDesc, LightDesc, ManyLightsDesc, SceneFile};
use super::light::{Light, Lights};
use super::many_lights::ManyLights;
use super::motion::Motion;
use super::parse::parse;
use super::{Camera, Scene};
use crate::InputError;
use crate::limits::{self, MAX_EMISSION, MAX_LIGHTS};
use crate::material::Material;
use objects::Placed;

/// Parses and builds a scene; `origin` names the file in errors and anchors relative mesh paths.
pub fn scene_from_toml(text: &str, origin: &Path) -> Result<Scene, InputError> {
    let file: SceneFile = parse(text, origin)?;
    let ctx = Ctx { file: origin };
    let camera = ctx.camera(&file.camera)?;
    let mut materials = ctx.materials(&file.materials)?;
    let mut placed = ctx.objects(&file.objects, &mut materials)?;
    if let Some(field) = &file.emitter_field {
        let generated = ctx.emitter_field(field)?.generate().map_err(|i| {
            ctx.err(
                "emitter_field.exclude",
                format!("rectangle {i}"),
                format!("leaves no room: every one of {MAX_DRAWS} draws reached into the box"),
            )
        })?;
        for (i, (mesh, lambert)) in generated.into_iter().enumerate() {
            materials.list.push(Material::Lambert(lambert));
            let id = materials.list.len() as u32 - 1;
            placed.push(&ctx, "emitter_field", format!("emitter[{i}]"), id, mesh)?;
        }
    }
    let materials = materials.list;
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
    ctx.emitters(&placed, &materials, &mut lights)?;
    if lights.is_empty() {
        return Err(ctx.err(
            "lights",
            "[]",
            "the scene has no lights (add [[lights]], [many_lights] or an emissive material)",
        ));
    }
    let Placed {
        objects,
        meshes,
        keyframes,
        dropped: dropped_degenerate,
        ..
    } = placed;
    let (lo, hi) = TriangleMesh::bounds_of(&meshes);
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
    let (geometry, motion) = if keyframes.iter().any(Option::is_some) {
        let motion = Motion::new(meshes, keyframes);
        (motion.geometry_at(0), Some(Arc::new(motion)))
    } else {
        (Arc::new(Geometry::new(&meshes)), None)
    };
    Ok(Scene {
        name,
        file: origin.to_path_buf(),
        camera,
        materials,
        objects,
        geometry,
        motion,
        posed_at: 0,
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
    pub(super) fn positive(&self, field: &str, x: f32) -> Result<f32, InputError> {
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
                    LightDesc::Triangle {
                        vertices,
                        radiance,
                        two_sided,
                    } => {
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
                            two_sided: two_sided.unwrap_or(false),
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

impl Ctx<'_> {
    /// The triangles of every emissive object as lights ([`Light::Triangle`], one- or two-sided
    /// as its material), appended to `lights` in object order, within [`MAX_LIGHTS`].
    fn emitters(
        &self,
        placed: &Placed,
        materials: &[Material],
        lights: &mut Vec<Light>,
    ) -> Result<(), InputError> {
        for (object, mesh) in placed.objects.iter().zip(&placed.meshes) {
            let Material::Lambert(lambert) = materials[object.material as usize] else {
                continue;
            };
            if !lambert.is_emitter() {
                continue;
            }
            if (lights.len() + mesh.triangle_count()) as u64 > MAX_LIGHTS {
                return Err(self.err(
                    "objects",
                    format!(
                        "{:?}: {} emissive triangles",
                        object.name,
                        mesh.triangle_count()
                    ),
                    format!("the scene has more than {MAX_LIGHTS} lights"),
                ));
            }
            lights.extend((0..mesh.triangle_count()).map(|t| Light::Triangle {
                vertices: mesh.triangle(t),
                radiance: lambert.emission,
                two_sided: lambert.two_sided,
            }));
        }
        Ok(())
    }

    /// The `[emitter_field]` generator, its fields checked.
    fn emitter_field(&self, f: &EmitterFieldDesc) -> Result<EmitterField, InputError> {
        limits::count(
            self.file,
            "emitter_field.count",
            f.count as u64,
            1,
            MAX_LIGHTS / 2,
        )?;
        let min = self.vec3("emitter_field.region.min", f.region.min)?;
        let max = self.vec3("emitter_field.region.max", f.region.max)?;
        if !min.cmple(max).all() {
            return Err(self.err(
                "emitter_field.region.max",
                format!("{max}"),
                format!("must be ≥ region.min {min} per axis"),
            ));
        }
        let [scale_min, scale_max] = f.scale;
        self.positive("emitter_field.scale[0]", scale_min)?;
        if !(self.positive("emitter_field.scale[1]", scale_max)? >= scale_min) {
            return Err(self.err(
                "emitter_field.scale",
                format!("{:?}", f.scale),
                "must be [min, max] with 0 < min ≤ max",
            ));
        }
        if !(f.strength > 0.0 && f.strength <= MAX_EMISSION) {
            return Err(self.err(
                "emitter_field.strength",
                f.strength.to_string(),
                format!("must lie in (0, {MAX_EMISSION:e}]"),
            ));
        }
        let colors = f.colors.clone().unwrap_or(DEFAULT_COLORS.to_vec());
        if colors.is_empty() || colors.len() > 1024 {
            return Err(self.err(
                "emitter_field.colors",
                format!("{} colours", colors.len()),
                "give 1 to 1024 colours",
            ));
        }
        let colors = (0..colors.len())
            .map(|i| self.emission(&format!("emitter_field.colors[{i}]"), colors[i]))
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(c) = colors
            .iter()
            .find(|c| (*c * f.strength).max_element() > MAX_EMISSION)
        {
            return Err(self.err(
                "emitter_field.strength",
                f.strength.to_string(),
                format!("times colour {c} exceeds {MAX_EMISSION:e}"),
            ));
        }
        let albedo = f.albedo.unwrap_or([1.0; 3]);
        if !albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
            return Err(self.err(
                "emitter_field.albedo",
                format!("{albedo:?}"),
                "each channel must lie in [0, 1]",
            ));
        }
        Ok(EmitterField {
            count: f.count,
            seed: f.seed,
            min,
            max,
            scale_min,
            scale_max,
            strength: f.strength,
            colors,
            albedo: Vec3::from_array(albedo),
            two_sided: f.two_sided.unwrap_or(true),
            exclude: f
                .exclude
                .as_ref()
                .map(|r| {
                    let lo = self.vec3("emitter_field.exclude.min", r.min)?;
                    let hi = self.vec3("emitter_field.exclude.max", r.max)?;
                    Ok([lo, hi])
                })
                .transpose()?,
        })
    }
}

#[cfg(test)]
mod tests;
