//! The command-line contract (DESIGN.md sec. 5): JSON keys, the paper's numbers, identities and
//! clear errors, through the real binary.

use std::process::Command;

use serde_json::Value;

fn radiosity(args: &[&str]) -> (bool, String, String) {
    let out =
        Command::new(env!("CARGO_BIN_EXE_radiosity")).args(args).output().expect("binary runs");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn json(args: &[&str]) -> Value {
    let (ok, stdout, stderr) = radiosity(args);
    assert!(ok, "radiosity {args:?} failed: {stderr}");
    serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("bad JSON from {args:?}: {e}\n{stdout}"))
}

#[test]
fn table_3_1_up_to_n_160_matches_the_paper_within_2_percent() {
    let v = json(&["study", "table-3.1", "--max-n", "160", "--json", "-"]);
    assert_eq!(v["study"], "table-3.1");
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 3 + 3, "n = 8, 32, 128 and 10, 40, 160");
    for r in rows {
        for key in ["surface", "mesh", "n", "dof", "error", "setup_seconds", "solve_seconds"] {
            assert!(!r[key].is_null(), "row lacks {key}: {r}");
        }
        assert_eq!(r["mesh"], "uniform");
        assert_eq!(r["method"], "centroid");
        let (e, p) = (r["error"].as_f64().unwrap(), r["paper_error"].as_f64().unwrap());
        assert!((e - p).abs() <= 0.02 * p, "{}: n = {}: {e} vs paper {p}", r["surface"], r["n"]);
    }
    let surfaces: Vec<&str> = rows.iter().map(|r| r["surface"].as_str().unwrap()).collect();
    assert!(surfaces.contains(&"four-piece") && surfaces.contains(&"five-piece"));
}

#[test]
fn table_3_4_up_to_n_160_matches_the_paper_within_2_percent() {
    let v = json(&["study", "table-3.4", "--max-n", "160", "--json", "-"]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    for r in rows {
        assert_eq!(r["dof"].as_u64().unwrap(), 3 * r["n"].as_u64().unwrap());
        let (e, p) = (r["error"].as_f64().unwrap(), r["paper_error"].as_f64().unwrap());
        assert!((e - p).abs() <= 0.02 * p, "{}: n = {}: {e} vs paper {p}", r["surface"], r["n"]);
    }
}

#[test]
fn closed_enclosures_have_unit_row_sums_and_report_pair_classes() {
    for scene in ["cube", "baffled-box"] {
        let v = json(&[
            "inspect", "--scene", scene, "--method", "centroid", "--refine", "2", "--json", "-",
        ]);
        for key in ["row_sum_min", "row_sum_max"] {
            let s = v[key].as_f64().unwrap();
            assert!((s - 1.0).abs() < 1e-10, "{scene}: {key} = {s}");
        }
        let total = v["pairs_total"].as_u64().unwrap();
        let parts =
            ["pairs_skipped", "pairs_full", "pairs_partial"].map(|k| v[k].as_u64().unwrap());
        assert_eq!(parts.iter().sum::<u64>(), total, "{scene}: {v}");
        assert_eq!(total, v["dof"].as_u64().unwrap() * v["n"].as_u64().unwrap());
    }
}

#[test]
fn solve_reports_the_error_and_times_as_json() {
    let v = json(&[
        "solve",
        "--scene",
        "five-piece",
        "--refine",
        "1",
        "--method",
        "linear",
        "--json",
        "-",
    ]);
    assert_eq!(v["dof"], 120);
    let e = v["error"].as_f64().unwrap();
    assert!((e - 0.317).abs() < 0.02 * 0.317, "{e}");
    assert!(v["residual"].as_f64().unwrap() < 1e-12);
    let v = json(&["solve", "--scene", "baffled-box", "--refine", "1", "--json", "-"]);
    assert!(v["error"].is_null(), "no true solution on the box");
    let [lo, _, hi] = [0, 1, 2].map(|k| v["solution_range"][k].as_f64().unwrap());
    // rho = 0.5 everywhere, E = 1 on the top: 0 < u and the top is brightest, below 1/(1-rho) = 2.
    assert!(lo > 0.0 && hi > 1.0 && hi < 2.0, "{v}");
}

#[test]
fn bad_input_is_a_clear_error_naming_the_culprit() {
    let cases: &[(&[&str], &str)] = &[
        (&["solve", "--scene", "sphere"], "unknown scene 'sphere'"),
        (&["solve", "--scene", "cube", "--method", "linear", "--alpha", "0.4"], "alpha = 0.4"),
        (&["solve", "--scene", "four-piece", "--params", "5,2,3"], "(5, 2, 3)"),
        (&["solve", "--scene", "four-piece", "--params", "5,2"], "A,B,C"),
        (&["solve", "--scene", "cube", "--solution", "edge"], "not on 'cube'"),
        (&["solve", "--scene", "four-piece", "--solution", "parabola"], "'parabola'"),
        (&["solve", "--scene", "four-piece", "--refine", "40"], "refine = 40"),
        (&["study", "table-9.9"], "unknown study 'table-9.9'"),
    ];
    for (args, needle) in cases {
        let (ok, _, stderr) = radiosity(args);
        assert!(!ok, "{args:?} should fail");
        assert!(stderr.contains(needle), "{args:?}: expected '{needle}' in: {stderr}");
        assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    }
}

#[test]
fn assemble_writes_a_numpy_matrix_that_solves_like_the_library() {
    let dir = std::env::temp_dir().join(format!("radiosity-npy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("k.npy");
    let (ok, _, stderr) = radiosity(&[
        "assemble",
        "--scene",
        "baffled-box",
        "--refine",
        "1",
        "--output",
        path.to_str().unwrap(),
    ]);
    assert!(ok, "{stderr}");
    let bytes = std::fs::read(&path).unwrap();
    let npy = npyz::NpyFile::new(&bytes[..]).unwrap();
    assert_eq!(npy.shape(), &[64, 64]);
    let k: Vec<f64> = npy.into_vec().unwrap();
    // A closed box: rows of K sum to rho = 0.5.
    for i in 0..64 {
        let s: f64 = k[i * 64..(i + 1) * 64].iter().sum();
        assert!((s - 0.5).abs() < 1e-12, "row {i}: {s}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
