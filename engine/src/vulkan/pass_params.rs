//! The push constants of the pass kernels (`PassParams` of the contract): what a plan step's
//! parameters look like on the device.

use shifts::preset::PassSpec;

use crate::contract::PassParams;

impl PassParams {
    /// The push constants of pass `pass` of a preset (`spec = None`: G-buffer or shade).
    pub fn new(pass: u32, spec: Option<&PassSpec>, collect_diagnostics: bool) -> PassParams {
        let base = PassParams {
            pass,
            collect_diagnostics: collect_diagnostics as u32,
            ..PassParams::default()
        };
        match spec {
            None => base,
            Some(&PassSpec::Candidates {
                bssrdf_samples,
                shared_light,
            }) => PassParams {
                bssrdf_samples,
                shared_light: shared_light as u32,
                ..base
            },
            Some(&PassSpec::Temporal {
                shift,
                mis,
                confidence_cap,
            }) => PassParams {
                shift: shift.code(),
                mis: mis.code(),
                confidence_cap,
                ..base
            },
            Some(&PassSpec::Spatial {
                shift,
                mis,
                neighbours,
                confidence_cap,
                ..
            }) => PassParams {
                shift: shift.code(),
                mis: mis.code(),
                neighbours,
                confidence_cap: confidence_cap.unwrap_or(0.0),
                ..base
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::mis::MisKind;
    use shifts::ShiftKind;

    /// The fields of a pass land in their push constants with the kinds' codes, an absent cap
    /// as 0 (the layout itself is checked by the contract at compile time).
    #[test]
    fn pass_params_carry_the_pass() {
        assert_eq!(size_of::<PassParams>(), 40);
        let spatial = PassSpec::Spatial {
            shift: ShiftKind::Hybrid,
            mis: MisKind::DefensivePairwise,
            neighbours: 4,
            confidence_cap: None,
            radius: shifts::preset::RadiusRule::Clamped,
            pairs: shifts::preset::Pairs::Independent,
        };
        let p = PassParams::new(2, Some(&spatial), true);
        assert_eq!((p.pass, p.shift, p.mis, p.neighbours), (2, 3, 2, 4));
        assert_eq!(
            (ShiftKind::Hybrid.code(), MisKind::DefensivePairwise.code()),
            (3, 2)
        );
        assert_eq!((p.confidence_cap, p.collect_diagnostics), (0.0, 1));
        assert_eq!(p.shade, 0, "the plan's step sets the shade");
        assert_eq!(p.target, 0, "the plan's step sets the target");
        let candidates = PassSpec::Candidates {
            bssrdf_samples: 3,
            shared_light: true,
        };
        let p = PassParams::new(0, Some(&candidates), false);
        assert_eq!((p.bssrdf_samples, p.shared_light, p.shift), (3, 1, 0));
    }
}
