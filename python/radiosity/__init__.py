"""Collocation solver for the occluded radiosity equation on polyhedral surfaces.

The same runs as the ``radiosity`` command line, in NumPy and SciPy::

    import radiosity
    scene = radiosity.Scene.builtin("five-piece")
    run = radiosity.solve(scene, refine=4)
    run.error, run.u, run.nodes            # as `radiosity solve --json` reports them

    op = radiosity.operator(radiosity.Scene.load("room.toml"), refine=3)
    u = op.solve(E)                        # E per face or per node; one column per case
    F = radiosity.view_factors(scene, refine=1)   # scipy.sparse.csr_matrix

Options take the command line's names and defaults (``--compression-tolerance`` is
``compression_tolerance``). Errors are raised as :class:`RadiosityError` with the library's
message.
"""

from __future__ import annotations

import json
from typing import TYPE_CHECKING, Any, Callable, Optional

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

from . import _native
from ._native import RadiosityError, Scene

if TYPE_CHECKING:
    import os

    import numpy.typing as npt
    from typing_extensions import Unpack

    from ._native import _Coplanar, _Path, _Progress, _RunKwargs, _RunOptions, _RunResult

__all__ = [
    "RadiosityError",
    "Scene",
    "Solution",
    "Operator",
    "ViewFactors",
    "solve",
    "operator",
    "view_factors",
    "from_arrays",
    "tqdm_progress",
]

# The library's defaults, which are the command line's (radiosity solve --help).
_DEFAULTS: dict[str, Any] = dict(_native.default_options())


def _options(given: dict[str, Any]) -> _RunOptions:
    unknown = sorted(set(given) - set(_DEFAULTS))
    if unknown:
        raise TypeError(f"unknown options {unknown}; known: {sorted(_DEFAULTS)}")
    options = dict(_DEFAULTS)
    options.update(given)
    return options  # type: ignore[return-value]


def from_arrays(
    vertices: npt.ArrayLike,
    triangles: npt.ArrayLike,
    rho: npt.ArrayLike,
    emission: npt.ArrayLike = 0.0,
    name: str = "mesh",
    coplanar: Optional[_Coplanar] = None,
) -> Scene:
    """A scene from a triangle mesh: ``vertices`` (m x 3), ``triangles`` (t x 3 indices into
    them), ``rho`` and ``emission`` per triangle or one value for all. Read as an STL file is:
    coplanar triangles that share edges and properties are merged into faces for visibility
    (``coplanar="keep"`` keeps them apart); the triangles stay the elements."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float64)
    triangles = np.ascontiguousarray(triangles, dtype=np.int64)
    count = len(triangles)
    rho = np.ascontiguousarray(np.broadcast_to(np.asarray(rho, dtype=np.float64), (count,)))
    emission = np.ascontiguousarray(
        np.broadcast_to(np.asarray(emission, dtype=np.float64), (count,))
    )
    return Scene.from_arrays(vertices, triangles, rho, emission, name, coplanar)


class Solution:
    """One run: ``u`` at the nodes, their positions ``nodes`` (dof x 3) and faces ``faces``,
    E at the nodes ``emission``, and every key of ``radiosity solve --json`` as an attribute
    (``error``, ``setup_seconds``, ``iterations``, ...; ``report`` holds them all). With
    emission cases, ``cases_u`` holds one column of u per case and ``u`` is their mean; with
    colour bands (``bands="rgb"``), ``bands_u`` one column per band."""

    u: npt.NDArray[np.float64]
    nodes: npt.NDArray[np.float64]
    faces: npt.NDArray[np.uintp]
    emission: npt.NDArray[np.float64]
    cases_u: Optional[npt.NDArray[np.float64]]
    bands_u: Optional[npt.NDArray[np.float64]]
    report: dict[str, Any]

    def __init__(self, raw: _RunResult) -> None:
        self.u = raw["u"]
        self.nodes = raw["nodes"]
        self.faces = raw["faces"]
        self.emission = raw["emission"]
        self.cases_u = raw.get("cases_u")
        self.bands_u = raw.get("bands_u")
        self.report = json.loads(raw["report"])

    def __getattr__(self, name: str) -> Any:
        report = self.__dict__.get("report", {})
        if name in report:
            return report[name]
        raise AttributeError(f"a solution has no '{name}'; its report has {sorted(report)}")

    def __repr__(self) -> str:
        r = self.report
        return f"Solution({r['surface']!r}, n={r['n']}, dof={r['dof']}, error={r['error']})"


def solve(
    scene: Scene,
    emission: Optional[npt.ArrayLike] = None,
    progress: Optional[_Progress] = None,
    **options: Unpack[_RunKwargs],
) -> Solution:
    """Solves the radiosity equation on ``scene`` as ``radiosity solve`` does, with its
    options (``refine``, ``method``, ``operator``, ``solver``, ``solution``, ``backend``, ...).
    ``emission`` replaces the scene's emission: per face (``scene.face_names`` order) or per
    node, one column per case for many cases. ``progress`` is a callable
    ``progress(stage, done, total)`` (see :func:`tqdm_progress`)."""
    if emission is not None:
        emission = np.ascontiguousarray(emission, dtype=np.float64)
    raw = _native.solve(scene, _options(dict(options)), emission, progress)
    return Solution(raw)


class Operator(scipy.sparse.linalg.LinearOperator):
    """The collocation operator K of one problem, built once (dense or compressed, as
    ``operator=`` chooses), as a SciPy ``LinearOperator`` (``op @ x`` is ``K x``).
    ``solve(E)`` solves ``(I - K) u = E`` for E per face or per node, a vector or one column
    per case (LU factors once for all of them; on the compressed operator the cases advance
    together through GMRES, one pass over the blocks per round of products). ``nodes`` (dof x 3),
    ``faces`` and ``rho`` describe the unknowns; ``report`` the operator (as in
    ``solve --json``)."""

    nodes: npt.NDArray[np.float64]
    faces: npt.NDArray[np.uintp]
    rho: npt.NDArray[np.float64]
    report: dict[str, Any]
    last_reports: list[dict[str, Any]]

    def __init__(self, native: _native.NativeOperator) -> None:
        self._native = native
        self.report = json.loads(native.report)
        self.nodes, self.faces, self.rho = native.nodes()
        super().__init__(dtype=np.float64, shape=(native.dof, native.dof))

    def _matvec(self, x: npt.ArrayLike) -> npt.NDArray[np.float64]:
        x = np.ascontiguousarray(np.ravel(x), dtype=np.float64)
        return self._native.matvec(x)

    def save(self, path: _Path) -> None:
        """Saves the operator for ``operator(scene, operator_file=path, ...)`` (the same
        scene and options) and ``radiosity solve --operator-file``."""
        self._native.save(str(path))

    def solve(self, emission: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """u with ``(I - K) u = E`` for each column of ``emission``; ``self.last_reports``
        then holds each case's solver report (solver, iterations, residual)."""
        emission = np.ascontiguousarray(emission, dtype=np.float64)
        u, reports = self._native.solve(emission)
        self.last_reports = [json.loads(r) for r in reports]
        return u


def operator(
    scene: Scene, progress: Optional[_Progress] = None, **options: Unpack[_RunKwargs]
) -> Operator:
    """The operator of ``scene`` for the run ``options`` describe (as :func:`solve` takes
    them), built once for products and many solves; or read from ``operator_file`` (saved by
    :meth:`Operator.save` or ``radiosity assemble --save``), which must have been built for the
    same scene, mesh, method and tolerance."""
    return Operator(_native.operator(scene, _options(dict(options)), progress))


class ViewFactors(scipy.sparse.csr_matrix):
    """Element-to-element view factors F_ij as a SciPy CSR matrix of the non-zero entries,
    with the element ``areas``, each element's ``sky_view_factors`` (1 - its row's sum) and
    the ``summary`` of ``radiosity viewfactors --json`` (reciprocity, row sums, error
    estimate, what conditioning and a threshold changed)."""

    areas: npt.NDArray[np.float64]
    sky_view_factors: npt.NDArray[np.float64]
    summary: dict[str, Any]


def view_factors(
    scene: Scene,
    refine: int = 0,
    tolerance: float = 1e-10,
    max_depth: int = 0,
    each_direction: bool = False,
    condition: bool = False,
    drop_below: Optional[float] = None,
    progress: Optional[_Progress] = None,
) -> ViewFactors:
    """View factors between the elements of the scene's uniform mesh at ``refine``, each to
    the absolute ``tolerance``, as ``radiosity viewfactors`` computes them: each pair
    integrated once, over the smaller element (F_ji = A_i F_ij / A_j), or with
    ``each_direction`` both, so that reciprocity checks the accuracy. ``condition``: made
    reciprocal exactly with no row above 1, no entry moved beyond the run's error estimate
    (``RadiosityError`` naming the entry otherwise); ``drop_below``: pairs whose two entries
    are below it dropped."""
    indptr, indices, data, n, areas, sky, summary = _native.view_factors(
        scene,
        refine,
        tolerance,
        max_depth,
        each_direction,
        condition=condition,
        drop_below=drop_below,
        progress=progress,
    )
    f = ViewFactors((data, indices, indptr), shape=(n, n))
    f.areas = areas
    f.sky_view_factors = sky
    f.summary = json.loads(summary)
    return f


def tqdm_progress() -> Callable[[str, int, int], None]:
    """A progress callable that draws one tqdm bar per stage (``pip install tqdm``)."""
    from tqdm import tqdm

    bars: dict[str, Any] = {}

    def progress(stage: str, done: int, total: int) -> None:
        if stage.startswith("note: "):
            tqdm.write(stage)
            return
        bar = bars.get(stage)
        if bar is None:
            bar = bars[stage] = tqdm(total=total or None, desc=stage)
        bar.update(done - bar.n)
        if total and done >= total:
            bar.close()

    return progress
