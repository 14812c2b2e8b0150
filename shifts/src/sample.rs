//! The reservoir sample of ReSTIR SSS [001 Alg. 3]: the entry point x2, the light vertex x3 and
//! the BSSRDF IS random numbers that regenerate x2 from the x1 they belong to.

use bytemuck::{Pod, Zeroable};
use glam::{Vec2, Vec3};
use sss::bssrdf::{BssrdfSample, Technique};

/// The stored intersection index meaning *unknown* (deferred index policy).
pub const INDEX_UNKNOWN: u32 = u32::MAX;

/// One SSS path sample `[x0, x1, x2, x3]` without its pixel: x2 on a translucent object, x3 on a
/// light, and the random numbers of BSSRDF IS [001 Alg. 3].
///
/// `#[repr(C)]`, 64 bytes, laid out like a std430 `struct { vec3 x3; uint light; vec2 bary;
/// uint object; uint prim; uint technique; float u_radius; float u_angle; uint index;
/// float p_disk; }` padded to its 16-byte alignment.
///
/// For a directional light the stored x3 is where the light sampler put the vertex (far along
/// `−direction`); contributions and visibility use the light's direction instead, so the vertex
/// acts as the point at infinity.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SssSample {
    x3: [f32; 3],
    light: u32,
    bary: [f32; 2],
    object: u32,
    prim: u32,
    /// [`Technique::index`] = axis · 3 + channel.
    technique: u32,
    u_radius: f32,
    u_angle: f32,
    /// Rank of x2 among the probe's hits sorted by `t`, or [`INDEX_UNKNOWN`].
    index: u32,
    /// `p_disk(x2 | x1)` of the x1 whose random numbers are stored.
    p_disk: f32,
    padding: [u32; 3],
}

impl SssSample {
    /// Size of one sample in a GPU buffer.
    pub const BYTES: usize = std::mem::size_of::<SssSample>();

    /// The sample made of the BSSRDF part `bssrdf` and the light vertex x3 on light `light`.
    pub fn new(bssrdf: &BssrdfSample, light: u32, x3: Vec3) -> SssSample {
        SssSample {
            x3: x3.to_array(),
            light,
            bary: bssrdf.bary.to_array(),
            object: bssrdf.object,
            prim: bssrdf.prim,
            technique: bssrdf.technique.index() as u32,
            u_radius: bssrdf.u_radius,
            u_angle: bssrdf.u_angle,
            index: bssrdf.index.unwrap_or(INDEX_UNKNOWN),
            p_disk: bssrdf.p_disk,
            padding: [0; 3],
        }
    }

    /// The BSSRDF part; `None` if the stored technique index is not one of the nine (a corrupt
    /// buffer).
    pub fn bssrdf(&self) -> Option<BssrdfSample> {
        Some(BssrdfSample {
            object: self.object,
            prim: self.prim,
            bary: Vec2::from_array(self.bary),
            technique: self.technique()?,
            u_radius: self.u_radius,
            u_angle: self.u_angle,
            index: self.index(),
            p_disk: self.p_disk,
        })
    }

    /// The same light vertex with a new BSSRDF part (after replay or inversion).
    pub fn with_bssrdf(&self, bssrdf: &BssrdfSample) -> SssSample {
        SssSample::new(bssrdf, self.light, self.x3())
    }

    pub fn x3(&self) -> Vec3 {
        Vec3::from_array(self.x3)
    }

    pub fn light(&self) -> u32 {
        self.light
    }

    pub fn object(&self) -> u32 {
        self.object
    }

    pub fn prim(&self) -> u32 {
        self.prim
    }

    pub fn bary(&self) -> Vec2 {
        Vec2::from_array(self.bary)
    }

    pub fn technique(&self) -> Option<Technique> {
        Technique::ALL.get(self.technique as usize).copied()
    }

    pub fn u_radius(&self) -> f32 {
        self.u_radius
    }

    pub fn u_angle(&self) -> f32 {
        self.u_angle
    }

    /// The intersection index, `None` = unknown.
    pub fn index(&self) -> Option<u32> {
        (self.index != INDEX_UNKNOWN).then_some(self.index)
    }

    /// The same sample with intersection index `index` (`None` = unknown).
    pub fn with_index(&self, index: Option<u32>) -> SssSample {
        SssSample {
            index: index.unwrap_or(INDEX_UNKNOWN),
            ..*self
        }
    }

    /// The cached `p_disk(x2 | x1)` of the x1 whose random numbers are stored.
    pub fn p_disk(&self) -> f32 {
        self.p_disk
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss::bssrdf::Axis;

    fn bssrdf(index: Option<u32>) -> BssrdfSample {
        BssrdfSample {
            object: 3,
            prim: 77,
            bary: Vec2::new(0.25, 0.5),
            technique: Technique {
                axis: Axis::Tangent,
                channel: 2,
            },
            u_radius: 0.3,
            u_angle: 0.9,
            index,
            p_disk: 12.5,
        }
    }

    #[test]
    fn layout_is_gpu_sized_and_conversions_round_trip() {
        assert_eq!(SssSample::BYTES, 64);
        assert_eq!(std::mem::align_of::<SssSample>(), 4);
        for index in [Some(0), Some(4), None] {
            let s = SssSample::new(&bssrdf(index), 2, Vec3::new(1.0, 2.0, 3.0));
            assert_eq!(s.bssrdf(), Some(bssrdf(index)));
            assert_eq!((s.light(), s.x3()), (2, Vec3::new(1.0, 2.0, 3.0)));
            assert_eq!(s.index(), index);
            let bytes: &[u8] = bytemuck::bytes_of(&s);
            assert_eq!(*bytemuck::from_bytes::<SssSample>(bytes), s);
        }
        assert_eq!(
            SssSample::new(&bssrdf(Some(1)), 0, Vec3::ZERO)
                .with_index(None)
                .index(),
            None
        );
    }

    #[test]
    fn corrupt_technique_index_is_reported_not_defaulted() {
        let mut s = SssSample::new(&bssrdf(Some(1)), 0, Vec3::ZERO);
        s.technique = 9;
        assert_eq!(s.technique(), None);
        assert_eq!(s.bssrdf(), None);
    }
}
