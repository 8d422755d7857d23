"""Every reader of a file refuses a bad one with its message (issue 36): never an uncaught
exception, never an allocation the file asks for before it is checked.

The forgeries are built here: JSON nested 100 000 deep, a zip bomb, a .npy header or zip
directory that lies about its size, truncated files, arrays of the wrong dtype (objects,
pickles), NaN where numbers are meant, a .mat of garbage or with dimensions claiming 32 GB,
tire files and tables of modes too large, too deep or holding numbers beyond every double.
"""

from __future__ import annotations

import io
import json
import struct
import tracemalloc
import zipfile

import numpy as np
import pytest

from tire_fmu.core.inplane_io import InPlaneStateSpace
from tire_fmu.file_checks import FileContentError
from tire_fmu.measurements import MAX_TABLE_BYTES, MeasurementError, read_modes
from tire_fmu.model_files import (
    INPLANE_ARRAYS,
    ModelFileError,
    _checksum,
    _metadata_checksum,
    load_inplane_npz,
    load_mat,
    save_inplane_mat,
    save_inplane_npz,
)
from tire_fmu.tire_files import MAX_TIRE_FILE_BYTES, TireFileError, read_tire_file


def _model(states: int = 6) -> InPlaneStateSpace:
    """A small stable in-plane state space (the loaders check form, not physics)."""
    rng = np.random.default_rng(36)
    inputs = ("torque", "rim_x", "rim_z", "road_0", "road_1")
    outputs = ("rim_Fx", "rim_Fz", "rim_My", "wheel_rate")
    a = rng.normal(size=(states, states)) - 5 * np.eye(states)
    return InPlaneStateSpace(
        a, rng.normal(size=(states, 5)), rng.normal(size=(4, states)),
        *(rng.normal(size=(4, 5)) for _ in range(3)), input_names=inputs,
        output_names=outputs, road_delays_s=np.array([[0.0, 0.001], [0.001, 0.002]]),
        operating_point={"static_outputs": dict.fromkeys(outputs, 0.0)},
        report={"max_relative_error": 0.01})


@pytest.fixture
def saved(tmp_path):
    return save_inplane_npz(_model(), tmp_path / "model.npz")


def _contents(path) -> dict:
    with np.load(path) as archive:
        return {name: archive[name] for name in archive.files}


def _write_npz(path, contents: dict, reseal: bool = True):
    """``contents`` as a model .npz, its checksums recomputed (a forger's file)."""
    meta_text = str(contents.pop("metadata"))
    if reseal:
        meta = json.loads(meta_text)
        meta.pop("checksums")
        checksums = {name: _checksum(np.asarray(contents[name])) for name in INPLANE_ARRAYS
                     if name in contents}
        checksums["metadata"] = _metadata_checksum(meta)
        meta_text = json.dumps({**meta, "checksums": checksums})
    np.savez(path, metadata=np.array(meta_text), **contents)
    return path


def _refused(load, path, *words):
    with pytest.raises(ModelFileError) as caught:
        load(path)
    message = str(caught.value)
    assert message.startswith(str(path)) and "\n" not in message, message
    for word in words:
        assert word in message, message
    return message


def test_a_model_round_trips_and_loads_within_its_limit(saved, tmp_path):
    model = _model()
    back = load_inplane_npz(saved)
    for name in INPLANE_ARRAYS:
        assert np.array_equal(getattr(back, name), getattr(model, name))
    mat = load_mat(save_inplane_mat(model, tmp_path / "model.mat"))
    assert np.array_equal(mat["A"], model.a)
    # a caller may ask for less than the default limit: refused before loading
    _refused(lambda p: load_inplane_npz(p, max_bytes=1000), saved, "more than the 1000")
    _refused(lambda p: load_mat(p, max_bytes=100), tmp_path / "model.mat", "more than the 100")


def test_metadata_nested_deeply_is_refused_not_a_recursion_error(saved, tmp_path):
    contents = _contents(saved)
    contents["metadata"] = np.array("[" * 100_000 + "]" * 100_000)
    forged = _write_npz(tmp_path / "deep.npz", contents, reseal=False)
    _refused(load_inplane_npz, forged, "nested 100000 levels deep", "more than the 64")


def _npy_header(shape, dtype="<f8") -> bytes:
    buffer = io.BytesIO()
    np.lib.format.write_array_header_1_0(  # the magic string, then the header
        buffer, {"descr": dtype, "fortran_order": False, "shape": shape})
    return buffer.getvalue()


def _peak_while(call) -> int:
    """The peak of memory traced (numpy's arrays included) while ``call`` runs."""
    tracemalloc.start()
    try:
        call()
    finally:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
    return peak


def test_a_zip_bomb_is_refused_before_it_expands(saved, tmp_path):
    """A 512 MB array of zeros deflated to well under a megabyte: np.load allocated all of it
    (the hostile pass's 4 MB file asked for 4 GiB); refused from the zip directory."""
    bomb = tmp_path / "bomb.npz"
    contents = _contents(saved)
    with zipfile.ZipFile(bomb, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, array in contents.items():
            if name == "a":
                with archive.open("a.npy", "w", force_zip64=True) as member:
                    member.write(_npy_header((2**26,)))
                    zeros = bytes(1 << 24)
                    for _ in range(32):
                        member.write(zeros)
            else:
                buffer = io.BytesIO()
                np.lib.format.write_array(buffer, array)
                archive.writestr(f"{name}.npy", buffer.getvalue())
    assert bomb.stat().st_size < 2**21
    peak = _peak_while(lambda: _refused(load_inplane_npz, bomb, "'a.npy' is compressed"))
    assert peak < 2**24


def test_a_header_or_directory_that_lies_about_its_size_is_refused(saved, tmp_path):
    # a stored member whose .npy header claims 4 GiB
    liar = tmp_path / "header.npz"
    with zipfile.ZipFile(saved) as source, zipfile.ZipFile(liar, "w") as archive:
        for item in source.infolist():
            data = source.read(item)
            if item.filename == "a.npy":
                data = _npy_header((2**29,)) + bytes(64)
            archive.writestr(item.filename, data)
    peak = _peak_while(lambda: _refused(load_inplane_npz, liar, "its header says (536870912,)"))
    assert peak < 2**24
    # the zip directory's entry for a.npy says it holds 4 GiB (central directory, offset 24)
    data = bytearray(saved.read_bytes())
    entry = data.index(b"PK\x01\x02")
    while bytes(data[entry + 46:entry + 51]) != b"a.npy":  # the entry's name follows at 46
        entry = data.index(b"PK\x01\x02", entry + 4)
    struct.pack_into("<I", data, entry + 24, 2**32 - 2)
    (tmp_path / "directory.npz").write_bytes(bytes(data))
    _refused(load_inplane_npz, tmp_path / "directory.npz")


def test_truncated_files_are_refused(saved, tmp_path):
    whole = saved.read_bytes()
    for fraction in (0.0, 0.1, 0.5, 0.9, 0.999):
        cut = tmp_path / f"cut{fraction}.npz"
        cut.write_bytes(whole[:int(fraction * len(whole))])
        _refused(load_inplane_npz, cut)
    mat = save_inplane_mat(_model(), tmp_path / "model.mat").read_bytes()
    for fraction in (0.0, 0.05, 0.5, 0.9, 0.999):
        cut = tmp_path / f"cut{fraction}.mat"
        cut.write_bytes(mat[:int(fraction * len(mat))])
        _refused(load_mat, cut)


@pytest.mark.parametrize("array, words", [
    (np.ones((6, 6), np.int64), ["int64", "real, complex or text"]),
    (np.ones((6, 6), np.float32), ["float32", "must be real"]),
    (np.ones((6, 6), complex), ["complex128", "must be real"]),
    (np.array([[None] * 6] * 6, dtype=object), ["object", "no pickles"]),
    (np.zeros(6), ["shape (6,)"]),
])
def test_arrays_of_the_wrong_dtype_or_shape_are_refused(saved, tmp_path, array, words):
    contents = _contents(saved)
    contents["a"] = array
    _refused(load_inplane_npz, _write_npz(tmp_path / "forged.npz", contents), *words)


def test_nan_in_a_is_refused_in_npz_and_mat(saved, tmp_path):
    contents = _contents(saved)
    contents["a"] = contents["a"].copy()
    contents["a"][2, 3] = np.nan
    _refused(load_inplane_npz, _write_npz(tmp_path / "nan.npz", contents),
             "'a' holds values that are not finite")
    model = _model()
    model.a[2, 3] = np.nan
    _refused(load_mat, save_inplane_mat(model, tmp_path / "nan.mat"),
             "A holds values that are not finite")


def _mat(path, **variables):
    import scipy.io

    scipy.io.savemat(path, variables, do_compression=False)
    return path


@pytest.mark.parametrize("variables, words", [
    (dict(A=np.eye(2), B=np.eye(2), C=np.eye(2), D=np.eye(2)), ["missing ['metadata_json']"]),
    (dict(A=np.eye(2), B=np.eye(2), C=np.eye(2), D=np.eye(2), metadata_json="{not json"),
     ["not valid JSON"]),
    (dict(A=np.eye(2), B=np.eye(2), C=np.eye(2), D=np.eye(2),
          metadata_json="[" * 5000 + "]" * 5000), ["nested 5000 levels deep"]),
    (dict(A=np.eye(2), B=np.eye(3), C=np.eye(2), D=np.eye(2),
          metadata_json='{"format": "tire_fmu.inplane-linear/1"}'), ["do not fit"]),
    (dict(A=np.eye(2) * 1j, B=np.eye(2), C=np.eye(2), D=np.eye(2),
          metadata_json='{"format": "tire_fmu.inplane-linear/1"}'), ["A is complex128"]),
    (dict(A=np.eye(2), B=np.eye(2), C=np.eye(2), D=np.eye(2), metadata_json='{"format": 3}'),
     ["metadata format 3"]),
    (dict(A="text", B=np.eye(2), C=np.eye(2), D=np.eye(2), metadata_json="{}"),
     ["A is char, must be double"]),
])
def test_a_mat_that_is_no_export_is_refused(tmp_path, variables, words):
    _refused(load_mat, _mat(tmp_path / "forged.mat", **variables), *words)


def test_a_mat_of_garbage_is_refused(tmp_path):
    rng = np.random.default_rng(0)
    for k, head in enumerate((b"", b"MATLAB 5.0 MAT-file" + bytes(108) + b"\x00\x01IM")):
        garbage = tmp_path / f"garbage{k}.mat"
        garbage.write_bytes(head + rng.integers(0, 256, 4096, dtype=np.uint8).tobytes())
        _refused(load_mat, garbage)


def test_a_mat_whose_dimensions_claim_32_gigabytes_is_refused_before_loading(tmp_path):
    path = _mat(tmp_path / "claim.mat", A=np.ones((5, 7)), B=np.eye(2), C=np.eye(2),
                D=np.eye(2), metadata_json="{}")
    data = bytearray(path.read_bytes())
    at = data.index(struct.pack("<ii", 5, 7))
    struct.pack_into("<ii", data, at, 65536, 65536)
    path.write_bytes(bytes(data))
    peak = _peak_while(lambda: _refused(load_mat, path, "expand to"))
    assert peak < 2**24


# -- tire files and tables of modes ------------------------------------------------------------

def test_a_tire_file_too_large_is_refused_before_it_is_read(tmp_path):
    path = tmp_path / "big.toml"
    path.write_text("# padding\n" * (MAX_TIRE_FILE_BYTES // 10 + 1))
    with pytest.raises(TireFileError, match="more than 1048576 bytes: not a tire file"):
        read_tire_file(path)


@pytest.mark.parametrize("body, words", [
    ("[parameters]\nR = 1" + "0" * 400 + "\n[units]\nR = \"m\"\n",
     f"parameters.R = an integer of {(10**400).bit_length()} bits: must be a number in "
     "(0.1, 3] m"),
    ("[parameters]\nR = " + "9" * 5000 + "\n", "not valid TOML"),
    ("[parameters]\nR = nan\n[units]\nR = \"m\"\n", "R = nan: must be a finite number"),
    ("[parameters]\nR = 0.5\n[units]\nR = \"m\"\n[tangential]\nk_tx = inf\n"
     "[tangential_units]\nk_tx = \"N/m^2\"\n", "k_tx = inf"),
])
def test_numbers_in_a_tire_file_that_no_double_holds_are_named(tmp_path, body, words):
    path = tmp_path / "tire.toml"
    path.write_text(body)
    with pytest.raises(TireFileError) as caught:
        read_tire_file(path, warn=False)
    assert words in str(caught.value)


def test_a_tire_file_that_is_not_text_is_refused(tmp_path):
    path = tmp_path / "binary.toml"
    path.write_bytes(b"\xff\xfe\x00garbage\x80")
    with pytest.raises(TireFileError, match="not UTF-8 text"):
        read_tire_file(path)


@pytest.mark.parametrize("text, words", [
    ("order,branch,frequency_hz\n0,in," + "9" * 200_000 + "\n", "not a CSV table"),
    ("order,branch,frequency_hz\n1e300,in,50\n", "must be an integer order n in [0, 800]"),
    ("order,branch,frequency_hz\n0,in,50\0\n", "column 'frequency_hz'"),
])
def test_a_table_of_modes_that_csv_or_a_mesh_cannot_take_is_refused(tmp_path, text, words):
    path = tmp_path / "modes.csv"
    path.write_text(text)
    with pytest.raises(MeasurementError) as caught:
        read_modes(path)
    assert words in str(caught.value)
    path.write_text("#" * (MAX_TABLE_BYTES + 1))
    with pytest.raises(MeasurementError, match="more than 1048576 bytes"):
        read_modes(path)


def test_every_file_error_is_one_line_from_the_cli(tmp_path, capsys):
    from tire_fmu.cli import main

    table = tmp_path / "modes.csv"
    table.write_text("order,branch,frequency_hz\n0,in," + "9" * 200_000 + "\n")
    tire = tmp_path / "tire.toml"
    tire.write_text("[parameters]\nR = " + "9" * 5000 + "\n")
    for argv in (["fit", str(table)], ["modes", "--tire-file", str(tire)]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "error:" in err and str(tmp_path) in err, err


def test_an_fmus_baked_parameters_are_checked_before_they_are_believed(tmp_path):
    from tire_fmu.fmu.slave import BAKED_PARAMETERS_FILE, _baked_parameter_values

    baked = tmp_path / BAKED_PARAMETERS_FILE
    for text, words in (('{"R": "heavy"}', "finite numbers"), ("[" * 10_000, "nested"),
                        ('{"R": NaN}', "finite numbers"), ("\x80", "not UTF-8")):
        baked.write_bytes(text.encode("latin-1"))
        with pytest.raises(FileContentError, match=words):
            _baked_parameter_values(str(tmp_path))
    baked.write_text('{"R": 0.6}')
    assert _baked_parameter_values(str(tmp_path)) == {"R": 0.6}
