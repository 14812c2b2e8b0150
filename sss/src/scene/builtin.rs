//! The built-in scenes: the TOML files of `scenes/`, embedded so they work from any directory.
//! [`BUILTIN`] recreate paper 001 §6's evaluation setups with procedural geometry;
//! [`WITH_ASSETS`] are paper 001's own scenes, whose meshes come from the asset directory.

/// `(name, one-line description)` of every built-in scene.
pub const BUILTIN: &[(&str, &str)] = &[
    (
        "bumpy",
        "bumpy translucent sphere, Lambert floor, one large quad light, occluder shadow edge (001 Fig. 6)",
    ),
    (
        "many-lights",
        "the bumpy scene lit by 512 small seeded sphere lights (001 Fig. 7)",
    ),
    (
        "materials",
        "gallery of the ten measured materials of Jensen et al. 2001 (001 Fig. 8)",
    ),
    (
        "mfp-0.25",
        "the bumpy scene with mean free paths scaled by 0.25 (001 Fig. 9)",
    ),
    (
        "mfp-0.5",
        "the bumpy scene with mean free paths scaled by 0.5 (001 Fig. 9)",
    ),
    (
        "mfp-1",
        "the bumpy scene with mean free paths scaled by 1 (001 Fig. 9)",
    ),
    (
        "mfp-2",
        "the bumpy scene with mean free paths scaled by 2 (001 Fig. 9)",
    ),
    (
        "mfp-4",
        "the bumpy scene with mean free paths scaled by 4 (001 Fig. 9)",
    ),
    (
        "slab",
        "thin translucent slab lit from behind: light bleeding",
    ),
    (
        "half-shadow",
        "translucent plane, directional light, shadow exactly over x < 0 (analytic BSSRDF check)",
    ),
    (
        "passing",
        "the bumpy scene with a small wax sphere moving across in front of the object (moving objects, disocclusion)",
    ),
    (
        "far-knot",
        "fine thin torus knot 1000 units from the origin: re-traced probe chords miss x2 (deferred-index stress)",
    ),
];

/// `(name, one-line description)` of every scene of the project that reads its meshes from the
/// asset directory (`super::assets`): paper 001's own scenes.
pub const WITH_ASSETS: &[(&str, &str)] = &[
    (
        "ajax",
        "paper 001's Ajax bust (glTF assets), backdrop and one large two-sided emissive plane, 720x1080 (001 Fig. 6)",
    ),
    (
        "ajax-many-lights",
        "the Ajax bust and backdrop lit by 512 small seeded emissive rectangles, 720x1080 (001 Fig. 7)",
    ),
];

/// The TOML text of built-in scene `name`.
pub fn source(name: &str) -> Option<&'static str> {
    Some(match name {
        "bumpy" => include_str!("../../../scenes/bumpy.toml"),
        "many-lights" => include_str!("../../../scenes/many-lights.toml"),
        "materials" => include_str!("../../../scenes/materials.toml"),
        "mfp-0.25" => include_str!("../../../scenes/mfp-0.25.toml"),
        "mfp-0.5" => include_str!("../../../scenes/mfp-0.5.toml"),
        "mfp-1" => include_str!("../../../scenes/mfp-1.toml"),
        "mfp-2" => include_str!("../../../scenes/mfp-2.toml"),
        "mfp-4" => include_str!("../../../scenes/mfp-4.toml"),
        "slab" => include_str!("../../../scenes/slab.toml"),
        "half-shadow" => include_str!("../../../scenes/half-shadow.toml"),
        "passing" => include_str!("../../../scenes/passing.toml"),
        "far-knot" => include_str!("../../../scenes/far-knot.toml"),
        "ajax" => include_str!("../../../scenes/ajax.toml"),
        "ajax-many-lights" => include_str!("../../../scenes/ajax-many-lights.toml"),
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::Material;
    use crate::scene::{GBuffer, Light, Scene};
    use geometry::Ray;
    use glam::{Vec3, Vec3A, vec3};
    use std::path::Path;

    /// Every built-in scene parses, from the embedded text and from its file on disk, stays under
    /// 100k triangles, has a translucent object, and keeps every `d` ≥ 1e-3 (ten times the BVH's
    /// 1e-4 hit tolerance). The `scenes/` folder holds exactly these files.
    #[test]
    fn every_builtin_parses_and_is_sane() {
        let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
        let mut on_disk: Vec<String> = std::fs::read_dir(&folder)
            .unwrap()
            .filter_map(|e| {
                e.unwrap()
                    .file_name()
                    .to_str()?
                    .strip_suffix(".toml")
                    .map(str::to_string)
            })
            .collect();
        on_disk.sort();
        let mut names: Vec<String> = BUILTIN
            .iter()
            .chain(WITH_ASSETS)
            .map(|(n, _)| n.to_string())
            .collect();
        names.sort();
        assert_eq!(on_disk, names);
        for (name, description) in BUILTIN {
            assert!(!description.is_empty());
            let scene = Scene::builtin(name).unwrap();
            assert_eq!(scene.name, *name);
            let from_disk = Scene::load(&folder.join(format!("{name}.toml"))).unwrap();
            assert_eq!(from_disk.lights, scene.lights);
            assert_eq!(
                from_disk.geometry.triangle_count(),
                scene.geometry.triangle_count()
            );
            assert!(
                scene.geometry.triangle_count() <= 100_000,
                "{name}: {}",
                scene.geometry.triangle_count()
            );
            assert_eq!(scene.dropped_degenerate, 0, "{name}");
            let d_min = scene
                .materials
                .iter()
                .filter_map(|m| match m {
                    Material::Translucent(t) => Some(t.d().min_element()),
                    Material::Lambert(_) => None,
                })
                .fold(f32::INFINITY, f32::min);
            assert!(d_min >= 1e-3, "{name}: smallest d = {d_min}");
        }
        assert!(Scene::builtin("nonexistent").is_none());
        assert_eq!(Scene::builtin("materials").unwrap().objects.len(), 11);
    }

    /// Paper 001's scenes load from the shared assets as `SCENES.md` places them: `ajax` has the
    /// bust (60 000 triangles, translucent, d = 0.5 · mfp / s(A) with the diffuse-transmission
    /// fit, ior 1.45 from the file), the backdrop (3 200) and the emissive plane (2 two-sided
    /// triangles, the only lights, at the documented corners); `ajax-many-lights` has 512
    /// rectangles and their 1 024 two-sided lights instead of the plane.
    #[test]
    fn paper_scenes_load_from_the_shared_assets() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        if crate::scene::assets::shared_or_skip(root, "paper scenes").is_none() {
            return;
        }
        let ajax = Scene::builtin("ajax").unwrap();
        let names: Vec<&str> = ajax.objects.iter().map(|o| o.name.as_str()).collect();
        assert_eq!(names, ["ajax", "backdrop", "light"]);
        let triangles = |object: u32| {
            (0..ajax.geometry.triangle_count())
                .filter(|&p| ajax.geometry.object_of(p) == object)
                .count()
        };
        assert_eq!(
            [triangles(0), triangles(1), triangles(2)],
            [60_000, 3_200, 2]
        );
        let Material::Translucent(skin) = *ajax.material_of_object(0) else {
            panic!("the bust is translucent")
        };
        assert_eq!(skin.ior, 1.45);
        let d = skin.d();
        for (got, want) in d.to_array().into_iter().zip([0.46591, 0.09007, 0.04315]) {
            assert!((got - want).abs() < 1e-4, "d = {d}");
        }
        assert_eq!(ajax.lights.len(), 2);
        let mut corners = Vec::new();
        for light in ajax.lights.iter() {
            let Light::Triangle {
                vertices,
                radiance,
                two_sided,
            } = *light
            else {
                panic!("{light:?}")
            };
            assert!(two_sided && radiance == Vec3::splat(16.5), "{light:?}");
            corners.extend(vertices);
        }
        for want in [
            vec3(-30.0, 27.314, -21.686),
            vec3(2.0, 27.314, -21.686),
            vec3(-30.0, 4.686, -44.314),
            vec3(2.0, 4.686, -44.314),
        ] {
            assert!(
                corners.iter().any(|c| c.distance(want) < 2e-3),
                "corner {want} not in {corners:?}"
            );
        }
        let many = Scene::builtin("ajax-many-lights").unwrap();
        assert_eq!(many.objects.len(), 2 + 512);
        assert_eq!(many.lights.len(), 1024);
        assert!(many.lights.iter().all(|l| matches!(
            l,
            Light::Triangle {
                two_sided: true,
                ..
            }
        )));
        assert_eq!(
            many.lights,
            Scene::builtin("ajax-many-lights").unwrap().lights,
            "seeded"
        );
    }

    #[test]
    fn many_lights_scene_is_deterministic() {
        let a = Scene::builtin("many-lights").unwrap();
        let b = Scene::builtin("many-lights").unwrap();
        assert_eq!(a.lights.len(), 512);
        assert_eq!(a.lights, b.lights);
        assert!(a.lights.iter().all(|l| matches!(l, Light::Sphere { .. })));
    }

    fn occluded(scene: &Scene, from: Vec3, to: Vec3) -> bool {
        scene
            .geometry
            .occluded(&Ray::segment(Vec3A::from(from), Vec3A::from(to)))
    }

    /// The half-shadow geometry documented in `half-shadow.toml`: the occluder's edge is exactly
    /// x = 0, the light is straight down, plane points are shadowed iff x < 0, and the camera
    /// sees only the plane, on both sides of the edge.
    #[test]
    fn half_shadow_geometry_is_exact() {
        let scene = Scene::builtin("half-shadow").unwrap();
        assert_eq!(scene.objects[0].name, "plane");
        let Light::Directional { direction, .. } = *scene.lights.get(0) else {
            panic!("directional")
        };
        assert_eq!(direction, vec3(0.0, -1.0, 0.0));
        let occluder_max_x = (0..scene.geometry.triangle_count())
            .filter(|&p| scene.geometry.object_of(p) == 1)
            .flat_map(|p| scene.geometry.vertices(p))
            .map(|v| v.x)
            .fold(f32::NEG_INFINITY, f32::max);
        assert_eq!(occluder_max_x, 0.0);
        for x in [-4.0, -0.5, -1e-3, 1e-3, 0.5, 4.0] {
            for z in [-4.0, 0.0, 3.0] {
                let p = vec3(x, 0.0, z);
                let s = scene.lights.sample(p, [0.5; 3]).unwrap();
                assert_eq!(s.wi, Vec3::Y);
                assert_eq!(
                    occluded(&scene, p + 1e-4 * Vec3::Y, s.point),
                    x < 0.0,
                    "({x}, {z})"
                );
            }
        }
        let g = GBuffer::render(&scene, 0);
        let hits: Vec<_> = g.pixels.iter().flatten().collect();
        assert_eq!(hits.len(), g.pixels.len(), "the plane fills the view");
        assert!(hits.iter().all(|h| h.object == 0));
        let left = hits.iter().filter(|h| h.position.x < 0.0).count();
        assert!(
            left > hits.len() / 4 && left < 3 * hits.len() / 4,
            "edge near the image centre: {left}"
        );
    }

    /// The `bumpy` scene shows lit, penumbra and shadowed parts of the object: from the object's
    /// G-buffer points, the light's four corners and centre are all visible, some, or none.
    #[test]
    fn bumpy_scene_has_lit_penumbra_and_shadowed_regions() {
        let scene = Scene::builtin("bumpy").unwrap();
        let Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        } = *scene.lights.get(0)
        else {
            panic!("quad light")
        };
        let targets = [
            corner,
            corner + edge_u,
            corner + edge_v,
            corner + edge_u + edge_v,
            corner + 0.5 * (edge_u + edge_v),
        ];
        let g = GBuffer::render(&scene, 0);
        let mut counts = [0usize; 3];
        let mut object_pixels = 0;
        for h in g.pixels.iter().flatten().filter(|h| h.object == 0) {
            object_pixels += 1;
            let from = h.position + 1e-4 * h.geometric_normal;
            let visible = targets
                .iter()
                .filter(|&&t| {
                    h.geometric_normal.dot(t - h.position) > 0.0 && !occluded(&scene, from, t)
                })
                .count();
            counts[match visible {
                0 => 0,
                5 => 2,
                _ => 1,
            }] += 1;
        }
        assert!(object_pixels > 1000, "object covers {object_pixels} pixels");
        let [shadowed, penumbra, lit] = counts;
        eprintln!(
            "bumpy: shadowed {shadowed}, penumbra {penumbra}, lit {lit} of {object_pixels} object pixels"
        );
        assert!(
            counts.iter().all(|&c| c * 20 > object_pixels),
            "shadowed {shadowed}, penumbra {penumbra}, lit {lit} of {object_pixels}"
        );
        // The occluder causes the shadow: without it every region would be lit or self-shadowed.
        let occluder_shadow = g
            .pixels
            .iter()
            .flatten()
            .filter(|h| h.object == 0)
            .filter(|h| {
                let c = targets[4];
                h.geometric_normal.dot(c - h.position) > 0.0
                    && occluded(&scene, h.position + 1e-4 * h.geometric_normal, c)
            })
            .count();
        assert!(
            occluder_shadow * 10 > object_pixels,
            "front-facing yet occluded: {occluder_shadow}"
        );
    }
}
