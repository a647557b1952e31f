//! The one error type of the crate.

use std::ffi::CStr;

/// Everything that can go wrong in snake-core.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A caller-supplied value is out of range, not finite or of the wrong size.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
    /// Bullet refused a call (the shim's message is kept).
    #[error("physics engine error ({code}): {message}")]
    Engine {
        /// The shim's status code (`SS_ERR_*`).
        code: i32,
        /// The shim's description of the failure.
        message: String,
    },
    /// The simulation produced a non-finite state (it blew up); the world should be discarded.
    #[error("simulation became non-finite: {0}")]
    NonFinite(String),
}

/// Shorthand for `Result<T, snake_core::Error>`.
pub type Result<T> = std::result::Result<T, Error>;

/// Turns a shim status code into a `Result`, fetching the shim's message on failure.
pub(crate) fn check(code: i32) -> Result<()> {
    if code == bullet_sys::SS_OK as i32 {
        return Ok(());
    }
    // SAFETY: ss_last_error returns a NUL-terminated thread-local string that lives until the next
    // failing call on this thread; it is copied out immediately.
    let message = unsafe { CStr::from_ptr(bullet_sys::ss_last_error()) }
        .to_string_lossy()
        .into_owned();
    Err(Error::Engine { code, message })
}

impl Error {
    /// The message without the "invalid argument: " of its kind, for an error wrapped in context
    /// (`file: key: message`).
    pub fn message(&self) -> String {
        match self {
            Error::InvalidArgument(m) => m.clone(),
            other => other.to_string(),
        }
    }
}

/// An `InvalidArgument` error from anything printable, as one line (see [`one_line`]).
pub(crate) fn invalid(message: impl Into<String>) -> Error {
    Error::InvalidArgument(one_line(message.into()))
}

/// A message as one line, whatever the user's files and values hold: control characters (a newline
/// inside an XML attribute, a YAML key or a model's metadata, say) are written escaped, as Rust
/// writes them. Every error of snake-core and snake-rl that quotes a user's input goes through it.
///
/// The line is at most [`MAX_ERROR_CHARS`] characters: a longer one
/// (a 1 MB link name quoted) keeps its start and end with ` [...] ` between them.
pub fn one_line(message: String) -> String {
    let message = if message.chars().any(char::is_control) {
        message
            .chars()
            .map(|c| {
                if c.is_control() {
                    c.escape_default().to_string()
                } else {
                    c.to_string()
                }
            })
            .collect()
    } else {
        message
    };
    capped(message)
}

/// Longest error message shown, characters: a message that quotes a user's value (a 1 MB link name)
/// is cut in its middle to this length, keeping the start (the file and key) and the end (what was
/// expected). Long enough for the longest list of allowed keys we print.
pub const MAX_ERROR_CHARS: usize = 600;

/// `message` cut in its middle to at most `MAX_ERROR_CHARS` characters (the Python CLI cuts its
/// lines with this too, through `snakesim._core.capped_message`).
pub fn capped(message: String) -> String {
    let count = message.chars().count();
    if count <= MAX_ERROR_CHARS {
        return message;
    }
    const CUT: &str = " [...] ";
    let tail = MAX_ERROR_CHARS / 3;
    let head = MAX_ERROR_CHARS - tail - CUT.len();
    let start: String = message.chars().take(head).collect();
    let end: String = message.chars().skip(count - tail).collect();
    format!("{start}{CUT}{end}")
}
