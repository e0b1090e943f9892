//! Running the real binary from the integration tests.
// Each test crate uses what it needs of this module.
#![allow(dead_code)]

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
