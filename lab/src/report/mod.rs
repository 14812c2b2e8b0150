//! What a comparison writes ([`write`]; its folder and text files through [`crate::output`]):
//! the comparison tables as Markdown and CSV with their intervals ([`tables`]), `results.json` as
//! typed structs ([`results`]), the reference and per-method images and error maps
//! ([`images`]), plots ([`plots`]), the inset figure ([`figure`]), the trajectory videos
//! ([`video`]) and the self-contained `report.html` ([`html`]).

mod comparison;
pub mod figure;
pub mod html;
pub mod images;
pub mod plots;
pub mod results;
pub mod tables;
pub mod video;

pub use comparison::{Written, write};
