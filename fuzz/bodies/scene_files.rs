//! Arbitrary text as a TOML scene file: an error or a valid scene, never a panic. Seed the corpus
//! with the examples: `mkdir -p corpus/scene_files && cp ../examples/*.toml corpus/scene_files/`,
//! then `cargo +nightly fuzz run scene_files`.
//!
//! Shared by the fuzz target of the same name (`cargo +nightly fuzz run NAME` in `fuzz/`) and
//! by `tests/fuzz_replay.rs`, which replays it on stable over seeded and damaged inputs.

/// Checks one input: returns where the input is outside the contract, panics on a failure.
pub fn check(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else { return };
    // Beside the examples, so that a mesh file named in the text is looked for there (this file
    // is built from the repository's root and from `fuzz/`).
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let examples = if root.join("examples").is_dir() {
        root.join("examples")
    } else {
        root.join("../examples")
    };
    let path = examples.join("fuzzed.toml");
    if let Ok(scene) = radiosity::scene::parse_toml(text, &path) {
        assert!(!scene.faces.is_empty());
        for f in &scene.faces {
            assert!((0.0..=1.0).contains(&f.rho) && f.emission.is_finite() && f.emission >= 0.0);
        }
    }
}
