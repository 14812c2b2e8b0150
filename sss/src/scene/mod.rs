//! See DESIGN §4.
