//! [`Error`]: why a lab job (a comparison, an experiment, a reference) stopped. Every variant
//! prints as one line that names the file, method or setting at fault.

use std::fmt;

use engine::PipelineError;
use engine::image::WriteError;
use sss::InputError;

use methods::MethodError;

#[derive(Debug)]
pub enum Error {
    /// A scene, reference or other input file, or a value read from one.
    Input(InputError),
    /// A method specification.
    Method(MethodError),
    /// A run that failed on its backend.
    Pipeline(PipelineError),
    /// An image that could not be written.
    Image(WriteError),
    /// A file or folder that could not be written (the message names it).
    Io(String),
    /// A plan that cannot run as given.
    Invalid(String),
    /// The caller asked to stop ([`crate::progress::Progress::stop_requested`]); the message
    /// says what was kept.
    Interrupted(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input(e) => e.fmt(f),
            Error::Method(e) => e.fmt(f),
            Error::Pipeline(e) => e.fmt(f),
            Error::Image(e) => e.fmt(f),
            Error::Io(m) | Error::Invalid(m) | Error::Interrupted(m) => f.write_str(m),
        }
    }
}

impl std::error::Error for Error {}

macro_rules! from_error {
    ($($t:ty => $variant:ident),*) => {$(
        impl From<$t> for Error {
            fn from(e: $t) -> Self {
                Error::$variant(e)
            }
        }
    )*};
}

from_error!(
    InputError => Input,
    MethodError => Method,
    PipelineError => Pipeline,
    WriteError => Image
);
