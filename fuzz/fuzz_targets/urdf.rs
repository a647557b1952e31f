#![no_main]
//! See `snakesim_fuzz::checks::urdf`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::urdf(bytes));
