"""A several-task scene in headless Chromium: each task's line is on screen, in its colour.

Same browser and skips as ``test_browser.py`` (Debian's chromium through Playwright;
on CI a missing browser fails).
"""

from __future__ import annotations

import numpy as np
import pytest

import clik
from clik.viz import export_html, palette
from clik.viz.task_paths import task_paths
from tests.viz.test_browser import OUT, Page, browser, count_in_box  # noqa: F401 (fixture)
from tests.viz.test_task_view import baxter, bent_start, box_goals

pytestmark = pytest.mark.browser


def rose(img: np.ndarray) -> np.ndarray:
    """The first other task's colour (0.85, 0.2, 0.45), blended into the background by a
    one-pixel line's antialiasing: red well above green, blue between them."""
    r, g, b = (img[..., i].astype(int) for i in range(3))
    return (r - g > 50) & (b - g > 10) & (r - b > 20)


def test_each_task_line_is_drawn_in_its_colour(browser):  # noqa: F811 (the fixture)
    robot = baxter()
    q0 = bent_start(robot)
    goals = box_goals(robot, q0)[1:3]  # the two hands: right (primary) and left
    result = clik.track(
        tasks=goals, q0=q0, law="pseudoinverse", gain=200.0, dt=2e-3, engine="python"
    )
    path = export_html(result, OUT / "baxter_two_hands.html", geometry="collision", tasks=goals)
    page = Page(browser)
    page.page.goto(path.as_uri())
    page.page.wait_for_function("window.clikSceneReady === true", timeout=60_000)
    page.set_visible(["meshcat", "robot"], False)  # the lines alone
    page.page.evaluate("document.getElementById('clik-caption').style.display = 'none'")
    page.seek(float(result.t[-1]))
    shot = page.shot("tasks_two_hands")
    (left,) = [p.achieved for p in task_paths(result, goals) if p.name == "left hand"]
    on_screen = page.project(left[:: max(1, len(left) // 20)])
    assert palette.TASKS[0] == (0.85, 0.2, 0.45)  # the first other task's: the left hand's
    line = rose(shot)
    assert count_in_box(line, on_screen, pad=6) > 20, "no left-hand line where the hand went"
    assert count_in_box(line, on_screen, pad=6) > 0.8 * line.sum()
    page.set_visible(["meshcat", "tasks"], False)
    page.seek(float(result.t[-1]))
    assert rose(page.shot("tasks_two_hands_hidden")).sum() < 5
    assert page.errors == []
