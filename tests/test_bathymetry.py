"""A seabed from a bathymetry grid, and the hard minimum clearance (issue 16, items 1 and 4).

References: the analytic Gaussian hill (eq. 40) that a grid samples, with the bound of cubic
spline interpolation, (5/384) h^4 max|f''''| per axis; the relative seabed of the paper's scenes,
whose Omega the same hill on a grid must reproduce; the trajectory's own e(t) for the clearance.
"""

from __future__ import annotations

import os
import warnings

import casadi as ca
import numpy as np
import pytest
import xarray as xr

from cable_ocp.control.verification import CLEARANCE_TOLERANCE, verify_profile
from cable_ocp.drive.controls import KnotSpline
from cable_ocp.scene.schema import Hill, SceneError, Seabed, SeabedGrid, load_scene
from cable_ocp.simulation.run import simulate
from cable_ocp.simulation.seabed import (
    OffGridError,
    clearance,
    clearance_error,
    clearance_margin,
    clearance_reference,
    seabed_height,
)
from cable_ocp.studies.survey_grid import survey_grid

HILL = Hill(height=15.0, x0=70.0, y0=20.0, width_x=20.0, width_y=20.0)  # paper_hill's
SPACING = 2.0  # m
LEVEL = -305.0  # m, the flat seabed of the sampled grid


def write_grid(path, x, y, z, **attributes):
    """A netCDF grid file of ``z`` (nx, ny) over ``x``, ``y`` (m)."""
    metres = {"units": "m"}
    data = xr.Dataset(
        {"elevation": (("x", "y"), z, {**metres, **attributes})},
        coords={"x": ("x", x, metres), "y": ("y", y, metres)},
    )
    data.to_netcdf(path)
    return path


def hill_grid(path, level=LEVEL, spacing=SPACING, x=(-40.0, 260.0), y=(-40.0, 100.0)):
    """paper_hill's hill sampled on a grid ``spacing`` apart, on a flat seabed at ``level``."""
    xs = np.arange(x[0], x[1] + spacing / 2, spacing)
    ys = np.arange(y[0], y[1] + spacing / 2, spacing)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    return write_grid(path, xs, ys, level + seabed_height([HILL], X, Y))


def interpolation_bound(spacing: float) -> float:
    """(5/384) h^4 (max|d^4z/dx^4| + max|d^4z/dy^4|) of the hill: d^4/du^4 exp(-u^2) <= 12."""
    fourth = HILL.height * 12 * (1 / HILL.width_x**4 + 1 / HILL.width_y**4)
    return 5 / 384 * spacing**4 * fourth


@pytest.fixture(scope="module")
def hill_file(tmp_path_factory):
    return hill_grid(tmp_path_factory.mktemp("grid") / "hill.nc")


def _grid(path) -> SeabedGrid:
    return SeabedGrid(file=str(path))


@pytest.fixture(scope="module")
def gridded(hill_file):
    return Seabed(grid=_grid(hill_file))


def test_a_sampled_hill_reproduces_the_analytic_height_within_the_spline_bound(gridded, validation):
    """Max error over 20 000 random points 9.4e-5 m at h = 2 m; the bound is 4.7e-4 m."""
    rng = np.random.default_rng(3)
    x, y = rng.uniform(-30, 250, 20_000), rng.uniform(-30, 90, 20_000)
    error = seabed_height(gridded, x, y) - (LEVEL + seabed_height([HILL], x, y))
    bound = interpolation_bound(SPACING)
    validation("paper_hill's hill on a 2 m bathymetry grid", "analytic", "Gaussian hill eq. 40",
               "max |z_grid - z_hill| (20 000 points)", f"{np.abs(error).max():.2g} m",
               f"< (5/384) h^4 max|d4z| = {bound:.2g} m and < 1e-4 m")  # fmt: skip
    assert bound == pytest.approx(4.69e-4, rel=1e-2)
    assert np.abs(error).max() < bound
    assert np.abs(error).max() < 1e-4


def test_the_grid_is_the_same_surface_in_numpy_sx_and_mx_with_exact_derivatives(gridded):
    """SX and MX give the numpy heights; the gradient is the spline's (central differences)."""
    points = np.array([[10.0, 3.0], [70.0, 20.0], [123.4, 55.5], [-40.0, 100.0]])
    for kind in (ca.SX, ca.MX):
        p = kind.sym("p", 2)
        z = seabed_height(gridded, p[0], p[1])
        f = ca.Function("z", [p], [z, ca.gradient(z, p)])
        for point in points:
            value, gradient = f(point)
            assert float(value) == pytest.approx(seabed_height(gridded, *point), abs=1e-12)
            if -40 < point[0] < 260 and -40 < point[1] < 100:
                h = 1e-4
                fd = [
                    (seabed_height(gridded, *(point + d)) - seabed_height(gridded, *(point - d)))
                    / (2 * h)
                    for d in (np.array([h, 0]), np.array([0, h]))
                ]
                np.testing.assert_allclose(np.array(gradient).ravel(), fd, atol=1e-7)
    # A symbolic point off the grid is held at the edge (defined for a solver), not 0
    p = ca.SX.sym("p", 2)
    outside = ca.Function("z", [p], [seabed_height(gridded, p[0], p[1])])
    assert float(outside([400.0, 20.0])) == pytest.approx(seabed_height(gridded, 260.0, 20.0))


def test_a_numeric_point_off_the_grid_names_the_file_and_the_point(gridded, hill_file):
    with pytest.raises(OffGridError, match=r"\(x, y\) = \(300, 5\) m is off") as info:
        seabed_height(gridded, np.array([0.0, 300.0]), np.array([0.0, 5.0]))
    assert str(hill_file) in str(info.value)


def test_a_seabed_without_a_grid_is_bit_identical_to_its_hills():
    """The paper scenes' e(t) and Omega: the section and its hills give the same bits."""
    rng = np.random.default_rng(1)
    end = np.column_stack(
        [rng.uniform(0, 140, 200), rng.uniform(-10, 40, 200), rng.uniform(-300, -280, 200)]
    )
    seabed = Seabed(hills=(HILL,))
    np.testing.assert_array_equal(clearance_error(seabed, end), clearance_error((HILL,), end))
    assert clearance_reference(seabed, end[0]) == clearance_reference((HILL,), end[0])


def test_absolute_seabed_error_is_against_the_target_from_the_start(gridded):
    """e = z_E - z_sb - delta, also at t = 0; the clearance is delta + e in both kinds."""
    end = np.array([[0.0, 0.0, -300.5], [70.0, 20.0, -285.0], [100.0, 30.0, -290.0]])
    expected = end[:, 2] - seabed_height(gridded, end[:, 0], end[:, 1]) - 5.0
    np.testing.assert_allclose(clearance_error(gridded, end), expected, rtol=0, atol=1e-12)
    hill_at_start = seabed_height([HILL], 0.0, 0.0)  # 2.6e-5 m
    assert clearance_error(gridded, end)[0] == pytest.approx(-0.5 - hill_at_start, abs=1e-6)
    for seabed in (gridded, Seabed(hills=(HILL,))):
        ref = clearance_reference(seabed, end[0])
        np.testing.assert_allclose(
            clearance(seabed, end, ref), 5.0 + clearance_error(seabed, end), atol=1e-12
        )


def test_clearance_margin_is_the_same_numerically_and_symbolically(hill_file):
    seabed = Seabed(grid=_grid(hill_file), hills=(HILL,), minimum_clearance=2.0)
    end = np.array([[50.0, 10.0, -280.0], [90.0, 25.0, -276.0]])
    numeric = clearance_margin(seabed, end, 5.0)
    expected = end[:, 2] - seabed_height(seabed, end[:, 0], end[:, 1]) - 2.0
    np.testing.assert_allclose(numeric, expected, rtol=0, atol=1e-12)
    x = ca.SX.sym("x", 6)  # a state-like column: its first three entries are the end
    r = ca.SX.sym("r")
    f = ca.Function("margin", [x, r], [clearance_margin(seabed, x, r)])
    for row, value in zip(end, numeric, strict=True):
        assert float(f(np.r_[row, 0, 0, 0], 5.0)) == pytest.approx(value, abs=1e-12)
    with pytest.raises(ValueError, match="seabed.minimum_clearance is not set"):
        clearance_margin(Seabed(), end, 5.0)


@pytest.fixture(scope="module")
def paper_hill(models_dir):
    return load_scene(models_dir / "paper_hill.toml")


def test_paper_hill_on_a_grid_has_the_locked_omega_of_the_analytic_hill(
    paper_hill, tmp_path, validation
):
    """The hill replaced by its grid (h = 2 m) on the flat level delta under the end's start.

    Measured: Omega 4.2761963 m both, differing by 2.9e-6 m; e(t) by at most 4.9e-5 m.
    """
    analytic = simulate(paper_hill, compiled=True)
    start = analytic.end[0]
    level = start[2] - 5.0 - seabed_height([HILL], start[0], start[1])
    grid = hill_grid(tmp_path / "hill.nc", level=level)
    scene = paper_hill.updated({"seabed.hills": [], "seabed.grid": {"file": str(grid)}})
    on_grid = simulate(scene, compiled=True)
    difference = abs(on_grid.omega - analytic.omega)
    validation("paper_hill locked, its hill as a 2 m grid (absolute seabed)", "analytic",
               "the analytic hill (relative seabed)", "|Omega difference|",
               f"{difference:.2g} m (Omega {analytic.omega:.4f} m)",
               "< 1e-5 m (asked: 1 mm)")  # fmt: skip
    assert abs(on_grid.omega - analytic.omega) < 1e-5  # far inside the 1 mm asked for
    assert np.abs(on_grid.clearance_error - analytic.clearance_error).max() < 1e-4


def test_an_end_leaving_the_grid_stops_the_run_naming_the_file_time_and_point(paper_hill, tmp_path):
    grid = hill_grid(tmp_path / "small.nc", x=(-40.0, 40.0), y=(-40.0, 40.0), spacing=4.0)
    scene = paper_hill.updated(
        {"seabed.hills": [], "seabed.grid": {"file": str(grid)}, "numerics.duration": 100.0}
    )
    with pytest.raises(OffGridError, match=r"leaves the bathymetry grid of .*small\.nc at t = "):
        simulate(scene, compiled=True)


def test_an_end_that_starts_under_the_seabed_is_refused_before_integrating(paper_hill, tmp_path):
    grid = hill_grid(tmp_path / "shallow.nc", level=-290.0, spacing=10.0)
    scene = paper_hill.updated({"seabed.hills": [], "seabed.grid": {"file": str(grid)}})
    with pytest.raises(OffGridError, match=r"the end starts 10 m under the seabed"):
        simulate(scene, compiled=True)


def test_optimize_refuses_an_end_that_starts_under_the_seabed_before_solving(
    paper_hill, tmp_path, monkeypatch
):
    """The API refuses it at entry (OffGridError, bad input), as simulate does: no solve starts."""
    from cable_ocp.control import optimization

    def forbidden(*args, **kwargs):
        pytest.fail("a start under the seabed must be refused before any solve")

    monkeypatch.setattr(optimization, "solve_verified", forbidden)
    grid = hill_grid(tmp_path / "shallow.nc", level=-294.0, spacing=10.0)
    scene = paper_hill.updated({"seabed.hills": [], "seabed.grid": {"file": str(grid)}})
    with pytest.raises(OffGridError, match=r"seabed.grid: the end starts 6 m under the seabed"):
        optimization.optimize(scene, quiet=True)


# ----------------------------------------------------------------------------------------------
# Bad grid files: one SceneError at load time, naming the field, the file and the point.
X4, Y4 = np.arange(5.0) * 10, np.arange(4.0) * 10


def _netcdf(path, x=X4, y=Y4, z=None, **attributes):
    z = np.full((x.size, y.size), -300.0) if z is None else z
    return write_grid(path, x, y, z, **attributes)


def _csv(path, rows):
    path.write_text("x,y,z\n" + "\n".join(",".join(map(str, r)) for r in rows) + "\n")
    return path


def _full_rows():
    return [(x, y, -300.0) for x in X4 for y in Y4]


def _with_nan(z):
    z = np.full((X4.size, Y4.size), -300.0)
    z[2, 1] = np.nan
    return z


BAD_GRIDS = {
    "nan": (lambda p: _netcdf(p / "g.nc", z=_with_nan(None)), r"elevation is nan at \(x, y\) = "
            r"\(20, 10\) m"),
    "not monotone": (lambda p: _netcdf(p / "g.nc", x=np.array([0.0, 10, 30, 20, 40])),
                     r"coordinate x is not strictly monotone at index 3 \(x = 30 then 20 m\)"),
    "too short": (lambda p: _netcdf(p / "g.nc", y=np.array([0.0, 10, 20]),
                                    z=np.zeros((5, 3))), r"axis y has 3 points"),
    "units": (lambda p: _netcdf(p / "g.nc", units="ft"), r"units 'ft'; expected metres"),
    "variable": (lambda p: xr.Dataset({"depth": (("x", "y"), np.zeros((5, 4)))},
                                      coords={"x": X4, "y": Y4}).to_netcdf(p / "g.nc")
                 or p / "g.nc", r"no variable 'elevation' \(variables: depth\)"),
    "csv nan": (lambda p: _csv(p / "g.csv", [*_full_rows()[:-1], (30.0, 30.0, "nan")]),
                r"row 20 of the data, \(x, y, z\) = \(30, 30, nan\) m, is not finite"),
    "csv missing": (lambda p: _csv(p / "g.csv", _full_rows()[1:]),
                    r"not a regular grid: point \(x, y\) = \(0, 0\) m is missing"),
    "csv twice": (lambda p: _csv(p / "g.csv", [*_full_rows(), (10.0, 20.0, -1.0)]),
                  r"grid point \(x, y\) = \(10, 20\) m is given twice"),
    "suffix": (lambda p: _csv(p / "g.txt", _full_rows()), r"unknown bathymetry format '.txt'"),
    "not netcdf": (lambda p: (p / "g.nc").write_text("x,y,z\n") and p / "g.nc",
                   r"cannot read as netCDF"),
}  # fmt: skip


@pytest.mark.parametrize("case", BAD_GRIDS, ids=str)
def test_a_bad_grid_file_is_one_scene_error_naming_the_field_file_and_point(
    case, paper_hill, tmp_path
):
    make, message = BAD_GRIDS[case]
    path = make(tmp_path)
    with pytest.raises(SceneError) as info:
        paper_hill.updated({"seabed.grid": {"file": str(path)}})
    text = str(info.value)
    assert text.startswith(f"seabed.grid.file: {path.resolve()}: "), text
    assert "\n" not in text
    assert info.match(message)


def _text(path, text, encoding="utf-8"):
    path.write_text(text, encoding=encoding)
    return path


ROWS = "\n".join(f"{x:g},{y:g},-300" for x in X4 for y in Y4)
CSV_FILES = {
    "empty": (lambda p: _text(p / "g.csv", ""), r"no data rows \(an empty file\)"),
    "header only": (lambda p: _text(p / "g.csv", "x,y,z\n"),
                    r"no data rows \(only a header line\)"),
    "trailing comma": (lambda p: _text(p / "g.csv", "x,y,z\n" + ROWS.replace("\n", ",\n", 3)),
                       r"line 2 has 4 fields \(a trailing comma\?\); expected 3: x, y, z \(m\)$"),
    "two columns": (lambda p: _text(p / "g.csv", "x,y\n0,0\n10,0\n"), r"line 2 has 2 fields"),
    "a word": (lambda p: _text(p / "g.csv", "x,y,z\n" + ROWS.replace("-300", "deep", 1)),
               r"line 2 = '0,0,deep' is not three numbers x, y, z$"),
    "latin-1": (lambda p: _text(p / "g.csv", "x,y,z # \xe9\n" + ROWS, "latin-1"),
                r"not a UTF-8 text file"),
}  # fmt: skip


@pytest.mark.parametrize("case", CSV_FILES, ids=str)
def test_a_bad_csv_grid_is_one_line_without_a_warning(case, paper_hill, tmp_path):
    """Empty, header only, a trailing comma, a short line, a word: one line naming the line."""
    make, message = CSV_FILES[case]
    path = make(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # genfromtxt warned "Empty input file" before its error
        with pytest.raises(SceneError) as info:
            paper_hill.updated({"seabed.grid": {"file": str(path)}})
    text = str(info.value)
    assert text.startswith(f"seabed.grid.file: {path.resolve()}: "), text
    assert "\n" not in text and len(text) < 300
    assert info.match(message)


def test_an_excel_csv_with_a_byte_order_mark_reads_as_its_plain_twin(tmp_path):
    """A UTF-8 byte-order mark before the header (or before the first row) is not a NaN."""
    plain = Seabed(grid=_grid(_text(tmp_path / "plain.csv", "x,y,z\n" + ROWS)))
    for name, text in (("header.csv", "x,y,z\n" + ROWS), ("rows.csv", ROWS)):
        marked = Seabed(grid=_grid(_text(tmp_path / name, "\ufeff" + text)))
        assert seabed_height(marked, 15.0, 12.0) == seabed_height(plain, 15.0, 12.0) == -300.0


def _loop(path):
    (path / "a.nc").symlink_to(path / "b.nc")
    (path / "b.nc").symlink_to(path / "a.nc")
    return path / "a.nc"


def _fifo(path):
    os.mkfifo(path / "g.nc")
    return path / "g.nc"


NOT_FILES = {
    "symlink loop": (_loop, r"a loop of symbolic links$"),
    "folder": (lambda p: (p / "g.nc").mkdir() or p / "g.nc", r"is a folder, not a file$"),
    "fifo": (_fifo, r"not a regular file \(a pipe, socket or device\)$"),
    "missing": (lambda p: p / "g.nc", r"file not found$"),
}


@pytest.mark.parametrize("case", NOT_FILES, ids=str)
def test_a_grid_that_is_not_a_file_says_what_it_is_naming_the_field(case, paper_hill, tmp_path):
    make, message = NOT_FILES[case]
    path = make(tmp_path)
    with pytest.raises(SceneError, match=r"^seabed\.grid\.file = ") as info:
        paper_hill.updated({"seabed.grid": {"file": str(path)}})
    assert "\n" not in str(info.value)
    assert info.match(message)


def test_a_good_csv_grid_is_the_same_surface_as_its_netcdf_twin(tmp_path):
    rows = [(x, y, -300.0 + 0.01 * x * y) for y in Y4[::-1] for x in X4]  # any row order
    z = np.array([[-300.0 + 0.01 * x * y for y in Y4] for x in X4])
    csv = Seabed(grid=_grid(_csv(tmp_path / "g.csv", rows)))
    netcdf = Seabed(grid=_grid(_netcdf(tmp_path / "g.nc", z=z[:, ::-1], y=Y4[::-1])))  # flipped
    x, y = np.array([3.0, 17.5, 40.0]), np.array([0.0, 12.0, 30.0])
    np.testing.assert_allclose(seabed_height(csv, x, y), seabed_height(netcdf, x, y), atol=1e-12)
    np.testing.assert_allclose(seabed_height(csv, x, y), -300.0 + 0.01 * x * y, atol=1e-9)


@pytest.mark.parametrize(
    "value, message",
    [
        (-1.0, r"^seabed\.minimum_clearance = -1\.0 is out of range: must be >= 0 \(m\)$"),
        (6.0, r"^seabed\.minimum_clearance = 6\.0 is out of range: must be <= seabed\.clearance"),
        ("2", r"^seabed\.minimum_clearance: expected a number"),
    ],
)
def test_minimum_clearance_is_validated(paper_hill, value, message):
    with pytest.raises(SceneError, match=message):
        paper_hill.updated({"seabed.minimum_clearance": value})


# ----------------------------------------------------------------------------------------------
# The verification reports the smallest clearance and enforces c_min.


def test_verification_reports_the_smallest_clearance_and_fails_a_profile_under_c_min(
    paper_hill,
):
    """The locked winch runs into paper_hill's hill: the clearance 5 + min e(t) < 2 m fails."""
    scene = paper_hill.updated({"seabed.minimum_clearance": 2.0})
    control = KnotSpline(scene.numerics.duration, scene.winch.knots)
    locked = np.zeros(control.size)
    reference = simulate(scene, compiled=True)
    lowest = 5.0 + reference.clearance_error.min()
    checked = verify_profile(scene, control, locked, compiled=True)
    assert checked.minimum_clearance == pytest.approx(lowest, abs=1e-9)
    assert checked.minimum_clearance_time == reference.time[reference.clearance_error.argmin()]
    assert lowest < 2.0 - CLEARANCE_TOLERANCE
    assert checked.trajectory is None
    assert lowest < 0  # into the hill
    assert checked.reason.startswith(f"the end goes {-lowest:.3g} m into the seabed at t = ")
    assert f"{2.0 - lowest:.3g} m under seabed.minimum_clearance = 2 m" in checked.reason
    # Without c_min the same profile passes, its smallest clearance still reported
    free = verify_profile(paper_hill, control, locked, compiled=True)
    assert free.reason is None and free.minimum_clearance == checked.minimum_clearance


def test_verification_passes_a_profile_that_keeps_c_min(models_dir):
    """paper_flat: the locked end only rises, so its lowest clearance is delta at t = 0."""
    scene = load_scene(
        models_dir / "paper_flat.toml",
        {"seabed.minimum_clearance": 4.5, "numerics.duration": 60.0},
    )
    control = KnotSpline(scene.numerics.duration, scene.winch.knots)
    checked = verify_profile(scene, control, np.zeros(control.size), compiled=True)
    assert checked.reason is None and checked.trajectory is not None
    assert checked.minimum_clearance == pytest.approx(5.0, abs=1e-6)


def test_the_bundled_survey_grid_is_what_its_script_makes(models_dir):
    shipped = xr.open_dataset(models_dir / "data" / "survey_grid.nc")
    made = survey_grid()
    xr.testing.assert_allclose(shipped, made, rtol=0, atol=1e-9)
    assert (models_dir / "data" / "survey_grid.nc").stat().st_size < 300_000


def test_the_bundled_deploy_grid_is_what_its_script_makes(models_dir):
    from cable_ocp.studies.deploy_grid import deploy_grid

    shipped = xr.open_dataset(models_dir / "data" / "deploy_grid.nc")
    xr.testing.assert_allclose(shipped, deploy_grid(), rtol=0, atol=1e-9)
    assert (models_dir / "data" / "deploy_grid.nc").stat().st_size < 300_000


def test_the_survey_figures_draw_the_grid_the_cable_and_c_min(models_dir, tmp_path):
    """plots.survey.seabed_view, cable_shapes and clearance on the bundled survey scene."""
    from cable_ocp import plots
    from cable_ocp.plots import survey

    scene = load_scene(models_dir / "survey.toml", {"numerics.duration": 10.0})
    run = simulate(scene, compiled=True)
    figure = survey.seabed_view(run, scene.seabed, path=tmp_path / "view.png")
    assert figure.axes[0].get_zlim()[1] == pytest.approx(-305.0 + 40.0, abs=2.0)  # the window
    plots.cable_shapes(run, seabed=scene.seabed, path=tmp_path / "shapes.png")
    drawn = plots.clearance(run, 5.0, minimum_clearance=2.0, path=tmp_path / "clearance.png")
    assert any(line.get_label() == "minimum c_min = 2.0 m" for line in drawn.axes[0].lines)
    for name in ("view.png", "shapes.png", "clearance.png"):
        assert (tmp_path / name).stat().st_size > 10_000


@pytest.mark.slow
def test_paper_hill_on_a_grid_has_the_optimum_of_the_analytic_hill(
    paper_hill, tmp_path, validation
):
    """The default optimize on the hill and on its 2 m grid (the transcription differentiates the
    B-spline): the verified optima agree within 1 mm of Omega.

    Measured: 1.30177e-4 m (analytic) against 1.30215e-4 m (grid), 3.8e-8 m apart.
    """
    from cable_ocp.control.optimization import optimize

    analytic = optimize(paper_hill, quiet=True)
    start = simulate(paper_hill, compiled=True).end[0]
    level = start[2] - 5.0 - seabed_height([HILL], start[0], start[1])
    grid = hill_grid(tmp_path / "hill.nc", level=level)
    scene = paper_hill.updated({"seabed.hills": [], "seabed.grid": {"file": str(grid)}})
    on_grid = optimize(scene, quiet=True)
    assert analytic.success and on_grid.success, (analytic.status, on_grid.status)
    difference = abs(on_grid.omega - analytic.omega)
    validation("paper_hill optimum, its hill as a 2 m grid (absolute seabed)", "analytic",
               "the optimum on the analytic hill", "|Omega difference|",
               f"{difference:.2g} m (Omega {analytic.omega:.4g} m, grid {on_grid.omega:.4g} m)",
               "<= 1 mm")  # fmt: skip
    assert difference <= 1e-3
