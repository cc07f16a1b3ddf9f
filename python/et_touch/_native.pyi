"""Type stubs of et_touch's native part (python/src). Use the API of `et_touch` itself; these
functions take C-contiguous float64 arrays (et_touch makes them so) and return summaries as
JSON text, with the `et` command's field names. Shapes: K values a frame, T triangles, L
electrodes, n rows; units SI (m, V, A, S per square)."""

from typing import Any, Callable, List, Optional, Tuple

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
I64 = npt.NDArray[np.int64]

BUDGET_S: float

class EtError(ValueError):
    """et refused an input: the message names the file, field or value and why."""

FRAME_SCALE_SAID: float
"""How far a frame may be from its reference V_0, a factor either way, before it is said."""

def protocol_table(name: str, electrodes: int, current_a: float) -> Tuple[I64, F64]:
    """A built-in protocol's rows (K x 4: source, sink, positive, negative) and currents (K, A)."""

def check_sheet(sheet_json: str) -> None:
    """Refuses a sheet spec a Reconstructor would refuse (EtError)."""
def check_protocol(
    electrodes: int,
    protocol: Optional[str],
    current_a: float,
    rows: Optional[I64],
    currents: Optional[F64],
) -> None:
    """Refuses a protocol a Reconstructor would refuse (EtError)."""
def scene_parts(path: str) -> Tuple[str, Optional[str], int, float, I64, F64]:
    """A scene file's sheet (JSON), protocol name (None for a protocol file), electrode count,
    current (A), rows (K x 4) and currents (K, A)."""

class Reconstructor:
    def __init__(
        self,
        sheet_json: str,
        electrodes: int,
        protocol: Optional[str],
        current_a: float,
        rows: Optional[I64],
        currents: Optional[F64],
        triangles: int,
        method: str,
        alpha: str,
        pixels: int,
        threshold: Optional[float],
        s: float,
        iterations: int,
        noise_figure: Optional[float],
        radius_m: Optional[float],
    ) -> None: ...
    def image(
        self, frame: F64, reference: Optional[F64] = None
    ) -> Tuple[str, F64, F64, Optional[F64], F64, F64]:
        """frame (K, V) against reference frames (n x K, V): the summary (JSON), pixels and
        their noise (rows x cols, Delta sigma / sigma_0, top row first, NaN outside), the
        values on the triangles (T; None for GREIT), dV (K, V) and the three-class picture
        (rows x cols: 0 background, 1 resistive, 2 conductive, NaN outside)."""
    def set_reference(self, reference: F64) -> None: ...
    def pixels_batch(self, frames: F64) -> Tuple[F64, F64, F64]:
        """frames (n x K, V) against the reference set: pixels (n * rows * cols), dV, alphas."""
    def objects_batch(self, frames: F64) -> str:
        """frames (n x K, V) against the reference set: JSON, one {"objects", "touches"} each."""
    def pixels(self, frame: F64) -> Tuple[F64, F64, float]:
        """frame (K, V) against the reference set: pixels (rows x cols), dV (K, V), alpha."""
    def fit_background(self, reference: F64) -> str: ...
    @property
    def background_fitted(self) -> bool: ...
    def scale_of(self, reference: F64) -> Optional[float]:
        """The mean of reference (n x K, V) over the model's frame of the untouched sheet."""
    def poor_fit(self, reference: F64) -> Optional[str]:
        """What is said when the model leaves over 20 % of reference's mean unexplained."""
    def not_volts(self, reference: F64) -> Optional[str]:
        """What is said when reference's mean passes 100 V: frames in another unit."""
    def electrode_off(self, reference: F64) -> Optional[str]:
        """What is said of an electrode whose values stand out from the model (0-based), or None."""
    def frame_scales(self, frames: F64, v0: F64) -> List[float]:
        """Each frame's scale to v0: the median of its values' ratios (NaN where none)."""
    def came_off(self, frames: F64, reference: F64) -> Optional[str]:
        """What is said of an electrode whose values stand out in frames, not in reference, or None."""
    def reference_changed(self, reference: F64) -> Optional[str]:
        """What is said when one of reference's frames differs from the others as a touch."""
    def forward(self, sigma: F64) -> F64:
        """The frame (K, V) of conductivity sigma (T, S per square)."""
    def jacobian(self) -> F64:
        """K x T, V per S/sq."""
    @property
    def nodes(self) -> F64:
        """n x 2, m."""
    @property
    def triangles(self) -> I64:
        """T x 3 node indices, counter-clockwise."""
    @property
    def electrodes(self) -> F64:
        """L x 2, m."""
    @property
    def protocol(self) -> Tuple[I64, F64]: ...
    @property
    def grid(self) -> Tuple[int, int, float, float, float]:
        """(rows, cols, x0_m, y0_m, pixel_m)."""
    @property
    def sigma0(self) -> float: ...
    @property
    def sheet_json(self) -> str: ...
    @property
    def set_up_s(self) -> Tuple[float, float, float]:
        """(mesh, forward_jacobian, matrix), s."""
    def frame_median(self, dv: F64, repeats: int) -> Optional[float]: ...

class Dataset:
    """An et dataset (`et collect`'s .csv or .npz)."""

    @staticmethod
    def load(path: str) -> "Dataset": ...
    @property
    def x(self) -> F64:
        """n x p observations, V."""
    @property
    def y(self) -> I64:
        """n classes."""
    @property
    def positions_m(self) -> F64:
        """n x 2, m."""
    @property
    def pressure_pa(self) -> F64: ...
    @property
    def centres_m(self) -> F64:
        """C x 2, m."""
    @property
    def electrodes_m(self) -> F64: ...
    @property
    def visit(self) -> I64: ...
    @property
    def feature_index(self) -> I64:
        """p: each feature's index in the frame."""
    @property
    def untouched(self) -> F64:
        """T x p: each visit's untouched frame, V."""
    @property
    def config_json(self) -> str: ...

class Model:
    @staticmethod
    def load(path: str) -> "Model": ...
    @staticmethod
    def from_json(
        text: str, scores: Optional[str] = None, note: Optional[str] = None
    ) -> "Model": ...
    def save(self, path: str) -> None: ...
    @property
    def kind(self) -> str: ...
    @property
    def is_board(self) -> bool: ...
    @property
    def label_type(self) -> Optional[str]: ...
    @property
    def note(self) -> Optional[str]: ...
    def file_json(self) -> str: ...
    def scores_json(self) -> Optional[str]: ...
    def predict(
        self, x: F64, v0: Optional[F64] = None
    ) -> Tuple[Optional[I64], Optional[List[str]], Optional[F64], Optional[F64]]:
        """(class indices, class names, positions n x 2 in m, third target)."""
    def predict_dataset(
        self, dataset: Dataset
    ) -> Tuple[Optional[I64], Optional[List[str]], Optional[F64], Optional[F64]]: ...
    def evaluate_table(
        self,
        x: F64,
        labels: Optional[List[str]],
        positions_m: Optional[F64],
        groups: Optional[List[str]],
    ) -> str: ...
    def evaluate_dataset(self, dataset: Dataset) -> str: ...
    def export_blob(self, precision: str) -> bytes: ...

def train_table(
    x: F64,
    labels: Optional[List[str]],
    positions_m: Optional[F64],
    groups: Optional[List[str]],
    kind: str,
    folds: Optional[int],
    cv: str,
    grid: Optional[Tuple[int, int]],
    per_group: bool,
    seed: int,
    label_type: Optional[str] = None,
    budget_s: float = 3600.0,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Model: ...
def train_dataset(
    dataset: Dataset,
    kind: str,
    shrinkage: Optional[float],
    folds: Optional[int],
    raw: bool,
    keep: Optional[int],
    seed: int,
    budget_s: float = 3600.0,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Model: ...
def read_recording(path: str) -> Tuple[str, F64, I64, I64, I64, str, bool]: ...
def read_frames(path: str, k: int) -> Tuple[F64, str]: ...
