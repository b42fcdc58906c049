"""The net's search: trees laid flat, and one layout shared by the net's pages and the paper die's tabs."""

from __future__ import annotations

import numpy as np
import pytest

from diefab import load_design
from diefab.geometry.trees import all_trees, heuristic_trees
from diefab.made.flatten import face_frames, hinges_of, homogeneous, place_trees, rooted, tree_parents
from diefab.made.unfold import net_layout, net_tab_shapes, tab_shapes, unfold

SHAPE_TOL = 1e-9


@pytest.mark.parametrize("name", ["d6", "d8", "fudge-gem"])
def test_tree_parents_match_a_breadth_first_walk_of_every_tree(name):
    poly = load_design(name).polyhedron
    trees = all_trees(poly)
    parent, hinge = tree_parents(poly, trees)
    for t, tree in enumerate(trees):
        p, h, order = rooted(poly, tree)
        assert np.array_equal(parent[t], p) and np.array_equal(hinge[t], h)
        assert sorted(order) == list(range(len(poly.faces)))


def test_tree_parents_of_heuristic_trees_of_a_large_die():
    poly = load_design("d20").polyhedron
    trees = heuristic_trees(poly, 40, np.random.default_rng(1))
    parent, hinge = tree_parents(poly, trees)
    for t, tree in enumerate(trees):
        p, h, _ = rooted(poly, tree)
        assert np.array_equal(parent[t], p) and np.array_equal(hinge[t], h)


def test_hinged_faces_keep_their_shared_edge():
    """Laid out along any tree, a face and its parent meet along their common edge."""
    poly = load_design("fudge-gem").polyhedron
    local = face_frames(poly, 20.0)
    trees = all_trees(poly)[::97]
    world, parent = place_trees(trees, poly, hinges_of(poly, local), homogeneous(local))
    for t in range(len(trees)):
        for f, g in enumerate(parent[t]):
            if f == g:
                continue
            shared = set(poly.faces[f].tolist()) & set(poly.faces[g].tolist())
            for v in shared:
                i = poly.faces[f].tolist().index(v)
                j = poly.faces[g].tolist().index(v)
                assert np.allclose(world[t, f, i], world[t, g, j], atol=1e-9)


@pytest.mark.parametrize("name", ["d6", "fudge-gem", "d20"])
def test_mass_model_tabs_are_the_nets_tabs(name):
    """The paper body's tabs and the net's tabs come from one layout: same edges, sides and shapes."""
    design = load_design(name)
    poly, scale = design.polyhedron, design.mm_per_unit
    body = {(t.a, t.b): t for t in tab_shapes(poly, scale, 5.0)}
    net = {(t.a, t.b): t for t in net_tab_shapes(unfold(poly, scale, tab_width=5.0))}
    assert body.keys() == net.keys() and len(body) == len(poly.edges) - len(poly.faces) + 1
    for key, t in body.items():
        u = net[key]
        assert t.glued == u.glued
        assert np.allclose([t.width_mm, t.lean_a, t.lean_b], [u.width_mm, u.lean_a, u.lean_b], rtol=0, atol=SHAPE_TOL)


def test_one_search_serves_the_net_and_the_body():
    design = load_design("d8")
    poly, scale = design.polyhedron, design.mm_per_unit
    from diefab.made.pages import parse_page

    tab_shapes(poly, scale, 5.0)
    layout = net_layout(poly, scale, parse_page("A4").printable, 5.0)
    net = unfold(poly, scale, tab_width=5.0)
    assert layout is net_layout(poly, scale, parse_page("A4").printable, 5.0)
    assert sorted(net.fold_edges.tolist()) == sorted(layout.tree)
    assert net.search == layout.stats and net.search is not layout.stats
