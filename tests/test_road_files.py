"""Road files: OpenCRG and profiles read by tire_fmu/road_files.py and by the native FMUs' C
(road_file.c), against the ASAM OpenCRG C API (pycrg) and pyopencrg as independent references;
the files ``tire-fmu road`` writes; refusals with the same sentence in both runtimes."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pycrg
import pyopencrg
import pytest
from road_file_c import CRoadFileError, CRoadFiles, compile_library
from scipy import integrate, signal, stats

from tire_fmu import road_files
from tire_fmu.cli import main
from tire_fmu.core.iso8608 import ISO_8608_GD_N0_M3, Iso8608Spectrum
from tire_fmu.core.obstacles import (
    MAX_CROWN_RADIUS_M,
    MAX_OBSTACLE_LENGTH_M,
    MAX_OBSTACLE_SIZE_M,
    ProfileRoad,
    StepCleat,
    TriangularCleat,
)
from tire_fmu.native.builder import INPLANE, RADIAL, c_folder
from tire_fmu.road_files import RoadFileError, read_road_file, write_crg, write_profile

pycrg.set_message_level(0)  # its loader's notices are no finding here
FORMATS = road_files.SUPPORTED_CRG_FORMATS
#: float32's relative half step: the C API keeps the grid in single precision
SINGLE = 2.0**-24


@pytest.fixture(scope="module")
def c_reader(tmp_path_factory) -> CRoadFiles:
    return CRoadFiles(compile_library(tmp_path_factory.mktemp("road_file_c")))


def _pycrg_heights(path, u, v) -> np.ndarray:
    """The ASAM C API's heights after its standard load (file, then its modifiers)."""
    with pycrg.DataSet.open(str(path)) as dataset:
        point = dataset.create_contact_point()
        return np.array([point.uv_to_z(float(a), float(b)) for a, b in zip(u, v)])


def _both(c_reader, path, v):
    """(Python's road file, C's road) at lateral offset v."""
    return read_road_file(path, v), c_reader.open(path, v)


def _probe_u(first, last, rng, knots):
    """Off-grid u inside, at the knots, just inside the ends and well beyond them."""
    span = last - first
    return np.r_[rng.uniform(first, last, 150), knots[::max(1, knots.size // 40)],
                 first + 1e-9, last - 1e-9, first, last, first - 0.3 * span, last + 0.3 * span,
                 first - 1e-6, last + 1e-6]


def _pyopencrg_road(rng, nu=301):
    """A road pyopencrg writes: long sections at uneven v, a slope and a banking channel, a
    start height; grid heights that are single-precision and short-decimal exact (k/256 m),
    so every format holds the same numbers."""
    v = np.array([-1.2, -0.7, -0.1, 0.35, 0.9, 1.4])
    z = rng.integers(-8, 9, (nu, v.size)) / 256
    slope = 0.01 * np.sin(np.arange(nu - 1) / 17)
    bank = 0.02 * np.cos(np.arange(nu) / 23)
    return pyopencrg.CrgRoad(z, u_inc=0.02, v=v, u_start=3.0, slope=slope, banking=bank,
                             z_start=0.1), v


@pytest.mark.parametrize("data_format", FORMATS)
def test_files_pyopencrg_writes_read_as_the_asam_c_api_evaluates_them(tmp_path, c_reader,
                                                                    data_format):
    """Acceptance: a .crg written by another tool gives the C API's heights to 1e-9 m in both
    readers, at off-grid u and v, near and beyond the extent; the two readers agree bit for
    bit. The file has uneven long sections, a slope and a banking channel, a start height and
    no modifiers block (OpenCRG's defaults put the start of the reference line at 0)."""
    rng = np.random.default_rng(5)
    road, v_sections = _pyopencrg_road(rng)
    path = tmp_path / f"other_{data_format}.crg"
    road.save(str(path), fmt=data_format)
    for v in (0.0, v_sections[0], v_sections[-1], 0.123, -0.95, v_sections[2] + 1e-9):
        ours, c = _both(c_reader, path, v)
        with c:
            first, last = ours.extent_m
            u = _probe_u(first, last, rng, ours.road.distances_m)
            reference = _pycrg_heights(path, u, np.full(u.size, v))
            python = ours.road.profile(u)[0]
            assert np.max(np.abs(python - reference)) < 1e-9, (v, np.abs(python - reference).max())
            assert np.array_equal(c.height(u), python)
            assert np.array_equal(c.heights_m, ours.road.heights_m)
            assert c.extent_m == ours.extent_m
            assert c.height_shift_m == ours.height_shift_m != 0.0
    if data_format[2] != "B":
        return  # pyopencrg's text slopes are not the 10 or 20 characters the C API reads
    # pyopencrg's own evaluation (no modifiers: the file as stored) differs by the shift alone
    stored = pyopencrg.read(str(path)).uv_to_z(u, np.full(u.size, v))
    inside = (u >= first) & (u <= last)
    assert np.allclose(stored[inside], python[inside] - ours.height_shift_m, rtol=0, atol=1e-9)


def test_double_precision_files_keep_their_doubles(tmp_path, c_reader):
    """KDBI keeps doubles; the C API rounds its grid to single precision: the two differ by
    at most half a single-precision step of the heights, and the readers give the file's own
    numbers (the interpolation of what was written)."""
    rng = np.random.default_rng(7)
    z = rng.normal(0.0, 0.02, (401, 3))
    path = write_crg(tmp_path / "doubles.crg", z, 0.005, [-0.5, 0.0, 0.5], "KDBI")
    ours, c = _both(c_reader, path, 0.2)
    with c:
        assert np.allclose(ours.road.heights_m, z[:, 1] + 0.4 * (z[:, 2] - z[:, 1]), rtol=0,
                           atol=1e-17)
        u = _probe_u(*ours.extent_m, rng, ours.road.distances_m)
        reference = _pycrg_heights(path, u, np.full(u.size, 0.2))
        bound = SINGLE * np.max(np.abs(z)) * 2 + 1e-15
        assert np.max(np.abs(ours.road.profile(u)[0] - reference)) <= bound
        assert np.array_equal(c.height(u), ours.road.profile(u)[0])


def _with_block(path: Path, block: str, out: Path) -> Path:
    """The text file ``path`` with ``block`` (header lines) before its $KD_DEFINITION."""
    text = path.read_text(encoding="latin-1")
    out.write_text(text.replace("$KD_DEFINITION", block + "\n$KD_DEFINITION", 1),
                   encoding="latin-1")
    return out


@pytest.mark.parametrize("mods", [
    "",
    "refpoint_u_fraction = 0.5\nrefpoint_z = 0.25",
    "refpoint_u = 5.0\nrefpoint_v = -0.4\nrefpoint_z = -1.0",
    "refpoint_v_fraction = 0.75\nrefpoint_v_offset = 0.1\nrefpoint_u_offset = 0.3",
    "refpoint_x = 10.0\nrefpoint_phi = 1.0",
    "refline_offset_z = 0.05\nrefline_offset_x = 3.0",
    "grid_nan_mode = 1\nscale_curvature = 2.0",
])
def test_the_modifiers_shift_the_heights_as_the_c_api_does(tmp_path, c_reader, mods):
    rng = np.random.default_rng(11)
    road, _ = _pyopencrg_road(rng, nu=121)
    source = tmp_path / "plain.crg"
    road.save(str(source), fmt="LDFI")
    path = _with_block(source, f"$ROAD_CRG_MODS\n{mods}\n$", tmp_path / "mods.crg")
    for v in (0.0, 0.6):
        ours, c = _both(c_reader, path, v)
        with c:
            u = _probe_u(*ours.extent_m, rng, ours.road.distances_m)
            reference = _pycrg_heights(path, u, np.full(u.size, v))
            assert np.max(np.abs(ours.road.profile(u)[0] - reference)) < 1e-9
            assert np.array_equal(c.height(u), ours.road.profile(u)[0])


def test_a_reference_line_end_height_integrates_as_the_c_api(tmp_path, c_reader):
    """reference_line_end_z: the C API's backward, then blended forward integration."""
    rng = np.random.default_rng(12)
    road, _ = _pyopencrg_road(rng, nu=61)
    source = tmp_path / "plain.crg"
    road.save(str(source), fmt="LDFI")
    text = source.read_text(encoding="latin-1")
    text = re.sub(r"reference_line_end_z\s*=.*", "reference_line_end_z = 0.4", text)
    path = tmp_path / "end_z.crg"
    path.write_text(text, encoding="latin-1")
    ours, c = _both(c_reader, path, 0.3)
    with c:
        u = _probe_u(*ours.extent_m, rng, ours.road.distances_m)
        assert np.max(np.abs(ours.road.profile(u)[0]
                             - _pycrg_heights(path, u, np.full(u.size, 0.3)))) < 1e-9
        assert np.array_equal(c.height(u), ours.road.profile(u)[0])


def test_files_the_cli_writes_agree_with_pycrg_and_pyopencrg(tmp_path, c_reader):
    """`tire-fmu road` files: read by both readers, pycrg and pyopencrg alike (KRBI to 1e-9 m;
    KDBI within the C API's single precision)."""
    iso = tmp_path / "iso.crg"
    cleat = tmp_path / "cleat.crg"
    assert main(["road", "iso8608", "--class", "C", "--length", "40", "--out", str(iso),
                 "--format", "KRBI"]) == 0
    assert main(["road", "cleat", "--out", str(cleat)]) == 0
    rng = np.random.default_rng(3)
    for path, tolerance in ((iso, 1e-9), (cleat, 2 * SINGLE * 0.02 + 1e-15)):
        for v in (0.0, -0.37, 0.5):
            ours, c = _both(c_reader, path, v)
            with c:
                u = _probe_u(*ours.extent_m, rng, ours.road.distances_m)
                python = ours.road.profile(u)[0]
                assert np.max(np.abs(python - _pycrg_heights(path, u, np.full(u.size, v)))) \
                    <= tolerance
                other = pyopencrg.read(str(path), apply_mods=True, check=False)
                assert np.max(np.abs(python - other.uv_to_z(u, np.full(u.size, v)))) < 1e-12
                assert np.array_equal(c.height(u), python)
                assert ours.height_shift_m == 0.0  # an empty modifiers block: as written


def test_a_profile_file_round_trips(tmp_path, c_reader):
    rng = np.random.default_rng(1)
    distances = np.cumsum(rng.uniform(1e-3, 0.2, 500)) - 3.0  # uneven, starting below 0
    heights = rng.normal(0.0, 0.01, distances.size)
    path = write_profile(tmp_path / "road.csv", distances, heights, ["a test road"])
    ours = read_road_file(path)
    assert np.array_equal(ours.road.distances_m, distances)  # repr: the same doubles
    assert np.array_equal(ours.road.heights_m, heights)
    assert ours.data_format == "profile" and ours.extent_m == (distances[0], distances[-1])
    with c_reader.open(path) as c:
        assert np.array_equal(c.distances_m, distances)
        assert np.array_equal(c.heights_m, heights)
        s = _probe_u(*ours.extent_m, rng, distances)
        assert np.array_equal(c.height(s), ours.road.profile(s)[0])
        assert np.array_equal(c.slope(s), ours.road.profile(s)[1])
    # blanks, a header line, comments and a byte-order mark read the same
    text = "\ufeff# measured\ndistance height\n" + "".join(
        f"  {float(a)!r}\t {float(b)!r}  # point\n" for a, b in zip(distances, heights))
    (tmp_path / "blank.txt").write_text(text, encoding="utf-8")
    again = read_road_file(tmp_path / "blank.txt")
    assert np.array_equal(again.road.heights_m, heights)
    with c_reader.open(tmp_path / "blank.txt") as c:
        assert np.array_equal(c.heights_m, heights)


def test_beyond_its_extent_the_road_is_level_at_its_end_heights(tmp_path, c_reader):
    """The C API's default border mode: the end heights kept, slope 0; the window means of
    a window across an end are the exact integral of that; leaves_extent says when."""
    distances = np.array([2.0, 2.5, 3.0, 4.0])
    heights = np.array([0.01, -0.02, 0.005, 0.03])
    path = write_profile(tmp_path / "short.csv", distances, heights)
    ours = read_road_file(path)
    height, slope = ours.road.profile([-5.0, 1.9, 4.1, 50.0])
    assert np.array_equal(height, [0.01, 0.01, 0.03, 0.03]) and not slope.any()
    # a window from 1 m before the start to 0.5 m into the road
    exact = 1.0 * 0.01 + 0.5 * 0.5 * (0.01 - 0.02)
    assert ours.road.mean_height(1.0, 2.5) == pytest.approx(exact / 1.5, abs=1e-15)
    assert ours.leaves_extent(1.9, 2.1) and ours.leaves_extent(3.9, 4.2)
    assert not ours.leaves_extent(2.0, 4.0)
    with c_reader.open(path) as c:
        assert c.extent_m == (2.0, 4.0)
        assert np.array_equal(c.height([-5.0, 1.9, 4.1, 50.0]), height)
        assert not c.slope([-5.0, 1.9, 4.1, 50.0]).any()
        assert c.mean([1.0], [2.5])[0] == ours.road.mean_height(1.0, 2.5)


def test_window_means_are_the_exact_integral(c_reader, tmp_path):
    rng = np.random.default_rng(4)
    distances = np.cumsum(rng.uniform(0.01, 0.1, 60))
    heights = rng.normal(0.0, 0.01, 60)
    road = ProfileRoad(distances, heights)
    lo = rng.uniform(distances[0] - 0.5, distances[-1], 40)
    hi = lo + rng.uniform(0.0, 0.4, 40)
    hi[0] = lo[0]  # a point: the height there
    quad = np.array([integrate.quad(lambda s: float(road.profile(s)[0]), a, b,
                                    points=distances[(distances > a) & (distances < b)],
                                    limit=200)[0] / (b - a) if b > a else
                     float(road.profile(a)[0]) for a, b in zip(lo, hi)])
    assert np.allclose(road.mean_height(lo, hi), quad, rtol=0, atol=1e-13)
    path = write_profile(tmp_path / "means.csv", distances, heights)
    with c_reader.open(path) as c:
        assert np.allclose(c.mean(lo, hi), road.mean_height(lo, hi), rtol=0, atol=1e-15)


# -- refusals ---------------------------------------------------------------------------------

def _crg(tmp_path, name="road.crg", data_format="LDFI", rows=11, nan_at=None, end_u=None):
    z = np.tile(np.linspace(0.0, 0.01, rows)[:, None], (1, 3))
    if nan_at is not None:
        z[nan_at] = np.nan
    data = road_files.crg_bytes(z, 0.1, [-0.5, 0.0, 0.5], data_format)
    if end_u is not None:
        data = re.sub(rb"reference_line_end_u\s*=\s*\S+",
                      f"reference_line_end_u = {end_u}".encode(), data)
    path = tmp_path / name
    path.write_bytes(data)
    return path


def _edit(path: Path, old: bytes, new: bytes) -> Path:
    data = path.read_bytes()
    assert old in data
    path.write_bytes(data.replace(old, new, 1))
    return path


REFUSALS = {
    "missing": (lambda t: t / "nowhere.crg", "cannot be read: No such file or directory"),
    "folder": (lambda t: t, "is a folder, not a road file"),
    "truncated binary": (lambda t: t / "cut.crg",
                         "truncated: the header declares 11 cross sections"),
    "truncated text": (lambda t: t / "cut_text.crg", "truncated: the last cross section has"),
    "text header contradicting its data": (lambda t: t / "short.crg",
                                           "the data hold 10 cross sections"),
    "no data section": (lambda t: t / "nodata.crg", "no data section"),
    "unsupported format": (lambda t: t / "krfi.crg", "data format 'KRFI': supported are KRBI"),
    "no increment": (lambda t: t / "noinc.crg", "no reference_line_increment"),
    "NaN in the track": (lambda t: t / "nan.crg", "no height (NaN) in long section 2 at u = 0.5"),
    "huge dimensions declared": (lambda t: t / "huge.crg", "must make 2 to 10000000 cross"),
    "a huge but consistent count in a small file": (lambda t: t / "claims.crg",
                                                    "truncated: the header declares 9000001"),
    "include files": (lambda t: t / "include.crg", "$ROAD_CRG_FILE (a road in several files)"),
    "scaling modifiers": (lambda t: t / "scale.crg", "modifier scale_length: scaling"),
    "another border mode": (lambda t: t / "border.crg", "border_mode_u = 1: only 2"),
    "a lateral offset off the road": (lambda t: t / "road.crg",
                                      "lateral offset 0.7 m: outside the road's width"),
    "profile: NaN height": (lambda t: t / "nan.csv", "line 3: '1.0, nan': distance and height"),
    "profile: distances not increasing": (lambda t: t / "back.csv",
                                          "line 3: distance 0.5 m after 1 m (line 2)"),
    "profile: three columns": (lambda t: t / "three.csv", "line 1: 3 values in '0 0 0'"),
    "profile: text": (lambda t: t / "text.csv", "line 2: '1, x': not two numbers"),
    "profile: one point": (lambda t: t / "one.csv", "1 points: a road profile needs"),
    "profile: a lateral offset": (lambda t: t / "ok.csv", "a profile file has no width"),
}


def _make_refused(tmp_path: Path) -> None:
    binary = _crg(tmp_path, "cut.crg", "KDBI")
    binary.write_bytes(binary.read_bytes()[:-120])
    five = np.zeros((11, 5))  # five values of 20 characters: two lines a cross section
    text = tmp_path / "cut_text.crg"
    text.write_bytes(road_files.crg_bytes(five, 0.1, np.linspace(-1, 1, 5), "LDFI")
                     .rstrip(b"\n").rsplit(b"\n", 1)[0] + b"\n")
    short = _crg(tmp_path, "short.crg", "LRFI", rows=10, end_u=2.0)
    del short
    _edit(_crg(tmp_path, "nodata.crg"), b"$" * 72, b"*" * 72)
    _edit(_crg(tmp_path, "krfi.crg"), b"#:LDFI", b"#:KRFI")
    _edit(_crg(tmp_path, "noinc.crg"), b"reference_line_increment", b"*reference_line_inc")
    _crg(tmp_path, "nan.crg", "KRBI", nan_at=(5, 1))
    _crg(tmp_path, "huge.crg", "KRBI", end_u=1e9)
    _crg(tmp_path, "claims.crg", "KRBI", end_u=900000.0)
    _edit(_crg(tmp_path, "include.crg"), b"$KD_DEFINITION", b"$ROAD_CRG_FILE\n$\n$KD_DEFINITION")
    _edit(_crg(tmp_path, "scale.crg"), b"$ROAD_CRG_MODS\n$", b"$ROAD_CRG_MODS\nscale_length = 2\n$")
    _edit(_crg(tmp_path, "border.crg"), b"$KD_DEFINITION",
          b"$ROAD_CRG_OPTS\nborder_mode_u = 1\n$\n$KD_DEFINITION")
    _crg(tmp_path, "road.crg")
    (tmp_path / "nan.csv").write_text("0, 0\n0.5, 0.01\n1.0, nan\n")
    (tmp_path / "back.csv").write_text("0 0\n1 0\n0.5 0\n")
    (tmp_path / "three.csv").write_text("0 0 0\n")
    (tmp_path / "text.csv").write_text("0, 0\n1, x\n")
    (tmp_path / "one.csv").write_text("# one\n0 0\n")
    (tmp_path / "ok.csv").write_text("0 0\n1 0\n")


@pytest.mark.parametrize("case", REFUSALS)
def test_a_bad_road_file_is_refused_with_the_same_sentence_in_both_runtimes(tmp_path, c_reader,
                                                                           case):
    folder = tmp_path / "files"
    folder.mkdir()
    _make_refused(folder)
    make, words = REFUSALS[case]
    path = make(folder)
    v = {"a lateral offset off the road": 0.7, "profile: a lateral offset": 0.1}.get(case, 0.0)
    with pytest.raises(RoadFileError) as caught:
        read_road_file(path, v)
    message = str(caught.value)
    assert message.startswith(f"{path}: ") and words in message, message
    with pytest.raises(CRoadFileError) as c_caught:
        c_reader.open(path, v)
    assert str(c_caught.value) == message
    assert c_caught.value.status in (1, 2, 3, 5)


def test_a_damaged_binary_file_is_refused_before_it_allocates(tmp_path, c_reader):
    """A header declaring more data than the file holds is refused from the sizes alone (the
    C reads nothing it has not checked); so is one holding more than it declares."""
    path = _crg(tmp_path, "long.crg", "KRBI")
    path.write_bytes(path.read_bytes() + b"\0" * 400)
    with pytest.raises(RoadFileError, match="bytes of data beyond the 11 cross sections"):
        read_road_file(path)
    with pytest.raises(CRoadFileError, match="bytes of data beyond the 11 cross sections"):
        c_reader.open(path)


# -- the roads `tire-fmu road` writes ---------------------------------------------------------

def _cli_json(argv, capsys) -> dict:
    assert main([*argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.mark.parametrize("road_class", ["A", "C", "H"])
def test_an_iso8608_road_file_has_its_class_psd(tmp_path, capsys, road_class):
    """The file's heights, read back, have the class's Gd(n): Welch's estimate (30 segments,
    Hann, no overlap) over the band away from its edges within its chi-squared spread, and
    its mean ratio to Gd(n) within 3 %."""
    path = tmp_path / f"iso_{road_class}.csv"
    data = _cli_json(["road", "iso8608", "--class", road_class, "--length", "1500",
                      "--spacing", "0.05", "--fade-in", "0", "--seed", "3", "--out",
                      str(path)], capsys)
    assert data["gd_n0_m3"] == ISO_8608_GD_N0_M3[road_class]
    z = read_road_file(path).road.heights_m[:-1]
    segments, spacing = 30, 0.05
    n, psd = signal.welch(z, fs=1 / spacing, window="hann", nperseg=z.size // segments,
                          noverlap=0, detrend=False)
    spectrum = Iso8608Spectrum(road_class)
    dn = n[1] - n[0]
    inside = (n > spectrum.n_min_cycles_per_m + 3 * dn) & (n < 0.9 * spectrum.n_max_cycles_per_m)
    ratio = psd[inside] / spectrum.psd_m3(n[inside])
    dof = 2 * segments
    low, high = dof / stats.chi2.ppf(0.995, dof), dof / stats.chi2.ppf(0.005, dof)
    assert np.mean((ratio < low) | (ratio > high)) <= 0.01
    assert np.mean(ratio) == pytest.approx(1.0, abs=0.03)


def test_a_cleat_file_has_the_cleats_geometry(tmp_path, capsys):
    """A 20 x 20 mm J2730 cleat after 1 m: the height inside, level road outside, edges one
    spacing long, and the road's integral the cleat's area exactly."""
    path = tmp_path / "cleat.csv"
    _cli_json(["road", "cleat", "--height", "0.02", "--length", "0.02", "--out", str(path),
               "--spacing", "0.001"], capsys)
    road = read_road_file(path).road
    s, z = road.distances_m, road.heights_m
    assert np.allclose(z[(s > 1.0005) & (s < 1.0195)], 0.02, rtol=1e-14, atol=0)
    assert np.all(z[(s < 0.9995) | (s > 1.0205)] == 0.0)
    assert road.integral(s[-1]) == pytest.approx(0.02 * 0.02, rel=1e-12)
    assert road.extent_m == (0.0, pytest.approx(2.02))


@pytest.mark.parametrize("half_angle", [45.0, 60.0, 85.0])
def test_a_triangular_cleat_file_has_its_flanks_crown_and_area(tmp_path, capsys, half_angle):
    path = tmp_path / "triangle.crg"
    data = _cli_json(["road", "triangle", "--height", "0.03", "--half-angle", str(half_angle),
                      "--crown-radius", "0.002", "--out", str(path), "--lead-in", "0.5"],
                     capsys)
    shape = TriangularCleat(0.03, half_angle, 0.002)
    alpha = np.radians(half_angle)
    apex = 0.03 + 0.002 * (1 / np.sin(alpha) - 1)
    assert shape.length_m == pytest.approx(2 * apex * np.tan(alpha))
    # the area: the sharp triangle less the part the crown cuts off
    cut = 0.002**2 * (1 / np.tan(alpha) - (np.pi / 2 - alpha))
    assert shape.integral(shape.length_m) == pytest.approx(apex**2 * np.tan(alpha) - cut,
                                                           rel=1e-12)
    road = read_road_file(path).road
    assert road.integral(road.extent_m[1]) == pytest.approx(shape.integral(shape.length_m),
                                                            rel=1e-12)
    assert data["height_max_m"] == pytest.approx(0.03, abs=2e-5)
    flank = (road.distances_m > 0.5 + 0.002) & (road.distances_m < 0.5 + 0.3 * shape.length_m)
    assert np.allclose(np.diff(road.heights_m[flank]) / np.diff(road.distances_m[flank]),
                       1 / np.tan(alpha), rtol=1e-9)


def test_a_step_file_rises_to_its_height_and_stays(tmp_path, capsys):
    path = tmp_path / "step.crg"
    _cli_json(["road", "step", "--height", "0.05", "--out", str(path)], capsys)
    road = read_road_file(path).road
    assert road.heights_m[0] == 0.0 and road.heights_m[-1] == pytest.approx(0.05, rel=1e-13)
    assert road.profile(100.0)[0] == road.heights_m[-1]  # beyond its end: level at the top
    step = StepCleat(0.05, 0.002)
    s = road.distances_m[-1]
    assert road.integral(s) == pytest.approx(step.integral(s - 1.0), rel=1e-12)


def test_a_pothole_file_goes_down(tmp_path, capsys):
    path = tmp_path / "pothole.csv"
    data = _cli_json(["road", "pothole", "--depth", "0.04", "--length", "0.3", "--out",
                      str(path)], capsys)
    assert data["height_min_m"] == pytest.approx(-0.04, rel=1e-13)
    assert data["height_max_m"] == 0.0


def test_road_show_reads_a_file_back_and_plots_it(tmp_path, capsys):
    path = tmp_path / "cleat.crg"
    _cli_json(["road", "cleat", "--out", str(path)], capsys)
    figure = tmp_path / "profile.png"
    data = _cli_json(["road", "show", str(path), "--lateral-offset", "0.25", "--plot",
                      str(figure)], capsys)
    assert data["format"] == "KDBI" and data["lateral_offset_m"] == 0.25
    assert data["extent_m"] == [0.0, pytest.approx(2.02)]
    assert figure.stat().st_size > 10_000


@pytest.mark.parametrize("argv, words", [
    (["road", "cleat", "--height", "nan", "--length", "-1", "--out", "x.crg"],
     ["--height = nan: must be a finite number", "--length = -1 m"]),
    (["road", "triangle", "--half-angle", "95", "--out", "x.crg"], ["--half-angle = 95 deg"]),
    (["road", "iso8608", "--n-min", "3", "--n-max", "2", "--out", "x.crg"],
     ["--n-max = 2 cycles/m: must be above --n-min"]),
    (["road", "cleat", "--out", "/no/such/folder/x.crg"], ["folder '/no/such/folder'"]),
    (["road", "show", "/no/such/road.crg"], ["cannot be read"]),
])
def test_bad_flags_are_one_line(argv, words, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    for word in words:
        assert word in err


# -- one set of limits -----------------------------------------------------------------------

def test_the_c_limits_are_the_pythons():
    header = (Path(str(c_folder())) / "road_file.h").read_text()
    defines = dict(re.findall(r"#define (ROAD_FILE_\w+) ([0-9.eE+-]+)L?", header))
    pairs = {"MAX_BYTES": road_files.MAX_ROAD_FILE_BYTES,
             "MAX_HEADER_BYTES": road_files.MAX_CRG_HEADER_BYTES,
             "MAX_KNOTS": road_files.MAX_CROSS_SECTIONS,
             "MAX_CHANNELS": road_files.MAX_CRG_CHANNELS,
             "MAX_ABS_HEIGHT_M": road_files.MAX_ABS_HEIGHT_M,
             "MAX_ABS_DISTANCE_M": road_files.MAX_ABS_DISTANCE_M,
             "MIN_INCREMENT_M": road_files.MIN_INCREMENT_M,
             "V_BORDER_M": road_files.V_BORDER_TOLERANCE_M,
             "HEADER_TOLERANCE_M": road_files.HEADER_TOLERANCE_M,
             "MAX_PROFILE_BYTES": road_files.MAX_PROFILE_FILE_BYTES}
    for name, value in pairs.items():
        assert float(defines[f"ROAD_FILE_{name}"]) == value, name
    from tire_fmu.cli import road

    assert (road.MAX_OBSTACLE_SIZE_M, road.MAX_OBSTACLE_LENGTH_M, road.MAX_CROWN_RADIUS_M) \
        == (MAX_OBSTACLE_SIZE_M, MAX_OBSTACLE_LENGTH_M, MAX_CROWN_RADIUS_M)
    assert road.FORMATS == FORMATS


def test_both_native_fmus_compile_the_reader():
    for kind in (RADIAL, INPLANE):
        assert "road_file.c" in kind.c_sources and "road_file.h" in kind.c_headers
