//! A [`Preset`] lowered to what runs per frame (DESIGN §6): the G-buffer, each pass, then
//! shade. Each [`Step`] names its kernel, the frame buffers it binds in the kernel's binding
//! order with how it uses them, and its parameters; the plan also says which reservoir buffer
//! holds a frame's final reservoirs, which the next frame reads as the previous ones
//! ([`Rotation`]).
//!
//! Both backends run the same plan: the CPU backend resolves each step's buffers to its
//! vectors and runs the kernel's Rust twin; the Vulkan backend binds them after the scene's
//! and puts a barrier before every step that touches what an earlier step wrote
//! ([`Plan::waits`]). The kernels' interfaces are in `kernels.rs`, which `build.rs` also reads to
//! write the GLSL buffer declarations.

mod kernels;

use shifts::Target;
use shifts::preset::{PassSpec, Preset, Shade};

use crate::contract::PassParams;
pub use kernels::{Access, KernelBuffer, PassKernel, Role, SCENE_BINDINGS};

/// One of a run's three reservoir buffers, by what it holds during a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Slot {
    /// The previous frame's final reservoirs.
    Previous,
    /// One of the two buffers the passes of this frame write in turn.
    Work(usize),
}

/// A buffer of a frame that a step binds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Resource {
    GBuffer,
    PreviousGBuffer,
    Reservoirs(Slot),
    /// The diagnostics of the preset's pass `i`.
    Diag(usize),
    Image,
    /// The Rao-Blackwellised value per pixel ([`Role::RaoBlackwellised`]).
    RaoBlackwellised,
}

/// One kernel dispatch of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub kernel: PassKernel,
    /// The stream key's `pass`: the preset pass's index, 0 for the G-buffer, the pass count
    /// for shade.
    pub pass: u32,
    /// The preset's pass this step runs (`None` for the G-buffer and shade).
    pub spec: Option<PassSpec>,
    /// `gbuffer`, [`PassSpec::label`] or `shade`: the step's timing label.
    pub label: String,
    /// The kernel's buffers after the scene's, in binding order, as this step binds them.
    pub buffers: Vec<(Resource, Access)>,
    /// The buffers zeroed before the kernel runs: the G-buffer step clears
    /// [`Resource::RaoBlackwellised`] for [`Shade::AllInputs`] (a frame's reuse passes write
    /// only the pixels they resample, shade paints the value where one was written).
    pub clears: Vec<Resource>,
    /// The preset's shade ([`PassParams::shade`]).
    pub shade: Shade,
    /// The preset's target function `p̂` ([`PassParams::target`]).
    pub target: Target,
}

impl Step {
    /// The buffer this step binds in `role`, if its kernel has one.
    pub fn resource(&self, role: Role) -> Option<Resource> {
        self.kernel
            .buffers()
            .iter()
            .zip(&self.buffers)
            .find(|(b, _)| b.role == role)
            .map(|(_, (resource, _))| *resource)
    }

    /// The step's push constants; diagnostics are collected by the preset's passes only.
    pub fn params(&self, collect_diagnostics: bool) -> PassParams {
        let collect = collect_diagnostics && self.spec.is_some();
        PassParams {
            shade: (self.shade == Shade::AllInputs) as u32,
            target: self.target.code(),
            ..PassParams::new(self.pass, self.spec.as_ref(), collect)
        }
    }

    /// The buffers the step touches: those it binds, and those it clears (written).
    fn touches(&self) -> impl Iterator<Item = (Resource, Access)> + '_ {
        let cleared = self.clears.iter().map(|&r| (r, Access::Write));
        self.buffers.iter().copied().chain(cleared)
    }
}

/// A preset's frame as steps.
#[derive(Clone, Debug, PartialEq)]
pub struct Plan {
    pub steps: Vec<Step>,
    /// The buffer that holds the frame's final reservoirs (the next frame's previous ones).
    pub final_reservoirs: Slot,
}

impl Plan {
    /// Lowers `preset` (validated: candidates first): the G-buffer (which clears the
    /// Rao-Blackwellised values for [`Shade::AllInputs`]), the preset's passes (each reads the
    /// reservoirs the previous one wrote and writes the other work buffer; the first writes
    /// `Work(0)`), then shade of the last pass's reservoirs.
    pub fn lower(preset: &Preset) -> Plan {
        let mut gbuffer = step(
            PassKernel::GBuffer,
            0,
            None,
            "gbuffer".into(),
            preset,
            |_| None,
        );
        if preset.shade == Shade::AllInputs {
            gbuffer.clears.push(Resource::RaoBlackwellised);
        }
        let mut steps = vec![gbuffer];
        let mut input = Slot::Previous;
        for (index, spec) in preset.passes.iter().enumerate() {
            let output = Slot::Work(index % 2);
            let kernel = match spec {
                PassSpec::Candidates { .. } => PassKernel::Candidates,
                PassSpec::Temporal { .. } => PassKernel::Temporal,
                PassSpec::Spatial { .. } => PassKernel::Spatial,
            };
            steps.push(step(
                kernel,
                index as u32,
                Some(*spec),
                spec.label(),
                preset,
                |role| match role {
                    Role::ReservoirsIn => Some(Resource::Reservoirs(input)),
                    Role::ReservoirsOut => Some(Resource::Reservoirs(output)),
                    Role::Diag => Some(Resource::Diag(index)),
                    _ => None,
                },
            ));
            input = output;
        }
        let passes = preset.passes.len() as u32;
        steps.push(step(
            PassKernel::Shade,
            passes,
            None,
            "shade".into(),
            preset,
            |role| (role == Role::ReservoirsIn).then_some(Resource::Reservoirs(input)),
        ));
        Plan {
            steps,
            final_reservoirs: input,
        }
    }

    /// Whether a step clears `resource` (then every frame writes it before reading it).
    pub fn clears(&self, resource: Resource) -> bool {
        self.steps.iter().any(|s| s.clears.contains(&resource))
    }

    /// The steps of the preset's passes, with the pass index.
    pub fn passes(&self) -> impl Iterator<Item = (usize, &Step)> {
        self.steps
            .iter()
            .filter(|s| s.spec.is_some())
            .map(|s| (s.pass as usize, s))
    }

    /// For each step, whether it must wait for the steps before it: it reads or writes a
    /// buffer that a step since the last wait wrote, or writes one that such a step read. The
    /// Vulkan backend puts a compute-to-compute barrier there.
    pub fn waits(&self) -> Vec<bool> {
        let mut read = Vec::new();
        let mut written = Vec::new();
        self.steps
            .iter()
            .map(|step| {
                let conflict = step.touches().any(|(resource, access)| {
                    written.contains(&resource)
                        || (access == Access::Write && read.contains(&resource))
                });
                if conflict {
                    read.clear();
                    written.clear();
                }
                for (resource, access) in step.touches() {
                    match access {
                        Access::Read => read.push(resource),
                        Access::Write => written.push(resource),
                    }
                }
                conflict
            })
            .collect()
    }
}

/// A step of `kernel` with `preset`'s shade and target: the roles every frame has are bound
/// here, the others by `bind`.
fn step(
    kernel: PassKernel,
    pass: u32,
    spec: Option<PassSpec>,
    label: String,
    preset: &Preset,
    bind: impl Fn(Role) -> Option<Resource>,
) -> Step {
    let buffers = kernel
        .buffers()
        .iter()
        .map(|b| {
            let resource = match b.role {
                Role::GBuffer => Resource::GBuffer,
                Role::PreviousGBuffer => Resource::PreviousGBuffer,
                Role::PreviousReservoirs => Resource::Reservoirs(Slot::Previous),
                Role::Image => Resource::Image,
                Role::RaoBlackwellised => Resource::RaoBlackwellised,
                role => bind(role).unwrap_or_else(|| {
                    unreachable!("{} binds {role:?} in a step of its own", kernel.name())
                }),
            };
            (resource, b.access)
        })
        .collect();
    Step {
        kernel,
        pass,
        spec,
        label,
        buffers,
        clears: Vec::new(),
        shade: preset.shade,
        target: preset.target,
    }
}

/// Which of a run's three physical reservoir buffers plays each [`Slot`] in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Rotation {
    /// The buffer holding the previous frame's final reservoirs; the work buffers are the other
    /// two, in order.
    pub previous: usize,
}

impl Rotation {
    /// The first frame's: buffer 2 plays the (empty) previous reservoirs.
    pub const FIRST: Rotation = Rotation { previous: 2 };

    /// The physical buffer of `slot`.
    pub fn buffer(&self, slot: Slot) -> usize {
        match slot {
            Slot::Previous => self.previous,
            Slot::Work(i) => (0..3)
                .filter(|&b| b != self.previous)
                .nth(i)
                .expect("two work buffers"),
        }
    }

    /// The next frame's: this frame's final reservoirs become the previous ones.
    pub fn next(&self, plan: &Plan) -> Rotation {
        Rotation {
            previous: self.buffer(plan.final_reservoirs),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sequential preset: every step reads what the previous one wrote, so every step but
    /// the G-buffer waits; the reservoirs ping-pong between the work buffers and the frame ends
    /// in the last pass's output, which the next frame reads as the previous reservoirs.
    #[test]
    fn sequential_lowers_to_ping_pong_steps_that_each_wait() {
        let preset = Preset::named("sequential").unwrap();
        let plan = Plan::lower(&preset);
        let labels: Vec<&str> = plan.steps.iter().map(|s| s.label.as_str()).collect();
        assert_eq!(labels[0], "gbuffer");
        assert_eq!(labels[labels.len() - 1], "shade");
        assert_eq!(plan.steps.len(), preset.passes.len() + 2);
        let temporal = &plan.steps[2];
        assert_eq!(temporal.kernel, PassKernel::Temporal);
        assert_eq!(
            temporal.buffers,
            [
                (Resource::GBuffer, Access::Read),
                (Resource::Reservoirs(Slot::Work(0)), Access::Read),
                (Resource::PreviousGBuffer, Access::Read),
                (Resource::Reservoirs(Slot::Previous), Access::Read),
                (Resource::Reservoirs(Slot::Work(1)), Access::Write),
                (Resource::Diag(1), Access::Write),
                (Resource::RaoBlackwellised, Access::Write),
            ]
        );
        assert!(plan.steps.iter().all(|s| s.clears.is_empty()));
        assert_eq!(temporal.params(false).shade, 0);
        assert_eq!(plan.final_reservoirs, Slot::Work(1));
        assert_eq!(
            plan.steps[3].resource(Role::ReservoirsIn),
            Some(Resource::Reservoirs(Slot::Work(1)))
        );
        assert_eq!(
            plan.steps[3].resource(Role::ReservoirsOut),
            Some(Resource::Reservoirs(Slot::Work(0)))
        );
        assert_eq!(
            plan.steps[5].resource(Role::ReservoirsIn),
            Some(Resource::Reservoirs(Slot::Work(1)))
        );
        assert_eq!(plan.waits(), [false, true, true, true, true, true]);
        let passes: Vec<usize> = plan.passes().map(|(i, _)| i).collect();
        assert_eq!(passes, [0, 1, 2, 3]);
        assert_eq!((plan.steps[0].pass, plan.steps[5].pass), (0, 4));
        assert_eq!(plan.steps[5].params(true).collect_diagnostics, 0);
        assert_eq!(plan.steps[1].params(true).collect_diagnostics, 1);
    }

    /// A step that touches nothing an earlier step wrote does not wait; a step that overwrites
    /// what an earlier one read does (write after read), as does one that reads what an
    /// earlier one wrote.
    #[test]
    fn waits_follow_the_hazards() {
        let plan = |buffers: Vec<Vec<(Resource, Access)>>| Plan {
            steps: buffers
                .into_iter()
                .map(|buffers| Step {
                    kernel: PassKernel::Spatial,
                    pass: 0,
                    spec: None,
                    label: String::new(),
                    buffers,
                    clears: Vec::new(),
                    shade: Shade::Selected,
                    target: Target::Luminance,
                })
                .collect(),
            final_reservoirs: Slot::Work(0),
        };
        let (a, b) = (Resource::Diag(0), Resource::Diag(1));
        let (r, w) = (Access::Read, Access::Write);
        assert_eq!(
            plan(vec![vec![(a, w)], vec![(b, w)]]).waits(),
            [false, false]
        );
        assert_eq!(
            plan(vec![vec![(a, w)], vec![(a, r)]]).waits(),
            [false, true]
        );
        assert_eq!(
            plan(vec![vec![(a, r)], vec![(a, w)]]).waits(),
            [false, true]
        );
        assert_eq!(
            plan(vec![vec![(a, r)], vec![(a, r)]]).waits(),
            [false, false]
        );
        assert_eq!(
            plan(vec![vec![(a, w)], vec![(a, r)], vec![(b, r)], vec![(a, r)]]).waits(),
            [false, true, false, false]
        );
    }

    /// Every step's push constants carry the preset's target (`TARGET_*`), the luminance's by
    /// default.
    #[test]
    fn every_step_carries_the_target() {
        let hybrid = Preset::named("hybrid").unwrap();
        for target in [Target::Luminance, Target::Red, Target::Blue] {
            let preset = Preset {
                target,
                ..hybrid.clone()
            };
            let codes: Vec<u32> = Plan::lower(&preset)
                .steps
                .iter()
                .map(|s| s.params(false).target)
                .collect();
            assert_eq!(codes, vec![target.code(); preset.passes.len() + 2]);
        }
        assert_eq!(
            Target::Luminance.code(),
            0,
            "a zeroed PassParams targets the luminance"
        );
    }

    /// Rao-Blackwellised shading: the G-buffer step clears the per-pixel values, the reuse
    /// passes write them and shade reads them, every step says so in its push constants, and
    /// the waits are those of selected shading (every step after the G-buffer already waits).
    #[test]
    fn shade_all_clears_writes_and_reads_the_rao_blackwellised_values() {
        let selected = Preset::named("hybrid").unwrap();
        let all = Preset {
            shade: Shade::AllInputs,
            ..selected.clone()
        };
        let plan = Plan::lower(&all);
        assert_eq!(plan.steps[0].clears, [Resource::RaoBlackwellised]);
        assert!(plan.steps[1..].iter().all(|s| s.clears.is_empty()));
        assert!(plan.steps.iter().all(|s| s.params(false).shade == 1));
        let rb = |s: &Step| {
            s.buffers
                .iter()
                .find(|(r, _)| *r == Resource::RaoBlackwellised)
                .map(|(_, a)| *a)
        };
        let accesses: Vec<_> = plan.steps.iter().map(rb).collect();
        let reuse = plan.steps.len() - 3;
        let mut want = vec![None, None];
        want.extend(vec![Some(Access::Write); reuse]);
        want.push(Some(Access::Read));
        assert_eq!(accesses, want);
        assert_eq!(plan.waits(), Plan::lower(&selected).waits());
    }

    /// Rotation: the work buffers are the two others, and each frame's final buffer is the next
    /// frame's previous one.
    #[test]
    fn rotation_hands_the_final_reservoirs_to_the_next_frame() {
        let plan = Plan::lower(&Preset::named("hybrid").unwrap());
        assert_eq!(plan.final_reservoirs, Slot::Work(0));
        let first = Rotation::FIRST;
        assert_eq!(
            [Slot::Previous, Slot::Work(0), Slot::Work(1)].map(|s| first.buffer(s)),
            [2, 0, 1]
        );
        let second = first.next(&plan);
        assert_eq!(second, Rotation { previous: 0 });
        assert_eq!(second.buffer(Slot::Work(0)), 1);
        assert_eq!(second.next(&plan), Rotation { previous: 1 });
    }
}
