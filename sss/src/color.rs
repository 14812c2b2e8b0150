//! Colour: the Rec. 709 luminance of linear RGB, in the precision of its argument.
//!
//! One definition serves the renderers (`f32`: light power, the target `p̂ = luminance(f)`, its
//! GLSL twin `luminance` in `sss/glsl/light.glsl`) and the statistics (`f64`: region means and
//! error metrics accumulate in double precision).

use glam::{DVec3, Vec3};

/// Linear RGB whose Rec. 709 luminance can be taken in its own precision.
pub trait Rgb: Copy {
    /// `f32` for [`Vec3`], `f64` for [`DVec3`].
    type Scalar;
    /// `0.2126 R + 0.7152 G + 0.0722 B` [ITU-R BT.709-6, item 3.2], summed left to right.
    fn luminance(self) -> Self::Scalar;
}

impl Rgb for Vec3 {
    type Scalar = f32;
    fn luminance(self) -> f32 {
        self.dot(Vec3::new(0.2126, 0.7152, 0.0722))
    }
}

impl Rgb for DVec3 {
    type Scalar = f64;
    fn luminance(self) -> f64 {
        self.dot(DVec3::new(0.2126, 0.7152, 0.0722))
    }
}

/// Rec. 709 luminance of linear RGB ([`Rgb::luminance`]): `f32` of a [`Vec3`], `f64` of a
/// [`DVec3`] (convert with `as_dvec3` to take an `f32` colour's luminance in double precision).
pub fn luminance<C: Rgb>(rgb: C) -> C::Scalar {
    rgb.luminance()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both precisions weigh the channels 0.2126, 0.7152, 0.0722 (the f32 weights are the f64
    /// ones rounded), and sum left to right as the GLSL twin's `glam_dot` does.
    #[test]
    fn weights_and_order_match_in_both_precisions() {
        let c = [0.3f32, 0.6, 0.9];
        let f = luminance(Vec3::from_array(c));
        assert_eq!(
            f.to_bits(),
            (0.2126f32 * 0.3 + 0.7152 * 0.6 + 0.0722 * 0.9).to_bits()
        );
        let d = luminance(Vec3::from_array(c).as_dvec3());
        let [r, g, b] = c.map(f64::from);
        assert_eq!(
            d.to_bits(),
            (0.2126 * r + 0.7152 * g + 0.0722 * b).to_bits()
        );
        for (w32, w64) in [(0.2126f32, 0.2126f64), (0.7152, 0.7152), (0.0722, 0.0722)] {
            assert_eq!(w32, w64 as f32);
        }
        assert_eq!(luminance(Vec3::ONE), 1.0);
    }
}
