//! Distributed runs through MPI: `mpirun -np N radiosity ...` against one process. Built with
//! `cargo test --release --features mpi --test mpi` where OpenMPI is installed
//! (`apt-get install -y libopenmpi-dev openmpi-bin libclang-dev`; .ci/run does it).
#![cfg(feature = "mpi")]

#[path = "suite/common/mod.rs"]
mod common;

use std::process::Command;

use serde_json::Value;

/// Runs `mpirun -np np radiosity args` (one thread per rank, the two cores shared), with a time
/// limit so that a hang fails the test instead of stalling it: (success, stdout, stderr).
fn mpirun(np: usize, args: &[&str]) -> (bool, String, String) {
    let np = np.to_string();
    let mut command = Command::new("timeout");
    command.args(["300", "mpirun", "--allow-run-as-root", "--oversubscribe", "-np", &np]);
    command.args(["-x", "RAYON_NUM_THREADS=1", env!("CARGO_BIN_EXE_radiosity")]);
    run(command.args(args))
}

fn run(command: &mut Command) -> (bool, String, String) {
    let out = command.current_dir(env!("CARGO_MANIFEST_DIR")).output().unwrap_or_else(|e| {
        panic!("mpirun does not start ({e}): install OpenMPI (apt-get install openmpi-bin)")
    });
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// The `u` column of a node CSV.
fn solution(path: &std::path::Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let at = header.iter().position(|&h| h == "u").expect("a u column");
    lines.map(|l| l.split(',').nth(at).unwrap().parse().unwrap()).collect()
}

/// Largest difference over the largest value.
fn relative_max_difference(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    let diff = a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    diff / a.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Solves `args` in one process and over `np` ranks: the solutions and the ranks' JSON.
fn one_and_distributed(np: usize, args: &[&str]) -> (Vec<f64>, Vec<f64>, Value) {
    let dir = tempfile_dir();
    let (one, many) = (dir.join("one.csv"), dir.join("many.csv"));
    let (json_one, json_many) = (dir.join("one.json"), dir.join("many.json"));
    let with = |csv: &std::path::Path, json: &std::path::Path| -> Vec<String> {
        let mut all: Vec<String> = ["solve"].iter().chain(args).map(|s| s.to_string()).collect();
        all.extend(["--csv".into(), csv.display().to_string()]);
        all.extend(["--json".into(), json.display().to_string()]);
        all
    };
    let args_one = with(&one, &json_one);
    let (ok, _, stderr) =
        common::radiosity(&args_one.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert!(ok, "one process {args:?}: {stderr}");
    let args_many = with(&many, &json_many);
    let (ok, _, stderr) = mpirun(np, &args_many.iter().map(|s| s.as_str()).collect::<Vec<_>>());
    assert!(ok, "{np} ranks {args:?}: {stderr}");
    let report = serde_json::from_str(&std::fs::read_to_string(&json_many).unwrap()).unwrap();
    (solution(&one), solution(&many), report)
}

/// A fresh directory under the target directory.
fn tempfile_dir() -> std::path::PathBuf {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let k = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("radiosity-mpi-{}-{k}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn two_ranks_solve_as_one_process_does() {
    let cases: [&[&str]; 5] = [
        &["--scene", "five-piece", "--refine", "6"],
        &["--scene", "five-piece", "--method", "linear", "--refine", "3"],
        &["--scene", "examples/furnished-room.toml", "--refine", "2"],
        &["--scene", "examples/louvre-window.toml", "--refine", "4"],
        &["--scene", "city:4x4:lit", "--refine", "1"],
    ];
    for args in cases {
        let args: Vec<&str> = args.iter().copied().chain(["--operator", "compressed"]).collect();
        let (one, two, report) = one_and_distributed(2, &args);
        let d = relative_max_difference(&one, &two);
        assert!(d <= 1e-12, "{args:?}: u differs by {d:.2e}");
        assert_eq!(report["ranks"], 2, "{args:?}");
        let per_rank = report["per_rank"].as_array().unwrap();
        assert_eq!(per_rank.len(), 2);
        for (rank, r) in per_rank.iter().enumerate() {
            assert_eq!(r["rank"], rank);
            assert!(r["operator_bytes"].as_u64().unwrap() > 0, "{args:?}: {r}");
            assert!(r["setup_seconds"].as_f64().unwrap() > 0.0, "{args:?}: {r}");
            // What every rank holds whatever its share: at least the operator's orders (16
            // bytes an element), and within the rank's peak.
            let replicated = r["replicated_bytes"].as_u64().unwrap();
            let n = one.len() as u64;
            assert!(replicated >= 8 * n, "{args:?}: {r}");
            if let Some(peak) = r["peak_rss_bytes"].as_u64() {
                assert!(replicated < peak, "{args:?}: {r}");
            }
        }
        assert!(report["communication_bytes"].as_u64().unwrap() > 0);
        assert!(report["load_imbalance"].as_f64().unwrap() >= 1.0);
    }
}

#[test]
fn one_rank_is_one_process() {
    let args = ["--scene", "five-piece", "--refine", "3", "--operator", "compressed"];
    let (one, alone, report) = one_and_distributed(1, &args);
    assert!(relative_max_difference(&one, &alone) <= 1e-12);
    assert!(report.get("ranks").is_none(), "a lone rank is not distributed: {report}");
}

#[test]
fn two_ranks_inspect_the_row_sums_of_one_process() {
    let args = ["inspect", "--scene", "baffled-box", "--refine", "3", "--operator", "compressed"];
    let one = common::json(&[&args[..], &["--json", "-"]].concat());
    let (ok, stdout, stderr) = mpirun(2, &[&args[..], &["--json", "-"]].concat());
    assert!(ok, "{stderr}");
    let two: Value = serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    for key in ["row_sum_min", "row_sum_max"] {
        let (a, b) = (one[key].as_f64().unwrap(), two[key].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-13, "{key}: {a} against {b}");
    }
    for key in ["near_entries", "far_blocks", "empty_blocks", "empty_block_pairs", "pairs_partial"]
    {
        assert_eq!(one[key], two[key], "{key}");
    }
    assert_eq!(two["ranks"], 2);
}

#[test]
fn a_rank_that_fails_stops_every_rank_with_its_message() {
    // Rank 0 has a good scene and waits for rank 1 in the block plan; rank 1's scene is
    // missing: both stop, with rank 1's message, instead of rank 0 waiting for ever.
    let binary = env!("CARGO_BIN_EXE_radiosity");
    let good = ["solve", "--scene", "five-piece", "--refine", "3", "--operator", "compressed"];
    let bad = ["solve", "--scene", "no-such-scene.toml", "--operator", "compressed"];
    let mut command = Command::new("timeout");
    command.args(["120", "mpirun", "--allow-run-as-root", "--oversubscribe"]);
    command.args(["-np", "1", binary]).args(good).arg(":").args(["-np", "1", binary]).args(bad);
    let started = std::time::Instant::now();
    let (ok, _, stderr) = run(&mut command);
    assert!(!ok, "a failing rank must fail the run");
    assert!(stderr.contains("error (rank 1)"), "{stderr}");
    assert!(stderr.contains("no-such-scene.toml"), "{stderr}");
    assert!(started.elapsed().as_secs() < 100, "the ranks did not stop: {stderr}");
}

#[test]
fn what_is_not_distributed_is_refused_over_ranks() {
    let base = ["solve", "--scene", "five-piece", "--refine", "2"];
    for (extra, culprit) in [
        (&["--operator", "dense"][..], "dense operator is not distributed"),
        (&["--solver", "lu"][..], "LU needs the dense matrix"),
    ] {
        let (ok, _, stderr) = mpirun(2, &[&base[..], extra].concat());
        assert!(!ok, "{extra:?}");
        assert!(stderr.contains(culprit), "{extra:?}: {stderr}");
    }
    let (ok, _, stderr) = mpirun(2, &["viewfactors", "--scene", "five-piece"]);
    assert!(!ok && stderr.contains("run the others in one process"), "{stderr}");
    let dense_bench = ["bench", "--scene", "five-piece", "--refine", "2", "--operator", "dense"];
    let (ok, _, stderr) = mpirun(2, &dense_bench);
    assert!(!ok && stderr.contains("--operator compressed --backends cpu"), "{stderr}");
}

#[test]
fn bench_times_the_operator_spread_over_ranks() {
    let args = ["bench", "--scene", "five-piece", "--refine", "4", "--operator", "compressed"];
    let (ok, stdout, stderr) = mpirun(2, &[&args[..], &["--json", "-"]].concat());
    assert!(ok, "{stderr}");
    let r: Value = serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    assert_eq!(r["ranks"], 2, "{r}");
    assert!(r["max_product_rel_diff"].as_f64().unwrap() <= 1e-5, "{r}");
    assert!(r["load_imbalance"].as_f64().unwrap() >= 1.0, "{r}");
}

#[test]
fn the_compression_study_runs_over_ranks() {
    // The compressed rows over two ranks, the dense reference at rank 0: each compressed
    // solution within 10 × its tolerance of the dense one, as in one process.
    let (ok, stdout, stderr) = mpirun(
        2,
        &[
            "study",
            "compression",
            "--max-n",
            "3000",
            "--json",
            "-",
            "--figures",
            "target/mpi-figures",
        ],
    );
    assert!(ok, "{stderr}");
    let study: Value = serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    let rows = study["rows"].as_array().unwrap();
    let compressed: Vec<&Value> = rows.iter().filter(|r| r["operator"] == "compressed").collect();
    assert_eq!(compressed.len(), 6, "{stdout}");
    for r in compressed {
        assert_eq!(r["ranks"], 2, "{r}");
        let tolerance = r["compression_tolerance"].as_f64().unwrap();
        let d = r["difference_from_dense"].as_f64().unwrap();
        assert!(d <= 10.0 * tolerance, "{r}");
    }
}
