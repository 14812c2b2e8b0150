//! An order-independent exact sum of `f64` values: 256-bit two's-complement fixed point with
//! quantum 2⁻¹²⁸. Integer addition is associative, so sums merged in any order (shards, resumed
//! checkpoints) are bit-identical to one sequential sum.
//!
//! Every `f64` with `2⁻⁷⁶ ≤ |x| < 2¹²⁶` is represented exactly (53 mantissa bits above the
//! quantum); smaller magnitudes are rounded to the nearest multiple of 2⁻¹²⁸ (ties away from 0).

/// Largest magnitude [`ExactSum::add`] accepts: `2¹²⁶`. A running sum stays exact while
/// `|Σ| < 2¹²⁷` (e.g. 10²⁸ additions of values up to 10¹⁰).
pub const EXACT_SUM_LIMIT: f64 = 8.507_059_173_023_462e37;

/// A running exact sum; limbs little-endian, two's complement.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct ExactSum(pub [u64; 4]);

impl ExactSum {
    /// Adds `x`; returns `false` (and adds nothing) if `x` is not finite or `|x| ≥ 2¹²⁶`.
    pub fn add(&mut self, x: f64) -> bool {
        match fixed_point(x) {
            Some(value) => {
                self.add_exact(&ExactSum(value));
                true
            }
            None => false,
        }
    }

    /// Adds another exact sum (wrapping; see [`EXACT_SUM_LIMIT`] for the headroom).
    pub fn add_exact(&mut self, other: &ExactSum) {
        let mut carry = false;
        for (a, &b) in self.0.iter_mut().zip(&other.0) {
            let (s1, c1) = a.overflowing_add(b);
            let (s2, c2) = s1.overflowing_add(carry as u64);
            *a = s2;
            carry = c1 || c2;
        }
    }

    /// The sum rounded to `f64` (deterministic; exact limbs are combined from the most significant).
    pub fn to_f64(&self) -> f64 {
        let negative = self.0[3] >> 63 == 1;
        let magnitude = if negative { negate(self.0) } else { self.0 };
        let value = magnitude
            .iter()
            .enumerate()
            .rev()
            .fold(0.0, |acc, (i, &limb)| {
                acc + limb as f64 * 2f64.powi(64 * i as i32 - 128)
            });
        if negative { -value } else { value }
    }
}

fn negate(limbs: [u64; 4]) -> [u64; 4] {
    let mut out = limbs.map(|l| !l);
    for limb in out.iter_mut() {
        let (v, carry) = limb.overflowing_add(1);
        *limb = v;
        if !carry {
            break;
        }
    }
    out
}

/// `round(x · 2¹²⁸)` as 256-bit two's complement, or `None` outside the accepted range.
fn fixed_point(x: f64) -> Option<[u64; 4]> {
    if !x.is_finite() || x.abs() >= EXACT_SUM_LIMIT {
        return None;
    }
    if x == 0.0 {
        return Some([0; 4]);
    }
    let bits = x.to_bits();
    let exponent = ((bits >> 52) & 0x7FF) as i32;
    let fraction = bits & ((1 << 52) - 1);
    // x = mantissa · 2^(shift − 128) with the quantum 2⁻¹²⁸.
    let (mantissa, shift) = if exponent == 0 {
        (fraction, -1074 + 128)
    } else {
        (fraction | (1 << 52), exponent - 1075 + 128)
    };
    let mut limbs = [0u64; 4];
    if shift >= 0 {
        let (word, bit) = ((shift / 64) as usize, shift % 64);
        let wide = (mantissa as u128) << bit;
        limbs[word] = wide as u64;
        if word + 1 < 4 {
            limbs[word + 1] = (wide >> 64) as u64;
        }
    } else if shift > -64 {
        let down = -shift as u32;
        limbs[0] = (mantissa >> down) + ((mantissa >> (down - 1)) & 1);
    }
    Some(if x < 0.0 { negate(limbs) } else { limbs })
}

#[cfg(test)]
mod tests {
    use super::*;
    use restir::rng::StreamKey;

    /// Values spanning 60 binary orders of magnitude and both signs, summed in three different
    /// orders and groupings: the exact sums agree bit for bit, while plain `f64` sums do not
    /// (negative control: shows the test data would expose a non-associative accumulator).
    #[test]
    fn sums_are_independent_of_order_and_grouping() {
        let mut rng = StreamKey::new(0, 0, 0, 0xE5AC).stream(1);
        let values: Vec<f64> = (0..10_000)
            .map(|_| (rng.next_f64() - 0.3) * 2f64.powi((rng.next_f64() * 60.0) as i32 - 30))
            .collect();
        let forward = values.iter().fold(ExactSum::default(), |mut s, &x| {
            assert!(s.add(x));
            s
        });
        let mut backward = ExactSum::default();
        values.iter().rev().for_each(|&x| assert!(backward.add(x)));
        let mut chunks = ExactSum::default();
        for chunk in values.chunks(777) {
            let mut part = ExactSum::default();
            chunk.iter().for_each(|&x| assert!(part.add(x)));
            chunks.add_exact(&part);
        }
        assert_eq!(forward, backward);
        assert_eq!(forward, chunks);
        let plain_forward: f64 = values.iter().sum();
        let plain_backward: f64 = values.iter().rev().sum();
        assert_ne!(
            plain_forward.to_bits(),
            plain_backward.to_bits(),
            "control: f64 sums agree by chance"
        );
        let exact_f64 = forward.to_f64();
        assert!(
            (exact_f64 - plain_forward).abs() <= 1e-9 * values.iter().map(|x| x.abs()).sum::<f64>()
        );
    }

    #[test]
    fn representation_is_exact_in_range_and_rejects_the_rest() {
        for x in [
            1.0,
            -1.0,
            0.1,
            -3.5e-20,
            1e30,
            -7.25,
            f64::MIN_POSITIVE,
            2f64.powi(-76),
        ] {
            let mut s = ExactSum::default();
            assert!(s.add(x));
            if x.abs() >= 2f64.powi(-76) {
                assert_eq!(s.to_f64(), x, "{x} not exact");
            }
            s.add(-x);
            assert_eq!(s, ExactSum::default(), "{x} − {x} ≠ 0");
        }
        let mut s = ExactSum::default();
        assert!(!s.add(f64::NAN) && !s.add(f64::INFINITY) && !s.add(EXACT_SUM_LIMIT));
        assert_eq!(s, ExactSum::default());
        assert_eq!(EXACT_SUM_LIMIT, 2f64.powi(126));
    }
}
