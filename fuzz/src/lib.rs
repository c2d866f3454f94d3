//! Fuzz targets of tincull's parsers (libFuzzer through `cargo fuzz`).
//!
//! The bodies live in `targets.rs` so that the root package's `tests/fuzz_corpus.rs` replays the checked-in corpus
//! through exactly the same code with the stable toolchain.

#[path = "targets.rs"]
pub mod targets;
