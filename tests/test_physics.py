"""Physics validator: face detection, reproducibility, backends, sleeping bodies, bad input."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

from diefab.core.errors import PhysicsError
from diefab.dice.design import load_design
from diefab.physics.simulate import PhysicsSettings, RollResult, classify_pose, drop, simulate
from diefab.physics.world import COCKED, World, die_body, fly, initial_conditions, run_batch

pytest.importorskip("pybullet")


@pytest.fixture(scope="module")
def gem():
    return load_design("fudge-gem")


@pytest.fixture(scope="module")
def cube():
    return load_design("d6")


def face_down(design, k: int) -> np.ndarray:
    """A rotation (model -> world) that turns face k's outward normal straight down."""
    n = design.polyhedron.normals[k]
    rot, _ = Rotation.align_vectors([[0.0, 0.0, -1.0]], [n])
    return rot.as_matrix()


def rest_height(design, k: int) -> float:
    poly = design.polyhedron
    center = design.mass_properties().center
    return float(poly.offsets[k] - poly.normals[k] @ center) + PhysicsSettings().collision_margin


# ----------------------------------------------------------------------
# face detection


def test_each_gem_face_placed_down_is_that_face(gem):
    for k, name in enumerate(gem.polyhedron.names):
        rot = face_down(gem, k)
        assert classify_pose(gem, rot) == name
        # placed just above the ground at rest, it stays on that face, fast path and plain loop alike
        height = rest_height(gem, k) + 0.01
        assert drop(gem, rot, height).face == name
        assert drop(gem, rot, height, plain=True).face == name


def test_edge_down_pose_is_cocked(gem):
    poly = gem.polyhedron
    a, b = poly.edge_faces[0]
    mid = poly.normals[a] + poly.normals[b]  # the edge between faces a and b points straight down
    rot, _ = Rotation.align_vectors([[0.0, 0.0, -1.0]], [mid / np.linalg.norm(mid)])
    assert classify_pose(gem, rot.as_matrix()) is None
    # a tilt just inside the tolerance is still the face; beyond it, cocked
    tilt = Rotation.from_rotvec([np.radians(2.0), 0, 0]).as_matrix()
    assert classify_pose(gem, tilt @ face_down(gem, 4)) == "f5"
    assert classify_pose(gem, tilt @ face_down(gem, 4), tolerance=1.0) is None


def test_world_classification_matches_rotation_convention(gem):
    body = die_body(gem.polyhedron, gem.mass_properties())
    for k in range(len(gem.polyhedron.faces)):
        quat = Rotation.from_matrix(face_down(gem, k) @ body.rotation).as_quat()
        from diefab.physics.world import resting_face

        assert resting_face(body.normals, quat, 3.0) == k
    assert np.isclose(np.linalg.det(body.rotation), 1.0)
    assert np.allclose(body.vertices.mean(axis=0) @ np.zeros(3), 0.0)


def test_free_flight_matches_the_engine(gem):
    """The free-fall shortcut lands where stepping the engine would (centre of mass exactly)."""
    settings = PhysicsSettings()
    body = die_body(gem.polyhedron, gem.mass_properties())
    states = initial_conditions(5, 0, 3, settings)
    flown, skipped = fly(states, body, settings)
    assert np.all(skipped > 100) and np.all(skipped % 4 == 0)
    assert np.all(flown[:, 2] - body.radius >= 0.25 - 1e-9)
    world = World(body, settings, slots=1)
    try:
        for state, after, k in zip(states, flown, skipped):
            world.place(0, state)
            world.step(int(k))
            pos, quat, lin, ang = world.state(0)
            assert np.allclose(pos, after[:3], atol=1e-9)
            assert np.allclose(lin, after[7:10], atol=1e-9)
            same = abs(np.dot(quat, after[3:7]))  # q and -q are one orientation
            assert same > 1 - 1e-4
            assert np.allclose(ang, after[10:13], atol=0.05)
    finally:
        world.close()


def flat_rebound(design, restitution: float, fall: float = 2.0) -> float:
    """Rebound speed over impact speed of `design` dropped flat on face 0 from `fall` units, at rest, spinless."""
    settings = PhysicsSettings(restitution=restitution)
    body = die_body(design.polyhedron, design.mass_properties())
    rest = rest_height(design, 0)
    quat = Rotation.from_matrix(face_down(design, 0) @ body.rotation).as_quat()
    world = World(body, settings, slots=1)
    try:
        world.place(0, [0, 0, rest + fall, *quat, 0, 0, 0, 0, 0, 0])
        heights = []
        for _ in range(int(2.0 / settings.time_step)):  # the fall takes 0.64 s; a rebound of speed 1 rises 0.64 s
            world.step()
            heights.append(world.state(0)[0][2])
    finally:
        world.close()
    heights = np.array(heights)
    touch = int(np.argmax(heights <= rest + 0.01 * fall))
    bottom = touch + int(np.argmin(heights[touch : touch + int(0.2 / settings.time_step)]))  # of the first impact
    bounced = heights[bottom:]  # the first rebound rises highest
    return float(np.sqrt(max(bounced.max() - rest, 0.0) / fall))


def test_restitution_is_the_engines_per_body_value_and_a_flat_drop_rebounds_at_about_its_square(cube):
    """Bullet multiplies the die's and the table's restitution: the rebound is not the setting."""
    rebound = {r: flat_rebound(cube, r) for r in (0.0, 0.3, 0.6, 0.9, 1.0)}
    assert rebound[0.0] < 0.01
    for r in (0.3, 0.6, 0.9, 1.0):
        assert 0.5 * r**2 <= rebound[r] <= r**2, (r, rebound[r])
    assert rebound[0.6] < 0.5 * 0.6  # far below the setting itself
    assert np.all(np.diff(list(rebound.values())) > 0)


def test_friction_is_the_engines_per_body_value_and_a_sliding_die_brakes_at_its_square(cube):
    """A die sliding flat decelerates at mu g, where mu is the product of the die's and the table's friction."""
    body = die_body(cube.polyhedron, cube.mass_properties())
    quat = Rotation.from_matrix(face_down(cube, 0) @ body.rotation).as_quat()
    for f in (0.2, 0.5, 0.8):
        settings = PhysicsSettings(friction=f)
        world = World(body, settings, slots=1)
        try:
            world.place(0, [0, 0, rest_height(cube, 0), *quat, 8.0, 0, 0, 0, 0, 0])
            world.step(24)  # the contact settles
            before = world.state(0)[2][0]
            world.step(24)
            after = world.state(0)[2][0]
        finally:
            world.close()
        assert after > 0  # still sliding
        mu = (before - after) / (24 * settings.time_step) / settings.gravity
        assert mu == pytest.approx(f**2, rel=0.06), (f, mu)


# ----------------------------------------------------------------------
# sleeping bodies


def test_reused_body_is_never_left_asleep_in_mid_air(gem):
    settings = PhysicsSettings()
    body = die_body(gem.polyhedron, gem.mass_properties())
    world = World(body, settings, slots=1)
    try:
        state = np.array([0, 0, rest_height(gem, 4) + 0.005, *Rotation.from_matrix(face_down(gem, 4) @ body.rotation)
                          .as_quat(), 0, 0, 0, 0, 0, 0])  # fmt: skip
        world.place(0, state)
        world.step(4 * 240)  # 4 s at rest: Bullet would put a sleeping-enabled body to sleep after 2 s
        assert np.linalg.norm(world.state(0)[2]) < 1e-3
        lifted = state.copy()
        lifted[2] = 3.0
        world.place(0, lifted)
        world.step(24)
        pos, _, lin, _ = world.state(0)
        assert pos[2] < 3.0 - 0.04 and lin[2] < -0.9  # it falls: 0.1 s of gravity
    finally:
        world.close()
    # the hazard is real: a body allowed to sleep, put to sleep on the ground and reset into the air, hangs
    world = World(body, settings, slots=1)
    p, die, cid = world.p, world.dice[0], world.cid
    try:
        p.changeDynamics(die, -1, activationState=p.ACTIVATION_STATE_ENABLE_SLEEPING, physicsClientId=cid)
        p.resetBasePositionAndOrientation(die, state[:3], state[3:7], physicsClientId=cid)
        world.step(4 * 240)
        p.resetBasePositionAndOrientation(die, lifted[:3], lifted[3:7], physicsClientId=cid)
        world.step(24)
        assert world.state(0)[0][2] == pytest.approx(3.0)
    finally:
        world.close()
    # and through the reused per-process world: a batch after a batch still lands every die
    first = run_batch(body, settings, 0, 0, 16)
    again = run_batch(body, settings, 0, 0, 16)
    assert np.array_equal(first, again) and np.all(first >= 0)


# ----------------------------------------------------------------------
# statistics and reproducibility


def test_cube_is_uniform(cube):
    result = simulate(cube, 600, seed=3, workers=1)
    assert result.cocked + result.unsettled <= 3
    counts = result.face_counts
    expected = counts.sum() / 6
    stat = ((counts - expected) ** 2 / expected).sum()
    assert stat < chi2.ppf(0.999, 5), counts


def test_gem_mirror_faces_agree(gem):
    result = simulate(gem, 1500, seed=4, workers=1)
    c = dict(zip(result.faces, result.face_counts))
    for a, b in (("f1", "f3"), ("f2", "f4"), ("f6", "f8"), ("f7", "f9")):
        n = c[a] + c[b]
        # binomial(n, 1/2): 4 standard deviations never flakes, a swapped face mapping fails it
        assert abs(c[a] - n / 2) < 4 * np.sqrt(n / 4) + 1, (a, b, c)
    assert c["f5"] > max(c["f6"], c["f8"]) > c["f1"] > c["f2"]


def test_same_counts_for_one_and_two_workers(gem):
    one = simulate(gem, 160, seed=11, workers=1)
    two = simulate(gem, 160, seed=11, workers=2)
    assert np.array_equal(one.outcomes, two.outcomes)
    assert np.array_equal(one.face_counts, two.face_counts)
    other = simulate(gem, 160, seed=12, workers=1)
    assert not np.array_equal(one.outcomes, other.outcomes)


def test_drop_does_not_depend_on_batching(gem):
    body = die_body(gem.polyhedron, gem.mass_properties())
    settings = PhysicsSettings()
    whole = run_batch(body, settings, 21, 0, 40)
    parts = np.concatenate([run_batch(body, settings, 21, a, min(a + 7, 40)) for a in range(0, 40, 7)])
    assert np.array_equal(whole, parts)
    assert np.array_equal(run_batch(body, settings, 21, 13, 14), whole[13:14])


def test_dask_local_cluster_gives_the_same_counts(gem):
    distributed = pytest.importorskip("distributed")
    local = simulate(gem, 64, seed=5, workers=1)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as lc:
        with distributed.Client(lc) as client:
            remote = simulate(gem, 64, seed=5, scheduler=client)
    assert np.array_equal(local.outcomes, remote.outcomes)


@pytest.mark.parametrize(("text", "seconds"), [("", 30.0), ("5", 5.0), (" 120.5 ", 120.5)])
def test_the_wait_for_a_worker_reads_its_environment_variable(monkeypatch, text, seconds):
    from diefab.physics.cluster import stall_limit

    monkeypatch.setenv("DIEFAB_DASK_STALL", text)
    assert stall_limit() == seconds


@pytest.mark.parametrize("text", ["0", "-3", "nan", "inf", "soon"])
def test_a_bad_wait_for_a_worker_is_refused_by_name(monkeypatch, text):
    from diefab.physics.cluster import stall_limit

    monkeypatch.setenv("DIEFAB_DASK_STALL", text)
    with pytest.raises(PhysicsError, match="DIEFAB_DASK_STALL"):
        stall_limit()


def test_roll_result_values(gem):
    result = simulate(gem, 48, seed=0, workers=1)
    assert isinstance(result, RollResult)
    assert result.n == 48 == result.landed + result.cocked + result.unsettled
    values = result.value_counts(gem)
    assert values.sum() == result.landed
    assert values[gem.support.index(0)] == result.face_counts[gem.polyhedron.face_index("f5")]
    assert np.isclose(result.value_probabilities(gem).sum(), 1.0)


def test_fast_path_agrees_with_plain_loop_drop_by_drop(gem):
    body = die_body(gem.polyhedron, gem.mass_properties())
    settings = PhysicsSettings()
    fast = run_batch(body, settings, 8, 0, 60)
    plain = run_batch(body, settings, 8, 0, 60, plain=True)
    # the same initial conditions; chaos and the free-fall integrator let a few drops differ
    assert np.mean(fast == plain) >= 0.85
    assert COCKED not in set(plain.tolist()) or np.mean(plain == COCKED) < 0.05


def test_energy_early_stop_never_changes_an_outcome(gem):
    """Stopping a die once it is trapped in a basin gives the face it would have settled on."""
    import dataclasses

    body = die_body(gem.polyhedron, gem.mass_properties())
    settings = PhysicsSettings()
    states = initial_conditions(4, 0, 160, settings)
    world = World(body, settings)
    try:
        early = world.run(states)
    finally:
        world.close()
    world = World(body, dataclasses.replace(settings, energy_fraction=0.0))
    try:
        settled = world.run(states)
    finally:
        world.close()
    assert np.array_equal(early, settled)


@pytest.mark.slow
def test_fast_path_distribution_matches_plain_loop(gem):
    body = die_body(gem.polyhedron, gem.mass_properties())
    settings = PhysicsSettings()
    fast = simulate(gem, 3000, seed=31).face_counts
    plain = run_batch(body, settings, 32, 0, 1500, plain=True)
    plain = np.bincount(plain[plain >= 0], minlength=9)
    from scipy.stats import chi2_contingency

    assert chi2_contingency(np.array([fast, plain]))[1] > 1e-4


# ----------------------------------------------------------------------
# settings and bad input


def test_settings_from_mapping_and_validation():
    s = PhysicsSettings.from_mapping({"friction": 0.5}, restitution=0.2, time_step=None)
    assert (s.friction, s.restitution, s.time_step) == (0.5, 0.2, 1 / 240)
    assert s.as_dict()["angular_velocity"] == [0.0, 10.0]
    for bad in (
        {"friction": -0.1},
        {"restitution": 1.5},
        {"time_step": 0},
        {"time_step": float("nan")},
        {"angular_velocity": [5, 1]},
        {"solver_iterations": 2.5},
        {"warp": 9},
    ):
        with pytest.raises(PhysicsError):
            PhysicsSettings.from_mapping(bad)


def test_simulate_rejects_bad_arguments(gem):
    for kwargs in ({"n": 0}, {"n": 10**12}, {"n": 10, "workers": 0}, {"n": 10, "seed": -1}):
        with pytest.raises(PhysicsError):
            simulate(gem, **kwargs)
    with pytest.raises(PhysicsError, match="radius"):
        simulate(gem, 10, settings=PhysicsSettings(drop_height=1.0, height_jitter=0.1))
    with pytest.raises(PhysicsError, match="unstable"):
        simulate(gem.with_params(c=1.0, d=4.0), 10, workers=1)


@pytest.mark.parametrize(
    "args",
    [
        ["--sims", "0"],
        ["--sims", "-5"],
        ["--sims", "1000000000000"],
        ["--workers", "0"],
        ["--friction", "-1"],
        ["--restitution", "1.5"],
        ["--time-step", "0"],
        ["--energy-fraction", "1"],
        ["--param", "a=nan"],
        ["--param", "c=1.0", "--param", "d=4.0"],
        ["--plot", "chart.gif"],
        ["--scheduler", "tcp://127.0.0.1:9"],
        ["--scheduler", "not a scheduler::"],
    ],
)
def test_cli_bad_input_is_one_line_exit_2(args, bad, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    bad("validate", "fudge-gem", "--sims", "10", "--workers", "1", *args)
    assert not list(tmp_path.iterdir())


def test_cli_json_and_plot(tmp_path, run):
    import json

    plot = tmp_path / "chart.svg"
    code, out, err = run("validate", "fudge-gem", "--sims", "40", "--workers", "1", "--json", "--plot", plot)
    assert code == 0, err
    data = json.loads(out)
    keys = "n counts face_counts probabilities cocked unsettled chi2 p_value tvd jsd seconds drops_per_second settings"
    for key in keys.split() + ["intervals", "expected_tvd", "expected_jsd", "solid_angle", "target_probabilities"]:
        assert key in data
    assert list(data["counts"]) == [str(v) for v in range(-4, 5)]
    assert sum(data["counts"].values()) + data["cocked"] + data["unsettled"] == data["n"] == 40
    assert data["settings"]["restitution"] == 0.3
    import xml.etree.ElementTree as ET

    assert ET.parse(plot).getroot().tag.endswith("svg")


def test_cli_interrupt_reports_finished_drops(gem, monkeypatch, run):
    from diefab.physics import simulate as physics

    def interrupted(*args, **kwargs):
        raise physics.SimulationInterrupted(123, 1000)

    monkeypatch.setattr(physics, "simulate", interrupted)
    code, _, err = run("validate", "fudge-gem", "--sims", "1000")
    assert code == 130
    assert "123 of 1000" in err and len(err.strip().splitlines()) == 1


def test_sigterm_stops_validate_cleanly_with_its_workers(tmp_path):
    """A kill (SIGTERM) ends a run like Ctrl-C: one line, exit 130, no worker left behind."""
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    proc = subprocess.Popen(
        [sys.executable, "-m", "diefab", "validate", "fudge-gem", "--sims", "2000000", "--workers", "2"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )  # fmt: skip
    children: set[int] = set()
    deadline = time.monotonic() + 60
    while len(children) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.5)
        for task in Path(f"/proc/{proc.pid}/task").glob("*/children"):
            children |= {int(c) for c in task.read_text().split()}
    time.sleep(2.0)  # let the workers finish some batches
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130
    assert "of 2000000" in err and len(err.strip().splitlines()) == 1
    time.sleep(0.5)
    for pid in children:
        try:
            status = Path(f"/proc/{pid}/status").read_text()
        except FileNotFoundError:
            continue
        assert "zombie" in status or f"PPid:\t{os.getpid()}" not in status


#: Forty runs of two workers, each stopped after a random 0.05 to 0.6 s, wherever the stop lands.
_STOPPED_AT_RANDOM = """
import signal
import numpy as np
from diefab.core import files
from diefab.dice.design import load_design
from diefab.physics.simulate import simulate

def interrupt(signum, frame):
    raise KeyboardInterrupt

files.STOP_SIGNALS = (*files.STOP_SIGNALS, signal.SIGALRM)
signal.signal(signal.SIGALRM, interrupt)
gem, rng, stopped = load_design("fudge-gem"), np.random.default_rng(2), 0
for _ in range(40):
    signal.setitimer(signal.ITIMER_REAL, rng.uniform(0.05, 0.6))
    try:
        simulate(gem, 2_000_000, seed=1, workers=2)
    except KeyboardInterrupt:  # SimulationInterrupted, or a stop before the run began
        stopped += 1
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
print(stopped)
"""


@pytest.mark.slow
def test_a_stop_anywhere_in_a_pooled_run_never_hangs():
    """A stop inside the pool's own calls (submit, wait) still ends the run: none of the forty hangs."""
    import signal
    import subprocess
    import sys

    if not hasattr(signal, "setitimer"):
        pytest.skip("needs interval timers")
    try:
        out = subprocess.run([sys.executable, "-c", _STOPPED_AT_RANDOM], capture_output=True, text=True, timeout=180)
    except subprocess.TimeoutExpired:
        pytest.fail("a stopped run hung")
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["40"]


@pytest.mark.parametrize("workers", [1, 2])
def test_interrupt_stops_cleanly_and_counts_finished_drops(gem, workers):
    from diefab.physics.simulate import SimulationInterrupted

    def progress(done, total):
        raise KeyboardInterrupt

    with pytest.raises(SimulationInterrupted) as exc:
        simulate(gem, 400, seed=1, workers=workers, progress=progress)
    assert 0 < exc.value.done < 400 and exc.value.total == 400
    # the pool is usable again afterwards
    assert simulate(gem, 40, seed=1, workers=workers).n == 40
