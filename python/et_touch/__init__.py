"""et from Python: touch sensing by electrical tomography, NumPy arrays in and out.

Imaging a frame (every number SI: metres, volts, amperes, siemens per square)::

    import et_touch as et
    sheet = et.disc(0.065, electrodes=16)                 # 13 cm disc, 16 electrodes
    r = et.Reconstructor(sheet, et.protocol("adjacent", 16, current_a=1e-3))
    image = r.image(v, v0)          # v: K volts; v0: K volts, or n x K untouched frames
    image.pixels                    # 64 x 64 Delta sigma / sigma_0, top row first, NaN outside
    image.objects                   # [{"x_m", "y_m", "sign", "area_m2", "peak", "z"}, ...]

Learning::

    model = et.train(X, y)          # y: labels (n) or positions (n x 2, m); kind="auto"
    model.predict(X_new)            # labels, or positions n x 2 (m)
    model.evaluate(X_test, y_test)  # {"mean_error_mm", "median_error_mm", "p90_error_mm", ...}
    board = et.train(et.read_dataset("train.npz"))   # QDA for the board from `et collect`
    open("model.etm", "wb").write(board.export_blob())

et's two entry points do the work (the Reconstructor and the Trainer of the Rust workspace),
the same code the `et` command runs: an image here is the image `et reconstruct` makes of the
same frames, and a model's predictions are `et eval`'s. The whole API: docs/python.md.
"""

from __future__ import annotations

import json
import operator
import os
import re
import sys
import threading
import warnings
from dataclasses import dataclass
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union, overload

import numpy as np

from . import _native
from ._native import Dataset, EtError

# What the imports above bound: left out of `dir(et_touch)` (`__dir__` below).
_IMPORTED = frozenset(globals())


class EtWarning(UserWarning):
    """What et says of a call it carries out, where the result may not be what was meant."""


def _warn(message: str) -> None:
    """Warns (:class:`EtWarning`) at the caller's line that called into this module, however
    deep the call that says it (a reference set by ``images(V, v0)`` was said at this
    module's own line)."""
    level, frame = 2, sys._getframe(1)
    while frame is not None and frame.f_code.co_filename == __file__:
        level, frame = level + 1, frame.f_back
    warnings.warn(message, EtWarning, stacklevel=level)


#: How far the untouched frame may be from the model's frame of the sheet (a factor either
#: way) before a Reconstructor not fitted to the frames says so: frames simulated from the
#: sheet's own values are within 4 % of it (every scene in sim/scenes), a real tank's against
#: a disc's default values 40 times it.
SCALE_SAID = 1.25

# How far a frame may be from its reference V_0 before it is said: et reconstruct's bound,
# and what it asks (a frame of the other sign was asked for its units).
_FRAME_SCALE_SAID: float = _native.FRAME_SCALE_SAID
_UNLIKE_UNITS = "are the frames and the reference in the same units, at the same current?"
_UNLIKE_SIGN = ("the other sign: were the frames' or the reference's measurement wires swapped, "
                "or their current driven the other way?")

__all__ = [
    "EtError",
    "EtWarning",
    "Sheet",
    "disc",
    "rectangle",
    "polygon",
    "Protocol",
    "protocol",
    "scene",
    "Reconstructor",
    "Image",
    "train",
    "Model",
    "Dataset",
    "read_dataset",
    "read_recording",
    "read_frames",
]

PathLike = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]


def _f64(a: Any, ndim: int, what: str) -> np.ndarray:
    """`a` as a C-contiguous float64 array of `ndim` dimensions: no copy when it already is."""
    out = _numbers(a, what)
    if out.ndim != ndim:
        # The two slips of shape with their fix: one row given alone, one row or column given
        # as a matrix.
        fix = ""
        if ndim == 2 and out.ndim == 1:
            fix = f" (one row? give it as one: [{what}] or {what}.reshape(1, -1))"
        elif ndim == 1 and out.ndim == 2 and 1 in out.shape:
            fix = f" (one row or column? give its values: {what}.ravel())"
        raise EtError(f"{what}: {out.ndim}-D array of shape {out.shape}; expected {ndim}-D{fix}")
    return out


def _numbers(a: Any, what: str) -> np.ndarray:
    """`a` as a C-contiguous float64 array of any shape: no copy when it already is. Complex
    values are refused (their imaginary part would be dropped with only NumPy's warning), and
    what NumPy cannot make numbers of is said with the argument's name. None is refused by
    name (it became one NaN, said as a recording's), and a masked array's masked values are
    NaN (NumPy hands over the values under the mask), which frames and features refuse by
    their index."""
    if a is None:
        raise EtError(f"{what} = None: give an array of numbers")
    if isinstance(a, (bytes, bytearray, memoryview)):
        # (NumPy's words held the whole of them, thousands of characters.)
        size = a.nbytes if isinstance(a, memoryview) else len(a)
        raise EtError(
            f"{what}: {size} bytes, not numbers (a port's or a file's raw bytes? "
            "np.frombuffer(b, dtype='<f4') reads them as little-endian float32)"
        )
    if np.ma.isMaskedArray(a):
        data = np.ma.getdata(a)
        # (Complex values are refused below, masked or not.)
        masked = np.ma.is_masked(a) and not np.iscomplexobj(data)
        a = np.ma.filled(a.astype(np.float64), np.nan) if masked else data
    try:
        given = np.asarray(a)
        if np.iscomplexobj(given):
            raise EtError(
                f"{what}: complex values; give real ones, the part you mean: the real part "
                "(np.real; frames are signed voltages, so not their magnitude), the quadrature "
                "(np.imag), or a feature's magnitude (np.abs)"
            )
        return np.ascontiguousarray(given, dtype=np.float64)
    except EtError:
        raise
    except (TypeError, ValueError) as e:
        said = str(e) if len(str(e)) <= 200 else str(e)[:200] + " ..."
        raise EtError(f"{what}: not an array of numbers ({said})") from None


def _volts(a: Any, what: str) -> Any:
    """``a`` as given, refused when it holds booleans (``v > 0``, a mask): not voltages, as
    `et reconstruct` refuses a boolean .npy (they were imaged as frames of 0 and 1 V)."""
    try:
        kind = np.asarray(a).dtype.kind
    except (TypeError, ValueError):
        return a  # (what makes no array is said by the conversion, by name)
    if kind == "b":
        raise EtError(f"{what} holds booleans (True, False), not voltages")
    return a


def _finite_frames(a: np.ndarray, what: str) -> np.ndarray:
    """Frames (or a frame) refused at their first NaN or infinite value, by its index: a
    recording holds NaN where the board sent none (the reconstruction said only "a frame value
    is NaN or infinite", of no frame or channel)."""
    finite = np.isfinite(a)
    if not finite.all():  # (the place looked for only then: one frame's check is a few us)
        at = tuple(int(i) for i in np.argwhere(~finite)[0])
        # (Of many frames, the rows to keep, written out.)
        keep = f": {what}[np.isfinite({what}).all(axis=1)] keeps the others" if a.ndim == 2 else ""
        raise EtError(
            f"{what}[{', '.join(map(str, at))}] = {a[at]}: frames are finite voltages (a "
            "recording's or a file's NaN is a value the system did not send: leave that frame "
            f"out{keep})"
        )
    return a


def _imaged_rows(frames: np.ndarray, what: str) -> np.ndarray:
    """Which rows of the frames (n x K) are imaged: those without a value missing (NaN, a
    value the system did not send), said in a warning by their numbers; an infinite value
    is refused by its place, and frames all missing."""
    nan = np.isnan(frames)
    if not nan.any():
        _finite_frames(frames, what)
        return np.ones(len(frames), dtype=bool)
    _finite_frames(np.where(nan, 0.0, frames), what)
    imaged = ~nan.any(axis=1)
    skipped = np.flatnonzero(~imaged)
    if not imaged.any():
        raise EtError(
            f"{what}: every frame has values missing (NaN: values the system did not send): "
            "nothing to image"
        )
    first = [int(i) for i in skipped[:5]]
    more = ", ..." if len(skipped) > 5 else ""
    _warn(
        f"{what}: {len(skipped)} of {len(frames)} frames have values missing (NaN: values the "
        f"system did not send) and are not imaged (frames {', '.join(map(str, first))}{more}): "
        "their pixels, dv and alpha are NaN, batch[i] and their objects None, as et "
        "reconstruct --all skips them"
    )
    return imaged


def _in_place(a: np.ndarray, imaged: np.ndarray, n: int) -> np.ndarray:
    """The rows of ``a`` (one per imaged frame) in their frames' places among ``n``, NaN in
    the others."""
    out = np.full((n,) + a.shape[1:], np.nan, dtype=np.result_type(a.dtype, np.float32))
    out[imaged] = a
    return out


# ---------------------------------------------------------------------------------------------
# Sheets


@dataclass
class Sheet:
    """A sheet: its outline, sheet resistance and electrodes, as a scene file's [sheet] table.

    ``spec`` is that table as a dict (metres, ohms per square, ohms): ``shape`` (``{"kind": "disc",
    "radius": R}``, ``{"kind": "rectangle", "width": W, "height": H}`` or ``{"kind":
    "polygon", "vertices": [[x, y], ...]}``), ``sheet_resistance`` and ``electrodes`` (``count``,
    ``width``, ``contact_ohm``, ``first_deg``, ``direction`` "ccw" or "cw", ``positions``,
    ``model`` "complete", "point" or "shunt"). Make one with :func:`disc`,
    :func:`rectangle`, :func:`polygon` or :func:`scene`.
    """

    spec: Dict[str, Any]

    def __post_init__(self) -> None:
        # Checked where it is made, as a scene's [sheet] is, not first where it is used.
        _native.check_sheet(_spec_json(self.spec))

    @property
    def electrodes(self) -> int:
        """How many electrodes it has."""
        return int(self.spec.get("electrodes", {}).get("count", 16))


def _plain(value: Any) -> Any:
    """``value`` with NumPy's scalars and arrays as Python's numbers and lists (a spec built from
    arrays: ``np.float32(0.1)`` or an array of vertices was "not JSON serializable")."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, (np.ndarray, np.generic)):
        return _plain(value.tolist())
    return value


def _spec_json(spec: Dict[str, Any]) -> str:
    """A sheet's spec as JSON, a NaN or infinite number refused by its name (JSON has none)."""
    spec = _plain(spec)

    def bad(value: Any, at: str) -> Optional[str]:
        if isinstance(value, dict):
            return next((b for k, v in value.items() if (b := bad(v, f"{at}.{k}" if at else k))), None)
        if isinstance(value, (list, tuple)):
            return next((b for i, v in enumerate(value) if (b := bad(v, f"{at}[{i}]"))), None)
        if isinstance(value, float) and not np.isfinite(value):
            return f"{at} = {value}"
        return None

    found = bad(spec, "")
    if found is not None:
        raise EtError(f"sheet: {found}: give a finite number")
    return json.dumps(spec)


_COUNT_MOST = 2**64 - 1


def _count(value: Any, what: str, least: int = 0, domain: Optional[str] = None) -> int:
    """``value`` as a whole number of at least ``least`` (and at most 2^64 - 1, what the
    native side's counts and seeds hold; each count's own bound is the native side's): a
    fraction, a negative number, a boolean or a number too large is refused by name rather
    than truncated, wrapped or raised as an ``OverflowError``. A count with a native
    ``domain`` (a key of ``_native.COUNTS``) says its bounds when it is refused here, as the
    native side says them (it said "at least 0", then the native side "4 to 32")."""
    said = f"{what} = {value!r}: a whole number of at least {least}"
    if domain is not None:
        lo, hi = _native.COUNTS[domain]
        even = "an even whole number" if domain == "electrodes" else "a whole number"
        said = f"{what} = {value!r}: {even} from {lo} to {hi}"
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        number = int(value)
    else:
        array = np.asarray(value)
        if (
            array.ndim != 0
            or array.dtype.kind not in "iuf"
            or not np.isfinite(array)
            or array != np.round(array)
        ):
            raise EtError(said)
        number = int(array)
    if number < least:
        raise EtError(said)
    if number > _COUNT_MOST:
        raise EtError(f"{what} = {value!r}: too large (at most 2^64 - 1)")
    return number


def _real(value: Any, what: str) -> float:
    """``value`` as a number (what ``float`` takes), refused by name when it is none (``float``
    said only "could not convert string to float") or a boolean (``True`` was 1)."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            return float(value)
        except (TypeError, ValueError):
            pass
    raise EtError(f"{what} = {value!r}: a number")


def _text(value: Any, what: str, choices: str) -> str:
    """``value`` as one of a parameter's names, refused by name when it is not text (the
    native side said only "'int' object is not an instance of 'str'")."""
    if not isinstance(value, str):
        raise EtError(f"{what} = {value!r}: {choices}")
    return value


def _sheet(
    shape: Dict[str, Any],
    electrodes: int,
    sheet_resistance: float,
    contact_ohm: float,
    width_m: float,
    first_deg: Optional[float],
    direction: str,
    model: str,
) -> Sheet:
    if direction not in ("ccw", "cw"):
        raise EtError(f"direction {direction!r}: 'ccw' or 'cw'")
    if model not in ("complete", "point", "shunt"):
        raise EtError(f"model {model!r}: 'complete', 'point' or 'shunt'")
    spec_electrodes: Dict[str, Any] = {
        "count": _count(electrodes, "electrodes", domain="electrodes"),
        "width": _real(width_m, "electrode_width_m"),
        "contact_ohm": _real(contact_ohm, "contact_ohm"),
        "direction": direction,
        "model": model,
    }
    if first_deg is not None:
        spec_electrodes["first_deg"] = _real(first_deg, "first_deg")
    return Sheet(
        {"shape": shape, "sheet_resistance": _real(sheet_resistance, "sheet_resistance"), "electrodes": spec_electrodes}
    )


def disc(
    radius_m: float,
    electrodes: int = 16,
    *,
    sheet_resistance: float = 30e3,
    contact_ohm: float = 1000.0,
    electrode_width_m: float = 0.005,
    first_deg: Optional[float] = None,
    direction: str = "ccw",
    model: str = "complete",
    placement: Optional[str] = None,
) -> Sheet:
    """A disc of ``radius_m`` (m) centred on the origin, ``electrodes`` evenly round its edge.

    ``sheet_resistance`` in ohms per square, ``contact_ohm`` each electrode's contact
    resistance (ohm), ``electrode_width_m`` each electrode's width along the edge (m), ``first_deg`` the
    first electrode's angle from +x (degrees; default half a spacing from +x), ``direction``
    the numbering "ccw" or "cw", ``model`` the electrode model ("complete", "point", "shunt").
    ``placement="pyeit"`` puts the electrodes where the Python peer's meshes do (electrode 0
    at 180 degrees, numbered clockwise: ``first_deg=180, direction="cw"``), so its frames
    image the right way round.
    """
    if placement is not None:
        if placement != "pyeit":
            raise EtError(f"placement {placement!r}: 'pyeit', or first_deg and direction")
        if first_deg is not None or direction != "ccw":
            raise EtError("placement='pyeit' sets first_deg and direction: give one or the other")
        first_deg, direction = 180.0, "cw"
    return _sheet(
        {"kind": "disc", "radius": _real(radius_m, "radius_m")},
        electrodes, sheet_resistance, contact_ohm, electrode_width_m, first_deg, direction, model,
    )


def rectangle(
    width_m: float,
    height_m: float,
    electrodes: int = 16,
    *,
    sheet_resistance: float = 30e3,
    contact_ohm: float = 1000.0,
    electrode_width_m: float = 0.005,
    first_deg: Optional[float] = None,
    direction: str = "ccw",
    model: str = "complete",
) -> Sheet:
    """A ``width_m`` x ``height_m`` rectangle (m) centred on the origin; options as :func:`disc`."""
    return _sheet(
        {
            "kind": "rectangle",
            "width": _real(width_m, "width_m"),
            "height": _real(height_m, "height_m"),
        },
        electrodes, sheet_resistance, contact_ohm, electrode_width_m, first_deg, direction,
        model,
    )


def polygon(
    vertices_m: Any,
    electrodes: int = 16,
    *,
    sheet_resistance: float = 30e3,
    contact_ohm: float = 1000.0,
    electrode_width_m: float = 0.005,
    first_deg: Optional[float] = None,
    direction: str = "ccw",
    model: str = "complete",
) -> Sheet:
    """A simple polygon, ``vertices_m`` n x 2 (m) counter-clockwise; options as :func:`disc`."""
    vertices = _f64(vertices_m, 2, "vertices_m").tolist()
    return _sheet(
        {"kind": "polygon", "vertices": vertices},
        electrodes, sheet_resistance, contact_ohm, electrode_width_m, first_deg, direction, model,
    )


# ---------------------------------------------------------------------------------------------
# Protocols


@dataclass(frozen=True)
class Protocol:
    """Who drives and who measures, value by value of a frame.

    ``rows`` is K x 4 (source, sink, positive, negative; 0-based electrodes: value k is
    U_positive - U_negative while the current enters by source and leaves by sink),
    ``currents`` K currents (A). ``name`` is set for et's built-in protocols (it chooses the
    protocol's default imaging threshold).
    """

    electrodes: int
    rows: np.ndarray
    currents: np.ndarray
    name: Optional[str] = None

    def __post_init__(self) -> None:
        # Frozen, with its own read-only copies (a row changed afterwards was ignored under a
        # built-in name), and checked where it is made as a Reconstructor takes it: a current of 0 or NaN,
        # a drive or measurement pair of one electrode, are refused here, not first there.
        rows = np.array(_numbers(self.rows, "rows"), dtype=np.int64)
        currents = np.array(_numbers(self.currents, "currents"))
        rows.flags.writeable = currents.flags.writeable = False
        object.__setattr__(self, "electrodes", _count(self.electrodes, "electrodes"))
        object.__setattr__(self, "rows", rows)
        object.__setattr__(self, "currents", currents)
        _native.check_protocol(*self._native_args())

    def __repr__(self) -> str:
        # Its size and current, not its K x 4 rows and K currents (hundreds of lines).
        currents = np.unique(self.currents)
        current = (f"{currents[0]:g} A" if len(currents) == 1
                   else f"{len(currents)} currents from {currents[0]:g} to {currents[-1]:g} A")
        name = f"{self.name!r}, " if self.name else ""
        return f"Protocol({name}{self.electrodes} electrodes, K = {len(self.rows)}, {current})"

    def _native_args(self) -> Tuple[int, Optional[str], float, Optional[np.ndarray], Optional[np.ndarray]]:
        """(electrodes, name, current, rows, currents) as the native side takes a protocol:
        a built-in one by its name unless its currents were changed row by row (then its rows,
        each with its own current: none is ignored)."""
        current_a = float(self.currents[0]) if len(self.currents) else 1e-3
        name = self.name if np.all(self.currents == current_a) else None
        if name:
            return self.electrodes, name, current_a, None, None
        return self.electrodes, None, current_a, self.rows, self.currents

    @property
    def K(self) -> int:  # noqa: N802 (the method's symbol)
        """Values a frame."""
        return int(self.rows.shape[0])

    def without(self, electrodes: Sequence[int]) -> Tuple["Protocol", np.ndarray]:
        """This protocol without every value that ``electrodes`` (0-based) drive or measure,
        and the indices of the values kept: a detached or broken electrode left out, as
        ``et reconstruct --skip-electrodes`` does. Image ``v[..., keep]`` with the protocol
        returned (a built-in protocol's name is dropped: its rows are no longer all of it)."""
        skip = np.atleast_1d(_whole(electrodes, "electrodes"))
        outside = skip[(skip < 0) | (skip >= self.electrodes)]
        if len(outside):
            raise EtError(
                f"electrodes: {int(outside[0])} is not one of this protocol's 0 to "
                f"{self.electrodes - 1}"
            )
        left_out = len(np.unique(skip))
        if 2 * left_out > self.electrodes:
            raise EtError(
                f"electrodes: {left_out} of the {self.electrodes} to leave out: at most half "
                f"({self.electrodes // 2}) may be, the image being made of the rest's values alone"
            )
        keep = np.flatnonzero(~np.isin(self.rows, skip).any(axis=1))
        if len(keep) == 0:
            raise EtError(
                f"electrodes: every one of the {self.K} values involves one of the {left_out} "
                "electrodes to leave out: nothing would be left to image; leave fewer out"
            )
        return Protocol(self.electrodes, self.rows[keep], self.currents[keep]), keep

    @classmethod
    def from_rows(
        cls, rows: Any, electrodes: int, current_a: float = 1e-3, base: int = 0
    ) -> "Protocol":
        """Any system's protocol: ``rows`` N x 4 (source, sink, positive, negative) or N x 5
        (the fifth the current, A), electrodes counted from ``base`` (0, or 1 for systems that
        count from 1); rows without a current drive ``current_a``."""
        table = _numbers(rows, "rows")
        if table.ndim != 2 or table.shape[1] not in (4, 5):
            # A number first (the arguments swapped) said as one, not as "shape (1,)".
            given = f"rows = {rows!r}: a number" if np.ndim(rows) == 0 else f"rows: shape {table.shape}"
            raise EtError(
                f"{given}; give the rows, N x 4 (source, sink, positive, negative) or N x 5 (a "
                "current last), then the electrodes: Protocol.from_rows(rows, electrodes)"
            )
        if base not in (0, 1) or isinstance(base, bool):
            raise EtError(f"base = {base!r}: electrodes are counted from 0 (et's) or 1")
        n = _count(electrodes, "electrodes", 2)
        currents = table[:, 4].copy() if table.shape[1] == 5 else np.full(len(table), current_a)
        electrodes_of = table[:, :4] - base
        _whole(table[:, :4], "rows")
        outside = np.flatnonzero((electrodes_of < 0).any(axis=1) | (electrodes_of >= n).any(axis=1))
        if len(outside):
            row = int(outside[0])
            raise EtError(
                f"rows: row {row} ({', '.join(f'{v:g}' for v in table[row, :4])}): electrodes "
                f"are {base} to {n - 1 + base} ({n} counted from {base})"
                + (": are they counted from 1? give base=1" if base == 0 and table[row, :4].max() == n else "")
            )
        return cls(n, electrodes_of.astype(np.int64), currents.astype(np.float64))

    @classmethod
    def from_pyeit(
        cls, ex_mat: Any, meas_mat: Any = None, electrodes: Optional[int] = None,
        current_a: float = 1e-3,
    ) -> "Protocol":
        """The Python peer's convention, as it comes: its protocol object (pyEIT 1.2's
        ``protocol.create(...)``, with ``ex_mat``, ``meas_mat`` and ``n_el``), or its arrays:
        ``ex_mat`` n_exc x 2 (source, sink) and ``meas_mat`` either n_exc x n_meas x 2 (pyEIT
        1.2: each excitation's [N, M] pairs, the value u[N] - u[M], frames excitation by
        excitation) or K x 3 (N, M, excitation index; earlier versions). ``electrodes``
        defaults to the object's ``n_el``, else the largest electrode + 1. pyEIT's frames are
        those of its ``meas_mat``: data with every pair of each excitation (its
        ``keep_ba``) are cut to them first, ``v[protocol.keep_ba]``. Its electrodes sit where
        ``placement="pyeit"`` puts them (electrode 0 at 180 degrees, numbered clockwise)."""
        if meas_mat is None and hasattr(ex_mat, "meas_mat"):
            if electrodes is None and hasattr(ex_mat, "n_el"):
                electrodes = int(ex_mat.n_el)
            ex_mat, meas_mat = ex_mat.ex_mat, ex_mat.meas_mat
        if meas_mat is None:
            raise EtError("from_pyeit: give the peer's protocol object, or ex_mat and meas_mat")
        ex, meas = _whole(ex_mat, "ex_mat"), _whole(meas_mat, "meas_mat")
        if meas.ndim == 3 and meas.shape[2] == 2:
            if meas.shape[0] != len(ex):
                raise EtError(
                    f"meas_mat {meas.shape}: one block of [N, M] pairs per excitation, and "
                    f"ex_mat has {len(ex)} rows"
                )
            excitation = np.repeat(np.arange(meas.shape[0]), meas.shape[1])
            meas = np.column_stack([meas.reshape(-1, 2), excitation])
        if ex.ndim != 2 or ex.shape[1] != 2 or meas.ndim != 2 or meas.shape[1] != 3:
            raise EtError(
                f"ex_mat {ex.shape} and meas_mat {meas.shape}: give n_exc x 2 and "
                "n_exc x n_meas x 2 (pyEIT 1.2) or K x 3"
            )
        if len(meas) == 0 or meas[:, 2].min() < 0 or meas[:, 2].max() >= len(ex):
            raise EtError("meas_mat: an excitation index outside ex_mat's rows")
        rows = np.column_stack([ex[meas[:, 2], 0], ex[meas[:, 2], 1], meas[:, 0], meas[:, 1]])
        if electrodes is not None:
            n = int(_whole(electrodes, "electrodes"))
        else:
            n = int(max(ex.max(), meas[:, :2].max()) + 1)
        if rows.min() < 0 or rows.max() >= n:
            raise EtError(f"from_pyeit: an electrode outside 0 to {n - 1}")
        return cls(n, rows, np.full(len(rows), _real(current_a, "current_a")))


def _whole(a: Any, what: str) -> np.ndarray:
    """``a`` as whole numbers (int64), refusing fractions rather than truncating them, and
    what is no number by name (``["a"]`` raised NumPy's ValueError)."""
    try:
        values = np.asarray(a, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise EtError(f"{what}: not whole numbers ({e})") from None
    bad = np.argwhere(~np.isfinite(values) | (values != np.round(values)))
    if len(bad):
        # Named by its place (the first of them) and value, as the rows' other checks are.
        place = f"[{', '.join(str(int(i)) for i in bad[0])}]" if values.ndim else ""
        value = values[tuple(bad[0])]
        raise EtError(
            f"{what}{place} = {value:g}: electrode numbers and indices are whole numbers"
        )
    return values.astype(np.int64)


def protocol(name: str, electrodes: int = 16, current_a: float = 1e-3) -> Protocol:
    """et's built-in protocol ``name`` ("adjacent", "pseudo-polar", "pp-pp", "opposite") on
    ``electrodes`` electrodes, driving ``current_a`` (A)."""
    n = _count(electrodes, "electrodes", domain="electrodes")
    name = _text(name, "name", "'adjacent', 'pseudo-polar', 'pp-pp' or 'opposite'").lower()
    current = _real(current_a, "current_a")
    if not current > 0 or not np.isfinite(current):
        # (The table's rows said it: "row 0: current 0 A".)
        raise EtError(f"current_a = {current!r}: give the current driven, above 0 A (1e-3 is 1 mA)")
    rows, currents = _native.protocol_table(name, n, current)
    return Protocol(n, rows, currents, name)


def scene(path: PathLike) -> Tuple[Sheet, Protocol]:
    """A scene file's sheet and protocol (the TOML files `et sim` and `et reconstruct` take)."""
    sheet_json, name, electrodes, current_a, rows, currents = _native.scene_parts(
        os.fsdecode(path)
    )
    return Sheet(json.loads(sheet_json)), Protocol(electrodes, rows, currents, name)


# ---------------------------------------------------------------------------------------------
# Imaging


class _Serialised:
    """A native object whose calls are made one thread at a time: a call holds it while the
    GIL is released, where a second thread's call would find it "Already borrowed". Another
    thread's call waits for the first to end."""

    def __init__(self, inner: Any) -> None:
        self._inner = inner
        self._lock = threading.RLock()

    def __getattr__(self, name: str) -> Any:
        with self._lock:
            value = getattr(self._inner, name)
        if not callable(value):
            return value

        def call(*args: Any, **kwargs: Any) -> Any:
            with self._lock:
                return value(*args, **kwargs)

        return call


def _reconstructor_again(
    made: Dict[str, Any], replayed: List[Tuple[str, np.ndarray]]
) -> "Reconstructor":
    """A pickled reconstructor made again: set up from its arguments, its background fit and
    reference replayed in their order."""
    r = Reconstructor(**made)
    for call, frames in replayed:
        getattr(r, call)(frames)
    return r


class Image:
    """One frame imaged.

    ``pixels`` and ``noise_sd``: rows x cols, Delta sigma / sigma_0 (no unit), the top row
    first, NaN outside the sheet (``plt.imshow(image.pixels, extent=image.extent)`` shows it
    upright, in metres). ``values``: Delta sigma / sigma_0 on each triangle of the mesh
    (Gauss-Newton; None for GREIT), for ``plt.tripcolor(x, y, triangles, values)``. ``dv``: V -
    V_0 (K, V). ``objects``: conductive (sign +1) and resistive (-1) objects, strongest first,
    as `et reconstruct --json` gives them; ``touches``: the presses (regions of positive change
    split at their saddles, above 5 times their noise); ``regions``: every region above the
    threshold. Each is a dict: ``x_m``, ``y_m``, ``sign``, ``area_m2``, ``peak`` (Delta sigma /
    sigma_0), ``z`` (peak over its noise).

    ``pixels``, ``dv``, ``alpha`` and ``extent`` are made with the image; the rest when first
    read: ``objects`` and ``touches`` alone with the noise of their own pixels, anything else
    by imaging the frame again in full, once. A loop that reads only the pixels pays for the
    pixels, one that reads the objects too for little more. Imaged against a reference set once (:meth:`Reconstructor.set_reference`),
    ``pixels`` come from the reconstruction's f32 operator from the second frame at an alpha
    on (within 1e-4 of the peak of the f64 image the rest is made from).
    """

    def __init__(
        self,
        pixels: np.ndarray,
        dv: np.ndarray,
        alpha: float,
        extent: Tuple[float, float, float, float],
        whole: Any,
        found: Any = None,
    ) -> None:
        self.pixels = pixels
        self.dv = dv
        self.alpha = alpha
        self.extent = extent
        self._whole = whole
        self._made: Optional[Tuple[Dict[str, Any], Any, Any, Any]] = None
        # The objects and touches alone (against a reference set), when the rest is not made.
        self._found = found
        self._found_made: Optional[Dict[str, Any]] = None

    def _objects_and_touches(self) -> Dict[str, Any]:
        if self._made is not None or self._found is None:
            return self.summary
        if self._found_made is None:
            self._found_made = self._found()
            self._found = None
        return self._found_made

    def _details(self) -> Tuple[Dict[str, Any], Any, Any, Any]:
        if self._made is None:
            summary_json, _, noise, values, _, classes = self._whole()
            self._made = (json.loads(summary_json), noise, values, classes)
            self._whole = None
        return self._made

    @property
    def noise_sd(self) -> np.ndarray:
        return self._details()[1]

    @property
    def values(self) -> Optional[np.ndarray]:
        return self._details()[2]

    @property
    def summary(self) -> Dict[str, Any]:
        return self._details()[0]

    @property
    def objects(self) -> List[Dict[str, Any]]:
        return self._objects_and_touches()["objects"]

    @property
    def touches(self) -> List[Dict[str, Any]]:
        return self._objects_and_touches()["touches"]

    @property
    def regions(self) -> List[Dict[str, Any]]:
        return self.summary["regions"]

    @property
    def threshold(self) -> float:
        return self.summary["threshold"]

    @property
    def noise(self) -> Dict[str, Any]:
        return self.summary["noise"]

    @property
    def timings_s(self) -> Dict[str, Any]:
        return self.summary["timings_s"]

    def segment(self) -> np.ndarray:
        """The three-class picture (rows x cols like ``pixels``): 0 background, 1 resistive
        (the conductivity fell), 2 conductive (it rose), NaN outside the sheet. Each object's
        pixels at or above half its own peak take its class, so a kind of target the image
        does not show stays empty (as `et reconstruct --segment` writes it)."""
        return self._details()[3]

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        # Pickled whole (a worker's image sent back by multiprocessing or joblib): what is
        # made when first read is made now, once, and sent with it.
        return (_image_made, (self.pixels, self.dv, self.alpha, self.extent, self._details()))

    def __repr__(self) -> str:
        rows, cols = self.pixels.shape
        return f"Image({rows} x {cols} pixels, alpha {self.alpha:.3g})"


def _image_made(
    pixels: np.ndarray,
    dv: np.ndarray,
    alpha: float,
    extent: Tuple[float, float, float, float],
    made: Tuple[Dict[str, Any], Any, Any, Any],
) -> Image:
    """A pickled image made again, with everything it says."""
    image = Image(pixels, dv, alpha, extent, None)
    image._made = made
    return image


class ImageBatch:
    """Frames imaged together (:meth:`Reconstructor.images`): ``pixels`` n x rows x cols
    (Delta sigma / sigma_0, top row first, NaN outside), ``dv`` n x K (V), ``alpha`` (n);
    ``batch[i]`` (and iterating) gives each frame's :class:`Image`, whose noise, objects and
    segmentation are made when first read, against the reference the batch was imaged
    against. A frame with values missing (NaN: values the system did not send) is not
    imaged, as `et reconstruct --all` skips it: its pixels, dv and alpha are NaN, its
    ``batch[i]`` and its objects and touches None; ``imaged`` says which frames were."""

    def __init__(self, r: "Reconstructor", frames: np.ndarray, reference: np.ndarray,
                 pixels: np.ndarray, dv: np.ndarray, alpha: np.ndarray,
                 imaged: Optional[np.ndarray] = None) -> None:
        self._r, self._frames, self._reference = r, frames, reference
        self.pixels, self.dv, self.alpha = pixels, dv, alpha
        #: Which frames were imaged (n booleans): False where a value was missing.
        self.imaged = np.ones(len(alpha), dtype=bool) if imaged is None else imaged
        self._found: Optional[List[Optional[Dict[str, Any]]]] = None

    def __len__(self) -> int:
        return len(self.alpha)

    @overload
    def __getitem__(self, i: int) -> Image: ...

    @overload
    def __getitem__(self, i: slice) -> "ImageBatch": ...

    def __getitem__(self, i: Union[int, slice]) -> Union[Optional[Image], "ImageBatch"]:
        if isinstance(i, slice):
            # The frames it selects, as a batch of their own (what is made is shared).
            part = ImageBatch(self._r, self._frames[i], self._reference, self.pixels[i],
                              self.dv[i], self.alpha[i], self.imaged[i])
            part._found = None if self._found is None else self._found[i]
            return part
        try:
            i = operator.index(i)
        except TypeError:
            raise TypeError(f"batch index {i!r}: a whole number or a slice") from None
        if not -len(self) <= i < len(self):
            raise IndexError(f"frame {i} of a batch of {len(self)}")
        if not self.imaged[i]:
            return None
        frame, reference, native = self._frames[i], self._reference, self._r._native
        found = self._found
        return Image(self.pixels[i], self.dv[i], float(self.alpha[i]), self._r.extent,
                     lambda: native.image(frame, reference),
                     (lambda: found[i]) if found is not None
                     else lambda: self._r._found_of(frame[None, :], reference)[0])

    @property
    def objects(self) -> List[Optional[List[Dict[str, Any]]]]:
        """Each frame's objects (a list per frame, strongest first, as ``Image.objects``;
        None for a frame not imaged), made for every frame at the first read, over every
        core."""
        return [None if f is None else f["objects"] for f in self._found_all()]

    @property
    def touches(self) -> List[Optional[List[Dict[str, Any]]]]:
        """Each frame's touches (a list per frame, as ``Image.touches``; None for a frame not
        imaged)."""
        return [None if f is None else f["touches"] for f in self._found_all()]

    def _found_all(self) -> List[Optional[Dict[str, Any]]]:
        if self._found is None:
            found = iter(self._r._found_of(self._frames[self.imaged], self._reference))
            self._found = [next(found) if kept else None for kept in self.imaged]
        return self._found

    def __iter__(self) -> Any:
        return (self[i] for i in range(len(self)))

    def __repr__(self) -> str:
        n, rows, cols = self.pixels.shape
        skipped = int((~self.imaged).sum())
        missing = f", {skipped} not imaged (values missing)" if skipped else ""
        return f"ImageBatch({n} frames of {rows} x {cols} pixels{missing})"


class Reconstructor:
    """A reconstruction set up once for a sheet, a protocol, a mesh and a method; it images
    every frame against the untouched frame (et's Reconstructor).

    ``triangles``: about how many triangles to mesh the sheet with. ``method``: "gn" (one-step
    Gauss-Newton with the NOSER prior; ``iterations`` > 1 refits) or "greit". ``alpha``:
    "auto" (Gauss-Newton: the L-curve's corner on each frame, never below generalised
    cross-validation's choice above the noise and 1 % of the change; GREIT: the noise figure's
    lambda), "corner", "gcv", "discrepancy", "lcurve", "quasi-optimality", or a number. ``pixels``: pixels across the
    image. ``threshold``: the share of the peak a region must reach (default: the protocol's).
    ``s``: the NOSER exponent; ``noise_figure`` and ``radius_m``: GREIT's. Set-up runs without
    the GIL and takes Ctrl-C at once.
    """

    def __init__(
        self,
        sheet: Sheet,
        protocol: Protocol,
        triangles: int = 8000,
        method: str = "gn",
        alpha: Union[str, float] = "auto",
        pixels: int = 64,
        threshold: Optional[float] = None,
        s: Optional[float] = None,
        iterations: int = 1,
        noise_figure: Optional[float] = None,
        radius_m: Optional[float] = None,
    ) -> None:
        if sheet.electrodes != protocol.electrodes:
            raise EtError(
                f"the protocol is of {protocol.electrodes} electrodes, the sheet has "
                f"{sheet.electrodes}"
            )
        method = _text(method, "method", "'gn' or 'greit'")
        # One method's options beside the other change nothing: refused, not ignored.
        if method == "greit":
            if s is not None:
                raise EtError(f"s = {s}: Gauss-Newton's NOSER exponent; GREIT has no prior")
            if iterations != 1:
                raise EtError(f"iterations = {iterations}: Gauss-Newton's; GREIT is one matrix")
            if noise_figure is not None and str(alpha) != "auto":
                raise EtError(
                    f"noise_figure = {noise_figure} sets GREIT's lambda under alpha='auto'; "
                    f"alpha={alpha!r} sets it otherwise: give one of them"
                )
        elif method == "gn" and (noise_figure is not None or radius_m is not None):
            raise EtError(
                "noise_figure and radius_m are GREIT's (method='greit'); Gauss-Newton's "
                "smoothing is alpha and s"
            )
        electrodes, name, current_a, rows, currents = protocol._native_args()
        self._native = _Serialised(_native.Reconstructor(
            _spec_json(sheet.spec), electrodes, name, current_a, rows, currents,
            _count(triangles, "triangles", domain="triangles"), method, str(alpha),
            _count(pixels, "pixels", domain="pixels"),
            None if threshold is None else _real(threshold, "threshold"),
            0.5 if s is None else _real(s, "s"),
            _count(iterations, "iterations", domain="iterations"),
            None if noise_figure is None else _real(noise_figure, "noise_figure"),
            None if radius_m is None else _real(radius_m, "radius_m"),
        ))
        self.protocol = protocol
        self._method = method
        self._reference: Optional[np.ndarray] = None
        self._v0: Optional[np.ndarray] = None
        # What pickle makes it again from: its arguments, then its last background fit and
        # reference in the order they were made (the native set-up is not pickled).
        self._made = dict(
            sheet=sheet, protocol=protocol, triangles=triangles, method=method, alpha=alpha,
            pixels=pixels, threshold=threshold, s=s, iterations=iterations,
            noise_figure=noise_figure, radius_m=radius_m,
        )
        self._replayed: List[Tuple[str, np.ndarray]] = []

    def _by_rows(self, frames: np.ndarray, what: str) -> np.ndarray:
        """``frames`` (n x K) as they are, or refused with the fix when they are K x n: frames
        as columns, as MATLAB users store them (said as frame 0 having n values)."""
        k = self.protocol.K
        n, m = frames.shape
        if m != k and n == k:
            raise EtError(
                f"{what} is {n} x {m}: its columns are the frames, K = {k} values each? give "
                f"them as rows ({what}.T, {m} x {k})"
            )
        # K frames of K values: a recording's frames are far more alike than its channels, so
        # columns clearly alike and rows not are frames as columns (as `et reconstruct` reads
        # such a file).
        if n == m == k >= 8:
            about_rows = float(((frames - frames.mean(axis=1, keepdims=True)) ** 2).sum())
            about_columns = float(((frames - frames.mean(axis=0)) ** 2).sum())
            if 4 * about_rows < about_columns:
                raise EtError(
                    f"{what} is {k} x {k} and its columns are alike, as a recording's frames "
                    f"are, where its rows are not: are the columns the frames? give them as "
                    f"rows ({what}.T)"
                )
        return frames

    def _keep(self, call: str, frames: np.ndarray) -> None:
        """Keeps the last call of its kind for pickle to replay, after the others kept."""
        self._replayed = [c for c in self._replayed if c[0] != call] + [(call, frames.copy())]

    def __reduce__(self) -> Tuple[Any, Tuple[Dict[str, Any], List[Tuple[str, np.ndarray]]]]:
        # Made again where unpickled (pickle, copy.deepcopy, multiprocessing, joblib): set up
        # from its arguments, then its background fit and reference replayed; the set-up's
        # time is spent again there.
        return (_reconstructor_again, (self._made, self._replayed))

    def _frames(self, v0: Any) -> np.ndarray:
        """The untouched frame(s) as n x K."""
        v0 = _finite_frames(_numbers(_volts(v0, "v0"), "v0"), "v0")
        return self._by_rows(_f64(v0[None, :] if v0.ndim == 1 else v0, 2, "v0"), "v0")

    def _say_fit(self, frames: np.ndarray) -> None:
        """Warns when the untouched frames (n x K), taken by the native side (what it refuses
        is said as refused, not first warned of), are far from the model's frame of the sheet:
        in shape (the model leaves much of them unexplained: another protocol, numbering or
        sheet, as `et reconstruct` warns), one of several as a touch or a drift differs from
        the others, in unit (past 100 V: mV or ADC counts), or, where the background was not
        fitted to them, in scale."""
        if frames.size:
            native = self._native
            for said in (
                native.electrode_off(frames), native.poor_fit(frames),
                native.reference_changed(frames), native.not_volts(frames),
            ):
                if said is not None:
                    _warn(said)
        if frames.size and not self._native.background_fitted:
            scale = self._native.scale_of(frames)
            # (Below 0 it runs against the model, which the reference's check refuses.)
            if scale is not None and 0 < scale and not 1 / SCALE_SAID <= scale <= SCALE_SAID:
                spec = self.sheet.spec
                _warn(
                    f"the untouched frame is {scale:.2g} times the model's frame of the sheet "
                    f"(sheet_resistance {spec['sheet_resistance']:.4g} ohm/sq, contact_ohm "
                    f"{spec['electrodes']['contact_ohm']:.4g}, the protocol's currents): "
                    "the images' values (peaks, z) come out about as many times theirs; "
                    "fit_background(v0) fits the sheet to the frames, as et reconstruct does"
                )

    def set_reference(self, v0: Any) -> None:
        """Sets the untouched frame ``v0`` (K values), or several (n x K: their mean is V_0 and
        their spread the noise of dV), that :meth:`image` images every later frame against
        when it is given none. The reference is read and checked once; the matrices made for
        the frames (one per alpha, a few kept) and their noise images are kept from frame to
        frame."""
        frames = self._frames(v0)
        self._native.set_reference(frames)
        self._say_fit(frames)
        self._reference = frames
        self._v0 = frames.mean(axis=0)
        self._keep("set_reference", frames)

    def _say_unlike(self, frames: np.ndarray, v0: np.ndarray) -> None:
        """Warns when frames (K, or n x K) are not alike their reference ``v0`` (K): the
        first past FRAME_SCALE_SAID times it, or under its inverse (the median of its values'
        ratios, the native rule `et reconstruct` warns with), as `et reconstruct` says (a
        reference in mV against frames in V was imaged as a press everywhere). Called after the
        native side took them: what it refuses is said as refused, not first warned of."""
        if frames.shape[-1] != len(v0):
            return  # (frames of another length are refused by the native side, by K)
        native = self._native
        scale = np.asarray(native.frame_scales(
            np.ascontiguousarray(np.atleast_2d(frames), dtype=np.float64),
            np.ascontiguousarray(v0, dtype=np.float64),
        ))
        unlike = np.flatnonzero(~((scale >= 1 / _FRAME_SCALE_SAID) & (scale <= _FRAME_SCALE_SAID))
                                & ~np.isnan(scale))
        if not len(unlike):
            return
        i = int(unlike[0])
        which = "the frame" if frames.ndim == 1 else f"frame {i}"
        times = scale[i] + 0.0  # (-0, a frame of zeros against negative values, said as 0)
        _warn(
            f"{which} is {times:.3g} times the reference V_0 (the median of its values' ratios; "
            f"{len(unlike)} of {len(scale)} frames past {_FRAME_SCALE_SAID:g} times either "
            f"way): {_UNLIKE_SIGN if times < 0 else _UNLIKE_UNITS} A press changes a frame by "
            "a few per cent"
        )

    def _say_came_off(self, frames: np.ndarray, reference: np.ndarray) -> None:
        """Warns when an electrode's values stand out as a detached electrode's in the frames
        to image (n x K), not in their ``reference`` (n x K), as `et reconstruct` says: a clip
        that came off during the recording."""
        said = self._native.came_off(frames, reference) if len(frames) else None
        if said is not None:
            _warn(said)

    def image(self, v: Any, v0: Any = None) -> Image:
        """Images frame ``v`` (K values, V) against ``v0``: the untouched frame (K values), or
        several untouched frames (n x K: their mean is V_0 and their spread the noise of dV;
        with one frame the noise is estimated from the protocol's redundancy); without
        ``v0``, against the reference :meth:`set_reference` set, the fast way to image many
        frames (the image's pixels at once, its noise and objects when first read). Frames
        are taken in single precision, as et's frames are."""
        v = _finite_frames(_f64(_volts(v, "v"), 1, "v"), "v")
        if v0 is None:
            if self._reference is None:
                raise EtError(
                    "no reference set: give the untouched frame(s), image(v, v0), or set them "
                    "once with set_reference(v0)"
                )
            pixels, dv, alpha = self._native.pixels(v)
            self._say_unlike(v, self._v0)
            self._say_came_off(v[None, :], self._reference)
            reference = self._reference
            return Image(pixels, dv, alpha, self.extent,
                         lambda: self._native.image(v, reference),
                         lambda: self._found_of(v[None, :], reference)[0])
        frames = self._frames(v0)
        made = self._native.image(v, frames)
        self._say_fit(frames)
        self._say_unlike(v, frames.mean(axis=0))
        self._say_came_off(v[None, :], frames)
        s = json.loads(made[0])
        return Image(made[1], made[4], s["alpha"], self.extent, lambda: made)

    def images(self, V: Any, v0: Any = None) -> "ImageBatch":
        """Images every frame of ``V`` (n x K, V) against the reference set (or ``v0``, set as
        the reference first) in one call without the GIL: an :class:`ImageBatch` of stacked
        ``pixels`` (n x rows x cols), ``dv`` (n x K) and ``alpha`` (n); ``batch[i]`` is frame
        i's :class:`Image`, its noise and objects made when first read. A frame with values
        missing (NaN, as :func:`read_recording` and :func:`read_frames` give a value the system
        did not send) is not imaged and said in a warning: NaN in the stacks, None as its
        ``batch[i]``, objects and touches (``batch.imaged``)."""
        if v0 is not None:
            self.set_reference(v0)
        if self._reference is None:
            raise EtError("no reference set: images(V, v0), or set_reference(v0) first")
        frames = self._by_rows(_f64(_volts(V, "V"), 2, "V"), "V")
        imaged = _imaged_rows(frames, "V")
        kept = frames if imaged.all() else frames[imaged]
        pixels, dv, alpha = self._native.pixels_batch(kept)
        # (Said of each frame by its number in V: a frame not imaged stands as V_0, which
        # says nothing.)
        said = frames if imaged.all() else np.where(imaged[:, None], frames, self._v0)
        self._say_unlike(said, self._v0)
        self._say_came_off(said, self._reference)
        rows, cols = self._native.grid[:2]
        pixels = pixels.reshape(len(kept), rows, cols)
        if not imaged.all():
            # The frames not imaged kept in their places, NaN (as `et reconstruct --all`'s
            # stack), so that frame i is still row i.
            n = len(frames)
            pixels, dv, alpha = (_in_place(a, imaged, n) for a in (pixels, dv, alpha))
        return ImageBatch(self, frames, self._reference, pixels, dv, alpha, imaged)

    def _found_of(self, frames: np.ndarray, reference: Any) -> List[Dict[str, Any]]:
        """Each frame's objects and touches against ``reference`` (set again if another was
        set since)."""
        if self._reference is not reference:
            self.set_reference(reference)
        return json.loads(self._native.objects_batch(frames))

    def fit_background(self, v0: Any) -> Dict[str, Any]:
        """Fits the sheet resistance and contact resistance to the untouched frame(s) ``v0``
        and images about them from then on (as `et reconstruct` does for measured frames); the
        fit as `et reconstruct --json`'s ``background``."""
        frames = self._frames(v0)
        fit = json.loads(self._native.fit_background(frames))
        self._say_fit(frames)
        self._keep("fit_background", frames)
        return fit

    def forward(self, sigma: Any) -> np.ndarray:
        """The frame (K values, V) of conductivity ``sigma``: one per triangle, or one number
        for all (S per square)."""
        sigma = np.asarray(sigma, dtype=np.float64)
        if sigma.ndim == 0:
            sigma = np.full(len(self.triangles), _real(sigma, "sigma"))
        return self._native.forward(_f64(sigma, 1, "sigma"))

    def jacobian(self) -> np.ndarray:
        """The Jacobian at the background, K x T (V per S/sq)."""
        return self._native.jacobian()

    @property
    def nodes(self) -> np.ndarray:
        """The mesh's nodes, n x 2 (m)."""
        return self._native.nodes

    @property
    def triangles(self) -> np.ndarray:
        """The mesh's triangles, T x 3 node indices (``plt.tripcolor(nodes[:, 0], nodes[:, 1],
        triangles, image.values)``)."""
        return self._native.triangles

    @property
    def electrodes(self) -> np.ndarray:
        """Each electrode's centre, L x 2 (m)."""
        return self._native.electrodes

    @property
    def sigma0(self) -> float:
        """The background conductivity, S per square (1 / sheet resistance)."""
        return self._native.sigma0

    @property
    def sheet(self) -> Sheet:
        """The sheet imaged (after :meth:`fit_background`, with the fitted values)."""
        return Sheet(json.loads(self._native.sheet_json))

    @property
    def extent(self) -> Tuple[float, float, float, float]:
        """The image's extent (left, right, bottom, top; m) for ``plt.imshow``."""
        rows, cols, x0, y0, size = self._native.grid
        return (x0, x0 + cols * size, y0, y0 + rows * size)

    def __repr__(self) -> str:
        rows, cols, _, _, _ = self._native.grid
        return (f"Reconstructor({self._method}, {len(self.triangles)} triangles, "
                f"{self.protocol!r}, {rows} x {cols} pixels)")

    @property
    def set_up_s(self) -> Dict[str, float]:
        """What the set-up took, s."""
        mesh, forward_jacobian, matrix = self._native.set_up_s
        return {"mesh": mesh, "forward_jacobian": forward_jacobian, "matrix": matrix}

    def frame_median(self, dv: Any, repeats: int = 100) -> Optional[float]:
        """The median time (s) of ``repeats`` warm applications of the last frame's
        reconstruction to ``dv``: `et reconstruct --json`'s ``timings_s.frame``."""
        return self._native.frame_median(_f64(dv, 1, "dv"), _count(repeats, "repeats", domain="repeats"))


# ---------------------------------------------------------------------------------------------
# Learning


def _labels(y: np.ndarray, what: str, noun: str) -> List[str]:
    """Labels (or groups) as text; a missing one (None or NaN, as pandas marks them) is
    refused by its row rather than made a class of its own."""
    if y.ndim != 1:
        raise EtError(f"{what}: shape {y.shape}; give one {noun} per row")
    values = [v.item() if hasattr(v, "item") else v for v in y]
    for i, v in enumerate(values):
        if v is None or (isinstance(v, float) and v != v):
            raise EtError(f"{what}[{i}] is {v}: a missing {noun}; drop its row, or give it one")
        if isinstance(v, bytes):
            # Bytes (np.genfromtxt's text, NumPy's "S" arrays) as the text they hold: "a",
            # not "b'a'"; they come back as bytes.
            try:
                values[i] = v.decode()
            except UnicodeDecodeError:
                raise EtError(f"{what}[{i}] = {v!r}: bytes that are not UTF-8 text") from None
    return [str(v) for v in values]


def _label_type(y: Any) -> str:
    """What labels were before they became text: "int", "float", "bool", "bytes" or "str" (a model
    gives its predictions back as that type). Whole numbers beside fractions are "float"; text
    beside numbers (or booleans beside either) is refused: NumPy makes a list of them text, so
    1 came back as "1"."""
    # A list as it was given: NumPy would make ["a", 1] text before its kinds are seen.
    a = y if isinstance(y, np.ndarray) else np.asarray(y, dtype=object)
    if a.dtype.kind == "b":
        return "bool"
    if a.dtype.kind in "iu":
        return "int"
    if a.dtype.kind == "f":
        return "float"
    if a.dtype.kind == "S":
        return "bytes"
    values = [v.item() if hasattr(v, "item") else v for v in a]
    kinds: Dict[str, Any] = {}
    for v in values:
        kind = (
            "bool" if isinstance(v, bool) else "int" if isinstance(v, int)
            else "float" if isinstance(v, float) else "bytes" if isinstance(v, bytes) else "str"
        )
        kinds.setdefault(kind, v)
    if set(kinds) == {"int", "float"}:
        return "float"
    if len(kinds) > 1:
        (one, a_value), (other, b_value) = list(kinds.items())[:2]
        raise EtError(
            f"y mixes labels of two kinds, {a_value!r} ({one}) and {b_value!r} ({other}): a "
            "model gives its classes back as one kind; give every label as the same kind "
            "(str(v) for each, if text is meant)"
        )
    return next(iter(kinds), "str")


def _as_given(names: Sequence[str], label_type: Optional[str]) -> np.ndarray:
    """Class names as the labels were given (their ``label_type``), one more at the end for a
    row no class took; a model from the command line (no type) gives whole numbers written
    plainly (no "01", no "+1") as ints and any other name as text."""
    if label_type is None:
        plain = all(re.fullmatch(r"-?(0|[1-9][0-9]*)", n) for n in names)
        label_type = "int" if plain and names else "str"
    if label_type == "int":
        return np.array([int(n) for n in names] + [-1])
    if label_type == "float":
        return np.array([float(n) for n in names] + [np.nan])
    if label_type == "bytes":
        return np.array([n.encode() for n in names] + [b""], dtype=object)
    if label_type == "bool":
        return np.array([n == "True" for n in names] + [None], dtype=object)
    return np.array(list(names) + [""], dtype=object)


def _targets(y: Any) -> Tuple[Optional[List[str]], Optional[np.ndarray]]:
    """Labels (a 1-D y) or positions (n x 2 or n x 3, m)."""
    if y is None:
        return None, None
    a = np.asarray(y)
    if a.ndim == 2 and a.dtype.kind in "fiuc":
        return None, _f64(a, 2, "y")
    if a.ndim == 1:
        return _labels(a, "y", "label"), None
    raise EtError(f"y: shape {a.shape}; give n labels or n x 2 positions (m)")


def _first_twice(names: Sequence[str]) -> Optional[str]:
    """The first name that comes again, or None (in one pass: a table may have thousands)."""
    seen: set = set()
    for name in names:
        if name in seen:
            return name
        seen.add(name)
    return None


def _model_from_json(
    text: str, scores: Optional[str] = None, note: Optional[str] = None
) -> "Model":
    """A model from its file's text (a board model trained here with its training's scores
    and note, which its file keeps not): how a pickled model is made again."""
    return Model(_native.Model.from_json(text, scores, note))


class Model:
    """A trained model: a table's (any sensor's features) or the board's (QDA or LDA from an et
    dataset). Made by :func:`train` or :meth:`Model.load`."""

    def __init__(self, native: "_native.Model") -> None:
        self._native = _Serialised(native)

    def __reduce__(self) -> Tuple[Any, Tuple[Any, ...]]:
        # Pickled as its model file's JSON, and checked as a file is when unpickled: for
        # pickle, copy.deepcopy, multiprocessing and joblib (the native object is not). A
        # board model trained here keeps its training's scores and note beside it.
        if self.is_board:
            said = (self._native.scores_json(), self._native.note)
            return (_model_from_json, (self._native.file_json(), *said))
        return (_model_from_json, (self._native.file_json(),))

    @property
    def kind(self) -> str:
        """The method: qda, lda, ridge, kernel-ridge, knn, gp, mlp or average."""
        return self._native.kind

    def __repr__(self) -> str:
        # Its method and size, not its tables (`info` is the whole file: megabytes).
        classes, features = self._native.size
        what = "positions" if classes is None else f"{classes} classes"
        board = "board, " if self.is_board else ""
        return f"et_touch.Model({self.kind}, {board}{what}, {features} features)"

    @property
    def is_board(self) -> bool:
        """Whether it is a board model (it classifies frames on the board: export_blob)."""
        return self._native.is_board

    @property
    def info(self) -> Dict[str, Any]:
        """The model file's content: the method, its tables and hyperparameters (a table
        model's file also keeps its cross-validation's scores; see :attr:`scores`)."""
        return json.loads(self._native.file_json())

    @property
    def scores(self) -> Optional[Dict[str, Any]]:
        """What cross-validation said of the model, as ``et train --json`` prints it
        (accuracies as fractions, errors in mm). A board model trained here: ``cv_accuracy``
        (stratified k-fold), ``leave_one_visit_out_accuracy`` (what a new session scores),
        ``cv_mean_error_mm``, ``shrinkage_scores`` (``accuracy`` None where that shrinkage
        could not be fitted) and the rest; None for a board model loaded from its file,
        which keeps no scores (a pickle or copy keeps them). A table model: the chosen method's ``cv_accuracy`` or
        ``cv_mean_error_mm``, and every ``candidates``' scores, from its file."""
        said = self._native.scores_json()
        return None if said is None else json.loads(said)

    def _predicted(self, X: Any, v0: Any) -> Tuple[Any, Any, Any, Any]:
        if isinstance(X, (str, bytes, os.PathLike)):
            X = read_dataset(X)
        if isinstance(X, Dataset):
            if v0 is not None:
                # (It was ignored: each observation is referenced to its own visit's.)
                raise EtError(
                    "an et dataset carries each visit's untouched frame: predict(dataset) "
                    "without v0"
                )
            return self._native.predict_dataset(X)
        if v0 is not None and not self.is_board:
            raise EtError(
                "v0 is a board model's untouched frame; a table's model predicts its own "
                "features as given (reference them before training and predicting)"
            )
        v0 = None if v0 is None else _f64(_volts(v0, "v0"), 1, "v0")
        X = self._by_name(X)
        if self.is_board:  # (a board model's X are frames; a table's booleans are features)
            _volts(X, "X")
        return self._native.predict(_f64(X, 2, "X"), v0)

    def _by_name(self, X: Any) -> Any:
        """A DataFrame's columns in the order the model read its training's (a model trained
        on one predicted another of the same columns in another order by position, without a
        word); arrays, and models trained on arrays, by position."""
        given = [str(c) for c in getattr(X, "columns", [])]
        if not given:
            return X  # (an array: the names are not fetched for each call)
        names = self._native.feature_names
        if names is None or given == names:
            return X
        twice = _first_twice(given)
        if twice is not None:
            raise EtError(f"X's column {twice!r} twice: each feature column is read by its name")
        at = {n: j for j, n in enumerate(given)}
        known = set(names)
        missing = [n for n in names if n not in at]
        extra = [n for n in given if n not in known]
        # (A model trained on arrays names its columns f0, f1, ...: other names are by position.)
        unnamed = names == [f"f{i}" for i in range(len(names))]
        if (missing or extra) and unnamed:
            return X
        if missing or extra:
            said = "; ".join(
                f"{what} {', '.join(repr(n) for n in ns)}"
                for what, ns in (("X lacks", missing), ("X has, the model never saw", extra))
                if ns
            )
            raise EtError(f"X's columns are not the model's: {said} (the model's: {names})")
        return np.asarray(X)[:, [at[n] for n in names]]

    def predict(self, X: Any, v0: Any = None) -> np.ndarray:
        """Predicts each row of ``X``: a table model's features (n x p); a board model's
        frames (n x K, V; minus the untouched frame ``v0`` when it was trained referenced) or an
        et dataset (its visits' own untouched frames). Returns a classifier's labels (a board
        model's class indices) or a regressor's positions n x 2 (m)."""
        classes, names, positions, _ = self._predicted(X, v0)
        if classes is None:
            return positions
        if names is None:
            return classes
        return _as_given(names, self._native.label_type)[classes]

    def predict_positions(self, X: Any, v0: Any = None) -> Optional[np.ndarray]:
        """Each row's position, n x 2 (m): a regressor's estimate, a classifier's class centre
        (None when its classes have no positions)."""
        return self._predicted(X, v0)[2]

    def evaluate(self, X: Any, y: Any = None, groups: Optional[Sequence[Any]] = None) -> Dict[str, Any]:
        """Scores the model as `et eval --json` does: on rows ``X`` and their labels or
        positions ``y`` (m) for a table model (``mean_error_mm``, ``median_error_mm``,
        ``p90_error_mm``, ``accuracy``, ...), or on an et dataset for a board model (pass it as
        ``X``)."""
        if isinstance(X, (str, bytes, os.PathLike)):
            X = read_dataset(X)
        if isinstance(X, Dataset):
            if y is not None or groups is not None:
                # (Both were ignored: the dataset's own classes and visits were scored.)
                raise EtError(
                    "an et dataset carries its classes and visits: evaluate(dataset) without "
                    f"{'y' if y is not None else 'groups'}"
                )
            scores = json.loads(self._native.evaluate_dataset(X))
            for note in ("scale_note", "trained_note"):
                if scores.get(note):
                    _warn(scores[note])
            return scores
        labels, positions = _targets(y)
        groups = None if groups is None else _labels(np.asarray(groups), "groups", "group")
        X = self._by_name(X)
        scores = json.loads(self._native.evaluate_table(_f64(X, 2, "X"), labels, positions, groups))
        for note in ("unit_note", "scale_note", "trained_note"):
            if scores.get(note):
                _warn(scores[note])
        unknown = scores.get("unknown_labels") or []
        if unknown and labels is not None:
            # As `et eval` notes it: rows of labels the model never saw count as missed (the
            # dict alone gave an accuracy of 0 without a word).
            missed = sum(label in set(unknown) for label in labels)
            shown = ", ".join(unknown[:5]) + (", ..." if len(unknown) > 5 else "")
            _warn(
                f"{len(unknown)} label{'' if len(unknown) == 1 else 's'} the model has no class "
                f"of ({shown}): {missed} row{'' if missed == 1 else 's'} counted as missed"
            )
        return scores

    def save(self, path: PathLike) -> None:
        """Writes et's model file (JSON): `et eval`, `et stream` and `et export` read it."""
        self._native.save(os.fsdecode(path))

    @classmethod
    def load(cls, path: PathLike) -> "Model":
        """Reads et's model file (a board model or a table's)."""
        return cls(_native.Model.load(os.fsdecode(path)))

    def export_blob(self, precision: str = "f16") -> bytes:
        """The board's model blob (`et export`; `et upload` sends it): "f16" or "f32" tables."""
        return self._native.export_blob(_text(precision, "precision", "'f16' or 'f32'"))


def train(
    X: Any,
    y: Any = None,
    *,
    kind: str = "auto",
    groups: Optional[Sequence[Any]] = None,
    folds: Optional[int] = None,
    cv: str = "shuffled",
    grid: Optional[Tuple[int, int]] = None,
    per_group: bool = False,
    seed: int = 1,
    shrinkage: Optional[float] = None,
    raw: bool = False,
    keep: Optional[int] = None,
    budget_s: Optional[float] = None,
    progress: Optional[Callable[[str, int, int], Any]] = None,
) -> Model:
    """Trains a model (et's Trainer; runs without the GIL).

    On arrays: ``X`` n x p features of any sensor, ``y`` n labels (a classifier) or n x 2
    positions in m (a regressor; n x 3 with z). ``kind``: "auto" (every method that fits the
    targets, the best by cross-validation), "qda", "lda", "ridge", "kernel-ridge", "knn",
    "gp" or "mlp". ``groups``: each row's session (cross-validation leaves one out);
    ``per_group`` standardises each session by its own statistics; ``cv``: "shuffled" or
    "blocks" (contiguous, for rows in time order); ``grid``: (rows, cols) classes from
    positions; ``folds``: default 5; ``budget_s``: the longest the training may be
    estimated to take, s (default 3600; ``float("inf")``: no limit; the Gaussian process, the
    perceptron and knn time a piece of their work first; past it, refused with the estimate). ``seed``: the shuffled folds'
    and the perceptron's starts.

    On an et dataset (``X`` a :class:`Dataset` or the path of `et collect`'s .csv/.npz): QDA
    ("auto" or "qda") or LDA for the board, ``shrinkage`` in [0, 1] (None: by
    cross-validation), ``folds`` (default 10), ``raw`` (not minus the untouched frame),
    ``keep`` (only the best features), ``seed`` (the stratified folds' shuffle),
    ``budget_s`` (QDA and LDA estimate their time, which grows with the classes squared,
    from a timed piece of their work and say it in ``what`` first); its cross-validation
    leaves one visit out, so ``groups``, ``cv``, ``grid`` and ``per_group`` (for arrays) are
    refused.

    ``progress``: a callable taking ``(what, done, total)``, called at every step (``what``
    changes as each stage starts; ``total`` 0 where steps are not counted), as ``et train``
    shows its progress; the Gaussian process, the perceptron and knn say their estimated time in
    ``what`` before their work (``progress=lambda what, done, total: print(what)``). An
    exception it raises stops the calls and is raised when the training ends. Ctrl-C (or
    Jupyter's interrupt) ends the training at its next step with ``KeyboardInterrupt``.
    """
    if progress is not None and not callable(progress):
        raise EtError(f"progress: a callable taking (what, done, total), not {type(progress).__name__}")
    kind = _text(kind, "kind", "'auto', 'qda', 'lda', 'ridge', 'kernel-ridge', 'knn', 'gp' or 'mlp'")
    if isinstance(cv, (int, np.integer)) and not isinstance(cv, (bool, np.bool_)):
        raise EtError(f"cv = {cv!r}: 'shuffled' or 'blocks'; the number of folds is folds={cv}")
    cv = _text(cv, "cv", "'shuffled' or 'blocks'")
    if isinstance(X, (str, bytes, os.PathLike)):
        X = read_dataset(X)
    if isinstance(X, Dataset):
        if y is not None:
            raise EtError("an et dataset carries its classes: train(dataset) without y")
        given = [
            name
            for name, value in (
                ("groups", groups), ("grid", grid),
                ("cv", None if cv == "shuffled" else cv), ("per_group", per_group or None),
            )
            if value is not None
        ]
        if given:
            raise EtError(
                f"{', '.join(given)}: for arrays of any sensor; an et dataset's visits are its "
                "sessions (its cross-validation leaves one out) and its grid is its classes"
            )
        model = Model(
            _native.train_dataset(
                X, kind, shrinkage, None if folds is None else _count(folds, "folds", domain="folds"), raw,
                None if keep is None else _count(keep, "keep"), _count(seed, "seed"),
                _native.BUDGET_S if budget_s is None else _real(budget_s, "budget_s"), progress,
            )
        )
        # What `et train --data` prints as its notes (too few data for the usual recipe, an
        # accuracy no better than guessing), as on arrays below.
        if model._native.note:
            _warn(model._native.note)
        return model
    if y is None:
        raise EtError("give y: n labels, or n x 2 positions (m)")
    if shrinkage is not None or raw or keep is not None:
        raise EtError("shrinkage, raw and keep apply to et datasets; on arrays they are chosen by cross-validation")
    labels, positions = _targets(y)
    # A table's columns by name (a pandas DataFrame's): the rows' numbers, times and
    # sessions are not features, as `et train --features` leaves them out (each was trained
    # on: a table recorded position after position predicted from its row numbers).
    named = [str(c) for c in getattr(X, "columns", [])]
    twice = _first_twice(named)
    if twice is not None:
        raise EtError(f"X's column {twice!r} twice: each feature column is read by its name")
    not_features = [n for n in named if _native.not_a_feature(n)]
    if not_features:
        said = ", ".join(repr(n) for n in not_features)
        raise EtError(
            f"X's columns {said} hold the rows' numbers, times or sessions (by their names), "
            "not measurements: a model that reads them predicts from the row's place in the "
            f"recording; leave them out (X.drop(columns=[{said}])), and give a session column "
            "as groups="
        )
    if groups is not None and cv == "blocks":
        raise EtError(
            "cv='blocks' with groups: with groups, cross-validation leaves one group out; "
            "give one or the other"
        )
    groups = None if groups is None else _labels(np.asarray(groups), "groups", "group")
    if groups is not None and len(set(groups)) < 2:
        _warn(
            f"one group ({groups[0]!r}) only: nothing in the data can show how a model holds on "
            "a new session"
        )
    if grid is not None and (isinstance(grid, (str, bytes)) or np.shape(grid) != (2,)):
        raise EtError(f"grid = {grid!r}: (rows, cols) of classes, e.g. (3, 3)")
    grid_pair = None if grid is None else (_count(grid[0], "grid rows"), _count(grid[1], "grid columns"))
    model = Model(
        _native.train_table(
            _f64(X, 2, "X"), labels, positions, groups, kind,
            None if folds is None else _count(folds, "folds", domain="folds"), cv, grid_pair,
            bool(per_group), _count(seed, "seed"), _label_type(y) if labels is not None else None,
            _native.BUDGET_S if budget_s is None else _real(budget_s, "budget_s"), progress,
            named or None,
        )
    )
    # What the training changed from the request, or found in the data (a feature of one
    # value), as `et train` says it: a warning, not only a field of `Model.info`.
    note = model._native.note
    if note:
        _warn(note)
    return model


# ---------------------------------------------------------------------------------------------
# Files


def _dataset_from_npz(data: bytes) -> Dataset:
    """A dataset from its .npz bytes: how a pickled dataset is made again."""
    return Dataset.from_npz_bytes(data)


def read_dataset(path: PathLike) -> Dataset:
    """Reads an et dataset (`et collect`'s .csv or .npz): ``x`` (n x p, V), ``y`` (class of
    each row), ``positions_m`` (n x 2), ``pressure_pa``, ``centres_m`` (C x 2), ``electrodes_m``,
    ``visit``, ``feature_index``, ``untouched`` (each visit's untouched frame), ``config_json``."""
    return Dataset.load(os.fsdecode(path))


def read_recording(path: PathLike) -> Dict[str, Any]:
    """Reads an et recording (`et sim`, `et record`; JSON Lines): a dict of ``header`` (its
    protocol, K, columns, units), ``voltages`` (n x K, V; NaN where the board sent NaN or
    infinity), ``seq``, ``t_us``, ``flags`` (n each), ``touches`` (per frame, the truth of a
    simulated frame or None) and ``truncated_tail`` (a cut last line was skipped)."""
    header, volts, seq, t_us, flags, touches, truncated = _native.read_recording(os.fsdecode(path))
    return {
        "header": json.loads(header), "voltages": volts, "seq": seq, "t_us": t_us,
        "flags": flags, "touches": json.loads(touches), "truncated_tail": truncated,
    }


def read_frames(path: PathLike, k: int) -> np.ndarray:
    """Reads any system's frames for a protocol of ``k`` values a frame, n x K (V): a CSV (one
    frame a row), a .npy, ``FILE.npz:NAME`` or ``FILE.mat:VARIABLE`` (a struct's field too, as
    EIDORS keeps its data: ``FILE.mat:vi.meas``; a matrix of frames as columns is read
    transposed), a JSON array of frames (``json.dump(F.tolist())``) or pandas' ``to_json()``,
    or an et recording's
    voltages, as `et reconstruct --frames` reads them (values in a unit of voltage a CSV names,
    ``mV`` in a row of units or ``ch1 (mV)``, in volts); NaN where a value is missing (an empty or NaN cell, a recording's null), as
    ``read_recording`` gives them."""
    frames, _ = _native.read_frames(os.fsdecode(path), _count(k, "k", 1))
    return frames


def __dir__() -> List[str]:
    """What ``dir(et_touch)`` lists: the module's own names and its API (``__all__``), not
    the modules and types it imports (``np``, ``json``, ``Any``), nor its private names."""
    dunder = [n for n in globals() if n.startswith("__") and n.endswith("__")]
    own = [n for n in globals() if n not in _IMPORTED and not n.startswith("_")]
    return sorted(set(own) | set(dunder) | set(__all__))
