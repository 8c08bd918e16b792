"""A small valid URDF (three links, one revolute joint) that URDF tests break one piece of."""

LINKS = '<link name="base"/><link name="l1"/><link name="l2"/>'
J1 = (
    '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
    '<origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/>'
    '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
)
J2 = '<joint name="j2" type="fixed"><parent link="l1"/><child link="l2"/></joint>'


def urdf_text(body: str = LINKS + J1 + J2) -> str:
    """The whole URDF document around ``body``."""
    return f'<?xml version="1.0"?>\n<robot name="r">\n{body}\n</robot>\n'
