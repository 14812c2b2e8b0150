//! Statistics for unbiasedness tests (DESIGN §3, "Statistics").
