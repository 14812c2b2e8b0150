twin::contract! {
    glsl_prefix = PURPOSE;

    /// BSSRDF probe numbers of candidate generation: per BSSRDF sample, `u_technique, u_radius,
    /// u_angle`.
    pub const PROBE: u32 = 0x100;
    /// Light-sample numbers of candidate generation: 3 per probe (shared light) or per hit.
    pub const LIGHT: u32 = 0x101;
    /// Weighted-reservoir selection numbers (`u` of [001 Alg. 1]), one per streamed candidate
    /// or input reservoir, in candidate generation and in reuse passes.
    pub const SELECT: u32 = 0x102;
    /// Spatial neighbour positions: 2 numbers (radius, angle) per neighbour slot.
    pub const NEIGHBOURS: u32 = 0x103;
    /// The path-tracing estimate that shades pixels whose x1 is not translucent.
    pub const OPAQUE: u32 = 0x104;
    /// A reciprocal spatial pass's pairings (`engine::reciprocal`): per neighbour slot (the
    /// key's `pixel` is the slot), 3 numbers (offset radius, angle, stripe phase).
    pub const PAIRS: u32 = 0x105;
    /// The volumetric random walks of a pixel (`methods::random_walk`).
    pub const WALK: u32 = 0x5257_0001;
    /// The light selection at the random walks' exits.
    pub const WALK_LIGHT: u32 = 0x5257_0002;
    /// The light selection at the exits of paper 000's hybrid estimator (`single-scatter`; ASCII
    /// "SS" + 2: its samples use `sss::integrator::single_scatter::PURPOSE_SINGLE_SCATTER`, "SS"
    /// + 1).
    pub const SINGLE_SCATTER_LIGHT: u32 = 0x5353_0002;
}
