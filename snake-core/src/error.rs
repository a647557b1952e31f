//! The one error type of the crate.

use std::ffi::CStr;

/// Everything that can go wrong in snake-core.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A caller-supplied value is out of range, not finite or of the wrong size.
    #[error("invalid argument: {0}")]
    InvalidArgument(Invalid),
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
            Error::InvalidArgument(m) => m.to_string(),
            other => other.to_string(),
        }
    }
}

/// What is invalid: the message, and the key path of the configuration value it is about when it
/// is about one (`action.steering`), kept apart so that a caller nesting the configuration (a run's
/// `env` table) prefixes the path ([`Invalid::under`]) instead of taking the message apart. Reads
/// as the message (`&str`): `key: detail`, or the detail alone.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Invalid {
    text: String,
    key: Option<String>,
    detail: String,
}

impl Invalid {
    /// A message about no key in particular.
    pub fn new(message: impl Into<String>) -> Self {
        let text = one_line(message.into());
        Invalid {
            detail: text.clone(),
            text,
            key: None,
        }
    }

    /// A message about the value at `key` (a dotted path): `detail` says what is wrong with it.
    pub fn at(key: impl Into<String>, detail: impl Into<String>) -> Self {
        let (key, detail) = (key.into(), one_line(detail.into()));
        Invalid {
            text: one_line(format!("{key}: {detail}")),
            key: Some(key),
            detail,
        }
    }

    /// The key path it is about, if any.
    pub fn key(&self) -> Option<&str> {
        self.key.as_deref()
    }

    /// What is wrong, without the key path.
    pub fn detail(&self) -> &str {
        &self.detail
    }

    /// The same error for a configuration nested at `prefix`: the key path `prefix.key`, or for an
    /// error about no key, the key `prefix` itself (an empty prefix changes nothing).
    pub fn under(self, prefix: &str) -> Self {
        if prefix.is_empty() {
            return self;
        }
        match &self.key {
            Some(key) => Invalid::at(format!("{prefix}.{key}"), self.detail),
            None => Invalid::at(prefix, self.text),
        }
    }
}

impl std::ops::Deref for Invalid {
    type Target = str;
    fn deref(&self) -> &str {
        &self.text
    }
}

impl std::fmt::Display for Invalid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// An `InvalidArgument` error from anything printable, as one line (see [`one_line`]).
pub(crate) fn invalid(message: impl Into<String>) -> Error {
    Error::InvalidArgument(Invalid::new(message))
}

/// An `InvalidArgument` error about the value at the key path `key`: `detail` says what is wrong.
pub(crate) fn invalid_at(key: impl Into<String>, detail: impl Into<String>) -> Error {
    Error::InvalidArgument(Invalid::at(key, detail))
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
    let message = short_numbers(message);
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

/// A number for a message, short whatever its size: `3600`, `0.05`, `1e300`, `-1e-9`, `NaN` (Rust's
/// `{}` writes 1e300 as 301 digits).
pub fn short(x: f64) -> String {
    if !x.is_finite() || x == 0.0 || (1e-4..1e15).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Most digits of a number written out in a message: Rust's `{}` writes 1e300 with 301 digits and
/// 1e-300 with 300 zeros, which a message would then cut in the middle of.
const MAX_NUMBER_DIGITS: usize = 20;

/// `message` with every number of more than [`MAX_NUMBER_DIGITS`] digits written short, as
/// [`short`] writes it (`1e300`, `1e-300`): the rule for every error line, so that no
/// message needs to remember it.
fn short_numbers(message: String) -> String {
    let bytes = message.as_bytes();
    let digits_from = |i: usize| bytes[i..].iter().take_while(|b| b.is_ascii_digit()).count();
    let mut out = String::with_capacity(message.len());
    let mut copied = 0;
    let mut i = 0;
    while i < bytes.len() {
        let starts_number = bytes[i].is_ascii_digit() && (i == 0 || !bytes[i - 1].is_ascii_digit());
        if !starts_number {
            i += 1;
            continue;
        }
        let whole = digits_from(i);
        let mut end = i + whole;
        let mut count = whole;
        if end + 1 < bytes.len() && bytes[end] == b'.' && bytes[end + 1].is_ascii_digit() {
            let fraction = digits_from(end + 1);
            count += fraction;
            end += 1 + fraction;
        }
        if count > MAX_NUMBER_DIGITS {
            if let Ok(x) = message[i..end].parse::<f64>() {
                out.push_str(&message[copied..i]);
                out.push_str(&short(x));
                copied = end;
            }
        }
        i = end;
    }
    if copied == 0 {
        return message;
    }
    out.push_str(&message[copied..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn long_numbers_are_written_short_and_others_kept() {
        let huge = format!("must be in [0, 100], got {}", 1e300);
        assert_eq!(capped(huge), "must be in [0, 100], got 1e300");
        let tiny = format!("got {} and -{}", 1e-300, 2.5e-250);
        assert_eq!(capped(tiny), "got 1e-300 and -2.5e-250");
        let plain = "step 864001 of 864000, 0.0041666666666666666 s, v1.2.3".to_owned();
        assert_eq!(capped(plain.clone()), plain);
        // A number cut by the cap would be unreadable: it is short before the cap.
        let long = format!("{}{}", "x".repeat(590), 1e300);
        assert!(capped(long).ends_with("1e300"));
    }
}
