"""clik.viz without a browser: scene contents, HTML files, the loopback-only live server.

The browser checks (what the scenes look like) are in ``test_browser.py``.
"""

from __future__ import annotations

import base64
import copy
import itertools
import json
import re
import subprocess
import sys
import time
import warnings
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import psutil
import pytest
import umsgpack

import clik
from clik.constraints.constraint_set import ConstraintSet
from clik.constraints.obstacle import Obstacle
from clik.errors import InputError
from clik.model.robot import PANDA_FINGERS
from clik.outputs.result import TrackingResult, write_outputs
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.trajectory import Circle
from clik.viz import build_scene, export_html, live, show, show_path, stop_server
from clik.viz.server import LOOPBACK, MeshcatServer
from clik.viz.timeline import Timeline
from tests.limits_check import assert_within_limits

MAX_HTML_BYTES = 5_000_000
"""The issue's budget for one exported scene (Panda, 3 s run)."""


def panda_run() -> TrackingResult:
    """A 3 s Panda position task along a circle, with an obstacle that activates rows.

    (A pose task cannot keep the fingers, rigid on the hand, off the ball: that run ends
    in a deadlock, the task and the constraint in conflict.)
    """
    robot = clik.Robot.load("panda", lock=PANDA_FINGERS)
    task = clik.Task(robot, "panda_hand", "position")
    q0 = robot.q_reference
    start = task.placement(q0)
    p0 = start.translation
    trajectory = Circle.through(p0, p0 + [0.0, 0.12, 0.0], [1.0, 0.0, 0.0], 2 * np.pi, duration=3.0)
    ball = Obstacle("ball", "sphere", p0 + [0.1, 0.06, -0.2], radius=0.05, threshold=0.05)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        constraints = ConstraintSet(robot, obstacles=[ball], obstacle_threshold=0.05)
    return clik.track(
        task, trajectory, q0=q0, law="pseudoinverse", gain=100.0, constraints=constraints
    )


@pytest.fixture(scope="module")
def case_study() -> TrackingResult:
    """Case study 4 (both constraints): a joint-range row and an obstacle row activate."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return build(scenario_path("case_study_both")).execute()


@pytest.fixture(scope="module")
def panda_result() -> TrackingResult:
    return panda_run()


def html_commands(path: Path) -> list[dict]:
    """The viewer commands embedded in an exported page, decoded."""
    text = path.read_text(encoding="utf-8")
    match = re.search(r"var commands = (\[.*?\]);", text, re.S)
    assert match, "no command list in the page"
    return [umsgpack.unpackb(base64.b64decode(s)) for s in json.loads(match.group(1))]


def set_object_paths(commands: list[dict]) -> set[str]:
    return {c["path"] for c in commands if c["type"] == "set_object"}


def animated_paths(commands: list[dict]) -> dict[str, list[str]]:
    (animation,) = [c for c in commands if c["type"] == "set_animation"]
    return {a["path"]: [t["name"] for t in a["clip"]["tracks"]] for a in animation["animations"]}


class TestExportHtml:
    def test_case_study_scene_is_complete(self, case_study, tmp_path):
        path = export_html(case_study, tmp_path / "scene.html")
        size = path.stat().st_size
        assert size < MAX_HTML_BYTES
        text = path.read_text(encoding="utf-8")
        assert "<script src" not in text and "viewer.connect" not in text  # no server, no files
        commands = html_commands(path)
        objects = set_object_paths(commands)
        for joint in ("joint1", "joint2", "joint3", "joint4"):
            assert any(p.startswith(f"/meshcat/robot/{joint}/") for p in objects), joint
        assert {
            "/meshcat/obstacles/pin/body",
            "/meshcat/obstacles/pin/shell",
            "/meshcat/paths/reference",
        } <= objects
        assert "/meshcat/witness/obstacle-pin-link4" in objects  # the active obstacle row
        tracks = animated_paths(commands)
        for joint in ("joint1", "joint2", "joint3", "joint4"):
            assert tracks[f"/meshcat/robot/{joint}"] == [".position", ".quaternion"]
        # joint3's upper-limit row was active: its links change colour.
        assert any(
            p.startswith("/meshcat/robot/joint3/") and names == [".material.color"]
            for p, names in tracks.items()
        )
        assert ".visible" in tracks["/meshcat/witness/obstacle-pin-link4"]
        (animation,) = [c for c in commands if c["type"] == "set_animation"]
        assert animation["options"]["play"] is True
        assert animation["options"]["repetitions"] > 1000  # loops (0 breaks meshcat 0.3.2)

    def test_panda_visual_html_is_under_budget(self, panda_result, tmp_path):
        assert panda_result.status == "completed"
        assert_within_limits(panda_result, panda_result.robot, obstacle_floor=0.05 - 1e-3)
        visual = export_html(panda_result, tmp_path / "visual.html")
        collision = export_html(panda_result, tmp_path / "collision.html", geometry="collision")
        print(
            f"Panda 3 s: visual {visual.stat().st_size / 1e6:.2f} MB, "
            f"collision {collision.stat().st_size / 1e6:.2f} MB"
        )
        assert visual.stat().st_size < MAX_HTML_BYTES
        assert collision.stat().st_size < visual.stat().st_size
        objects = set_object_paths(html_commands(visual))
        for k in range(1, 8):
            assert any(p.startswith(f"/meshcat/robot/panda_joint{k}/") for p in objects)
        assert "/meshcat/obstacles/ball/body" in objects

    def test_write_is_atomic_and_replaces(self, case_study, tmp_path):
        target = tmp_path / "sub" / "scene.html"
        export_html(case_study, target)
        first = target.stat().st_mtime_ns
        export_html(case_study, target, fps=10)
        assert target.stat().st_mtime_ns >= first
        assert [p.name for p in target.parent.iterdir()] == ["scene.html"]  # no temp file left

    def test_fewer_frames_make_a_smaller_file(self, case_study, tmp_path):
        dense = export_html(case_study, tmp_path / "a.html", fps=60)
        sparse = export_html(case_study, tmp_path / "b.html", fps=10)
        assert sparse.stat().st_size < dense.stat().st_size

    def test_saved_result_needs_its_robot(self, case_study, tmp_path):
        case_study.save(tmp_path / "trajectory.npz")
        loaded = TrackingResult.load(tmp_path / "trajectory.npz")
        with pytest.raises(InputError, match="robot"):
            export_html(loaded, tmp_path / "x.html")
        assert not (tmp_path / "x.html").exists()
        export_html(loaded, tmp_path / "x.html", robot=case_study.robot)
        assert (tmp_path / "x.html").is_file()

    def test_bad_options(self, case_study, tmp_path):
        with pytest.raises(InputError, match="geometry"):
            export_html(case_study, tmp_path / "x.html", geometry="meshes")
        with pytest.raises(InputError, match="fps"):
            export_html(case_study, tmp_path / "x.html", fps=0)
        other = clik.Robot.load("ur5")
        with pytest.raises(InputError, match=r"result\.q"):
            export_html(case_study, tmp_path / "x.html", robot=other)


class TestScene:
    def test_moving_obstacle_is_animated(self, case_study):
        moving = copy.copy(case_study)
        moving.info = copy.deepcopy(case_study.info)
        moving.info["obstacles"][0]["velocity"] = [0.0, 0.02, 0.0]
        commands = build_scene(moving).commands
        tracks = animated_paths(commands)
        assert tracks["/meshcat/obstacles/pin"] == [".position"]
        assert "/meshcat/obstacles/pin" not in animated_paths(build_scene(case_study).commands)

    def test_workspace_box_and_tool_cone_are_drawn(self):
        """The regions of the kinds (info["shapes"]): the box's walls and edges and its
        threshold; the cone, whose apex follows its frame's origin along the animation."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = build(scenario_path("panda_cup_upright")).execute()
        commands = build_scene(result, geometry="collision").commands
        objects = set_object_paths(commands)
        assert {
            "/meshcat/regions/workspace:table/walls",
            "/meshcat/regions/workspace:table/edges",
            "/meshcat/regions/workspace:table/threshold",
            "/meshcat/regions/cone:cup/cone",
        } <= objects
        tracks = animated_paths(commands)
        assert tracks["/meshcat/regions/cone:cup"] == [".position"]
        assert "/meshcat/regions/workspace:table" not in tracks

    def test_regions_are_drawn_where_the_kinds_say(self):
        """The box's walls are its faces (its area) and its edges its 12 sides; the cone's
        rim is at its half-angle from the direction, its apex on the frame's origin."""
        from clik.constraints.cone import DRAWN_LENGTH, Cone
        from clik.constraints.region import Lines, Surface
        from clik.constraints.workspace import Workspace

        lower, upper = np.array([-0.1, 0.0, 0.2]), np.array([0.3, 0.5, 0.4])
        box = Workspace.region({"name": "workspace:b", "lower": lower, "upper": upper,
                                "threshold": 0.05})  # fmt: skip
        walls, edges, inner = box.parts
        assert isinstance(walls, Surface) and isinstance(edges, Lines) and box.follows is None
        a, b, c = (walls.vertices[walls.triangles[:, i]] for i in range(3))
        area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1).sum()
        x, y, z = upper - lower
        assert area == pytest.approx(2 * (x * y + y * z + z * x))
        sides = np.linalg.norm(edges.points[1::2] - edges.points[::2], axis=1)
        assert sorted(sides) == pytest.approx(sorted([x, y, z] * 4))
        assert inner.name == "threshold" and inner.points.min(axis=0) == pytest.approx(lower + 0.05)
        u = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)
        cone = Cone.region({"name": "cone:c", "frame": "tip", "direction": u.tolist(),
                            "angle": 0.4})  # fmt: skip
        (surface,) = cone.parts
        assert cone.follows == "tip" and surface.smooth
        np.testing.assert_allclose(surface.vertices[0], 0.0)
        rim = surface.vertices[1:]
        np.testing.assert_allclose(rim @ u, DRAWN_LENGTH)
        np.testing.assert_allclose(np.arccos(rim @ u / np.linalg.norm(rim, axis=1)), 0.4)

    def test_timeline_is_real_time_and_ends_on_the_last_sample(self):
        t = np.arange(3001) * 1e-3
        timeline = Timeline.from_times(t, 30)
        assert len(timeline) == 91
        assert timeline.times[-1] == pytest.approx(3.0)
        assert timeline.index[-1] == 3000
        np.testing.assert_allclose(t[timeline.index], timeline.times, atol=5e-4)
        odd = Timeline.from_times(np.linspace(0.0, 1.01, 102), 10)
        assert odd.times[-1] == pytest.approx(1.01) and odd.index[-1] == 101

    def test_planar_arm_is_seen_from_above(self, case_study):
        view = build_scene(case_study).view
        assert view.planar
        assert view.offset[2] > 0 and np.linalg.norm(view.offset[:2]) < 1e-2 * view.offset[2]

    def test_spatial_arm_gets_a_three_quarter_view(self, panda_result):
        view = build_scene(panda_result, geometry="collision").view
        assert not view.planar
        assert np.all(np.abs(view.offset) > 0.1)


def cielab(rgb) -> np.ndarray:
    """CIELAB (D65) of an sRGB colour in [0, 1]."""
    c = np.asarray(rgb, dtype=float)
    c = np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)
    xyz = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = (xyz @ c) / [0.95047, 1.0, 1.08883]
    f = np.where(xyz > (6 / 29) ** 3, np.cbrt(xyz), xyz / (3 * (6 / 29) ** 2) + 4 / 29)
    return np.array([116 * f[1] - 16, 500 * (f[0] - f[1]), 200 * (f[1] - f[2])])


MIN_DELTA_E = 25.0
"""Smallest CIELAB distance between two legend colours (about 2.3 is just noticeable)."""


class TestLegend:
    def test_legend_colours_are_pairwise_distinct(self):
        from clik.viz import palette

        colours = [tuple(c) for c, _ in palette.LEGEND]
        assert len(set(colours)) == len(colours)
        labels = [label for _, label in palette.LEGEND]
        assert len(set(labels)) == len(labels)
        for (a, la), (b, lb) in itertools.combinations(palette.LEGEND, 2):
            gap = float(np.linalg.norm(cielab(a) - cielab(b)))
            assert gap >= MIN_DELTA_E, f"{la!r} and {lb!r} look alike (Delta E {gap:.1f})"
        for colour, label in palette.LEGEND:
            for background in (palette.BACKGROUND_TOP, palette.BACKGROUND_BOTTOM):
                gap = float(np.linalg.norm(cielab(colour) - cielab(background)))
                assert gap >= MIN_DELTA_E, f"{label!r} fades into the background"

    def test_every_scene_colour_has_its_own_legend_entry(self):
        from clik.viz import palette

        drawn = {
            palette.REFERENCE,
            palette.TRAIL,
            palette.OBSTACLE,
            palette.OBSTACLE_SHELL,
            palette.ROW_ACTIVE,
            palette.MONITOR_NEAR,
            palette.REGION,
            palette.MONITOR_CLEAR,
            palette.JOINT_LIMIT_ACTIVE,
            palette.JOINT_LIMIT_NEAR,
        }
        assert drawn == {tuple(c) for c, _ in palette.LEGEND}

    def test_shell_and_body_differ_in_the_page_and_its_caption(self, case_study, tmp_path):
        from clik.viz import palette
        from clik.viz.commands import color_int

        path = export_html(case_study, tmp_path / "scene.html")
        materials = {
            c["path"]: c["object"]["materials"][0]["color"]
            for c in html_commands(path)
            if c["type"] == "set_object" and c["path"].startswith("/meshcat/obstacles/pin/")
        }
        assert materials["/meshcat/obstacles/pin/body"] == color_int(palette.OBSTACLE)
        assert materials["/meshcat/obstacles/pin/shell"] == color_int(palette.OBSTACLE_SHELL)
        text = path.read_text(encoding="utf-8")
        swatches = re.findall(r'<span style="background:#([0-9a-f]{6})"></span>', text)
        assert swatches == [f"{color_int(c):06x}" for c, _ in palette.LEGEND]


def listening(pid: int) -> list[tuple[str, int]]:
    """(address, port) of the TCP sockets process ``pid`` listens on."""
    return [
        (c.laddr.ip, c.laddr.port)
        for c in psutil.Process(pid).net_connections("tcp")
        if c.status == psutil.CONN_LISTEN
    ]


def all_listeners() -> list[tuple[str, int]]:
    """Every listening TCP socket of the machine, from /proc (IPv4 and IPv6)."""
    found = []
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            if state == "0A":  # LISTEN
                address, port = local.split(":")
                found.append((address, int(port, 16)))
    return found


class TestLiveServer:
    def test_listens_on_loopback_only_and_stops(self):
        server = MeshcatServer.start()
        try:
            sockets = listening(server.pid)
            assert len(sockets) == 2  # ZMQ commands and HTTP/websocket
            assert all(address == LOOPBACK for address, _ in sockets), sockets
            ports = {port for _, port in sockets}
            assert str(ports.pop()) in server.zmq_url + server.web_url
            # No wildcard (0.0.0.0 or ::) listener on those ports, IPv4 or IPv6.
            wildcard = {"00000000", "00000000000000000000000000000000"}
            assert not [
                (a, p)
                for a, p in all_listeners()
                if p in {port for _, port in sockets} and a in wildcard
            ]
        finally:
            server.stop()
        assert not server.alive

    def test_server_exits_with_its_parent(self):
        code = (
            "from clik.viz.server import MeshcatServer; import os; "
            "s = MeshcatServer.start(); print(s.pid, flush=True); os._exit(0)"
        )
        out = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True
        ).stdout
        pid = int(out.split()[-1])
        deadline = time.monotonic() + 10
        while psutil.pid_exists(pid) and psutil.Process(pid).status() != psutil.STATUS_ZOMBIE:
            assert time.monotonic() < deadline, "the orphaned server is still running"
            time.sleep(0.2)

    def test_show_starts_then_reuses_one_server(self, case_study, capsys):
        try:
            url = show(case_study)
            server = live._server
            assert server is not None and server.alive
            assert url.startswith(f"http://{LOOPBACK}:") and url in capsys.readouterr().out
            assert show(case_study, geometry="collision") == url
            assert live._server is server
            assert all(address == LOOPBACK for address, _ in listening(server.pid))
        finally:
            stop_server()
        assert not server.alive

    def test_inline_view_for_notebooks(self, case_study, monkeypatch):
        import IPython.display

        shown = []
        monkeypatch.setattr(IPython.display, "display", shown.append)
        try:
            show(case_study, inline=True)
        finally:
            stop_server()
        (widget,) = shown
        assert "<iframe srcdoc=" in widget.data and "clikSceneReady" in widget.data


class TestShowPath:
    def test_output_folder_of_a_shipped_scenario(self, case_study, tmp_path, monkeypatch):
        write_outputs(case_study, tmp_path)
        sent = []
        monkeypatch.setattr(live, "show", lambda result, **kw: sent.append(result) or "url")
        assert show_path(tmp_path, block=False) == "url"
        (result,) = sent
        assert result.robot.name == "planar4r" and result.robot.nq == 4
        np.testing.assert_array_equal(result.q, case_study.q)

    def test_scenario_file_is_run(self, monkeypatch):
        sent = []
        monkeypatch.setattr(live, "show", lambda result, **kw: sent.append(result) or "url")
        show_path(scenario_path("case_study_obstacle"), block=False)
        assert sent[0].robot is not None and sent[0].status == "completed"

    def test_folder_without_the_robot_lock_says_what_is_missing(self, panda_result, tmp_path):
        write_outputs(panda_result, tmp_path)  # run from the API: no scenario, fingers locked
        with pytest.raises(InputError, match="robot_lock"):
            show_path(tmp_path, block=False)

    def test_not_a_target(self, tmp_path):
        with pytest.raises(InputError, match=r"trajectory\.npz"):
            show_path(tmp_path, block=False)

    def test_block_returns_on_ctrl_c_and_stops_the_server(self, monkeypatch):
        def interrupt(seconds: float) -> None:
            raise KeyboardInterrupt

        monkeypatch.setattr(live, "time", SimpleNamespace(sleep=interrupt))
        show_path(scenario_path("case_study_obstacle"))
        assert live._server is None
