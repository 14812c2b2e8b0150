//! `[[objects]]` → scene objects with their world-space meshes: procedural shapes, mesh files
//! (OBJ, PLY, glTF) beside the scene file (`mesh`) or in the asset directory (`asset`), placed
//! by their transform. A glTF file without a `material` becomes one object per material of its
//! primitives, each keeping the file's material unless the scene file defines one of that name
//! (the override, [`Materials::of_gltf`]).

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use geometry::limits::MAX_COORDINATE;
use geometry::load::MeshFormat;
use geometry::load::gltf::{GltfMaterial, load_gltf};
use geometry::{TriangleMesh, load_mesh};
use glam::{Affine3A, Quat, Vec3};

use super::{Ctx, within_coordinates};
use crate::InputError;
use crate::limits::{MAX_EMISSION, MAX_FRAMES, MAX_SCENE_TRIANGLES};
use crate::material::{Lambert, Material};
use crate::scene::format::{
    KeyDesc, MaterialDesc, ObjectDesc, RotateDesc, ScaleDesc, TransformDesc,
};
use crate::scene::motion::{Key, Keyframes};
use crate::scene::{Object, assets};

/// The scene's materials while objects are placed: the file's (by name, in file order) and the
/// ones glTF objects add after them.
pub(in crate::scene) struct Materials<'a> {
    pub list: Vec<Material>,
    pub ids: HashMap<String, u32>,
    /// The file's descriptions, for the materials that override a glTF file's.
    pub descs: &'a [MaterialDesc],
}

/// Objects and their world-space meshes (degenerate triangles dropped), in scene order.
#[derive(Default)]
pub(in crate::scene) struct Placed {
    pub objects: Vec<Object>,
    pub meshes: Vec<TriangleMesh>,
    /// Per object, its motion (`None` at rest).
    pub keyframes: Vec<Option<Keyframes>>,
    /// Degenerate triangles removed.
    pub dropped: usize,
    triangles: u64,
    names: HashSet<String>,
}

impl Placed {
    /// Adds the object `name` of material `material` with its world-space `mesh` (errors at
    /// `field`: a vertex out of range, no triangle left, a duplicate name, too many triangles).
    pub fn push(
        &mut self,
        ctx: &Ctx,
        field: &str,
        name: String,
        material: u32,
        mut mesh: TriangleMesh,
    ) -> Result<(), InputError> {
        if let Some(p) = mesh
            .positions
            .iter()
            .find(|p| !(p.is_finite() && within_coordinates(p.to_array())))
        {
            return Err(ctx.err(
                format!("{field}.transform"),
                format!("{:?}", p.to_array()),
                format!("moves a vertex beyond |coordinate| ≤ {MAX_COORDINATE:e}"),
            ));
        }
        self.dropped += mesh.drop_degenerate();
        if mesh.indices.is_empty() {
            return Err(ctx.err(field, format!("{name:?}"), "no non-degenerate triangles"));
        }
        self.triangles += mesh.triangle_count() as u64;
        if self.triangles > MAX_SCENE_TRIANGLES {
            return Err(ctx.err(
                field,
                format!("{} triangles so far", self.triangles),
                format!("the scene has more than {MAX_SCENE_TRIANGLES} triangles"),
            ));
        }
        if !self.names.insert(name.clone()) {
            return Err(ctx.err(
                format!("{field}.name"),
                format!("{name:?}"),
                "duplicate object name",
            ));
        }
        self.objects.push(Object { name, material });
        self.meshes.push(mesh);
        self.keyframes.push(None);
        Ok(())
    }
}

/// Where an object's triangles come from.
enum Source<'a> {
    Shape(&'a crate::scene::format::ShapeDesc),
    /// A mesh file.
    File(PathBuf),
}

impl Ctx<'_> {
    /// Places every object of the file; glTF objects may add materials to `materials`.
    pub(super) fn objects(
        &self,
        descs: &[ObjectDesc],
        materials: &mut Materials,
    ) -> Result<Placed, InputError> {
        if descs.is_empty() {
            return Err(self.err("objects", "[]", "the scene has no objects"));
        }
        let mut placed = Placed::default();
        for (i, desc) in descs.iter().enumerate() {
            let field = format!("objects[{i}]");
            let first = placed.objects.len();
            let source = self.source(desc, &field)?;
            let xf = self.transform(&desc.transform, &format!("{field}.transform"))?;
            let is_gltf = |path: &Path| {
                matches!(MeshFormat::of(path), Ok(MeshFormat::Gltf | MeshFormat::Glb))
            };
            match (&source, &desc.material) {
                (Source::File(path), None) if is_gltf(path) => {
                    self.gltf_objects(&field, &desc.name, path, &xf, materials, &mut placed)?;
                }
                (_, Some(name)) => {
                    let material = self.material_id(&field, name, materials)?;
                    let local = match source {
                        Source::Shape(shape) => self.shape(shape, &format!("{field}.shape"))?,
                        Source::File(path) => load_mesh(&path)?,
                    };
                    placed.push(
                        self,
                        &field,
                        desc.name.clone(),
                        material,
                        local.transformed(&xf),
                    )?;
                }
                (_, None) => {
                    return Err(self.err(
                        format!("{field}.material"),
                        "(missing)",
                        "required but for glTF files (whose primitives keep their materials)",
                    ));
                }
            }
            if let Some(keys) = &desc.motion {
                self.motion(
                    keys,
                    &format!("{field}.motion"),
                    first,
                    &mut placed,
                    materials,
                )?;
            }
        }
        Ok(placed)
    }

    /// The `motion` of the objects `first..` that one `[[objects]]` entry placed: its keys
    /// checked, one pivot (the centre of their bounds) for all of them. Refused: no key, frames
    /// not increasing or past [`MAX_FRAMES`], an emissive object, a pose past
    /// [`MAX_COORDINATE`].
    fn motion(
        &self,
        descs: &[KeyDesc],
        field: &str,
        first: usize,
        placed: &mut Placed,
        materials: &Materials,
    ) -> Result<(), InputError> {
        if descs.is_empty() {
            return Err(self.err(field, "[]", "needs at least one key"));
        }
        if descs.len() as u64 > MAX_FRAMES as u64 {
            return Err(self.err(
                field,
                format!("{} keys", descs.len()),
                format!("more keys than frames ({MAX_FRAMES})"),
            ));
        }
        for object in &placed.objects[first..] {
            let material = &materials.list[object.material as usize];
            if matches!(material, Material::Lambert(l) if l.is_emitter()) {
                return Err(self.err(
                    field,
                    format!("{:?}", object.name),
                    "an emissive object cannot move (its triangles are lights, placed once)",
                ));
            }
        }
        let (lo, hi) = TriangleMesh::bounds_of(&placed.meshes[first..]);
        let pivot = 0.5 * (lo + hi);
        let reach = pivot.abs().max_element() + (hi - lo).length();
        let mut keys: Vec<Key> = Vec::with_capacity(descs.len());
        for (k, desc) in descs.iter().enumerate() {
            let at = |member: &str| format!("{field}[{k}].{member}");
            if let Some(before) = keys.last().map(|key| key.frame)
                && desc.frame <= before
            {
                return Err(self.err(
                    at("frame"),
                    desc.frame.to_string(),
                    format!("must be greater than the previous key's frame {before}"),
                ));
            }
            if desc.frame >= MAX_FRAMES {
                return Err(self.err(
                    at("frame"),
                    desc.frame.to_string(),
                    format!("must be below {MAX_FRAMES}"),
                ));
            }
            let translation = self.vec3(&at("translate"), desc.translate.unwrap_or([0.0; 3]))?;
            if reach + translation.abs().max_element() > MAX_COORDINATE {
                return Err(self.err(
                    at("translate"),
                    format!("{translation}"),
                    format!("moves a vertex beyond |coordinate| ≤ {MAX_COORDINATE:e}"),
                ));
            }
            keys.push(Key {
                frame: desc.frame,
                rotation: self.rotation(desc.rotate, &at("rotate"))?,
                translation,
            });
        }
        let keyframes = Keyframes::new(pivot, keys);
        for slot in &mut placed.keyframes[first..] {
            *slot = Some(keyframes.clone());
        }
        Ok(())
    }

    /// The id of the file's material `name`, or an error at `{field}.material` listing them.
    fn material_id(
        &self,
        field: &str,
        name: &str,
        materials: &Materials,
    ) -> Result<u32, InputError> {
        materials.ids.get(name).copied().ok_or_else(|| {
            let mut known: Vec<&str> = materials.ids.keys().map(String::as_str).collect();
            known.sort_unstable();
            self.err(
                format!("{field}.material"),
                format!("{name:?}"),
                format!("no material of that name; defined: [{}]", known.join(", ")),
            )
        })
    }

    /// The object's `shape`, `mesh` (relative to the scene file's folder) or `asset` (relative to
    /// the asset directory): exactly one of them; a missing file is reported at its field.
    fn source<'d>(&self, desc: &'d ObjectDesc, field: &str) -> Result<Source<'d>, InputError> {
        match (&desc.shape, &desc.mesh, &desc.asset) {
            (Some(shape), None, None) => Ok(Source::Shape(shape)),
            (None, Some(mesh), None) => {
                let field = format!("{field}.mesh");
                let path = self.file.parent().unwrap_or(Path::new("")).join(mesh);
                if !path.is_file() {
                    return Err(self.err(
                        field,
                        format!("{mesh:?}"),
                        format!("mesh file not found at {}", path.display()),
                    ));
                }
                Ok(Source::File(path))
            }
            (None, None, Some(asset)) => {
                let path = assets::resolve(self.file, &format!("{field}.asset"), asset)?;
                Ok(Source::File(path))
            }
            _ => Err(self.err(
                field,
                format!("{:?}", desc.name),
                "give exactly one of `shape`, `mesh` and `asset`",
            )),
        }
    }

    /// The objects of glTF file `path`: one per material of its primitives (named `name`, or
    /// `name/<material>` when there are several), each of the file's material or of the scene
    /// file's material of the same name.
    fn gltf_objects(
        &self,
        field: &str,
        name: &str,
        path: &Path,
        xf: &Affine3A,
        materials: &mut Materials,
        placed: &mut Placed,
    ) -> Result<(), InputError> {
        let file = load_gltf(path)?;
        let mut groups: BTreeMap<Option<usize>, Vec<TriangleMesh>> = BTreeMap::new();
        for primitive in file.primitives {
            groups
                .entry(primitive.material)
                .or_default()
                .push(primitive.mesh);
        }
        let several = groups.len() > 1;
        for (index, meshes) in groups {
            let gltf = index.map(|i| &file.materials[i]);
            let label = gltf_label(gltf, index);
            let material = materials.of_gltf(self, path, gltf, index)?;
            let object = if several {
                format!("{name}/{label}")
            } else {
                name.to_string()
            };
            let mesh = TriangleMesh::merged(&meshes);
            placed.push(self, field, object, material, mesh.transformed(xf))?;
        }
        Ok(())
    }

    /// `transform = { translate, rotate, scale }` as an affine map: scale, then rotate, then
    /// translate.
    pub(super) fn transform(&self, t: &TransformDesc, field: &str) -> Result<Affine3A, InputError> {
        let translate = self.vec3(
            &format!("{field}.translate"),
            t.translate.unwrap_or([0.0; 3]),
        )?;
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
        let rotation = self.rotation(t.rotate, &format!("{field}.rotate"))?;
        Ok(Affine3A::from_scale_rotation_translation(
            scale, rotation, translate,
        ))
    }

    /// Euler angles applied X, then Y, then Z (extrinsic), or a rotation about one axis.
    fn rotation(&self, rotate: Option<RotateDesc>, field: &str) -> Result<Quat, InputError> {
        let degrees = std::f32::consts::PI / 180.0;
        match rotate {
            None => Ok(Quat::IDENTITY),
            Some(RotateDesc::Euler(angles)) => {
                let r = self.vec3(field, angles)? * degrees;
                Ok(Quat::from_rotation_z(r.z)
                    * Quat::from_rotation_y(r.y)
                    * Quat::from_rotation_x(r.x))
            }
            Some(RotateDesc::Axis(a)) => {
                let axis = self.vec3(&format!("{field}.axis"), a.axis)?;
                let axis = axis.try_normalize().ok_or_else(|| {
                    self.err(
                        format!("{field}.axis"),
                        format!("{axis}"),
                        "must be non-zero",
                    )
                })?;
                if !(a.degrees.is_finite() && a.degrees.abs() <= MAX_COORDINATE) {
                    return Err(self.err(
                        format!("{field}.degrees"),
                        a.degrees.to_string(),
                        format!("must be finite, |degrees| ≤ {MAX_COORDINATE:e}"),
                    ));
                }
                Ok(Quat::from_axis_angle(axis, a.degrees * degrees))
            }
        }
    }
}

/// A glTF material's name in object names and errors: its name, else `material[<index>]`, or
/// `default` for primitives without one.
fn gltf_label(material: Option<&GltfMaterial>, index: Option<usize>) -> String {
    match (material.and_then(|m| m.name.clone()), index) {
        (Some(name), _) => name,
        (None, Some(i)) => format!("material[{i}]"),
        (None, None) => "default".to_string(),
    }
}

impl Materials<'_> {
    /// A new material for the primitives of glTF file `path` with material `gltf` (number
    /// `index` of the file; `None`: glTF's default material): the scene file's material of the
    /// same name, its missing fields from `gltf`, or else `gltf` itself as a Lambert surface
    /// (base colour factor as albedo, textures not read, emissive where it emits).
    fn of_gltf(
        &mut self,
        ctx: &Ctx,
        path: &Path,
        gltf: Option<&GltfMaterial>,
        index: Option<usize>,
    ) -> Result<u32, InputError> {
        let name = gltf.and_then(|m| m.name.as_deref());
        let overriding = name.and_then(|n| self.descs.iter().position(|d| d.name() == n));
        let material = match (overriding, gltf) {
            (Some(at), _) => ctx.material(&self.descs[at], &format!("materials[{at}]"), gltf)?,
            (None, Some(m)) => Material::Lambert(gltf_lambert(path, m, index)?),
            (None, None) => Material::Lambert(Lambert::new(Vec3::ONE)),
        };
        self.list.push(material);
        Ok(self.list.len() as u32 - 1)
    }
}

/// A glTF material as a Lambert surface, its values checked (errors name the glTF file).
fn gltf_lambert(
    path: &Path,
    m: &GltfMaterial,
    index: Option<usize>,
) -> Result<Lambert, InputError> {
    let element = |member: &str| format!("materials[{}].{member}", index.unwrap_or(0));
    let [r, g, b, _] = m.base_color;
    if ![r, g, b].iter().all(|c| (0.0..=1.0).contains(c)) {
        return Err(InputError::new(
            path,
            element("pbrMetallicRoughness.baseColorFactor"),
            format!("{:?}", m.base_color),
            "each channel must lie in [0, 1]",
        ));
    }
    if !m.emission.iter().all(|e| (0.0..=MAX_EMISSION).contains(e)) {
        return Err(InputError::new(
            path,
            element("emissiveFactor"),
            format!("{:?}", m.emission),
            format!(
                "emissiveFactor × KHR_materials_emissive_strength must lie in [0, {MAX_EMISSION:e}]"
            ),
        ));
    }
    Ok(Lambert {
        albedo: Vec3::new(r, g, b),
        emission: Vec3::from_array(m.emission),
        two_sided: m.double_sided,
    })
}
