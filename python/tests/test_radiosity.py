"""The Python package against the command line: the same runs give the same numbers."""

import csv
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
import scipy.sparse

import radiosity

ROOT = pathlib.Path(__file__).resolve().parents[2]
ROOM = str(ROOT / "examples" / "furnished-room.toml")


def binary():
    path = pathlib.Path(os.environ.get("RADIOSITY_BIN", ROOT / "target" / "release" / "radiosity"))
    if not path.is_file():
        pytest.fail(f"no radiosity binary at {path}: build it with `cargo build --release` "
                    "(or set RADIOSITY_BIN)")
    return str(path)


def cli(*args):
    out = subprocess.run([binary(), *args], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return out.stdout


def cli_solve(tmp_path, *args):
    """The CLI's report and its nodal u (from --csv)."""
    table = tmp_path / "nodes.csv"
    report = json.loads(cli("solve", *args, "--json", "-", "--csv", str(table)))
    with open(table) as f:
        rows = list(csv.DictReader(f))
    return report, np.array([float(r["u"]) for r in rows])


def relative_max(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


@pytest.mark.parametrize("method", ["centroid", "linear"])
def test_five_piece_equals_the_command_line(tmp_path, method):
    run = radiosity.solve(radiosity.Scene.builtin("five-piece"), refine=3, method=method)
    report, u = cli_solve(tmp_path, "--scene", "five-piece", "--refine", "3", "--method", method)
    assert run.error == report["error"]
    assert run.dof == report["dof"] and run.solver == report["solver"]
    assert relative_max(run.u, u) <= 1e-14
    assert run.nodes.shape == (run.dof, 3)


def test_the_paper_s_error_at_refine_4():
    run = radiosity.solve(radiosity.Scene.builtin("five-piece"), refine=4)
    assert f"{run.error:.4f}" == "0.5114"


@pytest.mark.parametrize("operator", ["dense", "compressed"])
def test_the_furnished_room_equals_the_command_line(tmp_path, operator):
    solver = "auto" if operator == "dense" else "iterative"
    run = radiosity.solve(radiosity.Scene.load(ROOM), refine=2, operator=operator, solver=solver)
    report, u = cli_solve(tmp_path, "--scene", ROOM, "--refine", "2", "--operator", operator,
                          "--solver", solver)
    assert run.operator == report["operator"] == operator
    # The compressed operator's products sum their blocks in a fixed order: the same bits.
    assert relative_max(run.u, u) <= 1e-14
    assert run.error is None and run.report["notes"] == report["notes"]


def test_view_factors_equal_the_command_line_s_npz(tmp_path):
    path = tmp_path / "f.npz"
    cli("viewfactors", "--scene", "examples/occluded-box.toml", "--refine", "1",
        "--output", str(path))
    f = radiosity.view_factors(radiosity.Scene.load(str(ROOT / "examples/occluded-box.toml")),
                               refine=1)
    expected = scipy.sparse.load_npz(path)
    assert isinstance(f, scipy.sparse.csr_matrix) and f.shape == expected.shape
    assert (f != expected).nnz == 0
    # A closed scene: every row sums to 1; reciprocity A_i F_ij = A_j F_ji, by construction
    # (each pair integrated once) to rounding.
    assert np.allclose(f.sum(axis=1), 1.0, atol=1e-9)
    af = scipy.sparse.diags(f.areas) @ f
    reciprocity = abs(af - af.T).max() / af.max()
    assert not f.summary["each_direction"]
    assert reciprocity < 1e-14 and f.summary["reciprocity_error"] < 1e-14
    assert f.summary["nonzeros"] == f.nnz


def test_view_factors_in_each_direction_are_reciprocal_to_their_accuracy():
    scene = radiosity.Scene.load(str(ROOT / "examples/occluded-box.toml"))
    once = radiosity.view_factors(scene, refine=0)
    both = radiosity.view_factors(scene, refine=0, each_direction=True)
    assert both.summary["each_direction"]
    assert 0 < both.summary["reciprocity_error"] < 1e-8
    assert abs(once - both).max() < 1e-8


def test_view_factors_give_sky_view_factors_and_condition_as_the_command_line(tmp_path):
    path = tmp_path / "f.npz"
    cli("viewfactors", "--scene", "city:3x2", "--refine", "0", "--tolerance", "1e-4",
        "--each-direction", "--condition", "--drop-below", "1e-4", "--output", str(path))
    scene = radiosity.Scene.builtin("city:3x2")
    f = radiosity.view_factors(scene, refine=0, tolerance=1e-4, each_direction=True,
                               condition=True, drop_below=1e-4)
    assert (f != scipy.sparse.load_npz(path)).nnz == 0
    assert np.array_equal(f.sky_view_factors, np.load(path)["sky_view_factors"])
    assert np.allclose(f.sky_view_factors, 1.0 - np.asarray(f.sum(axis=1)).ravel(), atol=1e-15)
    assert f.sky_view_factors.min() >= 0.0 and f.summary["reciprocity_error"] <= 1e-15
    assert 0 < f.summary["conditioning"]["largest_change"] <= f.summary["error_estimate"]
    assert f.summary["dropped"]["entries"] > 0
    with pytest.raises(radiosity.RadiosityError, match="drop-below"):
        radiosity.view_factors(scene, refine=0, drop_below=2.0)


def test_an_operator_solves_many_cases_as_each_solve():
    scene = radiosity.Scene.load(ROOM)
    op = radiosity.operator(scene, refine=2)
    assert op.shape == (op.faces.size, op.faces.size) and op.report["operator"] == "dense"
    lamp = np.array([1.0 if name == "lamp" else 0.0 for name in scene.face_names])
    floor = np.array([1.0 if name == "floor" else 0.0 for name in scene.face_names])
    u = op.solve(np.column_stack([lamp, floor, 2 * lamp + floor]))
    assert u.shape == (op.shape[0], 3)
    own = radiosity.solve(scene, refine=2)
    assert np.array_equal(u[:, 0], own.u)  # the scene's lamp is its only emitter, E = 1
    assert relative_max(u[:, 2], 2 * u[:, 0] + u[:, 1]) <= 1e-13
    assert np.array_equal(op.solve(lamp), u[:, 0])
    assert [r["solver"] for r in op.last_reports] == ["lu"]
    # A closed room: the rows of K / rho sum to 1, so K 1 = rho at every node.
    assert np.max(np.abs(op @ np.ones(op.shape[0]) - op.rho)) <= 1e-12
    x = np.random.default_rng(1).random(op.shape[0])
    assert np.allclose(op.matvec(x), op @ x)


def test_a_mesh_from_arrays_is_the_same_scene_as_its_stl_file(tmp_path):
    # A closed unit box of twelve triangles, its top emitting.
    v = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    emission = np.zeros(12)
    emission[2:4] = 1.0
    scene = radiosity.from_arrays(v, triangles, rho=0.5, emission=emission, name="box")
    assert len(scene) == 6 and "faces_merged: 12 -> 6" in " ".join(scene.notes)
    run = radiosity.solve(scene, refine=1)
    assert run.report["warnings"] == []
    kept = radiosity.solve(radiosity.from_arrays(v, triangles, 0.5, emission, coplanar="keep"),
                           refine=1)
    assert relative_max(run.u, kept.u) <= 1e-13


def test_the_memory_limit_refuses_as_on_the_command_line():
    # The louvre room at refine 3 (n = 3 584): its compressed operator takes about 40 MB, its
    # dense matrix 0.1 GB (tests/suite/cli_operator.rs makes the same runs).
    room = radiosity.Scene.load(str(ROOT / "examples" / "louvre-room.toml"))
    for operator in ["dense", "compressed"]:
        with pytest.raises(radiosity.RadiosityError, match="3584"):
            radiosity.operator(room, refine=3, operator=operator, memory_limit="40M")
    op = radiosity.operator(room, refine=3, operator="compressed", memory_limit=1 << 30)
    assert op.shape == (3584, 3584)
    for limit, needle in [("12X", "K, M, G or T"), ("manyG", "no size"), (0, "at least one")]:
        with pytest.raises(radiosity.RadiosityError, match=needle):
            radiosity.operator(room, refine=0, memory_limit=limit)
    # A later run without a limit is not held to the last one's.
    assert radiosity.operator(room, refine=3, operator="dense").shape == (3584, 3584)


def test_errors_carry_the_library_s_message():
    scene = radiosity.Scene.builtin("five-piece")
    with pytest.raises(radiosity.RadiosityError, match="operator 'sparse' is not known"):
        radiosity.solve(scene, refine=0, operator="sparse")
    with pytest.raises(TypeError, match="unknown options"):
        radiosity.solve(scene, refin=0)
    with pytest.raises(radiosity.RadiosityError, match="five"):
        radiosity.Scene.builtin("five")
    with pytest.raises(radiosity.RadiosityError, match="no such file"):
        radiosity.Scene.load("/nonexistent/room.toml")
    v = np.eye(3)
    with pytest.raises(radiosity.RadiosityError, match="mesh/0"):
        radiosity.from_arrays(v, [[0, 1, 2]], rho=1.5)
    with pytest.raises(radiosity.RadiosityError, match="vertex 7"):
        radiosity.from_arrays(v, [[0, 1, 7]], rho=0.5)
    op = radiosity.operator(radiosity.Scene.load(ROOM), refine=0)
    with pytest.raises(radiosity.RadiosityError, match="one row per face"):
        op.solve(np.ones(5))


def test_progress_reaches_the_callback():
    seen = []
    radiosity.solve(radiosity.Scene.builtin("five-piece"), refine=2,
                    progress=lambda stage, done, total: seen.append((stage, done, total)))
    stages = {s for s, _, _ in seen}
    assert {"assembly", "solve"} <= stages, stages
    assembly = [(d, t) for s, d, t in seen if s == "assembly"]
    assert assembly[-1][0] == assembly[-1][1] > 0


def test_a_saved_operator_reloads_and_refuses_another_problem(tmp_path):
    scene = radiosity.Scene.load(ROOM)
    e = np.random.default_rng(2).random(len(scene))
    for kind in ["dense", "compressed"]:
        path = tmp_path / f"{kind}.bin"
        options = dict(refine=2, operator=kind, solver="iterative")
        op = radiosity.operator(scene, **options)
        op.save(path)
        loaded = radiosity.operator(scene, operator_file=str(path), **options)
        assert loaded.report["operator"] == kind
        tolerance = 0.0 if kind == "dense" else 1e-12
        assert relative_max(loaded.solve(e), op.solve(e)) <= tolerance
        # The CLI reads what Python saved.
        report = json.loads(cli("solve", "--scene", ROOM, "--refine", "2", "--solver",
                                "iterative", "--operator-file", str(path), "--json", "-"))
        assert report["operator"] == kind
        with pytest.raises(radiosity.RadiosityError, match="saved for another problem"):
            radiosity.operator(scene, refine=1, operator_file=str(path))
    path.write_bytes(path.read_bytes()[:-100])
    with pytest.raises(radiosity.RadiosityError, match="truncated"):
        radiosity.operator(scene, refine=2, operator_file=str(path))


def test_colour_bands_equal_the_command_line(tmp_path):
    box = str(ROOT / "examples" / "cornell-box" / "CornellBox-Original.obj")
    run = radiosity.solve(radiosity.Scene.load(box), refine=1, bands="rgb")
    table = tmp_path / "bands.csv"
    report = json.loads(cli("solve", "--scene", box, "--refine", "1", "--bands", "rgb",
                            "--json", "-", "--csv", str(table)))
    with open(table) as f:
        rows = list(csv.DictReader(f))
    assert [b["band"] for b in run.bands] == [b["band"] for b in report["bands"]]
    for k, band in enumerate("rgb"):
        expected = np.array([float(r[f"u_{band}"]) for r in rows])
        assert relative_max(run.bands_u[:, k], expected) <= 1e-14
    with pytest.raises(radiosity.RadiosityError, match="band 'x'"):
        radiosity.solve(radiosity.Scene.load(box), refine=0, bands="r,x")


def test_the_gpu_backend_equals_the_cpu():
    # Without an adapter the library's error says how to install one (lavapipe); only
    # RADIOSITY_GPU=skip skips, as for the Rust GPU tests.
    if os.environ.get("RADIOSITY_GPU") == "skip":
        pytest.skip("RADIOSITY_GPU=skip")
    scene = radiosity.Scene.builtin("five-piece")
    gpu = radiosity.solve(scene, refine=3, backend="gpu")
    cpu = radiosity.solve(scene, refine=3)
    assert gpu.backend == "gpu" and gpu.device
    assert relative_max(gpu.u, cpu.u) <= 1e-12
