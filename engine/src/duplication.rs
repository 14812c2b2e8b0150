//! The duplication map [PTE]: per pixel, how many pixels of the frame hold a final sample with
//! the same x2 (object, triangle, barycentrics). Spatial reuse copies one good sample into many
//! pixels; the map counts the copies. The telemetry reports it (`diagnostics::Telemetry::sharing`),
//! and `restir:<preset>/duplication=divides` divides a temporal history's confidence by it
//! (`shifts::preset::Duplication`).

use std::collections::HashMap;

use shifts::PixelReservoir;

/// Per pixel of `reservoirs` (a frame's final ones), the number of pixels whose sample has the
/// same x2, itself included: 1 for a sample no other pixel holds, 0 without a sample. The counts
/// do not depend on the order the pixels are visited in.
pub fn sharing(reservoirs: &[PixelReservoir]) -> Vec<u32> {
    let key = |r: &PixelReservoir| {
        let b = r.y.bary();
        let (object, prim) = (r.y.object(), r.y.prim());
        (r.has_sample != 0).then_some((object, prim, b.x.to_bits(), b.y.to_bits()))
    };
    let mut holders: HashMap<(u32, u32, u32, u32), u32> = HashMap::new();
    for k in reservoirs.iter().filter_map(key) {
        *holders.entry(k).or_default() += 1;
    }
    reservoirs
        .iter()
        .map(|r| key(r).map_or(0, |k| holders[&k]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Vec2, Vec3};
    use shifts::SssSample;
    use sss::bssrdf::{BssrdfSample, EntryPoint, Probe, TechniqueSelection};

    /// Three pixels hold one x2, one pixel another, one none: counts 3, 3, 3, 1, 0, whatever
    /// else the samples carry (a copy keeps x2; its light or weight may differ).
    #[test]
    fn pixels_holding_one_x2_count_each_other() {
        let probe = Probe::sample(&TechniqueSelection::default(), 0.1, 0.2, 0.3);
        let with = |prim: u32, light: u32| {
            let x2 = EntryPoint {
                object: 0,
                prim,
                bary: Vec2::new(0.25, 0.5),
                position: Vec3::ZERO,
                geometric_normal: Vec3::Y,
                shading_normal: Vec3::Y,
            };
            let bssrdf = BssrdfSample::new(&probe, Some(0), &x2, 1.0);
            let mut r = PixelReservoir::empty();
            r.y = SssSample::new(&bssrdf, light, Vec3::splat(light as f32));
            r.has_sample = 1;
            r
        };
        let reservoirs = [
            with(4, 0),
            with(7, 0),
            with(4, 1),
            with(4, 0),
            PixelReservoir::empty(),
        ];
        assert_eq!(sharing(&reservoirs), vec![3, 1, 3, 3, 0]);
    }
}
