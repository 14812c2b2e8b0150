//! Seed 001's qualitative findings and whether measured numbers reproduce them: each experiment
//! states its findings as [`Finding`]s and writes them as a table ([`markdown`]).

use crate::method_result::MethodResult;
use crate::metrics::Area;
use crate::regions::Region;

/// One qualitative finding of seed 001 and whether the measured numbers show it.
#[derive(Clone, Debug, PartialEq)]
pub struct Finding {
    pub claim: String,
    /// `None` when it cannot be measured (an empty region).
    pub holds: Option<bool>,
    pub measured: String,
}

/// The findings as a Markdown table.
pub fn markdown(findings: &[Finding]) -> String {
    let mut out = String::from("| finding of seed 001 | reproduces | measured |\n|---|---|---|\n");
    for f in findings {
        let holds = match f.holds {
            Some(true) => "yes",
            Some(false) => "**no**",
            None => "n/a (region empty)",
        };
        out.push_str(&format!("| {} | {holds} | {} |\n", f.claim, f.measured));
    }
    if findings.iter().any(|f| f.holds == Some(false)) {
        out.push_str(
            "\nFindings marked **no** are discussed in docs/experiments.md (equal-time rows: a CPU \
             ReSTIR frame costs several path-traced frames, unlike seed 001's GPU implementation).\n",
        );
    }
    out
}

/// The MSE of `method` in `region`, if both exist.
pub fn mse(rows: &[MethodResult], method: &str, region: Region) -> Option<f64> {
    rows.iter()
        .find(|r| r.method == method)?
        .metrics
        .iter()
        .find(|m| m.area == Area::Region(region))
        .map(|m| m.mse)
}

/// The method with the lowest MSE in `region` among `among`.
pub fn best<'a>(rows: &[MethodResult], among: &[&'a str], region: Region) -> Option<&'a str> {
    among
        .iter()
        .filter_map(|m| Some((*m, mse(rows, m, region)?)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(m, _)| m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_finding_that_fails_points_to_the_discussion() {
        let finding = |holds| Finding {
            claim: "a".into(),
            holds,
            measured: "m".into(),
        };
        let ok = markdown(&[finding(Some(true)), finding(None)]);
        assert!(ok.contains("| a | yes | m |") && ok.contains("n/a (region empty)"));
        assert!(!ok.contains("docs/experiments.md"));
        let failed = markdown(&[finding(Some(false))]);
        assert!(failed.contains("**no**") && failed.contains("docs/experiments.md"));
    }
}
