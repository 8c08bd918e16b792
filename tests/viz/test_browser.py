"""The scenes in a real browser: headless Chromium (Debian's package) through Playwright.

Each test opens a scene, waits until it is built, pauses the animation, seeks
it to fixed times, takes screenshots (kept under ``out/browser/`` for a person
to look at) and checks pixels where the robot and the obstacle must be, by
projecting their world positions with the page's own camera.

Needs ``/usr/bin/chromium`` (``apt-get install chromium``; ``.ci/run`` does it)
and the ``playwright`` Python package; never ``playwright install``. Without
them the tests are skipped, except on CI (``CI=true`` in the environment, as
GitHub Actions, GitLab CI and ``.ci/run`` set it), where they fail: a CI run
must not pass with its browser tests silently skipped.
"""

from __future__ import annotations

import importlib
import io
import os
import warnings
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from clik.outputs.result import TrackingResult
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.viz import export_html, show, stop_server

CHROMIUM = "/usr/bin/chromium"
OUT = Path(__file__).resolve().parents[2] / "out" / "browser"
CHROMIUM_ARGS = [
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
]
VIEWPORT = {"width": 1024, "height": 768}

pytestmark = pytest.mark.browser


def on_ci() -> bool:
    """Whether this is a CI run: ``CI`` set to ``true`` (or ``1``, ``yes``) in the environment."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


def missing() -> str | None:
    """What the browser tests lack (Chromium, Playwright, Pillow), or None."""
    if not Path(CHROMIUM).exists():
        return f"no {CHROMIUM}: apt-get install chromium (CI's .ci/run does)"
    for module, how in (
        (
            "playwright.sync_api",
            "pip install playwright (the 'test' extra); never "
            "`playwright install`: the tests use Debian's chromium",
        ),
        ("PIL.Image", "pip install pillow (the 'test' extra)"),
    ):
        try:
            importlib.import_module(module)
        except ImportError:
            return f"no {module}: {how}"
    return None


def require_browser() -> None:
    """Skip when the browser tests cannot run; on CI fail instead."""
    problem = missing()
    if problem is None:
        return
    if on_ci():
        pytest.fail(
            f"CI={os.environ['CI']}: the browser tests must run, but {problem}", pytrace=False
        )
    pytest.skip(problem)


PROJECT_JS = """(points) => {
    const THREE = MeshCat.THREE;
    const root = viewer.scene_tree.find(["meshcat"]).object;
    root.updateMatrixWorld(true);
    viewer.camera.updateMatrixWorld(true);
    const canvas = viewer.renderer.domElement;
    return points.map((p) => {
        const v = new THREE.Vector3(p[0], p[1], p[2]).applyMatrix4(root.matrixWorld);
        v.project(viewer.camera);
        return [(v.x + 1) / 2 * canvas.clientWidth, (1 - v.y) / 2 * canvas.clientHeight];
    });
}"""
ROBOT_BUILT_JS = """() => {
    try {
        const robot = viewer.scene_tree.find(["meshcat", "robot"]);
        return Object.keys(robot.children).length > 0 && viewer.animator.actions.length > 0;
    } catch (e) { return false; }
}"""


# -- pixels ------------------------------------------------------------------------------


def rgb(png: bytes) -> np.ndarray:
    from PIL import Image

    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)


def drawn(img: np.ndarray, without: np.ndarray) -> np.ndarray:
    """Pixels an element covers: where the image differs from the one drawn without it.

    (The planar arm's links are neutral greys, apart from the legend's colours: found by
    hiding the robot rather than by their colour.)
    """
    return np.abs(img - without).sum(axis=2) > 30


def purple(img: np.ndarray) -> np.ndarray:
    """The obstacle: its body (0.45, 0.2, 0.65), lit, bare or seen through its threshold
    shell (cyan (0, 0.75, 0.8) at 22 % opacity), or the shell alone over a light background
    (a point obstacle has no body)."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    body = (b > 90) & (b - g > 50) & (r - g > 25) & (g < 120)
    through_shell = (b > 120) & (b - g > 50) & (b - r > 40)
    shell = (r > 120) & (g - r > 25) & (b - r > 25)
    return body | through_shell | shell


def magenta(img: np.ndarray) -> np.ndarray:
    """Links of a joint whose range row is active (0.85, 0.1, 0.8)."""
    r, g, b = img[..., 0], img[..., 1], img[..., 2]
    return (r > 150) & (b > 130) & (g < 90)


def count_in_box(mask: np.ndarray, points: np.ndarray, pad: float) -> int:
    """Pixels of ``mask`` inside the bounding box of ``points`` (px) grown by ``pad``."""
    (x0, y0), (x1, y1) = points.min(axis=0) - pad, points.max(axis=0) + pad
    h, w = mask.shape
    xs, ys = (
        slice(max(int(x0), 0), min(int(x1) + 1, w)),
        slice(max(int(y0), 0), min(int(y1) + 1, h)),
    )
    return int(mask[ys, xs].sum())


# -- browser -----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def browser() -> Iterator[object]:
    require_browser()
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS)
        yield b
        b.close()


class Page:
    """One page with its console errors collected."""

    def __init__(self, browser: object) -> None:
        self.page = browser.new_page(viewport=VIEWPORT)  # type: ignore[attr-defined]
        self.errors: list[str] = []
        self.page.on("console", lambda m: m.type == "error" and self.errors.append(m.text))
        self.page.on("pageerror", lambda e: self.errors.append(f"page error: {e}"))

    def seek(self, t: float) -> None:
        self.page.evaluate(f"viewer.animator.pause(); viewer.animator.seek({t})")
        self.page.evaluate(
            "new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))"
        )

    def shot(self, name: str) -> np.ndarray:
        """The canvas as drawn, without meshcat's controls panel (open by default: its
        coloured stripes would count as drawn lines)."""
        OUT.mkdir(parents=True, exist_ok=True)
        self.page.evaluate("viewer.gui.domElement.style.visibility = 'hidden'")
        png = self.page.screenshot()
        self.page.evaluate("viewer.gui.domElement.style.visibility = ''")
        (OUT / f"{name}.png").write_bytes(png)
        return rgb(png)

    def project(self, points: np.ndarray) -> np.ndarray:
        return np.array(self.page.evaluate(PROJECT_JS, np.asarray(points).tolist()))

    def set_visible(self, path: list[str], visible: bool) -> None:
        self.page.evaluate(
            f"viewer.scene_tree.find({path!r}).object.visible = {str(visible).lower()};"
            "viewer.set_dirty()"
        )


def joint_origins(result: TrackingResult, t: float) -> np.ndarray:
    """World positions of every joint and frame origin at run time ``t`` [s]."""
    model = result.robot.model
    data = model.createData()
    pin.framesForwardKinematics(model, data, result.q[np.argmin(np.abs(result.t - t))])
    return np.array([f.translation for f in data.oMf])


def check_planar_arm(page: Page, result: TrackingResult, name: str) -> None:
    """Robot and obstacle drawn where they belong, the pose changes with time, highlights."""
    obstacle = np.array(result.info["obstacles"][0]["position"])
    (center,) = page.project(obstacle[None])
    shell = float(np.linalg.norm(page.project([obstacle + [0.03, 0, 0]])[0] - center))
    images, arms = {}, {}
    for t in (0.0, 1.5, 2.4, 3.0):
        page.seek(t)
        img = page.shot(f"{name}_t{t:.1f}")
        images[t] = img
        arm = arms[t] = page.project(joint_origins(result, t))
        page.set_visible(["meshcat", "robot"], False)
        links = drawn(img, page.shot(f"{name}_t{t:.1f}_no_robot"))
        page.set_visible(["meshcat", "robot"], True)
        assert count_in_box(links, arm, pad=20) > 1500, f"robot not drawn at t={t}"
        assert count_in_box(links, arm, pad=20) > 0.8 * links.sum(), f"robot misplaced at t={t}"
        assert count_in_box(purple(img), center[None], pad=shell) > 15, f"no obstacle at t={t}"
    assert np.linalg.norm(arms[3.0][-1] - arms[0.0][-1]) > 50  # the tip moved on the screen
    assert np.abs(images[3.0] - images[0.0]).sum(axis=2).astype(bool).sum() > 2000
    # joint3's upper-limit row is active from 1.32 s to 2.60 s: its link turns magenta.
    assert count_in_box(magenta(images[2.4]), arms[2.4], pad=20) > 300
    assert count_in_box(magenta(images[0.0]), arms[0.0], pad=20) < 20


# -- tests -------------------------------------------------------------------------------


def test_without_chromium_skip_or_on_ci_fail(monkeypatch):
    monkeypatch.setitem(globals(), "CHROMIUM", "/nonexistent/chromium")
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match="no /nonexistent/chromium: apt-get install"):
        require_browser()
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception):
        require_browser()
    for value in ("true", "1"):
        monkeypatch.setenv("CI", value)
        with pytest.raises(pytest.fail.Exception, match="the browser tests must run, but no "):
            require_browser()


@pytest.fixture(scope="module")
def case_study() -> TrackingResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build(scenario_path("case_study_both")).execute()


def test_exported_case_study_renders(browser, case_study, tmp_path):
    path = export_html(case_study, OUT / "case_study_both.html")
    page = Page(browser)
    page.page.goto(path.as_uri())
    page.page.wait_for_function("window.clikSceneReady === true", timeout=30_000)
    check_planar_arm(page, case_study, "html_case_study")
    assert page.errors == []


def test_exported_panda_renders(browser, tmp_path):
    from tests.viz.test_viz import panda_run

    result = panda_run()
    path = export_html(result, OUT / "panda.html")
    page = Page(browser)
    page.page.goto(path.as_uri())
    page.page.wait_for_function("window.clikSceneReady === true", timeout=60_000)
    shots = {}
    for t in (0.0, 1.5):
        page.seek(t)
        shots[t] = page.shot(f"html_panda_t{t:.1f}")
        arm = page.project(joint_origins(result, t))
        page.set_visible(["meshcat", "robot"], False)
        page.seek(t)
        empty = page.shot(f"html_panda_t{t:.1f}_no_robot")
        page.set_visible(["meshcat", "robot"], True)
        robot = np.abs(shots[t] - empty).sum(axis=2) > 30
        assert count_in_box(robot, arm, pad=60) > 5000, f"Panda not drawn at t={t}"
        assert count_in_box(robot, arm, pad=60) > 0.9 * robot.sum()
    assert (np.abs(shots[1.5] - shots[0.0]).sum(axis=2) > 30).sum() > 1000
    ball = np.array(result.info["obstacles"][0]["position"])
    assert count_in_box(purple(shots[0.0]), page.project(ball[None]), pad=40) > 500
    assert page.errors == []


def test_live_page_renders(browser, case_study):
    try:
        url = show(case_study)
        page = Page(browser)
        page.page.goto(url)
        page.page.wait_for_function(ROBOT_BUILT_JS, timeout=30_000)
        check_planar_arm(page, case_study, "live_case_study")
        assert page.errors == []
    finally:
        stop_server()
