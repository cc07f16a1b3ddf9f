"""Read an et recording (JSON Lines) with nothing but the Python standard library.

    from et_recording import load
    header, frames = load("touch.jsonl")
    header["K"], header["protocol"], header["columns"][0]   # what each column measures
    frames[0]["voltages"]                                  # V_m in volts, K values
    frames[0].get("touches")                               # the truth, for simulated frames
    header.get("units")                                    # SI: m, Pa (recordings before it too)
    frames[0].get("invalid", [])                           # columns the board sent as NaN/inf
    frames[0]["flags"] & RAIL, frames[0]["flags"] & COMPLIANCE   # readings the board flagged

Every number is SI (the header's "units" says so): voltages in V, the truth's x, y and radius in
m and its pressure in Pa, t_us in microseconds.

A frame's "flags" carry the board's word on its scan: RAIL (bit 0) a reading with samples on an
ADC rail (clipped: a gain too high, or a contact that opens), COMPLIANCE (bit 3) the current
source unable to drive its load (a contact loose or dry: readings too small). Such frames'
values may not be the sheet's; the summary counts them.

JSON has no NaN: a value the board sent as NaN or infinite is written as null; load() turns it
into float("nan") and the frame lists its columns in "invalid".

With numpy:  V = numpy.array([f["voltages"] for f in frames])   # shape (n_frames, K)
With pandas: pandas.read_json("touch.jsonl", lines=True).iloc[1:]

Run as a script for a summary:  python3 python/et_recording.py touch.jsonl
"""

import json
import math
import sys

FORMAT = "et-recording"
VERSION = 1
RAIL = 1 << 0
COMPLIANCE = 1 << 3


def load(path):
    """Return (header, frames). A last line cut short by a crash is skipped with a warning;
    anything else that is not a recording's raises ValueError naming the file and line."""
    with open(path, encoding="utf-8", errors="replace") as f:
        lines = f.read().splitlines()
    if not lines:
        raise ValueError(f"{path}: empty file, no header")
    first = lines[0].lstrip("\ufeff")
    try:
        header = json.loads(first)
    except json.JSONDecodeError as e:
        # Another of et's text files is said as what it is.
        if first.startswith("# et-dataset"):
            raise ValueError(f"{path}:1: an et dataset (et collect), not a recording: read it with et_dataset.py") from None
        if first.replace(" ", "").lower().startswith("source,sink,positive,negative"):
            raise ValueError(f"{path}:1: a protocol file (et protocol --csv), not a recording") from None
        raise ValueError(
            f"{path}:1: not an et recording: its first line is not JSON ({e.msg}, column "
            f"{e.colno}); et sim and et record write recordings, and `et reconstruct --frames` "
            "reads another system's frames (.csv, .npy, .npz, .mat)"
        ) from None
    kind = header.get("format") if isinstance(header, dict) else None
    if kind in ("et-model", "et-table-model"):
        raise ValueError(f"{path}:1: an et model file (et train), not a recording")
    if kind != FORMAT:
        raise ValueError(
            f"{path}:1: not an et recording: its first line is JSON without et's "
            f'"format": "{FORMAT}" (another tool\'s file?)'
        )
    if header.get("version") != VERSION:
        raise ValueError(f"{path}:1: {FORMAT} version {header.get('version')!r}: this reader reads version {VERSION}")
    frames = []
    for number, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        try:
            frame = json.loads(line)
        except json.JSONDecodeError as e:
            if number == len(lines):
                print(f"{path}:{number}: last line cut short, skipped", file=sys.stderr)
                break
            said = f"{path}:{number}: not a JSON frame ({e.msg}, column {e.colno})"
            raise ValueError(said) from None
        if not isinstance(frame, dict) or not isinstance(frame.get("voltages"), list):
            raise ValueError(f"{path}:{number}: a frame without its list of voltages")
        if len(frame["voltages"]) != header["K"]:
            raise ValueError(f"{path}:{number}: {len(frame['voltages'])} values, K = {header['K']}")
        frame["voltages"] = [math.nan if v is None else v for v in frame["voltages"]]
        frame["invalid"] = [i for i, v in enumerate(frame["voltages"]) if not math.isfinite(v)]
        frames.append(frame)
    return header, frames


def main(argv):
    if len(argv) != 2:
        print("usage: python3 et_recording.py RECORDING.jsonl", file=sys.stderr)
        return 2
    try:
        header, frames = load(argv[1])
    except (OSError, ValueError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    touched = sum(1 for f in frames if f.get("touches"))
    peak = max((abs(v) for f in frames for v in f["voltages"] if math.isfinite(v)), default=0.0)
    invalid = sum(1 for f in frames if f["invalid"])
    rail = sum(1 for f in frames if f.get("flags", 0) & RAIL)
    compliance = sum(1 for f in frames if f.get("flags", 0) & COMPLIANCE)
    print(f"frames {len(frames)}")
    print(f"K {header['K']}")
    print(f"protocol {header['protocol']} L {header['electrodes']}")
    print(f"touched {touched}")
    print(f"invalid_frames {invalid}")
    print(f"rail_frames {rail}")
    print(f"compliance_frames {compliance}")
    print(f"peak_volts {peak:.6f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
