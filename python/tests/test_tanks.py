"""et's defaults from Python on two real saline tanks measured by other labs' instruments, as a
user of the module meets them: the sheet and the protocol built from the data set's own
tables (`et.disc`, `et.Protocol.from_rows`), the background fitted to the reference frame,
then every case with known targets imaged with nothing else chosen. The bar is the one
`et reconstruct`'s test holds (host/tests/tanks.rs): the strongest object at most 5 mm from a
target in the median case, its sign right in all but one case, the object count within one
in 80 % of cases; and `Image.segment()` is the picture `et reconstruct --segment` writes.

The data (`../shared/data/tanks/`, beside the project, not in the repository): the "Open 2D
Electrical Impedance Tomography data archive", Hauptmann, Kolehmainen, Mach, Savolainen,
Seppanen, Siltanen (2017), arXiv:1704.01178 (KIT4, 16 electrodes); the Kuopio Tomography
Challenge 2023's training data (Finnish Inverse Problems Society and the University of
Eastern Finland, Zenodo record 8252370; 32 electrodes). Without the folder the tests skip.
"""

import csv
from pathlib import Path

import numpy as np
import pytest

import et_touch as et

TANKS = Path(__file__).resolve().parents[3] / "shared" / "data" / "tanks"

# name, radius (m), electrode width (m): from ../shared/data/tanks/README.md.
GEOMETRY = [("kit4-2017", 0.14, 0.025), ("ktc2023-training", 0.115, 0.0113)]


def table(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def tank(name, radius, width):
    """The tank's sheet, protocol, reference frame and cases (id, frame, targets)."""
    d = TANKS / name
    angles = [float(r["angle_deg"]) for r in table(d / "electrodes.csv")]
    step = (angles[1] - angles[0] + 540.0) % 360.0 - 180.0
    sheet = et.disc(
        radius, len(angles), electrode_width_m=width, contact_ohm=20.0,
        first_deg=angles[0], direction="ccw" if step > 0 else "cw",
    )
    injections = table(d / "injection_pairs.csv")
    measurements = table(d / "measurement_pairs.csv")
    # One row per frame value, electrodes from 1; the amplitudes are in mA.
    rows = [
        [float(i["source_electrode(+)"]), float(i["sink_electrode(-)"]),
         float(m["plus_electrode"]), float(m["minus_electrode"]),
         1e-3 * float(i["amplitude_file_units"])]
        for i in injections for m in measurements
    ]
    protocol = et.Protocol.from_rows(rows, len(angles), base=1)
    reference = np.loadtxt(d / "reference.csv", delimiter=",", ndmin=2)[0]
    voltages = np.loadtxt(d / "voltages.csv", delimiter=",", ndmin=2)
    truth = table(d / "ground_truth_objects.csv")
    cases = []
    for row, sample in enumerate(table(d / "samples.csv")):
        targets = [
            (float(t["centroid_x_m"]), float(t["centroid_y_m"]), t["kind"] == "conductive")
            for t in truth if t["sample_id"] == sample["sample_id"]
        ]
        if targets:
            cases.append((sample["sample_id"], voltages[row], targets))
    return sheet, protocol, reference, cases


@pytest.mark.parametrize("name, radius, width", GEOMETRY)
def test_defaults_hold_on_a_real_tank(name, radius, width):
    if not (TANKS / name).is_dir():
        pytest.skip("no ../shared/data/tanks beside the project")
    sheet, protocol, reference, cases = tank(name, radius, width)
    r = et.Reconstructor(sheet, protocol)
    r.fit_background(reference)
    misses, signs, counts = [], 0, 0
    for case_id, v, targets in cases:
        image = r.image(v, reference)
        assert image.objects, f"{name} {case_id}: no object"
        top = image.objects[0]
        miss, conductive = min(
            (np.hypot(x - top["x_m"], y - top["y_m"]), c) for x, y, c in targets
        )
        misses.append(miss)
        signs += (top["sign"] > 0) == conductive
        counts += abs(len(image.objects) - len(targets)) <= 1
        classes = image.segment()
        assert classes.shape == image.pixels.shape
        inside = ~np.isnan(image.pixels)
        assert np.array_equal(np.isnan(classes), ~inside), f"{name} {case_id}: NaN outside only"
        assert set(np.unique(classes[inside])) <= {0.0, 1.0, 2.0}
    n = len(cases)
    summary = (
        f"{name}: {1e3 * np.median(misses):.1f} mm, sign {signs}/{n}, count {counts}/{n}"
    )
    print(summary)
    assert np.median(misses) <= 5e-3 and signs >= n - 1 and counts >= 0.8 * n, summary


def test_the_segment_is_et_reconstructs(et_cli, work):
    name, radius, width = GEOMETRY[1]
    if not (TANKS / name).is_dir():
        pytest.skip("no ../shared/data/tanks beside the project")
    sheet, protocol, reference, cases = tank(name, radius, width)
    case_id, v, _ = cases[0]
    r = et.Reconstructor(sheet, protocol)
    r.fit_background(reference)
    image = r.image(v, reference)
    # The same tank through the command line: a scene, its protocol file and the frames.
    np.savetxt(work / "frames.csv", np.vstack([reference, v]), delimiter=",")
    rows = np.column_stack([protocol.rows + 1, protocol.currents])
    np.savetxt(
        work / "protocol.csv", rows, delimiter=",", fmt=["%d"] * 4 + ["%.9e"],
        header="source,sink,positive,negative,current_a", comments="",
    )
    e = sheet.spec["electrodes"]
    (work / "scene.toml").write_text(
        f'[sheet]\nshape = {{ kind = "disc", radius = {radius} }}\n'
        f"electrodes = {{ count = {e['count']}, width = {width}, contact_ohm = 20, "
        f"first_deg = {e['first_deg']}, direction = \"{e['direction']}\" }}\n"
        '[scan]\nprotocol = { file = "protocol.csv", base = 1 }\n'
    )
    summary = et_cli(
        "reconstruct", "--scene", work / "scene.toml", "--frames", work / "frames.csv",
        "--reference", 1, "--frame", 1, "--json", "--force", "--out", work / "tank.png",
        "--segment", work / "classes.npy",
    )
    cli = np.load(work / "classes.npy")
    assert summary["segment"]["unit"].startswith("class")
    agree = np.mean((cli == image.segment()) | (np.isnan(cli) & np.isnan(image.segment())))
    # The module takes frames in single precision as the CLI's reader does: the same picture.
    assert agree > 0.995, f"{case_id}: the module's and the CLI's pictures agree on {agree:.3%}"
