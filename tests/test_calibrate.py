"""Physics profiles and calibration of the physics to real rolls."""

from __future__ import annotations

import json

import pytest

from diefab.errors import PhysicsError
from diefab.physics import PhysicsSettings, load_profile, profile_to_toml

# ----------------------------------------------------------------------
# physics profiles


def test_profile_round_trips(tmp_path):
    settings = PhysicsSettings(restitution=0.45, friction=0.6, angular_velocity=(0.0, 22.5), drop_height=3.0)
    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(settings, name="x", calibration={"deviance": 1.5}, comment="hello"))
    assert load_profile(path) == settings


def test_profile_lies_between_design_and_options(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("[physics]\nrestitution = 0.5\n")
    s = load_profile(path, base={"restitution": 0.1, "friction": 0.3}, friction=None, drop_height=4.0)
    assert (s.restitution, s.friction, s.drop_height) == (0.5, 0.3, 4.0)


@pytest.mark.parametrize(
    "text, words",
    [
        ("[physics]\nrestitution = 2\n", "restitution=2.0"),
        ("[physics]\nspin = 2\n", "unknown physics setting 'spin'"),
        ("foo = 1\n[physics]\n", "unknown key 'foo'"),
        ("physics = 3\n", "[physics] table"),
        ("[physics\n", "malformed TOML"),
        ('[physics]\nangular_velocity = "fast"\n', "angular_velocity"),
    ],
)
def test_bad_profile_is_named(tmp_path, text, words):
    path = tmp_path / "p.toml"
    path.write_text(text)
    with pytest.raises(PhysicsError, match=None) as info:
        load_profile(path)
    assert words in str(info.value) and str(path) in str(info.value)


def test_missing_profile(tmp_path):
    with pytest.raises(PhysicsError, match="does not exist"):
        load_profile(tmp_path / "nope.toml")
    with pytest.raises(PhysicsError, match="unknown physics profile"):
        load_profile("no-such-profile")


@pytest.mark.parametrize("command", [["validate", "d6", "--sims", "10", "--workers", "1"], ["optimize", "fudge-gem"]])
def test_cli_bad_profile_is_one_line_exit_2(tmp_path, bad, monkeypatch, command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "p.toml").write_text("[physics]\nfriction = -1\n")
    assert "friction" in bad(*command, "--physics", "p.toml")


def test_cli_validate_uses_profile_then_options(tmp_path, run):
    path = tmp_path / "p.toml"
    path.write_text(profile_to_toml(PhysicsSettings(restitution=0.5, angular_velocity=(0.0, 20.0))))
    code, out, err = run("validate", "d6", "--sims", "20", "--workers", "1", "--physics", path, "--friction", "0.5",
                         "--json")  # fmt: skip
    assert code == 0, err
    settings = json.loads(out)["settings"]
    assert (settings["restitution"], settings["friction"], settings["angular_velocity"]) == (0.5, 0.5, [0.0, 20.0])
