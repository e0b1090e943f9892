//! Running the real binary from the integration tests.
// Each test crate uses what it needs of this module.
#![allow(dead_code)]

pub mod gpu;

use std::process::Command;

use serde_json::Value;

/// Runs `radiosity args` in the crate's root: (success, stdout, stderr).
pub fn radiosity(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_radiosity"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs `radiosity args`, which must succeed and print JSON.
pub fn json(args: &[&str]) -> Value {
    let (ok, stdout, stderr) = radiosity(args);
    assert!(ok, "radiosity {args:?} failed: {stderr}");
    serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("bad JSON from {args:?}: {e}\n{stdout}"))
}

/// A directory for a test's files, named by `tag` and the process.
pub fn temp_dir(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("radiosity-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The scene file `path` (relative to the crate's root) moved rigidly by `offset`: every
/// `vertices` and `translate` triple shifted, mesh files referred to by absolute path. Written to
/// `dir`; returns the new file's path.
pub fn translated_scene(path: &str, offset: [f64; 3], dir: &std::path::Path) -> std::path::PathBuf {
    let root = env!("CARGO_MANIFEST_DIR");
    let source = std::path::Path::new(root).join(path);
    let text = std::fs::read_to_string(&source).unwrap();
    let mesh_dir = source.parent().unwrap().to_str().unwrap().to_string();
    let shift_triples = |line: &str| -> String {
        let mut out = String::new();
        let mut rest = line;
        while let Some(open) = rest.find('[') {
            let after = &rest[open + 1..];
            // Innermost brackets only: a triple has no '[' before its ']'.
            let close = after.find(']').unwrap();
            if after[..close].contains('[') {
                out += &rest[..=open];
                rest = after;
                continue;
            }
            let v: Vec<f64> =
                after[..close].split(',').map(|x| x.trim().parse().unwrap()).collect();
            assert_eq!(v.len(), 3, "{line}");
            out += &rest[..open];
            out += &format!(
                "[{:?}, {:?}, {:?}]",
                v[0] + offset[0],
                v[1] + offset[1],
                v[2] + offset[2]
            );
            rest = &after[close + 1..];
        }
        out + rest
    };
    let moved: String = text
        .lines()
        .map(|line| {
            if line.starts_with("vertices") || line.starts_with("translate") {
                shift_triples(line)
            } else {
                line.replace("file = \"", &format!("file = \"{mesh_dir}/"))
            }
        })
        .map(|l| l + "\n")
        .collect();
    let name = format!(
        "moved-{}-{}",
        offset.iter().map(|o| o.to_string()).collect::<Vec<_>>().join("_"),
        source.file_name().unwrap().to_str().unwrap()
    );
    let target = dir.join(name);
    std::fs::write(&target, moved).unwrap();
    target
}
