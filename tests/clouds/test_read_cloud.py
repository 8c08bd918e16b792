"""Point cloud files: .npy, PLY (ASCII, binary) and PCD (ascii, binary), read to the same points."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from clik.clouds import read as read_module
from clik.clouds import read_cloud, voxel_spheres
from clik.errors import InputError

POINTS = np.array([[0.1, 0.2, 0.3], [-1.0, 0.5, 2.0], [np.nan, 0.0, 0.0], [0.0, np.inf, 1.0],
                   [0.25, -0.75, 0.125]])  # fmt: skip
FINITE = POINTS[[0, 1, 4]]


def write_ply(path: Path, binary: bool) -> Path:
    from plyfile import PlyData, PlyElement

    vertex = np.array([tuple(p) for p in POINTS], dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    PlyData([PlyElement.describe(vertex, "vertex")], text=not binary).write(str(path))
    return path


def write_pcd(path: Path, binary: bool, extra: bool = False) -> Path:
    fields = "x y z intensity" if extra else "x y z"
    size, kind, count = ("8 8 8 4", "F F F F", "1 1 1 1") if extra else ("8 8 8", "F F F", "1 1 1")
    head = (f"# .PCD v0.7\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\nTYPE {kind}\n"
            f"COUNT {count}\nWIDTH {len(POINTS)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
            f"POINTS {len(POINTS)}\nDATA {'binary' if binary else 'ascii'}\n")  # fmt: skip
    if extra:
        dtype = np.dtype([("x", "<f8"), ("y", "<f8"), ("z", "<f8"), ("intensity", "<f4")])
        rows = np.array([(*p, 7.0) for p in POINTS], dtype=dtype)
    else:
        rows = POINTS.astype("<f8")
    if binary:
        path.write_bytes(head.encode() + rows.tobytes())
    else:
        text = "\n".join(" ".join(repr(float(v)) for v in (tuple(r) if extra else r)) for r in rows)
        path.write_text(head + text + "\n")
    return path


FORMS = ["npy", "ply ascii", "ply binary", "pcd ascii", "pcd binary",
         "pcd binary with another field", "pcd ascii with another field"]  # fmt: skip


@pytest.mark.parametrize("form", FORMS)
def test_every_form_reads_the_same_finite_points(tmp_path: Path, form: str) -> None:
    if form == "npy":
        path = tmp_path / "c.npy"
        np.save(path, POINTS)
    elif form.startswith("ply"):
        path = write_ply(tmp_path / "c.ply", binary="binary" in form)
    else:
        path = write_pcd(tmp_path / "c.pcd", "binary" in form, extra="another" in form)
    cloud = read_cloud(path)
    np.testing.assert_array_equal(cloud.points, FINITE)
    assert cloud.dropped == 2  # the NaN and the infinity, counted
    assert not cloud.points.flags.writeable


def test_a_malformed_pcd_header_names_the_file_and_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.pcd"
    path.write_text("VERSION 0.7\nFIELDS x y z\nSIZES 4 4 4\n")
    with pytest.raises(InputError, match=r"bad\.pcd, line 3: expected a PCD header key"):
        read_cloud(path)


def test_a_compressed_pcd_is_refused_with_the_way_out(tmp_path: Path) -> None:
    path = write_pcd(tmp_path / "c.pcd", binary=True)
    path.write_bytes(path.read_bytes().replace(b"DATA binary", b"DATA binary_compressed"))
    with pytest.raises(InputError, match="save it as binary"):
        read_cloud(path)


def test_a_malformed_ply_header_names_the_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.ply"
    path.write_bytes(b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nbogus\n")
    with pytest.raises(InputError, match=r"bad\.ply, line 5"):
        read_cloud(path)


def test_budgets_and_shapes_are_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = tmp_path / "c.npy"
    np.save(path, POINTS)
    monkeypatch.setattr(read_module, "MAX_CLOUD_POINTS", 4)
    with pytest.raises(InputError, match="at most 4 points"):
        read_cloud(path)
    monkeypatch.setattr(read_module, "MAX_CLOUD_BYTES", 10)
    with pytest.raises(InputError, match="at most 10 bytes"):
        read_cloud(path)
    monkeypatch.undo()
    flat = tmp_path / "flat.npy"
    np.save(flat, np.zeros((4, 2)))
    with pytest.raises(InputError, match=r"shape \(N, 3\)"):
        read_cloud(flat)
    with pytest.raises(InputError, match=r"\.npy, \.ply or \.pcd"):
        read_cloud(tmp_path / "c.xyz")


def test_voxel_spheres_hold_every_point(tmp_path: Path) -> None:
    """(C1): each point lies in its voxel's sphere; radii within the voxel's diagonal."""
    rng = np.random.default_rng(45)
    points = rng.uniform(-0.5, 0.5, size=(5000, 3))
    voxel = 0.05
    centres, radii = voxel_spheres(points, voxel)
    keys = np.floor(points / voxel).astype(int)
    assert len(centres) == len(np.unique(keys, axis=0))
    assert np.all(radii <= np.sqrt(3.0) * voxel + 1e-12)
    nearest = np.min(np.linalg.norm(points[:, None, :] - centres[None, :, :], axis=2)
                     - radii[None, :], axis=1)  # fmt: skip
    assert np.all(nearest <= 1e-12)  # inside (or on) some sphere
    same, none = voxel_spheres(points, 0.0)
    np.testing.assert_array_equal(same, points)
    assert not none.any()
    with pytest.raises(InputError, match="voxel"):
        voxel_spheres(points, -0.1)
