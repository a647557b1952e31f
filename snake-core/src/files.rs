//! Reading a user's files, bounded: every reader of a robot, URDF, world, heightfield, targets,
//! config, model or CSV file goes through [`read_bytes`] or [`read_text`], and every YAML or XML text
//! passes [`check_yaml_shape`] or [`check_xml_shape`] before its parser sees it.
//!
//! - Only regular files are read (a link to one is followed). A device (`/dev/zero` grows without
//!   end), a FIFO (blocks until a writer comes, perhaps never) or a socket is refused in one line. The
//!   file is opened without blocking and checked on the open handle, so what is checked is what is
//!   read, and at most `cap + 1` bytes are ever read (a file that grows while read is caught too).
//! - Parsers take time that grows faster than the file with deep nesting (200 KB of nested brackets
//!   took serde's YAML parser 47 s) or many attributes on one XML element (roxmltree's duplicate
//!   check: 200,000 attributes took 67 s); the shape checks refuse such text in linear time, so that
//!   every file within the size caps parses in well under a second.
//! - Errors name the file and the problem, never quote its contents.

use std::collections::BTreeSet;
use std::io::Read;
use std::os::unix::fs::{MetadataExt, OpenOptionsExt};
use std::path::Path;
use std::sync::Mutex;

use crate::error::invalid;
use crate::limits::{MAX_NESTING, MAX_XML_ATTRIBUTES};
use crate::Result;

/// Opens the regular file `path` for reading, if it has at most `cap` bytes, and remembers it as an
/// input; `what` names it in errors (e.g. "robot file"). Refuses a directory, a device, FIFO or socket
/// and a larger file in one line. For a reader that reads a line at a time ([`crate::tables`]); the
/// caller still stops at `cap` bytes, since a file may grow while read.
pub fn open_regular(path: &Path, cap: u64, what: &str) -> Result<std::fs::File> {
    let shown = path.display();
    let cannot = |e: std::io::Error| invalid(format!("{what} {shown}: cannot read: {e}"));
    // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(path)
        .map_err(cannot)?;
    let meta = file.metadata().map_err(cannot)?;
    remember_input(&meta);
    if meta.is_dir() {
        return Err(invalid(format!("{what} {shown}: is a directory")));
    }
    if !meta.is_file() {
        return Err(invalid(format!(
            "{what} {shown}: not a regular file (a device, FIFO or socket); give a file"
        )));
    }
    if meta.len() > cap {
        return Err(too_large(what, path, meta.len(), cap));
    }
    Ok(file)
}

/// Reads at most `cap` bytes of the regular file `path`; `what` names it in errors (e.g. "robot
/// file"). Refuses a device, FIFO or socket and a larger file in one line.
pub fn read_bytes(path: &Path, cap: u64, what: &str) -> Result<Vec<u8>> {
    let file = open_regular(path, cap, what)?;
    let cannot =
        |e: std::io::Error| invalid(format!("{what} {}: cannot read: {e}", path.display()));
    let mut bytes = Vec::with_capacity(file.metadata().map_err(cannot)?.len() as usize);
    file.take(cap + 1).read_to_end(&mut bytes).map_err(cannot)?;
    if bytes.len() as u64 > cap {
        return Err(too_large(what, path, bytes.len() as u64, cap));
    }
    Ok(bytes)
}

/// Every file this process has read through [`read_bytes`]: an output must never replace one of its
/// own run's inputs (`--output` onto the robot file), whatever path names it.
static INPUTS: Mutex<BTreeSet<FileVersion>> = Mutex::new(BTreeSet::new());

/// One version of one file: its device and inode, and its modification time, since a file removed
/// while the process runs frees its inode for a new file.
type FileVersion = (u64, u64, i64, i64);

fn version(meta: &std::fs::Metadata) -> FileVersion {
    (meta.dev(), meta.ino(), meta.mtime(), meta.mtime_nsec())
}

fn remember_input(meta: &std::fs::Metadata) {
    if let Ok(mut inputs) = INPUTS.lock() {
        inputs.insert(version(meta));
    }
}

/// Remembers `path` (after links) as an input of this process: for a reader outside this crate (the
/// Python package's reads of models, statistics and configurations), so that one set holds every file
/// the process reads, whichever language read it. A path that names nothing is ignored.
pub fn remember_input_path(path: &Path) {
    if let Ok(meta) = std::fs::metadata(path) {
        remember_input(&meta);
    }
}

/// Forgets that `path` (after links) was read as an input: for a command that rewrites its own
/// output file after reading its previous text (`snake-cli atlas` keeps the rest of its Markdown).
/// Call it only once the path has been checked against the real inputs.
pub fn forget_input(path: &Path) {
    if let (Ok(meta), Ok(mut inputs)) = (std::fs::metadata(path), INPUTS.lock()) {
        inputs.remove(&version(&meta));
    }
}

/// True when `path` is (after links) a file this process has read as an input.
pub fn is_input(path: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(path) else {
        return false;
    };
    INPUTS
        .lock()
        .map(|inputs| inputs.contains(&version(&meta)))
        .unwrap_or(false)
}

/// [`read_bytes`] for a text file, which must be UTF-8.
pub fn read_text(path: &Path, cap: u64, what: &str) -> Result<String> {
    String::from_utf8(read_bytes(path, cap, what)?).map_err(|e| {
        invalid(format!(
            "{what} {}: not UTF-8 text (byte {} is not)",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

fn too_large(what: &str, path: &Path, len: u64, cap: u64) -> crate::Error {
    invalid(format!(
        "{what} {}: {len} bytes or more, more than the {cap} it may have",
        path.display()
    ))
}

/// Refuses YAML text nested deeper than [`MAX_NESTING`] (flow brackets, block indentation levels and
/// `- ` entries on one line, all counted together); `shown` names it in the error. A linear scan that
/// over-counts rather than under-counts (a bracket inside a plain scalar counts), which no real file
/// comes near.
pub fn check_yaml_shape(text: &str, shown: &str) -> Result<()> {
    let mut indents: Vec<usize> = Vec::new();
    let mut flow = 0usize;
    for (number, line) in text.lines().enumerate() {
        let body = line.trim_start_matches(' ');
        if body.is_empty() || body.starts_with('#') {
            continue;
        }
        let indent = line.len() - body.len();
        if flow == 0 {
            while indents.last().is_some_and(|&top| top > indent) {
                indents.pop();
            }
            if indents.last() != Some(&indent) {
                indents.push(indent);
            }
        }
        let mut dashes = 0;
        let mut rest = body;
        while let Some(after) = rest.strip_prefix("- ") {
            dashes += 1;
            rest = after.trim_start_matches(' ');
        }
        let mut quote: Option<char> = None;
        let mut previous = ' ';
        let mut escaped = false;
        let mut deepest_flow = flow;
        for c in rest.chars() {
            match quote {
                Some('"') if escaped => escaped = false,
                Some('"') if c == '\\' => escaped = true,
                Some(q) if c == q => quote = None,
                Some(_) => {}
                None => match c {
                    '#' if previous.is_whitespace() => break,
                    '"' | '\'' if previous.is_whitespace() || "[{,:".contains(previous) => {
                        quote = Some(c)
                    }
                    '[' | '{' => {
                        flow += 1;
                        deepest_flow = deepest_flow.max(flow);
                    }
                    ']' | '}' => flow = flow.saturating_sub(1),
                    _ => {}
                },
            }
            previous = c;
        }
        if indents.len().saturating_sub(1) + dashes + deepest_flow > MAX_NESTING {
            return Err(invalid(format!(
                "{shown}:{}: nested more than {MAX_NESTING} levels deep",
                number + 1
            )));
        }
    }
    Ok(())
}

/// Refuses XML text with elements nested deeper than [`MAX_NESTING`] or an element with more than
/// [`MAX_XML_ATTRIBUTES`] attributes; `shown` names it in the error. Comments, CDATA, processing
/// instructions and declarations are skipped; the parser that follows checks everything else.
pub fn check_xml_shape(text: &str, shown: &str) -> Result<()> {
    let bytes = text.as_bytes();
    let line_at = |at: usize| bytes[..at].iter().filter(|&&b| b == b'\n').count() + 1;
    let skip_past = |from: usize, end: &[u8]| -> usize {
        bytes[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(bytes.len(), |p| from + p + end.len())
    };
    let mut depth = 0usize;
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &bytes[i..];
        if rest.starts_with(b"<!--") {
            i = skip_past(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_past(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_past(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            i = skip_past(i + 2, b">");
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_past(i + 2, b">");
        } else {
            let start = i;
            let mut attributes = 0usize;
            let mut quote: Option<u8> = None;
            let mut closed_self = false;
            i += 1;
            while i < bytes.len() {
                let b = bytes[i];
                match quote {
                    Some(q) if b == q => quote = None,
                    Some(_) => {}
                    None if b == b'"' || b == b'\'' => quote = Some(b),
                    None if b == b'=' => attributes += 1,
                    None if b == b'>' => {
                        closed_self = bytes[i - 1] == b'/';
                        break;
                    }
                    None => {}
                }
                i += 1;
            }
            i += 1;
            if attributes > MAX_XML_ATTRIBUTES {
                return Err(invalid(format!(
                    "{shown}:{}: an element with more than {MAX_XML_ATTRIBUTES} attributes",
                    line_at(start)
                )));
            }
            if !closed_self {
                depth += 1;
                if depth > MAX_NESTING {
                    return Err(invalid(format!(
                        "{shown}:{}: elements nested more than {MAX_NESTING} levels deep",
                        line_at(start)
                    )));
                }
            }
        }
    }
    Ok(())
}

/// Longest excerpt of a user's value quoted in an error, characters.
const EXCERPT_CHARS: usize = 24;

/// A short, escaped excerpt of a user's value for an error message: at most 24 characters, quoted,
/// control characters escaped, an ellipsis where it was cut; and only of a value that reads as a name
/// or a number ([`is_name_like`]): anything else is named by its length alone. A file that is not
/// ours (a password file handed to `--world` or `--targets`, or named by a hostile model) puts its
/// lines where keys and values are expected, and a line with `$`, `:` or `*` in it is never quoted,
/// not even in part.
pub fn excerpt(value: &str) -> String {
    if !is_name_like(value) {
        return format!("<{} characters, not shown>", value.chars().count());
    }
    let mut chars = value.chars();
    let head: String = chars.by_ref().take(EXCERPT_CHARS).collect();
    let cut = if chars.next().is_some() { "..." } else { "" };
    format!("{head:?}{cut}")
}

/// True for text made of letters, digits, spaces and `_ . , + - /` only: a key, a joint name, a
/// number or a path, as a user writes them.
pub fn is_name_like(text: &str) -> bool {
    text.chars()
        .all(|c| c.is_alphanumeric() || " _.,+-/".contains(c))
}

/// A YAML parser's error as one line that names the file and the place but quotes no more of the
/// file than short excerpts: serde quotes whole values (`invalid type: string "<the whole file>"`),
/// and a text that is not a mapping at all (a file that is not ours, `/etc/passwd` say) is named as
/// such without a word of it. `what` names the expected content, e.g. "a world file".
pub fn yaml_error(shown: &str, what: &str, error: &serde_norway::Error) -> crate::Error {
    let location = error.location().map(|l| (l.line(), l.column()));
    let message = error.to_string();
    let message = message.split(" at line ").next().unwrap_or(&message);
    if message.starts_with("invalid type")
        && message.contains("expected struct")
        && location == Some((1, 1))
    {
        return invalid(format!(
            "{shown}: not {what} (expected a YAML mapping of its keys)"
        ));
    }
    let at = location
        .map(|(line, column)| format!(" at line {line} column {column}"))
        .unwrap_or_default();
    invalid(format!("{shown}: {}{at}", quoted_excerpts(message)))
}

/// The first number of a parsed YAML document that is not finite (`.nan`, `.inf`, `-.inf`; a literal
/// too large for a double, `1e999`, is a string to YAML), as an error naming its key path
/// (`randomize.mass_scale[0]`)
/// under `prefix` (a file name or a key; empty for none). serde turns a non-finite number into a
/// JSON `null`, which reads as "not given": a setting would be silently dropped, so every YAML reader
/// refuses them here, optional keys included.
pub fn check_finite_yaml(value: &serde_norway::Value, prefix: &str) -> Result<()> {
    fn walk(value: &serde_norway::Value, path: &mut String) -> Option<(String, f64)> {
        use serde_norway::Value as Y;
        match value {
            Y::Number(n) => n
                .as_f64()
                .filter(|x| !x.is_finite())
                .map(|x| (path.clone(), x)),
            Y::Sequence(items) => items.iter().enumerate().find_map(|(k, item)| {
                let len = path.len();
                path.push_str(&format!("[{k}]"));
                let found = walk(item, path);
                path.truncate(len);
                found
            }),
            Y::Mapping(map) => map.iter().find_map(|(key, item)| {
                let len = path.len();
                let name = match key {
                    Y::String(s) => s.clone(),
                    Y::Number(n) => n.to_string(),
                    Y::Bool(b) => b.to_string(),
                    _ => "?".to_owned(),
                };
                if !path.is_empty() {
                    path.push('.');
                }
                path.push_str(&withheld_unless_name(&name));
                let found = walk(item, path);
                path.truncate(len);
                found
            }),
            Y::Tagged(tagged) => walk(&tagged.value, path),
            Y::Null | Y::Bool(_) | Y::String(_) => None,
        }
    }
    let mut path = String::new();
    match walk(value, &mut path) {
        None => Ok(()),
        Some((key, x)) => {
            let yaml = if x.is_nan() {
                ".nan"
            } else if x > 0.0 {
                ".inf"
            } else {
                "-.inf"
            };
            let detail =
                format!("must be a finite number, got {yaml} (non-finite numbers are refused)");
            Err(match (prefix.is_empty(), key.is_empty()) {
                (true, true) => invalid(detail),
                (true, false) => crate::error::invalid_at(key, detail),
                (false, true) => crate::error::invalid_at(prefix, detail),
                (false, false) => crate::error::invalid_at(format!("{prefix}: {key}"), detail),
            })
        }
    }
}

/// Parses YAML text (the shape already checked) into `T` as serde does, after refusing a non-finite
/// number anywhere in it ([`check_finite_yaml`]); errors as [`yaml_error`] gives them, `what` naming
/// the expected content (e.g. "a world file").
pub fn from_yaml<T: serde::de::DeserializeOwned>(text: &str, shown: &str, what: &str) -> Result<T> {
    let parsed: T = serde_norway::from_str(text).map_err(|e| yaml_error(shown, what, &e))?;
    // Parsed again as a plain value only to find non-finite numbers: serde has already said the
    // text is valid, so this cannot fail on syntax.
    let value: serde_norway::Value =
        serde_norway::from_str(text).map_err(|e| yaml_error(shown, what, &e))?;
    check_finite_yaml(&value, shown)?;
    Ok(parsed)
}

/// A key for an error message's key path: itself when it is a short name ([`is_name_like`], at most
/// 24 characters), an [`excerpt`] otherwise.
pub fn withheld_unless_name(text: &str) -> String {
    if is_name_like(text) && text.chars().count() <= EXCERPT_CHARS {
        text.to_owned()
    } else {
        excerpt(text)
    }
}

/// `message` with every double-quoted or backquoted part cut to an [`excerpt`], or withheld where it
/// does not read as a name ([`withheld_unless_name`]): serde's messages quote keys and values whole.
pub fn quoted_excerpts(message: &str) -> String {
    let mut out = String::new();
    let mut rest = message;
    while let Some(open) = rest.find(['"', '`']) {
        let quote = rest.as_bytes()[open] as char;
        out.push_str(&rest[..open]);
        let after = &rest[open + 1..];
        // serde escapes a quote inside a quoted value as \"; a backquoted name has no escapes.
        let mut end = None;
        let mut escaped = false;
        for (k, c) in after.char_indices() {
            match c {
                '\\' if quote == '"' && !escaped => escaped = true,
                c if c == quote && !escaped => {
                    end = Some(k);
                    break;
                }
                _ => escaped = false,
            }
        }
        let Some(end) = end else {
            out.push_str(&excerpt(after));
            return out;
        };
        let inner = &after[..end];
        if !is_name_like(inner) || inner.chars().count() > EXCERPT_CHARS {
            out.push_str(&excerpt(inner));
        } else {
            out.push(quote);
            out.push_str(inner);
            out.push(quote);
        }
        rest = &after[end + 1..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    const SHADOW: &str =
        "root:$6$abcdefghSALT$VeryLongHashValueThatIsSecret1234567890:19000:0:99999:7:::";

    #[test]
    fn non_finite_yaml_numbers_are_refused_with_their_key_path() {
        for (text, expected) in [
            (
                "a: {b: [1, .nan]}",
                "f.yaml: a.b[1]: must be a finite number, got .nan",
            ),
            ("x: -.inf", "f.yaml: x: must be a finite number, got -.inf"),
            ("x: .Inf", "f.yaml: x: must be a finite number, got .inf"),
            (".inf", "f.yaml: must be a finite number, got .inf"),
        ] {
            let value: serde_norway::Value = serde_norway::from_str(text).unwrap();
            let e = check_finite_yaml(&value, "f.yaml").unwrap_err().message();
            assert!(e.starts_with(expected), "{text}: {e}");
        }
        let fine: serde_norway::Value = serde_norway::from_str("a: [1, 2.5e300, -3]").unwrap();
        assert!(check_finite_yaml(&fine, "f.yaml").is_ok());
    }

    #[test]
    fn values_that_are_not_names_are_never_quoted() {
        assert_eq!(excerpt("ground_frction"), "\"ground_frction\"");
        assert_eq!(
            excerpt(&"x".repeat(30)),
            format!("\"{}\"...", "x".repeat(24))
        );
        assert_eq!(excerpt(SHADOW), "<79 characters, not shown>");
        let message = format!("unknown field `{SHADOW}`, expected one of `ground`, `pegs`");
        let shown = quoted_excerpts(&message);
        assert_eq!(
            shown,
            "unknown field <79 characters, not shown>, expected one of `ground`, `pegs`"
        );
        assert!(!shown.contains("root"));
    }

    #[test]
    fn devices_fifos_and_directories_are_refused_without_reading() {
        let err = read_bytes(Path::new("/dev/zero"), 1 << 20, "robot file").unwrap_err();
        assert!(err.message().contains("not a regular file"), "{err}");
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("fifo");
        let status = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap();
        assert!(status.success());
        let started = Instant::now();
        let err = read_bytes(&fifo, 1 << 20, "world file").unwrap_err();
        assert!(err.message().contains("not a regular file"), "{err}");
        assert!(
            started.elapsed().as_secs_f64() < 1.0,
            "a FIFO must not block"
        );
        let err = read_bytes(dir.path(), 1 << 20, "world file").unwrap_err();
        assert!(err.message().contains("is a directory"), "{err}");
    }

    #[test]
    fn a_file_over_its_cap_is_refused_and_one_at_it_is_read() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.yaml");
        std::fs::write(&path, "x".repeat(100)).unwrap();
        assert!(!is_input(&path));
        assert_eq!(read_bytes(&path, 100, "f").unwrap().len(), 100);
        assert!(is_input(&path), "a file read is remembered as an input");
        let err = read_bytes(&path, 99, "config").unwrap_err();
        assert!(err.message().contains("more than the 99"), "{err}");
        // A link to a device is refused like the device.
        let link = dir.path().join("zero.yaml");
        std::os::unix::fs::symlink("/dev/zero", &link).unwrap();
        assert!(read_text(&link, 100, "f").is_err());
    }

    #[test]
    fn deep_yaml_is_refused_in_linear_time_and_real_files_pass() {
        let deep = "[".repeat(100_000) + &"]".repeat(100_000);
        let started = Instant::now();
        let err = check_yaml_shape(&deep, "w.yaml").unwrap_err();
        assert!(started.elapsed().as_secs_f64() < 0.5);
        assert!(err.message().contains("nested more than 64"), "{err}");
        let mut block = String::new();
        for k in 0..70 {
            block += &format!("{}a:\n", "  ".repeat(k));
        }
        assert!(check_yaml_shape(&block, "w.yaml").is_err());
        let dashes = "- ".repeat(70) + "x\n";
        assert!(check_yaml_shape(&dashes, "w.yaml").is_err());
        let fine = "ground: {heightfield: {file: 'a[b.csv', scale: [1, 1, 1]}}\n\
                    obstacles:\n  - box: {half_extents: [1, 2, 3]} # [[[\n    position: [0, 0, 0]\n";
        check_yaml_shape(fine, "w.yaml").unwrap();
        check_yaml_shape(&"[".repeat(MAX_NESTING), "w.yaml").unwrap();
    }

    #[test]
    fn xml_with_many_attributes_or_deep_elements_is_refused() {
        let many: String = (0..200_000).map(|k| format!(" a{k}=\"1\"")).collect();
        let text = format!("<robot name=\"r\"><link{many}/></robot>");
        let started = Instant::now();
        let err = check_xml_shape(&text, "r.urdf").unwrap_err();
        assert!(started.elapsed().as_secs_f64() < 0.5);
        assert!(err.message().contains("more than 64 attributes"), "{err}");
        let deep = "<a>".repeat(65) + &"</a>".repeat(65);
        assert!(check_xml_shape(&deep, "r.urdf").is_err());
        let fine = "<?xml version=\"1.0\"?><!-- <<<< --><robot name=\"r\"><link name=\"a>b\"/>\
                    <joint name=\"j\" type=\"revolute\"><axis xyz=\"0 0 1\"/></joint></robot>";
        check_xml_shape(fine, "r.urdf").unwrap();
        check_xml_shape(&("<a>".repeat(64) + &"</a>".repeat(64)), "r.urdf").unwrap();
    }
}
