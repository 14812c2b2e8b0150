//! Placeholder: replaced by the Intel Open Image Denoise stage.
use super::{DenoiseError, Guide};
use crate::image::Image;

pub fn denoise(_guide: &Guide, _frame: &Image) -> Result<Image, DenoiseError> {
    Err(DenoiseError::Unavailable("OIDN: not yet".into()))
}
