//! [`ShiftKind`]: the registered shifts by name, by GPU code and as CPU shifts, declared from
//! the lines of `registry.rs` by `shift_registry!`.
//!
//! `engine/build.rs` reads the same lines with its own `shift_registry!`, which keeps each
//! line's name, GLSL twin and flags and drops the CPU expression, to write the GLSL kind
//! constants and the dispatch list of `shifts/glsl/shift.glsl`. So a kind's name, CPU shift and
//! GPU code come from one line, and a kind whose GLSL twin is missing does not compile.

/// One registry line per shift, in code order:
///
/// ```text
/// /// docs
/// Kind = "name", glsl_file::glsl_twin, |material| cpu_shift [, resolves_deferred_index];
/// ```
///
/// `glsl_twin` is a function of `shifts/glsl/<glsl_file>.glsl` (see `shift.glsl`); the CPU
/// expression is a function of the receiver's `&Translucent` that returns the shift. Flags:
/// `resolves_deferred_index` marks a shift whose selected sample needs its intersection index
/// resolved after the pass ([`crate::resolve_deferred_index`]); `keeps_numbers`,
/// `keeps_connectable_numbers`, `replays_numbers` and `replays_unconnectable_numbers` say what
/// it does with the BSSRDF random numbers a sample stores ([`StoredNumbers`]; none: it
/// re-derives them for the receiver or reads none).
macro_rules! shift_registry {
    ($(
        $(#[doc = $doc:literal])*
        $kind:ident = $name:literal, $file:ident :: $twin:ident, $cpu:expr $(, $flag:ident)* ;
    )*) => {
        /// Every registered shift, negative controls included (so a test can build a preset
        /// with a deliberately wrong shift). Its [`ShiftKind::code`] is its position in the
        /// registry, which is also the GLSL constant `SHIFT_<KIND>`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum ShiftKind {
            $( $(#[doc = $doc])* $kind, )*
        }

        impl ShiftKind {
            /// Every kind, in registry order.
            pub const ALL: [ShiftKind; [$(stringify!($kind)),*].len()] = [$(ShiftKind::$kind),*];

            /// The name used in presets, tables and on the command line.
            pub fn name(&self) -> &'static str {
                match self {
                    $( ShiftKind::$kind => $name, )*
                }
            }

            /// The kind called `name`, if registered.
            pub fn named(name: &str) -> Option<ShiftKind> {
                ShiftKind::ALL.into_iter().find(|k| k.name() == name)
            }

            /// The kind's code on the GPU: its position in the registry.
            pub const fn code(&self) -> u32 {
                *self as u32
            }

            /// Whether the selected sample of a pass with this shift needs its intersection
            /// index resolved afterwards ([`crate::resolve_deferred_index`], deferred policy
            /// [001 §4.3]).
            pub fn resolves_deferred_index(&self) -> bool {
                self.flags().contains(&"resolves_deferred_index")
            }

            /// What the shift does with the BSSRDF random numbers a sample stores.
            pub fn stored_numbers(&self) -> StoredNumbers {
                let flags = self.flags();
                if flags.contains(&"keeps_numbers") {
                    StoredNumbers::Kept
                } else if flags.contains(&"keeps_connectable_numbers") {
                    StoredNumbers::KeptIfConnectable
                } else if flags.contains(&"replays_numbers") {
                    StoredNumbers::Replayed
                } else if flags.contains(&"replays_unconnectable_numbers") {
                    StoredNumbers::ReplayedUnlessConnectable
                } else {
                    StoredNumbers::Rederived
                }
            }

            /// The flags of the kind's registry line.
            fn flags(&self) -> &'static [&'static str] {
                match self {
                    $( ShiftKind::$kind => &[$(registry_flag!($flag)),*], )*
                }
            }

            /// Runs `f` with the shift built for a receiver of material `material` (the
            /// hybrid's κ_dist depends on it; every shift fails between different objects, so
            /// one material suffices).
            pub fn with_shift<R>(
                &self,
                material: &Translucent,
                f: impl FnOnce(&dyn for<'s> Shift<SssDomain<'s>>) -> R,
            ) -> R {
                match self {
                    $( ShiftKind::$kind => f(&($cpu)(material)), )*
                }
            }
        }
    };
}

/// A registry line's flag by name (an unknown flag does not compile).
macro_rules! registry_flag {
    (resolves_deferred_index) => {
        "resolves_deferred_index"
    };
    (keeps_numbers) => {
        "keeps_numbers"
    };
    (keeps_connectable_numbers) => {
        "keeps_connectable_numbers"
    };
    (replays_numbers) => {
        "replays_numbers"
    };
    (replays_unconnectable_numbers) => {
        "replays_unconnectable_numbers"
    };
}

/// What a shift does with the BSSRDF random numbers `(u_radius, u_angle, technique)` that a
/// sample stores [001 §3.2.2, §4.3]. Delayed reconnection replays them at the receiver's x1,
/// which is unbiased only if they are the numbers of the x1 of the pixel the sample sits in;
/// a shift that moves a sample and keeps them leaves numbers drawn at another pixel's x1
/// (`Preset::validate` rejects a chain that replays such numbers).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredNumbers {
    /// Re-derived for the receiver (probabilistic inversion [001 Alg. 4]), or not moved.
    Rederived,
    /// Kept while the sample moves (reconnection): afterwards they belong to another x1.
    Kept,
    /// Kept, but only for paths connectable in the hybrid's sense (distant reconnection: x2 at
    /// least the hybrid's κ_dist from both x1), which the hybrid reconnects and never replays.
    KeptIfConnectable,
    /// Replayed at the receiver (delayed reconnection): they must belong to the source's x1;
    /// afterwards they belong to the receiver's.
    Replayed,
    /// The hybrid [001 §4.1]: kept for paths connectable at both ends, replayed for the others.
    /// Its kept numbers are connectable, which it never replays: a hybrid may follow a hybrid.
    ReplayedUnlessConnectable,
}

impl StoredNumbers {
    /// Whether a sample moved by a pass of shift `self` may carry numbers of another x1.
    pub fn leaves_foreign(self) -> bool {
        matches!(
            self,
            StoredNumbers::Kept
                | StoredNumbers::KeptIfConnectable
                | StoredNumbers::ReplayedUnlessConnectable
        )
    }

    /// Whether a pass of shift `self` replays numbers that an earlier pass of `earlier` may
    /// have left foreign (the hybrid replays no connectable path, the only ones that a hybrid
    /// or distant reconnection keeps).
    pub fn replays_foreign_of(self, earlier: StoredNumbers) -> bool {
        match self {
            StoredNumbers::Replayed => earlier.leaves_foreign(),
            StoredNumbers::ReplayedUnlessConnectable => earlier == StoredNumbers::Kept,
            StoredNumbers::Rederived | StoredNumbers::Kept | StoredNumbers::KeptIfConnectable => {
                false
            }
        }
    }
}

use restir::shift::Shift;
use sss::material::Translucent;

use crate::domain::SssDomain;
// The registry's CPU expressions name the shifts as the crate root exports them.
use crate::*;

include!("registry.rs");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_codes_are_unique_and_round_trip() {
        let names: std::collections::HashSet<_> = ShiftKind::ALL.iter().map(|s| s.name()).collect();
        assert_eq!(names.len(), ShiftKind::ALL.len());
        for (i, kind) in ShiftKind::ALL.into_iter().enumerate() {
            assert_eq!(kind.code(), i as u32);
            assert_eq!(ShiftKind::named(kind.name()), Some(kind));
        }
        assert_eq!(ShiftKind::named("nope"), None);
        let deferred: Vec<_> = ShiftKind::ALL
            .into_iter()
            .filter(ShiftKind::resolves_deferred_index)
            .collect();
        assert_eq!(deferred, [ShiftKind::InvertingDeferred]);
        let numbers = |n| {
            ShiftKind::ALL
                .into_iter()
                .filter(|k| k.stored_numbers() == n)
                .collect::<Vec<_>>()
        };
        use ShiftKind::*;
        assert_eq!(numbers(StoredNumbers::Kept), [Reconnection]);
        assert_eq!(
            numbers(StoredNumbers::KeptIfConnectable),
            [DistantReconnection]
        );
        assert_eq!(
            numbers(StoredNumbers::ReplayedUnlessConnectable),
            [Hybrid, HybridIgnoringCriterion]
        );
        assert_eq!(
            numbers(StoredNumbers::Rederived),
            [Identity, InvertingExact, InvertingDeferred]
        );
    }
}
