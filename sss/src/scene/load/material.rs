//! `[[materials]]` → materials: translucent (parameters or a measured preset with overrides)
//! and Lambert (optionally emissive), each checked; a material that overrides a glTF file's
//! takes the fields it leaves out from the file.

use std::collections::HashMap;

use geometry::load::gltf::GltfMaterial;
use glam::Vec3;

use super::Ctx;
use super::objects::Materials;
use crate::InputError;
use crate::limits::MAX_EMISSION;
use crate::material::{BoundaryKind, Lambert, MEASURED_NAMES, Material, Translucent, measured};
use crate::profile::ScaleFit;
use crate::scene::format::{BoundaryDesc, FitDesc, MaterialDesc};

impl Ctx<'_> {
    /// The file's materials, by name (names unique).
    pub(super) fn materials<'d>(
        &self,
        descs: &'d [MaterialDesc],
    ) -> Result<Materials<'d>, InputError> {
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
            materials.push(self.material(desc, &field, None)?);
        }
        Ok(Materials {
            list: materials,
            ids,
            descs,
        })
    }

    /// The material `desc` (at `field`); where it overrides the glTF material `gltf`, the
    /// fields it leaves out come from `gltf` (`ior`; `emission`, `two_sided`).
    pub(super) fn material(
        &self,
        desc: &MaterialDesc,
        field: &str,
        gltf: Option<&GltfMaterial>,
    ) -> Result<Material, InputError> {
        match desc {
            MaterialDesc::Lambert {
                albedo,
                emission,
                two_sided,
                ..
            } => {
                if !albedo.iter().all(|a| (0.0..=1.0).contains(a)) {
                    return Err(self.err(
                        format!("{field}.albedo"),
                        format!("{albedo:?}"),
                        "each channel must lie in [0, 1]",
                    ));
                }
                let emission = emission.or(gltf.map(|m| m.emission)).unwrap_or([0.0; 3]);
                if !emission.iter().all(|e| (0.0..=MAX_EMISSION).contains(e)) {
                    return Err(self.err(
                        format!("{field}.emission"),
                        format!("{emission:?}"),
                        format!("each channel must lie in [0, {MAX_EMISSION:e}]"),
                    ));
                }
                Ok(Material::Lambert(Lambert {
                    albedo: Vec3::from_array(*albedo),
                    emission: Vec3::from_array(emission),
                    two_sided: two_sided.or(gltf.map(|m| m.double_sided)).unwrap_or(false),
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
                    ior: ior.or(gltf.map(|m| m.ior)).unwrap_or(base.ior),
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
}
