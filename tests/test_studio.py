"""The studio in a real headless browser: Chromium driven by Playwright.

The server runs as ``python -m diefab studio`` in a subprocess on a free
127.0.0.1 port.  The page's state is read from its hidden JSON element and
the chart's SVG, never from pixels; downloads are checked geometrically.
Skipped where Playwright or Chromium is missing.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

playwright_api = pytest.importorskip("playwright.sync_api")

CHROMIUM = next((p for p in ("/usr/bin/chromium", shutil.which("chromium") or "") if p and os.path.exists(p)), None)
if CHROMIUM is None:
    pytest.skip("Chromium is not installed (apt-get install chromium)", allow_module_level=True)

ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
        "--disable-component-update", "--no-first-run", "--disable-sync"]  # fmt: skip
ROOT = Path(__file__).resolve().parent.parent
#: Where the screenshots go: a scratch folder, or docs/img when asked (``DIEFAB_SHOTS=docs/img``), so that a
#: test run leaves the checkout as it was.
SHOTS = Path(os.environ.get("DIEFAB_SHOTS") or Path(tempfile.gettempdir()) / "diefab-studio-shots")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _children(pid: int) -> list[int]:
    """Live child processes of `pid` (Linux /proc), the multiprocessing resource tracker left out."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            cmd = (entry / "cmdline").read_bytes().replace(b"\0", b" ").decode()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        state = stat.rsplit(")", 1)[1].split()[0]
        if ppid == pid and state != "Z" and "resource_tracker" not in cmd:
            out.append(int(entry.name))
    return out


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    out = tmp_path_factory.mktemp("studio-out")
    port = _free_port()
    # NiceGUI takes a PYTEST_* variable for its own test harness: the studio runs as a user would run it
    env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")} | {"PYTHONPATH": str(ROOT)}
    log = open(out.parent / "studio.log", "wb")  # a file, not a pipe: a full pipe would stall the server
    proc = subprocess.Popen([sys.executable, "-m", "diefab", "studio", "fudge-gem", "--no-browser", "--port",
                             str(port), "--out", str(out)], cwd=ROOT, env=env, stdout=log,
                            stderr=subprocess.STDOUT)  # fmt: skip
    url = f"http://127.0.0.1:{port}"
    try:
        for _ in range(240):
            try:
                urllib.request.urlopen(url + "/healthz", timeout=1).close()
                break
            except OSError:
                if proc.poll() is not None:
                    pytest.fail(f"the studio did not start: {(out.parent / 'studio.log').read_text()}")
                time.sleep(0.25)
        yield {"url": url, "out": out, "proc": proc}
    finally:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(5)
        log.close()


@pytest.fixture(scope="module")
def browser():
    with playwright_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield b
        b.close()


@pytest.fixture
def page(browser, server):
    pg = browser.new_page(viewport={"width": 1400, "height": 1000}, accept_downloads=True)
    pg.requests_outside = []
    pg.on("request", lambda r: None if r.url.startswith((server["url"], "data:", "blob:"))
          else pg.requests_outside.append(r.url))  # fmt: skip
    pg.goto(server["url"] + "/")
    _wait_state(pg, lambda s: s["name"] == "fudge-gem")
    yield pg
    pg.close()


def _state(pg) -> dict:
    text = pg.locator(".studio-state").text_content()
    return json.loads(text) if text else {}


def _wait_state(pg, cond, timeout=60.0) -> dict:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        s = _state(pg)
        if s and cond(s):
            return s
        pg.wait_for_timeout(100)
    raise AssertionError(f"the page's state never met the condition; last: {str(_state(pg))[:300]}")


def _wait_text(pg, selector: str, pattern: str, timeout_s: float) -> str:
    """Wait until the text of `selector` matches the regular expression `pattern`; the text."""
    pg.wait_for_function("([sel, pat]) => new RegExp(pat).test(document.querySelector(sel).textContent)",
                         arg=[selector, pattern], timeout=timeout_s * 1000)  # fmt: skip
    return pg.locator(selector).text_content()


def _bars(pg) -> list[str]:
    return pg.eval_on_selector_all(".studio-chart svg path", "els => els.map(e => e.getAttribute('d'))")


def _shot(pg, name: str, full: bool = False) -> None:
    SHOTS.mkdir(parents=True, exist_ok=True)
    pg.wait_for_timeout(1500)  # the 3D die follows the chart by a moment
    pg.screenshot(path=str(SHOTS / f"studio-{name}.png"), full_page=full)


def test_page_works_offline(page):
    """Every script, style and font comes from the studio itself: no CDN."""
    page.wait_for_timeout(1500)
    assert page.requests_outside == []


def test_template_slider_chart_margins_undo(page):
    from diefab import load_design, value_probabilities

    page.locator(".q-select").first.click()  # the template chooser in the header
    page.get_by_role("option", name="fudge-gem", exact=True).click()
    before = _wait_state(page, lambda s: s["name"] == "fudge-gem")
    bars_before = _bars(page)
    assert len(before["probabilities"]) == 9 and abs(sum(before["probabilities"]) - 1) < 1e-9

    page.locator('.studio-param-a [tabindex="0"]').first.focus()
    page.evaluate("""() => {
        window.__lat = [];
        const chart = document.querySelector('.studio-chart');
        const slider = document.querySelector('.studio-param-a');
        slider.addEventListener('keydown', () => { window.__t0 = performance.now(); window.__t1 = null; }, true);
        new MutationObserver(() => {
            if (window.__t0 && !window.__t1) {
                window.__t1 = performance.now();
                window.__lat.push(window.__t1 - window.__t0);
            }
        }).observe(chart, {subtree: true, childList: true, attributes: true});
    }""")  # fmt: skip
    server_ms = []
    for _ in range(12):
        page.keyboard.press("ArrowRight")
        page.wait_for_function("() => window.__t1 !== null", timeout=10_000)
        page.wait_for_timeout(150)
        server_ms.append(_state(page)["server_ms"] or float("nan"))
    after = _wait_state(page, lambda s: s["params"]["a"] > before["params"]["a"])
    latencies = page.evaluate("() => window.__lat")
    print(f"slider-to-chart latency, ms: median {np.median(latencies):.1f}, p90 {np.percentile(latencies, 90):.1f}, "
          f"max {max(latencies):.1f}, "
          f"n {len(latencies)}; of it in the server: median {np.nanmedian(server_ms):.1f}; "
          f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")  # fmt: skip
    # the chart and the margins follow the slider, and agree with the library's fast model at the new parameters
    assert _bars(page) != bars_before
    expected = value_probabilities(load_design("fudge-gem").with_params(**after["params"]), "fast")
    np.testing.assert_allclose(after["probabilities"], expected, atol=1e-9)
    margins = lambda s: [f["margin"] for f in s["faces"]]  # noqa: E731
    assert margins(after) != margins(before)
    assert after["undo"] == 1  # one slider dragged is one undo step

    page.get_by_role("button", name="undo").click()
    undone = _wait_state(page, lambda s: s["params"]["a"] == before["params"]["a"])
    assert undone["redo"] == 1 and margins(undone) == margins(before)
    page.get_by_role("button", name="redo").click()
    _wait_state(page, lambda s: s["params"]["a"] == after["params"]["a"])


def test_click_face_shows_its_numbers(page):
    box = page.locator(".studio-scene canvas").first.bounding_box()
    for _ in range(30):  # the die is drawn a moment after the numbers: a click before that hits nothing
        page.mouse.click(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2)
        page.wait_for_timeout(1000)
        if re.search(r"face f\d+", page.locator(".studio-face").text_content()):
            break
    text = _wait_text(page, ".studio-face", r"face f\d+", 10)
    name = re.search(r"face (f\d+)", text).group(1)
    face = next(f for f in _state(page)["faces"] if f["name"] == name)
    assert f"{face['probability']:.4f}" in text and f"{face['margin']:.4f}" in text


def test_net_linked_to_die(page):
    page.wait_for_selector(".studio-net .net-face", timeout=60_000)
    n = page.locator(".studio-net .net-face").count()
    assert n == len(_state(page)["faces"])
    # once the die stays the same, it is shown as printed: its solid built in a worker, the values engraved
    _wait_text(page, ".studio-made-note", r"^$", 240)
    _shot(page, "main")
    page.locator(".studio-net .net-face").first.hover()
    page.wait_for_timeout(500)
    _shot(page, "net", full=True)


def test_validate_runs_drops_with_progress(page):
    page.get_by_role("tab", name="Validate").click()
    page.get_by_label("drops").fill("60")
    page.locator(".studio-validate").click()
    _wait_text(page, ".studio-verdict", r"p = ", 240)
    verdict = page.locator(".studio-verdict").text_content()
    m = re.search(r"(\d+) of (\d+) drops on a face, (\d+) cocked, (\d+) unsettled", verdict)
    assert m and int(m.group(2)) == 60 and int(m.group(1)) + int(m.group(3)) + int(m.group(4)) == 60
    assert page.locator(".studio-validate-bar").count() == 1
    _shot(page, "validate", full=True)


def test_downloads_are_sound(page, server, tmp_path):
    import xml.etree.ElementTree as ET

    import trimesh

    from diefab import load_design

    d = load_design("fudge-gem")
    page.get_by_role("tab", name="Make").click()
    with page.expect_download(timeout=120_000) as info:
        page.locator(".studio-download-net").click()
    svg = tmp_path / "net.svg"
    info.value.save_as(svg)
    root = ET.parse(svg).getroot()
    assert root.tag.endswith("svg")
    width, height = (float(root.get(k).removesuffix("mm")) for k in ("width", "height"))
    assert width == pytest.approx(210.0) and height / 297.0 == pytest.approx(round(height / 297.0))  # A4 sheets

    with page.expect_download(timeout=240_000) as info:
        page.locator(".studio-download-stl").click()
    stl = tmp_path / "die.stl"
    info.value.save_as(stl)
    mesh = trimesh.load(stl)
    assert mesh.is_watertight
    poly = d.polyhedron
    volume = poly.volume * d.mm_per_unit**3
    # engraved labels remove a little material: between 0.5 % and 8 % of the uncut die
    assert 0.92 * volume < mesh.volume < 0.995 * volume
    # and the files were written in --out only
    assert {p.name for p in server["out"].iterdir() if not p.name.startswith(".")} >= {
        "fudge-gem-net.svg",
        "fudge-gem.stl",
    }


def test_bad_upload_is_one_message_and_server_lives(page, server, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\nfamily = "gem"\nparams = {a = 99, b = 0.5, c = 0.7, d = 1.4}\n')
    page.locator(".studio-upload input[type=file]").set_input_files(str(bad))
    page.wait_for_function("() => document.querySelector('.studio-error').textContent.length > 0", timeout=20_000)
    message = page.locator(".studio-error").text_content()
    assert "a=99" in message and "Traceback" not in message and "\n" not in message
    outside = tmp_path / "outside.toml"
    outside.write_text('name = "m"\nfamily = "mesh"\nmesh = "/etc/passwd"\nvalues = {}\n')
    page.locator(".studio-upload input[type=file]").set_input_files(str(outside))
    page.wait_for_function("() => document.querySelector('.studio-error').textContent !== " + json.dumps(message),
                           timeout=20_000)  # fmt: skip
    assert "Traceback" not in page.locator(".studio-error").text_content()
    with urllib.request.urlopen(server["url"] + "/healthz", timeout=5) as reply:
        assert reply.status == 200


def test_design_job_cancels_and_closing_the_page_stops_jobs(browser, server):
    pg = browser.new_page(viewport={"width": 1400, "height": 1000})
    pg.goto(server["url"] + "/")
    _wait_state(pg, lambda s: bool(s))
    pg.get_by_role("tab", name="Design for target").click()
    # a share tuned by simulation: seconds of work, so the job is still running when it is cancelled
    _choose(pg, ".studio-design-model", "simulation")
    pg.get_by_label("target").fill("1:1,2:3,3:1.4")
    pg.locator(".studio-design").click()
    _wait_text(pg, ".studio-design-text", r"budget", 60)
    assert _children(server["proc"].pid)
    pg.locator(".studio-cancel").click()
    _wait_text(pg, ".studio-design-text", r"cancelled", 60)
    # a target a fair die carries exactly is designed at once, and opens in the page
    pg.get_by_label("target").fill("1:1,2:1,3:1")
    pg.locator(".studio-design").click()
    _wait_text(pg, ".studio-design-text", r"designed", 120)
    designed = _wait_state(pg, lambda s: s["name"].startswith("die-"))
    np.testing.assert_allclose(designed["target"], [1 / 3] * 3)
    np.testing.assert_allclose(designed["probabilities"], designed["target"], atol=1e-6)
    _shot(pg, "design", full=True)
    # a validation left running stops when its page closes
    pg.get_by_role("tab", name="Validate").click()
    pg.get_by_label("drops").fill("200000")
    pg.locator(".studio-validate").click()
    _wait_text(pg, ".studio-validate-text", r"drops", 60)
    assert _children(server["proc"].pid)
    pg.close()
    end = time.monotonic() + 60  # the server drops a page unheard for RECONNECT_SECONDS, then ends its workers
    while _children(server["proc"].pid) and time.monotonic() < end:
        time.sleep(0.5)
    assert _children(server["proc"].pid) == []


def _choose(pg, select: str, option: str) -> None:
    pg.locator(select).first.click()
    pg.get_by_role("option", name=option, exact=True).click()


@pytest.mark.slow
def test_paper_fill_shows_the_solid_body_at_once_then_the_made_body(page):
    from diefab import load_design, value_probabilities

    _choose(page, ".studio-fill", "paper")
    first = _wait_state(page, lambda s: s["fill"] == "paper")
    solid = load_design("fudge-gem")
    if first["provisional"]:  # the stand-in: the same shape as a solid body
        np.testing.assert_allclose(first["probabilities"], value_probabilities(solid, "fast"), atol=1e-9)
    # the page keeps following the slider while the made body is computed
    page.locator('.studio-param-a [tabindex="0"]').first.focus()
    page.keyboard.press("ArrowRight")
    moved = _wait_state(page, lambda s: s["params"]["a"] > first["params"]["a"])
    if moved["provisional"]:
        stand_in = solid.with_params(**moved["params"])
        np.testing.assert_allclose(moved["probabilities"], value_probabilities(stand_in, "fast"), atol=1e-9)
    _shot(page, "paper")
    made = _wait_state(page, lambda s: not s["provisional"] and s["params"] == moved["params"], timeout=240)
    paper = load_design("fudge-gem").with_params(**moved["params"])
    paper = replace(paper, fill=replace(paper.fill, kind="paper"))
    np.testing.assert_allclose(made["probabilities"], value_probabilities(paper, "fast"), atol=1e-9)
    margins = [f["margin"] for f in made["faces"]]
    np.testing.assert_allclose(margins, paper.margins(), atol=1e-12)


@pytest.fixture(scope="module")
def roll_video_file(server):
    """Two simulated drops of the d6 filmed by the rendering rig, as a video in the studio's folder; the truth."""
    cv2 = pytest.importorskip("cv2")
    if not hasattr(cv2, "aruco"):
        pytest.skip("OpenCV without the aruco module")
    pytest.importorskip("pybullet")
    from diefab import load_design
    from diefab.camera.rig import roll_video
    from diefab.dice.markers import marker_layout

    d = load_design("d6")
    _, truth, frames = roll_video(d, marker_layout(d), 2, seed=3, fps=15.0, hold=10)
    path = server["out"] / "rolls.avi"
    writer = None
    for f in frames:
        if writer is None:
            h, w = f.image.shape[:2]
            writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 15, (w, h), isColor=f.image.ndim == 3)
        writer.write(f.image)
    writer.release()
    return path, truth


@pytest.mark.slow
def test_camera_reads_a_video_with_live_counts_and_verdict(page, server, roll_video_file):
    from diefab.stats.rolllog import read_log

    path, truth = roll_video_file
    page.locator(".q-select").first.click()
    page.get_by_role("option", name="d6", exact=True).click()
    _wait_state(page, lambda s: s["name"] == "d6")
    page.get_by_role("tab", name="Test with the camera").click()
    _choose(page, ".studio-camera-source", "video file in the output folder")
    page.locator(".studio-camera-where input").fill(path.name)
    page.get_by_label("still frames").fill("6")
    page.locator(".studio-camera-start").click()
    _wait_text(page, ".studio-camera-text", r"source ended", 240)
    rows = read_log(server["out"] / "d6-rolls.csv").rolls
    # one roll per drop at most, never a wrong value; what the page counts is what the log holds
    assert 1 <= len(rows) <= len(truth)
    assert all(r.value in (t, None) for r, t in zip(rows, truth))
    read = sum(r.value is not None for r in rows)
    text = page.locator(".studio-camera-rolls").text_content()
    assert text.startswith(f"{read} rolls read, {len(rows) - read} unread")
    assert re.search(rf"^{read} rolls?: TVD", page.locator(".studio-camera-sequential").text_content())
    assert page.locator(".studio-camera-frame img").get_attribute("src").startswith("data:image/jpeg")
    _shot(page, "camera", full=True)
    # a path outside the studio's folder is refused in one line
    page.locator(".studio-camera-where input").fill("../../etc")
    page.locator(".studio-camera-start").click()
    page.wait_for_function("() => /reads files only in/.test(document.querySelector('.studio-error').textContent)",
                           timeout=20_000)  # fmt: skip
