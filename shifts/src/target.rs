//! The target function `p̂` of the SSS domain: a scalar of the unshadowed contribution `f`
//! (DESIGN §9). The kinds are the contract's [`Target`] (GLSL `TARGET_*`, evaluated by
//! `domain_target_of` in `glsl/domain.glsl`). A scalar target positive wherever `f` is keeps
//! GRIS unbiased for every channel [001 Eq. 5]; it only moves the variance, by how well `p̂`
//! follows the colour the pixel is shaded with. A channel target `p̂ = f_c` is positive wherever
//! `f_c` is, so GRIS with it is unbiased for channel `c` alone (the other channels of its image
//! miss the samples where `f_c = 0`); `restir:<preset>/channels=rgb` runs one per channel.

use glam::Vec3;
use sss::bssrdf;

pub use crate::contract::Target;

impl Target {
    /// `luminance`, `mean`, `l2`, `red`, `green` or `blue`.
    pub fn name(self) -> &'static str {
        match self {
            Target::Luminance => "luminance",
            Target::Mean => "mean",
            Target::L2 => "l2",
            Target::Red => "red",
            Target::Green => "green",
            Target::Blue => "blue",
        }
    }

    /// The target named `name`.
    pub fn named(name: &str) -> Option<Target> {
        Target::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The channel a channel target estimates (0 red, 1 green, 2 blue); `None` for the scalar
    /// targets, which estimate all three.
    pub fn channel(self) -> Option<usize> {
        match self {
            Target::Red => Some(0),
            Target::Green => Some(1),
            Target::Blue => Some(2),
            Target::Luminance | Target::Mean | Target::L2 => None,
        }
    }

    /// Whether `domain_target_of` (`glsl/domain.glsl`) has this target: the luminance and the
    /// channels; the mean and the L2 norm are CPU-only.
    pub fn has_kernel(self) -> bool {
        !matches!(self, Target::Mean | Target::L2)
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
            Target::Red => f.x,
            Target::Green => f.y,
            Target::Blue => f.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Names round-trip; every target is 0 where `f` is and positive wherever what it estimates
    /// is: a scalar target wherever any channel of `f ≥ 0` is, a channel target wherever its
    /// channel is (and 0 where only the others are, which leaves channel `c`'s estimator
    /// unbiased); the luminance one is `bssrdf::target` bit for bit (the GLSL twin's).
    #[test]
    fn names_values_and_support() {
        assert_eq!(Target::default(), Target::Luminance);
        for t in Target::ALL {
            assert_eq!(Target::named(t.name()), Some(t));
            assert_eq!(t.of(Vec3::ZERO), 0.0);
            for (c, unit) in [Vec3::X, Vec3::Y, Vec3::Z].into_iter().enumerate() {
                for f in [unit, unit * 1e-30, unit + Vec3::splat(0.25)] {
                    let covered = t
                        .channel()
                        .is_none_or(|own| own == c || f.min_element() > 0.0);
                    assert_eq!(t.of(f) > 0.0, covered, "{t:?} {f}");
                }
            }
        }
        assert_eq!(Target::named("max"), None);
        let f = Vec3::new(0.3, 0.5, 0.125);
        assert_eq!(Target::Luminance.of(f), bssrdf::target(f));
        assert_eq!(Target::Mean.of(f), 0.925 / 3.0);
        assert_eq!(Target::L2.of(Vec3::new(3.0, 4.0, 0.0)), 5.0);
        let channels = [Target::Red, Target::Green, Target::Blue].map(|t| t.of(f));
        assert_eq!(channels, f.to_array());
        assert_eq!(
            Target::ALL.map(Target::channel),
            [None, None, None, Some(0), Some(1), Some(2)]
        );
        assert_eq!(
            Target::ALL.map(Target::has_kernel),
            [true, false, false, true, true, true]
        );
    }
}
