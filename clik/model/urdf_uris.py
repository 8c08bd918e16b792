"""The checked URDF as Pinocchio reads it: every mesh named by the file the checks read.

Pinocchio looks ``package://pkg/rest`` up as ``<dir>/pkg/rest`` for each folder it is
given (and those of ``ROS_PACKAGE_PATH``): a package whose folder is not called
after it (moveit_resources' ``moveit_resources_panda_description`` lives in
``panda_description/``), or that lies deeper in a workspace, is not found, and a
file of the same name elsewhere could be read instead of the one checked.
:func:`pinocchio_urdf` therefore writes, in the checked tree, each mesh
``filename`` as the absolute path of the file
:func:`~clik.model.urdf_check.check_urdf` checked (symlinks resolved), and returns
the text Pinocchio builds the models from. A mesh that names no file (a missing
visual mesh, left out by :mod:`clik.model.visual_meshes`) is left as it is.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from lxml import etree

from clik.model.urdf_links import checked_mesh_file

MESH_PATHS = ("link/visual/geometry/mesh", "link/collision/geometry/mesh")
"""Where Pinocchio reads mesh filenames in a URDF."""


def pinocchio_urdf(root: etree._Element, urdf: Path, package_dirs: Sequence[str | Path]) -> str:
    """The URDF text of the checked tree ``root``, its mesh files as absolute paths.

    Args:
        root: The ``<robot>`` element :func:`~clik.model.urdf_check.check_urdf`
            returned (changed in place: its mesh filenames).
        urdf: The URDF file (or the xacro file it was expanded from): relative mesh
            filenames are relative to its folder.
        package_dirs: The package folders the checks used (the same
            :class:`~clik.model.packages.PackageDirs`: its searches are reused).

    Returns:
        The URDF, as text, for Pinocchio's ``buildModelFromXML`` and
        ``buildGeomFromUrdfString``.
    """
    for where in MESH_PATHS:
        for mesh in root.iterfind(where):
            filename = mesh.get("filename")
            file = None if not filename else checked_mesh_file(filename, urdf, package_dirs)
            if file is not None:
                mesh.set("filename", str(file))
    return etree.tostring(root, encoding="unicode")
