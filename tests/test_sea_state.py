"""Vessel motion from a sea state (issue 16 item 3): a JONSWAP spectrum at the winch.

References: the generated record's own statistics (its variance and scipy.signal.welch's spectral
peak, not the spectrum it was drawn from); the rates against central differences; roll and pitch
against the lever arm applied by hand to the surface elevation.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import welch

from cable_ocp.drive.drive import Drive
from cable_ocp.drive.vessel import top_motion
from cable_ocp.scene.schema import SceneError, load_scene

SEA = {"significant_height": 2.0, "peak_period": 8.0, "components": 200, "seed": 4}


def sea_scene(models_dir, sea=SEA, scene="paper_hill", **heave):
    return load_scene(models_dir / f"{scene}.toml", {"top.heave": {"sea_state": sea, **heave}})


def vertical(scene, t):
    """The winch's vertical displacement (m) over the fixed top's: the sea state alone."""
    return top_motion(scene.top)(t)[0][2] - scene.top.start[2]


@pytest.mark.parametrize(
    "gamma, seed", [(1.0, 4), (3.3, 4), (3.3, 9), (7.0, 0)], ids=["PM", "3.3", "3.3-seed9", "7"]
)
def test_a_long_record_has_the_sea_states_hs_and_tp(models_dir, gamma, seed, validation):
    """Three hours at 4 Hz: 4 sqrt(m0) within 2 % of H_s, Welch's peak within 5 % of T_p.

    The peak is checked where the spectrum has one (gamma > 1): the Pierson-Moskowitz spectrum
    (gamma = 1) is within 2 % of its peak over +-5 % of f_p, flatter than the scalloping of any
    periodogram, so its argmax wandered by up to 12 % over three seeds.
    """
    scene = sea_scene(models_dir, {**SEA, "peak_enhancement": gamma, "seed": seed}, "hanging")
    rate = 4.0  # Hz
    t = np.arange(0.0, 3 * 3600.0, 1 / rate)
    z = vertical(scene, t)
    hs = 4 * np.sqrt(np.var(z))
    frequency, density = welch(z, fs=rate, nperseg=8192)
    tp = 1 / frequency[np.argmax(density)]
    hs_error, tp_error = abs(hs / 2.0 - 1), abs(tp / 8.0 - 1)
    validation(f"JONSWAP heave H_s = 2 m, T_p = 8 s, gamma = {gamma}, 200 components, 3 h, "
               f"seed {seed}", "analytic", "the record's variance and Welch spectral peak",
               "H_s = 4 sqrt(m0) error; T_p error", f"{hs_error:.1e}; {tp_error:.1e}",
               "<= 2 %; <= 5 % (gamma > 1)")  # fmt: skip
    assert hs_error <= 0.02
    assert gamma == 1.0 or tp_error <= 0.05


def test_the_rates_are_the_derivatives_and_the_start_is_top_start(models_dir):
    scene = sea_scene(models_dir, scene="hanging")
    motion = top_motion(scene.top)
    t = np.linspace(0.0, 60.0, 301)
    dt = 1e-4
    position, velocity, acceleration = motion(t)
    ahead, behind = motion(t + dt), motion(t - dt)
    np.testing.assert_allclose(velocity, (ahead[0] - behind[0]) / (2 * dt), atol=1e-6)
    np.testing.assert_allclose(acceleration, (ahead[1] - behind[1]) / (2 * dt), atol=1e-6)
    np.testing.assert_array_equal(position[:, 0], scene.top.start)
    assert np.abs(velocity[2]).max() > 0.3  # m/s: the winch does move


def test_a_seed_gives_one_record(models_dir):
    t = np.linspace(0.0, 100.0, 50)
    first = vertical(sea_scene(models_dir, scene="hanging"), t)
    again = vertical(sea_scene(models_dir, scene="hanging"), t)
    other = vertical(sea_scene(models_dir, {**SEA, "seed": 5}, scene="hanging"), t)
    np.testing.assert_array_equal(first, again)
    assert np.abs(first - other).max() > 0.1


def test_roll_and_pitch_move_the_winch_by_its_lever_arm(models_dir):
    """Constant RAOs: the winch at offset o moves by (p o_z, -r o_z, h + r o_y - p o_x)."""
    offset = (-20.0, 6.0, 4.0)
    heave, roll, pitch = 0.8, 0.02, 0.01  # m/m, rad/m, rad/m
    rows = [{"frequency": w, "heave": heave, "roll": roll, "pitch": pitch} for w in (0.1, 5.0)]
    sea = {**SEA, "winch_offset": list(offset), "rao": rows}
    t = np.linspace(0.0, 120.0, 400)
    moved = top_motion(sea_scene(models_dir, sea, scene="hanging").top)(t)[0]
    eta = vertical(sea_scene(models_dir, scene="hanging"), t)  # the surface, less its start
    ox, oy, oz = offset
    expected = np.vstack(
        [pitch * oz * eta, -roll * oz * eta, (heave + roll * oy - pitch * ox) * eta]
    )
    np.testing.assert_allclose(moved, expected, rtol=0, atol=1e-12)


def test_an_rao_phase_lags_the_heave(models_dir):
    """A heave RAO of gain 1 and phase pi is the surface upside down (less its start)."""
    rows = [{"frequency": w, "heave_phase": np.pi} for w in (0.1, 5.0)]
    t = np.linspace(0.0, 80.0, 300)
    flipped = top_motion(sea_scene(models_dir, {**SEA, "rao": rows}, scene="hanging").top)(t)
    upright = top_motion(sea_scene(models_dir, scene="hanging").top)(t)
    np.testing.assert_allclose(flipped[1], -upright[1], atol=1e-12)
    np.testing.assert_allclose(flipped[2], -upright[2], atol=1e-12)


def test_the_sea_state_adds_to_the_tow_and_a_sine(models_dir):
    t = np.linspace(0.0, 210.0, 500)
    tow = load_scene(models_dir / "paper_hill.toml")
    both = sea_scene(models_dir, amplitude=0.5, period=9.0)
    sine = load_scene(
        models_dir / "paper_hill.toml", {"top.heave": {"amplitude": 0.5, "period": 9.0}}
    )
    sea = sea_scene(models_dir)
    for k in range(3):
        alone = top_motion(sea.top)(t)[k] - top_motion(tow.top)(t)[k]
        expected = top_motion(sine.top)(t)[k] + alone
        np.testing.assert_allclose(top_motion(both.top)(t)[k], expected, rtol=0, atol=1e-12)
    assert both.top.has_heave and sea.top.has_heave and not tow.top.has_heave


def test_compensation_pays_out_the_whole_vertical_motion(models_dir):
    """With compensation the winch turns by (z_A(t) - z_A(0)) / r_D, the sea state included."""
    scene = sea_scene(models_dir, amplitude=0.4, compensation=True)
    drive = Drive.from_scene(scene)
    t = np.linspace(0.0, 50.0, 101)
    phi, rate, _ = drive.winch_angle(t)
    z, vz, _ = (part[2] for part in top_motion(scene.top)(t))
    radius = scene.winch.drum_radius
    np.testing.assert_allclose(phi, (z - z[0]) / radius, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rate, vz / radius, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "sea, message",
    [
        ({**SEA, "significant_height": 0.0},
         r"^top\.heave\.sea_state\.significant_height = 0\.0 is out of range: must be > 0 and "
         r"<= 30 \(m\): the highest seas"),
        ({**SEA, "significant_height": 1e50},
         r"^top\.heave\.sea_state\.significant_height = 1e\+50 is out of range: must be > 0 and "
         r"<= 30 \(m\): the highest seas measured have a significant height of about 20 m$"),
        ({**SEA, "significant_height": -1.0}, r"^top\.heave\.sea_state\.significant_height = -1"),
        ({**SEA, "peak_period": 0.0},
         r"^top\.heave\.sea_state\.peak_period = 0\.0 is out of range: must be >= 1 and <= 30 "
         r"\(s\): waves at sea peak between"),
        ({**SEA, "peak_period": 0.05},
         r"^top\.heave\.sea_state\.peak_period = 0\.05 is out of range: must be >= 1 and <= 30 "),
        ({**SEA, "peak_period": 1e10},
         r"^top\.heave\.sea_state\.peak_period = 10000000000\.0 is out of range: must be >= 1 "),
        ({**SEA, "peak_enhancement": 0.5},
         r"^top\.heave\.sea_state\.peak_enhancement = 0\.5 is out of range: must be >= 1"),
        ({**SEA, "components": 0},
         r"^top\.heave\.sea_state\.components = 0 is out of range: must be >= 1"),
        ({**SEA, "components": 2.5}, r"^top\.heave\.sea_state\.components: expected an integer"),
        ({"peak_period": 8.0}, r"^top\.heave\.sea_state\.significant_height: missing required"),
        ({**SEA, "rao": [[0.5, 1.0, 0.0]]},
         r"^top\.heave\.sea_state\.rao\[0\]: expected a table, got list"),
        ({**SEA, "rao": {"frequency": [0.5]}}, r"^top\.heave\.sea_state\.rao: expected a list"),
        ({**SEA, "rao": [{"heave": 1.0}]},
         r"^top\.heave\.sea_state\.rao\[0\]\.frequency: missing required key"),
        ({**SEA, "rao": [{"frequency": 0.5}, {"frequency": 0.5}]},
         r"^top\.heave\.sea_state\.rao\[1\]\.frequency = 0\.5 is out of range: must be > "
         r"top\.heave\.sea_state\.rao\[0\]\.frequency = 0\.5"),
        ({**SEA, "rao": [{"frequency": 0.5, "roll": -0.1}]},
         r"^top\.heave\.sea_state\.rao\[0\]\.roll = -0\.1 is out of range: must be >= 0"),
        ({**SEA, "rao": [{"frequency": 0.5, "sway": 0.1}]},
         r"^top\.heave\.sea_state\.rao\[0\]\.sway: unknown key"),
        ({**SEA, "winch_offset": [1.0, 2.0]},
         r"^top\.heave\.sea_state\.winch_offset: expected 3 numbers"),
    ],
    ids=["hs-zero", "hs-huge", "hs-negative", "tp-zero", "tp-short", "tp-huge", "gamma-below-1",
         "no-components", "components-float", "no-hs", "rao-row-list", "rao-columns",
         "rao-no-frequency", "rao-not-increasing", "rao-negative-gain", "rao-unknown",
         "offset-shape"],
)  # fmt: skip
def test_bad_sea_states_are_one_line_errors(models_dir, sea, message):
    with pytest.raises(SceneError, match=message) as caught:
        sea_scene(models_dir, sea)
    assert "\n" not in str(caught.value)


def test_a_heave_needs_an_amplitude_or_a_sea_state(models_dir):
    with pytest.raises(SceneError, match=r"^top\.heave\.amplitude: missing required key \(or"):
        load_scene(models_dir / "hanging.toml", {"top.heave": {"period": 8.0}})


def test_the_readmes_survey_tables_load(tmp_path):
    """The TOML example of the README's scene section is a valid scene."""
    readme = (Path(__file__).resolve().parent.parent / "README.md").read_text(encoding="utf-8")
    example = next(b for b in re.findall(r"```toml\n(.*?)```", readme, re.S) if "sea_state" in b)
    path = tmp_path / "survey_tables.toml"
    path.write_text("[model]\n[top]\n[numerics]\n" + example, encoding="utf-8")
    scene = load_scene(path)
    assert len(scene.environment.current_profile) == 3
    sea = scene.top.heave.sea_state
    assert (sea.significant_height, sea.peak_period, len(sea.rao)) == (2.0, 8.0, 2)
    assert scene.top.has_heave and top_motion(scene.top)(np.array([0.0, 5.0]))[0].shape == (3, 2)
