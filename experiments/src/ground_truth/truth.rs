//! The ground truth of a scene: the converged volumetric random walk (`random-walk`, each
//! material's `boundary`), computed like a reference — `B` independent batches of
//! `random-walk:S` at the measured frame, batch `b` with seed [`TRUTH_SEED`]` + b` (no replica
//! uses those seeds) — and cached per scene, size, frame and batch shape. The batches are kept
//! (not only their mean): their spread is the ground truth's own standard error, per pixel and
//! per region. A cache file is a checkpoint: it is rewritten after every batch and resumed.
//!
//! File (`.rsgt`, little-endian): the magic `RSGT0001`, then `u32` width, height, frame,
//! batches, spp per batch, batches done, then per finished batch `width · height` RGB `f32`.
//! A file that does not match its name's key is recomputed, never trusted.

use std::path::{Path, PathBuf};

use engine::{Backend, Image};
use glam::Vec3;
use sss::scene::Scene;

use lab::error::Error;
use lab::output::{file_stem, output_dir};
use lab::progress::Progress;
use methods::Method;

/// Seed of batch 0 (ASCII "GRNDTRTH"); batch `b` uses `TRUTH_SEED + b`.
pub const TRUTH_SEED: u64 = 0x4752_4E44_5452_5448;

/// The version of the random walk a cached ground truth was computed with. Bump it whenever the
/// walk's estimate changes (the `random-walk:2` rows of `lab/tests/pinned_output.rs` change).
pub const TRUTH_VERSION: u32 = 1;

const MAGIC: &[u8; 8] = b"RSGT0001";

/// What names a cached ground truth.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TruthKey {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frame: u32,
    pub batches: u32,
    pub spp_per_batch: u32,
}

impl TruthKey {
    /// `gt-v<TRUTH_VERSION>-<scene>-<W>x<H>-f<frame>-<B>x<S>spp.rsgt`.
    pub fn file_name(&self) -> String {
        format!(
            "gt-v{TRUTH_VERSION}-{}-{}x{}-f{}-{}x{}spp.rsgt",
            file_stem(&self.scene),
            self.width,
            self.height,
            self.frame,
            self.batches,
            self.spp_per_batch
        )
    }

    fn header(&self, done: u32) -> [u32; 6] {
        [
            self.width,
            self.height,
            self.frame,
            self.batches,
            self.spp_per_batch,
            done,
        ]
    }
}

/// The finished batches of a ground truth.
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    pub key: TruthKey,
    /// One image per finished batch.
    pub batches: Vec<Image>,
    /// The cache file.
    pub path: PathBuf,
    /// Whether every batch came from the cache.
    pub cached: bool,
}

impl Truth {
    pub fn is_complete(&self) -> bool {
        self.batches.len() == self.key.batches as usize
    }
}

/// The ground truth of `scene` (cache name `key.scene`, frame `key.frame`, the camera's size)
/// from the cache folder `dir`: reused when complete, resumed when partial, computed otherwise,
/// on the CPU (the cache holds one deterministic answer whatever the comparison's backend). A
/// stop request keeps the checkpoint and returns [`Error::Interrupted`].
pub fn obtain(
    dir: &Path,
    scene: &Scene,
    key: &TruthKey,
    progress: &mut dyn Progress,
) -> Result<Truth, Error> {
    if key.batches < 2 || key.spp_per_batch == 0 {
        return Err(Error::Invalid(format!(
            "ground truth of {}: {} batches × {} spp; need ≥ 2 batches (a standard error) of ≥ 1 spp",
            key.scene, key.batches, key.spp_per_batch
        )));
    }
    let path = output_dir(dir)?.join(key.file_name());
    let mut batches = load(&path, key).unwrap_or_default();
    let cached = batches.len() == key.batches as usize;
    let walk = Method::parse(&format!("random-walk:{}", key.spp_per_batch))?;
    progress.begin(
        &format!("ground truth {}", key.scene),
        key.batches as u64,
        batches.len() as u64,
    );
    while batches.len() < key.batches as usize {
        if progress.stop_requested() {
            progress.end();
            return Err(Error::Interrupted(format!(
                "interrupted while computing the ground truth; checkpoint {} resumes next time",
                path.display()
            )));
        }
        let seed = TRUTH_SEED + batches.len() as u64;
        let frames = key.frame + 1;
        batches.push(walk.render_on(&Backend::Cpu, scene, frames, seed)?.image);
        save(&path, key, &batches)?;
        progress.step();
    }
    progress.end();
    Ok(Truth {
        key: key.clone(),
        batches,
        path,
        cached,
    })
}

/// The finished batches of the file at `path` if its header is `key`'s; `None` otherwise.
fn load(path: &Path, key: &TruthKey) -> Option<Vec<Image>> {
    let bytes = std::fs::read(path).ok()?;
    let body = bytes.strip_prefix(MAGIC)?;
    let words = |range: std::ops::Range<usize>| -> Option<Vec<u32>> {
        body.get(range.start * 4..range.end * 4).map(|b| {
            b.chunks_exact(4)
                .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect()
        })
    };
    let header = words(0..6)?;
    let done = header[5];
    if header[..5] != key.header(0)[..5] || done > key.batches {
        return None;
    }
    let pixels = key.width as usize * key.height as usize;
    let floats = words(6..6 + done as usize * pixels * 3)?;
    if body.len() != (6 + floats.len()) * 4 {
        return None;
    }
    let batches = floats
        .chunks_exact((pixels * 3).max(1))
        .take(done as usize)
        .map(|batch| Image {
            width: key.width,
            height: key.height,
            pixels: batch
                .chunks_exact(3)
                .map(|c| {
                    Vec3::new(
                        f32::from_bits(c[0]),
                        f32::from_bits(c[1]),
                        f32::from_bits(c[2]),
                    )
                })
                .collect(),
        })
        .collect();
    Some(batches)
}

fn save(path: &Path, key: &TruthKey, batches: &[Image]) -> Result<(), Error> {
    let mut bytes = MAGIC.to_vec();
    for word in key.header(batches.len() as u32) {
        bytes.extend_from_slice(&word.to_le_bytes());
    }
    for p in batches.iter().flat_map(|b| &b.pixels) {
        for c in p.to_array() {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    // Write then rename, so that an interrupted write never leaves a torn checkpoint.
    let partial = path.with_extension("rsgt.partial");
    std::fs::write(&partial, &bytes)
        .and_then(|()| std::fs::rename(&partial, path))
        .map_err(|e| Error::Io(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use lab::progress::Silent;
    use lab::scenes::with_resolution;

    /// Computed once, then reused bit for bit; a file of another key (here: a truncated one) is
    /// recomputed, not trusted; one batch is refused.
    #[test]
    fn the_cache_computes_once_then_reuses() {
        let dir = std::env::temp_dir().join(format!("reshift-truth-{}", std::process::id()));
        let scene = with_resolution(Scene::builtin("slab").unwrap(), Some((6, 4)));
        let key = TruthKey {
            scene: "slab".into(),
            width: 6,
            height: 4,
            frame: 1,
            batches: 3,
            spp_per_batch: 2,
        };
        let first = obtain(&dir, &scene, &key, &mut Silent).unwrap();
        assert!(first.is_complete() && !first.cached);
        assert_ne!(first.batches[0], first.batches[1], "independent batches");
        let again = obtain(&dir, &scene, &key, &mut Silent).unwrap();
        assert!(again.cached);
        assert_eq!(again.batches, first.batches);
        let bytes = std::fs::read(&first.path).unwrap();
        std::fs::write(&first.path, &bytes[..bytes.len() - 4]).unwrap();
        let redone = obtain(&dir, &scene, &key, &mut Silent).unwrap();
        assert!(!redone.cached);
        assert_eq!(redone.batches, first.batches, "a function of the seeds");
        let one = TruthKey { batches: 1, ..key };
        assert!(matches!(
            obtain(&dir, &scene, &one, &mut Silent),
            Err(Error::Invalid(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
