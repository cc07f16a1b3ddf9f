"""Read an et data set (`et collect --out NAME.csv`) with nothing but the Python standard library.

    from et_dataset import load
    meta, names, rows = load("train.csv")
    meta["config"]["protocol"], meta["centres_m"][0]    # the '#' lines, parsed
    names[:3], names[-5:]        # f0 f1 f2 ... label x_m y_m visit pressure_pa
    rows[0][names.index("label")]

Every number in the file is in SI units (volts, metres, pascals; its '# units:' line says
so). The file: '#' lines first (format, units, scan configuration, feature indices, class
centres and electrode positions in m, each visit's untouched frame in volts, provenance), then
one row of column names, then one row per observation. Feature columns f0.. are frame values in
volts (V_m, not referenced: subtract the row's visit's untouched frame for V_m - V_0); label is
the class (0-based, row-major over the grid); x_m, y_m where the finger really pressed; visit
the 0-based session; pressure_pa the press's pressure. Version 1 files (x_mm, y_mm,
pressure_kpa, centres_mm, electrodes_mm) are read too, as written (mm, kPa).

With numpy (the '#' lines and the names row are not numbers, so skip them first):

    import numpy
    with open("train.csv") as f:
        lines = [line for line in f if not line.startswith("#")]
    names = lines[0].strip().split(",")
    table = numpy.loadtxt(lines[1:], delimiter=",", ndmin=2)   # shape (observations, columns)
    x = table[:, [i for i, n in enumerate(names) if n.startswith("f")]]
    label = table[:, names.index("label")].astype(int)

(`numpy.loadtxt(path, delimiter=",", comments="#")` alone fails on the names row.)
Large sets: `et collect --out NAME.npz` writes the same content as NumPy arrays, SI units
(`numpy.load`; the arrays' names say their units).

Run as a script for a summary:  python3 python/et_dataset.py train.csv
"""

import json
import sys

FORMATS = ("# et-dataset 2", "# et-dataset 1")


def _numbers(text):
    return [float(v) for v in text.split()]


def load(path):
    """Return (meta, names, rows): the parsed '#' lines, the column names, the rows as floats.
    What is not an et data set raises ValueError naming the file (and line)."""
    try:
        return _load(path)
    except UnicodeDecodeError:
        raise ValueError(f"{path}: not text (UTF-8), so not an et data set") from None


def _other_kind(first):
    """What another of et's files is, by its first line, said before "not an et data set"."""
    if first.replace(" ", "").lower().startswith("source,sink,positive,negative"):
        return "a protocol file (et protocol --csv), "
    try:
        kind = json.loads(first).get("format")
    except (ValueError, AttributeError):
        return ""
    return {
        "et-recording": "an et recording (et sim, et record: read it with et_recording.py), ",
        "et-model": "an et model file (et train), ",
        "et-table-model": "an et model file (et train), ",
    }.get(kind, "")


def _load(path):
    meta = {}
    with open(path, encoding="utf-8-sig") as f:
        first = f.readline().rstrip("\r\n")
        if first not in FORMATS:
            raise ValueError(f"{path}:1: {_other_kind(first)}not an et data set (expected {FORMATS[0]!r})")
        number = 1
        for line in f:
            number += 1
            line = line.rstrip("\r\n")
            if line.startswith("#"):
                key, _, value = line[1:].strip().partition(":")
                value = value.strip()
                try:
                    if key == "config":
                        meta[key] = json.loads(value)
                    elif key == "feature_index":
                        meta[key] = [int(v) for v in value.split()]
                    elif key in ("centres_m", "electrodes_m", "centres_mm", "electrodes_mm",
                                 "untouched"):
                        meta[key] = [_numbers(part) for part in value.split(";") if part.strip()]
                    else:
                        meta[key] = value
                except ValueError as e:
                    raise ValueError(f"{path}:{number}: {key}: {e}") from None
                continue
            names = line.split(",")
            break
        else:
            raise ValueError(f"{path}: no row of column names after the '#' lines")
        rows = []
        for number, line in enumerate(f, start=number + 1):
            if not line.strip():
                continue
            values = line.rstrip("\r\n").split(",")
            if len(values) != len(names):
                raise ValueError(f"{path}:{number}: {len(values)} values, {len(names)} columns")
            try:
                rows.append([float(v) for v in values])
            except ValueError:
                column = next(i for i, v in enumerate(values) if not _is_number(v))
                raise ValueError(
                    f"{path}:{number}: column {names[column]!r}: {values[column]!r} is not a number"
                ) from None
    return meta, names, rows


def _is_number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def main(argv):
    if len(argv) != 2:
        print("usage: python3 et_dataset.py DATASET.csv", file=sys.stderr)
        return 2
    try:
        meta, names, rows = load(argv[1])
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    features = sum(1 for n in names if n.startswith("f"))
    label = names.index("label")
    classes = len({int(r[label]) for r in rows})
    visits = len({int(r[names.index("visit")]) for r in rows})
    print(f"observations {len(rows)}")
    print(f"features {features}")
    print(f"classes {classes}")
    print(f"visits {visits} (untouched frames {len(meta.get('untouched', []))})")
    print(f"protocol {meta['config']['protocol']} L {meta['config']['electrodes']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
