"""The V+ transformation (a Cartesian location): x, y, z in mm, yaw, pitch, roll in degrees.

Conventions, with the V+ Language User's Guide v17 lines they come from
(/work/shared/seeds/vplus-language-users-guide-v17.txt):

* Orientation is "ZYZ' Euler values" (L5989): yaw about the local Z axis, then
  pitch about the new local Y axis, then roll about the newest local Z axis, in
  that strict order (L6048-6052).  As a matrix, ``R = Rz(yaw) @ Ry(pitch) @ Rz(roll)``
  and a point p in the location's frame is ``t + R p`` in the reference frame.
* ``a:b`` (``Location.__mul__``) is composition, b expressed in a's frame; the
  worked example L6145-6154 (``loc_a = TRANS(300,50,350,0,180,0)``,
  ``loc_a:TRANS(-50,20,30)`` = ``350, 70, 320, 0, 180, 0``) is a test.
* Decomposition (what DECOMPOSE / LISTL show) is canonical:
    - every angle is normalised to (-180, 180] (L6018: "a positive rotation of
      190 deg is shown as -170");
    - pitch is reported in [0, 180] (the NOFLIP sign; a negative pitch p is
      rewritten as yaw+180, -p, roll+180, the same rotation);
    - at pitch 0 or 180 yaw and roll turn about the same axis and only their
      sum (pitch 0) or difference (pitch 180) is defined.  V+ "automatically
      reflects rotation of the quill in the roll component ... and the yaw
      component is forced to 0 degrees" (L6033-6037, four-axis SCARA, whose
      tool points straight down, pitch = 180, L6044-6045).  We apply the same
      rule to every transformation: at pitch 0 or 180 (within 1e-7 rad) yaw is
      0 and all of the rotation is in roll.
  Locations built from components are canonicalised the same way, so
  ``Location(0, 0, 0, 30, 180, 40)`` *is* ``Location(0, 0, 0, 0, 180, 10)``, as
  the controller (which stores a matrix) would display it.
* APPRO / DEPART work in the tool frame (L6369-6372): ``approach(loc, d)`` is
  ``loc:TRANS(0, 0, -d)``, d mm back along the tool Z axis; for a SCARA (tool Z
  down) that is d mm above the location (L6360-6364: "a point 50 mm above place").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_SINGULAR = 1e-7  # rad: |sin(pitch)| below this is pitch 0 or 180
_SNAP_DEG = 1e-9  # deg: pitch this close to 0 / 180 is treated as exactly that


def _norm(a: float) -> float:
    """Angle in degrees, normalised to (-180, 180]."""
    a = math.fmod(a, 360.0)
    if a > 180.0:
        a -= 360.0
    elif a <= -180.0:
        a += 360.0
    return a + 0.0  # no -0.0


def _cs(deg: float) -> tuple[float, float]:
    """cos, sin of an angle in degrees, exact at multiples of 90."""
    q = deg / 90.0
    if q == int(q):
        return ((1.0, 0.0), (0.0, 1.0), (-1.0, 0.0), (0.0, -1.0))[int(q) % 4]
    r = math.radians(deg)
    return math.cos(r), math.sin(r)


def _rotation(yaw: float, pitch: float, roll: float) -> np.ndarray:
    cy, sy = _cs(yaw)
    cp, sp = _cs(pitch)
    cr, sr = _cs(roll)
    return np.array(
        [
            [cy * cp * cr - sy * sr, -cy * cp * sr - sy * cr, cy * sp],
            [sy * cp * cr + cy * sr, -sy * cp * sr + cy * cr, sy * sp],
            [-sp * cr, sp * sr, cp],
        ]
    )


def _canonical_angles(yaw: float, pitch: float, roll: float) -> tuple[float, float, float]:
    """The V+ display form of a ZYZ' triple (see the module docstring)."""
    yaw, pitch, roll = _norm(yaw), _norm(pitch), _norm(roll)
    if pitch < 0.0:
        yaw, pitch, roll = _norm(yaw + 180.0), -pitch, _norm(roll + 180.0)
    if abs(pitch) <= _SNAP_DEG:
        return 0.0, 0.0, _norm(roll + yaw)
    if abs(pitch - 180.0) <= _SNAP_DEG:
        return 0.0, 180.0, _norm(roll - yaw)
    return yaw, pitch, roll


@dataclass(frozen=True)
class Location:
    """A V+ transformation: x, y, z (mm) and yaw, pitch, roll (deg, ZYZ')."""

    x: float
    y: float
    z: float
    yaw: float
    pitch: float
    roll: float

    def __post_init__(self):
        yaw, pitch, roll = _canonical_angles(float(self.yaw), float(self.pitch), float(self.roll))
        object.__setattr__(self, "x", float(self.x))
        object.__setattr__(self, "y", float(self.y))
        object.__setattr__(self, "z", float(self.z))
        object.__setattr__(self, "yaw", yaw)
        object.__setattr__(self, "pitch", pitch)
        object.__setattr__(self, "roll", roll)

    # ------------------------------------------------------------ matrices
    @classmethod
    def from_matrix(cls, T: np.ndarray) -> "Location":
        """From a 4x4 homogeneous matrix (translation in mm), decomposed canonically."""
        T = np.asarray(T, dtype=float)
        R = T[:3, :3]
        sp = math.hypot(R[0, 2], R[1, 2])
        pitch = math.atan2(sp, R[2, 2])
        if sp < _SINGULAR:
            if R[2, 2] > 0.0:  # pitch 0: R = Rz(yaw + roll)
                yaw, pitch, roll = 0.0, 0.0, math.atan2(R[1, 0], R[0, 0])
            else:  # pitch 180: R = Ry(180) Rz(roll - yaw)
                yaw, pitch, roll = 0.0, math.pi, math.atan2(R[1, 0], -R[0, 0])
        else:
            yaw = math.atan2(R[1, 2], R[0, 2])
            roll = math.atan2(R[2, 1], -R[2, 0])
        return cls(T[0, 3], T[1, 3], T[2, 3], math.degrees(yaw), math.degrees(pitch), math.degrees(roll))

    def rotation(self) -> np.ndarray:
        """3x3 rotation matrix."""
        return _rotation(self.yaw, self.pitch, self.roll)

    def matrix(self) -> np.ndarray:
        """4x4 homogeneous matrix, translation in mm."""
        T = np.eye(4)
        T[:3, :3] = self.rotation()
        T[:3, 3] = (self.x, self.y, self.z)
        return T

    # ------------------------------------------------------------ algebra
    def __mul__(self, other: "Location") -> "Location":
        """V+ ``self:other``: `other` expressed in this location's frame."""
        if not isinstance(other, Location):
            return NotImplemented
        return Location.from_matrix(self.matrix() @ other.matrix())

    def inverse(self) -> "Location":
        """V+ INVERSE(): ``a:INVERSE(a)`` is NULL."""
        R = self.rotation()
        T = np.eye(4)
        T[:3, :3] = R.T
        T[:3, 3] = -R.T @ np.array([self.x, self.y, self.z])
        return Location.from_matrix(T)

    def shifted(self, dx: float = 0.0, dy: float = 0.0, dz: float = 0.0) -> "Location":
        """V+ SHIFT(loc BY dx, dy, dz): translation added in the reference (world) axes."""
        return Location(self.x + dx, self.y + dy, self.z + dz, self.yaw, self.pitch, self.roll)

    def components(self) -> tuple[float, ...]:
        """(x, y, z, yaw, pitch, roll), as DECOMPOSE gives them."""
        return (self.x, self.y, self.z, self.yaw, self.pitch, self.roll)

    def position(self) -> np.ndarray:
        return np.array([self.x, self.y, self.z])


NULL = Location(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


def trans(x: float = 0.0, y: float = 0.0, z: float = 0.0, yaw: float = 0.0, pitch: float = 0.0,
          roll: float = 0.0) -> Location:
    """V+ TRANS(x, y, z, yaw, pitch, roll); missing components are 0."""
    return Location(x, y, z, yaw, pitch, roll)


def approach(loc: Location, distance_mm: float) -> Location:
    """The APPRO point: `distance_mm` back along the tool Z axis from `loc`, i.e.
    ``loc:TRANS(0, 0, -distance)``.  For a SCARA (tool Z down) a positive distance is
    above the location (V+ guide v17 L6360-6372).  DEPART d is ``approach(HERE, d)``."""
    return loc * Location(0.0, 0.0, -float(distance_mm), 0.0, 0.0, 0.0)
