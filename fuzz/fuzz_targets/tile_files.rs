//! Fuzz target `tile_files`: see `src/targets.rs`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| tincull_fuzz::targets::tile_files(data));
