//! The ablation's rows: what varies, on which camera, at which size.

use sss::scene::Scene;

/// The resolution rows: the run's resolution times these factors (128×96 → 256×192, 384×288).
pub const RESOLUTION_FACTORS: [u32; 2] = [2, 3];

/// Modifiers without a Vulkan kernel: their rows run on the CPU backend only.
pub const CPU_ONLY: [&str; 4] = [
    "/radius=unclamped",
    "/pairs=reciprocal",
    "/target=mean",
    "/target=l2",
];

/// How the camera moves over the trajectory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Framing {
    /// The scene's trajectory; `false`: at rest at its last pose (`Camera::at_rest`).
    pub moving: bool,
    /// Sub-pixel jitter per frame.
    pub jitter: bool,
}

impl Framing {
    /// The scene's own camera: moving and jittered (paper 001's setup).
    pub const SCENE: Framing = Framing {
        moving: true,
        jitter: true,
    };

    /// `scene` with this framing; the scene's own camera is returned unchanged.
    pub fn apply(self, mut scene: Scene) -> Scene {
        if !self.moving {
            scene.camera = scene.camera.at_rest();
        }
        if !self.jitter {
            scene.camera = scene.camera.with_jitter(false);
        }
        scene
    }

    /// `moving`, `static`, with `-unjittered` when jitter is off.
    pub fn name(self) -> String {
        let motion = if self.moving { "moving" } else { "static" };
        let jitter = if self.jitter { "" } else { "-unjittered" };
        format!("{motion}{jitter}")
    }
}

/// One row of the ablation: a method spec on a camera at a resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct Variation {
    /// What varies, e.g. `temporal cap 1`.
    pub label: String,
    /// The method, e.g. `restir:hybrid/cap=1`.
    pub spec: String,
    pub framing: Framing,
    pub resolution: (u32, u32),
}

impl Variation {
    /// The rows' group: one comparison per camera and resolution.
    pub(super) fn group(&self) -> String {
        let (w, h) = self.resolution;
        format!("{}-{w}x{h}", self.framing.name())
    }
}

/// The rows for `base` at `resolution`: the unmodified preset, then one knob changed per row.
pub fn variations(base: &str, resolution: (u32, u32)) -> Vec<Variation> {
    let row = |label: String, modifier: &str, framing, resolution| Variation {
        label,
        spec: format!("{base}{modifier}"),
        framing,
        resolution,
    };
    let here =
        |label: &str, modifier: &str| row(label.into(), modifier, Framing::SCENE, resolution);
    let mut rows = vec![
        here("default (temporal cap 3)", ""),
        here("temporal cap 1", "/cap=1"),
        here("temporal cap 5", "/cap=5"),
        here("temporal cap 20", "/cap=20"),
        here("spatial cap 1", "/spatial-cap=1"),
        here("spatial cap 3", "/spatial-cap=3"),
        here("neighbours 2", "/neighbours=2"),
        here("neighbours 8", "/neighbours=8"),
        here("radius unclamped", "/radius=unclamped"),
        here("reciprocal pairs", "/pairs=reciprocal"),
        here("target mean", "/target=mean"),
        here("target l2", "/target=l2"),
        here("shade=all", "/shade=all"),
    ];
    for (label, moving, jitter) in [
        ("static camera", false, true),
        ("no jitter", true, false),
        ("static camera, no jitter", false, false),
    ] {
        rows.push(row(
            label.into(),
            "",
            Framing { moving, jitter },
            resolution,
        ));
    }
    for k in RESOLUTION_FACTORS {
        let (w, h) = (resolution.0 * k, resolution.1 * k);
        rows.push(row(format!("{w}×{h}"), "", Framing::SCENE, (w, h)));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::super::FRAMES;
    use super::*;
    use methods::Method;

    /// The rows: the default first, every knob of issue 10 that exists once, each method spec
    /// parses, framings and resolutions differ from the default only where the label says so,
    /// and the resolution rows scale the run's resolution.
    #[test]
    fn the_rows_cover_every_knob_once() {
        let rows = variations("restir:hybrid", (128, 96));
        assert_eq!(rows[0].spec, "restir:hybrid");
        assert_eq!(rows[0].group(), "moving-128x96");
        let labels: Vec<&str> = rows.iter().map(|v| v.label.as_str()).collect();
        for wanted in [
            "temporal cap 1",
            "temporal cap 5",
            "temporal cap 20",
            "spatial cap 1",
            "neighbours 2",
            "neighbours 8",
            "radius unclamped",
            "reciprocal pairs",
            "target mean",
            "target l2",
            "shade=all",
            "static camera",
            "no jitter",
            "256×192",
            "384×288",
        ] {
            assert_eq!(
                labels.iter().filter(|l| **l == wanted).count(),
                1,
                "{wanted}"
            );
        }
        for v in &rows {
            Method::parse(&v.spec).unwrap_or_else(|e| panic!("{}: {e}", v.spec));
            let modified = v.spec != "restir:hybrid";
            let elsewhere = v.framing != Framing::SCENE || v.resolution != (128, 96);
            assert!(
                modified != elsewhere || v == &rows[0],
                "{}: changes one thing",
                v.label
            );
        }
        let groups: std::collections::BTreeSet<String> =
            rows.iter().map(Variation::group).collect();
        assert_eq!(groups.len(), 6, "{groups:?}");
        let small = variations("restir:sequential", (8, 6));
        let sizes: Vec<(u32, u32)> = small.iter().map(|v| v.resolution).collect();
        assert!(sizes.contains(&(16, 12)) && sizes.contains(&(24, 18)));
    }

    /// A framing changes the camera as named: at rest every frame has the last pose.
    #[test]
    fn framings_apply_to_the_camera() {
        let camera = Scene::builtin("bumpy").unwrap().camera;
        let still = Framing {
            moving: false,
            jitter: false,
        }
        .apply(Scene::builtin("bumpy").unwrap());
        assert_eq!(still.camera.eye(0), camera.eye(FRAMES - 1));
        assert!(!still.camera.jittered());
        let same = Framing::SCENE.apply(Scene::builtin("bumpy").unwrap());
        assert_eq!(same.camera, camera);
    }
}
