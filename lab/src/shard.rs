//! Jobs split over replica seeds: `--shard i/n` of `reshift bias` and `reshift compare` renders
//! the seeds of its part of `0..N` and writes a partial file, `shard-i-of-n.json`; merging the
//! `n` parts gives the outcome of one run bit for bit (docs/cluster.md).
//!
//! Here what every kind of shard shares: the part of the seeds ([`seeds`]: contiguous ranges,
//! as the reference's batches, `sss::integrator::Shard`), the file name, reading a shard file
//! ([`read`]), the checks before a merge ([`check_set`]: one plan, one count, every part once)
//! and [`Exact`], an `f64` written to JSON so that it reads back to the same bits, NaN and
//! infinities included. The kinds are in [`crate::bias::shard`] and [`crate::compare::shard`].

use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use geometry::limits::read_file;
use serde::de::{self, Deserializer, Visitor};
use serde::{Deserialize, Serialize, Serializer};
use serde_json::Value;
pub use sss::integrator::Shard;

use crate::error::Error;

/// Bytes a shard file may have (a compare shard holds its replicas' measured frames).
pub const MAX_SHARD_BYTES: u64 = 1 << 32;

/// The version of the code that wrote a shard: shards of different versions do not merge.
pub const CODE_VERSION: &str = env!("CARGO_PKG_VERSION");

/// The seeds of `shard` among the `replicas` seeds from `first_seed` (S):
/// `S + ⌊i·N/n⌋ .. S + ⌊(i+1)·N/n⌋`, like the batches of a reference shard. The plans check that
/// `S + N` is a seed.
pub fn seeds(shard: Shard, replicas: u32, first_seed: u64) -> Range<u64> {
    let r = shard.batches(replicas);
    first_seed.saturating_add(r.start as u64)..first_seed.saturating_add(r.end as u64)
}

/// `shard-i-of-n.json`.
pub fn file_name(shard: Shard) -> String {
    format!("shard-{}-of-{}.json", shard.index, shard.count)
}

/// The JSON of a shard file and its `schema`; an unreadable file, bad JSON or no `schema` string
/// is one line naming the file.
pub fn read(path: &Path) -> Result<(String, Value), Error> {
    let bytes = read_file(path, MAX_SHARD_BYTES)?;
    let bad = |reason: String| Error::Invalid(format!("{}: {reason}", path.display()));
    let value: Value =
        serde_json::from_slice(&bytes).map_err(|e| bad(format!("not a shard file: {e}")))?;
    let schema = value
        .get("schema")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("no \"schema\" field: not a shard file".into()))?;
    Ok((schema.to_string(), value))
}

/// A shard file parsed as `T`; a field of the wrong type or missing is one line naming it.
pub fn parse<T: for<'de> Deserialize<'de>>(path: &Path, value: Value) -> Result<T, Error> {
    serde_json::from_value(value)
        .map_err(|e| Error::Invalid(format!("{}: not a valid shard file: {e}", path.display())))
}

/// What every kind of shard says of itself.
pub trait Part {
    /// Everything that determines the merged result, as a JSON object (one field each).
    fn plan(&self) -> Value;
    /// Which part of the seeds it holds.
    fn shard(&self) -> Shard;
}

/// `parts` (each with its file) in shard order, after checking that they are one whole run:
/// every plan equal to the first's (else one line naming the field and both values), one part
/// count, no part twice and none missing.
pub fn check_set<T: Part>(mut parts: Vec<(PathBuf, T)>) -> Result<Vec<(PathBuf, T)>, Error> {
    parts.sort_by_key(|(_, p)| p.shard().index);
    let Some((first_path, first)) = parts.first() else {
        return Err(Error::Invalid("merge: no shard given".into()));
    };
    let plan = first.plan();
    let name = |p: &Path| p.display().to_string();
    for (path, part) in &parts[1..] {
        if let Some((field, theirs, ours)) = first_difference(&part.plan(), &plan) {
            return Err(Error::Invalid(format!(
                "{}: field '{field}' is {theirs}, {} has {ours}",
                name(path),
                name(first_path)
            )));
        }
    }
    let count = first.shard().count;
    for (path, part) in &parts {
        if part.shard().count != count {
            return Err(Error::Invalid(format!(
                "{}: field 'shards' is {}, {} has {count}",
                name(path),
                part.shard().count,
                name(first_path)
            )));
        }
    }
    for pair in parts.windows(2) {
        if pair[0].1.shard() == pair[1].1.shard() {
            return Err(Error::Invalid(format!(
                "{} and {} are both shard {} of {count}",
                name(&pair[0].0),
                name(&pair[1].0),
                pair[0].1.shard().index
            )));
        }
    }
    if let Some(missing) = (0..count).find(|&i| parts.iter().all(|(_, p)| p.shard().index != i)) {
        return Err(Error::Invalid(format!(
            "merge: shard {missing} of {count} ({}) is missing; {} of {count} given",
            file_name(Shard {
                index: missing,
                count
            }),
            parts.len()
        )));
    }
    Ok(parts)
}

/// The first field (in key order) where the objects `a` and `b` differ, with `a`'s and `b`'s
/// values as JSON text.
fn first_difference(a: &Value, b: &Value) -> Option<(String, String, String)> {
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return (a != b).then(|| ("plan".into(), a.to_string(), b.to_string()));
    };
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    keys.into_iter().find_map(|k| {
        let (x, y) = (a.get(k), b.get(k));
        let text = |v: Option<&Value>| v.map_or("absent".into(), Value::to_string);
        (x != y).then(|| (k.clone(), text(x), text(y)))
    })
}

/// An `f64` that a shard file keeps to the bit: a finite value is a JSON number (written
/// shortest by `ryu`, read back exactly with serde_json's `float_roundtrip`), a non-finite one
/// the string `NaN`, `inf` or `-inf` (JSON has no number for them).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exact(pub f64);

impl Serialize for Exact {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self.0 {
            x if x.is_finite() => s.serialize_f64(x),
            x if x.is_nan() => s.serialize_str("NaN"),
            x if x > 0.0 => s.serialize_str("inf"),
            _ => s.serialize_str("-inf"),
        }
    }
}

impl<'de> Deserialize<'de> for Exact {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Exact, D::Error> {
        struct ExactVisitor;
        impl Visitor<'_> for ExactVisitor {
            type Value = Exact;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, \"NaN\", \"inf\" or \"-inf\"")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Exact, E> {
                Ok(Exact(v))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Exact, E> {
                Ok(Exact(v as f64))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Exact, E> {
                Ok(Exact(v as f64))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Exact, E> {
                match v {
                    "NaN" => Ok(Exact(f64::NAN)),
                    "inf" => Ok(Exact(f64::INFINITY)),
                    "-inf" => Ok(Exact(f64::NEG_INFINITY)),
                    _ => Err(E::invalid_value(de::Unexpected::Str(v), &self)),
                }
            }
        }
        d.deserialize_any(ExactVisitor)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Awkward values (subnormal, extremes, a long expansion, -0, the non-finite ones) read back
    /// to the same bits.
    #[test]
    fn shard_numbers_round_trip_exactly() {
        let values = [
            0.1,
            1.0 / 3.0,
            -0.0,
            f64::MIN_POSITIVE / 3.0,
            f64::MAX,
            f64::EPSILON,
            2.0f64.sqrt() * 1e-300,
            0.30000000000000004,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        let exact: Vec<Exact> = values.iter().map(|&v| Exact(v)).collect();
        let text = serde_json::to_string(&exact).unwrap();
        let back: Vec<Exact> = serde_json::from_str(&text).unwrap();
        for (a, b) in values.iter().zip(&back) {
            assert_eq!(a.to_bits(), b.0.to_bits(), "{a:e} → {text}");
        }
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..10_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let v = f64::from_bits(state);
            let back: Exact =
                serde_json::from_str(&serde_json::to_string(&Exact(v)).unwrap()).unwrap();
            assert!(v.to_bits() == back.0.to_bits() || (v.is_nan() && back.0.is_nan()));
        }
        assert!(serde_json::from_str::<Exact>("\"nan\"").is_err());
    }

    struct Fake(Shard, Value);
    impl Part for Fake {
        fn plan(&self) -> Value {
            self.1.clone()
        }
        fn shard(&self) -> Shard {
            self.0
        }
    }

    fn part(index: u32, count: u32, method: &str) -> (PathBuf, Fake) {
        let shard = Shard { index, count };
        let plan = serde_json::json!({ "method": method, "replicas": 8 });
        (PathBuf::from(file_name(shard)), Fake(shard, plan))
    }

    /// A whole set comes back in shard order; a different plan, a duplicate, a missing part and
    /// another count are refused with one line naming what is wrong.
    #[test]
    fn a_set_is_checked_before_a_merge() {
        let set = check_set(vec![part(2, 3, "a"), part(0, 3, "a"), part(1, 3, "a")]).unwrap();
        let order: Vec<u32> = set.iter().map(|(_, p)| p.0.index).collect();
        assert_eq!(order, [0, 1, 2]);
        let error = |parts| check_set(parts).err().unwrap().to_string();
        assert_eq!(
            error(vec![
                part(0, 4, "restir:delayed"),
                part(3, 4, "restir:hybrid")
            ]),
            "shard-3-of-4.json: field 'method' is \"restir:hybrid\", shard-0-of-4.json has \"restir:delayed\""
        );
        assert_eq!(
            error(vec![part(0, 2, "a"), part(1, 2, "a"), part(1, 2, "a")]),
            "shard-1-of-2.json and shard-1-of-2.json are both shard 1 of 2"
        );
        assert_eq!(
            error(vec![part(0, 3, "a"), part(2, 3, "a")]),
            "merge: shard 1 of 3 (shard-1-of-3.json) is missing; 2 of 3 given"
        );
        assert_eq!(
            error(vec![part(0, 2, "a"), part(1, 3, "a")]),
            "shard-1-of-3.json: field 'shards' is 3, shard-0-of-2.json has 2"
        );
    }

    /// Contiguous ranges that cover `S..S+N` once, also with more shards than seeds.
    #[test]
    fn seeds_of_the_shards_cover_every_replica_once() {
        for (n, count, first) in [(8, 2, 0), (8, 3, 0), (5, 4, 7), (2, 3, 0), (3, 2, 100)] {
            let all: Vec<u64> = (0..count)
                .flat_map(|index| seeds(Shard { index, count }, n, first))
                .collect();
            assert_eq!(all, (first..first + n as u64).collect::<Vec<_>>());
        }
    }
}
