"""Scene URDFs from Python (doc/python.md#building-a-scene): links with implicit collision shapes, joints and the
`<implicit_sim>` extension (doc/scenes.md), written as one URDF text.

    from implicit_sim.scene import Scene, Shape
    scene = Scene("drop", comment="a ball dropped on the ground")
    scene.friction(mu=0.5, e_t=1, e_o=1, e_r=0.01)
    scene.halfspace("ground")
    scene.link("ball", mass=1, inertia=(0.004, 0.004, 0.004), collision=Shape.sphere(0.1))
    scene.floating("ball", xyz=(0, 0, 0.5))
    model = implicit_sim.load_scene_string(scene.urdf(), name="drop")

A value is written as given when it is a string (so a script controls its digits), an integer as such, a float in
its shortest round-trip form (1.0 as "1"), a sequence as its values separated by spaces. Lengths in m, masses in kg,
inertias in kg m^2 about the centre of mass, angles in rad.
"""
import math
from xml.sax.saxutils import escape

HALF_PI = "1.5707963267948966"  # rad, as the committed scenes write it


def text(value):
    """The attribute text of a value (see the module's docstring)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool) or value is None:
        raise ValueError(f"scene: a value must be a number, a string or a sequence of numbers, got {value!r}")
    if isinstance(value, int):
        return str(value)
    try:
        number = float(value)
    except TypeError:
        return " ".join(text(v) for v in value)
    if not math.isfinite(number):
        raise ValueError(f"scene: every number must be finite, got {number!r}")
    if number.is_integer() and abs(number) < 1e15:
        return str(int(number))
    return repr(number)


def element(tag, attributes=(), children=None):
    """`<tag a="..."/>` (or with the given child lines, indented by two spaces), as a list of lines."""
    head = tag + "".join(f' {name}="{escape(text(value), {chr(34): "&quot;"})}"' for name, value in attributes
                         if value is not None)
    if not children:
        return [f"<{head}/>"]
    return [f"<{head}>"] + ["  " + line for line in children] + [f"</{tag}>"]


def inline(tag, attributes=(), child=None):
    """One line: `<tag ...>` `child` `</tag>` (the URDF `<geometry>` wrapper, kept on one line)."""
    return f"<{tag}>{element(*child)[0]}</{tag}>" if child else element(tag, attributes)[0]


class Shape:
    """A visual or collision shape: the URDF geometry tools draw, the `<implicit>` element the simulator uses
    (None: the stock geometry as is), and its origin in the link frame."""

    def __init__(self, geometry, implicit=None, xyz=None, rpy=None):
        self.geometry = geometry  # (tag, [(attribute, value), ...])
        self.implicit = implicit  # [(attribute, value), ...] starting with ("type", ...), or None
        self.xyz, self.rpy = xyz, rpy

    def at(self, xyz=None, rpy=None):
        """This shape at an origin in the link frame."""
        return Shape(self.geometry, self.implicit, xyz, rpy)

    @staticmethod
    def sphere(radius):
        return Shape(("sphere", [("radius", radius)]))

    @staticmethod
    def box(size):
        """size: the full lengths (x, y, z), as URDF."""
        return Shape(("box", [("size", size)]))

    @staticmethod
    def cylinder(radius, length):
        """Axis z, as URDF; the implicit cylinder (two caps and the side)."""
        return Shape(("cylinder", [("radius", radius), ("length", length)]),
                     [("type", "cylinder"), ("radius", radius), ("length", length)])

    @staticmethod
    def ellipsoid(semi_axes, tool_radius=None):
        """Tools draw a sphere of the largest semi-axis (or tool_radius)."""
        radius = tool_radius if tool_radius is not None else max(float(a) for a in semi_axes)
        return Shape(("sphere", [("radius", radius)]), [("type", "ellipsoid"), ("semi_axes", semi_axes)])

    @staticmethod
    def superellipsoid(semi_axes, exponent, tool_size=None):
        """|x/a|^p + |y/b|^p + |z/c|^p <= 1 (p = exponent in [2, 100]); tools draw the box it rounds (or tool_size)."""
        size = tool_size if tool_size is not None else [2 * float(a) for a in semi_axes]
        return Shape(("box", [("size", size)]),
                     [("type", "superellipsoid"), ("semi_axes", semi_axes), ("exponent", exponent)])

    @staticmethod
    def prism(sides, radius, length):
        """A regular N-gon prism (circumradius, a vertex on +x, axis z); tools draw its cylinder."""
        return Shape(("cylinder", [("radius", radius), ("length", length)]),
                     [("type", "prism"), ("sides", sides), ("radius", radius), ("length", length)])

    @staticmethod
    def halfspace(tool_size=(4, 4, 0.001)):
        """The half-space z <= 0 of its frame (a ground plane); tools draw a thin box."""
        return Shape(("box", [("size", tool_size)]), [("type", "halfspace")])

    def lines(self, tag, mass=None):
        """`<visual>` or `<collision>`; mass (kg) goes on `<implicit>` (the uniform solid's inertia is computed)."""
        implicit = self.implicit
        if mass is not None:
            implicit = (implicit or [("type", self.geometry[0])] + self.geometry[1]) + [("mass", mass)]
        children = []
        if self.xyz is not None or self.rpy is not None:
            children += element("origin", [("xyz", self.xyz), ("rpy", self.rpy)])
        children.append(inline("geometry", child=self.geometry))
        if implicit and tag == "collision":
            children += element("implicit", implicit)
        return element(tag, children=children)


class Scene:
    """A scene being written: `urdf()` gives its text, `write(path)` saves it."""

    def __init__(self, name, gravity=(0, 0, -9.81), comment=None, world=True):
        """world: start with the link `world` (a scene); False for a robot description (its own root)."""
        if comment is not None and "--" in comment:
            raise ValueError("scene: a comment may not contain '--' (XML)")
        self.name, self.gravity, self.comment = name, gravity, comment
        self._extension = []  # the `<implicit_sim>` children, in the order given
        self._body = element("link", [("name", "world")]) if world else []

    def friction(self, **values):
        """`<friction mu e_t e_o e_r e_roll/>`: the default of every pair, or with link1 and link2 one pair's."""
        pair = [(key, values.pop(key)) for key in ("link1", "link2") if key in values]
        self._extension += element("friction", pair + list(values.items()))

    def body(self, link, **values):
        """`<body link velocity angular_velocity force torque locked/>` (world frame; locked: e.g. "y rx rz")."""
        self._extension += element("body", [("link", link)] + list(values.items()))

    def joint_start(self, name, **values):
        """`<joint name position velocity effort/>`: a joint's start (doc/scenes.md#joints)."""
        self._extension += element("joint", [("name", name)] + list(values.items()))

    def link(self, name, mass=None, inertia=None, com=None, visual=None, collision=None):
        """A link. inertia: (ixx, iyy, izz) about the centre of mass at com (xyz in the link frame); without it, a
        given mass goes on the collision's `<implicit>`; a static link needs neither."""
        children = []
        if inertia is not None:
            if mass is None:
                raise ValueError(f"scene: link '{name}': an inertia needs a mass")
            ixx, iyy, izz = inertia
            inertial = element("origin", [("xyz", com)]) if com is not None else []
            inertial += element("mass", [("value", mass)])
            inertial += element("inertia", [("ixx", ixx), ("ixy", 0), ("ixz", 0), ("iyy", iyy), ("iyz", 0),
                                            ("izz", izz)])
            children += element("inertial", children=inertial)
        elif mass is not None and collision is None:
            raise ValueError(f"scene: link '{name}': a mass without an inertia needs a collision shape")
        if visual is not None:
            children += visual.lines("visual")
        if collision is not None:
            children += collision.lines("collision", mass if inertia is None else None)
        self._body += element("link", [("name", name)], children)

    def joint(self, name, type, parent, child, xyz=None, rpy=None, axis=None, limit=None):
        """A URDF joint; limit: e.g. dict(lower=-1, upper=1, effort=10, velocity=2) (rad or m, N m or N, per s)."""
        children = element("parent", [("link", parent)]) + element("child", [("link", child)])
        if xyz is not None or rpy is not None:
            children += element("origin", [("xyz", xyz), ("rpy", rpy)])
        if axis is not None:
            children += element("axis", [("xyz", axis)])
        if limit is not None:
            children += element("limit", list(limit.items()))
        self._body += element("joint", [("name", name), ("type", type)], children)

    def fixed(self, child, parent="world", xyz=None, rpy=None):
        """The fixed joint `<child>_joint`."""
        self.joint(f"{child}_joint", "fixed", parent, child, xyz, rpy)

    def floating(self, child, xyz=None, rpy=None):
        """The floating joint `<child>_joint` from the world: a free body starting at that pose."""
        self.joint(f"{child}_joint", "floating", "world", child, xyz, rpy)

    def halfspace(self, name, xyz=None, rpy=None, tool_size=(4, 4, 0.001), visual=None):
        """A static link whose collision is the half-space z <= 0 of its frame, welded to the world at (xyz, rpy)."""
        self.link(name, visual=visual, collision=Shape.halfspace(tool_size))
        self.fixed(name, xyz=xyz, rpy=rpy)

    def urdf(self):
        lines = ['<?xml version="1.0"?>']
        if self.comment is not None:
            lines += ("<!-- " + self.comment + " -->").split("\n")
        extension = element("implicit_sim", [("gravity", self.gravity)], self._extension)
        robot = element("robot", [("name", self.name)], extension + self._body)
        return "\n".join(lines + robot) + "\n"

    def write(self, path):
        with open(path, "w") as f:
            f.write(self.urdf())
