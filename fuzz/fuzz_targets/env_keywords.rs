#![no_main]
//! See `snakesim_fuzz::checks::env_keywords`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::env_keywords(bytes));
