//! The progressive reference renderer (DESIGN §4, §7): the baseline estimator ([`super::pt`]) run
//! in independent batches, with per-pixel sums and sums of squares of the batch means, so every
//! pixel has a standard error; checkpoint / resume; shards by batch range; merge.
//!
//! Batch `b` is samples `b·K .. (b+1)·K` of the baseline (K = `spp_per_batch`), so a batch's
//! random numbers depend only on `(seed, frame, pixel, b)`. Sums are [`ExactSum`]s: merging shards
//! or resuming a checkpoint gives the same bits as one uninterrupted, unsharded run.
//!
//! # Checkpoint format (little-endian)
//!
//! | field | type |
//! |---|---|
//! | magic `RSSSREF1` | 8 bytes |
//! | width, height, frame | u32 ×3 |
//! | seed | u64 |
//! | spp_per_batch, batches (planned total), start, next, end | u32 ×5 |
//! | estimator: bit 0 hit policy (0 = uniform one, 1 = all), bit 1 Xie radii, bit 2 dipole profile | u8 |
//! | P(axis) ×3, P(channel) ×3 | f32 ×6 |
//! | nonfinite | u64 |
//! | scene name: length, UTF-8 bytes | u32, bytes |
//! | per pixel (row-major): Σm per RGB, then Σm² per RGB, each 4 limbs | u64 ×24 |
//!
//! `start..next` are the batches accumulated so far, `start..end` the ones this run owns.

use std::ops::Range;
use std::path::{Path, PathBuf};

use geometry::limits::{bytes as human, read_file};
use glam::DVec3;

use super::exact::ExactSum;
use super::pt::{self, HitPolicy, PtSettings};
use crate::InputError;
use crate::bssrdf::{RadiusSampling, TechniqueSelection};
use crate::limits::{self, MAX_PIXELS};
use crate::profile::ProfileKind;
use crate::scene::{GBuffer, Scene};

const MAGIC: &[u8; 8] = b"RSSSREF1";
/// Bytes of the fixed-size fields of a checkpoint (everything but the name and the pixels).
const FIXED_BYTES: u64 = 8 + 3 * 4 + 8 + 5 * 4 + 1 + 6 * 4 + 8 + 4;
/// Bytes of one pixel: Σm and Σm² per RGB channel, 4 limbs each.
const PIXEL_BYTES: u64 = 2 * 3 * 4 * 8;
/// Longest scene name in a checkpoint, in bytes.
const MAX_NAME_BYTES: u64 = 4096;
/// Largest checkpoint file: [`MAX_PIXELS`] pixels.
pub const MAX_CHECKPOINT_BYTES: u64 = FIXED_BYTES + MAX_NAME_BYTES + MAX_PIXELS * PIXEL_BYTES;

/// Bits of the checkpoint's estimator byte (a byte of 0 or 1 is a file from before the options).
const FLAG_ALL_HITS: u8 = 1;
const FLAG_XIE: u8 = 2;
const FLAG_DIPOLE: u8 = 4;

/// The estimator byte of `settings`.
fn estimator_flags(settings: &PtSettings) -> u8 {
    let mut flags = 0;
    if settings.hits == HitPolicy::All {
        flags |= FLAG_ALL_HITS;
    }
    if settings.radius == RadiusSampling::Xie {
        flags |= FLAG_XIE;
    }
    if settings.profile == ProfileKind::Dipole {
        flags |= FLAG_DIPOLE;
    }
    flags
}

/// What a reference integrates; two references can be merged only if these agree.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceConfig {
    /// Scene name (recorded in checkpoints, checked on merge).
    pub scene: String,
    pub frame: u32,
    pub seed: u64,
    pub spp_per_batch: u32,
    /// Planned number of batches of the whole (unsharded) reference.
    pub batches: u32,
    pub settings: PtSettings,
}

/// Shard `index` of `count`: the batches `⌊index·B/count⌋ .. ⌊(index+1)·B/count⌋`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parses `"i/n"` with `i < n`; `field` names the option in the error.
    pub fn parse(text: &str, field: &str) -> Result<Shard, InputError> {
        let bad =
            |reason: &str| InputError::new("(command line)", field, format!("{text:?}"), reason);
        let (i, n) = text.split_once('/').ok_or_else(|| bad("expected `i/n`"))?;
        let index: u32 = i
            .trim()
            .parse()
            .map_err(|_| bad("shard index is not an integer"))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad("shard count is not an integer"))?;
        if count == 0 || index >= count {
            return Err(bad("need 0 ≤ i < n"));
        }
        Ok(Shard { index, count })
    }

    pub fn batches(&self, total: u32) -> Range<u32> {
        let at = |k: u32| (k as u64 * total as u64 / self.count as u64) as u32;
        at(self.index)..at(self.index + 1)
    }
}

/// A progressive reference over a G-buffer: exact sums of per-pixel batch means and their squares.
#[derive(Clone, Debug, PartialEq)]
pub struct Reference {
    pub config: ReferenceConfig,
    pub width: u32,
    pub height: u32,
    /// First batch this run owns.
    pub start: u32,
    /// Next batch to render (`start..next` are accumulated).
    pub next: u32,
    /// One past the last batch this run owns.
    pub end: u32,
    /// Samples that were NaN or infinite (left out of their batch mean), plus batch means that
    /// could not be accumulated exactly (see [`ExactSum::add`]). None are expected.
    pub nonfinite: u64,
    sum: Vec<[ExactSum; 3]>,
    sum_sq: Vec<[ExactSum; 3]>,
}

impl Reference {
    /// An empty reference for `shard` of `config` on a `width × height` image.
    pub fn new(
        config: ReferenceConfig,
        width: u32,
        height: u32,
        shard: Shard,
    ) -> Result<Reference, InputError> {
        let bad = |field: &str, value: String, reason: &str| {
            Err(InputError::new("(reference)", field, value, reason))
        };
        if config.spp_per_batch == 0 {
            return bad("spp_per_batch", "0".into(), "must be ≥ 1");
        }
        if config.batches == 0 {
            return bad("batches", "0".into(), "must be ≥ 1");
        }
        if config.batches as u64 * config.spp_per_batch as u64 > u32::MAX as u64 + 1 {
            let value = format!("{} × {}", config.batches, config.spp_per_batch);
            return bad(
                "batches",
                value,
                "batches × spp_per_batch must not exceed 2³² samples per pixel",
            );
        }
        limits::resolution(Path::new("(reference)"), "width×height", width, height)?;
        let range = shard.batches(config.batches);
        let pixels = width as usize * height as usize;
        Ok(Reference {
            config,
            width,
            height,
            start: range.start,
            next: range.start,
            end: range.end,
            nonfinite: 0,
            sum: vec![[ExactSum::default(); 3]; pixels],
            sum_sq: vec![[ExactSum::default(); 3]; pixels],
        })
    }

    pub fn is_complete(&self) -> bool {
        self.next == self.end
    }

    /// Number of batches accumulated.
    pub fn batches_done(&self) -> u32 {
        self.next - self.start
    }

    /// Renders up to `max_batches` more batches of `gbuffer` (which must be of
    /// `config.frame`, same size); returns how many it rendered.
    pub fn run(&mut self, scene: &Scene, gbuffer: &GBuffer, max_batches: u32) -> u32 {
        assert_eq!(
            (gbuffer.width, gbuffer.height),
            (self.width, self.height),
            "G-buffer size"
        );
        let stop = self.end.min(self.next.saturating_add(max_batches));
        let k = self.config.spp_per_batch;
        for batch in self.next..stop {
            let image = pt::render(
                scene,
                gbuffer,
                &self.config.settings,
                self.config.seed,
                batch * k,
                k,
            );
            self.nonfinite += image.nonfinite;
            for ((sum, sum_sq), m) in self.sum.iter_mut().zip(&mut self.sum_sq).zip(&image.pixels) {
                for c in 0..3 {
                    let accepted = sum[c].add(m[c]) && sum_sq[c].add(m[c] * m[c]);
                    self.nonfinite += !accepted as u64;
                }
            }
        }
        let done = stop - self.next;
        self.next = stop;
        done
    }

    /// Per-pixel mean over the accumulated batches (0 before the first batch).
    pub fn mean(&self) -> Vec<DVec3> {
        let n = self.batches_done().max(1) as f64;
        self.sum
            .iter()
            .map(|s| DVec3::from_array(s.map(|x| x.to_f64() / n)))
            .collect()
    }

    /// Per-pixel standard error of the mean, from the spread of the batch means (∞ with < 2 batches).
    pub fn std_err(&self) -> Vec<DVec3> {
        let n = self.batches_done() as f64;
        self.sum
            .iter()
            .zip(&self.sum_sq)
            .map(|(s, q)| {
                DVec3::from_array(std::array::from_fn(|c| {
                    if n < 2.0 {
                        return f64::INFINITY;
                    }
                    let mean = s[c].to_f64() / n;
                    let variance = ((q[c].to_f64() - n * mean * mean) / (n - 1.0)).max(0.0);
                    (variance / n).sqrt()
                }))
            })
            .collect()
    }

    /// Sums complete shards of one reference, each with the file it was read from (any order).
    /// The shards must share the configuration and image size and cover a contiguous batch
    /// range without overlap; errors name the shard's file, the field and both values.
    pub fn merge(mut parts: Vec<(PathBuf, Reference)>) -> Result<Reference, InputError> {
        parts.sort_by_key(|(_, p)| p.start);
        let Some((first_path, first)) = parts.first() else {
            return Err(InputError::new(
                "(merge)",
                "shards",
                "none",
                "nothing to merge",
            ));
        };
        let mut merged = first.clone();
        for (path, part) in &parts {
            if let Some((field, theirs, ours)) = first.difference(part) {
                return Err(InputError::new(
                    path,
                    field,
                    theirs,
                    format!(
                        "differs from {} ({ours}): shards of different references",
                        first_path.display()
                    ),
                ));
            }
            if !part.is_complete() {
                return Err(InputError::new(
                    path,
                    "start/next/end",
                    format!("{}/{}/{}", part.start, part.next, part.end),
                    "shard is incomplete",
                ));
            }
            if std::ptr::eq(part, first) {
                continue;
            }
            if part.start != merged.end {
                return Err(InputError::new(
                    path,
                    "start/end",
                    format!("{}/{}", part.start, part.end),
                    format!(
                        "batch ranges overlap or leave a gap: the shards before it end at {}",
                        merged.end
                    ),
                ));
            }
            for (a, b) in merged
                .sum
                .iter_mut()
                .zip(&part.sum)
                .chain(merged.sum_sq.iter_mut().zip(&part.sum_sq))
            {
                for c in 0..3 {
                    a[c].add_exact(&b[c]);
                }
            }
            merged.nonfinite = merged.nonfinite.saturating_add(part.nonfinite);
            merged.end = part.end;
            merged.next = part.end;
        }
        Ok(merged)
    }

    /// The first field in which `other` is of another reference: `(field, other's, self's)`.
    fn difference(&self, other: &Reference) -> Option<(&'static str, String, String)> {
        let (a, b) = (&self.config, &other.config);
        let size = |r: &Reference| format!("{}×{}", r.width, r.height);
        let fields = [
            ("scene", format!("{:?}", b.scene), format!("{:?}", a.scene)),
            ("width×height", size(other), size(self)),
            ("frame", b.frame.to_string(), a.frame.to_string()),
            ("seed", b.seed.to_string(), a.seed.to_string()),
            (
                "spp_per_batch",
                b.spp_per_batch.to_string(),
                a.spp_per_batch.to_string(),
            ),
            ("batches", b.batches.to_string(), a.batches.to_string()),
            (
                "hit_policy",
                format!("{:?}", b.settings.hits),
                format!("{:?}", a.settings.hits),
            ),
            (
                "selection",
                format!("{:?}", b.settings.selection),
                format!("{:?}", a.settings.selection),
            ),
        ];
        fields.into_iter().find(|(_, theirs, ours)| theirs != ours)
    }

    /// Writes the checkpoint (format in the module documentation).
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        std::fs::write(path, self.to_bytes())
    }

    /// The checkpoint's bytes (format in the module documentation).
    pub fn to_bytes(&self) -> Vec<u8> {
        let c = &self.config;
        let mut out = Vec::with_capacity(96 + c.scene.len() + self.sum.len() * 192);
        out.extend_from_slice(MAGIC);
        for v in [self.width, self.height, c.frame] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&c.seed.to_le_bytes());
        for v in [c.spp_per_batch, c.batches, self.start, self.next, self.end] {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.push(estimator_flags(&c.settings));
        for p in c
            .settings
            .selection
            .axis
            .iter()
            .chain(&c.settings.selection.channel)
        {
            out.extend_from_slice(&p.to_le_bytes());
        }
        out.extend_from_slice(&self.nonfinite.to_le_bytes());
        out.extend_from_slice(&(c.scene.len() as u32).to_le_bytes());
        out.extend_from_slice(c.scene.as_bytes());
        for (s, q) in self.sum.iter().zip(&self.sum_sq) {
            for limb in s.iter().chain(q).flat_map(|x| x.0) {
                out.extend_from_slice(&limb.to_le_bytes());
            }
        }
        out
    }

    /// Reads a checkpoint written by [`Reference::save`].
    pub fn load(path: &Path) -> Result<Reference, InputError> {
        Reference::from_bytes(&read_file(path, MAX_CHECKPOINT_BYTES)?, path)
    }

    /// Parses checkpoint bytes; `path` names them in errors. Every size in the header is checked
    /// against the limits and the bytes present before anything is allocated.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Reference, InputError> {
        let mut reader = Reader { bytes, at: 0, path };
        let magic = reader.take(8, "magic")?;
        if magic != MAGIC {
            return Err(InputError::new(
                path,
                "magic",
                format!("{magic:?}"),
                "not a reshift reference checkpoint",
            ));
        }
        let (width, height, frame) = (
            reader.u32("width")?,
            reader.u32("height")?,
            reader.u32("frame")?,
        );
        limits::resolution(path, "width×height", width, height)?;
        let seed = reader.u64("seed")?;
        let (spp_per_batch, batches) = (reader.u32("spp_per_batch")?, reader.u32("batches")?);
        let (start, next, end) = (
            reader.u32("start")?,
            reader.u32("next")?,
            reader.u32("end")?,
        );
        if !(start <= next && next <= end && end <= batches) {
            return Err(InputError::new(
                path,
                "start/next/end",
                format!("{start}/{next}/{end} of {batches}"),
                "inconsistent batch range",
            ));
        }
        let flags = reader.take(1, "estimator")?[0];
        if flags > FLAG_ALL_HITS | FLAG_XIE | FLAG_DIPOLE {
            return Err(InputError::new(
                path,
                "estimator",
                flags.to_string(),
                "expected bits 0 (all hits), 1 (Xie radii) and 2 (dipole profile) only",
            ));
        }
        let mut probabilities = [0.0f32; 6];
        for p in &mut probabilities {
            *p = f32::from_le_bytes(reader.array("selection")?);
        }
        let selection = TechniqueSelection {
            axis: [probabilities[0], probabilities[1], probabilities[2]],
            channel: [probabilities[3], probabilities[4], probabilities[5]],
        };
        for (field, p) in [
            ("selection.axis", selection.axis),
            ("selection.channel", selection.channel),
        ] {
            let sum: f32 = p.iter().sum();
            if !(p.iter().all(|x| (0.0..=1.0).contains(x)) && (sum - 1.0).abs() <= 1e-4) {
                return Err(InputError::new(
                    path,
                    field,
                    format!("{p:?}"),
                    "probabilities must lie in [0, 1] and sum to 1",
                ));
            }
        }
        let nonfinite = reader.u64("nonfinite")?;
        let name_len = reader.u32("scene_name_length")? as u64;
        if name_len > MAX_NAME_BYTES {
            return Err(InputError::new(
                path,
                "scene_name_length",
                name_len.to_string(),
                format!("longer than {MAX_NAME_BYTES} bytes"),
            ));
        }
        let scene = String::from_utf8(reader.take(name_len as usize, "scene_name")?.to_vec())
            .map_err(|e| InputError::new(path, "scene_name", "(bytes)", e.to_string()))?;
        let pixel_bytes = width as u64 * height as u64 * PIXEL_BYTES;
        let left = (bytes.len() - reader.at) as u64;
        if left != pixel_bytes {
            return Err(InputError::new(
                path,
                "pixels",
                human(left),
                format!(
                    "the header's {width}×{height} pixels need {}",
                    human(pixel_bytes)
                ),
            ));
        }
        let config = ReferenceConfig {
            scene,
            frame,
            seed,
            spp_per_batch,
            batches,
            settings: PtSettings {
                hits: if flags & FLAG_ALL_HITS != 0 {
                    HitPolicy::All
                } else {
                    HitPolicy::UniformOne
                },
                selection,
                radius: if flags & FLAG_XIE != 0 {
                    RadiusSampling::Xie
                } else {
                    RadiusSampling::Exact
                },
                profile: if flags & FLAG_DIPOLE != 0 {
                    ProfileKind::Dipole
                } else {
                    ProfileKind::Burley
                },
            },
        };
        let mut reference =
            Reference::new(config, width, height, Shard::WHOLE).map_err(|e| InputError {
                file: path.to_path_buf(),
                ..e
            })?;
        (
            reference.start,
            reference.next,
            reference.end,
            reference.nonfinite,
        ) = (start, next, end, nonfinite);
        for (s, q) in reference.sum.iter_mut().zip(reference.sum_sq.iter_mut()) {
            for x in s.iter_mut().chain(q.iter_mut()) {
                for limb in &mut x.0 {
                    *limb = reader.u64("pixels")?;
                }
            }
        }
        Ok(reference)
    }
}

/// A cursor over checkpoint bytes whose errors name the field being read.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    path: &'a Path,
}

impl Reader<'_> {
    fn take(&mut self, n: usize, field: &str) -> Result<&[u8], InputError> {
        let slice = self
            .bytes
            .get(self.at..self.at.saturating_add(n))
            .ok_or_else(|| {
                InputError::new(
                    self.path,
                    field,
                    format!("offset {}", self.at),
                    "file ends early (truncated checkpoint)",
                )
            })?;
        self.at += n;
        Ok(slice)
    }

    fn array<const N: usize>(&mut self, field: &str) -> Result<[u8; N], InputError> {
        let mut out = [0; N];
        out.copy_from_slice(self.take(N, field)?);
        Ok(out)
    }

    fn u32(&mut self, field: &str) -> Result<u32, InputError> {
        Ok(u32::from_le_bytes(self.array(field)?))
    }

    fn u64(&mut self, field: &str) -> Result<u64, InputError> {
        Ok(u64::from_le_bytes(self.array(field)?))
    }
}

#[cfg(test)]
mod tests;
