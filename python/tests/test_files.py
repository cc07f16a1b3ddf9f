"""et's files read into NumPy arrays, against the standard-library readers and numpy itself."""

import importlib.util
import json
import os
import re

import numpy as np
import pytest

import et_touch as et

from conftest import ROOT, SCENES


def stdlib_reader(name):
    spec = importlib.util.spec_from_file_location(name, ROOT / "python" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_standard_librarys_reader_says_what_is_not_a_recording(recording, tmp_path):
    # It raised json's own JSONDecodeError ("Expecting value: line 1 column 1"), of no file.
    reader = stdlib_reader("et_recording")
    frames_csv = tmp_path / "frames.csv"
    frames_csv.write_text("v0,v1\n0.1,0.2\n")
    with pytest.raises(ValueError, match="frames.csv:1: not an et recording: its first line is "
                       "not JSON .*et reconstruct --frames"):
        reader.load(frames_csv)
    lines = open(recording).read().splitlines()
    damaged = tmp_path / "damaged.jsonl"
    damaged.write_text("\n".join(lines[:3] + ['{"seq": 2, oops}'] + lines[4:]) + "\n")
    with pytest.raises(ValueError, match="damaged.jsonl:4: not a JSON frame"):
        reader.load(damaged)
    assert reader.main(["et_recording.py", str(damaged)]) == 1
    # Another of et's files, or another tool's JSON, said as what it is ("not an et-recording
    # version 1 header" said of each).
    for text, said in [
        ("# et-dataset 2\n", "an et dataset (et collect), not a recording: read it with et_dataset.py"),
        ("source,sink,positive,negative\n0,1,2,3\n", "a protocol file (et protocol --csv), not a recording"),
        ('{"format": "et-table-model", "version": 2}\n', "an et model file (et train), not a recording"),
        ('{"a": 1}\n', "not an et recording: its first line is JSON without et's \"format\": \"et-recording\""),
    ]:
        other = tmp_path / "other.txt"
        other.write_text(text)
        with pytest.raises(ValueError, match=re.escape(f"other.txt:1: {said}")):
            reader.load(other)
    # And to the dataset reader, a recording said as one.
    with pytest.raises(ValueError, match=re.escape("an et recording (et sim, et record: read it with et_recording.py), not an et data set")):
        stdlib_reader("et_dataset").load(recording)


def test_the_standard_librarys_dataset_reader_names_the_cell(et_cli, tmp_path):
    # A cell that is not a number raised float()'s "could not convert string to float: 'x'",
    # of no line or column, and the script ended in a traceback.
    reader = stdlib_reader("et_dataset")
    dataset = tmp_path / "d.csv"
    et_cli(
        "collect", "--scene", SCENES / "square-13cm-16.toml", "--grid", "2x2", "--visits", 1,
        "--scans", 1, "--subsections", 2, "--out", dataset,
    )
    lines = open(dataset).read().splitlines()
    header = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    cells = lines[header + 1].split(",")
    cells[-1] = "x"
    damaged = tmp_path / "damaged.csv"
    damaged.write_text("\n".join(lines[:header + 1] + [",".join(cells)] + lines[header + 2:]))
    last = lines[header].split(",")[-1]
    with pytest.raises(ValueError, match=f"damaged.csv:{header + 2}: column '{last}': 'x' is not"):
        reader.load(damaged)
    assert reader.main(["et_dataset.py", str(damaged)]) == 1
    binary = tmp_path / "frames.npy"
    binary.write_bytes(b"\x93NUMPY\x01\x00")
    with pytest.raises(ValueError, match="frames.npy: not text"):
        reader.load(binary)


def test_a_recording_reads_as_the_standard_library_reads_it(recording):
    r = et.read_recording(recording)
    header, frames = stdlib_reader("et_recording").load(recording)
    assert r["header"] == header
    assert r["voltages"].shape == (len(frames), header["K"])
    # et's frames are single precision, written as the shortest decimal that reads back.
    stdlib = np.array([f["voltages"] for f in frames], dtype=np.float32)
    np.testing.assert_array_equal(r["voltages"], stdlib.astype(np.float64))
    np.testing.assert_array_equal(r["seq"], [f["seq"] for f in frames])
    np.testing.assert_array_equal(r["t_us"], [f["t_us"] for f in frames])
    assert r["touches"] == [f.get("touches") for f in frames]
    assert r["truncated_tail"] is False
    # read_frames takes a recording as et reconstruct --frames does (it was read as a CSV
    # and refused for its JSON), and says its K.
    np.testing.assert_array_equal(et.read_frames(recording, header["K"]), r["voltages"])
    with pytest.raises(et.EtError, match="an et recording of K = 208 values a frame, not 32"):
        et.read_frames(recording, 32)
    # A path as bytes (os.listdir(b".") gives them) is a path, as Python's open() takes it
    # (it raised "'bytes' object is not an instance of 'str'").
    path = os.fsencode(recording)
    np.testing.assert_array_equal(et.read_frames(path, header["K"]), r["voltages"])
    np.testing.assert_array_equal(et.read_recording(path)["voltages"], r["voltages"])


def test_a_cut_recording_keeps_its_whole_frames(recording, work):
    cut = work / "cut.jsonl"
    text = recording.read_text()
    cut.write_text(text[: len(text) - 50])
    r = et.read_recording(cut)
    assert r["truncated_tail"] is True
    assert len(r["voltages"]) == len(text.splitlines()) - 2


def test_a_dataset_reads_the_same_from_csv_and_npz(et_cli, work, dataset):
    csv_path = work / "train.csv"
    et_cli(
        "collect", "--scene", SCENES / "square-13cm-16.toml", "--grid", "3x3", "--visits", 2,
        "--scans", 3, "--subsections", 5, "--out", csv_path, "--force",
    )
    a, b = et.read_dataset(dataset), et.read_dataset(csv_path)
    for name in ("x", "y", "positions_m", "centres_m", "visit", "feature_index", "untouched"):
        np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=1e-12, err_msg=name)
    assert json.loads(a.config_json) == json.loads(b.config_json)
    # numpy reads et's .npz itself: the same observations.
    with np.load(dataset) as raw:
        np.testing.assert_array_equal(a.x, raw["x"])


@pytest.mark.parametrize("layout", ["rows", "columns"])
def test_frames_of_another_system_read_in_either_orientation(work, layout):
    rng = np.random.default_rng(3)
    frames = rng.normal(1.0, 0.1, size=(7, 208)).astype(np.float32).astype(np.float64)
    path = work / f"frames-{layout}.npy"
    np.save(path, frames if layout == "rows" else frames.T)
    np.testing.assert_array_equal(et.read_frames(path, 208), frames)
    csv = work / f"frames-{layout}.csv"
    np.savetxt(csv, frames, delimiter=",", fmt="%.9g")
    np.testing.assert_allclose(et.read_frames(csv, 208), frames, rtol=1e-7)
    # A DAQ's name (.dat) holding the same text: read by what it holds, not as a recording.
    dat = work / f"frames-{layout}.dat"
    np.savetxt(dat, frames, fmt="%.9g")
    np.testing.assert_allclose(et.read_frames(dat, 208), frames, rtol=1e-7)
    # A value missing (an empty cell, a DAQ's dropped sample): NaN there, the rest read.
    if layout == "rows":
        lines = dat.read_text().splitlines()
        cells = lines[2].split(" ")
        cells[5] = "nan"
        lines[2] = " ".join(cells)
        dat.write_text("\n".join(lines) + "\n")
        read = et.read_frames(dat, 208)
        assert np.isnan(read[2, 5]) and np.isnan(read).sum() == 1
        # As JSON, Python's NaN in it (json.dump writes it), and as a CSV in millivolts whose
        # row of units says so: the same volts.
        gappy = frames.copy()
        gappy[2, 5] = np.nan
        as_json = work / "frames.json"
        as_json.write_text(json.dumps(gappy.tolist()))
        np.testing.assert_array_equal(et.read_frames(as_json, 208), gappy)
        # As pandas' default to_json() writes a DataFrame (a key a column, each its values by
        # the rows' index), written here without pandas.
        as_columns = work / "frames-columns.json"
        columns = {f"ch{k}": {str(i): v for i, v in enumerate(gappy[:, k])} for k in range(208)}
        as_columns.write_text(json.dumps(columns))
        np.testing.assert_array_equal(et.read_frames(as_columns, 208), gappy)
        mv = work / "frames-mv.csv"
        names = ",".join(f"ch{k}" for k in range(208))
        units = ",".join(["mV"] * 208)
        np.savetxt(mv, frames * 1e3, delimiter=",", fmt="%.9g", header=names + "\n" + units,
                   comments="")
        np.testing.assert_allclose(et.read_frames(mv, 208), frames, rtol=1e-6)


def test_compressed_and_big_endian_arrays_read_as_numpy_reads_them(work, dataset):
    """`savez_compressed` (deflated entries) and big-endian arrays, as numpy writes them."""
    rng = np.random.default_rng(4)
    # (Frames are taken in single precision.)
    frames = rng.normal(1.0, 0.1, size=(5, 208)).astype(np.float32).astype(np.float64)
    packed = work / "frames-compressed.npz"
    np.savez_compressed(packed, frames=frames)
    np.testing.assert_array_equal(et.read_frames(packed, 208), frames)
    turned = work / "frames-big-endian.npy"
    np.save(turned, frames.astype(">f8"))
    np.testing.assert_array_equal(et.read_frames(turned, 208), frames)
    # A dataset rewritten with savez_compressed, array for array, reads back the same.
    with np.load(dataset) as raw:
        arrays = {name: raw[name] for name in raw.files}
    again = work / "dataset-compressed.npz"
    np.savez_compressed(again, **arrays)
    a, b = et.read_dataset(dataset), et.read_dataset(again)
    np.testing.assert_array_equal(a.x, b.x)
    np.testing.assert_array_equal(a.y, b.y)


def test_bad_files_are_named_in_the_error(work):
    missing = work / "no-such.jsonl"
    with pytest.raises(et.EtError, match="no-such.jsonl"):
        et.read_recording(missing)
    bad = work / "bad.npz"
    bad.write_bytes(b"PK\x03\x04 not a zip")
    with pytest.raises(et.EtError, match="bad.npz"):
        et.read_dataset(bad)
    wrong = work / "wrong.npy"
    np.save(wrong, np.zeros((3, 5)))
    with pytest.raises(et.EtError, match="wrong.npy"):
        et.read_frames(wrong, 208)


def test_dir_lists_the_api_not_the_imports():
    # `dir(et_touch)` showed `np`, `json`, `os`, `Any`, ... beside the API.
    names = dir(et)
    assert set(et.__all__) <= set(names)
    assert "SCALE_SAID" in names and "__doc__" in names
    for imported in ["np", "json", "os", "re", "Any", "Optional", "dataclass", "annotations"]:
        assert imported not in names, imported
    assert not [n for n in names if n.startswith("_") and not n.endswith("__")]
