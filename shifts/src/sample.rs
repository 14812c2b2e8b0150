//! The reservoir sample of ReSTIR SSS [001 Alg. 3] — the entry point x2, the light vertex x3 and
//! the BSSRDF IS random numbers that regenerate x2 from the x1 they belong to — and the stored
//! per-pixel reservoir. Both are declared in `contract.rs`, shared with
//! `shifts/glsl/sample.glsl`.

use bytemuck::Zeroable;
use glam::{Vec2, Vec3};
use restir::reservoir::Reservoir;
use sss::bssrdf::{BssrdfSample, Technique};

pub(crate) use crate::contract::SssSample;
use sss::contract::bssrdf::INDEX_UNKNOWN;

use crate::contract::PixelReservoir;

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

impl PixelReservoir {
    /// Bytes per pixel of one reservoir buffer.
    pub const BYTES: usize = std::mem::size_of::<PixelReservoir>();

    /// No sample, `W = 0`, `c = 0` (all bytes zero).
    pub fn empty() -> PixelReservoir {
        PixelReservoir::zeroed()
    }

    /// The reservoir in `restir`'s form.
    pub fn get(&self) -> Reservoir<SssSample> {
        Reservoir {
            y: (self.has_sample != 0).then_some(self.y),
            ucw: self.ucw,
            confidence: self.confidence,
        }
    }
}

impl Default for PixelReservoir {
    fn default() -> Self {
        PixelReservoir::empty()
    }
}

impl From<&Reservoir<SssSample>> for PixelReservoir {
    fn from(r: &Reservoir<SssSample>) -> PixelReservoir {
        PixelReservoir {
            y: r.y.unwrap_or_else(SssSample::zeroed),
            ucw: r.ucw,
            confidence: r.confidence,
            has_sample: r.y.is_some() as u32,
        }
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
        // [001 §5.2]: a reservoir of 64 bytes per pixel per buffer, here without quantisation.
        assert_eq!(SssSample::BYTES, 52);
        assert_eq!(PixelReservoir::BYTES, 64);
        assert_eq!(std::mem::align_of::<SssSample>(), 4);
        assert_eq!(std::mem::align_of::<PixelReservoir>(), 4);
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

    #[test]
    fn reservoir_layout_round_trips() {
        assert_eq!(PixelReservoir::BYTES, SssSample::BYTES + 12);
        let empty = Reservoir::<SssSample> {
            y: None,
            ucw: 0.0,
            confidence: 3.0,
        };
        assert_eq!(PixelReservoir::from(&empty).get(), empty);
        let mut sample = SssSample::zeroed();
        bytemuck::bytes_of_mut(&mut sample)[0] = 7;
        let full = Reservoir {
            y: Some(sample),
            ucw: 0.5,
            confidence: 2.0,
        };
        let stored = PixelReservoir::from(&full);
        assert_eq!(stored.get(), full);
        assert_eq!(
            *bytemuck::from_bytes::<PixelReservoir>(bytemuck::bytes_of(&stored)),
            stored
        );
    }
}
