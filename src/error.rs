//! Errors raised where input enters photonwave: files, scene descriptions, settings.
//!
//! Every variant names what the user can fix: the file, the line or the setting's field.

use std::fmt;
use std::path::{Path, PathBuf};

/// Everything that can go wrong before or while rendering, caused by input.
#[derive(Debug)]
// Each variant's doc names and explains its fields.
#[allow(missing_docs)]
pub enum Error {
    /// The file at `path` could not be read at all; `message` says why.
    Io { path: PathBuf, message: String },
    /// The file at `path` was read but its content is wrong at `line` (1-based; 0 when
    /// unknown), as `message` says.
    Parse { path: PathBuf, line: usize, message: String },
    /// The scene as a whole cannot be rendered (no light, zero-area emitter, …): `message`.
    Scene { message: String },
    /// A setting has a value that makes no sense; `field` is its name as the user wrote it,
    /// `message` what is wrong.
    Setting { field: String, message: String },
    /// Writing the output file at `path` failed; `message` says why.
    Output { path: PathBuf, message: String },
}

/// The longest parse message kept whole, in bytes.
pub const MAX_MESSAGE: usize = 400;

/// `message` cut at a character boundary below [`MAX_MESSAGE`] bytes, with "…" where it was cut.
fn shortened(mut message: String) -> String {
    if message.len() > MAX_MESSAGE {
        let mut end = MAX_MESSAGE;
        while !message.is_char_boundary(end) {
            end -= 1;
        }
        message.truncate(end);
        message.push('…');
    }
    message
}

impl Error {
    /// An I/O error on `path`.
    pub fn io(path: &Path, err: impl fmt::Display) -> Self {
        Error::Io { path: path.to_path_buf(), message: err.to_string() }
    }
    /// A parse error at `line` (1-based) of `path`. A message that quotes a long line of the
    /// file is cut to [`MAX_MESSAGE`] bytes: the file and line say where the rest is.
    pub fn parse(path: &Path, line: usize, message: impl Into<String>) -> Self {
        Error::Parse { path: path.to_path_buf(), line, message: shortened(message.into()) }
    }
    /// A scene-level error.
    pub fn scene(message: impl Into<String>) -> Self {
        Error::Scene { message: message.into() }
    }
    /// A bad setting.
    pub fn setting(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::Setting { field: field.into(), message: message.into() }
    }
    /// A failure while writing `path`.
    pub fn output(path: &Path, err: impl fmt::Display) -> Self {
        Error::Output { path: path.to_path_buf(), message: err.to_string() }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Io { path, message } => write!(f, "{}: cannot read: {message}", path.display()),
            Error::Parse { path, line: 0, message } => write!(f, "{}: {message}", path.display()),
            Error::Parse { path, line, message } => {
                write!(f, "{}:{line}: {message}", path.display())
            }
            Error::Scene { message } => write!(f, "scene error: {message}"),
            Error::Setting { field, message } => write!(f, "setting `{field}`: {message}"),
            Error::Output { path, message } => {
                write!(f, "{}: cannot write: {message}", path.display())
            }
        }
    }
}

impl std::error::Error for Error {}

/// Shorthand used across the crate.
pub type Result<T> = std::result::Result<T, Error>;
