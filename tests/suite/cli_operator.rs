//! The compressed operator through the command line (ARCHITECTURE.md, "The command line"): its
//! solves against the dense one's, the compression study and bench, shadowed blocks, memory
//! limits and estimates, and saved operators reloaded.

use crate::common;

use common::{json, radiosity};
use serde_json::Value;

#[test]
fn the_compressed_operator_solves_like_the_dense_one() {
    // Five-piece, both methods: the compressed run's solution equals the dense one's to well
    // within 10 x the tolerance (measured through E_n, whose reference is the same true solution),
    // and its JSON carries the operator's keys.
    for (method, refine) in [("centroid", "3"), ("linear", "2")] {
        let run = |operator: &str| {
            json(&[
                "solve",
                "--scene",
                "five-piece",
                "--method",
                method,
                "--refine",
                refine,
                "--operator",
                operator,
                "--compression-tolerance",
                "1e-8",
                "--json",
                "-",
            ])
        };
        let (d, c) = (run("dense"), run("compressed"));
        assert_eq!(
            (d["operator"].as_str(), c["operator"].as_str()),
            (Some("dense"), Some("compressed"))
        );
        let (ed, ec) = (d["error"].as_f64().unwrap(), c["error"].as_f64().unwrap());
        // u is about 50 at most; E_n moves by at most max |u_c - u_d|.
        assert!((ed - ec).abs() <= 10.0 * 1e-8 * 50.0, "{method}: {ed} vs {ec}");
        assert_eq!(c["compression_tolerance"].as_f64(), Some(1e-8));
        for key in ["operator_bytes", "near_entries", "far_blocks", "max_rank", "peak_rss_bytes"] {
            assert!(c[key].as_u64().is_some_and(|v| v > 0), "{method}: {key} in {c}");
        }
        assert!(c["operator_bytes"].as_u64() < d["operator_bytes"].as_u64(), "{method}");
    }
}

#[test]
fn the_compression_study_compares_every_tolerance_with_the_dense_solution() {
    let dir = std::env::temp_dir().join(format!("radiosity-compression-{}", std::process::id()));
    let v = json(&[
        "study",
        "compression",
        "--max-n",
        "2560",
        "--figures",
        dir.to_str().unwrap(),
        "--json",
        "-",
    ]);
    let rows = v["rows"].as_array().unwrap();
    // Centroid and linear at n = 2 560: one dense run and three tolerances each.
    assert_eq!(rows.len(), 8, "{v}");
    for r in rows.iter().filter(|r| r["operator"] == "compressed") {
        let tol = r["compression_tolerance"].as_f64().unwrap();
        let diff = r["difference_from_dense"].as_f64().unwrap();
        assert!(diff <= 10.0 * tol, "{r}");
    }
    assert!(dir.join("compression.png").exists() && dir.join("compression.svg").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_compression_study_runs_on_any_scene() {
    // The furnished room (no true solution: its lamp's emission) at n = 1 152 and 4 608.
    let dir = std::env::temp_dir().join(format!("radiosity-scene-study-{}", std::process::id()));
    let v = json(&[
        "study",
        "compression",
        "--scene",
        "examples/furnished-room.toml",
        "--tolerances",
        "1e-6,1e-9",
        "--max-n",
        "5000",
        "--figures",
        dir.to_str().unwrap(),
        "--json",
        "-",
    ]);
    assert_eq!(v["scene"], "furnished-room", "{v}");
    let rows = v["rows"].as_array().unwrap();
    let ns: Vec<u64> = rows.iter().map(|r| r["n"].as_u64().unwrap()).collect();
    assert_eq!(ns, [1152, 1152, 1152, 4608, 4608, 4608], "{v}");
    for r in rows {
        assert!(r["error"].is_null(), "no true solution, no E_n: {r}");
        assert_eq!(r["method"], "centroid");
    }
    for r in rows.iter().filter(|r| r["operator"] == "compressed") {
        let tol = r["compression_tolerance"].as_f64().unwrap();
        let diff = r["difference_from_dense"].as_f64().unwrap();
        assert!(diff <= 10.0 * tol, "{r}");
    }
    let fits = v["fits"].as_array().unwrap();
    assert_eq!(fits.len(), 3, "dense and two tolerances: {v}");
    assert!(fits.iter().all(|f| f["time_exponent"].as_f64().unwrap().is_finite()), "{v}");
    assert!(dir.join("compression.png").exists());
    let _ = std::fs::remove_dir_all(&dir);

    // The scene and the tolerances belong to this study alone; bad ones are named.
    let (ok, _, stderr) = radiosity(&["study", "table-3.1", "--scene", "cube"]);
    assert!(!ok && stderr.contains("--scene belongs to study compression"), "{stderr}");
    let (ok, _, stderr) =
        radiosity(&["study", "compression", "--scene", "cube", "--tolerances", "2"]);
    assert!(!ok && stderr.contains("must lie in (0, 1)"), "{stderr}");
    let (ok, _, stderr) = radiosity(&["study", "compression", "--scene", "no-such.toml"]);
    assert!(!ok && stderr.contains("no-such.toml"), "{stderr}");
}

#[test]
fn the_compression_study_takes_shadowed_blocks() {
    // The furnished room at n = 1 152: the flag reaches the compressed runs (another operator,
    // as close to the dense solution) and the study says it was used.
    let dir = std::env::temp_dir().join(format!("radiosity-shadowed-study-{}", std::process::id()));
    let study = |shadowed: bool| {
        let mut args = vec!["study", "compression", "--scene", "examples/furnished-room.toml"];
        args.extend(["--tolerances", "1e-6", "--max-n", "1200", "--json", "-"]);
        args.extend(["--figures", dir.to_str().unwrap()]);
        if shadowed {
            args.push("--shadowed-blocks");
        }
        json(&args)
    };
    let (plain, shadowed) = (study(false), study(true));
    assert_eq!(plain["shadowed_blocks"], false, "{plain}");
    assert_eq!(shadowed["shadowed_blocks"], true, "{shadowed}");
    let compressed = |v: &serde_json::Value| {
        let rows = v["rows"].as_array().unwrap();
        rows.iter().find(|r| r["operator"] == "compressed").unwrap().clone()
    };
    let (p, s) = (compressed(&plain), compressed(&shadowed));
    assert_ne!(p["operator_bytes"], s["operator_bytes"], "{p}\n{s}");
    assert!(s["difference_from_dense"].as_f64().unwrap() <= 1e-5, "{s}");
    let _ = std::fs::remove_dir_all(&dir);
    let (ok, _, stderr) = radiosity(&["study", "table-3.1", "--shadowed-blocks"]);
    assert!(!ok && stderr.contains("--shadowed-blocks belongs to study compression"), "{stderr}");
}

#[test]
fn bench_times_the_compressed_operator_against_the_dense_one() {
    let v = json(&[
        "bench",
        "--scene",
        "five-piece",
        "--refine",
        "3",
        "--operator",
        "compressed",
        "--repeats",
        "1",
        "--json",
        "-",
    ]);
    assert_eq!(v["operator"], "compressed");
    let diff = v["max_product_rel_diff"].as_f64().unwrap();
    assert!(diff <= 10.0 * 1e-6, "{v}");
    for key in ["setup_seconds", "dense_setup_seconds", "speedup"] {
        assert!(v[key].as_f64().is_some_and(|x| x > 0.0), "{key}: {v}");
    }
    assert!(v["operator_bytes"].as_u64().is_some_and(|b| b > 0));
}

#[test]
fn shadowed_blocks_keep_fewer_exact_entries_and_the_same_row_sums() {
    // The louvre room at refine 3: with shadowed blocks, the blocks that slats and tangent
    // planes cut keep only their partly visible pairs exact, and the closed room's rows still
    // sum to 1 within the tolerance.
    let run = |extra: &[&str]| {
        let args = ["inspect", "--scene", "examples/louvre-room.toml", "--refine", "3"];
        json(&[&args[..], &["--operator", "compressed", "--json", "-"], extra].concat())
    };
    let (plain, shadowed) = (run(&["--no-shadowed-blocks"]), run(&["--shadowed-blocks"]));
    assert_eq!(plain["shadowed_blocks"], 0, "{plain}");
    let entries = |v: &serde_json::Value| v["near_entries"].as_f64().unwrap();
    assert!(entries(&shadowed) < 0.8 * entries(&plain), "{shadowed} against {plain}");
    // The same pairs partly visible (a handful may fall on the other side of a sliver's
    // threshold with other leaves).
    let partial = |v: &serde_json::Value| v["pairs_partial"].as_f64().unwrap();
    assert!((partial(&shadowed) - partial(&plain)).abs() <= 1e-4 * partial(&plain));
    for key in ["row_sum_min", "row_sum_max"] {
        let sum = shadowed[key].as_f64().unwrap();
        assert!((sum - 1.0).abs() <= 1e-5, "{key} {sum}");
    }
}

#[test]
fn shadowed_blocks_are_made_by_default_where_faces_hold_many_elements_and_say_so() {
    // Five-piece at refine 4 holds 512 elements a face, at refine 3 128: the default makes
    // shadowed blocks on the first alone, with a note saying why; the flags force either.
    let run = |refine: &str, extra: &[&str]| {
        let args = ["inspect", "--scene", "five-piece", "--refine", refine, "--operator"];
        let (ok, out, err) =
            radiosity(&[&args[..], &["compressed", "--json", "-"], extra].concat());
        assert!(ok, "{err}");
        let report: serde_json::Value = serde_json::from_str(&out).unwrap();
        (report["shadowed_blocks"].as_u64().unwrap(), err)
    };
    let (blocks, err) = run("4", &[]);
    assert!(blocks > 0 && err.contains("shadowed blocks on (512 elements per face"), "{err}");
    let (blocks, err) = run("3", &[]);
    assert!(blocks == 0 && err.contains("shadowed blocks off (128 elements per face"), "{err}");
    let (blocks, err) = run("4", &["--no-shadowed-blocks"]);
    assert!(blocks == 0 && !err.contains("shadowed blocks"), "{err}");
    let (blocks, _) = run("3", &["--shadowed-blocks"]);
    assert!(blocks > 0);
    let (ok, _, err) = radiosity(&[
        "inspect",
        "--scene",
        "five-piece",
        "--refine",
        "3",
        "--shadowed-blocks",
        "--no-shadowed-blocks",
    ]);
    assert!(!ok && err.contains("cannot be used with"), "{err}");
}

#[test]
fn a_memory_limit_refuses_before_it_is_passed_and_lets_through_what_fits() {
    // The louvre room at refine 3 (n = 3 584): its compressed operator takes about 40 MB, its
    // dense matrix 0.1 GB.
    let scene = "examples/louvre-room.toml";
    let run = |operator: &str, limit: &str| {
        let args = ["inspect", "--scene", scene, "--refine", "3", "--operator", operator];
        radiosity(&[&args[..], &["--memory-limit", limit, "--json", "-"]].concat())
    };
    for operator in ["dense", "compressed"] {
        let (ok, _, err) = run(operator, "40M");
        assert!(!ok && err.contains("--memory-limit") && err.contains("3584"), "{err}");
    }
    let (ok, out, err) = run("compressed", "1G");
    assert!(ok, "{err}");
    let report: serde_json::Value = serde_json::from_str(&out).unwrap();
    let peak = report["peak_rss_bytes"].as_f64().unwrap();
    assert!(peak > 0.0 && peak < (1u64 << 30) as f64, "{peak}");
    for (limit, needle) in [("12X", "K, M, G or T"), ("manyG", "no size"), ("0", "at least one")] {
        let (ok, _, err) = run("compressed", limit);
        assert!(!ok && err.contains(needle), "{limit}: {err}");
    }
}

/// The size after `after` in `text` ("12.3 MiB", "1.50 GiB", "800.0 KiB"), in bytes.
fn size_after(text: &str, after: &str) -> f64 {
    let at = text.find(after).unwrap_or_else(|| panic!("'{after}' not in: {text}")) + after.len();
    let mut words = text[at..].split_whitespace();
    let number: f64 = words.next().unwrap().parse().unwrap();
    let unit = match words.next().unwrap().trim_end_matches([',', ')', ';', ':']) {
        "KiB" => 1u64 << 10,
        "MiB" => 1 << 20,
        "GiB" => 1 << 30,
        other => panic!("unit '{other}' in: {text}"),
    };
    number * unit as f64
}

#[test]
fn a_compressed_build_is_estimated_first_and_refused_when_the_estimate_cannot_fit() {
    // The five-piece surface at refine 3 (n = 640): the estimate is a note and a JSON key.
    let args = ["inspect", "--scene", "five-piece", "--refine", "3", "--operator", "compressed"];
    let (ok, out, err) = radiosity(&[&args[..], &["--json", "-"]].concat());
    assert!(ok && err.contains("memory estimate: about"), "{err}");
    let report: Value = serde_json::from_str(&out).unwrap();
    let estimate = report["memory_estimate_bytes"].as_f64().unwrap();
    let stored = report["operator_bytes"].as_f64().unwrap();
    assert!(estimate >= 0.5 * stored, "estimate {estimate}, stored {stored}");
    // A limit below the estimate: refused before the plan is walked, naming what it needs
    // above what may be used, and what would fit.
    let started = std::time::Instant::now();
    let (ok, out, err) = radiosity(&[&args[..], &["--memory-limit", "1M", "--json", "-"]].concat());
    assert!(!ok && out.is_empty(), "{out}");
    let (needed, available) = (size_after(&err, "would need about "), size_after(&err, "but "));
    assert!(needed > available, "{err}");
    for needle in
        ["640 unknowns", "may be used (--memory-limit 1.0 MiB less the", "it would fit with"]
    {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert!(started.elapsed().as_secs_f64() < 30.0);
    let solved = json(&[
        "solve",
        "--scene",
        "five-piece",
        "--refine",
        "3",
        "--operator",
        "compressed",
        "--json",
        "-",
    ]);
    assert!(solved["memory_estimate_bytes"].as_f64().unwrap() > 0.0, "{solved}");
    // The dense matrix reports none.
    let v = json(&["inspect", "--scene", "five-piece", "--refine", "2", "--json", "-"]);
    assert!(v["memory_estimate_bytes"].is_null() && v["operator"] == "dense", "{v}");
}

#[test]
fn a_saved_operator_reloads_to_the_same_solution_and_only_for_its_problem() {
    let dir = std::env::temp_dir().join(format!("radiosity-saved-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let solve_from = |file: &str| {
        radiosity(&["solve", "--scene", "five-piece", "--refine", "3", "--operator-file", file])
    };
    let solve = |extra: &[&str]| {
        let mut args = vec!["solve", "--scene", "five-piece", "--refine", "3", "--json", "-"];
        args.extend(extra);
        json(&args)
    };
    for (operator, exact) in [("dense", true), ("compressed", false)] {
        let file = path(&format!("{operator}.bin"));
        let (ok, _, stderr) = radiosity(&[
            "assemble",
            "--scene",
            "five-piece",
            "--refine",
            "3",
            "--operator",
            operator,
            "--save",
            &file,
        ]);
        assert!(ok && stderr.contains(&format!("saved the {operator} operator")), "{stderr}");
        let loaded = solve(&["--operator-file", &file, "--solver", "iterative"]);
        let built = solve(&["--operator", operator, "--solver", "iterative"]);
        assert_eq!(loaded["operator"], operator);
        assert_eq!(loaded["operator_bytes"], built["operator_bytes"]);
        let (a, b) = (loaded["error"].as_f64().unwrap(), built["error"].as_f64().unwrap());
        // The compressed product's parallel sums are not ordered from run to run.
        assert!(if exact { a == b } else { (a - b).abs() <= 1e-12 * b }, "{operator}: {a} {b}");

        // Another problem, another kind or tolerance: refused, naming what differs.
        for (args, says) in [
            (
                vec!["--scene", "five-piece", "--refine", "2"],
                "refine 3 (this run: uniform refine 2)",
            ),
            (
                vec!["--scene", "four-piece", "--refine", "3"],
                "scene five-piece (this run: four-piece)",
            ),
            (
                vec!["--scene", "five-piece", "--refine", "3", "--method", "linear"],
                "(this run: linear",
            ),
            (vec!["--scene", "five-piece", "--refine", "3", "--imt-nodes", "64"], "integrals"),
        ] {
            let mut all = vec!["solve"];
            all.extend(args);
            all.extend(["--operator-file", file.as_str()]);
            let (ok, _, stderr) = radiosity(&all);
            assert!(!ok && stderr.contains(says), "{operator} {all:?}: {stderr}");
        }
        let other = if exact { "compressed" } else { "dense" };
        let (ok, _, stderr) = radiosity(&[
            "solve",
            "--scene",
            "five-piece",
            "--refine",
            "3",
            "--operator",
            other,
            "--operator-file",
            &file,
        ]);
        assert!(!ok && stderr.contains(&format!("this run asks for the {other} one")), "{stderr}");

        // Cut anywhere, or damaged: refused with what is wrong, never a panic or a wrong answer.
        let bytes = std::fs::read(&file).unwrap();
        let cut = path("cut.bin");
        for k in 1..=24 {
            let at = bytes.len() * k / 25;
            std::fs::write(&cut, &bytes[..at]).unwrap();
            let (ok, _, stderr) = solve_from(&cut);
            assert!(
                !ok && stderr.starts_with("error: ")
                    && ["truncated", "damaged", "not an operator file"]
                        .iter()
                        .any(|s| stderr.contains(s)),
                "{operator} cut at {at}: {stderr}"
            );
        }
    }
    let (ok, _, stderr) = solve_from("README.md");
    assert!(!ok && stderr.contains("README.md: not an operator file of radiosity"), "{stderr}");
    let (ok, _, stderr) = radiosity(&["assemble", "--scene", "five-piece", "--refine", "1"]);
    assert!(!ok && stderr.contains("give --output K.npy"), "{stderr}");
    let (ok, _, stderr) = radiosity(&[
        "assemble",
        "--scene",
        "five-piece",
        "--operator",
        "compressed",
        "--output",
        "k.npy",
    ]);
    assert!(!ok && stderr.contains("the .npy file holds the dense matrix"), "{stderr}");
}
