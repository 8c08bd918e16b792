"""Hostile files: nothing outside the user's files is read, nothing is fetched or expanded.

A secret file is planted next to the inputs, with a content no other file
holds. Hostile URDFs point at it (XML external entities, absolute and
relative; parameter entities; external DTDs; XInclude; package paths leaving
their package) or at a loopback port (network entities, DTDs and meshes), or
try to expand without bound (entity bombs). Each is loaded with
``Robot.load`` and with the command line in a new process, and the tests
check that

- the load fails with a :class:`clik.RobotLoadError` (exit code 2 for the
  command), quickly;
- the secret's content appears nowhere: not in the exception, not on stdout
  or stderr (C++ output included), not in any file written;
- the secret file is never opened (Linux inotify watches it, across
  processes) and the loopback port never sees a connection.

Scenario files are data only: TOML has no code, no includes, no variables.
Strings that look like code or shell are just strings (rejected where a name
or a choice is expected, kept as text in ``name``); include-like keys are
unknown keys. Paths in a scenario (``robot.source``, an obstacle's mesh
``file``) are the user's own choice and may point anywhere, absolute or
relative to the scenario's folder; what clik guarantees is that it never
echoes the content of a file it cannot use, and never fetches a URL.
"""

from __future__ import annotations

import ctypes
import json
import os
import socket
import subprocess
import sys
import time
import uuid
import zipfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from clik import ClikError, GeometryError, RobotLoadError, ScenarioError
from clik.constraints import Obstacle
from clik.model.robot import Robot
from clik.scenarios import scenario_path
from clik.scenarios.runner import build
from clik.scenarios.scenario import load_scenario

SECRET = f"CLIK-PLANTED-{uuid.uuid4().hex}"
"""Content of the planted file: appears in no other file."""

CASE = scenario_path("case_study_unconstrained").read_text()
SHORT = CASE.replace(
    "goal = [0.8, -0.2, 0.0]\nduration = 3.0\ncruise_speed = 0.12",
    "goal = [0.57, -0.16, 0.0]\nduration = 0.3",
)
"""The case study's scenario cut to a 0.3 s run."""
LOAD_SECONDS = 1.0  # a refused file is refused at once: nothing is expanded

BODY = (
    '<link name="base"/><link name="l1"/>'
    '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
    '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)


# ---------------------------------------------------------------- watchers


class OpenWatch:
    """Counts the times a file is opened or read, by any process (Linux inotify)."""

    IN_ACCESS, IN_OPEN, IN_NONBLOCK = 0x1, 0x20, 0o4000

    def __init__(self, path: Path) -> None:
        libc = ctypes.CDLL(None, use_errno=True)
        self.fd = libc.inotify_init1(self.IN_NONBLOCK)
        if self.fd < 0:
            pytest.skip("inotify is not available")
        if libc.inotify_add_watch(self.fd, os.fsencode(path), self.IN_OPEN | self.IN_ACCESS) < 0:
            pytest.skip("inotify cannot watch the planted file")

    def events(self) -> int:
        count = 0
        while True:
            try:
                data = os.read(self.fd, 65536)
            except BlockingIOError:
                return count
            count += len(data) // 16  # struct inotify_event without a name: 16 bytes

    def close(self) -> None:
        os.close(self.fd)


class Listener:
    """A loopback TCP port that records whether anyone connected to it."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.sock.setblocking(False)
        self.port = self.sock.getsockname()[1]

    def connections(self) -> int:
        count = 0
        while True:
            try:
                conn, _ = self.sock.accept()
            except BlockingIOError:
                return count
            conn.close()
            count += 1

    def close(self) -> None:
        self.sock.close()


class Planted:
    """The planted secret, its watcher and a loopback port."""

    def __init__(self, root: Path) -> None:
        self.root = root
        self.private = root / "private"
        self.private.mkdir()
        self.secret = self.private / "secret.txt"
        self.secret.write_text(f"{SECRET}\n0 0 0 1 0 0 0 1 0 0 0 1\n", encoding="utf-8")
        self.inputs = root / "inputs"
        self.inputs.mkdir()
        self.watch = OpenWatch(self.secret)
        self.listener = Listener()

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.listener.port}"

    def write(self, name: str, data: str | bytes) -> Path:
        path = self.inputs / name
        if isinstance(data, str):
            data = data.encode("utf-8")
        path.write_bytes(data)
        return path

    def assert_untouched(self) -> None:
        assert self.watch.events() == 0, "the planted file was opened"
        assert self.listener.connections() == 0, "something connected to the network"

    def assert_no_leak(self, *texts: str) -> None:
        """The secret is in none of ``texts`` nor in any file under the test folder."""
        for text in texts:
            assert SECRET not in text
        for path in self.root.rglob("*"):
            if path.is_file() and path != self.secret:
                assert SECRET.encode() not in path.read_bytes(), path
                if path.suffix == ".npz":
                    with zipfile.ZipFile(path) as archive:
                        for member in archive.namelist():
                            assert SECRET.encode() not in archive.read(member), (path, member)


@pytest.fixture
def planted(tmp_path) -> Iterator[Planted]:
    if not sys.platform.startswith("linux"):
        pytest.skip("the open watch uses Linux inotify")
    planted = Planted(tmp_path)
    yield planted
    planted.watch.close()
    planted.listener.close()


def test_the_watchers_see_a_read_and_a_connection(planted):
    """The control for every test below: a read of the secret and a connection are seen."""
    planted.assert_untouched()
    assert SECRET in planted.secret.read_text(encoding="utf-8")
    with socket.create_connection(("127.0.0.1", planted.listener.port), timeout=1.0):
        pass
    time.sleep(0.05)
    assert planted.watch.events() > 0
    assert planted.listener.connections() == 1
    with pytest.raises(AssertionError):
        planted.assert_no_leak(SECRET)


# ---------------------------------------------------------------- hostile URDFs


def doc(doctype: str, body: str = BODY, root: str = '<robot name="r">') -> str:
    return f'<?xml version="1.0"?>\n{doctype}\n{root}{body}</robot>\n'


def billion_laughs() -> str:
    entities = "".join(f'<!ENTITY l{i} "{f"&l{i - 1};" * 10}">' for i in range(1, 10))
    return doc(f'<!DOCTYPE robot [<!ENTITY l0 "lol">{entities}]>', root='<robot name="&l9;">')


def dae_with_entity(target: str) -> str:
    """A COLLADA tetrahedron whose vertex array is an external entity."""
    return f"""<?xml version="1.0" encoding="utf-8"?>
<!DOCTYPE COLLADA [<!ENTITY xxe SYSTEM "{target}">]>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="12">&xxe;</float_array>
      <technique_common><accessor source="#pa" count="4" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="4"><input semantic="VERTEX" source="#v" offset="0"/>
      <p>0 2 1 0 1 3 0 3 2 1 2 3</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
"""


def with_mesh(filename: str) -> str:
    geometry = f'<geometry><mesh filename="{filename}"/></geometry>'
    link = f'<link name="l1"><collision>{geometry}</collision></link>'
    return doc("", BODY.replace('<link name="l1"/>', link))


HOSTILE: dict[str, tuple[Callable[[Planted], str | bytes], str]] = {
    "xxe-absolute-in-attribute": (
        lambda p: doc(
            f'<!DOCTYPE robot [<!ENTITY xxe SYSTEM "file://{p.secret}">]>',
            root='<robot name="&xxe;">',
        ),
        "declares XML entities",
    ),
    "xxe-relative-in-text": (
        lambda p: doc(
            '<!DOCTYPE robot [<!ENTITY xxe SYSTEM "../private/secret.txt">]>',
            BODY + "<description>&xxe;</description>",
        ),
        "declares XML entities",
    ),
    "xxe-parameter-entity": (
        lambda p: doc(f'<!DOCTYPE robot [<!ENTITY % p SYSTEM "file://{p.secret}"> %p;]>'),
        "declares XML entities",
    ),
    "xxe-utf16": (
        lambda p: (
            doc(
                f'<!DOCTYPE robot [<!ENTITY xxe SYSTEM "file://{p.secret}">]>',
                BODY + "<description>&xxe;</description>",
            )
            .replace('version="1.0"?>', 'version="1.0" encoding="UTF-16"?>')
            .encode("utf-16")
        ),
        "cannot load robot",
    ),
    "external-dtd-file": (
        lambda p: doc(f'<!DOCTYPE robot SYSTEM "file://{p.secret}">'),
        "refers to an external DTD",
    ),
    "external-dtd-network": (
        lambda p: doc(f'<!DOCTYPE robot SYSTEM "{p.url}/robot.dtd">'),
        "refers to an external DTD",
    ),
    "public-dtd-network": (
        lambda p: doc(f'<!DOCTYPE robot PUBLIC "-//clik//robot//EN" "{p.url}/robot.dtd">'),
        "refers to an external DTD",
    ),
    "network-entity": (
        lambda p: doc(
            f'<!DOCTYPE robot [<!ENTITY net SYSTEM "{p.url}/x">]>', root='<robot name="&net;">'
        ),
        "declares XML entities",
    ),
    "billion-laughs": (lambda p: billion_laughs(), "declares XML entities"),
    "quadratic-blowup": (
        lambda p: doc(
            f'<!DOCTYPE robot [<!ENTITY a "{"a" * 50_000}">]>',
            BODY + "<description>" + "&a;" * 50_000 + "</description>",
        ),
        "declares XML entities",
    ),
    "xinclude-file": (
        lambda p: doc(
            "",
            BODY + f'<xi:include href="file://{p.secret}" parse="text"/>',
            root='<robot name="r" xmlns:xi="http://www.w3.org/2001/XInclude">',
        ),
        "XInclude elements are refused",
    ),
    "xinclude-network": (
        lambda p: doc(
            "",
            BODY + f'<xi:include href="{p.url}/x.xml"/>',
            root='<robot name="r" xmlns:xi="http://www.w3.org/2001/XInclude">',
        ),
        "XInclude elements are refused",
    ),
    "mesh-network": (lambda p: with_mesh(f"{p.url}/l1.stl"), "unsupported URI scheme"),
    "mesh-package-escape": (
        lambda p: with_mesh("package://inputs/../private/secret.txt"),
        "leaves its package folder",
    ),
    "mesh-collada-xxe": (
        lambda p: with_mesh(str(p.write("l1.dae", dae_with_entity(f"file://{p.secret}")))),
        "Pinocchio cannot build the model",
    ),
}


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_urdf_is_refused_by_robot_load(planted, capfd, name):
    make, words = HOSTILE[name]
    urdf = planted.write("hostile.urdf", make(planted))
    start = time.perf_counter()
    with pytest.raises(RobotLoadError) as caught:
        Robot.load(urdf, package_dirs=[planted.root])
    assert time.perf_counter() - start < LOAD_SECONDS
    assert words in str(caught.value)
    captured = capfd.readouterr()
    planted.assert_no_leak(str(caught.value), repr(caught.value), captured.out, captured.err)
    planted.assert_untouched()


def run_cli(planted: Planted, scenario: Path, *extra: str) -> subprocess.CompletedProcess:
    out = planted.root / "out"
    return subprocess.run(
        [sys.executable, "-m", "clik.cli", "solve", str(scenario), "--out", str(out), *extra],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
        cwd=planted.inputs,
    )


@pytest.mark.parametrize("name", HOSTILE)
def test_hostile_urdf_is_refused_by_the_command_line(planted, name):
    make, words = HOSTILE[name]
    planted.write("hostile.urdf", make(planted))
    text = CASE.replace('source = "planar4r"', 'source = "hostile.urdf"')
    text = text.replace("[robot]\n", '[robot]\npackage_dirs = [".."]\n')
    scenario = planted.write("scenario.toml", text)
    proc = run_cli(planted, scenario, "--html", "--plots")
    assert proc.returncode == 2, proc.stderr
    assert "robot.source" in proc.stderr and words in proc.stderr
    assert "Traceback" not in proc.stderr
    planted.assert_no_leak(proc.stdout, proc.stderr)
    planted.assert_untouched()


def test_a_good_run_next_to_the_planted_file_writes_no_trace_of_it(planted):
    """The control: a run that succeeds, with every output, never touches the secret."""
    scenario = planted.write("scenario.toml", SHORT)
    proc = run_cli(planted, scenario, "--html", "--plots")
    assert proc.returncode == 0, proc.stderr
    assert (planted.root / "out" / "summary.json").is_file()
    planted.assert_no_leak(proc.stdout, proc.stderr)
    planted.assert_untouched()


# ---------------------------------------------------------------- meshes the user names


def test_obstacle_mesh_with_an_external_entity_is_not_expanded(planted, capfd):
    mesh = planted.write("obstacle.dae", dae_with_entity(f"file://{planted.secret}"))
    with pytest.raises(GeometryError) as caught:
        Obstacle("m", "mesh", [0.5, 0.0, 0.0], file=mesh)
    captured = capfd.readouterr()
    planted.assert_no_leak(str(caught.value), captured.out, captured.err)
    planted.assert_untouched()


def test_a_file_that_is_not_a_mesh_is_not_echoed(planted, capfd):
    """An obstacle mesh or a robot source pointing at any file: refused, content never shown."""
    with pytest.raises(GeometryError, match=r"has format '\.txt'"):  # refused unread
        Obstacle("m", "mesh", [0.5, 0.0, 0.0], file=planted.secret)
    with pytest.raises(RobotLoadError, match="malformed XML") as caught:
        Robot.load(planted.secret)
    captured = capfd.readouterr()
    planted.assert_no_leak(str(caught.value), captured.out, captured.err)


# ---------------------------------------------------------------- scenarios are data


CODE_LIKE = [
    "__import__('os').system('touch PWNED')",
    "$(touch PWNED)",
    "`touch PWNED`",
    "{{ cycler.__init__.__globals__.os.popen('touch PWNED') }}",
    "%(PWNED)s; touch PWNED",
]


@pytest.mark.parametrize(
    ("old", "key"),
    [
        ('law = "transpose"', "solver.law"),
        ('kind = "line"', "trajectory.kind"),
        ('frame = "tip"', "task.frame"),
        ('source = "planar4r"', "robot.source"),
        ('unit = "deg"', "initial.unit"),
    ],
)
@pytest.mark.parametrize("payload", CODE_LIKE)
def test_code_in_a_string_is_only_a_string(tmp_path, monkeypatch, old, key, payload):
    monkeypatch.chdir(tmp_path)
    name = old.split(" = ")[0]
    text = CASE.replace(old, f"{name} = {json.dumps(payload)}", 1)  # a TOML basic string
    scenario = tmp_path / "s.toml"
    scenario.write_text(text)
    with pytest.raises(ScenarioError) as caught:
        build(scenario)
    assert f": {key}: " in str(caught.value)
    assert not (tmp_path / "PWNED").exists()


def test_a_name_that_looks_like_code_is_kept_as_text(tmp_path):
    payload = "$(touch PWNED); __import__('os').system('touch PWNED')"
    text = SHORT.replace('name = "', f"name = {json.dumps(payload)}\n# was: ", 1)
    scenario = tmp_path / "s.toml"
    scenario.write_text(text)
    proc = subprocess.run(
        [sys.executable, "-m", "clik.cli", "solve", str(scenario), "--out", str(tmp_path / "o")],
        capture_output=True,
        text=True,
        check=False,
        timeout=120,
        cwd=tmp_path,
    )
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.startswith(payload + ": completed")
    assert not (tmp_path / "PWNED").exists()


@pytest.mark.parametrize(
    ("old", "new", "key"),
    [
        ('name = "', 'include = "other.toml"\nname = "', "include"),
        ('name = "', 'import = ["os"]\nname = "', "import"),
        ('name = "', '"!include" = "/etc/passwd"\nname = "', "!include"),
        ('source = "planar4r"', 'source = "planar4r"\nextends = "base.toml"', "robot.extends"),
        ("[solver]", '[solver]\nexec = "print(1)"', "solver.exec"),
    ],
)
def test_include_like_keys_are_unknown_keys(tmp_path, old, new, key):
    scenario = tmp_path / "s.toml"
    scenario.write_text(CASE.replace(old, new, 1))
    with pytest.raises(ScenarioError) as caught:
        load_scenario(scenario)
    assert f": {key}: unknown key; valid keys here: " in str(caught.value)


def test_paths_in_a_scenario_are_the_users_choice(tmp_path):
    """Absolute or relative, inside the scenario's folder or not: a path is used as given."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    from clik.model.planar_arm import write_planar_arm

    urdf = write_planar_arm(elsewhere / "arm.urdf", [0.3] * 4)
    v = 0.02 * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    faces = [(1, 3, 5), (3, 2, 5), (2, 4, 5), (4, 1, 5), (3, 1, 6), (2, 3, 6), (4, 2, 6), (1, 4, 6)]
    mesh = elsewhere / "m.obj"
    mesh.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in v)
        + "".join(f"f {a} {b} {c}\n" for a, b, c in faces)
    )
    folder = tmp_path / "scenarios"
    folder.mkdir()
    text = CASE.replace('source = "planar4r"', f'source = "{urdf}"')
    text += '\n[[obstacles]]\nname = "m"\nshape = "mesh"\nfile = "../elsewhere/m.obj"\n'
    text += "position = [2, 2, 0]\n"
    scenario = folder / "s.toml"
    scenario.write_text(text)
    run = build(scenario)
    assert run.robot.source_path == urdf
    mesh_obstacle = run.tracker.constraints.obstacles[1]
    assert mesh_obstacle.params["file"] == str(folder / "../elsewhere/m.obj")


def test_a_robot_url_is_refused_without_a_connection(tmp_path):
    listener = Listener()
    try:
        text = CASE.replace(
            'source = "planar4r"', f'source = "http://127.0.0.1:{listener.port}/r.urdf"'
        )
        scenario = tmp_path / "s.toml"
        scenario.write_text(text)
        with pytest.raises(ClikError, match="URLs are not fetched"):
            build(scenario)
        with pytest.raises(ClikError):
            Robot.load(f"http://127.0.0.1:{listener.port}/r.urdf")
        assert listener.connections() == 0
    finally:
        listener.close()


# ---------------------------------------------------------------- mesh side files and symlinks


OBJ_TETRAHEDRON = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


def test_an_obstacle_obj_is_read_without_its_material_file(planted, capfd):
    """``mtllib`` pointing at the secret: the loader gets a copy without it, reads nothing else."""
    mtl = os.path.relpath(planted.secret, planted.inputs)
    mesh = planted.write("m.obj", f"mtllib {mtl}\nusemtl secret\n{OBJ_TETRAHEDRON}")
    obstacle = Obstacle("m", "mesh", [0.5, 0.0, 0.0], file=mesh)
    assert obstacle.bounding_radius == pytest.approx(0.1)
    captured = capfd.readouterr()
    planted.assert_no_leak(captured.out, captured.err)
    planted.assert_untouched()


def test_a_urdf_obj_naming_a_material_file_outside_its_package_is_refused(planted, capfd):
    package = planted.inputs / "pkg"
    package.mkdir()
    mtl = os.path.relpath(planted.secret, package)
    (package / "m.obj").write_text(f"mtllib {mtl}\n{OBJ_TETRAHEDRON}")
    urdf = planted.write("r.urdf", with_mesh("package://pkg/m.obj"))
    with pytest.raises(RobotLoadError, match="material file") as caught:
        Robot.load(urdf, package_dirs=[planted.inputs])
    assert "leaves the folder" in str(caught.value)
    captured = capfd.readouterr()
    planted.assert_no_leak(str(caught.value), captured.out, captured.err)
    planted.assert_untouched()


def test_mesh_symlinks_leaving_their_folder_are_refused(planted, capfd):
    """A mesh in a package (or next to a scenario) that links to a file outside it."""
    package = planted.inputs / "pkg"
    package.mkdir()
    (package / "m.stl").symlink_to(planted.secret)
    (planted.inputs / "obstacle.stl").symlink_to(planted.secret)
    urdf = planted.write("r.urdf", with_mesh("package://pkg/m.stl"))
    with pytest.raises(RobotLoadError, match="which leaves its folder") as in_urdf:
        Robot.load(urdf, package_dirs=[planted.inputs])
    with pytest.raises(GeometryError, match="which leaves its folder") as in_scenario:
        Obstacle("m", "mesh", [0.5, 0.0, 0.0], file=planted.inputs / "obstacle.stl")
    captured = capfd.readouterr()
    planted.assert_untouched()
    (package / "m.stl").unlink()  # the leak check reads every file under the test folder
    (planted.inputs / "obstacle.stl").unlink()
    planted.assert_no_leak(str(in_urdf.value), str(in_scenario.value), captured.out, captured.err)


def test_a_symlinked_mesh_inside_its_package_is_read(planted):
    """The control: a symlink that stays inside the package is followed."""
    package = planted.inputs / "pkg"
    (package / "meshes").mkdir(parents=True)
    (package / "meshes" / "real.obj").write_text(OBJ_TETRAHEDRON)
    (package / "m.obj").symlink_to(package / "meshes" / "real.obj")
    urdf = planted.write("r.urdf", with_mesh("package://pkg/m.obj"))
    robot = Robot.load(urdf, package_dirs=[planted.inputs])
    assert robot.collision_model.ngeoms == 1
    planted.assert_untouched()
