//! Arbitrary text as a TOML scene file: an error or a valid scene, never a panic. Seed the corpus
//! with the examples: `mkdir -p corpus/scene_files && cp ../examples/*.toml corpus/scene_files/`,
//! then `cargo +nightly fuzz run scene_files`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/fuzzed.toml");
    if let Ok(scene) = radiosity::scene::parse_toml(text, &path) {
        assert!(!scene.faces.is_empty());
        for f in &scene.faces {
            assert!((0.0..=1.0).contains(&f.rho) && f.emission.is_finite() && f.emission >= 0.0);
        }
    }
});
