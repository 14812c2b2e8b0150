//! Errors for user input (scene files, meshes, checkpoints, command-line values): the one
//! [`InputError`] of the workspace, defined beside the mesh loaders in `geometry::error`.

pub use geometry::error::{InputError, MAX_MESSAGE_CHARS, one_line};
