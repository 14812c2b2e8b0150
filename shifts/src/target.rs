//! The target function `p̂` of the SSS domain: a scalar of the unshadowed contribution `f`
//! (DESIGN §9). Any choice that is positive wherever `f` is keeps GRIS unbiased [001 Eq. 5]; it
//! only moves the variance, by how well `p̂` follows the colour the pixel is shaded with.

use glam::Vec3;
use sss::bssrdf;

/// How `p̂` weighs the channels of `f` (all of them ≥ 0, so all have the support of `f`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Target {
    /// `p̂ = luminance(f)` (Rec. 709 weights), paper 001's choice and the only one with a GLSL
    /// twin (`bssrdf_target`).
    #[default]
    Luminance,
    /// `p̂ = (f_r + f_g + f_b)/3`.
    Mean,
    /// `p̂ = ‖f‖₂`, scaled by the largest channel so that tiny `f` does not underflow to 0.
    L2,
}

impl Target {
    pub const ALL: [Target; 3] = [Target::Luminance, Target::Mean, Target::L2];

    /// `luminance`, `mean` or `l2`.
    pub fn name(self) -> &'static str {
        match self {
            Target::Luminance => "luminance",
            Target::Mean => "mean",
            Target::L2 => "l2",
        }
    }

    /// The target named `name`.
    pub fn named(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// `p̂` of the contribution `f`.
    pub fn of(self, f: Vec3) -> f32 {
        match self {
            Target::Luminance => bssrdf::target(f),
            Target::Mean => (f.x + f.y + f.z) / 3.0,
            Target::L2 => {
                let m = f.max_element();
                if m > 0.0 { m * (f / m).length() } else { 0.0 }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names round-trip; every target is 0 exactly where `f` is, positive elsewhere on `f ≥ 0`,
    /// and the luminance one is `bssrdf::target` bit for bit (the GLSL twin's).
    #[test]
    fn names_values_and_support() {
        for t in Target::ALL {
            assert_eq!(Target::named(t.name()), Some(t));
            assert_eq!(t.of(Vec3::ZERO), 0.0);
            for f in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(1e-30, 0.0, 0.0)] {
                assert!(t.of(f) > 0.0, "{t:?} {f}");
            }
        }
        assert_eq!(Target::named("max"), None);
        let f = Vec3::new(0.3, 0.5, 0.125);
        assert_eq!(Target::Luminance.of(f), bssrdf::target(f));
        assert_eq!(Target::Mean.of(f), 0.925 / 3.0);
        assert_eq!(Target::L2.of(Vec3::new(3.0, 4.0, 0.0)), 5.0);
    }
}
