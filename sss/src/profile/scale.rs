//! Christensen & Burley's scale `s(A)`: the shape parameter of the normalized diffusion profile
//! is `d = ℓ / s(A)` [004 Eq. 5] (Christensen & Burley 2015, §5), fit to Monte Carlo references
//! for three ways of stating the length `ℓ`.

/// Which Christensen–Burley fit of `s(A)`, i.e. which length the material's `ℓ` is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ScaleFit {
    /// Light enters perpendicular to the surface; `ℓ` is the volume mean free path `1/σt`.
    Searchlight,
    /// Light enters through an ideal diffuse (rough) interface; `ℓ` is the volume mean free path.
    DiffuseTransmission,
    /// `ℓ` is the diffuse mean free path measured on the surface (artist-friendly; UE4's choice).
    Dmfp,
}

/// `s(A)` for the surface albedo `A ∈ [0, 1]` [004 Eq. 5]. Positive on [0, 1] for every fit
/// (minimum 0.85, 0.9, 3.5), so `d = ℓ / s(A)` is always defined.
pub fn scale_factor(fit: ScaleFit, albedo: f32) -> f32 {
    let a = albedo;
    match fit {
        ScaleFit::Searchlight => 1.85 - a + 7.0 * (a - 0.8).abs().powi(3),
        ScaleFit::DiffuseTransmission => 1.9 - a + 3.5 * (a - 0.8).powi(2),
        ScaleFit::Dmfp => 3.5 + 100.0 * (a - 0.33).powi(4),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Spot values computed by hand from [004 Eq. 5].
    #[test]
    fn spot_values() {
        let cases = [
            (ScaleFit::Searchlight, 0.8, 1.05),         // 1.85 − 0.8
            (ScaleFit::Searchlight, 0.0, 5.434),        // 1.85 + 7·0.512
            (ScaleFit::Searchlight, 1.0, 0.906),        // 0.85 + 7·0.008
            (ScaleFit::DiffuseTransmission, 0.8, 1.1),  // 1.9 − 0.8
            (ScaleFit::DiffuseTransmission, 0.0, 4.14), // 1.9 + 3.5·0.64
            (ScaleFit::DiffuseTransmission, 1.0, 1.04), // 0.9 + 3.5·0.04
            (ScaleFit::Dmfp, 0.33, 3.5),                // minimum
            (ScaleFit::Dmfp, 0.0, 4.685921),            // 3.5 + 100·0.33⁴
            (ScaleFit::Dmfp, 1.0, 23.651121),           // 3.5 + 100·0.67⁴
        ];
        for (fit, a, want) in cases {
            let got = scale_factor(fit, a);
            assert!(
                (got - want).abs() < 1e-5 * want,
                "{fit:?}, A = {a}: s = {got}, want {want}"
            );
        }
    }

    #[test]
    fn positive_on_unit_interval() {
        for fit in [
            ScaleFit::Searchlight,
            ScaleFit::DiffuseTransmission,
            ScaleFit::Dmfp,
        ] {
            for i in 0..=1000 {
                let a = i as f32 / 1000.0;
                assert!(scale_factor(fit, a) >= 0.85, "{fit:?}, A = {a}");
            }
        }
    }
}
