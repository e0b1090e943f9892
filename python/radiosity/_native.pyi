"""Type stubs of ``radiosity._native`` (python/src/lib.rs): the library's scenes, solves,
operators and view factors, NumPy arrays in and out.

Names starting with ``_`` exist only here (type aliases and dictionaries' shapes); every other
name is one the module defines, and python/tests/test_stubs.py checks that the two agree:
names, parameters, defaults and the ``Literal`` vocabularies (against ``option_values()``).
"""

import os
from typing import Callable, Literal, Optional, Union, final

import numpy as np
import numpy.typing as npt
from typing_extensions import NotRequired, TypedDict

# The options' fixed vocabularies (the command line's names).
_NonPlanar = Literal["split", "refuse"]
_Duplicates = Literal["drop", "refuse"]
_Coplanar = Literal["merge", "keep"]
_Method = Literal["centroid", "linear"]
_Mesh = Literal["uniform", "discontinuity", "discontinuity-uniform-diagonals", "auto-discontinuity"]
_ShadowLines = Literal["segments", "chords"]
_Solution = Literal["none", "x2y2", "shadow", "edge"]
_Backend = Literal["cpu", "gpu"]
_Precision = Literal["f64", "f32"]
_OperatorKind = Literal["auto", "dense", "compressed"]
_ShadowedBlocks = Literal["auto", "on", "off"]
_Solver = Literal["auto", "lu", "iterative"]

_Path = Union[str, os.PathLike[str]]
# progress(stage, done, total): total 0 where the stage's length is not known; notes come as
# progress("note: TEXT", 0, 0).
_Progress = Callable[[str, int, int], None]
_Floats = npt.NDArray[np.float64]
_Indices = npt.NDArray[np.uintp]

class _RunOptions(TypedDict):
    """Every option of a run, as `solve` and `operator` take them (the package fills in the
    command line's defaults). `bands` is "grey", "rgb" or a comma-separated list of r, g, b."""

    refine: int
    method: _Method
    alpha: Optional[float]
    mesh: _Mesh
    shadow_lines: _ShadowLines
    solution: Optional[_Solution]
    beta: Optional[float]
    gamma: Optional[float]
    backend: _Backend
    precision: _Precision
    storage: _Precision
    operator: _OperatorKind
    compression_tolerance: float
    shadowed_blocks: _ShadowedBlocks
    memory_limit: Optional[Union[int, str]]
    solver: _Solver
    tolerance: float
    operator_file: Optional[_Path]
    bands: str

class _RunKwargs(TypedDict, total=False):
    """The options of `radiosity.solve` and `radiosity.operator` as keywords: `_RunOptions`,
    each one optional (the command line's default where not given)."""

    refine: int
    method: _Method
    alpha: Optional[float]
    mesh: _Mesh
    shadow_lines: _ShadowLines
    solution: Optional[_Solution]
    beta: Optional[float]
    gamma: Optional[float]
    backend: _Backend
    precision: _Precision
    storage: _Precision
    operator: _OperatorKind
    compression_tolerance: float
    shadowed_blocks: _ShadowedBlocks
    memory_limit: Optional[Union[int, str]]
    solver: _Solver
    tolerance: float
    operator_file: Optional[_Path]
    bands: str

class _RunResult(TypedDict):
    """What `solve` returns: u and E at the nodes, the nodes' positions (dof x 3) and faces,
    the report (JSON of `radiosity solve --json`); with emission cases `cases_u` (dof x
    cases), with colour bands `bands_u` (dof x bands)."""

    u: _Floats
    nodes: _Floats
    faces: _Indices
    emission: _Floats
    report: str
    cases_u: NotRequired[_Floats]
    bands_u: NotRequired[_Floats]

class RadiosityError(ValueError):
    """What the library refused or could not do, with its message (the culprit named)."""

@final
class Scene:
    """A scene, from a file, a built-in name or arrays."""

    @staticmethod
    def load(
        path: _Path,
        nonplanar: Optional[_NonPlanar] = None,
        duplicates: Optional[_Duplicates] = None,
        coplanar: Optional[_Coplanar] = None,
    ) -> Scene: ...
    @staticmethod
    def builtin(name: str, params: tuple[float, float, float] = (5.0, 2.0, 1.0)) -> Scene: ...
    @staticmethod
    def from_arrays(
        vertices: npt.NDArray[np.float64],
        triangles: npt.NDArray[np.int64],
        rho: npt.NDArray[np.float64],
        emission: npt.NDArray[np.float64],
        name: str = "mesh",
        coplanar: Optional[_Coplanar] = None,
    ) -> Scene: ...
    @property
    def name(self) -> str: ...
    @property
    def face_names(self) -> list[str]: ...
    @property
    def notes(self) -> list[str]: ...
    def __len__(self) -> int: ...

@final
class NativeOperator:
    """The collocation operator K of one run's problem, built once."""

    @property
    def dof(self) -> int: ...
    @property
    def report(self) -> str: ...
    def nodes(self) -> tuple[_Floats, _Indices, _Floats]: ...
    def save(self, path: _Path) -> None: ...
    def matvec(self, x: npt.NDArray[np.float64]) -> _Floats: ...
    def solve(self, emission: npt.NDArray[np.float64]) -> tuple[_Floats, list[str]]: ...

def solve(
    scene: Scene,
    options: _RunOptions,
    emission: Optional[npt.NDArray[np.float64]] = None,
    progress: Optional[_Progress] = None,
) -> _RunResult: ...
def operator(
    scene: Scene, options: _RunOptions, progress: Optional[_Progress] = None
) -> NativeOperator: ...
def view_factors(
    scene: Scene,
    refine: int,
    tolerance: float,
    max_depth: int,
    each_direction: bool = False,
    condition: bool = False,
    drop_below: Optional[float] = None,
    progress: Optional[_Progress] = None,
) -> tuple[
    npt.NDArray[np.int64], npt.NDArray[np.int64], _Floats, int, _Floats, _Floats, str
]: ...
def option_values() -> dict[str, list[str]]: ...
def default_options() -> _RunOptions: ...
