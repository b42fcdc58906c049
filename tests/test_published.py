"""Published real rolls: the square cuboids' table reads into dice of the stated geometry and counts."""

from __future__ import annotations

import numpy as np
import pytest

from diefab.search.published import published_source, square_cuboid, square_cuboid_dice


def test_every_published_row_gives_a_die_with_its_rolls_and_its_fraction():
    dice = square_cuboid_dice()
    assert len(dice) == 15
    for d in dice:
        ratio = float(d.name.split("-")[1])
        assert d.design.support == [0, 1]
        assert round(d.counts[1] / d.n, 3) == pytest.approx(_published(ratio))
    assert sum(d.n for d in dice) == 9329  # the table's N column


def _published(ratio: float) -> float:
    import json
    from importlib import resources

    table = json.loads(resources.files("diefab").joinpath("data", "published", "square-cuboids.json").read_text())
    (row,) = [r for r in table["table"] if abs(r["x_over_y"] - ratio) < 1e-9]
    return row["p_square"]


@pytest.mark.parametrize("ratio", [0.47, 1.0, 2.65])
def test_square_cuboid_geometry(ratio):
    d = square_cuboid(ratio)
    poly = d.polyhedron
    extent = np.ptp(poly.vertices, axis=0)
    assert extent.max() == pytest.approx(2.0)
    assert extent[2] / extent[0] == pytest.approx(ratio) and extent[0] == pytest.approx(extent[1])
    square = [k for k, n in enumerate(poly.names) if d.values[n] == 1]
    assert len(square) == 2 and np.allclose(np.abs(poly.normals[square, 2]), 1)
    assert poly.volume == pytest.approx(np.prod(extent))


def test_the_table_names_its_source():
    assert "Mathematical Gazette" in published_source("square-cuboids")


def test_the_shipped_printed_dice_are_the_sources_designs():
    """Each printed die's quasi-static prediction reproduces the source's own quasi-static column.

    The geometry was identified by that match; a die read with the wrong
    hull, centre of mass or outcome labels would miss it by far more.
    """
    from diefab.models.probabilities import value_probabilities
    from diefab.search.published import printed_dice

    dice = printed_dice()
    if not dice:
        pytest.skip("no printed dice shipped")
    for d in dice:
        assert d.n == d.counts.sum() > 0 and "ours" in d.reference, d.name
        assert d.tvd(value_probabilities(d.design, "basins"), d.reference["ours"]) < 0.02, d.name


def test_landing_model_scores_agree_with_the_guard_on_dice_with_mirror_groups():
    from diefab.search.fidelity import LANDING_MODELS, landing_model_scores, model_tvd
    from diefab.search.published import printed_dice

    mirrored = [die for die in printed_dice() if die.groups]  # mirror-image outcomes compared up to relabelling
    assert mirrored
    for die in mirrored:
        scores = landing_model_scores(die)
        assert set(scores) == set(LANDING_MODELS) and sum(s["to_trust"] for s in scores.values()) == 1
        for model, s in scores.items():
            assert s["tvd"] == pytest.approx(model_tvd(die, model))
            assert sum(s["predicted"]) == pytest.approx(1.0) and 0 < s["expected_tvd"] < 0.1


def test_every_coin_of_the_table_gives_its_flips_and_its_edge_share():
    import json
    from importlib import resources

    from diefab.search.published import thick_coin_dice

    table = json.loads(resources.files("diefab").joinpath("data", "published", "thick-coins.json").read_text())
    dice = thick_coin_dice()
    assert len(dice) == len(table["table"]) == 2 and "Stand-up Maths" in published_source("thick-coins")
    for d, row in zip(dice, table["table"]):
        assert d.design.support == [0, 1] and d.n == row["flips"] and d.counts[1] / d.n == pytest.approx(row["edge"])


@pytest.mark.parametrize(("ratio", "sides"), [(0.3535, 16), (0.577, 128)])
def test_thick_coin_geometry(ratio, sides):
    from diefab.search.published import thick_coin

    d = thick_coin(ratio, sides=sides)
    poly = d.polyhedron
    assert len(poly.faces) == sides + 2
    z = poly.vertices[:, 2]
    assert np.ptp(z) / 2 == pytest.approx(ratio)  # thickness over the diameter 2
    axial = np.isclose(np.abs(poly.normals[:, 2]), 1)
    assert [d.values[n] for n, a in zip(poly.names, axial) if a] == [0, 0]
    assert all(d.values[n] == 1 for n, a in zip(poly.names, axial) if not a)
    # every side is tangent to the unit circle, so the prism's volume is the polygon's area times the thickness
    centre = poly.vertices.mean(axis=0)
    sides_at = [np.dot(poly.normals[k], poly.vertices[poly.faces[k][0]] - centre) for k in np.flatnonzero(~axial)]
    assert np.allclose(sides_at, 1.0)
    assert poly.volume == pytest.approx(sides * np.tan(np.pi / sides) * 2 * ratio)
