//! The checks the fuzz targets run (shared with the workspace's tests/parsers.rs).
pub mod checks;
/// `snake-cli run --targets`'s parser: the binary's own source file, compiled here too.
#[path = "../../snake-cli/src/targets.rs"]
pub mod targets;
