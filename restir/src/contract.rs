twin::contract! {
    /// Most domains (receiver + neighbours) one resampling step combines; the weight buffers are
    /// stack arrays of this length.
    pub const MAX_DOMAINS: usize = 16;

    /// The MIS schemes of [`crate::mis`] by name, for pipelines described as data: a pass names
    /// its scheme with a `MisKind`, and the GPU twin (`restir/glsl/mis.glsl`) dispatches on its
    /// code through `MIS_KINDS(X)` to `mis_<stem>_weight` and `mis_<stem>_needs_all_targets`.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum MisKind in MIS {
        /// [`crate::mis::Gbh`].
        Gbh(gbh),
        /// [`crate::mis::Pairwise`].
        Pairwise(pairwise),
        /// [`crate::mis::DefensivePairwise`].
        DefensivePairwise(defensive_pairwise),
        /// `1/M` with confidences ([`crate::mis::ConfidenceOnly`]): biased unless supports agree
        /// (a control, not a default).
        ConfidenceOnly(confidence_only),
    }

    /// Why a shift produced no sample. Every failure gives the shifted candidate weight 0. On
    /// the GPU a shift returns its code, or `SHIFT_OK` (0) when it succeeded.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum Fail in SHIFT_FAIL, 0 = SHIFT_OK {
        /// The inverse map has no solution for this point.
        NotInvertible,
        /// The shifted point lies outside the destination domain.
        OutOfSupport,
        /// A visibility test of the shift failed.
        Occluded,
        /// The Jacobian is 0 or not finite (a singular point of the map).
        Degenerate,
        /// A rule of the shift rejects the pair (it must reject in both directions).
        Rejected,
    }

    /// The kind of a [`crate::resample::ResampleError`] (or of its
    /// [`crate::reservoir::InvalidCandidate`]) as a GPU kernel reports it: the low byte of its
    /// error word, 0 for none (`restir/glsl/resample.glsl`).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub enum ResampleCode in RESAMPLE, 0 = RESAMPLE_OK {
        InvalidWeight,
        InvalidTarget,
        InvalidConfidence,
        InvalidUcw,
        TooManyDomains,
        BadPdf,
        BadJacobian,
    }
}
