//! The fuzz targets of `fuzz/` on stable, for a bounded number of inputs: seeded random bytes, and
//! the example scene files cut short, with lines dropped and bytes changed. Each target's check
//! (an error or a valid result, never a panic) is the same code as the fuzzer's. Emission files
//! damaged the same ways are refused with the file named.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

#[path = "../../fuzz/bodies/kernels.rs"]
mod kernels;
#[path = "../../fuzz/bodies/scene_files.rs"]
mod scene_files;
#[path = "../../fuzz/bodies/scenes.rs"]
mod scenes;

/// `count` inputs of f64 values, each drawn from ordinary sizes, special values (NaN, infinities,
/// zeros, huge and tiny) and repeats of a value drawn before (touching and coplanar faces).
fn numbers(seed: u64, count: usize, values: usize) -> Vec<Vec<u8>> {
    let mut rng = StdRng::seed_from_u64(seed);
    let special = [f64::NAN, f64::INFINITY, -f64::INFINITY, 0.0, -0.0, 1e300, 1e-300, 1.0, -1.0];
    (0..count)
        .map(|_| {
            let mut drawn: Vec<f64> = Vec::with_capacity(values);
            for _ in 0..values {
                let v = match rng.random_range(0..10) {
                    0 => special[rng.random_range(0..special.len())],
                    1..=3 if !drawn.is_empty() => drawn[rng.random_range(0..drawn.len())],
                    4 => rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-12..12)),
                    _ => rng.random_range(-2.0..2.0),
                };
                drawn.push(v);
            }
            drawn.iter().flat_map(|v| v.to_le_bytes()).collect()
        })
        .collect()
}

#[test]
fn kernels_on_seeded_inputs() {
    for input in numbers(1, 20_000, 14) {
        kernels::check(&input);
    }
}

#[test]
fn scenes_on_seeded_inputs() {
    for input in numbers(2, 2_000, 42) {
        scenes::check(&input);
    }
}

/// The text `text` damaged in a few ways: cut at `cuts` places, each line dropped in turn, and
/// random bytes changed.
fn damaged(text: &str, cuts: usize, seed: u64) -> Vec<Vec<u8>> {
    let bytes = text.as_bytes();
    let mut out: Vec<Vec<u8>> =
        (1..cuts).map(|k| bytes[..bytes.len() * k / cuts].to_vec()).collect();
    let lines: Vec<&str> = text.lines().collect();
    for skip in 0..lines.len() {
        let kept: Vec<&str> =
            lines.iter().enumerate().filter(|&(k, _)| k != skip).map(|(_, l)| *l).collect();
        out.push(kept.join("\n").into_bytes());
    }
    let mut rng = StdRng::seed_from_u64(seed);
    let alphabet = b"0123456789.-+eE[],=\"# \nabcxyz{}";
    for _ in 0..100 {
        let mut changed = bytes.to_vec();
        for _ in 0..rng.random_range(1..4) {
            let at = rng.random_range(0..changed.len());
            changed[at] = alphabet[rng.random_range(0..alphabet.len())];
        }
        out.push(changed);
    }
    out
}

#[test]
fn scene_files_damaged_every_way() {
    let examples = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut files = 0;
    for entry in std::fs::read_dir(&examples).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        scene_files::check(text.as_bytes());
        for input in damaged(&text, 40, files) {
            scene_files::check(&input);
        }
        files += 1;
    }
    assert!(files >= 5, "the examples' scene files: {files}");
}

#[test]
fn damaged_emission_files_are_refused_with_the_file_named() {
    let dir = std::env::temp_dir().join(format!("radiosity-fuzz-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = "lamp,window\n1.0,0.0\n0.5,2.0\n0.0,0.25\n";
    let path = dir.join("cases.csv");
    std::fs::write(&path, good).unwrap();
    radiosity::problems::EmissionCases::read_csv(&path).unwrap();
    let (mut refused, mut read) = (0, 0);
    for input in damaged(good, 12, 7) {
        std::fs::write(&path, &input).unwrap();
        match radiosity::problems::EmissionCases::read_csv(&path) {
            Ok(_) => read += 1,
            Err(e) => {
                let message = e.to_string();
                assert!(message.contains("cases.csv"), "{message}");
                refused += 1;
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(refused > 0 && read > 0, "refused {refused}, read {read}");
}
