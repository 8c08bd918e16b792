"""The 3-D view's rough edges of issue 27: link colours apart from the legend, controls open.

The legend's colours mean states (blue reference, orange "closest link inside
threshold", red "active obstacle row", ...): the planar arm's own links are drawn in
neutral tones, and any robot colour near a legend colour is drawn grey. The HTML page
opens meshcat's controls panel, so the play controls are in view.
"""

from __future__ import annotations

import warnings

import pytest

import clik
from clik.outputs.result import TrackingResult
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.viz import export_html, palette
from clik.viz.robot_layer import drawn_geometry, robot_commands
from tests.viz.test_browser import browser  # noqa: F401 (the fixture)


@pytest.fixture(scope="module")
def planar_run() -> TrackingResult:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build(scenario_path("case_study_unconstrained")).execute()


def test_planar_arm_colours_are_none_of_the_legend():
    robot = clik.Robot.load("planar4r")
    _, parts = robot_commands(robot, drawn_geometry(robot))
    drawn = {rgb for joint in parts.values() for _, rgb in joint}
    assert len(drawn) >= 3  # still told apart: two link tones, joints, tip
    for rgb in drawn:
        for colour, label in palette.LEGEND:
            assert palette.distance(rgb, colour) >= palette.LEGEND_DISTANCE, (rgb, label)
    # the URDF's own materials (what another viewer shows) are neutral too
    own = {tuple(float(c) for c in go.meshColor[:3]) for go in robot.visual_model.geometryObjects}
    assert own == drawn


@pytest.mark.parametrize(("label", "colour"), [(label, colour) for colour, label in palette.LEGEND])
def test_a_link_coloured_like_a_legend_entry_is_drawn_neutral(label, colour):
    assert palette.link_color(colour) == palette.ROBOT_NEUTRAL, label
    assert all(
        palette.distance(palette.ROBOT_NEUTRAL, c) >= palette.LEGEND_DISTANCE
        for c, _ in palette.LEGEND
    )


def test_a_link_colour_apart_from_the_legend_is_kept():
    assert palette.link_color((0.72, 0.72, 0.7)) == (0.72, 0.72, 0.7)
    assert palette.distance((1.0, 0.0, 0.0), (1.0, 0.0, 0.0)) == 0.0
    assert palette.distance((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)) == pytest.approx(100.0, abs=0.1)


def test_the_page_opens_the_play_controls(planar_run, tmp_path):
    text = export_html(planar_run, tmp_path / "scene.html").read_text()
    opened = text.index("viewer.gui.open();")
    assert "viewer.animator.folder.open()" in text
    assert text.index("viewer.handle_command_bytearray(bytes);") < opened  # after the scene
    assert opened < text.index("window.clikSceneReady = true")


@pytest.mark.browser
def test_the_play_controls_are_visible_in_the_browser(browser, planar_run, tmp_path):  # noqa: F811
    path = export_html(planar_run, tmp_path / "scene.html")
    page = browser.new_page(viewport={"width": 1024, "height": 768})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.goto(path.as_uri())
    page.wait_for_function("window.clikSceneReady === true", timeout=30_000)
    state = page.evaluate(
        "() => ({gui: viewer.gui.closed, animations: viewer.animator.folder.closed})"
    )
    assert state == {"gui": False, "animations": False}
    play = page.get_by_text("play", exact=True)
    assert play.count() >= 1 and play.first.is_visible()
    assert page.get_by_text("Open Controls", exact=True).count() == 0
    assert errors == []
    page.close()
