//! Placeholder: replaced by the spatiotemporal variance-guided filter.
use super::{DenoiseError, Guide};
use crate::backend::Backend;
use crate::image::Image;

#[derive(Clone, Debug, Default)]
pub struct Params {}

pub fn denoise_on(
    _backend: &Backend,
    _guides: &[Guide],
    _frames: &[Image],
    _params: &Params,
) -> Result<Image, DenoiseError> {
    Err(DenoiseError::Unavailable("SVGF: not yet".into()))
}
