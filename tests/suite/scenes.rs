//! Real scenes through the command line: scene files, outputs, view factors, the occluder index,
//! automatic discontinuity meshing and graded meshes, imperfect and far-off scenes, a lit city,
//! the louvre room and triangle soups merged into faces.

use std::path::PathBuf;

use serde_json::Value;

use crate::common;

use common::{json, radiosity, temp_dir, translated_scene};

#[test]
fn the_five_piece_surface_from_a_file_gives_the_built_in_numbers() {
    for method in ["centroid", "linear"] {
        let run = |scene: &str| {
            json(&[
                "solve",
                "--scene",
                scene,
                "--solution",
                "x2y2",
                "--method",
                method,
                "--refine",
                "2",
                "--json",
                "-",
            ])
        };
        let (file, builtin) = (run("examples/five-piece.toml"), run("five-piece"));
        assert_eq!(file["n"], builtin["n"]);
        assert_eq!(file["error"], builtin["error"], "{method}");
        assert_eq!(file["solution_range"], builtin["solution_range"], "{method}");
    }
}

/// `inspect` of a closed scene file at `refine`, whose rows of K/rho must sum to 1 within 1e-12
/// (Lemma 2.1), as JSON.
fn inspect_closed_scene(scene: &str, refine: &str) -> serde_json::Value {
    let v = json(&["inspect", "--scene", scene, "--refine", refine, "--json", "-"]);
    let (lo, hi) = (v["row_sum_min"].as_f64().unwrap(), v["row_sum_max"].as_f64().unwrap());
    assert!(lo > 1.0 - 1e-12 && hi < 1.0 + 1e-12, "{scene} refine {refine}: {lo} {hi}");
    v
}

#[test]
fn the_staircase_hall_closes_and_its_steps_shadow_in_part() {
    // A scene written for checks that no code was tuned for: a free-standing staircase in a
    // closed hall (the floor cut around its footprint, its sides non-convex), lit by a window.
    let v = inspect_closed_scene("examples/staircase-hall.toml", "1");
    assert!(
        v["pairs_partial"].as_u64().unwrap() > 1000 && v["pairs_hidden"].as_u64().unwrap() > 1000
    );
}

#[test]
fn the_louvre_window_closes_and_its_slats_shadow_the_room_in_part() {
    // The window fills its opening in the east wall, so the room is closed (Lemma 2.1), and the
    // slats hanging inside it shadow in part the pairs between the window and the room.
    for refine in ["1", "2"] {
        let v = inspect_closed_scene("examples/louvre-window.toml", refine);
        assert!(v["n"].as_u64() == Some(40 << (2 * refine.parse::<u32>().unwrap())), "{v}");
        assert!(
            v["pairs_partial"].as_u64().unwrap() > 1000
                && v["pairs_hidden"].as_u64().unwrap() > 1000,
            "{v}"
        );
    }
}

#[test]
fn the_furnished_room_closes_sees_exactly_and_writes_its_outputs() {
    let v = inspect_closed_scene("examples/furnished-room.toml", "1");
    assert!(v["pairs_partial"].as_u64().unwrap() > 0 && v["pairs_hidden"].as_u64().unwrap() > 0);

    let dir = temp_dir("room");
    let (png, vtu, csv) = (dir.join("room.png"), dir.join("room.vtu"), dir.join("room.csv"));
    let r = json(&[
        "solve",
        "--scene",
        "examples/furnished-room.toml",
        "--refine",
        "1",
        "--png",
        png.to_str().unwrap(),
        "--png-size",
        "600x400",
        "--vtu",
        vtu.to_str().unwrap(),
        "--csv",
        csv.to_str().unwrap(),
        "--json",
        "-",
    ]);
    let n = r["n"].as_u64().unwrap() as usize;
    // The lamp emits 1 and reflects 0.2 of what it receives; everything else is lit by it.
    let [lo, _, hi] = [0, 1, 2].map(|k| r["solution_range"][k].as_f64().unwrap());
    assert!(lo > 0.0 && hi > 1.0 && hi < 1.2, "{lo} {hi}");

    let image = image::open(&png).unwrap().to_rgb8();
    assert_eq!(image.dimensions(), (600, 400));
    let coloured = image.pixels().filter(|p| p.0 != [255, 255, 255]).count();
    assert!(coloured > 600 * 400 / 5, "the room fills the picture: {coloured} pixels");

    let text = std::fs::read_to_string(&vtu).unwrap();
    assert!(text.contains(&format!("NumberOfCells=\"{n}\"")));
    assert!(text.contains("Name=\"u\"") && text.contains("Name=\"rho\""));

    let rows: Vec<String> =
        std::fs::read_to_string(&csv).unwrap().lines().map(String::from).collect();
    assert_eq!(rows.len(), n + 1);
    assert_eq!(rows[0], "node,element,face,x,y,z,rho,E,u");
    let u_max = rows[1..]
        .iter()
        .map(|l| l.rsplit(',').next().unwrap().parse::<f64>().unwrap())
        .fold(f64::NEG_INFINITY, f64::max);
    assert_eq!(u_max, hi);
}

#[test]
fn view_factors_of_howell_c11_and_a_closed_box() {
    let dir = temp_dir("vf");
    let scene = dir.join("c11.toml");
    std::fs::write(
        &scene,
        "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[1,1,0],[0,1,0]]\n\
         [[faces]]\nname = \"b\"\nvertices = [[0,0,1],[0,1,1],[1,1,1],[1,0,1]]\n",
    )
    .unwrap();
    let (ok, out, err) =
        radiosity(&["viewfactors", "--scene", scene.to_str().unwrap(), "--refine", "1"]);
    assert!(ok, "{err}");
    assert!(out.contains("0.1998248957"), "{out}");
    // Each direction integrated on its own: reciprocity measures the accuracy.
    let args =
        ["viewfactors", "--scene", "cube", "--refine", "0", "--each-direction", "--json", "-"];
    let v = json(&args);
    let (lo, hi) = (v["row_sum_min"].as_f64().unwrap(), v["row_sum_max"].as_f64().unwrap());
    assert!(lo > 1.0 - 1e-10 && hi < 1.0 + 1e-10, "{lo} {hi}");
    assert!(v["each_direction"].as_bool().unwrap(), "{v}");
    let reciprocity = v["reciprocity_error"].as_f64().unwrap();
    assert!(reciprocity > 0.0 && reciprocity < 1e-9, "{v}");
    let (ok, _, err) = radiosity(&["viewfactors", "--scene", "cube", "--output", "F.txt"]);
    assert!(!ok && err.contains(".npy, .csv, .npz (sparse CSR) or .mtx"), "{err}");
    // Only the options view factors use: the scene and its mesh, not the collocation method
    // and its quadrature, which would be ignored.
    let (ok, help, err) = radiosity(&["viewfactors", "--help"]);
    assert!(ok, "{err}");
    for option in ["--scene", "--refine", "--mesh", "--grade", "--coplanar", "--tolerance"] {
        assert!(help.contains(option), "{option} missing from:\n{help}");
    }
    for option in ["--method", "--alpha", "--quadrature", "--max-level", "--ibase", "--imt-nodes"] {
        assert!(!help.contains(option), "{option} offered by:\n{help}");
    }
    let (ok, _, err) = radiosity(&["viewfactors", "--scene", "cube", "--method", "linear"]);
    assert!(!ok && err.contains("--method"), "{err}");
}

/// The arrays of a NumPy `.npz` archive by name, as npyz reads each `.npy` in it.
fn npz_arrays(path: &std::path::Path) -> std::collections::HashMap<String, Vec<u8>> {
    use std::io::Read;
    let mut zip = zip::ZipArchive::new(std::fs::File::open(path).unwrap()).unwrap();
    (0..zip.len())
        .map(|k| {
            let mut entry = zip.by_index(k).unwrap();
            let mut bytes = Vec::new();
            entry.read_to_end(&mut bytes).unwrap();
            (entry.name().to_string(), bytes)
        })
        .collect()
}

fn npy_values<T: npyz::Deserialize>(bytes: &[u8]) -> Vec<T> {
    npyz::NpyFile::new(bytes).unwrap().into_vec().unwrap()
}

#[test]
fn sparse_view_factors_hold_the_dense_output_s_non_zero_entries() {
    // A closed box: every pair of elements of one face is zero (coplanar), and the sparse files
    // leave those entries out.
    let dir = temp_dir("vf-sparse");
    let file = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let base = ["viewfactors", "--scene", "cube", "--refine", "0", "--output"];
    for name in ["F.npy", "F.npz", "F.mtx"] {
        let (ok, _, err) = radiosity(&[&base[..], &[file(name).as_str()]].concat());
        assert!(ok, "{name}: {err}");
    }
    let dense: Vec<f64> = npy_values(&std::fs::read(file("F.npy")).unwrap());
    let n = (dense.len() as f64).sqrt() as usize;
    let nonzeros = dense.iter().filter(|&&v| v != 0.0).count();
    assert!(nonzeros < dense.len() && nonzeros > 0, "{nonzeros} of {}", dense.len());
    // The npz: SciPy's CSR arrays, rebuilding every entry bit for bit.
    let arrays = npz_arrays(&dir.join("F.npz"));
    let mut names: Vec<&str> = arrays.keys().map(String::as_str).collect();
    names.sort_unstable();
    assert_eq!(
        names,
        [
            "data.npy",
            "format.npy",
            "indices.npy",
            "indptr.npy",
            "shape.npy",
            "sky_view_factors.npy"
        ]
    );
    // Beside the matrix, each element's sky view factor: 1 less its row's sum (0 in a box).
    let sky: Vec<f64> = npy_values(&arrays["sky_view_factors.npy"]);
    let row_sums: Vec<f64> = dense.chunks(n).map(|row| row.iter().sum()).collect();
    assert!(
        sky.iter().zip(&row_sums).all(|(s, r)| (s - (1.0 - r)).abs() <= 1e-15 && s.abs() < 1e-9)
    );
    let shape: Vec<i64> = npy_values(&arrays["shape.npy"]);
    assert_eq!(shape, vec![n as i64, n as i64]);
    // A 0-d array of the bytes "csr", as numpy writes `np.array(b"csr")`.
    let format = &arrays["format.npy"];
    let header = String::from_utf8_lossy(&format[10..format.len() - 3]);
    assert!(header.contains("'descr': '|S3'") && header.contains("'shape': ()"), "{header}");
    assert!(format.ends_with(b"csr"));
    let data: Vec<f64> = npy_values(&arrays["data.npy"]);
    let indices: Vec<i64> = npy_values(&arrays["indices.npy"]);
    let indptr: Vec<i64> = npy_values(&arrays["indptr.npy"]);
    assert_eq!((data.len(), indptr.len()), (nonzeros, n + 1));
    let mut rebuilt = vec![0.0; n * n];
    for i in 0..n {
        for k in indptr[i] as usize..indptr[i + 1] as usize {
            rebuilt[i * n + indices[k] as usize] = data[k];
        }
    }
    assert_eq!(rebuilt, dense);
    // The Matrix Market file: the same entries, 1-based, each value read back exactly.
    let mtx = std::fs::read_to_string(file("F.mtx")).unwrap();
    let mut lines = mtx.lines().filter(|l| !l.starts_with('%'));
    assert_eq!(lines.next().unwrap(), format!("{n} {n} {nonzeros}"));
    let mut from_mtx = vec![0.0; n * n];
    for line in lines {
        let f: Vec<&str> = line.split(' ').collect();
        let (i, j): (usize, usize) = (f[0].parse().unwrap(), f[1].parse().unwrap());
        from_mtx[(i - 1) * n + j - 1] = f[2].parse().unwrap();
    }
    assert_eq!(from_mtx, dense);
    let v = json(&["viewfactors", "--scene", "cube", "--refine", "0", "--json", "-"]);
    assert_eq!(v["nonzeros"].as_u64(), Some(nonzeros as u64), "{v}");
}

/// An open scene's sky view factors as CSV and in the summary, the matrix conditioned for
/// closure and its small entries dropped, each said in the JSON; bad values refused by name.
#[test]
fn view_factors_give_sky_view_factors_and_condition_for_closure() {
    let dir = temp_dir("vf-closure");
    let file = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (sky_csv, matrix) = (file("sky.csv"), file("F.npz"));
    let base = ["viewfactors", "--scene", "city:3x2", "--refine", "0", "--tolerance", "1e-4"];
    let v = json(
        &[
            &base[..],
            &["--each-direction", "--condition", "--drop-below", "1e-4"],
            &["--sky-view-factors", &sky_csv, "--output", &matrix, "--json", "-"],
        ]
        .concat(),
    );
    let estimate = v["error_estimate"].as_f64().unwrap();
    let change = v["conditioning"]["largest_change"].as_f64().unwrap();
    assert!(change > 0.0 && change <= estimate, "{v}");
    assert!(v["reciprocity_error"].as_f64().unwrap() <= 1e-15, "{v}");
    assert!(v["dropped"]["entries"].as_u64().unwrap() > 0, "{v}");
    assert_eq!(v["dropped"]["below"].as_f64(), Some(1e-4), "{v}");
    let (lo, hi) = (v["sky_view_factor_min"].as_f64().unwrap(), v["sky_view_factor_max"].as_f64());
    assert!(lo >= 0.0 && hi == Some(1.0), "{v}");
    // One line per element, the same values as the npz holds beside the matrix.
    let text = std::fs::read_to_string(&sky_csv).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("element,face,area,sky_view_factor"));
    let from_csv: Vec<f64> =
        lines.map(|l| l.rsplit(',').next().unwrap().parse().unwrap()).collect();
    let sky: Vec<f64> =
        npy_values(&npz_arrays(std::path::Path::new(&matrix))["sky_view_factors.npy"]);
    assert_eq!(from_csv.len(), v["n"].as_u64().unwrap() as usize);
    assert_eq!(from_csv, sky);
    for (option, value, says) in [
        ("--drop-below", "2", "drop-below"),
        ("--drop-below", "nan", "drop-below"),
        ("--sky-view-factors", "sky.txt", ".csv or .npy"),
    ] {
        let (ok, _, err) = radiosity(&[&base[..], &[option, value]].concat());
        assert!(!ok && err.contains(says), "{option} {value}: {err}");
    }
}

#[test]
fn view_factors_say_when_their_estimates_miss_the_tolerance() {
    // Howell's C-14 (squares meeting at a right angle along a whole edge): its touching outer
    // triangles meet 1e-10 (the default) but not 1e-16, which rounding alone exceeds.
    let dir = temp_dir("vf-tolerance");
    let scene = dir.join("c14.toml");
    std::fs::write(
        &scene,
        "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[1,1,0],[0,1,0]]\n\
         [[faces]]\nname = \"b\"\nvertices = [[0,0,0],[0,0,1],[1,0,1],[1,0,0]]\n",
    )
    .unwrap();
    let scene = scene.to_str().unwrap();
    let (ok, _, err) = radiosity(&["viewfactors", "--scene", scene, "--refine", "0"]);
    assert!(ok && !err.contains("warning"), "{err}");
    let (ok, _, err) =
        radiosity(&["viewfactors", "--scene", scene, "--refine", "0", "--tolerance", "1e-16"]);
    assert!(ok && err.contains("exceeds --tolerance 1.0e-16"), "{err}");
    // Said before the work starts, too.
    assert!(err.contains("below what f64 arithmetic delivers"), "{err}");
}

#[test]
fn the_occluder_index_gives_the_views_of_the_core_plan() {
    let v = json(&["bench-plan", "--scene", "city:5x4", "--nodes", "12", "--json", "-"]);
    assert_eq!(v["faces"].as_u64().unwrap(), 4 * 20 + 11 * 9);
    assert_eq!(v["identical"], true);
    assert!(v["shadowed_views"].as_u64().unwrap() > 0);
    assert_eq!(v["timings"].as_array().unwrap().len(), 3);
}

#[test]
fn automatic_discontinuity_meshing_reproduces_the_four_piece_rows() {
    for refine in ["0", "1", "2"] {
        let run = |mesh: &[&str]| {
            let mut args =
                vec!["solve", "--scene", "four-piece", "--refine", refine, "--json", "-"];
            args.extend(mesh);
            json(&args)
        };
        let hand = run(&["--mesh", "discontinuity"]);
        let auto = run(&["--mesh", "auto-discontinuity", "--shadow-lines", "chords"]);
        assert_eq!(hand["n"], auto["n"]);
        let (a, b) = (hand["error"].as_f64().unwrap(), auto["error"].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-9 * a, "refine {refine}: {a} vs {b}");
        assert_eq!(auto["mesh"], "auto-discontinuity");
    }
}

#[test]
fn grading_toward_the_common_edge_restores_the_rate_of_the_edge_solution() {
    // (3.4) with beta = 0.5 is singular along y = A, the edge S1 shares with S5: O(h^0.5) on the
    // uniform mesh (ratio 1.41), about O(h) with q = 2.
    let error = |refine: &str, grade: &[&str]| {
        let mut args = vec![
            "solve",
            "--scene",
            "five-piece",
            "--solution",
            "edge",
            "--refine",
            refine,
            "--json",
            "-",
        ];
        args.extend(grade);
        json(&args)["error"].as_f64().unwrap()
    };
    let graded = ["--grade", "S1:2", "--grade", "S5:3", "--grading", "2"];
    let uniform_ratio = error("2", &[]) / error("3", &[]);
    let graded_ratio = error("2", &graded) / error("3", &graded);
    assert!((1.3..1.5).contains(&uniform_ratio), "{uniform_ratio}");
    assert!(graded_ratio > 1.9, "{graded_ratio}");
}

#[test]
fn bad_scene_files_and_options_name_the_culprit() {
    let dir = temp_dir("bad");
    let broken = dir.join("broken.toml");
    std::fs::write(
        &broken,
        "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0]]\n",
    )
    .unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--scene".into(), broken.to_str().unwrap().into()], "broken.toml"),
        (vec!["--scene".into(), "missing.toml".into()], "missing.toml"),
        (vec!["--scene".into(), "city:3".into()], "city:NXxNY"),
        (
            vec!["--scene".into(), "five-piece".into(), "--grade".into(), "S9:0".into()],
            "no face 'S9'",
        ),
        (
            vec!["--scene".into(), "five-piece".into(), "--grade".into(), "S1:7".into()],
            "edges 0 to 3",
        ),
        (
            vec![
                "--scene".into(),
                "cube".into(),
                "--png".into(),
                "/tmp/x.png".into(),
                "--png-size".into(),
                "9x9".into(),
            ],
            "picture size",
        ),
    ];
    let (ok, _, err) = radiosity(&["inspect", "--scene", "cube", "--png", "x.png"]);
    assert!(!ok && err.contains("belong to solve"), "{err}");
    for (extra, expect) in cases {
        let mut args = vec!["solve".to_string(), "--refine".into(), "0".into()];
        args.extend(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (ok, _, err) = radiosity(&args);
        assert!(!ok && err.contains(expect), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
}

/// The occluded box with a black lamp (rho = 0 on the emitting top): BiCGSTAB broke down on it
/// (its shadow residual E lives only on zero rows of K). The lamp's rows are taken out, and the
/// iterative solver agrees with LU to 1e-12.
#[test]
fn a_black_lamp_solves_iteratively_as_with_lu() {
    let dir = temp_dir("black-lamp");
    let scene = std::fs::read_to_string("examples/occluded-box.toml")
        .unwrap()
        .replace("emission = 1.0\n", "emission = 1.0\nrho = 0.0\n");
    assert!(scene.contains("rho = 0.0"));
    let path = dir.join("black-top.toml");
    std::fs::write(&path, scene).unwrap();
    let nodal_u = |solver: &str| -> Vec<f64> {
        let csv = dir.join(format!("{solver}.csv"));
        let (ok, out, err) = radiosity(&[
            "solve",
            "--scene",
            path.to_str().unwrap(),
            "--refine",
            "2",
            "--solver",
            solver,
            "--csv",
            csv.to_str().unwrap(),
        ]);
        assert!(ok, "{err}");
        assert!(out.contains("32 unknowns known as u = E"), "{out}");
        let text = std::fs::read_to_string(&csv).unwrap();
        text.lines().skip(1).map(|l| l.rsplit(',').next().unwrap().parse().unwrap()).collect()
    };
    let (lu, gmres) = (nodal_u("lu"), nodal_u("iterative"));
    assert_eq!(lu.len(), 576);
    let scale = lu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = lu.iter().zip(&gmres).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(diff <= 1e-12 * scale, "GMRES differs from LU by {diff:e} (scale {scale})");
}

/// Survey coordinates: the scene moved rigidly far from the origin gives the same u, to the
/// rounding of the moved input itself (1000 ε |offset| / size), for both methods.
#[test]
fn scenes_far_from_the_origin_give_the_same_solution() {
    let dir = temp_dir("far-from-origin");
    let eps = f64::EPSILON;
    let nodal = |scene: &std::path::Path, method: &str, refine: &str| -> (Vec<f64>, Value) {
        let csv = dir.join("u.csv");
        let v = json(&[
            "solve",
            "--scene",
            scene.to_str().unwrap(),
            "--method",
            method,
            "--refine",
            refine,
            "--csv",
            csv.to_str().unwrap(),
            "--json",
            "-",
        ]);
        let text = std::fs::read_to_string(&csv).unwrap();
        let u = text.lines().skip(1).map(|l| l.rsplit(',').next().unwrap().parse().unwrap());
        (u.collect(), v)
    };
    let cases = [
        ("examples/occluded-box.toml", 2.0 * 3f64.sqrt(), "centroid", "2"),
        ("examples/occluded-box.toml", 2.0 * 3f64.sqrt(), "linear", "1"),
        ("examples/furnished-room.toml", 31.25f64.sqrt(), "centroid", "1"),
    ];
    for (file, size, method, refine) in cases {
        let (base, _) = nodal(&translated_scene(file, [0.0; 3], &dir), method, refine);
        let scale = base.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for offset in [[1e6, 1e6, 1e6], [5e5, 4.2e6, 100.0], [-3e7, 0.0, 2e3]] {
            let (u, _) = nodal(&translated_scene(file, offset, &dir), method, refine);
            let change = base.iter().zip(&u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            let bound = 1000.0 * eps * offset.iter().fold(0.0f64, |m, o| m.max(o.abs())) / size;
            assert!(
                change <= bound * scale,
                "{file} {method} at {offset:?}: u changed by {:.2e} (bound {bound:.1e})",
                change / scale
            );
        }
    }
    // Coordinates that stay exact when moved (multiples of 1/4, offsets of 2^10 and more): the
    // same scene, computed in another frame. Node positions round differently there, so a pair
    // on an exact tie (an element edge on a shadow line) may fall on the other side of it; u
    // stays the same to rounding.
    let box_with_plate = "name = \"plate-box\"\n[defaults]\nrho = 0.5\n\
        [[faces]]\nname = \"bottom\"\nvertices = [[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]]\n\
        [[faces]]\nname = \"top\"\nvertices = [[0, 1, 1], [1, 1, 1], [1, 0, 1], [0, 0, 1]]\nemission = 1.0\n\
        [[faces]]\nname = \"front\"\nvertices = [[0, 0, 1], [1, 0, 1], [1, 0, 0], [0, 0, 0]]\n\
        [[faces]]\nname = \"back\"\nvertices = [[1, 1, 0], [1, 1, 1], [0, 1, 1], [0, 1, 0]]\n\
        [[faces]]\nname = \"left\"\nvertices = [[0, 1, 0], [0, 1, 1], [0, 0, 1], [0, 0, 0]]\n\
        [[faces]]\nname = \"right\"\nvertices = [[1, 0, 1], [1, 1, 1], [1, 1, 0], [1, 0, 0]]\n\
        [[faces]]\nname = \"plate\"\nvertices = [[0.25, 0.25, 0.5], [0.75, 0.25, 0.5], [0.75, 0.75, 0.5], [0.25, 0.75, 0.5]]\nradiates = \"both\"\n";
    std::fs::write(dir.join("plate-box.toml"), box_with_plate).unwrap();
    let original = dir.join("plate-box.toml");
    let (base, v0) = nodal(&original, "centroid", "2");
    let scale = base.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for offset in [[1048576.0, -2097152.0, 1024.0], [8388608.0, 0.0, -4194304.0]] {
        // An absolute path: `translated_scene` joins it to the crate's root, which keeps it.
        let moved = translated_scene(original.to_str().unwrap(), offset, &dir);
        let (u, v) = nodal(&moved, "centroid", "2");
        let class = |v: &Value, key: &str| v["pairs"][key].as_i64().unwrap();
        for key in ["same_plane", "facing_away", "hidden", "total"] {
            assert_eq!(class(&v, key), class(&v0, key), "{key} at {offset:?}");
        }
        let moved_classes = (class(&v, "full") - class(&v0, "full")).abs();
        assert!(moved_classes <= 8, "{moved_classes} pairs changed between full and partial");
        let change = base.iter().zip(&u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(change <= 1e-13 * scale, "plate box at {offset:?}: {:.2e}", change / scale);
    }
}

#[test]
fn imperfect_scenes_are_named_where_they_go_wrong() {
    let dir = temp_dir("imperfect");
    // An OBJ face that refers to a vertex the file lacks: the line is named.
    let obj = dir.join("bad.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n").unwrap();
    let (ok, _, err) = radiosity(&["solve", "--scene", obj.to_str().unwrap()]);
    assert!(
        !ok && err.contains("bad.obj: line 5: face vertex 9") && err.contains("3 vertices"),
        "{err}"
    );
    // A coordinate beyond f64: file, line and column.
    let big = dir.join("big.toml");
    let text = std::fs::read_to_string("examples/occluded-box.toml").unwrap();
    std::fs::write(&big, text.replacen("[2, 2, 0]", "[2, 1e400, 0]", 1)).unwrap();
    let (ok, _, err) = radiosity(&["solve", "--scene", big.to_str().unwrap()]);
    assert!(!ok && err.contains("big.toml") && err.contains("line 10"), "{err}");
    // A lid lying on the floor: warned, naming both faces; the two sides of a plate are not.
    let lid = dir.join("lid.toml");
    let lid_text = "name = \"lid\"\n[defaults]\nrho = 0.5\n\
        [[faces]]\nname = \"floor\"\nvertices = [[1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 0]]\n\
        [[faces]]\nname = \"ceiling\"\nvertices = [[0, 1, 1], [1, 1, 1], [1, 0, 1], [0, 0, 1]]\nemission = 1.0\n\
        [[faces]]\nname = \"lid\"\nvertices = [[0.2, 0.2, 0], [0.2, 0.6, 0], [0.6, 0.6, 0], [0.6, 0.2, 0]]\n";
    std::fs::write(&lid, lid_text).unwrap();
    let (ok, _, err) = radiosity(&["solve", "--scene", lid.to_str().unwrap(), "--refine", "0"]);
    assert!(ok && err.contains("warning: faces 'floor' and 'lid' lie on one another"), "{err}");
    let (ok, _, err) = radiosity(&["solve", "--scene", "baffled-box", "--refine", "0"]);
    assert!(ok && !err.contains("warning"), "{err}");
    // Missing files and unknown names say so, and what else would do.
    for missing in ["no-such-scene.toml", "no-such-mesh.obj"] {
        let (ok, _, err) = radiosity(&["solve", "--scene", missing]);
        assert!(!ok && err.contains(missing) && err.contains("no such file"), "{err}");
    }
    let (ok, _, err) = radiosity(&["solve", "--scene", "nope"]);
    assert!(!ok && err.contains("city:NXxNY") && err.contains("FILE.toml"), "{err}");
    // Nothing emits: said, with how to set emission.
    let (ok, _, err) = radiosity(&["solve", "--scene", "city:1x1", "--refine", "0"]);
    assert!(
        ok && err.contains("no face of 'city-1x1' emits") && err.contains("emission ="),
        "{err}"
    );
}

#[test]
fn a_lit_city_solves_with_light_on_every_street() {
    // The plain city emits nothing (a warning, u = 0); under its sky every face is lit, the
    // ground most where it sees most sky, and u <= E + rho max u keeps it below 1.
    let v = json(&["solve", "--scene", "city:2x2", "--refine", "0", "--json", "-"]);
    assert!(v["warnings"].to_string().contains("no face"), "{v}");
    let v = json(&["solve", "--scene", "city:2x2:lit", "--refine", "0", "--json", "-"]);
    assert_eq!(v["surface"], "city-2x2-lit");
    assert_eq!(v["warnings"].as_array().map(Vec::len), Some(0), "{v}");
    let [lo, _, hi] = [0, 1, 2].map(|k| v["solution_range"][k].as_f64().unwrap());
    assert!(lo >= 0.0 && (hi - 1.0).abs() < 1e-12, "{lo} {hi}: the sky's u is E = 1");
    let dir = temp_dir("lit-city");
    let csv = dir.join("u.csv");
    let (ok, _, err) = radiosity(&[
        "solve",
        "--scene",
        "city:2x2:lit",
        "--refine",
        "0",
        "--csv",
        csv.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lit = text.lines().skip(1).filter(|l| !l.contains(",sky,")).all(|l| {
        let u: f64 = l.rsplit(',').next().unwrap().parse().unwrap();
        u > 0.0 && u < 1.0
    });
    assert!(lit, "every face but the sky has 0 < u < 1:\n{text}");
    let (ok, _, err) = radiosity(&["solve", "--scene", "city:2x2:dark"]);
    assert!(!ok && err.contains("city:NXxNY:lit"), "{err}");
}

#[test]
fn the_louvre_room_closes_and_is_lit_through_its_slats() {
    // Lemma 2.1 across the louvre: every row of K/rho sums to 1, with pairs hidden and partly
    // seen through the slats. At refine 2 nodes lie on the line where the partition meets the
    // walls, in the partition's plane: seen edge-on, it must hide nothing on either side (it
    // hid half a slat, and the row summed to 0.99684).
    for refine in ["1", "2"] {
        let v = inspect_closed_scene("examples/louvre-room.toml", refine);
        assert!(v["pairs_partial"].as_u64().unwrap() > 0);
        assert!(v["pairs_hidden"].as_u64().unwrap() > 0);
    }
    // The east part sees the lamp only through the louvre: lit, but far less than the west.
    let dir = temp_dir("louvre");
    let csv = dir.join("u.csv");
    let path = csv.to_str().unwrap();
    let (ok, _, err) = radiosity(&[
        "solve",
        "--scene",
        "examples/louvre-room.toml",
        "--refine",
        "1",
        "--csv",
        path,
    ]);
    assert!(ok, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let floor_u = |east: bool| -> f64 {
        let values: Vec<f64> = text
            .lines()
            .skip(1)
            .map(|l| l.split(',').collect::<Vec<_>>())
            .filter(|f| f[2] == "floor" && (f[3].parse::<f64>().unwrap() > 2.0) == east)
            .map(|f| f[8].parse().unwrap())
            .collect();
        values.iter().sum::<f64>() / values.len() as f64
    };
    let (west, east) = (floor_u(false), floor_u(true));
    assert!(east > 0.0 && east < 0.5 * west, "floor west {west}, east {east}");
}

/// An STL triangle soup: a ground of 2 x 2 cells around a 2 x 2 footprint, in a 6 x 6 square,
/// and a building of height 3 on the footprint, walls in 1 x 1 cells; under a sky in a TOML
/// scene.
fn tessellated_block(dir: &std::path::Path) -> PathBuf {
    let mut stl = String::from("solid block\n");
    let mut quad = |p: [[f64; 3]; 4]| {
        for t in [[p[0], p[1], p[2]], [p[0], p[2], p[3]]] {
            stl.push_str("facet normal 0 0 0\nouter loop\n");
            for v in t {
                stl.push_str(&format!("vertex {} {} {}\n", v[0], v[1], v[2]));
            }
            stl.push_str("endloop\nendfacet\n");
        }
    };
    for i in 0..6 {
        for j in 0..6 {
            if (2..4).contains(&i) && (2..4).contains(&j) {
                continue;
            }
            let (x, y) = (i as f64, j as f64);
            quad([[x, y, 0.0], [x + 1.0, y, 0.0], [x + 1.0, y + 1.0, 0.0], [x, y + 1.0, 0.0]]);
        }
    }
    // Walls from (x, y) along (ux, uy), outward normal (ux, uy) x z.
    for (x, y, ux, uy) in
        [(2.0, 2.0, 1.0, 0.0), (4.0, 2.0, 0.0, 1.0), (4.0, 4.0, -1.0, 0.0), (2.0, 4.0, 0.0, -1.0)]
    {
        for s in 0..2 {
            for z in 0..3 {
                let p = |ds: f64, dz: f64| {
                    let t = s as f64 + ds;
                    [x + ux * t, y + uy * t, z as f64 + dz]
                };
                quad([p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)]);
            }
        }
    }
    quad([[2.0, 2.0, 3.0], [4.0, 2.0, 3.0], [4.0, 4.0, 3.0], [2.0, 4.0, 3.0]]);
    stl.push_str("endsolid block\n");
    std::fs::write(dir.join("block.stl"), stl).unwrap();
    let toml = "name = \"block\"\n[[faces]]\nname = \"sky\"\n\
                vertices = [[0, 0, 8], [0, 6, 8], [6, 6, 8], [6, 0, 8]]\nrho = 0.0\nemission = 1.0\n\
                [[meshes]]\nfile = \"block.stl\"\nrho = 0.4\n";
    let path = dir.join("block.toml");
    std::fs::write(&path, toml).unwrap();
    path
}

#[test]
fn a_triangle_soup_merged_into_faces_gives_the_solution_of_its_triangles() {
    use radiosity::pipeline::{RunConfig, SceneSource};
    use radiosity::scene::{Coplanar, ImportOptions};
    let path = tessellated_block(&temp_dir("soup"));
    let run = |coplanar| {
        let mut config = RunConfig::paper(radiosity::scene::BuiltinScene::Cube, 1);
        let import = ImportOptions { coplanar: Some(coplanar), ..Default::default() };
        config.scene = SceneSource::File(path.clone(), import);
        config.solution = None;
        radiosity::pipeline::run_keeping_mesh(&config).unwrap()
    };
    let (merged, kept) = (run(Coplanar::Merge), run(Coplanar::Keep));
    // 32 ground cells, 24 wall cells and the roof as 114 triangles, and the sky.
    assert_eq!(kept.scene.faces.len(), 115);
    // The ground in a few disks around the footprint, four walls, the roof, the sky.
    let faces = merged.scene.faces.len();
    assert!((8..=12).contains(&faces), "{faces} faces");
    assert!(merged.report.notes.iter().any(|n| n.starts_with("faces_merged: 115 -> ")));
    // The same elements, found by their centroids, with the same solution.
    let by_centroid = |run: &radiosity::pipeline::Run| {
        let mut values: Vec<([u64; 3], f64)> = run
            .mesh
            .elements()
            .iter()
            .zip(&run.report.u)
            .map(|(e, &u)| (e.centroid().to_array().map(f64::to_bits), u))
            .collect();
        values.sort_by_key(|v| v.0);
        values
    };
    let (a, b) = (by_centroid(&merged), by_centroid(&kept));
    assert_eq!(a.len(), 4 * 116);
    let mut worst = 0.0f64;
    for ((ka, ua), (kb, ub)) in a.iter().zip(&b) {
        assert_eq!(ka, kb);
        worst = worst.max((ua - ub).abs());
    }
    let lit = a.iter().map(|x| x.1).fold(0.0, f64::max);
    assert!(lit > 0.5 && worst <= 1e-13, "largest difference {worst:.2e}");
}

#[test]
fn the_estimates_study_checks_every_scene_both_ways() {
    // One seed of each generated family (four scenes and seven contacts of two triangles) and
    // the cube, at one tolerance: each run against the reference, each pair once and each
    // direction, and every promise kept.
    let v = json(&[
        "study",
        "estimates",
        "--seeds",
        "1",
        "--tolerances",
        "1e-4",
        "--scene",
        "cube",
        "--json",
        "-",
    ]);
    let rows = v["rows"].as_array().unwrap();
    assert_eq!(rows.len(), (4 + 7 + 1) * 2, "{v}");
    assert!(rows.iter().any(|r| r["scene"] == "cube"), "{v}");
    for r in rows {
        assert!(r["error_ratio"].as_f64().unwrap() <= 1.0, "{r}");
        assert_eq!(r["negative"], 0, "{r}");
        assert_eq!(r["holds"], true, "{r}");
    }
    assert_eq!(v["failed"], 0, "{v}");
    assert_eq!(v["reference_tolerance"], 1e-11, "{v}");
    let (ok, _, stderr) = radiosity(&["study", "estimates", "--shadowed-blocks"]);
    assert!(!ok && stderr.contains("--shadowed-blocks belongs to study compression"), "{stderr}");
    let (ok, _, stderr) = radiosity(&["study", "table-3.1", "--seeds", "2"]);
    assert!(!ok && stderr.contains("--seeds belongs to study estimates"), "{stderr}");
}
