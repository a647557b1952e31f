#![no_main]
//! See `snakesim_fuzz::checks::fit_overrides`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::fit_overrides(bytes));
