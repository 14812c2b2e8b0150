use super::*;
use crate::error::MAX_MESSAGE_CHARS;
use crate::material::BoundaryKind;
use crate::profile::ScaleFit;
use crate::scene::Object;
use crate::scene::Scene;
use crate::scene::format::{RotateDesc, ScaleDesc, TransformDesc};
use glam::Affine3A;

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
    let doc = include_str!("../../../../docs/scene-format.md");
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
        rotate: Some(RotateDesc::Euler([90.0, 90.0, 0.0])),
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

/// Two triangles (z = 0 facing +z, z = 1 facing −z) in one buffer, each its own primitive of
/// its own material: "wax" (overridden by the scene file, its ior 1.6 inherited) and "lamp"
/// (emissive 2 × 3, two-sided, base colour 0.25 grey, left to the file).
const TWO_MATERIALS_GLTF: &str = r#"{
  "asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_materials_ior", "KHR_materials_emissive_strength"],
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0}, "material": 0},
    {"attributes": {"POSITION": 1}, "material": 1}
  ]}],
  "materials": [
    {"name": "wax", "extensions": {"KHR_materials_ior": {"ior": 1.6}}},
    {"name": "lamp", "doubleSided": true, "emissiveFactor": [1.0, 0.5, 0.25],
     "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 3.0}},
     "pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.25, 0.25, 1.0]}}
  ],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 1, 0]},
    {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 1], "max": [1, 1, 1]}
  ],
  "bufferViews": [{"buffer": 0, "byteLength": 72}],
  "buffers": [{"byteLength": 72, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAAAAAAAAAAAAAAAIA/AAAAAAAAgD8AAIA/AACAPwAAAAAAAIA/"}]
}"#;

/// A glTF object without a `material` becomes one object per material of its primitives
/// (`name/<material>`): the scene file's `wax` overrides the file's and takes the file's ior,
/// the file's emissive `lamp` becomes a two-sided Lambert emitter whose triangle is a light, and
/// the object's transform applies after the file's nodes. With a `material`, the file is one
/// object of it.
#[test]
fn gltf_objects_keep_or_override_the_files_materials() {
    let dir = scratch("gltf-materials");
    std::fs::write(dir.join("two.gltf"), TWO_MATERIALS_GLTF).unwrap();
    let text = edit(
        "[[objects]]\nname = \"ball\"\nmaterial = \"wax\"\nshape = { type = \"sphere\", radius = 0.5 }",
        "[[objects]]\nname = \"thing\"\nmesh = \"two.gltf\"\ntransform = { translate = [0.0, 0.0, -2.0] }",
    );
    let scene = Scene::from_toml_str(&text, &dir.join("scene.toml")).unwrap();
    let names: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["thing/wax", "thing/lamp"]);
    let Material::Translucent(wax) = *scene.material_of_object(0) else {
        panic!("wax is translucent")
    };
    assert_eq!((wax.ior, wax.albedo), (1.6, Vec3::new(0.8, 0.6, 0.4)));
    let Material::Lambert(lamp) = *scene.material_of_object(1) else {
        panic!("lamp is Lambert")
    };
    assert_eq!(lamp.emission, Vec3::new(3.0, 1.5, 0.75));
    assert!(lamp.two_sided && lamp.albedo == Vec3::splat(0.25));
    // The point light of MINIMAL, then the lamp's one triangle, at z = 1 − 2.
    assert_eq!(scene.lights.len(), 2);
    let Light::Triangle {
        vertices,
        radiance,
        two_sided,
    } = *scene.lights.get(1)
    else {
        panic!("the lamp's triangle")
    };
    assert!(two_sided && radiance == lamp.emission);
    assert!(vertices.iter().all(|v| v.z == -1.0), "{vertices:?}");
    let one = edit(
        "[[objects]]\nname = \"ball\"\nmaterial = \"wax\"\nshape = { type = \"sphere\", radius = 0.5 }",
        "[[objects]]\nname = \"thing\"\nmaterial = \"floor\"\nmesh = \"two.gltf\"",
    );
    let scene = Scene::from_toml_str(&one, &dir.join("scene.toml")).unwrap();
    assert_eq!((scene.objects.len(), scene.lights.len()), (1, 1));
    assert_eq!(scene.geometry.triangle_count(), 2);
    let missing = edit("material = \"wax\"\nshape", "shape");
    assert_rejected(&missing, "objects[0].material", "(missing)");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `motion` keys load as keyframes about the object's pivot (its placed bounds' centre); bad
/// keys are refused in one line naming the key: none, frames not increasing or too large, a
/// pose past the coordinate limit, an emissive object that moves. Control: the same keys on a
/// scene without motion load it at rest.
#[test]
fn motion_keys_load_and_bad_keys_are_rejected() {
    let ball = r#"shape = { type = "sphere", radius = 0.5 }"#;
    let moving = |keys: &str| {
        edit(
            ball,
            &format!("{ball}\ntransform = {{ translate = [1.0, 0.0, 0.0] }}\nmotion = {keys}"),
        )
    };
    let scene = load(&moving(
        "[{ frame = 0 }, { frame = 10, translate = [0.0, 2.0, 0.0], rotate = { axis = [0.0, 0.0, 1.0], degrees = 120.0 } }]",
    ))
    .unwrap();
    let motion = scene.motion.as_ref().expect("the ball moves");
    assert_eq!(scene.moving_object(), Some("ball"));
    // Halfway: up by 1 and turned 60° about z through the pivot (1, 0, 0); the pivot's
    // neighbour one unit along +x turns 60° toward +y.
    let at5 = motion.transform(0, 5);
    assert!(
        (at5.transform_point3(Vec3::new(1.0, 0.0, 0.0)) - Vec3::new(1.0, 1.0, 0.0)).length() < 1e-5
    );
    let turned = at5.transform_point3(Vec3::new(2.0, 0.0, 0.0));
    let want = Vec3::new(1.5, 1.0 + 0.75f32.sqrt(), 0.0);
    assert!((turned - want).length() < 1e-5, "{turned}");
    assert_eq!(motion.transform(0, 0), Affine3A::IDENTITY);
    assert!(load(MINIMAL).unwrap().motion.is_none());

    assert_rejected(&moving("[]"), "objects[0].motion", "[]");
    assert_rejected(
        &moving("[{ frame = 3 }, { frame = 3 }]"),
        "objects[0].motion[1].frame",
        "3",
    );
    assert_rejected(
        &moving("[{ frame = 70000 }]"),
        "objects[0].motion[0].frame",
        "70000",
    );
    assert_rejected(
        &moving("[{ frame = 0, translate = [1e9, 0.0, 0.0] }]"),
        "objects[0].motion[0].translate",
        "1000000000",
    );
    assert_rejected(
        &moving("[{ frame = 0, rotate = { axis = [0.0, 0.0, 0.0], degrees = 10.0 } }]"),
        "objects[0].motion[0].rotate.axis",
        "0",
    );
    let glowing = moving("[{ frame = 0 }]").replace(
        "albedo = [0.8, 0.6, 0.4]\nmfp = [0.1, 0.05, 0.02]",
        "albedo = [0.8, 0.6, 0.4]\nmfp = [0.1, 0.05, 0.02]\n\n[[materials]]\nname = \"lamp\"\ntype = \"lambert\"\nalbedo = [1.0, 1.0, 1.0]\nemission = [1.0, 1.0, 1.0]",
    );
    let glowing = glowing.replacen("material = \"wax\"", "material = \"lamp\"", 1);
    assert_rejected(&glowing, "objects[0].motion", "ball");
}
