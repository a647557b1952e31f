#![no_main]
//! See `snakesim_fuzz::checks::run_config`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::run_config(bytes));
