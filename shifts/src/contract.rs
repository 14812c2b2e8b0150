use bytemuck::{Pod, Zeroable};

twin::contract! {
    /// Stream purpose tags of the shifts, in the top two bits of `StreamKey::purpose`; the low
    /// 30 bits hold the source pixel (see `SssDomain::shift_stream`): probabilistic
    /// inversion's γ.
    pub const PURPOSE_INVERSION: u32 = 0b10 << 30;
    /// The uniform hit pick of delayed reconnection when the intersection index is unknown.
    pub const PURPOSE_PICK: u32 = 0b11 << 30;
    /// The source pixel's bits of a shift's stream purpose.
    pub const PARTNER_PIXEL_MASK: u32 = (1 << 30) - 1;

    /// Which parts of delayed reconnection run, as bits of a set (`delayed::Checks`, GLSL
    /// `checks`); only the negative controls of `broken` switch one off: the light Jacobian of
    /// [001 Eq. 11], ...
    pub const DELAYED_CHECK_JACOBIAN: u32 = 1 << 0;
    /// ... the y2–x3 visibility test, ...
    pub const DELAYED_CHECK_VISIBILITY: u32 = 1 << 1;
    /// ... and both.
    pub const DELAYED_CHECKS_ALL: u32 = DELAYED_CHECK_JACOBIAN | DELAYED_CHECK_VISIBILITY;

    /// Offset of shadow-segment ends from x2 (along its geometric normal) and from x3 (scene
    /// units; the built-in scenes are about one unit across).
    pub const SHADOW_EPSILON: f32 = 1e-4;

    /// The factor by which the negative control `broken::DelayedJacobianOff` scales the
    /// Jacobian of delayed reconnection: 3% too large, just beyond the ±2% that the
    /// unbiasedness tests resolve per region and channel.
    pub const BROKEN_JACOBIAN_ERROR: f32 = 1.03;

    /// How the target function `p̂` of the SSS domain weighs the channels of the unshadowed
    /// contribution `f` (DESIGN §9; methods in `target.rs`). Every choice is ≥ 0 and positive
    /// where it is meant to integrate: the scalar targets wherever `f` is, a channel target
    /// wherever its channel is, so GRIS with it is unbiased for that channel [001 Eq. 5].
    #[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
    pub enum Target in TARGET {
        /// `p̂ = luminance(f)` (Rec. 709 weights), paper 001's choice.
        #[default]
        Luminance,
        /// `p̂ = (f_r + f_g + f_b)/3`.
        Mean,
        /// `p̂ = ‖f‖₂`, scaled by the largest channel so that tiny `f` does not underflow to 0.
        L2,
        /// `p̂ = f_r`: GRIS with it estimates the red channel alone.
        Red,
        /// `p̂ = f_g`.
        Green,
        /// `p̂ = f_b`.
        Blue,
    }

    /// How the intersection index of an inverted sample is found (DESIGN §5).
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum IndexPolicy in INDEX_POLICY {
        /// Re-trace the chord during the shift at *both* ends of the pair; fail (`NotInvertible`)
        /// if x2 is not among the hits of either (matched by triangle and `t`). Unbiased: the
        /// shift and its back-shift fail on the same events (see `InvertingReconnection`).
        Exact,
        /// Leave the index unknown; `resolve_deferred_index` sets it for the selected sample
        /// after the pass. Paper 001's fast choice, slightly biased.
        Deferred,
    }

    /// One SSS path sample `[x0, x1, x2, x3]` without its pixel: x2 on a translucent object, x3
    /// on a light, and the random numbers of BSSRDF IS [001 Alg. 3] (methods in `sample.rs`).
    ///
    /// For a directional light the stored x3 is where the light sampler put the vertex (far
    /// along `−direction`); contributions and visibility use the light's direction instead, so
    /// the vertex acts as the point at infinity.
    #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
    pub struct SssSample {
        pub(crate) x3: [f32; 3],
        pub(crate) light: u32,
        pub(crate) bary: [f32; 2],
        pub(crate) object: u32,
        pub(crate) prim: u32,
        /// `Technique::index` = axis · 3 + channel.
        pub(crate) technique: u32,
        pub(crate) u_radius: f32,
        pub(crate) u_angle: f32,
        /// Rank of x2 among the probe's hits sorted by `t`, or `INDEX_UNKNOWN` (of the `sss`
        /// contract).
        pub(crate) index: u32,
        /// `p_disk(x2 | x1)` of the x1 whose random numbers are stored.
        pub(crate) p_disk: f32,
    }

    /// A stored reservoir `{y, W, c}` of one pixel [001 Alg. 2], the per-pixel buffer that the
    /// passes read and write: 64 bytes, paper 001's size [001 §5.2], reached without
    /// quantisation — every field is a 4-byte scalar, so std430 packs sample and reservoir
    /// without gaps (a 1920×1080 buffer is 126.6 MiB, inside a 128 MiB storage-buffer range).
    #[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
    pub struct PixelReservoir {
        /// The selected sample `Y` (meaningful when `has_sample` is 1).
        pub y: SssSample,
        /// Unbiased contribution weight `W` (`ucw`), finite and ≥ 0.
        pub ucw: f32,
        /// Confidence weight `c`.
        pub confidence: f32,
        /// 1 when `y` holds the selected sample, 0 for an empty reservoir.
        pub has_sample: u32,
    }
}
