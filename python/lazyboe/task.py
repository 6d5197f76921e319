"""Typed goals and tasks for PlanningSession.plan(): each is the query format's object
(docs/task.md) with names and defaults, and converts itself with ``to_query()``. A plain dict in
the query format works everywhere one of these does; the library checks either the same way.

    >>> goal = lazyboe.Pose.from_matrix(robot.forward_kinematics(q), position_tolerance=0.01)
    >>> r = session.plan(start, goal, payload=lazyboe.Payload(3.0, com=[0, 0, 0.05]))
"""

import numpy as np


def _vector(value, size, name):
    v = np.asarray(value, dtype=float).reshape(-1)
    if v.size != size:
        raise ValueError(f"{name}: expected {size} numbers, got {v.size}")
    return [float(x) for x in v]


def _quaternion(rotation):
    """[w, x, y, z] (w >= 0) of a 3x3 rotation matrix."""
    m = np.asarray(rotation, dtype=float)
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    # Shepperd's method: from the largest of w, x, y, z, so that no division is by ~0.
    k = int(np.argmax([trace, m[0, 0], m[1, 1], m[2, 2]]))
    if k == 0:
        s = 2 * np.sqrt(1 + trace)
        q = [s / 4, (m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s]
    elif k == 1:
        s = 2 * np.sqrt(1 + m[0, 0] - m[1, 1] - m[2, 2])
        q = [(m[2, 1] - m[1, 2]) / s, s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s]
    elif k == 2:
        s = 2 * np.sqrt(1 - m[0, 0] + m[1, 1] - m[2, 2])
        q = [(m[0, 2] - m[2, 0]) / s, (m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s]
    else:
        s = 2 * np.sqrt(1 - m[0, 0] - m[1, 1] + m[2, 2])
        q = [(m[1, 0] - m[0, 1]) / s, (m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4]
    if q[0] < 0:
        q = [-v for v in q]
    return [float(v) for v in q]


class Pose:
    """A pose goal: a link's position (m) and orientation (quaternion [w, x, y, z]) in the base
    frame, each within its tolerance (m, rad). free_axis: a vector of the base frame about
    which any rotation will do (e.g. [0, 0, 1]: any yaw about the vertical). link: default the
    robot's tip link."""

    def __init__(self, position, orientation, *, free_axis=None, link=None,
                 position_tolerance=0.01, orientation_tolerance=0.05):
        self.position = _vector(position, 3, "position")
        self.orientation = _vector(orientation, 4, "orientation")
        self.free_axis = None if free_axis is None else _vector(free_axis, 3, "free_axis")
        self.link = link
        self.position_tolerance = float(position_tolerance)
        self.orientation_tolerance = float(orientation_tolerance)

    @classmethod
    def from_matrix(cls, matrix, **options):
        """The pose of a 4x4 homogeneous transform (as Robot.forward_kinematics returns);
        options as the constructor's."""
        m = np.asarray(matrix, dtype=float)
        if m.shape != (4, 4):
            raise ValueError(f"matrix: expected a 4x4 transform, got shape {m.shape}")
        return cls(m[:3, 3], _quaternion(m[:3, :3]), **options)

    def to_query(self):
        """The goal as the query format has it."""
        pose = {"position": self.position, "orientation": self.orientation}
        if self.free_axis is not None:
            pose["free_axis"] = self.free_axis
        if self.link is not None:
            pose["link"] = self.link
        return {"pose": pose, "position_tolerance": self.position_tolerance,
                "orientation_tolerance": self.orientation_tolerance}

    def __repr__(self):
        return f"Pose({self.to_query()!r})"


class Payload:
    """What the arm carries: mass (kg), centre of mass (m) in the link's frame, and either its
    inertia about the centre of mass ([ixx, ixy, ixz, iyy, iyz, izz], kg m^2, URDF order) or a
    solid box's size (m), whose density (kg/m^3) may replace the mass (mass=None); neither: a
    point mass. link: default the robot's tip link."""

    def __init__(self, mass, com=(0.0, 0.0, 0.0), *, inertia=None, box=None, density=None,
                 link=None):
        self.mass = None if mass is None else float(mass)
        self.density = None if density is None else float(density)
        self.com = _vector(com, 3, "com")
        self.inertia = None if inertia is None else _vector(inertia, 6, "inertia")
        self.box = None if box is None else _vector(box, 3, "box")
        self.link = link

    def to_query(self):
        """The payload as the query format has it."""
        q = {"com": self.com}
        for key in ("mass", "density", "inertia", "box", "link"):
            if getattr(self, key) is not None:
                q[key] = getattr(self, key)
        return q

    def __repr__(self):
        return f"Payload({self.to_query()!r})"


class EndEffectorLimits:
    """Limits on a link's motion, checked at every simulation tick: linear speed (m/s), linear
    acceleration (m/s^2), and tilt (rad) of an axis of the link's frame from the vertical (axis
    default: the direction of the link's frame that is vertical at the start, so a container is
    carried as it is held). link: default the robot's tip link. None: no limit."""

    def __init__(self, *, max_linear_speed=None, max_linear_acceleration=None, max_tilt=None,
                 axis=None, link=None):
        self.max_linear_speed = max_linear_speed
        self.max_linear_acceleration = max_linear_acceleration
        self.max_tilt = max_tilt
        self.axis = None if axis is None else _vector(axis, 3, "axis")
        self.link = link

    def to_query(self):
        """The limits as the query format has them."""
        keys = ("max_linear_speed", "max_linear_acceleration", "max_tilt", "axis", "link")
        return {k: getattr(self, k) for k in keys if getattr(self, k) is not None}

    def __repr__(self):
        return f"EndEffectorLimits({self.to_query()!r})"
