//! Scene files end to end: TOML faces, groups, sides and meshes, OBJ/STL import, errors that
//! name the culprit, non-planar polygons split and exact duplicates dropped.

use std::path::PathBuf;

use super::*;
use crate::scene::Colour;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("radiosity-scene-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn toml_faces_groups_sides_and_meshes() {
    let dir = temp_dir("toml");
    write(
        &dir,
        "box.obj",
        "mtllib box.mtl\no lid\nusemtl glow\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nf 1 2 3 4\n\
         o side\nv 0 0 0\nv 1 0 0\nv 1 0 1\nf 5 6 7\n",
    );
    write(&dir, "box.mtl", "newmtl glow\nKd 0.1 0.2 0.3\nKe 2 2 2\n");
    let p = write(
        &dir,
        "s.toml",
        r#"
name = "test"
[defaults]
rho = 0.5
[groups.side]
rho = 0.9
[[faces]]
name = "floor"
vertices = [[0, 0, -1], [2, 0, -1], [2, 2, -1], [0, 2, -1]]
normal = [0, 0, 1]
emission = 3.0
[[faces]]
name = "plate"
vertices = [[0, 0, 3], [1, 0, 3], [1, 1, 3]]
radiates = "both"
rho = [0.25, 0.5, 0.75]
emission = [1, 0, 0.5]
[[meshes]]
file = "box.obj"
translate = [0, 0, 0.5]
rho = 0.7
"#,
    );
    let s = load(&p).unwrap();
    assert_eq!(s.name, "test");
    let names: Vec<&str> = s.faces.iter().map(|f| f.name.as_str()).collect();
    // OBJ faces by file and line, with their group and material.
    let (lid, side) =
        ("box/box.obj:8 (g lid; usemtl glow)", "box/box.obj:13 (g side; usemtl glow)");
    assert_eq!(names, ["floor", "plate", "plate.back", lid, side]);
    let f = |n: &str| &s.faces[s.face_index(n).unwrap()];
    assert_eq!((f("floor").rho, f("floor").emission), (0.5, 3.0));
    assert!((f("plate").frame.normal + f("plate.back").frame.normal).length() < 1e-15);
    // Per channel in the file: the means for the grey problem, the channels kept.
    let plate = f("plate.back");
    assert_eq!((plate.rho, plate.emission), (0.5, 0.5));
    assert_eq!(plate.colour.rho, Some([0.25, 0.5, 0.75]));
    assert_eq!((plate.channel(0), plate.channel(2)), ((0.25, 1.0), (0.75, 0.5)));
    assert_eq!(f("floor").colour, Colour::default());
    // The material's Kd and Ke, above the mesh entry's rho.
    let lid = f(lid);
    assert!((lid.rho - 0.2).abs() < 1e-7 && lid.emission == 2.0, "{} {}", lid.rho, lid.emission);
    assert!((lid.vertices[0].z - 1.5).abs() < 1e-15);
    assert_eq!(lid.colour.rho.map(|c| c.map(|x| x as f32)), Some([0.1, 0.2, 0.3]));
    // The group's rho above the mesh entry's, and above the material's channels.
    assert_eq!((f(side).rho, f(side).colour.rho), (0.9, None));
}

#[test]
fn bad_scene_files_name_the_culprit() {
    let dir = temp_dir("bad");
    let cases = [
        ("name = 3", "invalid type"),
        ("[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]", "no rho"),
        (
            "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nnormal = [0,0,-1]",
            "normal",
        ),
        (
            "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\ngroup = \"g\"",
            "unknown group 'g'",
        ),
        ("[groups.g]\nrho = 2.0", "rho = 2"),
        ("[groups.g]\nrho = [0.5, 2.0, 0.5]", "rho = 2"),
        (
            "[defaults]\nrho = [0.5, 0.5, 1.5]\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]",
            "'a (channel b)'",
        ),
        ("[defaults]\nrho = \"x\"", "expected a number, or three numbers [r, g, b]"),
        ("[defaults]\nrho = [0.5, 0.5]", "invalid length 2"),
        ("[defaults]\nemission = [1, 1, 1, 1]", "invalid length 4"),
        ("[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\nrh = 1", "unknown field"),
        ("[defaults]\nrho = 0.5\n[[meshes]]\nfile = \"missing.obj\"", "missing.obj"),
        (
            "[defaults]\nrho = 0.5\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,nan],[0,1,0]]",
            "non-finite",
        ),
        (
            "[defaults]\nrho = 0.5\nradiates = \"both\"\n[[faces]]\nname = \"a\"\nvertices = [[0,0,0],[1,0,0],[0,1,0]]\n[[faces]]\nname = \"a.back\"\nvertices = [[0,0,1],[1,0,1],[0,1,1]]",
            "unique",
        ),
    ];
    for (k, (text, expect)) in cases.iter().enumerate() {
        let p = write(&dir, &format!("bad{k}.toml"), text);
        let e = load(&p).unwrap_err().to_string();
        assert!(e.contains(expect), "case {k}: {e}");
    }
    let p = write(&dir, "broken.obj", "v 0 0 0\nv 1 0 0\nf 1 2 9\n");
    assert!(load(&p).is_err());
    let p = write(&dir, "scene.ply", "");
    assert!(load(&p).unwrap_err().to_string().contains(".toml"));
}

#[test]
fn stl_triangles_become_faces_with_the_import_rho() {
    let dir = temp_dir("stl");
    let text = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
                vertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
    let p = write(&dir, "tri.stl", text);
    let s = load(&p).unwrap();
    assert_eq!(s.faces.len(), 1);
    assert_eq!((s.faces[0].name.as_str(), s.faces[0].rho), ("tri/0", IMPORT_RHO));
}

/// The view factor from a point at `p` with normal `n` to a planar polygon facing it, by
/// Lambert's contour formula (independent of the code under test).
fn point_view_factor(p: DVec3, n: DVec3, polygon: &[DVec3]) -> f64 {
    let k = polygon.len();
    let sum: f64 = (0..k)
        .map(|i| {
            let (a, b) = (polygon[i] - p, polygon[(i + 1) % k] - p);
            let c = a.cross(b);
            c.length().atan2(a.dot(b)) * n.dot(c) / c.length()
        })
        .sum();
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

#[test]
fn a_slightly_non_planar_quad_is_split_along_its_shorter_diagonal() {
    let dir = temp_dir("warped");
    // A quadrilateral at z = 1 facing down, vertex 3 lifted by delta (f32-exact values, as
    // tobj reads f32); diagonal 0-2 (2.02) is shorter than 1-3 (2.24).
    let delta = 2f64.powi(-10);
    let corners = [[0.0, 0.0, 1.0], [0.0, 1.0, 1.0], [1.75, 1.0, 1.0], [2.0, 0.0, 1.0 + delta]];
    let mut text = String::new();
    for c in corners {
        text += &format!("v {} {} {}\n", c[0], c[1], c[2]);
    }
    text += "g warped\nf 1 2 3 4\n";
    let p = write(&dir, "warped.obj", &text);
    let s = load(&p).unwrap();
    let names: Vec<&str> = s.faces.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["warped.obj:6 (g warped)/t0", "warped.obj:6 (g warped)/t1"]);
    let v: Vec<DVec3> = corners.iter().map(|&c| DVec3::from_array(c)).collect();
    assert_eq!(s.faces[0].vertices, [v[0], v[1], v[2]]);
    assert_eq!(s.faces[1].vertices, [v[0], v[2], v[3]]);
    assert_eq!(s.notes.len(), 1, "{:?}", s.notes);
    assert!(s.notes[0].contains("split 1 non-planar"), "{:?}", s.notes);
    // Seen from points below, the two triangles' view factors sum to the flat quad's within
    // the quad's non-planarity relative to the point's distance (delta / height).
    let mut flat = v.clone();
    flat[3].z = 1.0;
    for p in [DVec3::new(1.0, 0.5, 0.0), DVec3::new(-0.5, 2.0, 0.3), DVec3::new(1.9, 0.1, 0.9)] {
        let halves: f64 = s.faces.iter().map(|f| point_view_factor(p, DVec3::Z, &f.vertices)).sum();
        let quad = point_view_factor(p, DVec3::Z, &flat);
        assert!((halves - quad).abs() <= delta / (1.0 - p.z), "{p}: {halves} vs {quad}");
        assert!((halves - quad).abs() > 1e-9, "{p}: the warp must show");
    }
    // Refused on request, naming the line.
    let refuse = ImportOptions { nonplanar: Some(NonPlanar::Refuse), ..Default::default() };
    let e = load_with(&p, refuse).unwrap_err().to_string();
    assert!(e.contains("warped.obj:6") && e.contains("not planar"), "{e}");
    // A typed TOML face is refused unless splitting is asked for.
    let toml = "[defaults]\nrho = 0.5\n[[faces]]\nname = \"w\"\n\
        vertices = [[0, 0, 1], [0, 1, 1], [1.75, 1, 1], [2, 0, 1.001]]\n";
    let t = write(&dir, "warped.toml", toml);
    assert!(load(&t).unwrap_err().to_string().contains("'w': not planar"));
    let split = ImportOptions { nonplanar: Some(NonPlanar::Split), ..Default::default() };
    assert_eq!(load_with(&t, split).unwrap().faces.len(), 2);
}

#[test]
fn exact_duplicates_are_dropped_and_counted_partial_overlaps_refused() {
    let dir = temp_dir("dups");
    let square = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0 0\nv 1.5 0 0\nv 1.5 1 0\nv 0.5 1 0\n";
    // Face 2 repeats face 1 from another vertex on; face 3 is its other side (a plate).
    let p = write(&dir, "dup.obj", &format!("{square}f 1 2 3 4\nf 3 4 1 2\nf 4 3 2 1\n"));
    let s = load(&p).unwrap();
    assert_eq!(s.faces.len(), 2);
    assert_eq!(s.notes.len(), 1);
    assert!(
        s.notes[0].contains("dropped 1 face") && s.notes[0].contains("'dup.obj:10"),
        "{:?}",
        s.notes
    );
    // Kept on request: then refused as overlapping, both named by line.
    let keep = ImportOptions { duplicates: Some(Duplicates::Refuse), ..Default::default() };
    let e = load_with(&p, keep).unwrap_err().to_string();
    assert!(e.contains("'dup.obj:9") && e.contains("'dup.obj:10") && e.contains("overlap"));
    // Half a square over another is no duplicate: refused.
    let p = write(&dir, "half.obj", &format!("{square}f 1 2 3 4\nf 5 6 7 8\n"));
    let e = load(&p).unwrap_err().to_string();
    assert!(e.contains("overlap") && e.contains("5e-1"), "{e}");
    // The same vertices with another material are no duplicate either.
    write(&dir, "two.mtl", "newmtl a\nKd 0.5 0.5 0.5\nnewmtl b\nKd 0.2 0.2 0.2\n");
    let text = format!("mtllib two.mtl\n{square}usemtl a\nf 1 2 3 4\nusemtl b\nf 1 2 3 4\n");
    let p = write(&dir, "two.obj", &text);
    assert!(load(&p).unwrap_err().to_string().contains("overlap"));
}
