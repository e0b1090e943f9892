//! The command-line contract (ARCHITECTURE.md, "The command line"): JSON keys, the paper's numbers, identities and
//! clear errors, through the real binary.

use crate::common;

use common::{json, radiosity};
use serde_json::Value;

#[test]
fn table_3_1_up_to_n_160_matches_the_paper_within_half_a_percent() {
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
        assert!((e - p).abs() <= 0.005 * p, "{}: n = {}: {e} vs paper {p}", r["surface"], r["n"]);
    }
    let surfaces: Vec<&str> = rows.iter().map(|r| r["surface"].as_str().unwrap()).collect();
    assert!(surfaces.contains(&"four-piece") && surfaces.contains(&"five-piece"));
}

#[test]
fn table_3_4_up_to_n_160_matches_the_paper_within_half_a_percent() {
    let v = json(&["study", "table-3.4", "--max-n", "160", "--json", "-"]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6);
    for r in rows {
        assert_eq!(r["dof"].as_u64().unwrap(), 3 * r["n"].as_u64().unwrap());
        let (e, p) = (r["error"].as_f64().unwrap(), r["paper_error"].as_f64().unwrap());
        assert!((e - p).abs() <= 0.005 * p, "{}: n = {}: {e} vs paper {p}", r["surface"], r["n"]);
    }
}

#[test]
fn table_3_3_up_to_n_480_matches_the_paper_within_1_percent() {
    let v = json(&["study", "table-3.3", "--max-n", "480", "--json", "-"]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 6, "uniform n = 10, 40, 160 and discontinuity n = 30, 120, 480");
    for r in rows {
        let (e, p) = (r["error"].as_f64().unwrap(), r["paper_error"].as_f64().unwrap());
        assert!((e - p).abs() <= 0.01 * p, "{}: n = {}: {e} vs paper {p}", r["mesh"], r["n"]);
    }
    // The paper's S5 diagonals matter: with the uniform mesh's, E_n at n = 120 is 30% lower.
    let other = json(&[
        "solve",
        "--scene",
        "five-piece",
        "--mesh",
        "discontinuity-uniform-diagonals",
        "--solution",
        "edge",
        "--beta",
        "0.5",
        "--refine",
        "1",
        "--json",
        "-",
    ]);
    assert_eq!(other["mesh"], "discontinuity-uniform-diagonals");
    let e = other["error"].as_f64().unwrap();
    assert!((e - 0.0178).abs() < 1e-4, "uniform-diagonal discontinuity mesh, n = 120: {e}");
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
        (
            &["solve", "--scene", "four-piece", "--quadrature", "gauss", "--max-level", "9"],
            "max-level",
        ),
        (
            &["solve", "--scene", "four-piece", "--quadrature", "gauss", "--near-ratio", "0"],
            "near-ratio",
        ),
        (
            &["solve", "--scene", "four-piece", "--quadrature", "seven-point", "--backend", "gpu"],
            "exact method only",
        ),
        (&["solve", "--scene", "four-piece", "--surface-lattice", "2"], "surface-lattice"),
        (
            &["solve", "--scene", "four-piece", "--alpha", "0.1"],
            "alpha belongs to the linear method",
        ),
        (
            &["solve", "--scene", "four-piece", "--solution", "x2y2", "--beta", "1"],
            "beta and gamma belong to the shadow or edge solution",
        ),
        (&["solve", "--scene", "four-piece", "--mesh", "fine"], "[possible values: uniform,"),
        (&["solve", "--scene", "five-piece", "--solution", "edge", "--gamma", "1"], "no gamma"),
        (
            &["solve", "--scene", "four-piece", "--solution", "shadow", "--beta", "nan"],
            "beta = NaN",
        ),
        (&["solve", "--scene", "four-piece", "--params", "nan,2,1"], "(NaN, 2, 1)"),
        (&["solve", "--scene", "five-piece", "--refine", "8", "--operator", "dense"], "3200.0 GiB"),
        (
            &["solve", "--scene", "cube", "--compression-tolerance", "0"],
            "compression tolerance = 0",
        ),
        (&["solve", "--scene", "cube", "--compression-tolerance", "1.5"], "must lie in (0, 1)"),
        (
            &["solve", "--scene", "cube", "--operator", "compressed", "--solver", "lu"],
            "LU needs the dense matrix",
        ),
        (
            &[
                "solve",
                "--scene",
                "cube",
                "--operator",
                "compressed",
                "--backend",
                "gpu",
                "--quadrature",
                "gauss",
            ],
            "the GPU backend evaluates the exact method only",
        ),
        (&["study", "stiff", "--backend", "cpu", "--max-n", "x"], "--max-n"),
        (&["study", "stiff", "--max-n", "100"], "--max-n belongs to the paper's tables"),
        (&["study", "estimates", "--backend", "gpu"], "--backend belongs to the paper's"),
        (&["study", "cities", "--figures", "x"], "--figures belongs to"),
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

fn rows_of<'a>(v: &'a Value, quadrature: &str, max_level: Option<u64>) -> Vec<&'a Value> {
    v["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["quadrature"] == quadrature && r["max_level"].as_u64() == max_level)
        .collect()
}

fn within(r: &Value, tolerance: f64) {
    let (e, p) = (r["error"].as_f64().unwrap(), r["paper_error"].as_f64().unwrap());
    assert!((e - p).abs() <= tolerance * p, "{}: n = {}: {e} vs paper {p}", r["series"], r["n"]);
}

#[test]
fn table_4_1_matches_the_paper_for_all_three_integration_methods() {
    let v = json(&["study", "table-4.1", "--max-n", "640", "--backend", "cpu", "--json", "-"]);
    for (quadrature, max_level) in [("exact", None), ("seven-point", Some(3)), ("gauss", Some(3))] {
        let rows = rows_of(&v, quadrature, max_level);
        assert_eq!(rows.len(), 4, "{quadrature}: n = 10, 40, 160, 640");
        for r in rows.iter().filter(|r| r["n"] != 10) {
            within(r, 0.01);
            assert!(r["paper_setup_seconds"].as_f64().is_some());
            assert!(r["setup_seconds"].as_f64().unwrap() > 0.0);
            if quadrature == "gauss" {
                assert_eq!(r["ibase"], 1);
            }
            // The paper's settings integrate to about 1e-3: visible, and not rounding error.
            let int = r["integration_error"].as_f64();
            match quadrature {
                "exact" => assert!(int.is_none(), "the exact CPU rows are the reference"),
                _ => assert!(int.unwrap() > 1e-4 && int.unwrap() < 1e-2, "{r}"),
            }
        }
    }
    let gpu = v["series"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["series"].as_str().unwrap().contains("gpu"));
    assert!(gpu.unwrap()["skipped"].as_str().unwrap().contains("the CPU was asked for"));
}

#[test]
fn table_4_2_reproduces_the_gauss_method_losing_accuracy_at_max_level_4() {
    let v = json(&["study", "table-4.2", "--max-n", "640", "--backend", "cpu", "--json", "-"]);
    for (quadrature, max_level) in [("exact", None), ("gauss", Some(4)), ("gauss", Some(5))] {
        let rows = rows_of(&v, quadrature, max_level);
        assert_eq!(rows.len(), 4, "{quadrature} {max_level:?}: n = 10, 40, 160, 640");
        for r in rows {
            within(r, 0.01);
        }
    }
    let at_640 = |max_level| {
        rows_of(&v, "gauss", Some(max_level)).iter().find(|r| r["n"] == 640).unwrap()["error"]
            .as_f64()
            .unwrap()
    };
    assert!(at_640(4) > 4.0 * at_640(5), "MaxLev 4 loses accuracy at n = 640, MaxLev 5 not");
}

#[test]
fn table_3_5_follows_the_caption_the_edge_solution_converges_at_half_order() {
    let v = json(&["study", "table-3.5", "--max-n", "640", "--json", "-"]);
    let five: Vec<&Value> =
        v["rows"].as_array().unwrap().iter().filter(|r| r["surface"] == "five-piece").collect();
    assert_eq!(five.len(), 4);
    for r in &five[1..] {
        for key in ["surface", "mesh", "n", "error", "ratio"] {
            assert!(!r[key].is_null(), "row lacks {key}: {r}");
        }
        let ratio = r["ratio"].as_f64().unwrap();
        assert!((ratio - 2f64.sqrt()).abs() < 0.02, "O(h^0.5) expected: ratio {ratio}");
    }
    assert!(v["notes"][0].as_str().unwrap().contains("caption"));
}

#[test]
fn figure_studies_write_png_and_svg_and_fit_rates() {
    let dir = std::env::temp_dir().join(format!("radiosity-figures-{}", std::process::id()));
    let dir_text = dir.to_str().unwrap();
    let v = json(&["study", "figure-3.4", "--max-n", "160", "--figures", dir_text, "--json", "-"]);
    let meshes: Vec<&str> =
        v["rows"].as_array().unwrap().iter().map(|r| r["mesh"].as_str().unwrap()).collect();
    assert!(meshes.contains(&"uniform") && meshes.contains(&"discontinuity"));
    for s in v["series"].as_array().unwrap() {
        // Centroid collocation on the 5-piece surface: about O(h) (paper (2.30)).
        let rate = s["rate"].as_f64().unwrap();
        assert!(rate > 0.5 && rate < 1.5, "{s}");
    }
    let png = std::fs::read(dir.join("figure-3.4.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert!(png.len() > 10_000, "a real picture, not an empty canvas");
    let svg = std::fs::read_to_string(dir.join("figure-3.4.svg")).unwrap();
    assert!(svg.starts_with("<svg") && svg.contains("uniform, nodes"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn figure_3_7_measures_the_error_over_all_of_s() {
    let dir = std::env::temp_dir().join(format!("radiosity-figure-37-{}", std::process::id()));
    let v = json(&[
        "study",
        "figure-3.7",
        "--max-n",
        "100",
        "--figures",
        dir.to_str().unwrap(),
        "--json",
        "-",
    ]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2 + 2 + 2 + 1, "n = 8, 32 | 24, 96 | 10, 40 | 30");
    for r in rows {
        let nodes = r["error"].as_f64().unwrap();
        let over = r["surface_error"].as_f64().unwrap();
        let iterated = r["iterated_error"].as_f64().unwrap();
        // u_n is worse between the nodes than at them; the iterated solution is not.
        assert!(over > 2.0 * nodes, "{r}");
        assert!(iterated < 3.0 * nodes && iterated >= 0.5 * nodes, "{r}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn error_vs_time_marks_a_pareto_front_per_method() {
    let dir = std::env::temp_dir().join(format!("radiosity-evt-{}", std::process::id()));
    let v = json(&[
        "study",
        "error-vs-time",
        "--max-n",
        "40",
        "--backend",
        "cpu",
        "--figures",
        dir.to_str().unwrap(),
        "--json",
        "-",
    ]);
    let rows = v["rows"].as_array().unwrap();
    for method in ["centroid", "linear"] {
        let of_method: Vec<&Value> = rows.iter().filter(|r| r["method"] == method).collect();
        assert!(of_method.len() >= 20, "{method}: {} rows", of_method.len());
        let front: Vec<&&Value> = of_method.iter().filter(|r| r["pareto"] == true).collect();
        assert!(!front.is_empty());
        // Nothing off the front is both faster and more accurate than a point on it.
        for f in &front {
            let (t, e) = (f["setup_seconds"].as_f64().unwrap(), f["error"].as_f64().unwrap());
            assert!(!of_method.iter().any(|r| {
                let (s, g) = (r["setup_seconds"].as_f64().unwrap(), r["error"].as_f64().unwrap());
                s < t && g < e
            }));
        }
    }
    assert!(dir.join("error-vs-time.png").exists() && dir.join("error-vs-time.svg").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_stability_study_passes_its_bounds_on_the_cpu() {
    let v = json(&["study", "stability", "--backend", "cpu", "--json", "-"]);
    let rows = v["rows"].as_array().unwrap();
    let mut cases: Vec<&str> = rows.iter().map(|r| r["case"].as_str().unwrap()).collect();
    cases.dedup();
    assert!(cases.len() >= 20, "{} cases", cases.len());
    for r in rows {
        for key in ["case", "backend", "precision", "relative_error", "bound"] {
            assert!(!r[key].is_null(), "row lacks {key}: {r}");
        }
        assert_eq!(r["backend"], "cpu");
        let (e, b) = (r["relative_error"].as_f64().unwrap(), r["bound"].as_f64().unwrap());
        assert!(e <= b, "{} ({}): {e} > {b}", r["case"], r["method"]);
        assert!(b < 1.0, "{}: a vacuous bound {b}", r["case"]);
    }
    assert_eq!(v["failed"], 0);
    // The rules that replace the closed forms where these cancel save digits: the thin element
    // and the far node lose at least 4 digits with closed forms everywhere, none with the rules.
    for case in ["sliver 1e6, far", "far away (1e4)"] {
        let r = rows
            .iter()
            .find(|r| r["case"] == case && r["method"] == "linear")
            .unwrap_or_else(|| panic!("no row {case}"));
        let (ours, closed) =
            (r["relative_error"].as_f64().unwrap(), r["closed_forms_error"].as_f64().unwrap());
        assert!(
            ours < 1e-14 && closed > 1e-12 && closed > 1e4 * ours,
            "{case}: {ours} vs {closed}"
        );
    }
}

#[test]
fn the_stiff_study_shows_conditioning_and_refuses_singular_systems() {
    let v = json(&["study", "stiff", "--json", "-"]);
    let rows = v["rows"].as_array().unwrap();
    let closed: Vec<&Value> = rows.iter().filter(|r| r["case"] == "cube").collect();
    assert!(closed.len() >= 5);
    let mut last = 0.0;
    for r in &closed {
        let rho = r["rho"].as_f64().unwrap();
        if rho == 1.0 {
            assert!(r["status"].as_str().unwrap().contains("singular"), "{r}");
            assert!(r["error_refined"].is_null());
            continue;
        }
        assert_eq!(r["status"], "solved");
        let kappa = r["condition_estimate"].as_f64().unwrap();
        assert!(kappa > last, "condition must grow as rho -> 1: {kappa} after {last}");
        // Near 1/(1 - rho): the constant mode of K has eigenvalue rho.
        assert!(kappa * (1.0 - rho) > 0.5 && kappa * (1.0 - rho) < 50.0, "rho {rho}: {kappa}");
        last = kappa;
        let (e, b) = (r["error_refined"].as_f64().unwrap(), r["bound"].as_f64().unwrap());
        assert!(e <= b, "rho {rho}: refined error {e} above its bound {b}");
        // Both errors are at rounding level here; refinement may move the last digits.
        assert!(
            e <= 1.5 * r["error_lu"].as_f64().unwrap() + 1e-15,
            "refinement must not lose digits: {r}"
        );
    }
    // GMRES agrees with LU on every solved row, to its tolerance (1e-13) times the condition.
    let solved: Vec<&Value> = rows.iter().filter(|r| r["status"] == "solved").collect();
    assert!(solved.len() >= 30, "{} solved rows", solved.len());
    for r in &solved {
        let kappa = r["condition_estimate"].as_f64().unwrap();
        let diff = r["gmres_vs_lu"].as_f64().unwrap_or_else(|| panic!("no GMRES in {r}"));
        assert!(diff <= 1e-13 * kappa.max(10.0), "{r}");
        assert!(r["gmres_iterations"].as_u64().unwrap() <= 60, "{r}");
    }
    // A black lamp (rho = 0) among faces with rho -> 1: its rows are taken out, and GMRES agrees
    // with LU to 1e-12 whatever rho the other faces have, rho = 1 included.
    let black: Vec<&Value> =
        rows.iter().filter(|r| r["case"].as_str().unwrap().contains("black")).collect();
    assert_eq!(black.len(), 14);
    for r in &black {
        assert_eq!(r["status"], "solved", "{r}");
        assert!(r["rows_eliminated"].as_u64().unwrap() > 0, "{r}");
        assert!(r["gmres_vs_lu"].as_f64().unwrap() <= 1e-12, "{r}");
    }
    // An open box stays regular at rho = 1.
    let open = rows
        .iter()
        .find(|r| r["rho"] == 1.0 && r["case"].as_str().unwrap().contains("open"))
        .unwrap();
    assert_eq!(open["status"], "solved");
    assert!(open["condition_estimate"].as_f64().unwrap() < 1e3);
}

#[test]
fn solve_reports_the_condition_estimate_of_a_closed_box() {
    // The baffled box is closed with rho = 0.5, so it solves (the singular case, rho = 1, is
    // refused in the stiff study's test above); the report carries the condition estimate.
    let v = json(&["solve", "--scene", "baffled-box", "--refine", "1", "--json", "-"]);
    let kappa = v["condition_estimate"].as_f64().unwrap();
    assert!(kappa > 1.0 && kappa < 10.0, "rho = 0.5 inside a closed box: condition {kappa}");
}

/// `study ID --help` lists the options that study takes and none of the others'.
#[test]
fn each_study_s_help_shows_its_own_options() {
    let cases: [(&str, &[&str]); 4] = [
        ("estimates", &["--seeds", "--scene", "--tolerances"]),
        (
            "compression",
            &[
                "--scene",
                "--tolerances",
                "--shadowed-blocks",
                "--max-n",
                "--backend",
                "--precision",
                "--figures",
            ],
        ),
        ("table-3.1", &["--max-n", "--backend", "--precision", "--figures"]),
        ("stability", &["--backend", "--precision"]),
    ];
    let every = [
        "--max-n",
        "--backend",
        "--precision",
        "--figures",
        "--scene",
        "--tolerances",
        "--seeds",
        "--shadowed-blocks",
    ];
    for (id, own) in cases {
        for flag in ["--help", "-h"] {
            let (ok, help, err) = radiosity(&["study", id, flag]);
            assert!(ok && help.contains(&format!("radiosity study {id}")), "{id}: {err}");
            assert!(help.contains("--json") && help.contains("--markdown"), "{id}: {help}");
            for option in every {
                let shown =
                    help.contains(&format!("{option} ")) || help.contains(&format!("{option}\n"));
                assert_eq!(shown, own.contains(&option), "{id} {flag}: {option} in\n{help}");
            }
        }
    }
}
