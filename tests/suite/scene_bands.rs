//! Colour bands and emission cases on real scenes (the Cornell box's OBJ file among them), and
//! the compressed operator against the dense matrix on occluded scenes.

use serde_json::Value;

use crate::common;

use common::{json, radiosity, temp_dir};

const CORNELL_BOX: &str = "examples/cornell-box/CornellBox-Original.obj";

/// A run of a scene file, in grey or per band, with the default import options.
fn file_run(path: &std::path::Path, refine: u32, bands: Vec<usize>) -> radiosity::pipeline::Run {
    use radiosity::pipeline::{RunConfig, SceneSource};
    let mut config = RunConfig::paper(radiosity::scene::BuiltinScene::Cube, refine);
    config.scene = SceneSource::parse(path.to_str().unwrap()).unwrap();
    config.solution = None;
    config.bands = bands;
    radiosity::pipeline::run_keeping_mesh(&config).unwrap()
}

#[test]
fn a_band_solve_equals_the_grey_solve_with_that_bands_rho_and_e() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    // A grey scene: one band is the grey problem, bit for bit (the rows are scaled by 1).
    let grey_scene = root.join("examples/occluded-box.toml");
    let (grey, band) = (file_run(&grey_scene, 2, vec![]), file_run(&grey_scene, 2, vec![1]));
    assert_eq!(band.bands[0].u, grey.report.u);
    assert_eq!(band.report.u, grey.report.u);

    // The Cornell box per band, against separate grey runs of copies of it whose materials have
    // that band's Kd and Ke in every channel (one assembly there, three here).
    let rgb = file_run(&root.join(CORNELL_BOX), 1, vec![0, 1, 2]);
    let dir = temp_dir("bands");
    let obj = std::fs::read_to_string(root.join(CORNELL_BOX)).unwrap();
    let mtl = std::fs::read_to_string(root.join(CORNELL_BOX).with_extension("mtl")).unwrap();
    for (k, band) in rgb.bands.iter().enumerate() {
        assert_eq!(band.channel, k);
        let one_channel: String = mtl
            .lines()
            .map(|l| match l.split_whitespace().collect::<Vec<_>>()[..] {
                [key @ ("Kd" | "Ke"), r, g, b] => {
                    let c = [r, g, b][k];
                    format!("{key} {c} {c} {c}\n")
                }
                _ => format!("{l}\n"),
            })
            .collect();
        std::fs::write(dir.join("CornellBox-Original.mtl"), one_channel).unwrap();
        std::fs::write(dir.join("CornellBox-Original.obj"), &obj).unwrap();
        let separate = file_run(&dir.join("CornellBox-Original.obj"), 1, vec![]);
        let scale = separate.report.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst =
            band.u.iter().zip(&separate.report.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-13 * scale, "band {k}: {worst:.2e} of {scale:.2e}");
        assert_eq!(band.emission, separate.emission, "band {k}");
    }
}

#[test]
fn the_cornell_box_solves_in_colour_from_its_unmodified_file() {
    let dir = temp_dir("cornell");
    let (png, csv) = (dir.join("cb.png"), dir.join("cb.csv"));
    let args = [
        "solve",
        "--scene",
        CORNELL_BOX,
        "--bands",
        "rgb",
        "--refine",
        "2",
        "--png",
        png.to_str().unwrap(),
        "--png-size",
        "600x400",
        "--csv",
        csv.to_str().unwrap(),
        "--json",
        "-",
    ];
    let (ok, stdout, stderr) = radiosity(&args);
    assert!(ok, "{stderr}");
    // The file's quirks, one line each, naming faces by file line.
    let notes: Vec<&str> = stderr.lines().filter(|l| l.starts_with("note: ")).collect();
    assert_eq!(notes.len(), 2, "{stderr}");
    assert!(
        notes[0].contains("split 1 non-planar") && notes[0].contains("CornellBox-Original.obj:62")
    );
    assert!(notes[1].contains("dropped 2 face(s)"), "{}", notes[1]);
    let r: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(r["notes"].as_array().unwrap().len(), 2);
    let bands: Vec<&str> =
        r["bands"].as_array().unwrap().iter().map(|b| b["band"].as_str().unwrap()).collect();
    assert_eq!(bands, ["r", "g", "b"]);

    // Colour bleeding: on the (nearly white) floor, red over green is larger beside the red left
    // wall (x = -1) than beside the green right wall (x = +1).
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (x, u_r, u_g) = (col("x"), col("u_r"), col("u_g"));
    let (mut left, mut right) = (Vec::new(), Vec::new());
    for line in lines.filter(|l| l.contains("usemtl floor")) {
        let cells: Vec<&str> = line.split(',').collect();
        let value = |k: usize| cells[k].parse::<f64>().unwrap();
        let ratio = value(u_r) / value(u_g);
        if value(x) < -0.6 {
            left.push(ratio);
        } else if value(x) > 0.6 {
            right.push(ratio);
        }
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    assert!(mean(&left) > 1.2 * mean(&right), "{} vs {}", mean(&left), mean(&right));

    // The picture is in colour: reddish pixels on the left, greenish on the right.
    let image = image::open(&png).unwrap().to_rgb8();
    let count = |red: bool| {
        image
            .enumerate_pixels()
            .filter(|(px, _, p)| {
                let [r, g, _] = p.0.map(i32::from);
                (*px < 300) == red && if red { r > 2 * g + 20 } else { g > r + 10 }
            })
            .count()
    };
    assert!(count(true) > 2000 && count(false) > 2000, "{} {}", count(true), count(false));
}

#[test]
fn bad_up_directions_and_band_names_are_refused() {
    for (args, expect) in [
        (&["--up", "0,0,0", "--png", "x.png"][..], "non-zero"),
        (&["--up", "0,1"][..], "three finite numbers"),
        (&["--bands", "rgbx"][..], "unknown band 'rgbx'"),
        (&["--bands", "r,q"][..], "unknown band 'q'"),
        (&["--bands", "r,r"][..], "named twice"),
    ] {
        let mut all = vec!["solve", "--scene", CORNELL_BOX, "--refine", "0"];
        all.extend(args);
        let (ok, _, err) = radiosity(&all);
        assert!(!ok && err.contains(expect), "{args:?}: {err}");
    }
    // inspect reports the file's repairs too, and solves no bands.
    let (ok, _, err) = radiosity(&["inspect", "--scene", CORNELL_BOX, "--refine", "0"]);
    assert!(ok && err.lines().filter(|l| l.starts_with("note: ")).count() == 2, "{err}");
    let (ok, _, err) = radiosity(&["inspect", "--scene", CORNELL_BOX, "--bands", "rgb"]);
    assert!(!ok && err.contains("belong to solve"), "{err}");
    // Bands are lit by the scene's emission, not by a true solution.
    let (ok, _, err) = radiosity(&["solve", "--scene", "five-piece", "--bands", "rgb"]);
    assert!(!ok && err.contains("--solution none"), "{err}");
}

#[test]
fn colour_bands_on_the_compressed_operator_agree_with_the_dense_bands() {
    use radiosity::operator::OperatorChoice;
    use radiosity::pipeline::{RunConfig, SceneSource};
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let run = |operator, tolerance: f64| {
        let mut config = RunConfig::paper(radiosity::scene::BuiltinScene::Cube, 3);
        config.scene = SceneSource::parse(root.join(CORNELL_BOX).to_str().unwrap()).unwrap();
        config.solution = None;
        config.bands = vec![0, 1, 2];
        config.operator = operator;
        config.compression.tolerance = tolerance;
        config.solver.tolerance = 1e-12;
        radiosity::pipeline::run_keeping_mesh(&config).unwrap()
    };
    let dense = run(OperatorChoice::Dense, 1e-6);
    for tolerance in [1e-6, 1e-9] {
        let compressed = run(OperatorChoice::Compressed, tolerance);
        assert_eq!(compressed.report.operator, "compressed");
        for (c, d) in compressed.bands.iter().zip(&dense.bands) {
            assert_eq!((c.channel, &c.emission), (d.channel, &d.emission));
            let scale = d.u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let worst = c.u.iter().zip(&d.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            // The red band differs from the grey rows most: scaling must reach every product.
            assert!(
                worst <= 10.0 * tolerance * scale,
                "band {}: {worst:.2e} of {scale:.2e}",
                c.channel
            );
        }
    }
}

/// Reads a CSV file of the binary's into its header and columns of numbers (by header name).
fn csv_columns(path: &std::path::Path) -> std::collections::HashMap<String, Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let mut columns: std::collections::HashMap<String, Vec<f64>> = Default::default();
    for line in lines {
        for (name, field) in header.iter().zip(line.split(',')) {
            if let Ok(v) = field.parse() {
                columns.entry(name.clone()).or_default().push(v);
            }
        }
    }
    columns
}

#[test]
fn emission_cases_on_one_operator_are_each_case_s_own_solve() {
    let room = "examples/furnished-room.toml";
    let scene = radiosity::scene::load(std::path::Path::new(room)).unwrap();
    let lamp: Vec<f64> = scene.faces.iter().map(|f| f.emission).collect();
    let floor: Vec<f64> = scene.faces.iter().map(|f| f64::from(f.name == "floor")).collect();
    let dir = temp_dir("cases");
    let file = dir.join("e.csv");
    let mut text = String::from("lamp,floor,both\n");
    for (l, f) in lamp.iter().zip(&floor) {
        text += &format!("{l},{f},{}\n", 2.0 * l + f);
    }
    std::fs::write(&file, text).unwrap();

    for (operator, solver, tolerance) in
        [("dense", "auto", 1e-13), ("compressed", "iterative", 1e-8)]
    {
        let csv = dir.join(format!("{operator}.csv"));
        let vtu = dir.join(format!("{operator}.vtu"));
        let args = |extra: &[&str]| {
            let mut args = vec!["solve", "--scene", room, "--refine", "2", "--json", "-"];
            args.extend(["--operator", operator, "--solver", solver]);
            args.extend(extra);
            args.iter().map(|s| s.to_string()).collect::<Vec<_>>()
        };
        let with_cases = args(&["--emission-file", file.to_str().unwrap()]);
        let with_cases: Vec<&str> =
            with_cases.iter().map(String::as_str).chain(["--csv", csv.to_str().unwrap()]).collect();
        let with_cases: Vec<&str> =
            with_cases.into_iter().chain(["--vtu", vtu.to_str().unwrap()]).collect();
        let report = json(&with_cases);
        let cases = report["cases"].as_array().unwrap();
        let names: Vec<&str> = cases.iter().map(|c| c["case"].as_str().unwrap()).collect();
        assert_eq!(names, ["lamp", "floor", "both"]);
        // The VTK file carries u per case at the vertices, u and E per case in the cells.
        let vtk = std::fs::read_to_string(&vtu).unwrap();
        for case in names {
            for (array, count) in [(format!("u_{case}"), 2), (format!("E_{case}"), 1)] {
                assert_eq!(vtk.matches(&format!("Name=\"{array}\"")).count(), count, "{array}");
            }
        }
        let plain = args(&[]);
        let plain = json(&plain.iter().map(String::as_str).collect::<Vec<_>>());
        // Bit for bit on the dense matrix; the compressed products' sums are not ordered.
        let range = |r: &Value| -> Vec<f64> {
            r["solution_range"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect()
        };
        let (a, b) = (range(&cases[0]), range(&plain));
        let exact = if operator == "dense" { 0.0 } else { 1e-12 };
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() <= exact * y.abs()), "{a:?} {b:?}");

        // The scene's own emission gives the plain solve; the cases are linear in E.
        let columns = csv_columns(&csv);
        let (u_lamp, u_floor, u_both) =
            (&columns["u_lamp"], &columns["u_floor"], &columns["u_both"]);
        let scale = u_both.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..u_lamp.len() {
            let combined = 2.0 * u_lamp[i] + u_floor[i];
            assert!((u_both[i] - combined).abs() <= tolerance * scale, "{operator}, node {i}");
            assert_eq!(columns["E_floor"][i], columns["E_both"][i] - 2.0 * columns["E_lamp"][i]);
        }
        let mean: Vec<f64> =
            (0..u_lamp.len()).map(|i| (u_lamp[i] + u_floor[i] + u_both[i]) / 3.0).collect();
        let worst = mean.iter().zip(&columns["u"]).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst <= 1e-14 * scale, "{operator}: u is the cases' mean ({worst:.1e})");
    }
}

#[test]
fn emission_files_that_do_not_fit_the_run_are_refused() {
    let dir = temp_dir("bad-cases");
    let file = dir.join("e.csv");
    std::fs::write(&file, "1\n2\n3\n").unwrap();
    let file = file.to_str().unwrap();
    let base = ["solve", "--scene", "examples/furnished-room.toml", "--refine", "0"];
    for (extra, says) in [
        (
            vec!["--emission-file", file],
            "give one row per face (36 faces in 'furnished-room') or one per node (72 nodes)",
        ),
        (vec!["--emission-file", file, "--bands", "rgb"], "emission cases give E themselves"),
        (vec!["--emission-file", "/nonexistent.csv"], "/nonexistent.csv"),
    ] {
        let args: Vec<&str> = base.iter().copied().chain(extra).collect();
        let (ok, _, stderr) = radiosity(&args);
        assert!(!ok && stderr.contains(says), "{args:?}: {stderr}");
    }
}

#[test]
fn occluded_scenes_compress_to_within_ten_times_the_tolerance_of_their_dense_matrix() {
    // Rooms with furniture and slats, a lit city and a box around a floating cube: products of
    // the compressed operator, with and without shadowed blocks, against the dense matrix's at
    // 1e-6 and 1e-9 (three vectors, the ones among them), and in the closed scenes every row of
    // K/rho summing to 1 (Lemma 2.1).
    use radiosity::assembly::{AssemblyOptions, assemble};
    use radiosity::operator::{CompressedOperator, CompressionOptions};
    use radiosity::pipeline::{self, RunConfig, SceneSource};
    use radiosity::progress::Silent;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let file = |name: &str| root.join(name).to_str().unwrap().to_string();
    let cases = [
        (file("examples/furnished-room.toml"), 3, true),
        (file("examples/louvre-room.toml"), 3, true),
        (file("examples/louvre-window.toml"), 3, true),
        (file("examples/occluded-box.toml"), 3, true),
        ("city:4x4:lit".to_string(), 2, false),
    ];
    for (scene, refine, closed) in cases {
        let mut config = RunConfig::paper(radiosity::scene::BuiltinScene::Cube, refine);
        config.scene = SceneSource::parse(&scene).unwrap();
        config.solution = None;
        let problem = pipeline::build(&config).unwrap();
        let assembly = AssemblyOptions::default();
        let k = assemble(&problem, &assembly, &Silent).unwrap().matrix;
        for (tolerance, shadowed_blocks) in
            [1e-6, 1e-9].into_iter().flat_map(|t| [(t, false), (t, true)])
        {
            let options = CompressionOptions {
                tolerance,
                shadowed_blocks: shadowed_blocks.into(),
                ..Default::default()
            };
            let op =
                CompressedOperator::build(&problem, &assembly, &options, None, &Silent).unwrap();
            let name =
                format!("{scene} refine {refine} at {tolerance:e}, shadowed {shadowed_blocks}");
            assert!(op.stats.far_blocks > 0, "{name}: nothing compressed: {:?}", op.stats);
            let d = op.max_product_difference(&|x| k.apply(x));
            assert!(d <= 10.0 * tolerance, "{name}: products differ by {d:.2e}");
            if closed {
                let sums = op.apply(&vec![1.0; problem.disc.dof()]);
                for (node, sum) in problem.disc.nodes().zip(sums) {
                    if node.rho > 0.0 {
                        let off = (sum / node.rho - 1.0).abs();
                        assert!(off <= 10.0 * tolerance, "{name}: a row sums to 1 + {off:.1e}");
                    }
                }
            }
        }
    }
}
