//! The sunlit parts ([`radiosity::sun::sunlit`]) against independent truth: the analytic shadow
//! of a box on a plane, the energy a closed city catches (every ray from the sun over the
//! ground ends on exactly one face that faces it), and rays cast at random points.

use glam::DVec3;
use radiosity::mesh::{Mesh, MeshKind};
use radiosity::scene::generated::{self, box_faces, face};
use radiosity::scene::{Face, Scene};
use radiosity::sun::{DEFAULT_X_AZIMUTH, Sun, Sunlit, sunlit};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

/// Suns from high to low, from every quarter.
const SUNS: [(f64, f64); 6] =
    [(0.0, 0.0), (10.0, 135.0), (35.0, 200.0), (50.0, 290.0), (62.0, 17.0), (75.0, 90.0)];

/// The ground, a square of side `2 half` centred on the origin, facing up.
fn ground(half: f64) -> Face {
    let c = |x: f64, y: f64| DVec3::new(x * half, y * half, 0.0);
    face("ground".into(), vec![c(-1.0, -1.0), c(1.0, -1.0), c(1.0, 1.0), c(-1.0, 1.0)])
}

/// The faces' sunlit parts at `refine`, summed per face.
fn by_face(scene: &Scene, refine: u32, sun: &Sun) -> Vec<Sunlit> {
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let elements = sunlit(scene, &mesh, sun.direction()).unwrap();
    Sunlit::by_face(&mesh, &elements)
}

fn sun(zenith: f64, azimuth: f64) -> Sun {
    Sun::new(zenith, azimuth, DEFAULT_X_AZIMUTH, 1.0).unwrap()
}

#[test]
fn a_box_on_the_ground_casts_its_analytic_shadow() {
    let (a, b, h) = (3.0, 7.0, 11.0);
    let mut faces = vec![ground(100.0)];
    faces.extend(box_faces("box", DVec3::new(0.5, -2.0, 0.0), DVec3::new(0.5 + a, 5.0, h), false));
    let scene = Scene::new("box on the ground", faces).unwrap();
    for (zenith, azimuth) in SUNS {
        let sun = sun(zenith, azimuth);
        let s = sun.direction();
        // The box seen from the sun covers its footprint swept by the top's displacement.
        let (dx, dy) = (h * s.x / s.z, h * s.y / s.z);
        let shadow = a * b + dx.abs() * b + dy.abs() * a;
        for refine in [0, 2] {
            let faces = by_face(&scene, refine, &sun);
            let lit = faces[0].lit_area;
            let want = 200.0 * 200.0 - shadow;
            assert!(
                (lit - want).abs() <= 1e-12 * want,
                "Z {zenith} A {azimuth} r {refine}: {lit} vs {want}"
            );
            for (f, face) in scene.faces.iter().enumerate().skip(1) {
                // Nothing shadows the box: each face facing the sun is lit whole.
                let facing = face.frame.normal.dot(s) > 0.0;
                let fraction = faces[f].fraction();
                let want = if facing { 1.0 } else { 0.0 };
                assert!((fraction - want).abs() <= 1e-12, "{}: {fraction}", face.name);
                let cos = face.frame.normal.dot(s).max(0.0);
                assert!((faces[f].cos_incidence - cos).abs() <= 1e-15, "{}", face.name);
            }
        }
    }
}

/// The faces of a box of `w` x `d` in plan, turned by `angle` about its centre `(cx, cy)`, from
/// height `z0` to `z1`, facing out.
fn turned_box(
    k: usize,
    (cx, cy): (f64, f64),
    (w, d): (f64, f64),
    (z0, z1): (f64, f64),
    angle: f64,
) -> Vec<Face> {
    let corner = |(sx, sy): (f64, f64), z: f64| {
        let (x, y) = (sx * 0.5 * w, sy * 0.5 * d);
        DVec3::new(
            cx + x * angle.cos() - y * angle.sin(),
            cy + x * angle.sin() + y * angle.cos(),
            z,
        )
    };
    let ring = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    let mut faces: Vec<Face> = (0..4)
        .map(|s| {
            let (a, b) = (ring[s], ring[(s + 1) % 4]);
            let wall = vec![corner(a, z0), corner(b, z0), corner(b, z1), corner(a, z1)];
            face(format!("b{k}-wall{s}"), wall)
        })
        .collect();
    faces.push(face(format!("b{k}-roof"), ring.iter().map(|&c| corner(c, z1)).collect()));
    faces.push(face(format!("b{k}-floor"), ring.iter().rev().map(|&c| corner(c, z0)).collect()));
    faces
}

/// A city of turned towers on a 4 x 4 grid, some standing on the ground and some floating
/// (bridges whose shadows fall on roofs and walls), all well inside a ground of side 400.
fn random_city(seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut faces = vec![ground(200.0)];
    for i in 0..4 {
        for j in 0..4 {
            let k = 4 * i + j;
            let centre = (-24.0 + 16.0 * i as f64, -24.0 + 16.0 * j as f64);
            let size = (rng.random_range(3.0..9.0), rng.random_range(3.0..9.0));
            let z0 = if rng.random_bool(0.3) { rng.random_range(2.0..10.0) } else { 0.0 };
            let z1 = z0 + rng.random_range(3.0..30.0);
            let angle = rng.random_range(0.0..std::f64::consts::FRAC_PI_2);
            faces.extend(turned_box(k, centre, size, (z0, z1), angle));
        }
    }
    Scene::new(format!("towers-{seed}"), faces).unwrap()
}

#[test]
fn a_closed_city_catches_the_sunlight_over_its_ground_exactly() {
    for seed in 0..4 {
        let scene = random_city(seed);
        for (zenith, azimuth) in SUNS {
            let sun = sun(zenith, azimuth);
            let want = 400.0 * 400.0 * sun.direction().z;
            for refine in [0, 1] {
                let caught: f64 = by_face(&scene, refine, &sun)
                    .iter()
                    .map(|f| f.lit_area * f.cos_incidence)
                    .sum();
                assert!(
                    (caught - want).abs() <= 1e-12 * want,
                    "seed {seed} Z {zenith} A {azimuth} refine {refine}: {caught} vs {want} ({:.1e})",
                    (caught - want) / want
                );
            }
        }
    }
}

/// Whether the ray from `origin` along `direction` meets the triangle `[a, b, c]` beyond
/// `t_min` (Möller–Trumbore).
fn hits(origin: DVec3, direction: DVec3, [a, b, c]: [DVec3; 3], t_min: f64) -> bool {
    let (e1, e2) = (b - a, c - a);
    let p = direction.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-14 * e1.length() * e2.length() {
        return false;
    }
    let s = origin - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = direction.dot(q) / det;
    let t = e2.dot(q) / det;
    (0.0..=1.0).contains(&u) && v >= 0.0 && u + v <= 1.0 && t > t_min
}

#[test]
fn sunlit_fractions_agree_with_rays_cast_at_random_points() {
    const RAYS: usize = 4000;
    let mut rng = StdRng::seed_from_u64(7);
    for seed in 0..2 {
        let scene = generated::city(seed);
        let triangles = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
        let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
        for (zenith, azimuth) in [(30.0, 160.0), (60.0, 250.0)] {
            let sun = sun(zenith, azimuth);
            let s = sun.direction();
            let exact = Sunlit::by_face(&mesh, &sunlit(&scene, &mesh, s).unwrap());
            for (f, face) in scene.faces.iter().enumerate() {
                if exact[f].cos_incidence == 0.0 {
                    continue;
                }
                let elements = &mesh.elements()[mesh.face_range(f)];
                let mut lit = 0;
                for _ in 0..RAYS {
                    // A uniform point of the face: an element by area, then a point in it.
                    let mut pick = rng.random_range(0.0..exact[f].area);
                    let e = elements.iter().find(|e| {
                        pick -= e.area();
                        pick <= 0.0
                    });
                    let [a, b, c] = e.unwrap_or(&elements[elements.len() - 1]).vertices;
                    let (mut u, mut v): (f64, f64) = (rng.random(), rng.random());
                    if u + v > 1.0 {
                        (u, v) = (1.0 - u, 1.0 - v);
                    }
                    let p = a + u * (b - a) + v * (c - a);
                    let blocked = triangles
                        .elements()
                        .iter()
                        .filter(|o| o.face != f)
                        .any(|o| hits(p, s, o.vertices, 1e-9));
                    lit += usize::from(!blocked);
                }
                let sampled = lit as f64 / RAYS as f64;
                let p = exact[f].fraction();
                // Five standard deviations of the sampled fraction (and at least those of
                // p(1 - p) = 1/RAYS, where the face is all lit or all shadowed).
                let sigma = (p * (1.0 - p)).max(1.0 / RAYS as f64).sqrt() / (RAYS as f64).sqrt();
                assert!(
                    (sampled - p).abs() <= 5.0 * sigma,
                    "seed {seed} Z {zenith} {}: exact {p}, sampled {sampled} (sigma {sigma:.1e})",
                    face.name
                );
            }
        }
    }
}

/// View factors of `scene` at refine `refine`, tolerance 1e-8, and the mesh.
fn view_factors_of(scene: &Scene, refine: u32) -> (Mesh, radiosity::viewfactors::ViewFactors) {
    use radiosity::viewfactors::{ViewFactorOptions, view_factors};
    let mesh = Mesh::new(scene, &MeshKind::Uniform, refine).unwrap();
    let planner = radiosity::visibility::PairPlanner::new(scene);
    let options = ViewFactorOptions { tolerance: 1e-8, ..Default::default() };
    let f = view_factors(scene, &mesh, &planner, &options, &radiosity::progress::Silent).unwrap();
    (mesh, f)
}

#[test]
fn an_open_plane_receives_the_sun_and_the_whole_sky() {
    use radiosity::shortwave::shortwave;
    use radiosity::sun::Sources;
    let mut plane = ground(10.0);
    plane.rho = 0.3;
    let scene = Scene::new("plane", vec![plane]).unwrap();
    let (mesh, f) = view_factors_of(&scene, 1);
    let sources = Sources::new(Sun::new(40.0, 120.0, 90.0, 800.0).unwrap(), 100.0).unwrap();
    let result = shortwave(&scene, &mesh, Some(&f), &sources, 1e-13).unwrap();
    let direct = 800.0 * 40f64.to_radians().cos();
    for e in &result.elements {
        assert!((e.direct - direct).abs() <= 1e-12 * direct, "{e:?}");
        assert_eq!(
            (e.sky, e.sky_view_factor, e.reflected, e.sunlit_fraction),
            (100.0, 1.0, 0.0, 1.0)
        );
        assert!((e.absorbed - 0.7 * (direct + 100.0)).abs() <= 1e-12 * direct);
    }
}

#[test]
fn reflections_in_a_sunlit_city_close_the_energy_and_match_lu() {
    use radiosity::shortwave::shortwave;
    use radiosity::sun::Sources;
    for seed in 0..2 {
        let scene = generated::city(seed);
        let (mesh, f) = view_factors_of(&scene, 1);
        for (zenith, azimuth) in [(20.0, 150.0), (65.0, 280.0)] {
            let sun = Sun::new(zenith, azimuth, 90.0, 850.0).unwrap();
            let sources = Sources::new(sun, 120.0).unwrap();
            let result = shortwave(&scene, &mesh, Some(&f), &sources, 1e-13).unwrap();
            let b = &result.balance;
            assert!(b.relative_gap <= 1e-9, "seed {seed} Z {zenith}: {b:?}");
            assert!(b.absorbed > 0.5 * b.received && b.escaped > 0.0, "{b:?}");
            // The same reflections by LU on the dense I - diag(rho) F.
            let n = mesh.len();
            let rho: Vec<f64> = mesh.elements().iter().map(|e| scene.faces[e.face].rho).collect();
            let a = faer::Mat::<f64>::from_fn(n, n, |i, j| {
                f64::from(u8::from(i == j)) - rho[i] * f.get(i, j)
            });
            let e = faer::Mat::<f64>::from_fn(n, 1, |i, _| {
                rho[i] * (result.elements[i].direct + result.elements[i].sky)
            });
            let lu = a.partial_piv_lu();
            let b_lu = faer::linalg::solvers::Solve::solve(&lu, &e);
            let largest = result.elements.iter().map(|e| e.outgoing).fold(0.0, f64::max);
            for i in 0..n {
                let gap = (result.elements[i].outgoing - b_lu[(i, 0)]).abs();
                assert!(gap <= 1e-10 * largest, "seed {seed} element {i}: {gap:e}");
            }
        }
    }
}

#[test]
fn the_sun_command_writes_per_face_and_per_element_fluxes_that_add_up() {
    use crate::common::{json, radiosity, temp_dir};
    let dir = temp_dir("sun");
    let (faces, elements) = (dir.join("faces.csv"), dir.join("elements.csv"));
    let (faces, elements) = (faces.to_str().unwrap(), elements.to_str().unwrap());
    let picture = dir.join("absorbed.png");
    let vtu = dir.join("fluxes.vtu");
    let common = [
        "sun",
        "--scene",
        "city:2x1",
        "--refine",
        "1",
        "--zenith",
        "35",
        "--azimuth",
        "160",
        "--direct-normal",
        "800",
        "--diffuse-horizontal",
        "100",
        "--tolerance",
        "1e-6",
    ];
    let mut args = common.to_vec();
    args.extend(["--csv", faces, "--element-csv", elements, "--json", "-"]);
    args.extend(["--png", picture.to_str().unwrap(), "--png-size", "400x300"]);
    args.extend(["--vtu", vtu.to_str().unwrap()]);
    let v = json(&args);
    // The VTU's cells carry the element CSV's columns, in the mesh's order.
    let text = std::fs::read_to_string(&vtu).unwrap();
    let cells = |name: &str| -> Vec<f64> {
        let start = format!(r#"Name="{name}" format="ascii">"#);
        let from = text.find(&start).unwrap_or_else(|| panic!("{name}")) + start.len();
        let to = from + text[from..].find("</DataArray>").unwrap();
        text[from..to].split_whitespace().map(|x| x.parse().unwrap()).collect()
    };
    let n = v["n"].as_u64().unwrap() as usize;
    let absorbed = cells("absorbed");
    assert_eq!((absorbed.len(), cells("sky_view_factor").len(), cells("face").len()), (n, n, n));
    let png = std::fs::read(&picture).unwrap();
    assert!(png.starts_with(b"\x89PNG") && png.len() > 2000, "{} bytes", png.len());
    let number = |key: &str| v[key].as_f64().unwrap_or_else(|| panic!("{key} in {v}"));
    assert!(number("relative_gap") <= 1e-9, "{v}");
    assert!(number("sunlit_area") > 0.0 && number("sunlit_area") < number("area_facing_sun"));
    assert!(number("absorbed") + number("escaped") > 0.99 * number("received"));
    assert_eq!(v["sun"]["zenith"], 35.0);
    // Each file's rows, weighted by area, give the absorbed power of the summary.
    for (path, first, rows) in
        [(faces, "face,name,", v["faces"].as_u64()), (elements, "element,face,", v["n"].as_u64())]
    {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header = lines.next().unwrap();
        assert!(header.starts_with(first) && header.ends_with(",absorbed,outgoing"), "{header}");
        let values: Vec<Vec<f64>> =
            lines.map(|l| l.split(',').skip(2).map(|x| x.parse().unwrap()).collect()).collect();
        assert_eq!(values.len() as u64, rows.unwrap());
        let total: f64 = values.iter().map(|r| r[0] * r[7]).sum();
        assert!((total - number("absorbed")).abs() <= 1e-12 * total, "{path}");
        if first.starts_with("element") {
            let column: Vec<f64> = values.iter().map(|r| r[7]).collect();
            assert_eq!(column, absorbed, "the VTU's cells and the element CSV");
        }
    }
    // Bad values are refused by name, before any work.
    for (flag, value, named) in [
        ("--zenith", "200", "sun zenith"),
        ("--direct-normal", "nan", "direct normal irradiance"),
        ("--diffuse-horizontal", "-1", "diffuse horizontal irradiance"),
        ("--csv", "faces.txt", "csv"),
    ] {
        let mut args = common.to_vec();
        let at = args.iter().position(|a| *a == flag);
        match at {
            Some(k) => args[k + 1] = value,
            None => args.extend([flag, value]),
        }
        let (ok, _, stderr) = radiosity(&args);
        assert!(!ok && stderr.contains(named), "{flag} {value}: {stderr}");
    }
}

#[test]
fn a_day_of_sun_positions_is_solved_on_one_set_of_view_factors() {
    use crate::common::{json, temp_dir};
    let dir = temp_dir("sun-day");
    let day = dir.join("day.csv");
    std::fs::write(
        &day,
        "time,zenith,azimuth,direct_normal,diffuse_horizontal\n\
         09:00,55,115,650,95\n12:00,30,180,850,110\n21:00,100,310,0,0\n",
    )
    .unwrap();
    let faces = dir.join("faces.csv");
    let v = json(&[
        "sun",
        "--scene",
        "city:2x1",
        "--refine",
        "0",
        "--sun-positions",
        day.to_str().unwrap(),
        "--csv",
        faces.to_str().unwrap(),
        "--json",
        "-",
    ]);
    let times = v["times"].as_array().unwrap_or_else(|| panic!("{v}"));
    assert_eq!(times.len(), 3);
    assert_eq!(times[1]["time"], "12:00");
    assert_eq!(times[1]["sun"]["azimuth"], 180.0);
    assert!(times[..2].iter().all(|t| t["relative_gap"].as_f64().unwrap() <= 1e-9));
    // Below the horizon, and no sky: nothing received.
    assert_eq!(times[2]["received"], 0.0);
    // The same noon as one sun, to the bit.
    let noon = json(&[
        "sun",
        "--scene",
        "city:2x1",
        "--refine",
        "0",
        "--zenith",
        "30",
        "--azimuth",
        "180",
        "--direct-normal",
        "850",
        "--diffuse-horizontal",
        "110",
        "--json",
        "-",
    ]);
    assert_eq!(noon["absorbed"], times[1]["absorbed"]);
    let text = std::fs::read_to_string(&faces).unwrap();
    assert!(text.starts_with("time,face,name,area,"), "{text}");
    let faces = v["faces"].as_u64().unwrap() as usize;
    assert_eq!(text.lines().count(), 1 + 3 * faces);
    assert_eq!(text.lines().filter(|l| l.starts_with("12:00,")).count(), faces);
}

/// A street canyon as an ASCII STL whose triangles are listed out of their faces' order (the
/// ground's three and each wall's two interleaved), with the files' areas and normals.
const CANYON_STL: &str = "solid canyon
facet normal 0 1 0
outer loop
vertex 0 0 0
vertex 0 0 6
vertex 20 0 0
endloop
endfacet
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 8 0 0
vertex 0 10 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 0 10 0
vertex 20 10 0
vertex 0 10 6
endloop
endfacet
facet normal 0 0 1
outer loop
vertex 8 0 0
vertex 20 10 0
vertex 0 10 0
endloop
endfacet
facet normal 0 1 0
outer loop
vertex 20 0 0
vertex 0 0 6
vertex 20 0 6
endloop
endfacet
facet normal 0 0 1
outer loop
vertex 8 0 0
vertex 20 0 0
vertex 20 10 0
endloop
endfacet
facet normal 0 -1 0
outer loop
vertex 20 10 0
vertex 20 10 6
vertex 0 10 6
endloop
endfacet
endsolid canyon
";

/// The lines of `path` after `header` (checked, where given).
fn lines_after(path: &std::path::Path, header: Option<&str>) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    if let Some(header) = header {
        assert_eq!(lines.next(), Some(header), "{}", path.display());
    }
    lines.map(str::to_owned).collect()
}

#[test]
fn the_export_writes_the_files_an_urban_les_reads_in_the_stl_s_order() {
    use crate::common::{json, radiosity, temp_dir};
    use radiosity::report::{NETSW_HEADER, TIMEDEPSW_HEADER};
    let dir = temp_dir("sun-export");
    let stl = dir.join("canyon.stl");
    std::fs::write(&stl, CANYON_STL).unwrap();
    let out = dir.join("inputs");
    let scene = stl.to_str().unwrap();
    let v = json(&[
        "sun",
        "--scene",
        scene,
        "--refine",
        "0",
        "--zenith",
        "30",
        "--azimuth",
        "170",
        "--direct-normal",
        "800",
        "--diffuse-horizontal",
        "100",
        "--export",
        out.to_str().unwrap(),
        "--expnr",
        "001",
        "--json",
        "-",
    ]);
    assert_eq!(v["exported"].as_array().unwrap().len(), 5, "{v}");
    let file = |name: &str| out.join(format!("{name}.001"));
    // Areas in the file's order: walls 60, ground 40, 100 and 60.
    let areas: Vec<f64> = lines_after(&file("facetarea.inp"), Some("# area of facets"))
        .iter()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(areas, [60.0, 40.0, 60.0, 100.0, 60.0, 60.0, 60.0]);
    let svf: Vec<f64> = lines_after(&file("svf.inp"), Some("# sky view factors"))
        .iter()
        .map(|l| l.parse().unwrap())
        .collect();
    assert_eq!(svf.len(), 7);
    // Each line of vfsparse: i j F_ij, by row then column.
    let entries: Vec<(usize, usize, f64)> = lines_after(&file("vfsparse.inp"), None)
        .iter()
        .map(|l| {
            let f: Vec<&str> = l.split(' ').collect();
            assert_eq!(f.len(), 3, "{l}");
            assert_eq!(f[2].split('.').nth(1).map(str::len), Some(8), "{l}");
            (f[0].parse().unwrap(), f[1].parse().unwrap(), f[2].parse().unwrap())
        })
        .collect();
    assert!(entries.windows(2).all(|w| (w[0].0, w[0].1) < (w[1].0, w[1].1)), "sorted");
    let mut rows = [0.0; 7];
    for &(i, j, fij) in &entries {
        assert!(i != j && fij >= 5e-7, "{i} {j} {fij}");
        rows[i - 1] += fij;
        let back = entries.iter().find(|e| (e.0, e.1) == (j, i)).expect("both directions kept");
        let gap = (areas[i - 1] * fij - areas[j - 1] * back.2).abs();
        assert!(gap <= (areas[i - 1] + areas[j - 1]) * 5e-9, "reciprocity {i} {j}: {gap:e}");
    }
    for (k, (row, sky)) in rows.iter().zip(&svf).enumerate() {
        assert!((row + sky - 1.0).abs() <= 1e-7, "facet {}: {row} + {sky}", k + 1);
    }
    // The ground sees the walls, a wall the ground and the other wall.
    assert!(svf[1] < 1.0 && svf[0] < 1.0);
    let netsw: Vec<f64> = lines_after(&file("netsw.inp"), Some(NETSW_HEADER))
        .iter()
        .map(|l| l.trim().parse().unwrap())
        .collect();
    let absorbed: f64 = netsw.iter().zip(&areas).map(|(k, a)| k * a).sum();
    let want = v["absorbed"].as_f64().unwrap();
    assert!((absorbed - want).abs() <= 1e-4 * areas.iter().sum::<f64>(), "{absorbed} vs {want}");
    let direct: Vec<f64> =
        lines_after(&file("Sdir.txt"), None).iter().map(|l| l.parse().unwrap()).collect();
    // The wall at y = 0 faces north, away from a sun in the south: no direct light; the wall
    // at y = 10 faces it.
    assert_eq!((direct.len(), direct[0], direct[4]), (7, 0.0, 0.0));
    assert!(direct[2] > 0.0 && direct[6] > 0.0, "{direct:?}");
    let lit = 800.0 * 30f64.to_radians().cos();
    assert!(direct[1] > 0.0 && direct[1] <= lit + 1e-4, "{direct:?}");

    // Direct light alone: no view factors, the same Sdir.txt and facetarea.inp, nothing else.
    let direct_only = dir.join("direct-only");
    let (ok, _, stderr) = radiosity(&[
        "sun",
        "--scene",
        scene,
        "--refine",
        "0",
        "--zenith",
        "30",
        "--azimuth",
        "170",
        "--direct-normal",
        "800",
        "--direct-only",
        "--export",
        direct_only.to_str().unwrap(),
        "--expnr",
        "001",
    ]);
    assert!(ok, "{stderr}");
    for name in ["Sdir.txt.001", "facetarea.inp.001"] {
        let (a, b) = (
            std::fs::read(out.join(name)).unwrap(),
            std::fs::read(direct_only.join(name)).unwrap(),
        );
        assert_eq!(a, b, "{name}");
    }
    let written: Vec<_> =
        std::fs::read_dir(&direct_only).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(written.len(), 2, "{written:?}");

    // A day: one column per time in Sdir.txt and timedepsw.inp, times in seconds.
    let day = dir.join("day.csv");
    std::fs::write(&day, "time,zenith,azimuth,direct_normal,diffuse_horizontal\n36000,40,150,700,90\n43200,30,180,800,100\n").unwrap();
    let out = dir.join("day");
    let args = [
        "sun",
        "--scene",
        scene,
        "--refine",
        "0",
        "--sun-positions",
        day.to_str().unwrap(),
        "--export",
        out.to_str().unwrap(),
    ];
    let (ok, _, stderr) = radiosity(&args);
    assert!(ok, "{stderr}");
    let timed = lines_after(&out.join("timedepsw.inp"), Some(TIMEDEPSW_HEADER));
    assert_eq!(timed.len(), 8);
    assert_eq!(timed[0].split_whitespace().collect::<Vec<_>>(), ["36000.00", "43200.00"]);
    assert!(lines_after(&out.join("Sdir.txt"), None).iter().all(|l| l.split(' ').count() == 2));
    assert!(!out.join("netsw.inp").exists());
    // Labels that are no seconds, and a refined mesh, are refused before the work.
    std::fs::write(
        &day,
        "time,zenith,azimuth,direct_normal,diffuse_horizontal\n10:00,40,150,700,90\n",
    )
    .unwrap();
    let (ok, _, stderr) = radiosity(&args);
    assert!(!ok && stderr.contains("10:00") && stderr.contains("seconds"), "{stderr}");
    let (ok, _, stderr) = radiosity(&[
        "sun",
        "--scene",
        scene,
        "--refine",
        "1",
        "--zenith",
        "30",
        "--azimuth",
        "170",
        "--direct-normal",
        "800",
        "--export",
        out.to_str().unwrap(),
    ]);
    assert!(!ok && stderr.contains("--refine 0"), "{stderr}");
}

#[test]
fn a_scene_file_s_sun_and_sky_tables_are_its_sources() {
    use crate::common::{json, radiosity, temp_dir};
    let dir = temp_dir("sun-tables");
    let faces = r#"name = "court"
[[faces]]
name = "ground"
vertices = [[0, 0, 0], [10, 0, 0], [10, 10, 0], [0, 10, 0]]
rho = 0.2
[[faces]]
name = "wall"
vertices = [[0, 10, 0], [10, 10, 0], [10, 10, 6], [0, 10, 6]]
rho = 0.4
"#;
    let write = |name: &str, tables: &str| {
        let path = dir.join(name);
        std::fs::write(&path, format!("{faces}{tables}")).unwrap();
        path.to_str().unwrap().to_string()
    };
    let with_tables = write(
        "court.toml",
        "[sun]\nzenith = 40\nazimuth = 170\nx_azimuth = 80\ndirect_normal = 750\n\
         [sky]\ndiffuse_horizontal = 90\n",
    );
    let bare = write("bare.toml", "");
    let from_file = json(&["sun", "--scene", &with_tables, "--refine", "1", "--json", "-"]);
    let from_flags = json(&[
        "sun",
        "--scene",
        &bare,
        "--refine",
        "1",
        "--zenith",
        "40",
        "--azimuth",
        "170",
        "--x-azimuth",
        "80",
        "--direct-normal",
        "750",
        "--diffuse-horizontal",
        "90",
        "--json",
        "-",
    ]);
    for key in ["absorbed", "received", "escaped", "sunlit_area", "sun", "direction"] {
        assert_eq!(from_file[key], from_flags[key], "{key}");
    }
    // The flags, all three given, override the tables.
    let overridden = json(&[
        "sun",
        "--scene",
        &with_tables,
        "--refine",
        "1",
        "--zenith",
        "20",
        "--azimuth",
        "170",
        "--direct-normal",
        "750",
        "--json",
        "-",
    ]);
    assert_eq!(
        (overridden["sun"]["zenith"].as_f64(), overridden["diffuse_horizontal"].as_f64()),
        (Some(20.0), Some(0.0))
    );
    // Refusals: no sun at all, a sky alone, an unknown key, a bad value, one flag of three.
    let sky_alone = write("sky.toml", "[sky]\ndiffuse_horizontal = 90\n");
    let unknown = write(
        "unknown.toml",
        "[sun]\nzenith = 40\nazimuth = 1\ndirect_normal = 1\nelevation = 50\n",
    );
    let bad = write("bad.toml", "[sun]\nzenith = 400\nazimuth = 1\ndirect_normal = 1\n");
    for (args, named) in [
        (vec!["sun", "--scene", &bare], "give --zenith, --azimuth and --direct-normal"),
        (vec!["sun", "--scene", &sky_alone], "a [sky] table needs a [sun] table"),
        (vec!["sun", "--scene", &unknown], "elevation"),
        (vec!["sun", "--scene", &bad], "sun zenith"),
        (vec!["sun", "--scene", &bare, "--zenith", "30"], "--azimuth"),
    ] {
        let (ok, _, stderr) = radiosity(&args);
        assert!(!ok && stderr.contains(named), "{args:?}: {stderr}");
    }
}

#[test]
fn direct_light_alone_skips_the_view_factors_and_keeps_the_direct_figures() {
    use crate::common::json;
    let args = [
        "sun",
        "--scene",
        "city:2x1",
        "--refine",
        "1",
        "--zenith",
        "50",
        "--azimuth",
        "230",
        "--direct-normal",
        "700",
        "--json",
        "-",
    ];
    let full = json(&args);
    let mut alone_args = args.to_vec();
    alone_args.push("--direct-only");
    let alone = json(&alone_args);
    assert!(alone["view_factor_tolerance"].is_null() && alone["sky_view_factor_min"].is_null());
    assert_eq!(alone["iterations"], 0);
    for key in ["received", "sunlit_area", "area_facing_sun"] {
        assert_eq!(alone[key], full[key], "{key}");
    }
    // Reflections not followed: what is not absorbed escapes.
    let number = |v: &serde_json::Value, key: &str| v[key].as_f64().unwrap();
    assert!(number(&alone, "relative_gap") <= 1e-12, "{alone}");
    assert!(number(&alone, "absorbed") < number(&full, "absorbed"));
}
