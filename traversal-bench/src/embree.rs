//! Embree 3 through a minimal hand-written FFI: one triangle geometry per object (geometry id =
//! object id), single-ray `rtcIntersect1` / `rtcOccluded1`, and a context intersection filter for
//! the object-restricted queries. Layouts follow `embree3/rtcore_*.h` 3.13 with
//! `RTC_MAX_INSTANCE_LEVEL_COUNT = 1` and `EMBREE_MIN_WIDTH = 0` (checked by `build.rs`).

use std::ffi::{c_char, c_int, c_uint, c_void};

use geometry::{Ray, TriangleMesh};

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;
type RtcFilterFunctionN = Option<unsafe extern "C" fn(args: *const FilterArguments)>;

const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
const BUFFER_TYPE_INDEX: c_uint = 0;
const BUFFER_TYPE_VERTEX: c_uint = 1;
const FORMAT_UINT3: c_uint = 0x5003;
const FORMAT_FLOAT3: c_uint = 0x9003;
const SCENE_FLAG_CONTEXT_FILTER_FUNCTION: c_uint = 1 << 3;
const INTERSECT_CONTEXT_FLAG_INCOHERENT: c_uint = 0;
const INVALID_GEOMETRY_ID: c_uint = u32::MAX;
const DEVICE_PROPERTY_VERSION: c_uint = 0;

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: c_uint,
    id: c_uint,
    flags: c_uint,
}

#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: c_uint,
    geom_id: c_uint,
    inst_id: [c_uint; 1],
}

#[repr(C, align(16))]
struct RtcRayHit {
    ray: RtcRay,
    hit: RtcHit,
}

#[repr(C)]
struct RtcIntersectContext {
    flags: c_uint,
    filter: RtcFilterFunctionN,
    inst_id: [c_uint; 1],
}

#[repr(C)]
struct FilterArguments {
    valid: *mut c_int,
    geometry_user_ptr: *mut c_void,
    context: *mut RtcIntersectContext,
    /// `RTCRayN` / `RTCHitN` with N = 1: the same layout as `RTCRay` / `RTCHit`.
    ray: *mut RtcRay,
    hit: *mut RtcHit,
    n: c_uint,
}

#[link(name = "embree3")]
unsafe extern "C" {
    fn rtcNewDevice(config: *const c_char) -> RtcDevice;
    fn rtcReleaseDevice(device: RtcDevice);
    fn rtcGetDeviceError(device: RtcDevice) -> c_uint;
    fn rtcGetDeviceProperty(device: RtcDevice, property: c_uint) -> isize;
    fn rtcNewScene(device: RtcDevice) -> RtcScene;
    fn rtcReleaseScene(scene: RtcScene);
    fn rtcSetSceneFlags(scene: RtcScene, flags: c_uint);
    fn rtcCommitScene(scene: RtcScene);
    fn rtcNewGeometry(device: RtcDevice, kind: c_uint) -> RtcGeometry;
    fn rtcSetNewGeometryBuffer(
        geometry: RtcGeometry,
        kind: c_uint,
        slot: c_uint,
        format: c_uint,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    fn rtcCommitGeometry(geometry: RtcGeometry);
    fn rtcAttachGeometryByID(scene: RtcScene, geometry: RtcGeometry, id: c_uint);
    fn rtcReleaseGeometry(geometry: RtcGeometry);
    fn rtcIntersect1(scene: RtcScene, context: *mut RtcIntersectContext, rayhit: *mut RtcRayHit);
    fn rtcOccluded1(scene: RtcScene, context: *mut RtcIntersectContext, ray: *mut RtcRay);
}

/// Our context behind Embree's: the filter casts the context pointer back to it.
#[repr(C)]
struct FilterContext {
    base: RtcIntersectContext,
    object: c_uint,
    /// `Some`: record every hit on `object` and reject it (all hits); `None`: accept it.
    hits: Option<*mut Vec<(f32, u32)>>,
}

/// Keeps hits on `context.object` only; in collecting mode records and rejects them, so Embree
/// goes on to the next hit.
unsafe extern "C" fn object_filter(args: *const FilterArguments) {
    // SAFETY: Embree passes valid pointers for N = 1; `context` is the `base` of a FilterContext.
    unsafe {
        let args = &*args;
        let context = &*(args.context as *const FilterContext);
        let hit = &*args.hit;
        if hit.geom_id != context.object {
            *args.valid = 0;
        } else if let Some(hits) = context.hits {
            (*hits).push(((*args.ray).tfar, hit.prim_id));
            *args.valid = 0;
        }
    }
}

/// One Embree device and two scenes over the same meshes: a plain one (closest hit, occlusion,
/// the way applications use Embree) and one that runs the context filter.
pub struct Embree {
    device: RtcDevice,
    scene: RtcScene,
    filtered: RtcScene,
    /// Global triangle id of each object's first triangle.
    first_prim: Vec<u32>,
}

// SAFETY: committed Embree scenes are safe to query from several threads at once.
unsafe impl Sync for Embree {}
unsafe impl Send for Embree {}

fn context(filter: RtcFilterFunctionN) -> RtcIntersectContext {
    RtcIntersectContext {
        flags: INTERSECT_CONTEXT_FLAG_INCOHERENT,
        filter,
        inst_id: [INVALID_GEOMETRY_ID],
    }
}

fn rtc_ray(ray: &Ray) -> RtcRay {
    RtcRay {
        org: ray.origin.to_array(),
        tnear: ray.t_min,
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: ray.t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl Embree {
    /// Builds both scenes (Embree's default build quality); object id = index in `meshes`.
    pub fn new(meshes: &[TriangleMesh]) -> Result<Embree, String> {
        // SAFETY: plain Embree API use; buffers are sized by Embree from the counts we pass and
        // filled within those counts.
        unsafe {
            let device = rtcNewDevice(c"threads=2".as_ptr());
            if device.is_null() {
                return Err("rtcNewDevice failed".into());
            }
            let scene = rtcNewScene(device);
            let filtered = rtcNewScene(device);
            rtcSetSceneFlags(filtered, SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
            let mut first_prim = Vec::new();
            let mut total = 0u32;
            for (id, mesh) in meshes.iter().enumerate() {
                first_prim.push(total);
                total += mesh.indices.len() as u32;
                for target in [scene, filtered] {
                    let geometry = rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE);
                    let vertices = rtcSetNewGeometryBuffer(
                        geometry,
                        BUFFER_TYPE_VERTEX,
                        0,
                        FORMAT_FLOAT3,
                        12,
                        mesh.positions.len(),
                    ) as *mut [f32; 3];
                    let indices = rtcSetNewGeometryBuffer(
                        geometry,
                        BUFFER_TYPE_INDEX,
                        0,
                        FORMAT_UINT3,
                        12,
                        mesh.indices.len(),
                    ) as *mut [u32; 3];
                    if vertices.is_null() || indices.is_null() {
                        return Err(format!("rtcSetNewGeometryBuffer failed for object {id}"));
                    }
                    for (i, p) in mesh.positions.iter().enumerate() {
                        vertices.add(i).write(p.to_array());
                    }
                    for (i, t) in mesh.indices.iter().enumerate() {
                        indices.add(i).write(*t);
                    }
                    rtcCommitGeometry(geometry);
                    rtcAttachGeometryByID(target, geometry, id as c_uint);
                    rtcReleaseGeometry(geometry);
                }
            }
            rtcCommitScene(scene);
            rtcCommitScene(filtered);
            match rtcGetDeviceError(device) {
                0 => Ok(Embree {
                    device,
                    scene,
                    filtered,
                    first_prim,
                }),
                error => Err(format!("Embree error {error} while building")),
            }
        }
    }

    /// `major.minor.patch` of the loaded library.
    pub fn version(&self) -> String {
        // SAFETY: valid device.
        let v = unsafe { rtcGetDeviceProperty(self.device, DEVICE_PROPERTY_VERSION) };
        format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100)
    }

    fn global(&self, geom_id: u32, prim_id: u32) -> u32 {
        self.first_prim[geom_id as usize] + prim_id
    }

    fn intersect(
        &self,
        scene: RtcScene,
        ray: &Ray,
        context: *mut RtcIntersectContext,
    ) -> Option<(u32, f32)> {
        let mut rayhit = RtcRayHit {
            ray: rtc_ray(ray),
            hit: RtcHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: INVALID_GEOMETRY_ID,
                geom_id: INVALID_GEOMETRY_ID,
                inst_id: [INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: committed scene, initialised context and ray.
        unsafe { rtcIntersect1(scene, context, &mut rayhit) };
        (rayhit.hit.geom_id != INVALID_GEOMETRY_ID).then(|| {
            (
                self.global(rayhit.hit.geom_id, rayhit.hit.prim_id),
                rayhit.ray.tfar,
            )
        })
    }

    /// Closest hit: `(global triangle id, t)`.
    pub fn closest_hit(&self, ray: &Ray) -> Option<(u32, f32)> {
        self.intersect(self.scene, ray, &mut context(None))
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        let mut r = rtc_ray(ray);
        // SAFETY: committed scene, initialised context and ray.
        unsafe { rtcOccluded1(self.scene, &mut context(None), &mut r) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Closest hit on `object` (the filter rejects other objects).
    pub fn closest_hit_on_object(&self, ray: &Ray, object: u32) -> Option<(u32, f32)> {
        let mut context = FilterContext {
            base: context(Some(object_filter)),
            object,
            hits: None,
        };
        self.intersect(self.filtered, ray, &mut context.base)
    }

    /// Every hit on `object` as `(t, global triangle id)`, sorted by `t` then id, duplicates
    /// removed: the filter records each hit and rejects it so that traversal continues.
    pub fn all_hits_on_object(&self, ray: &Ray, object: u32, out: &mut Vec<(f32, u32)>) {
        out.clear();
        let mut context = FilterContext {
            base: context(Some(object_filter)),
            object,
            hits: Some(out as *mut _),
        };
        // The filter rejects every hit, so this returns no hit after visiting all of them.
        let none = self.intersect(self.filtered, ray, &mut context.base);
        debug_assert!(none.is_none());
        let first = self.first_prim[object as usize];
        for hit in out.iter_mut() {
            hit.1 += first;
        }
        out.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        out.dedup_by_key(|h| h.1);
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        // SAFETY: handles created in `new`, released once.
        unsafe {
            rtcReleaseScene(self.scene);
            rtcReleaseScene(self.filtered);
            rtcReleaseDevice(self.device);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geometry::Geometry;
    use geometry::shapes::cuboid;
    use glam::{Affine3A, Vec3, Vec3A};

    /// Two unit cubes on the x axis (centres 0 and 3) and a ray along +x through both: checks
    /// the hand-written layouts and the id mapping against reshift's answers.
    #[test]
    fn bindings_agree_with_reshift_on_two_cubes() {
        let cube = cuboid(Vec3::splat(0.5));
        let meshes = [
            cube.clone(),
            cube.transformed(&Affine3A::from_translation(Vec3::new(3.0, 0.0, 0.0))),
        ];
        let embree = Embree::new(&meshes).expect("Embree scene");
        let geometry = Geometry::new(&meshes);
        let ray = Ray::new(Vec3A::new(-2.0, 0.1, 0.2), Vec3A::X, 0.0, f32::INFINITY);

        let (prim, t) = embree.closest_hit(&ray).expect("hits the first cube");
        let ours = geometry.closest_hit(&ray).unwrap();
        assert_eq!(prim, ours.prim);
        assert!((t - 1.5).abs() < 1e-5, "t = {t}");

        assert!(embree.occluded(&ray));
        assert!(!embree.occluded(&Ray { t_max: 1.0, ..ray }));

        let (prim, t) = embree
            .closest_hit_on_object(&ray, 1)
            .expect("hits the second cube");
        assert_eq!(prim, geometry.closest_hit_on_object(&ray, 1).unwrap().prim);
        assert!(prim >= 12, "object 1's triangles follow object 0's 12");
        assert!((t - 4.5).abs() < 1e-5, "t = {t}");

        let (mut hits, mut ours) = (Vec::new(), Vec::new());
        for object in 0..2 {
            embree.all_hits_on_object(&ray, object, &mut hits);
            geometry.all_hits_on_object(&ray, object, &mut ours);
            ours.sort_by(|a, b| a.t.total_cmp(&b.t));
            let entry = 3.0 * object as f32 + 1.5;
            assert_eq!(hits.len(), 2, "object {object}: {hits:?}");
            assert!((hits[0].0 - entry).abs() < 1e-5 && (hits[1].0 - entry - 1.0).abs() < 1e-5);
            let prims: Vec<u32> = ours.iter().map(|h| h.prim).collect();
            assert_eq!(hits.iter().map(|h| h.1).collect::<Vec<_>>(), prims);
        }
    }
}
