//! `twin`: the contract between the Rust crates and their GLSL twins (DESIGN §6,
//! `docs/gpu-backend.md`).
//!
//! Everything both languages must agree on — constants, kinds (enums whose codes cross the
//! boundary) and std430 structs — is written once, in Rust, inside [`contract!`]. The macro
//! emits the Rust items and a description of each ([`Item`]); `engine/build.rs` includes the
//! same contract files, renders the descriptions to GLSL headers ([`render`]) and puts them on
//! `glslc`'s include path. So a kind or a field exists on both sides or on neither, and a kind
//! the GLSL does not handle is a compile error rather than a default.
//!
//! Layouts: a contract struct is `#[repr(C)]` and may only hold types with a [`Std430`] layout
//! (`u32`, `i32`, `f32`, `f64`, arrays of them, other contract structs). The macro checks at
//! compile time that every Rust `offset_of!` and `size_of` equals the std430 offset and size of
//! the GLSL struct rendered from it, which spells out the same fields in the same order. A type
//! whose GLSL layout differs from its Rust one, such as a `vec3` (16-byte aligned in std430,
//! 4 in Rust), is caught where it would move a field:
//!
//! ```compile_fail
//! struct Vec3([f32; 3]);
//! impl twin::Std430 for Vec3 {
//!     const ALIGN: usize = 16;
//!     const SIZE: usize = 12;
//!     fn glsl_type() -> twin::Type {
//!         twin::Type { name: "vec3", lengths: Vec::new() }
//!     }
//! }
//! twin::contract! {
//!     pub struct Light {
//!         pub kind: u32,
//!         pub position: Vec3, // std430 offset 16, Rust offset 4: does not compile
//!     }
//! }
//! ```

pub mod glslc;
mod render;
pub mod spirv;

pub use render::{header, push_constant_header};

/// A type with a std430 layout: its alignment, its size and its GLSL spelling.
pub trait Std430 {
    const ALIGN: usize;
    const SIZE: usize;
    fn glsl_type() -> Type;
}

/// A GLSL type: a scalar or struct name with array lengths, outermost first
/// (`[[f32; 3]; 2]` is `float name[2][3]`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Type {
    pub name: &'static str,
    pub lengths: Vec<usize>,
}

macro_rules! scalar {
    ($($rust:ty => $glsl:literal, $size:literal;)*) => {$(
        impl Std430 for $rust {
            const ALIGN: usize = $size;
            const SIZE: usize = $size;
            fn glsl_type() -> Type {
                Type { name: $glsl, lengths: Vec::new() }
            }
        }
    )*};
}

scalar! {
    u32 => "uint", 4;
    i32 => "int", 4;
    f32 => "float", 4;
    f64 => "double", 8;
}

/// std430 arrays: the element's alignment, a stride of the element's size (a multiple of its
/// alignment for every [`Std430`] type).
impl<T: Std430, const N: usize> Std430 for [T; N] {
    const ALIGN: usize = T::ALIGN;
    const SIZE: usize = N * T::SIZE;
    fn glsl_type() -> Type {
        let mut t = T::glsl_type();
        t.lengths.insert(0, N);
        t
    }
}

/// The largest of `aligns` (1 for none): a struct's std430 alignment.
pub const fn max_align(aligns: &[usize]) -> usize {
    let mut max = 1;
    let mut i = 0;
    while i < aligns.len() {
        if aligns[i] > max {
            max = aligns[i];
        }
        i += 1;
    }
    max
}

/// A value a GLSL constant can hold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Uint(u32),
    Int(i32),
    Float(f32),
}

impl From<u32> for Value {
    fn from(v: u32) -> Value {
        Value::Uint(v)
    }
}

/// A length or count (`usize` on the Rust side), which GLSL holds as a `uint`.
impl From<usize> for Value {
    fn from(v: usize) -> Value {
        Value::Uint(u32::try_from(v).expect("a contract constant fits a GLSL uint"))
    }
}

impl From<i32> for Value {
    fn from(v: i32) -> Value {
        Value::Int(v)
    }
}

impl From<f32> for Value {
    fn from(v: f32) -> Value {
        Value::Float(v)
    }
}

/// A struct field: name, type, byte offset and the text of its doc comment.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: &'static str,
    pub ty: Type,
    pub offset: usize,
    pub docs: Vec<String>,
}

/// One variant of a kind.
#[derive(Clone, Debug, PartialEq)]
pub struct Variant {
    /// The Rust variant name (`DefensivePairwise`); the GLSL constant is
    /// `<PREFIX>_<SCREAMING_SNAKE>` (`MIS_DEFENSIVE_PAIRWISE`).
    pub name: &'static str,
    pub code: u32,
    /// Further arguments of the variant's entry in the `<PREFIX>_KINDS(X)` list, if any.
    pub args: Vec<String>,
    pub docs: Vec<String>,
}

/// What a contract declares.
#[derive(Clone, Debug, PartialEq)]
pub enum Item {
    /// `const <type> NAME = value;`
    Const {
        /// The GLSL name (the Rust name, after the contract's `glsl_prefix`).
        name: &'static str,
        value: Value,
        /// The Rust expression, kept as a comment when it is not a plain literal.
        expr: &'static str,
        docs: Vec<String>,
    },
    /// `const uint <PREFIX>_<VARIANT> = code;` per variant, `<PREFIX>_KIND_COUNT`, a constant
    /// for code 0 when the codes start at 1, and, when the variants carry arguments, the list
    /// `#define <PREFIX>_KINDS(X) X(<PREFIX>_<VARIANT>, args...) ...` for dispatching.
    Kinds {
        rust: &'static str,
        prefix: &'static str,
        zero: Option<&'static str>,
        variants: Vec<Variant>,
        docs: Vec<String>,
    },
    /// `struct Name { fields };`, or a push-constant block `layout(push_constant) uniform Name
    /// { fields } instance;` in a header of its own.
    Struct {
        rust: &'static str,
        glsl: &'static str,
        fields: Vec<Field>,
        size: usize,
        push_constant: Option<&'static str>,
        docs: Vec<String>,
    },
}

/// The text of a `doc = ...` attribute as `stringify!` writes it (raw or plain string), or
/// `None` for another attribute.
pub fn doc_text(meta: &str) -> Option<String> {
    let literal = meta
        .strip_prefix("doc")?
        .trim_start()
        .strip_prefix('=')?
        .trim();
    let raw = literal.strip_prefix('r');
    let body = match raw {
        Some(rest) => {
            let hashes = rest.len() - rest.trim_start_matches('#').len();
            let inner = &rest[hashes..rest.len() - hashes];
            inner.strip_prefix('"')?.strip_suffix('"')?.to_string()
        }
        None => literal
            .strip_prefix('"')?
            .strip_suffix('"')?
            .replace("\\\"", "\"")
            .replace("\\\\", "\\"),
    };
    Some(body.strip_prefix(' ').unwrap_or(&body).to_string())
}

/// The doc-comment lines among `metas` (as `stringify!` writes them).
pub fn docs(metas: &[&str]) -> Vec<String> {
    metas.iter().filter_map(|m| doc_text(m)).collect()
}

/// Declares the items of a contract: constants, kinds and std430 structs shared with GLSL.
/// It emits each as ordinary Rust, plus `pub fn glsl_items() -> Vec<twin::Item>` listing them
/// in order, which `engine/build.rs` renders to a GLSL header.
///
/// ```
/// twin::contract! {
///     /// Hits per probe a kernel keeps.
///     pub const KEPT_HITS: u32 = 16;
///
///     /// Resampling MIS schemes; GLSL `MIS_GBH`, `MIS_PAIRWISE`, and `MIS_KINDS(X)`.
///     #[derive(Clone, Copy, Debug, PartialEq, Eq)]
///     pub enum MisKind in MIS {
///         Gbh(gbh),
///         Pairwise(pairwise),
///     }
///
///     /// Why a shift failed; codes from 1, GLSL `SHIFT_OK` = 0.
///     #[derive(Clone, Copy, Debug, PartialEq, Eq)]
///     pub enum Fail in SHIFT_FAIL, 0 = SHIFT_OK {
///         Occluded,
///         Rejected,
///     }
///
///     /// A std430 struct; GLSL name `GPixel`.
///     #[derive(Clone, Copy, Debug, Default, PartialEq)]
///     pub struct GpuPixel as GPixel {
///         pub position: [f32; 3],
///         pub valid: u32,
///     }
///
///     /// Push constants, declared in GLSL as a block named `params`.
///     #[derive(Clone, Copy, Debug, Default, PartialEq)]
///     pub struct PassParams in push_constant params {
///         pub pass: u32,
///     }
/// }
///
/// assert_eq!(MisKind::Pairwise.code(), 1);
/// assert_eq!(Fail::from_code(2), Some(Fail::Rejected));
/// assert_eq!(glsl_items().len(), 5);
/// ```
///
/// A kind's variants may carry arguments (`Gbh(gbh)`) for the GLSL list `<PREFIX>_KINDS(X)`;
/// `0 = NAME` makes codes start at 1 and names code 0. A contract that starts with
/// `glsl_prefix = P;` names its constants `P_<NAME>` in GLSL.
#[macro_export]
macro_rules! contract {
    (glsl_prefix = $prefix:ident; $($body:tt)*) => {
        $crate::__contract! { ($prefix) [] $($body)* }
    };
    ($($body:tt)*) => {
        $crate::__contract! { () [] $($body)* }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __contract {
    (($($pre:ident)?) [$($items:expr,)*]) => {
        /// Every item of this contract in order, for the GLSL header (`engine/build.rs`).
        pub fn glsl_items() -> ::std::vec::Vec<$crate::Item> {
            ::std::vec![$($items,)*]
        }
    };

    (($($pre:ident)?) [$($items:expr,)*]
        $(#[$meta:meta])*
        $vis:vis const $name:ident : $ty:ty = $value:expr;
        $($rest:tt)*
    ) => {
        $(#[$meta])*
        $vis const $name: $ty = $value;
        $crate::__contract! {
            ($($pre)?) [$($items,)* $crate::Item::Const {
                name: concat!($(stringify!($pre), "_",)? stringify!($name)),
                value: $crate::Value::from($name),
                expr: stringify!($value),
                docs: $crate::docs(&[$(stringify!($meta)),*]),
            },]
            $($rest)*
        }
    };

    (($($pre:ident)?) [$($items:expr,)*]
        $(#[$meta:meta])*
        $vis:vis enum $name:ident in $prefix:ident $(, 0 = $zero:ident)? {
            $($(#[$vmeta:meta])* $variant:ident $(($($arg:tt),*))?),* $(,)?
        }
        $($rest:tt)*
    ) => {
        $(#[$meta])*
        #[repr(u32)]
        $vis enum $name {
            $($(#[$vmeta])* $variant,)*
        }

        impl $name {
            /// Every variant, in code order.
            pub const ALL: [$name; [$(stringify!($variant)),*].len()] = [$($name::$variant),*];

            /// The variant's code: the value of its GLSL constant.
            pub const fn code(self) -> u32 {
                self as u32 $(+ { let _ = stringify!($zero); 1 })?
            }

            /// The variant with code `code`, if any.
            pub fn from_code(code: u32) -> Option<$name> {
                $name::ALL.into_iter().find(|v| v.code() == code)
            }
        }

        $crate::__contract! {
            ($($pre)?) [$($items,)* $crate::Item::Kinds {
                rust: stringify!($name),
                prefix: stringify!($prefix),
                zero: { let zero: Option<&'static str> = None; $(let zero = Some(stringify!($zero));)? zero },
                variants: ::std::vec![$($crate::Variant {
                    name: stringify!($variant),
                    code: $name::$variant.code(),
                    args: ::std::vec![$($(stringify!($arg).to_string()),*)?],
                    docs: $crate::docs(&[$(stringify!($vmeta)),*]),
                }),*],
                docs: $crate::docs(&[$(stringify!($meta)),*]),
            },]
            $($rest)*
        }
    };

    (($($pre:ident)?) [$($items:expr,)*]
        $(#[$meta:meta])*
        $vis:vis struct $name:ident $(as $glsl:ident)? $(in push_constant $block:ident)? {
            $($(#[$fmeta:meta])* $fvis:vis $field:ident : $fty:ty),* $(,)?
        }
        $($rest:tt)*
    ) => {
        $(#[$meta])*
        #[repr(C)]
        $vis struct $name {
            $($(#[$fmeta])* $fvis $field: $fty,)*
        }

        // The std430 layout of the GLSL struct equals the Rust layout, field by field.
        const _: () = {
            let mut offset = 0usize;
            $(
                offset = offset.next_multiple_of(<$fty as $crate::Std430>::ALIGN);
                assert!(
                    offset == ::core::mem::offset_of!($name, $field),
                    concat!("std430 offset of ", stringify!($name), "::", stringify!($field)),
                );
                offset += <$fty as $crate::Std430>::SIZE;
            )*
            let align = $crate::max_align(&[$(<$fty as $crate::Std430>::ALIGN),*]);
            assert!(
                offset.next_multiple_of(align) == ::core::mem::size_of::<$name>(),
                concat!("std430 size of ", stringify!($name)),
            );
        };

        impl $crate::Std430 for $name {
            const ALIGN: usize = $crate::max_align(&[$(<$fty as $crate::Std430>::ALIGN),*]);
            const SIZE: usize = ::core::mem::size_of::<$name>();
            fn glsl_type() -> $crate::Type {
                let name: &'static str = stringify!($name);
                $(let name: &'static str = stringify!($glsl);)?
                $crate::Type { name, lengths: ::std::vec::Vec::new() }
            }
        }

        $crate::__contract! {
            ($($pre)?) [$($items,)* $crate::Item::Struct {
                rust: stringify!($name),
                glsl: <$name as $crate::Std430>::glsl_type().name,
                fields: ::std::vec![$($crate::Field {
                    name: stringify!($field),
                    ty: <$fty as $crate::Std430>::glsl_type(),
                    offset: ::core::mem::offset_of!($name, $field),
                    docs: $crate::docs(&[$(stringify!($fmeta)),*]),
                }),*],
                size: ::core::mem::size_of::<$name>(),
                push_constant: { let block: Option<&'static str> = None; $(let block = Some(stringify!($block));)? block },
                docs: $crate::docs(&[$(stringify!($meta)),*]),
            },]
            $($rest)*
        }
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doc_attributes_are_read_in_both_forms() {
        assert_eq!(doc_text(r#"doc = r" A line""#).as_deref(), Some("A line"));
        assert_eq!(
            doc_text(r##"doc = r#" say "hi""#"##).as_deref(),
            Some(r#"say "hi""#)
        );
        assert_eq!(doc_text(r#"doc = " x \"y\"""#).as_deref(), Some(r#"x "y""#));
        assert_eq!(doc_text("derive(Clone)"), None);
    }

    /// The passing twin of the `compile_fail` example of the crate docs: a 16-byte aligned
    /// `vec4` first and a `uint` after it sit at the same offsets in both languages; the padding
    /// makes the Rust size the std430 size, a multiple of 16 (without it the size check fails).
    #[test]
    fn a_layout_that_agrees_compiles() {
        #[derive(Clone, Copy)]
        struct Vec3(#[allow(dead_code)] [f32; 4]);
        impl Std430 for Vec3 {
            const ALIGN: usize = 16;
            const SIZE: usize = 16;
            fn glsl_type() -> Type {
                Type {
                    name: "vec4",
                    lengths: Vec::new(),
                }
            }
        }
        contract! {
            glsl_prefix = LIGHT;
            pub const PI: f32 = std::f32::consts::PI;
            pub struct Light {
                pub position: Vec3,
                pub kind: u32,
                pub pad: [u32; 3],
            }
        }
        let items = glsl_items();
        assert!(matches!(
            items[0],
            Item::Const {
                name: "LIGHT_PI",
                ..
            }
        ));
        let Item::Struct { fields, size, .. } = &items[1] else {
            panic!("{items:?}")
        };
        assert_eq!((fields[1].offset, *size), (16, 32));
    }

    #[test]
    fn std430_of_scalars_and_arrays() {
        assert_eq!((<[f32; 3]>::ALIGN, <[f32; 3]>::SIZE), (4, 12));
        assert_eq!((<[f64; 3]>::ALIGN, <[f64; 3]>::SIZE), (8, 24));
        assert_eq!(
            <[[u32; 3]; 2]>::glsl_type(),
            Type {
                name: "uint",
                lengths: vec![2, 3]
            }
        );
    }
}
