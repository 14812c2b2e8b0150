//! Stream random numbers: every random decision draws from a generator seeded by an explicit
//! [`StreamKey`], never from a global RNG, so results do not depend on scheduling or thread count.
//!
//! Key → seed: `splitmix64` over the packed key words and the run seed (see [`StreamKey::seed_pair`]);
//! generator: PCG32 (`rand_pcg::Pcg32`, XSH-RR output on a 64-bit LCG). The GLSL twin is
//! `restir/glsl/rng.glsl` and must produce the same sequence.

use rand_core::Rng;
use rand_pcg::Pcg32;

/// Identifies one independent random stream: a pixel at a frame, inside a pass, for one purpose.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct StreamKey {
    pub pixel: u32,
    pub frame: u32,
    pub pass: u32,
    pub purpose: u32,
}

/// One step of splitmix64 used as a 64-bit finaliser (Steele, Lea & Flood 2014).
#[inline]
pub fn splitmix64(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

impl StreamKey {
    pub const fn new(pixel: u32, frame: u32, pass: u32, purpose: u32) -> Self {
        Self {
            pixel,
            frame,
            pass,
            purpose,
        }
    }

    /// The PCG32 `(state, stream)` pair for this key under the run seed `seed`.
    pub fn seed_pair(&self, seed: u64) -> (u64, u64) {
        let k0 = ((self.pixel as u64) << 32) | self.frame as u64;
        let k1 = ((self.pass as u64) << 32) | self.purpose as u64;
        let state = splitmix64(seed ^ splitmix64(k0 ^ splitmix64(k1)));
        let stream = splitmix64(state ^ 0xD1B5_4A32_D192_ED03);
        (state, stream)
    }

    /// The generator for this key under the run seed `seed` (a replica uses its own seed).
    pub fn stream(&self, seed: u64) -> Stream {
        let (state, stream) = self.seed_pair(seed);
        Stream(Pcg32::new(state, stream))
    }
}

/// A keyed PCG32 stream.
#[derive(Clone, Debug)]
pub struct Stream(Pcg32);

impl Stream {
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.0.next_u32()
    }

    /// A uniform `f32` in [0, 1): `(u >> 8) · 2⁻²⁴`, so 1.0 is never returned.
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        u32_to_unit_f32(self.next_u32())
    }

    /// A uniform `f64` in [0, 1) with 53 random bits (for host-side statistics, not kernels).
    #[inline]
    pub fn next_f64(&mut self) -> f64 {
        let hi = (self.next_u32() >> 5) as u64;
        let lo = (self.next_u32() >> 6) as u64;
        ((hi << 26) | lo) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// `(u >> 8) · 2⁻²⁴`: 24 random bits, exactly representable, in [0, 1).
#[inline]
pub fn u32_to_unit_f32(u: u32) -> f32 {
    (u >> 8) as f32 * (1.0 / 16_777_216.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_key_same_sequence_and_keys_differ() {
        let key = StreamKey::new(7, 3, 1, 2);
        let mut a = key.stream(42);
        let mut b = key.stream(42);
        let mut c = StreamKey::new(7, 3, 1, 3).stream(42);
        let mut d = key.stream(43);
        let xs: Vec<u32> = (0..16).map(|_| a.next_u32()).collect();
        let ys: Vec<u32> = (0..16).map(|_| b.next_u32()).collect();
        let zs: Vec<u32> = (0..16).map(|_| c.next_u32()).collect();
        let ws: Vec<u32> = (0..16).map(|_| d.next_u32()).collect();
        assert_eq!(xs, ys);
        assert_ne!(xs, zs);
        assert_ne!(xs, ws);
    }

    #[test]
    fn unit_float_is_in_half_open_interval() {
        assert_eq!(u32_to_unit_f32(0), 0.0);
        assert!(u32_to_unit_f32(u32::MAX) < 1.0);
        assert_eq!(u32_to_unit_f32(u32::MAX), 1.0 - 2f32.powi(-24));
    }

    /// Golden values: the GLSL twin is checked against these.
    #[test]
    fn golden_sequence() {
        let mut s = StreamKey::new(1, 2, 3, 4).stream(5);
        let got: Vec<u32> = (0..4).map(|_| s.next_u32()).collect();
        let (state, stream) = StreamKey::new(1, 2, 3, 4).seed_pair(5);
        // Reference PCG32 written out: inc = 2·stream + 1; state ← state + inc; step; then output.
        let inc = (stream << 1) | 1;
        let mul = 6_364_136_223_846_793_005u64;
        let mut st = state.wrapping_add(inc).wrapping_mul(mul).wrapping_add(inc);
        let mut want = Vec::new();
        for _ in 0..4 {
            let old = st;
            st = st.wrapping_mul(mul).wrapping_add(inc);
            let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
            let rot = (old >> 59) as u32;
            want.push(xorshifted.rotate_right(rot));
        }
        assert_eq!(got, want);
    }
}
