// What the GLSL twins under `sss/glsl/` share with this crate, one `twin::contract!` per twin
// (its GLSL prefix); `engine/build.rs` includes this file and renders `contract/sss.glsl` from
// `glsl_items`. The crate's modules re-export these items where they are used, so each value
// is written here once. This file is also compiled by the build script, so it names no item
// of the crate outside doc links.

/// Every item of the `sss` contract, in order (`engine/build.rs` renders `contract/sss.glsl`).
pub fn glsl_items() -> Vec<twin::Item> {
    [
        burley::glsl_items(),
        xie::glsl_items(),
        dipole::glsl_items(),
        light::glsl_items(),
        material::glsl_items(),
        bssrdf::glsl_items(),
        pt::glsl_items(),
        random_walk::glsl_items(),
        single_scatter::glsl_items(),
    ]
    .concat()
}

/// `burley.glsl`.
pub mod burley {
    twin::contract! {
        glsl_prefix = BURLEY;

        /// The quantile of the radius CDF used as the truncation radius `r_max` (DESIGN §9).
        pub const R_MAX_QUANTILE: f32 = 0.999;
    }
}

/// `xie.glsl`.
pub mod xie {
    twin::contract! {
        glsl_prefix = XIE;

        /// Iteration cap of the bracketed Newton solve behind [`crate::profile::Xie::cdf`]
        /// (converged to f32 in the round-trip test over ξ ∈ [1e-7, 1 − 2⁻²⁴]).
        pub const INVERSE_ITERATIONS: usize = 12;
    }
}

/// `dipole.glsl`.
pub mod dipole {
    twin::contract! {
        glsl_prefix = DIPOLE;

        /// Iteration cap of the monotone Newton solve in `Dipole::sample_pole` (converged to
        /// f32 in the round-trip test).
        pub const NEWTON_ITERATIONS: usize = 32;

        /// One of the two sources of the dipole.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Pole in DIPOLE_POLE {
            /// The real source at depth `z_r = 1/σt′` below the surface.
            Real,
            /// The virtual (negative) source at height `z_v = z_r(1 + 4A/3)` above it.
            Virtual,
        }
    }
}

/// `light.glsl`.
pub mod light {
    twin::contract! {
        glsl_prefix = LIGHT;

        /// Distance from a shading point at which a directional light's vertex x3 is placed
        /// (scene units); scenes are a few units across, so the vertex lies outside any of them.
        pub const DIRECTIONAL_DISTANCE: f32 = 1.0e4;
    }
}

/// The interface kinds of `material.glsl` and `random_walk.glsl`.
pub mod material {
    twin::contract! {
        /// The interface that path-traced volumetric transport meets at the object's surface
        /// (the random walk, the single-scatter estimator's zero- and single-scattering paths);
        /// scene field `boundary`. The diffusion BSSRDF is not affected: its Fresnel terms
        /// always use `ior` ([`crate::material::FresnelTransmission`]). On the GPU a medium
        /// carries its code (`GpuMedium::interface`).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum BoundaryKind in BOUNDARY {
            /// Fresnel-free Lambertian transmission both ways, no internal reflection; `ior`
            /// unused (the convention of diffusion-profile renderers [000 slide 57]). The
            /// default.
            #[default]
            Diffuse,
            /// A smooth dielectric of index `ior`: Fresnel reflection or refraction at entry and
            /// at every internal boundary hit, total internal reflection.
            Dielectric,
            /// No interface: every crossing keeps its direction (as `ior = 1` with a smooth
            /// surface).
            IndexMatched,
        }
    }
}

/// `bssrdf.glsl`.
pub mod bssrdf {
    twin::contract! {
        glsl_prefix = BSSRDF;

        /// The nine BSSRDF IS techniques, index `axis · 3 + channel`
        /// ([`crate::bssrdf::Technique::index`]).
        pub const TECHNIQUE_COUNT: usize = 9;
        /// The stored intersection index meaning *unknown*: `BssrdfSample::index == None` on
        /// the GPU, and the deferred index policy's stored index (`shifts::SssSample`).
        pub const INDEX_UNKNOWN: u32 = u32::MAX;

        /// Projection axis of the probe ray, in the frame of x1's geometric normal (DESIGN §9).
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum Axis in BSSRDF_AXIS {
            Normal,
            Tangent,
            Bitangent,
        }

        /// How every technique draws its disk radius from its channel's Burley profile (DESIGN §4
        /// "Radius sampling"). The density of the result enters `p_disk`, so both choices are
        /// unbiased.
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum RadiusSampling in BSSRDF_RADIUS {
            /// The exact inverse of the radius CDF (`Burley::sample_radius`); density `R̄_d`.
            #[default]
            Exact,
            /// Xie et al.'s approximate inverse `g(ξ)` [004 Eq. 21] weighted by the density of
            /// `g(U)` itself (`Xie::pdf_disk`), not by `R̄_d`.
            Xie,
        }

        /// Why x2 cannot be regenerated from x1; on the GPU the inverse returns its code, or
        /// `BSSRDF_INVERT_OK` (0).
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum InvertFail in BSSRDF_INVERT, 0 = BSSRDF_INVERT_OK {
            /// No technique reaches x2 from x1 (`p_disk(x2 | x1) = 0`).
            OutOfSupport,
            /// The re-traced chord has no hit on x2's triangle at x2's `t` (exact index policy).
            IndexNotFound,
        }
    }
}

/// `pt.glsl`.
pub mod pt {
    twin::contract! {
        glsl_prefix = PT;

        /// `purpose` of the per-sample streams of the baseline (and of the reference, which is
        /// the same estimator with more samples).
        pub const PURPOSE_PT: u32 = 0x5054_0001;
        /// Offset of shadow-ray origins along the geometric normal and their shortening at the
        /// light, in scene units (scenes are about 1 unit across; the BVH ignores hits closer
        /// than 1e-4 anyway).
        pub const SHADOW_EPSILON: f32 = 1e-4;

        /// Which diffusion profile a BSSRDF evaluates: Burley's normalized diffusion `A R̄_d`
        /// (DESIGN §9, every method's default) or the Jensen dipole of the same material
        /// (`DipoleProfiles`), the profile of paper 002 (`PtSettings::profile`).
        #[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
        pub enum ProfileKind in PT_PROFILE {
            #[default]
            Burley,
            Dipole,
        }
    }
}

/// `random_walk.glsl`.
pub mod random_walk {
    twin::contract! {
        glsl_prefix = RANDOM_WALK;

        /// Segments (free flights) per walk before it is cut off and reported truncated.
        pub const DEFAULT_MAX_BOUNCES: u32 = 1 << 16;
        /// Below this `|g|` the Henyey–Greenstein inverse CDF cancels catastrophically;
        /// directions are then drawn isotropically and weighted by `value / pdf` (exact, not an
        /// approximation).
        pub const SMALL_G: f32 = 1e-3;

        /// How a walk ended ([`crate::random_walk::WalkEnd::kind`]); on the GPU the walk
        /// returns its code.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum WalkEndKind in RANDOM_WALK_END {
            Exited,
            Terminated,
            Truncated,
        }

        /// Where a path inside the medium meets the boundary
        /// ([`crate::random_walk::Crossing::kind`]); on the GPU the crossing returns its code.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum CrossingKind in RANDOM_WALK_CROSSING {
            /// It leaves along one direction (index-matched or refracted).
            LeavesSpecular,
            /// It leaves by Lambertian transmission.
            LeavesDiffuse,
            /// It is reflected back inside (Fresnel or total internal reflection).
            Reflected,
        }
    }
}

/// `single_scatter.glsl`.
pub mod single_scatter {
    twin::contract! {
        glsl_prefix = SINGLE_SCATTER;

        /// `purpose` of the per-sample streams (ASCII "SS" + 1).
        pub const PURPOSE_SINGLE_SCATTER: u32 = 0x5353_0001;
        /// Unscattered chords followed through internal reflections before the path is cut off.
        pub const DEFAULT_MAX_SEGMENTS: u32 = 256;

        /// How the channel of a distance sample is drawn.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum ChannelSelection in SINGLE_SCATTER_CHANNEL {
            /// `P_c = 1/3`.
            Uniform,
            /// `P_c = σs,c / Σ σs = σt,c α_c / Σ σt α` [000 "RGB variation in σt"] (uniform when
            /// the medium does not scatter).
            Scattering,
        }
    }
}
