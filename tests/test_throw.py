"""The one-parameter throw spans the source's gentle release and the paper's vigorous drop."""

from __future__ import annotations

import pytest

from diefab.core.errors import PhysicsError
from diefab.physics.simulate import PhysicsSettings
from diefab.physics.throw import GENTLE, HARD, MAX_VIGOR, VIGOROUS, throw_settings


def test_vigor_one_is_the_default_throw_and_zero_the_gentle_release():
    assert throw_settings(1.0) == PhysicsSettings()
    gentle = throw_settings(0)
    assert (gentle.restitution, gentle.friction, gentle.drop_height) == (0.0, 0.1, GENTLE["drop_height"])
    assert gentle.angular_velocity == (0.0, 0.0) and gentle.height_jitter == 0.0


def test_every_setting_moves_linearly_and_the_rest_of_the_base_is_kept():
    base = PhysicsSettings(rolling_friction=0.01, capture_energy=0.2)
    half = throw_settings(0.5, base)
    assert half.friction == pytest.approx((GENTLE["friction"] + VIGOROUS["friction"]) / 2)
    assert half.drop_height == pytest.approx((GENTLE["drop_height"] + VIGOROUS["drop_height"]) / 2)
    assert half.angular_velocity[1] == pytest.approx(VIGOROUS["spin"] / 2)
    assert (half.rolling_friction, half.capture_energy) == (0.01, 0.2)
    heights = [throw_settings(v).drop_height for v in (0, 0.25, 0.5, 0.75, 1, 1.5, 2)]
    assert heights == sorted(heights)


def test_past_one_the_throw_moves_linearly_on_to_the_hard_end():
    hard = throw_settings(2.0)
    assert (hard.restitution, hard.friction, hard.drop_height, hard.height_jitter, hard.angular_velocity) == (
        HARD["restitution"],
        HARD["friction"],
        HARD["drop_height"],
        HARD["height_jitter"],
        (0.0, HARD["spin"]),
    )
    s = throw_settings(1.25)
    for key in ("restitution", "drop_height", "friction"):
        assert getattr(s, key) == pytest.approx(0.75 * VIGOROUS[key] + 0.25 * HARD[key])
    # the two pieces meet at the default throw
    assert throw_settings(1.0 + 1e-9).drop_height == pytest.approx(throw_settings(1.0 - 1e-9).drop_height)
    # and past the hard end the same line goes on: as far past HARD at 3 as HARD is past the default
    top = throw_settings(MAX_VIGOR)
    for key in ("restitution", "drop_height", "height_jitter"):
        assert getattr(top, key) == pytest.approx(2 * HARD[key] - VIGOROUS[key])
    assert top.angular_velocity[1] == pytest.approx(2 * HARD["spin"] - VIGOROUS["spin"]) and top.restitution < 1


@pytest.mark.parametrize("bad", [-0.1, 3.5, float("inf"), float("nan"), "1", True, None])
def test_vigor_outside_its_range_is_refused(bad):
    with pytest.raises(PhysicsError, match="vigor"):
        throw_settings(bad)
