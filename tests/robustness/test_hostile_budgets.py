"""Hostile sizes and numbers: refused quickly, in bounded memory, with the field named.

Each probe of issue 15 (a URDF with thousands of links or attributes, a 100 MB
mesh, a FIFO or folder given as a mesh, numbers far outside physical ranges,
a megabyte-long name) must end in the expected clik error within a time bound
(pytest-timeout, or a subprocess with a timeout: a hang fails the test, not
the suite) and, for the large files, with the child's peak memory under 1 GB.
Large files are made at test time, sparse: every refusal is decided on the
file's size or header, before its content is read.
"""

from __future__ import annotations

import json
import os
import struct
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from clik import GeometryError, InputError, RobotLoadError
from clik.cli import main
from clik.constraints import Obstacle
from clik.model.mesh_check import MAX_MESH_BYTES
from clik.model.robot import Robot
from clik.model.urdf_check import MAX_MOVABLE_JOINTS, check_urdf
from clik.scenarios import scenario_path

pytestmark = pytest.mark.timeout(60)

SECONDS = 10.0
"""Time bound of every refusal (most take milliseconds)."""
MEMORY_BYTES = 2**30
"""Peak memory bound of a child process refusing a large file."""

LINKS = '<link name="base"/><link name="l1"/>'
J1 = (
    '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
    '<origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)


def urdf(body: str = LINKS + J1, root: str = '<robot name="r">') -> str:
    return f'<?xml version="1.0"?>\n{root}{body}</robot>\n'


def chain(n: int) -> str:
    """A chain of ``n`` revolute joints."""
    links = "".join(f'<link name="l{i}"/>' for i in range(n + 1))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i}"/><child link="l{i + 1}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(n)
    )
    return urdf(links + joints)


def with_mesh(filename: str, scale: str = "1 1 1") -> str:
    geometry = f'<geometry><mesh filename="{filename}" scale="{scale}"/></geometry>'
    return urdf(
        LINKS.replace(
            '<link name="l1"/>', f'<link name="l1"><collision>{geometry}</collision></link>'
        )
        + J1
    )


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


def refused(call, error=RobotLoadError) -> str:
    """The message of the error ``call()`` raises, checked to come within :data:`SECONDS`."""
    start = time.perf_counter()
    with pytest.raises(error) as caught:
        call()
    assert time.perf_counter() - start < SECONDS
    message = str(caught.value)
    assert len(message) < 2000, message[:200]
    return message


def binary_stl(path: Path, triangles: np.ndarray) -> Path:
    """A binary STL of ``triangles`` (n, 3, 3)."""
    records = b"".join(
        struct.pack("<12fH", 0.0, 0.0, 0.0, *t.reshape(-1).tolist(), 0) for t in triangles
    )
    path.write_bytes(b"\0" * 80 + struct.pack("<I", len(triangles)) + records)
    return path


TETRAHEDRON = np.array(
    [
        [[0, 0, 0], [1, 0, 0], [0, 1, 0]],
        [[0, 0, 0], [0, 0, 1], [1, 0, 0]],
        [[0, 0, 0], [0, 1, 0], [0, 0, 1]],
        [[1, 0, 0], [0, 0, 1], [0, 1, 0]],
    ],
    dtype=float,
)


def sparse_stl(path: Path, size: int) -> Path:
    """A binary STL of ``size`` bytes whose header claims as many faces as fit (sparse)."""
    faces = (size - 84) // 50
    with open(path, "wb") as file:
        file.write(b"\0" * 80 + struct.pack("<I", faces))
        file.truncate(84 + 50 * faces)
    return path


def bounded(code: str, tmp_path: Path) -> dict:
    """Run ``code`` in a child Python (timeout :data:`SECONDS`); its JSON output and peak memory."""
    script = textwrap.dedent(
        """
        import json, resource, sys
        out = {}
        try:
        {body}
        except Exception as error:
            out["error"] = type(error).__name__
            out["message"] = str(error)
        # The peak of this process's own memory (VmHWM starts anew at exec; ru_maxrss
        # would keep the high-water mark of the pytest process it was forked from).
        with open("/proc/self/status") as status:
            hwm = [line for line in status if line.startswith("VmHWM:")]
        out["maxrss"] = (
            int(hwm[0].split()[1]) * 1024
            if hwm
            else resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
        )
        print(json.dumps(out))
        """
    ).replace("{body}", textwrap.indent(textwrap.dedent(code), "    "))
    proc = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        timeout=SECONDS + 20,  # the import of clik included
        cwd=tmp_path,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    result = json.loads(proc.stdout.splitlines()[-1])
    assert result["maxrss"] < MEMORY_BYTES
    return result


# ---------------------------------------------------------------- URDF budgets


def test_a_2000_link_chain_is_checked_in_linear_time(tmp_path, monkeypatch):
    """With the link budgets lifted, the checks of 2,000 links take well under 2 s."""
    import clik.model.urdf_check as urdf_check

    monkeypatch.setattr(urdf_check, "MAX_MOVABLE_JOINTS", 10**6)
    monkeypatch.setattr(urdf_check, "MAX_LINKS", 10**6)
    monkeypatch.setattr(urdf_check, "MAX_DEPTH", 10**6)
    path = write(tmp_path / "chain.urdf", chain(2000))
    start = time.perf_counter()
    check_urdf(path)
    assert time.perf_counter() - start < 2.0


def sensor_tree(n: int, arm: int = 7) -> str:
    """``n`` links: an arm of ``arm`` revolute joints, then fixed frames hung off it."""
    links = "".join(f'<link name="l{i}"/>' for i in range(n))
    joints = "".join(
        f'<joint name="j{i}" type="revolute"><parent link="l{i - 1}"/><child link="l{i}"/>'
        '<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(1, arm + 1)
    ) + "".join(
        f'<joint name="f{i}" type="fixed"><parent link="l{1 + i % arm}"/><child link="l{i}"/>'
        '<origin xyz="0.01 0 0"/></joint>'
        for i in range(arm + 1, n)
    )
    return urdf(links + joints)


@pytest.mark.parametrize("n", [2000, 10_000])
def test_thousands_of_links_are_checked_and_loaded(tmp_path, n):
    """A robot with thousands of fixed frames (sensors, markers) is within the budgets."""
    path = write(tmp_path / "sensors.urdf", sensor_tree(n))
    start = time.perf_counter()
    check_urdf(path)
    assert time.perf_counter() - start < 2.0 * n / 2000
    robot = Robot.load(path)
    assert robot.nq == 7 and robot.model.existFrame(f"l{n - 1}")


def test_a_chain_deeper_than_pinocchio_holds_is_refused_at_once(tmp_path):
    """Pinocchio's reader recurses along the tree (a 5,000-link chain crashes it)."""
    links = "".join(f'<link name="l{i}"/>' for i in range(5001))
    joints = "".join(
        f'<joint name="j{i}" type="{"revolute" if i == 0 else "fixed"}"><parent link="l{i}"/>'
        f'<child link="l{i + 1}"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        for i in range(5000)
    )
    path = write(tmp_path / "deep.urdf", urdf(links + joints))
    message = refused(lambda: Robot.load(path))
    assert "1001 joints from the root link" in message and "MAX_DEPTH" in message


@pytest.mark.parametrize("n", [2000, 10_000])
def test_a_long_chain_is_refused_at_once_by_its_budget(tmp_path, n):
    path = write(tmp_path / "chain.urdf", chain(n))
    message = refused(lambda: Robot.load(path))
    assert f"{n} movable joints" in message or "links" in message
    assert "MAX_MOVABLE_JOINTS" in message or "MAX_LINKS" in message


def test_the_movable_joint_budget_is_what_pinocchio_holds(tmp_path):
    """The largest chain allowed loads (Pinocchio's Data grows as nv^3)."""
    robot = Robot.load(write(tmp_path / "chain.urdf", chain(MAX_MOVABLE_JOINTS)))
    assert robot.nq == MAX_MOVABLE_JOINTS


@pytest.mark.parametrize("count", [20_000, 100_000])
def test_thousands_of_attributes_are_refused_before_parsing(tmp_path, count):
    attributes = " ".join(f'a{i}="{i}"' for i in range(count))
    path = write(tmp_path / "r.urdf", urdf(LINKS + J1, root=f'<robot name="r" {attributes}>'))
    message = refused(lambda: check_urdf(path))
    assert f"an element has {count + 1} attributes" in message and "MAX_ATTRIBUTES" in message
    assert "line 2" in message


def test_too_many_elements_are_refused(tmp_path):
    path = write(tmp_path / "r.urdf", urdf(LINKS + J1 + "<x/>" * 600_000))
    assert "MAX_ELEMENTS" in refused(lambda: check_urdf(path))


def test_a_megabyte_name_is_refused_and_shortened_in_the_message(tmp_path):
    name = "n" * 1_000_000
    path = write(tmp_path / "r.urdf", urdf(LINKS.replace('"l1"', f'"{name}"') + J1))
    message = refused(lambda: check_urdf(path))
    assert "(1000000 characters)" in message and "MAX_NAME_LENGTH" in message
    assert len(message) < 400


# ---------------------------------------------------------------- URDF numbers


NUMBERS = {
    "origin xyz": (J1.replace('xyz="0 0 0.1"', 'xyz="1e308 1e308 1e308"'), "origin xyz="),
    "origin rpy": (J1.replace('rpy="0 0 0"', 'rpy="0 0 100"'), "origin rpy="),
    "axis": (J1.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1e300"/>'), "axis xyz="),
    "limit": (J1.replace('upper="1"', 'upper="1e300"'), "limit upper="),
    "negative velocity": (J1.replace('velocity="1"', 'velocity="-1"'), "velocity='-1' is negative"),
    "damping": (J1.replace("</joint>", '<dynamics damping="inf"/></joint>'), "dynamics damping="),
}
LINK_NUMBERS = {
    "mass": ('<inertial><mass value="1e300"/></inertial>', "mass value="),
    "inertia": (
        '<inertial><mass value="1"/><inertia ixx="1e300" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
        "</inertial>",
        "inertia ixx=",
    ),
    "box": ('<collision><geometry><box size="1 1 5000"/></geometry></collision>', "box size="),
    "sphere": ('<visual><geometry><sphere radius="1e9"/></geometry></visual>', "sphere radius="),
    "visual origin": (
        '<visual><origin xyz="0 0 2000"/><geometry><sphere radius="1"/></geometry></visual>',
        "origin xyz=",
    ),
}


@pytest.mark.parametrize("name", [*NUMBERS, *LINK_NUMBERS])
def test_numbers_outside_their_range_are_refused_with_the_range(tmp_path, name):
    if name in NUMBERS:
        joint, words = NUMBERS[name]
        text = urdf(LINKS + joint)
    else:
        inside, words = LINK_NUMBERS[name]
        text = urdf(LINKS.replace('<link name="l1"/>', f'<link name="l1">{inside}</link>') + J1)
    message = refused(lambda: check_urdf(write(tmp_path / "r.urdf", text)))
    assert words in message
    assert "out of range" in message or "negative" in message or "not finite" in message


def test_a_huge_mesh_scale_is_refused_before_coal(tmp_path):
    binary_stl(tmp_path / "m.stl", TETRAHEDRON)
    path = write(tmp_path / "r.urdf", with_mesh("m.stl", "1e100 1e100 1e100"))
    message = refused(lambda: Robot.load(path))
    assert "collision mesh scale" in message and "[1e-06, 1e+06]" in message


def test_a_huge_obstacle_scale_is_an_input_error(tmp_path):
    mesh = binary_stl(tmp_path / "m.stl", TETRAHEDRON)
    message = refused(
        lambda: Obstacle("m", "mesh", [0, 0, 0], file=mesh, scale=[1e100] * 3), InputError
    )
    assert "obstacles.m.scale" in message


def test_far_mesh_vertices_are_refused_before_the_hull(tmp_path):
    mesh = binary_stl(tmp_path / "m.stl", TETRAHEDRON * 1e30)
    message = refused(lambda: Obstacle("m", "mesh", [0, 0, 0], file=mesh), GeometryError)
    assert "MAX_COORDINATE" in message
    obj = tmp_path / "far.obj"
    obj.write_text("v 0 0 0\nv 1e9 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 4 2\nf 2 4 3\n")
    assert "MAX_COORDINATE" in refused(
        lambda: Obstacle("m", "mesh", [0, 0, 0], file=obj), GeometryError
    )
    path = write(tmp_path / "r.urdf", with_mesh("far.obj"))
    assert "MAX_COORDINATE" in refused(lambda: Robot.load(path))


def test_a_huge_origin_is_refused_by_the_command_line(tmp_path, capsys):
    path = write(tmp_path / "r.urdf", urdf(LINKS + NUMBERS["origin xyz"][0]))
    case = scenario_path("case_study_unconstrained").read_text()
    scenario = write(tmp_path / "s.toml", case.replace('source = "planar4r"', f'source = "{path}"'))
    start = time.perf_counter()
    code = main(["solve", str(scenario), "--out", str(tmp_path / "out")])
    assert time.perf_counter() - start < SECONDS
    assert code == 2
    err = capsys.readouterr().err
    assert "origin xyz=" in err and "out of range" in err


# ---------------------------------------------------------------- large meshes


def test_a_100_mb_link_mesh_is_refused_on_its_size(tmp_path):
    sparse_stl(tmp_path / "big.stl", 100 * 2**20)
    write(tmp_path / "r.urdf", with_mesh("big.stl"))
    result = bounded("from clik.model.robot import Robot\nRobot.load('r.urdf')", tmp_path)
    assert result["error"] == "RobotLoadError"
    assert f"above the budget of {MAX_MESH_BYTES} bytes" in result["message"]


def test_a_100_mb_obstacle_mesh_is_refused_on_its_size(tmp_path):
    sparse_stl(tmp_path / "big.stl", 100 * 2**20)
    code = "from clik.constraints import Obstacle\nObstacle('m', 'mesh', [0, 0, 0], file='big.stl')"
    result = bounded(code, tmp_path)
    assert result["error"] == "GeometryError"
    assert "obstacles.m.file" in result["message"] and "MAX_MESH_BYTES" in result["message"]


def test_a_mesh_declaring_millions_of_vertices_is_refused_on_its_header(tmp_path):
    ply = tmp_path / "m.ply"
    ply.write_text("ply\nformat ascii 1.0\nelement vertex 50000000\nproperty float x\nend_header\n")
    message = refused(lambda: Obstacle("m", "mesh", [0, 0, 0], file=ply), GeometryError)
    assert "50000000 vertex" in message and "MAX_MESH_ELEMENTS" in message


def test_a_mesh_format_that_names_side_files_is_refused(tmp_path):
    gltf = write(tmp_path / "m.gltf", '{"buffers": [{"uri": "../secret.bin"}]}')
    assert "has format '.gltf'" in refused(
        lambda: Obstacle("m", "mesh", [0, 0, 0], file=gltf), GeometryError
    )


# ---------------------------------------------------------------- not regular files


@pytest.mark.parametrize("kind", ["fifo", "folder"])
def test_a_fifo_or_folder_mesh_is_named_and_never_opened(tmp_path, kind):
    path = tmp_path / "m.stl"
    if kind == "fifo":
        os.mkfifo(path)  # opening it would block
    else:
        path.mkdir()
    words = "not a regular file" if kind == "fifo" else "is a folder"
    message = refused(lambda: Obstacle("m", "mesh", [0, 0, 0], file=path), GeometryError)
    assert words in message and "no such" not in message
    urdf_path = write(tmp_path / "r.urdf", with_mesh("m.stl"))
    assert words in refused(lambda: Robot.load(urdf_path))


def test_a_fifo_urdf_is_named_and_never_opened(tmp_path):
    path = tmp_path / "r.urdf"
    os.mkfifo(path)
    assert "not a regular file" in refused(lambda: Robot.load(path))
