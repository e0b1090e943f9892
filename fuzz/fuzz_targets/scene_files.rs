//! Arbitrary text as a TOML scene file: an error or a valid scene, never a panic. Seed the corpus
//! with the examples: `mkdir -p corpus/scene_files && cp ../examples/*.toml corpus/scene_files/`,
//! then `cargo +nightly fuzz run scene_files`.

#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../bodies/scene_files.rs"]
mod body;

fuzz_target!(|data: &[u8]| body::check(data));
