//! The checks the fuzz targets run (shared with the workspace's tests/parsers.rs).
pub mod checks;
