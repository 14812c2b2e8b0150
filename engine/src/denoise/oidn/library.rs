//! Finding and loading Intel Open Image Denoise (OIDN ≥ 2.0) at run time, like the Vulkan
//! loader: no link-time dependency, so the engine builds and runs where OIDN is not installed.
//!
//! The library is looked for, in order, in `$OIDN_DIR` (the directory or its `lib/`), on the
//! system library path (`dlopen("libOpenImageDenoise.so.2")`) and in the `pyoidn` Python
//! package (`python3 -m pip install pyoidn` ships it). It is loaded once per process
//! ([`shared`]), with one CPU device kept for the process's life.
//!
//! Only the entry points the denoiser calls are declared, with the signatures and enum values of
//! OIDN 2.x's `include/OpenImageDenoise/oidn.h`.

use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::ptr;
use std::sync::{Mutex, OnceLock};

use glam::Vec3;

use crate::denoise::{DenoiseError, Denoiser};

/// The library's file name (OIDN 2.x's soname).
pub const SONAME: &str = "libOpenImageDenoise.so.2";
/// The directory holding [`SONAME`] (or a `lib/` with it), looked in first.
pub const DIR_ENV: &str = "OIDN_DIR";
/// The oldest version accepted, as OIDN encodes it (`major·10000 + minor·100 + patch`).
const MIN_VERSION: c_int = 20000;
const INSTALL: &str = "install it with `python3 -m pip install pyoidn`, or set OIDN_DIR to the \
                       directory holding libOpenImageDenoise.so.2";

// oidn.h: `OIDNDevice`, `OIDNFilter` are opaque handles; `OIDNDeviceType`, `OIDNFormat` and
// `OIDNError` C enums (int-sized).
type Device = *mut c_void;
type Filter = *mut c_void;
const OIDN_DEVICE_TYPE_CPU: c_int = 1;
const OIDN_FORMAT_FLOAT3: c_int = 3;
const OIDN_ERROR_NONE: c_int = 0;

// A float3 image is read as packed `f32` triples.
const _: () = assert!(std::mem::size_of::<Vec3>() == 3 * std::mem::size_of::<f32>());

/// A place where the library may be.
#[derive(Clone, Debug, PartialEq)]
pub enum Place {
    /// A file: skipped when absent; when present it must be OIDN ≥ 2.0, or loading fails there.
    File(PathBuf),
    /// `dlopen(SONAME)`: `LD_LIBRARY_PATH`, then the system's library cache and directories.
    System,
    /// A place not looked in, and why (`OIDN_DIR unset`): named in the not-found message.
    Skipped(String),
}

impl Place {
    fn describe(&self) -> String {
        match self {
            Place::File(path) => path.display().to_string(),
            Place::System => format!("the system library path ({SONAME})"),
            Place::Skipped(why) => format!("[{why}]"),
        }
    }
}

/// `dir/SONAME` and `dir/lib/SONAME`.
pub fn dir_places(dir: &Path) -> [Place; 2] {
    [
        Place::File(dir.join(SONAME)),
        Place::File(dir.join("lib").join(SONAME)),
    ]
}

/// The search order: `oidn_dir` (from [`DIR_ENV`]), the system library path, then the library
/// inside the `pyoidn` package directory.
pub fn places(oidn_dir: Option<&Path>, pyoidn: Option<&Path>) -> Vec<Place> {
    let mut places = Vec::new();
    match oidn_dir {
        Some(dir) => places.extend(dir_places(dir)),
        None => places.push(Place::Skipped(format!("{DIR_ENV} unset"))),
    }
    places.push(Place::System);
    places.push(match pyoidn {
        Some(package) => Place::File(package.join("oidn").join("lib").join(SONAME)),
        None => Place::Skipped("no pyoidn package for python3".into()),
    });
    places
}

/// The `pyoidn` package's directory as `python3` resolves it, without importing the package
/// (`importlib.util.find_spec` locates a top-level package without running it); `None` without
/// `python3` or the package.
pub fn pyoidn_dir() -> Option<PathBuf> {
    const FIND: &str = "import importlib.util as u\n\
                        s = u.find_spec('pyoidn')\n\
                        print(s.submodule_search_locations[0] \
                        if s and s.submodule_search_locations else '')";
    let output = Command::new("python3").args(["-c", FIND]).output().ok()?;
    let dir = String::from_utf8(output.stdout).ok()?;
    let dir = dir.trim();
    (output.status.success() && !dir.is_empty()).then(|| PathBuf::from(dir))
}

/// `oidnSetSharedFilterImage(filter, name, devPtr, format, width, height, byteOffset,
/// pixelByteStride, rowByteStride)`.
type SetSharedFilterImage = unsafe extern "C" fn(
    Filter,
    *const c_char,
    *mut c_void,
    c_int,
    usize,
    usize,
    usize,
    usize,
    usize,
);

/// The entry points used, as declared in `oidn.h` (2.x names: `oidnGetDeviceInt`,
/// `oidnSetFilterBool`; 1.x had `oidnGetDevice1i`, `oidnSetFilter1b`).
struct Api {
    new_device: unsafe extern "C" fn(c_int) -> Device,
    commit_device: unsafe extern "C" fn(Device),
    release_device: unsafe extern "C" fn(Device),
    get_device_int: unsafe extern "C" fn(Device, *const c_char) -> c_int,
    get_device_error: unsafe extern "C" fn(Device, *mut *const c_char) -> c_int,
    new_filter: unsafe extern "C" fn(Device, *const c_char) -> Filter,
    set_shared_filter_image: SetSharedFilterImage,
    set_filter_bool: unsafe extern "C" fn(Filter, *const c_char, bool),
    commit_filter: unsafe extern "C" fn(Filter),
    execute_filter: unsafe extern "C" fn(Filter),
    release_filter: unsafe extern "C" fn(Filter),
}

/// A loaded OIDN with its committed CPU device.
pub struct Oidn {
    /// Where the library was loaded from.
    pub place: String,
    /// OIDN's version, `major·10000 + minor·100 + patch`.
    pub version: i32,
    api: Api,
    device: Device,
    /// The filters kept for the next calls, the most recently used last (at most
    /// [`FILTERS_KEPT`]): creating and first committing one loads and lays out the network's
    /// weights for its image size, which OIDN's documentation asks callers not to repeat for
    /// every image.
    filters: Mutex<Vec<KeptFilter>>,
    /// Keeps the library mapped while `api`'s pointers are in use.
    _library: libloading::Library,
}

/// How many filters [`Oidn`] keeps (a stream denoises at one size with one set of inputs; a
/// comparison may alternate two).
pub(super) const FILTERS_KEPT: usize = 2;

/// A filter kept by [`Oidn`], and what it was set up for: its kind, image size, input names and
/// options. Its images are set again before every commit.
struct KeptFilter {
    setup: FilterSetup,
    filter: Filter,
}

#[derive(Clone, Debug, PartialEq)]
struct FilterSetup {
    kind: CString,
    size: (u32, u32),
    inputs: Vec<CString>,
    options: Vec<(CString, bool)>,
}

// SAFETY: oidn.h's API is thread-safe ("All API calls are thread-safe, but operations that use
// the same device will be serialized", OIDN API documentation); the device handle is only passed
// to it. Errors are kept per thread, and each call of `run` queries them on its own thread.
unsafe impl Send for Oidn {}
unsafe impl Sync for Oidn {}

/// The process's OIDN, loaded on first use from [`places`] (`$OIDN_DIR`, system, pyoidn).
pub fn shared() -> Result<&'static Oidn, DenoiseError> {
    static SHARED: OnceLock<Result<Oidn, DenoiseError>> = OnceLock::new();
    SHARED
        .get_or_init(|| {
            let dir = std::env::var_os(DIR_ENV).map(PathBuf::from);
            let places = places(dir.as_deref(), pyoidn_dir().as_deref());
            Oidn::load_from(&places)
        })
        .as_ref()
        .map_err(Clone::clone)
}

fn unusable(why: String) -> DenoiseError {
    DenoiseError::Unavailable(format!("OIDN: {why}; {INSTALL}"))
}

impl Oidn {
    /// Loads the first of `places` that exists. An absent place is skipped; a present one that
    /// is not a loadable OIDN ≥ 2.0 with a CPU device ends the search with an error naming it.
    pub fn load_from(places: &[Place]) -> Result<Oidn, DenoiseError> {
        for place in places {
            let (library, described) = match place {
                Place::Skipped(_) => continue,
                Place::File(path) if !path.exists() => continue,
                Place::File(path) => {
                    // SAFETY: loading runs the library's initialisers; a file at an OIDN place
                    // is taken to be a shared library (a non-ELF file is refused by dlopen).
                    match unsafe { libloading::Library::new(path) } {
                        Ok(library) => (library, path.display().to_string()),
                        Err(e) => {
                            return Err(unusable(format!(
                                "{} is not a loadable library ({e})",
                                path.display()
                            )));
                        }
                    }
                }
                // SAFETY: as above, for the system's OIDN. A failure means not installed there.
                Place::System => match unsafe { libloading::Library::new(SONAME) } {
                    Ok(library) => (library, format!("{SONAME} on the system library path")),
                    Err(_) => continue,
                },
            };
            return Oidn::open(library, described);
        }
        let looked: Vec<String> = places.iter().map(Place::describe).collect();
        Err(DenoiseError::Unavailable(format!(
            "OIDN ≥ 2.0 ({SONAME}) not found; looked in {}; {INSTALL}",
            looked.join(", ")
        )))
    }

    /// Resolves the entry points of `library` (loaded from `place`), creates and commits a CPU
    /// device and checks its version.
    fn open(library: libloading::Library, place: String) -> Result<Oidn, DenoiseError> {
        fn get<T: Copy>(
            library: &libloading::Library,
            place: &str,
            name: &str,
        ) -> Result<T, DenoiseError> {
            // SAFETY: `T` is the symbol's type as declared in oidn.h (see `Api`).
            unsafe { library.get::<T>(name.as_bytes()) }
                .map(|symbol| *symbol)
                .map_err(|_| unusable(format!("{place} lacks {name} (not OIDN ≥ 2.0)")))
        }
        let api = Api {
            new_device: get(&library, &place, "oidnNewDevice")?,
            commit_device: get(&library, &place, "oidnCommitDevice")?,
            release_device: get(&library, &place, "oidnReleaseDevice")?,
            get_device_int: get(&library, &place, "oidnGetDeviceInt")?,
            get_device_error: get(&library, &place, "oidnGetDeviceError")?,
            new_filter: get(&library, &place, "oidnNewFilter")?,
            set_shared_filter_image: get(&library, &place, "oidnSetSharedFilterImage")?,
            set_filter_bool: get(&library, &place, "oidnSetFilterBool")?,
            commit_filter: get(&library, &place, "oidnCommitFilter")?,
            execute_filter: get(&library, &place, "oidnExecuteFilter")?,
            release_filter: get(&library, &place, "oidnReleaseFilter")?,
        };
        // SAFETY: entry points of the loaded library, called as oidn.h declares them; a null
        // device is allowed in `oidnGetDeviceError` (it reports why creation failed).
        let device = unsafe { (api.new_device)(OIDN_DEVICE_TYPE_CPU) };
        let mut oidn = Oidn {
            place,
            version: 0,
            api,
            device,
            filters: Mutex::new(Vec::new()),
            _library: library,
        };
        let unusable_device = |e: DenoiseError| unusable(format!("{}: {e}", oidn.place));
        oidn.check("creating a CPU device")
            .map_err(unusable_device)?;
        // SAFETY: `device` is a valid device handle of this library.
        unsafe { (oidn.api.commit_device)(oidn.device) };
        oidn.check("committing the CPU device")
            .map_err(unusable_device)?;
        // SAFETY: as above; "version" is a device parameter of every OIDN ≥ 0.9.
        oidn.version = unsafe { (oidn.api.get_device_int)(oidn.device, c"version".as_ptr()) };
        if oidn.version < MIN_VERSION {
            return Err(unusable(format!(
                "{} is OIDN {}, older than 2.0",
                oidn.place,
                version_string(oidn.version)
            )));
        }
        Ok(oidn)
    }

    /// `major.minor.patch` of the loaded library.
    pub fn version_string(&self) -> String {
        version_string(self.version)
    }

    /// `Err(Failed)` with the device's first pending error (oidn.h: the first unqueried error of
    /// the calling thread, cleared by the query), `Ok` where there is none.
    fn check(&self, doing: &str) -> Result<(), DenoiseError> {
        let mut message: *const c_char = ptr::null();
        // SAFETY: `device` is this library's device handle (or null, which oidn.h allows);
        // `message` receives a string owned by the library, valid until its next call.
        let code = unsafe { (self.api.get_device_error)(self.device, &mut message) };
        if code == OIDN_ERROR_NONE {
            return Ok(());
        }
        let message = if message.is_null() {
            "no message".into()
        } else {
            // SAFETY: a NUL-terminated string of the library, read before any other call.
            unsafe { CStr::from_ptr(message) }.to_string_lossy()
        };
        Err(DenoiseError::Failed {
            denoiser: Denoiser::Oidn,
            reason: format!("{doing}: {message} (OIDN error {code})"),
        })
    }

    /// Runs filter `kind` on `width × height` float3 images shared with the library: `inputs`
    /// by name (`color`, `albedo`, …), boolean `options` (`hdr`, …), the result into `output`.
    /// Errors after committing and executing the filter are the device's ([`DenoiseError::Failed`]).
    pub fn run(
        &self,
        kind: &CStr,
        (width, height): (u32, u32),
        inputs: &[(&CStr, &[Vec3])],
        options: &[(&CStr, bool)],
        output: &mut [Vec3],
    ) -> Result<(), DenoiseError> {
        let n = width as usize * height as usize;
        for (name, image) in inputs {
            if image.len() != n {
                return Err(DenoiseError::Mismatch(format!(
                    "OIDN image {name:?} has {} pixels, not {width}×{height}",
                    image.len()
                )));
            }
        }
        if output.len() != n {
            return Err(DenoiseError::Mismatch(format!(
                "OIDN output has {} pixels, not {width}×{height}",
                output.len()
            )));
        }
        let setup = FilterSetup {
            kind: kind.to_owned(),
            size: (width, height),
            inputs: inputs.iter().map(|(name, _)| (*name).to_owned()).collect(),
            options: options.iter().map(|&(n, v)| (n.to_owned(), v)).collect(),
        };
        // The lock is held through the execution: OIDN serialises a device's work anyway.
        let mut kept = self.filters.lock().unwrap_or_else(|e| e.into_inner());
        let filter = match kept.iter().position(|k| k.setup == setup) {
            Some(i) => kept.remove(i).filter,
            None => self.new_filter(&setup)?,
        };
        /// Releases the filter unless it is kept.
        struct Release<'a>(&'a Oidn, Option<Filter>);
        impl Drop for Release<'_> {
            fn drop(&mut self) {
                if let Some(filter) = self.1 {
                    // SAFETY: a filter created by `oidnNewFilter`, released once.
                    unsafe { (self.0.api.release_filter)(filter) }
                }
            }
        }
        let mut release = Release(self, Some(filter));
        // SAFETY: calls as oidn.h declares them on this library's device. Every image holds
        // `width·height` packed float3 pixels (checked above; strides 0 mean packed) and outlives
        // the execution, which is synchronous; the filter keeps the pointers after `run`
        // returns but reads them only after they are set again, before its next commit. The
        // library only reads the inputs (the `*mut` of its signature is for the output).
        unsafe {
            let images = inputs
                .iter()
                .map(|&(name, image)| (name, image.as_ptr() as *mut c_void))
                .chain([(c"output", output.as_mut_ptr() as *mut c_void)]);
            for (name, pixels) in images {
                (self.api.set_shared_filter_image)(
                    filter,
                    name.as_ptr(),
                    pixels,
                    OIDN_FORMAT_FLOAT3,
                    width as usize,
                    height as usize,
                    0,
                    0,
                    0,
                );
            }
            (self.api.commit_filter)(filter);
            self.check("committing the filter")?;
            (self.api.execute_filter)(filter);
            self.check("executing the filter")?;
        }
        release.1 = None;
        kept.push(KeptFilter { setup, filter });
        if kept.len() > FILTERS_KEPT {
            let oldest = kept.remove(0);
            // SAFETY: a filter created by `oidnNewFilter`, no longer kept, released once.
            unsafe { (self.api.release_filter)(oldest.filter) }
        }
        Ok(())
    }

    /// How many filters are kept now.
    #[cfg(test)]
    pub(super) fn kept_filters(&self) -> usize {
        self.filters.lock().map_or(0, |kept| kept.len())
    }

    /// A new filter of `setup`'s kind with its options set.
    fn new_filter(&self, setup: &FilterSetup) -> Result<Filter, DenoiseError> {
        // SAFETY: calls as oidn.h declares them on this library's device; the strings outlive
        // the calls.
        unsafe {
            let filter = (self.api.new_filter)(self.device, setup.kind.as_ptr());
            if let Err(e) = self.check("creating the filter") {
                if !filter.is_null() {
                    (self.api.release_filter)(filter);
                }
                return Err(e);
            }
            for (name, value) in &setup.options {
                (self.api.set_filter_bool)(filter, name.as_ptr(), *value);
            }
            Ok(filter)
        }
    }
}

impl Drop for Oidn {
    fn drop(&mut self) {
        let kept = std::mem::take(self.filters.get_mut().unwrap_or_else(|e| e.into_inner()));
        for k in kept {
            // SAFETY: filters this library created and kept, released once, before the device.
            unsafe { (self.api.release_filter)(k.filter) }
        }
        if !self.device.is_null() {
            // SAFETY: the device this library created, released once, before the library.
            unsafe { (self.api.release_device)(self.device) }
        }
    }
}

fn version_string(version: c_int) -> String {
    format!(
        "{}.{}.{}",
        version / 10000,
        version / 100 % 100,
        version % 100
    )
}

/// Where OIDN is required to run the tests that need it (set in CI): they fail instead of
/// skipping when it cannot be loaded.
#[cfg(test)]
pub const REQUIRE_ENV: &str = "RESHIFT_REQUIRE_OIDN";

/// The shared OIDN, or `None` after printing why `test` is skipped; panics instead when
/// [`REQUIRE_ENV`]` = 1`.
#[cfg(test)]
pub fn shared_or_skip(test: &str) -> Option<&'static Oidn> {
    match shared() {
        Ok(oidn) => {
            eprintln!("{test}: OIDN {} from {}", oidn.version_string(), oidn.place);
            Some(oidn)
        }
        Err(e) if std::env::var(REQUIRE_ENV).as_deref() == Ok("1") => {
            panic!("{test}: {REQUIRE_ENV}=1 but OIDN is unavailable: {e}")
        }
        Err(e) => {
            eprintln!("{test}: skipped, OIDN unavailable: {e}");
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fresh empty directory for `test` under the system's temporary directory.
    fn empty_dir(test: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("reshift-{test}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn message(e: DenoiseError) -> String {
        let DenoiseError::Unavailable(message) = e else {
            panic!("not Unavailable: {e:?}")
        };
        assert!(!message.contains('\n'), "{message}");
        assert!(message.contains("pip install pyoidn"), "{message}");
        message
    }

    #[test]
    fn the_search_order_is_oidn_dir_system_pyoidn() {
        let (dir, package) = (Path::new("/opt/oidn"), Path::new("/site/pyoidn"));
        assert_eq!(
            places(Some(dir), Some(package)),
            [
                Place::File(dir.join(SONAME)),
                Place::File(dir.join("lib").join(SONAME)),
                Place::System,
                Place::File(package.join("oidn/lib").join(SONAME)),
            ]
        );
        let unset = places(None, None);
        assert!(matches!(
            unset[..],
            [Place::Skipped(_), Place::System, Place::Skipped(_)]
        ));
    }

    /// OIDN_DIR pointing at an empty directory: not found, one line naming both files looked
    /// for and how to install OIDN.
    #[test]
    fn an_empty_oidn_dir_is_not_found() {
        let dir = empty_dir("oidn-empty");
        let e = Oidn::load_from(&dir_places(&dir))
            .err()
            .expect("nothing to load");
        let message = message(e);
        for place in dir_places(&dir) {
            assert!(message.contains(&place.describe()), "{message}");
        }
        std::fs::remove_dir_all(dir).unwrap();
    }

    /// A file at an OIDN place that is not a shared library: one line naming it; the search
    /// stops there (a later place is not tried).
    #[test]
    fn a_fake_library_is_named() {
        let dir = empty_dir("oidn-fake");
        let fake = dir.join(SONAME);
        std::fs::write(&fake, "not a shared library").unwrap();
        let e = Oidn::load_from(&[Place::File(fake.clone()), Place::System])
            .err()
            .expect("a text file is no library");
        let message = message(e);
        assert!(message.contains(&format!("{} is not a loadable library", fake.display())));
        std::fs::remove_dir_all(dir).unwrap();
    }

    /// A real shared library without OIDN's entry points (the C library this process runs on,
    /// found in /proc/self/maps): one line naming the file and the first missing symbol.
    #[test]
    fn a_library_without_oidn_symbols_is_named() {
        let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
        let libc = maps
            .lines()
            .filter_map(|line| line.split_whitespace().nth(5))
            .find(|path| path.contains("/libc.so") || path.contains("/libc-"))
            .expect("a dynamically linked C library");
        let e = Oidn::load_from(&[Place::File(libc.into())])
            .err()
            .expect("libc is not OIDN");
        let message = message(e);
        assert!(
            message.contains(&format!("{libc} lacks oidnNewDevice")),
            "{message}"
        );
    }

    #[test]
    fn versions_read_as_major_minor_patch() {
        assert_eq!(version_string(20501), "2.5.1");
        assert_eq!(version_string(11404), "1.14.4");
    }
}
