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
/// expression is a function of the receiver's `&Translucent` that returns the shift, whose type
/// declares what it does with stored random numbers ([`DeclaresNumbers`]). The flag
/// `resolves_deferred_index` marks a shift whose selected sample needs its intersection index
/// resolved after the pass ([`crate::resolve_deferred_index`]).
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

            /// The documentation of the kind's registry line, its lines joined by spaces.
            pub fn about(&self) -> String {
                let lines: &[&str] = match self {
                    $( ShiftKind::$kind => &[$($doc),*], )*
                };
                lines.iter().map(|l| l.trim()).collect::<Vec<_>>().join(" ")
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
                match self {
                    $( ShiftKind::$kind => [$(registry_flag!($flag)),*].contains(&"resolves_deferred_index"), )*
                }
            }

            /// What the shift does with the BSSRDF random numbers a sample stores: the
            /// declaration of the type its registry line builds.
            pub fn numbers(&self) -> Numbers {
                match self {
                    $( ShiftKind::$kind => declared($cpu), )*
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
}

/// The declaration of the shift type that `build` returns, without building one.
fn declared<S: DeclaresNumbers>(_build: impl Fn(&Translucent) -> S) -> Numbers {
    S::NUMBERS
}

use restir::shift::Shift;
use sss::material::Translucent;

use crate::domain::SssDomain;
use crate::numbers::{DeclaresNumbers, Numbers};
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
        for kind in ShiftKind::ALL {
            assert!(!kind.about().is_empty(), "{}", kind.name());
        }
    }
}
