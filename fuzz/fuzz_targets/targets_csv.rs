#![no_main]
//! See `snakesim_fuzz::checks::targets_csv`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::targets_csv(bytes));
