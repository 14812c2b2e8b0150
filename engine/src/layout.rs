//! GPU buffer layouts of the pipeline (DESIGN §6): the per-pixel reservoir that passes read and
//! write. `#[repr(C)]`, `Pod`, 16-byte multiple so a std430 array of them has no gaps.

use bytemuck::{Pod, Zeroable};
use restir::reservoir::Reservoir;
use shifts::SssSample;

/// A stored reservoir `{y, W, c}` of one pixel [001 Alg. 2]. Layout (std430):
/// `struct { SssSample y; float ucw; float confidence; uint has_sample; uint padding; }`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct PixelReservoir {
    pub sample: SssSample,
    /// Unbiased contribution weight `W` (`ucw`), finite and ≥ 0.
    pub ucw: f32,
    /// Confidence weight `c`.
    pub confidence: f32,
    /// 1 when `sample` holds the selected sample, 0 for an empty reservoir.
    pub has_sample: u32,
    padding: u32,
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
            y: (self.has_sample != 0).then_some(self.sample),
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
            sample: r.y.unwrap_or_else(SssSample::zeroed),
            ucw: r.ucw,
            confidence: r.confidence,
            has_sample: r.y.is_some() as u32,
            padding: 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_is_a_16_byte_multiple_and_round_trips() {
        assert_eq!(PixelReservoir::BYTES % 16, 0);
        assert_eq!(PixelReservoir::BYTES, SssSample::BYTES + 16);
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
