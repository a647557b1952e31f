#![no_main]
//! See `snakesim_fuzz::checks::world_file`.

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| snakesim_fuzz::checks::world_file(bytes));
