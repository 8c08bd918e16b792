"""clik.model.urdf_check: strict parsing and structural checks, one problem per case."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from clik.errors import RobotLoadError
from clik.model.urdf_check import check_urdf
from tests.urdf_snippets import J1, J2, LINKS
from tests.urdf_snippets import urdf_text as robot


def write(tmp_path: Path, text: str, name: str = "r.urdf") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def problem(path: Path, **options: object) -> RobotLoadError:
    with pytest.raises(RobotLoadError) as caught:
        check_urdf(path, **options)
    return caught.value


def test_valid_file_returns_the_robot_element(tmp_path):
    root = check_urdf(write(tmp_path, robot()))
    assert root.tag == "robot"
    assert [link.get("name") for link in root.iterfind("link")] == ["base", "l1", "l2"]


BAD = {
    "not robot root": ("<model/>", "root element is <model>, expected <robot>"),
    "missing child link": (
        robot(LINKS + J1 + J2.replace('child link="l2"', 'child link="l9"')),
        "joint 'j2' names child link 'l9' that does not exist",
    ),
    "missing parent element": (
        robot(LINKS + J1 + J2.replace('<parent link="l1"/>', "")),
        "joint 'j2' has no <parent link=...>",
    ),
    "duplicate link": (
        robot(LINKS + '<link name="l1"/>' + J1 + J2),
        "link name 'l1' appears twice",
    ),
    "unknown joint type": (robot(LINKS + J1 + J2.replace("fixed", "hinge")), "type 'hinge'"),
    "no movable joint": (robot(LINKS + J1.replace("revolute", "fixed") + J2), "no movable"),
    "cycle": (
        robot(
            '<link name="a"/><link name="b"/>'
            '<joint name="ab" type="revolute"><parent link="a"/><child link="b"/>'
            '<limit lower="0" upper="1"/></joint>'
            '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint>'
        ),
        "the joints form a cycle through links",
    ),
    "two parents": (
        robot(LINKS + J1 + J2 + J2.replace('"j2"', '"j3"').replace('"l1"', '"base"')),
        "link 'l2' is the child of two joints ('j2' and 'j3')",
    ),
    "two roots": (robot(LINKS + J1), "several root links ('base', 'l2')"),
    "nan origin": (robot(LINKS + J1.replace("0 0 0.1", "0 nan 0.1") + J2), "not finite"),
    "short origin": (robot(LINKS + J1.replace("0 0 0.1", "0 0") + J2), "is not 3 number(s)"),
    "zero axis": (robot(LINKS + J1.replace('xyz="0 0 1"', 'xyz="0 0 0"') + J2), "zero axis"),
    "inverted limits": (
        robot(LINKS + J1.replace('lower="-1" upper="1"', 'lower="1" upper="-1"') + J2),
        "joint 'j1' has lower limit 1 above its upper limit -1",
    ),
    "revolute without limit": (
        robot(LINKS + J1.split("<limit")[0] + "</joint>" + J2),
        "joint 'j1' is revolute but has no <limit>",
    ),
}


@pytest.mark.parametrize("text, words", BAD.values(), ids=BAD.keys())
def test_each_structural_problem_is_named(tmp_path, text, words):
    error = problem(write(tmp_path, text))
    assert words in error.problem
    assert error.line is not None
    assert f"line {error.line}" in str(error)


def test_missing_file(tmp_path):
    error = problem(tmp_path / "nothere.urdf")
    assert str(error) == f"cannot load robot {tmp_path / 'nothere.urdf'}: file not found"


def test_empty_file(tmp_path):
    assert problem(write(tmp_path, "  \n")).problem == "file is empty"


def test_malformed_xml_gives_the_line(tmp_path):
    error = problem(write(tmp_path, '<robot name="r">\n<link name="a">\n</robot>\n'))
    assert error.problem.startswith("malformed XML: Opening and ending tag mismatch")
    assert error.line == 3
    assert ", line 3:" in str(error)


def mesh_robot(filename: str) -> str:
    # a collision mesh: required (a missing visual mesh is a warning, test_visual_meshes.py)
    collision = f'<collision><geometry><mesh filename="{filename}"/></geometry></collision>'
    return robot(
        LINKS.replace('<link name="l1"/>', f'<link name="l1">{collision}</link>') + J1 + J2
    )


def test_missing_mesh_file_is_named(tmp_path):
    error = problem(write(tmp_path, mesh_robot("meshes/nothere.stl")))
    assert "mesh file 'meshes/nothere.stl' not found" in error.problem
    assert error.line == 3


def test_a_missing_mesh_is_named_by_its_whole_path(tmp_path):
    """A long mesh path is shown whole (the file can be found from the message); a path past
    the shown length keeps its start and its file name, and gives its length."""
    fr3 = "package://franka_description/meshes/robot_arms/fr3/visual/link0.dae"  # 67 chars
    error = problem(write(tmp_path, mesh_robot(fr3)), package_dirs=[tmp_path])
    assert f"mesh file {fr3!r} not found" in error.problem
    deep = "package://pkg/" + "folder/" * 60 + "link0_visual.dae"
    error = problem(write(tmp_path, mesh_robot(deep)), package_dirs=[tmp_path])
    assert "'package://pkg/folder/folder/" in error.problem
    assert f"...link0_visual.dae' ({len(deep)} characters) not found" in error.problem


def test_relative_and_package_meshes_that_exist_pass(tmp_path):
    (tmp_path / "pkg" / "meshes").mkdir(parents=True)
    (tmp_path / "pkg" / "meshes" / "l1.stl").write_text("solid l1\nendsolid l1\n")
    check_urdf(write(tmp_path, mesh_robot("pkg/meshes/l1.stl")))
    urdf = write(tmp_path, mesh_robot("package://pkg/meshes/l1.stl"))
    check_urdf(urdf, package_dirs=[tmp_path])
    error = problem(urdf, package_dirs=[tmp_path / "pkg"])
    assert "mesh file 'package://pkg/meshes/l1.stl' not found" in error.problem


def test_package_path_escaping_with_dotdot_is_refused(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "secret.stl").write_text("solid s\nendsolid s\n")  # exists, outside pkg
    urdf = write(tmp_path, mesh_robot("package://pkg/../secret.stl"))
    error = problem(urdf, package_dirs=[tmp_path])
    assert error.problem == "mesh 'package://pkg/../secret.stl' leaves its package folder"


def test_external_entity_is_refused_without_reading_the_file(tmp_path):
    planted = tmp_path / "planted.txt"
    planted.write_text("PLANTED-SECRET-4242")
    text = (
        '<?xml version="1.0"?>\n'
        f'<!DOCTYPE robot [ <!ENTITY xxe SYSTEM "file://{planted}"> ]>\n'
        f'<robot name="r">{LINKS.replace("l2", "&xxe;")}{J1}</robot>\n'
    )
    error = problem(write(tmp_path, text))
    assert "declares XML entities" in error.problem
    assert error.line == 2
    assert "PLANTED-SECRET-4242" not in str(error)


def test_billion_laughs_is_refused_fast(tmp_path):
    entities = "".join(
        f'<!ENTITY lol{i} "{f"&lol{i - 1};" * 10}">\n' for i in range(1, 10)
    ).replace("&lol0;", "lol")
    text = f'<?xml version="1.0"?>\n<!DOCTYPE robot [\n{entities}]>\n<robot name="&lol9;"/>\n'
    start = time.perf_counter()
    error = problem(write(tmp_path, text))
    assert time.perf_counter() - start < 0.1
    assert "declares XML entities" in error.problem


def test_external_dtd_is_refused(tmp_path):
    text = robot().replace(
        "<robot", '<!DOCTYPE robot SYSTEM "http://example.com/r.dtd">\n<robot', 1
    )
    error = problem(write(tmp_path, text))
    assert error.problem == "the DOCTYPE refers to an external DTD, which is refused"
    assert error.line == 2


def test_plain_doctype_is_accepted(tmp_path):
    text = robot().replace("<robot", "<!DOCTYPE robot>\n<robot", 1)
    assert check_urdf(write(tmp_path, text)).get("name") == "r"


def test_fixed_joint_may_have_a_zero_axis(tmp_path):
    text = robot(LINKS + J1 + J2.replace("</joint>", '<axis xyz="0 0 0"/></joint>'))
    assert check_urdf(write(tmp_path, text)).get("name") == "r"


def test_package_uri_with_an_extra_slash_is_read_like_pinocchio(tmp_path):
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "l1.stl").write_text("solid l1\nendsolid l1\n")
    check_urdf(write(tmp_path, mesh_robot("package:///pkg/l1.stl")), package_dirs=[tmp_path])
