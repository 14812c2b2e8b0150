//! The reference of a comparison and its cache. A reference is `sss::integrator::reference`
//! (the path tracer in independent batches) at the measured frame, with a seed no replica uses
//! ([`REFERENCE_SEED`]). The policy ([`obtain`]): a checkpoint the user names is checked and
//! used; otherwise the cache entry named by [`ReferenceKey::file_name`] is reused when complete,
//! resumed when partial, and computed otherwise, with checkpoints ([`accumulate`]) so that an
//! interrupted reference resumes next time.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use engine::Image;
use glam::DVec3;
use sss::InputError;
use sss::integrator::pt::PtSettings;
use sss::integrator::{Reference, ReferenceConfig, Shard};
use sss::scene::{GBuffer, Scene};

use crate::error::Error;
use crate::output::{file_stem, output_dir};
use crate::progress::Progress;

/// Seed of the reference's batches (ASCII "REFERENC"); replicas use seeds `0..K`.
pub const REFERENCE_SEED: u64 = 0x5245_4645_5245_4E43;

/// Checkpoints are written at least this often while a reference renders.
pub const CHECKPOINT_EVERY: Duration = Duration::from_secs(30);

/// Where the reference of a comparison comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum ReferenceSource {
    /// A checkpoint written by `reshift reference`, checked against the comparison.
    File(PathBuf),
    /// The cache folder `dir`, for a reference of `spp` samples per pixel in batches of
    /// `batch_spp` (`spp` a multiple ≥ 2× of `batch_spp`: the standard error needs 2 batches).
    Cache {
        dir: PathBuf,
        spp: u32,
        batch_spp: u32,
    },
}

/// A reference ready for a comparison.
pub struct Obtained {
    pub reference: Reference,
    /// The checkpoint it was read from or saved to.
    pub path: PathBuf,
    /// Whether it existed (a named file or a complete cache entry) rather than being computed.
    pub cached: bool,
}

/// What a results file records of an obtained reference, without its pixels: its frame, its
/// samples per pixel in whole batches, where it was read from or saved to and whether it existed.
#[derive(Clone, Debug, PartialEq)]
pub struct Provenance {
    pub frame: u32,
    pub spp: u64,
    pub batches: u32,
    pub path: PathBuf,
    pub cached: bool,
}

impl Obtained {
    pub fn provenance(&self) -> Provenance {
        let r = &self.reference;
        Provenance {
            frame: r.config.frame,
            spp: r.batches_done() as u64 * r.config.spp_per_batch as u64,
            batches: r.batches_done(),
            path: self.path.clone(),
            cached: self.cached,
        }
    }
}

/// The version of the transport model a cached reference was computed with. Bump it whenever the
/// reference's estimate changes (the BSSRDF, the path tracer, the scenes' defaults: the `pt` rows
/// of `lab/tests/pinned_output.rs` change), so that no stale cache file is ever reused.
/// 2: the BSSRDF's Fresnel transmittance uses the material's `ior`.
pub const MODEL_VERSION: u32 = 2;

/// What identifies a cached reference.
#[derive(Clone, Debug, PartialEq)]
pub struct ReferenceKey {
    /// The built-in scene name, or `file-<stem>-<hash of the file's text>`.
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub frame: u32,
    pub spp_per_batch: u32,
    pub batches: u32,
}

impl ReferenceKey {
    /// Total samples per pixel.
    pub fn spp(&self) -> u64 {
        self.spp_per_batch as u64 * self.batches as u64
    }

    /// `ref-v<MODEL_VERSION>-<scene>-<W>x<H>-f<frame>-<batches>x<spp_per_batch>spp.rsref`.
    pub fn file_name(&self) -> String {
        format!(
            "ref-v{MODEL_VERSION}-{}-{}x{}-f{}-{}x{}spp.rsref",
            self.scene, self.width, self.height, self.frame, self.batches, self.spp_per_batch
        )
    }

    /// The reference configuration of this key (default path-tracer settings).
    pub fn config(&self, scene_name: &str) -> ReferenceConfig {
        ReferenceConfig {
            scene: scene_name.to_string(),
            frame: self.frame,
            seed: REFERENCE_SEED,
            spp_per_batch: self.spp_per_batch,
            batches: self.batches,
            settings: PtSettings::default(),
        }
    }

    /// An empty (unsharded) reference for this key.
    pub fn empty(&self, scene_name: &str) -> Result<Reference, InputError> {
        Reference::new(
            self.config(scene_name),
            self.width,
            self.height,
            Shard::WHOLE,
        )
    }
}

/// The cache file of `key` under `cache_dir`.
pub fn cache_path(cache_dir: &Path, key: &ReferenceKey) -> PathBuf {
    cache_dir.join(key.file_name())
}

/// The reference of `scene` (cache key `scene_key`) at `frame` and the camera's resolution,
/// from `source` (see the module documentation). Computing one reports progress as the phase
/// `reference`; a stop request leaves a checkpoint and returns [`Error::Interrupted`].
pub fn obtain(
    source: &ReferenceSource,
    scene: &Scene,
    scene_key: &str,
    frame: u32,
    progress: &mut dyn Progress,
) -> Result<Obtained, Error> {
    let (width, height) = (scene.camera.width(), scene.camera.height());
    let (dir, spp, batch) = match source {
        ReferenceSource::File(path) => {
            let reference = Reference::load(path)?;
            check_reference(&reference, path, width, height, frame)?;
            if reference.config.scene != scene.name {
                return Err(Error::Invalid(format!(
                    "{}: a reference of scene {:?}, not {:?}",
                    path.display(),
                    reference.config.scene,
                    scene.name
                )));
            }
            return Ok(Obtained {
                reference,
                path: path.clone(),
                cached: true,
            });
        }
        ReferenceSource::Cache {
            dir,
            spp,
            batch_spp,
        } => (dir, *spp, *batch_spp),
    };
    if batch == 0 || spp < 2 * batch || !spp.is_multiple_of(batch) {
        return Err(Error::Invalid(format!(
            "a reference of {spp} spp in batches of {batch} spp: need a multiple ≥ 2× of the batch"
        )));
    }
    let key = ReferenceKey {
        scene: file_stem(scene_key),
        width,
        height,
        frame,
        spp_per_batch: batch,
        batches: spp / batch,
    };
    let path = cache_path(&output_dir(dir)?, &key);
    let mut reference = match Reference::load(&path) {
        Ok(r) if r.config == key.config(&scene.name) && (r.width, r.height) == (width, height) => r,
        _ => key.empty(&scene.name)?,
    };
    if reference.is_complete() {
        return Ok(Obtained {
            reference,
            path,
            cached: true,
        });
    }
    let what = format!("reference frame {frame}");
    accumulate(&mut reference, scene, &path, &what, None, progress)?;
    if !reference.is_complete() {
        return Err(Error::Interrupted(format!(
            "interrupted while computing the reference; checkpoint {} resumes next time",
            path.display()
        )));
    }
    Ok(Obtained {
        reference,
        path,
        cached: false,
    })
}

/// Renders the remaining batches of `reference` (at most `max_batches`) one at a time as the
/// progress phase `what`, saving a checkpoint to `path` every [`CHECKPOINT_EVERY`], after a stop
/// request (once the current batch is done) and at the end.
pub fn accumulate(
    reference: &mut Reference,
    scene: &Scene,
    path: &Path,
    what: &str,
    max_batches: Option<u32>,
    progress: &mut dyn Progress,
) -> Result<(), Error> {
    let scene = &*scene.at_frame(reference.config.frame);
    let gbuffer = GBuffer::render(scene, reference.config.frame);
    progress.begin(
        what,
        (reference.end - reference.start) as u64,
        reference.batches_done() as u64,
    );
    let mut saved = Instant::now();
    let stop = reference
        .next
        .saturating_add(max_batches.unwrap_or(u32::MAX))
        .min(reference.end);
    let save = |r: &Reference| {
        r.save(path)
            .map_err(|e| Error::Io(format!("{}: {e}", path.display())))
    };
    while reference.next < stop && !progress.stop_requested() {
        reference.run(scene, &gbuffer, 1);
        progress.step();
        if saved.elapsed() > CHECKPOINT_EVERY {
            save(reference)?;
            saved = Instant::now();
        }
    }
    progress.end();
    save(reference)
}

/// Checks that `reference` (read from `path`) is of `width × height` at `frame`: a reference
/// of another size or frame is an input error, not a silent mismatch.
pub fn check_reference(
    reference: &Reference,
    path: &Path,
    width: u32,
    height: u32,
    frame: u32,
) -> Result<(), InputError> {
    if (reference.width, reference.height) != (width, height) {
        return Err(InputError::new(
            path,
            "width×height",
            format!("{}×{}", reference.width, reference.height),
            format!("the comparison renders {width}×{height}"),
        ));
    }
    if reference.config.frame != frame {
        return Err(InputError::new(
            path,
            "frame",
            reference.config.frame.to_string(),
            format!("the comparison measures frame {frame}"),
        ));
    }
    if reference.batches_done() < 2 {
        return Err(InputError::new(
            path,
            "batches",
            reference.batches_done().to_string(),
            "a reference needs at least 2 finished batches (for its standard error)",
        ));
    }
    Ok(())
}

/// What metrics need of a reference at one frame: the per-pixel mean and its standard error
/// over the reference's independent batches ([`crate::metrics`]).
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReference {
    pub frame: u32,
    pub mean: Vec<DVec3>,
    pub std_err: Vec<DVec3>,
    /// Finished batches (≥ 2).
    pub batches: u32,
    pub spp: u64,
}

impl FrameReference {
    pub fn new(reference: &Reference) -> FrameReference {
        FrameReference {
            frame: reference.config.frame,
            mean: reference.mean(),
            std_err: reference.std_err(),
            batches: reference.batches_done(),
            spp: reference.batches_done() as u64 * reference.config.spp_per_batch as u64,
        }
    }
}

/// The per-pixel reference mean as a linear RGB image.
pub fn mean_image(reference: &Reference) -> Image {
    Image {
        width: reference.width,
        height: reference.height,
        pixels: reference.mean().iter().map(|p| p.as_vec3()).collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::Silent;

    #[test]
    fn cache_key_names_every_field() {
        let key = ReferenceKey {
            scene: "bumpy".into(),
            width: 64,
            height: 48,
            frame: 15,
            spp_per_batch: 16,
            batches: 32,
        };
        assert_eq!(
            key.file_name(),
            format!("ref-v{MODEL_VERSION}-bumpy-64x48-f15-32x16spp.rsref")
        );
        assert_eq!(key.spp(), 512);
    }

    /// The cache computes a reference once, then reuses it bit for bit; a batch size that does
    /// not divide the spp is refused.
    #[test]
    fn the_cache_computes_once_then_reuses() {
        let dir = std::env::temp_dir().join(format!("reshift-refcache-{}", std::process::id()));
        let scene = crate::scenes::with_resolution(Scene::builtin("slab").unwrap(), Some((6, 4)));
        let source = ReferenceSource::Cache {
            dir: dir.clone(),
            spp: 4,
            batch_spp: 2,
        };
        let first = obtain(&source, &scene, "slab", 1, &mut Silent).unwrap();
        let again = obtain(&source, &scene, "slab", 1, &mut Silent).unwrap();
        assert!(!first.cached && again.cached);
        assert_eq!(first.path, again.path);
        assert_eq!(first.reference.mean(), again.reference.mean());
        let odd = ReferenceSource::Cache {
            dir: dir.clone(),
            spp: 5,
            batch_spp: 2,
        };
        assert!(matches!(
            obtain(&odd, &scene, "slab", 1, &mut Silent),
            Err(Error::Invalid(_))
        ));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
