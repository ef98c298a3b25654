"""Stream a MuJoCo run to Rerun (.rrd file and/or a live viewer), cheaply.

Cost model (Rerun 0.41): each ``rr.log`` call costs ~100+ µs of Python, so nothing
here calls ``rr.log`` per body per frame. ``sample`` copies the poses of the bodies
that can move and the joint positions into preallocated numpy buffers (a few µs);
every ``chunk_frames`` frames, and at ``close``, each buffer goes out with one
``send_columns`` call per entity on the ``sim_time`` timeline (a duration, seconds).

Entity layout in the viewer::

    world                             the MuJoCo world frame (Z up, metres)
    world/<body>                      one entity per body; Transform3D = body pose in world
    world/<body>/<geom>               its geoms: static Transform3D (pose in the body) + Mesh3D
    world/<geom>                      geoms of the world body itself (floor, tables, ...)
    robot/joints/<joint>              joint positions as scalars (hinge: degrees, slide: mm,
                                      as the controller reports them)
    program/log                       TYPE output line by line at its time, and errors (TextLog)
    program/task<n>/line              the program line task n is at, when it changes (TextLog)
    program/task<n>/line_number       the same line as a number (scalar)
    program/thread_<name>/line, .../line_number   the same for each GPL thread
    world/tcp                         the tool tip at each frame (Points3D: its path over time)
    world/plan                        the tool tip's path as planned, for each motion at the
                                      simulated time it was planned (LineStrips3D)
    world/regions/<name>              the scene's regions (Boxes3D, static)
    world/locations/<name>            the taught locations (Transform3D axes, static)
    gripper/closed, gripper/force_n   the hand's state and its grip force on the held part
    cell/events                       grasp, release, slip, drop, collision... (TextLog)
    signals/<n>                       digital signals as 0/1 scalars, at each change
    vision/<camera>                   pictures as taken, with the locators' outlines and poses
    <name>                            anything sent with ``log_scalar``

Bodies are flat under ``world`` (each carries its world pose, not a pose relative to
its parent), so a body's entity path never changes with the kinematic tree. Bodies
that cannot move (no joint in their chain to the world, not mocap) are logged once,
static; a moving body whose pose does not change (a parked or sleeping part) is sent only
when it changes. A blueprint opens the viewer on the 3D view beside the joints, the
signals and the program log. Geoms of groups 0-2 are drawn (those MuJoCo's viewer shows by default);
height fields and SDF geoms are skipped.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np
import rerun as rr
import trimesh

__all__ = ["Recorder", "geom_mesh", "entity_part"]

TIMELINE = "sim_time"
PLAN_COLOUR = (255, 160, 0)   # the planned paths, beside the executed one
PLANE_HALF_SIZE = 2.0   # metres: an infinite MuJoCo plane (size 0) is drawn this big


def _name(model: mujoco.MjModel, objtype, i: int, prefix: str) -> str:
    return mujoco.mj_id2name(model, objtype, i) or f"{prefix}{i}"


def entity_part(text: str) -> str:
    """`text` as one part of an entity path (slashes, spaces... escaped)."""
    return rr.escape_entity_path_part(text)


def geom_mesh(model: mujoco.MjModel, g: int) -> trimesh.Trimesh | None:
    """The geom's shape as a triangle mesh in the geom's own frame (None if not drawable)."""
    gtype = model.geom_type[g]
    size = model.geom_size[g]
    T = mujoco.mjtGeom
    if gtype == T.mjGEOM_PLANE:
        hx = size[0] if size[0] > 0 else PLANE_HALF_SIZE
        hy = size[1] if size[1] > 0 else PLANE_HALF_SIZE
        v = np.array([[-hx, -hy, 0], [hx, -hy, 0], [hx, hy, 0], [-hx, hy, 0]], float)
        return trimesh.Trimesh(v, np.array([[0, 1, 2], [0, 2, 3]]), process=False)
    if gtype == T.mjGEOM_SPHERE:
        return trimesh.creation.icosphere(subdivisions=2, radius=size[0])
    if gtype == T.mjGEOM_CAPSULE:
        return trimesh.creation.capsule(height=2 * size[1], radius=size[0], count=[24, 12])
    if gtype == T.mjGEOM_ELLIPSOID:
        m = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        m.apply_scale(size[:3])
        return m
    if gtype == T.mjGEOM_CYLINDER:
        return trimesh.creation.cylinder(radius=size[0], height=2 * size[1], sections=32)
    if gtype == T.mjGEOM_BOX:
        return trimesh.creation.box(extents=2 * size[:3])
    if gtype == T.mjGEOM_MESH:
        m = model.geom_dataid[g]
        va, vn = model.mesh_vertadr[m], model.mesh_vertnum[m]
        fa, fn = model.mesh_faceadr[m], model.mesh_facenum[m]
        return trimesh.Trimesh(model.mesh_vert[va:va + vn].astype(float),
                               model.mesh_face[fa:fa + fn].astype(np.int64), process=False)
    return None   # height field, SDF: not drawn


def _geom_rgba(model: mujoco.MjModel, g: int) -> np.ndarray:
    rgba = model.geom_rgba[g]
    mat = model.geom_matid[g]
    # MuJoCo's renderer: a material's colour wins unless the geom sets its own rgba.
    if mat >= 0 and np.allclose(rgba, [0.5, 0.5, 0.5, 1.0]):
        rgba = model.mat_rgba[mat]
    return np.clip(np.asarray(rgba, float), 0.0, 1.0)


def blueprint():
    """The viewer's layout: the cell in 3D, beside the joints, the signals and the program log."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(rrb.Horizontal(
        rrb.Spatial3DView(origin="world", name="cell"),
        rrb.Vertical(
            rrb.TimeSeriesView(origin="robot/joints", name="joints"),
            rrb.TimeSeriesView(origin="signals", name="signals"),
            rrb.TextLogView(origin="program", name="program"),
        ),
        column_shares=[3, 2],
    ), collapse_panels=True)


class Recorder:
    """Record a MuJoCo simulation to Rerun.

    ``path``: the .rrd file to write (parent folders are created); ``spawn``: also
    stream to a viewer started for it; ``connect``: to a viewer at that address;
    ``serve_port``: serve the recording on this loopback port for viewers that connect
    (it buffers everything for a late one). With none, the recorder is disabled and
    costs next to nothing. Call ``wants_frame``/``sample`` from the physics loop, then ``close``.
    """

    def __init__(self, model: mujoco.MjModel, path: str | Path | None, app_id: str = "twin",
                 fps: float = 30.0, spawn: bool = False, *, chunk_frames: int = 600,
                 geom_groups: tuple[int, ...] = (0, 1, 2), connect: str | None = None,
                 serve_port: int | None = None) -> None:
        if fps <= 0:
            raise ValueError("fps must be positive")
        self.model = model
        self.path = Path(path) if path is not None else None
        self.fps = float(fps)
        self.chunk_frames = max(1, int(chunk_frames))
        self.enabled = self.path is not None or spawn or connect is not None or serve_port is not None
        self._geom_groups = tuple(geom_groups)
        self._closed = False
        self._next_frame = -math.inf
        self.frames = 0

        # A dedicated stream (never the global one); none at all when disabled.
        self.rec = rr.RecordingStream(app_id) if self.enabled else None
        if self.enabled:
            sinks = []
            if spawn:
                rr.spawn(connect=False)   # start a viewer, listening on the default address
                sinks.append(rr.GrpcSink())
            if connect is not None:
                sinks.append(rr.GrpcSink(connect))
            if serve_port is not None:   # a viewer connects to us (the notebook's inline viewer)
                sinks.append(rr.GrpcServerSink(bind_ip="127.0.0.1", port=serve_port))
            if self.path is not None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                sinks.append(rr.FileSink(str(self.path)))
            self.rec.set_sinks(*sinks)
            self.rec.send_blueprint(blueprint())

        self._body_paths = self._entity_names()
        self._moving = np.flatnonzero(self._moving_mask())
        # Hinge and slide joints become scalars; free and ball joints are seen as body poses.
        jt = model.jnt_type
        self._joints = np.flatnonzero((jt == mujoco.mjtJoint.mjJNT_HINGE) | (jt == mujoco.mjtJoint.mjJNT_SLIDE))
        self._joint_qadr = model.jnt_qposadr[self._joints]
        self._joint_scale = np.where(jt[self._joints] == mujoco.mjtJoint.mjJNT_HINGE, 180.0 / math.pi, 1000.0)
        self._joint_paths = ["robot/joints/" + entity_part(_name(model, mujoco.mjtObj.mjOBJ_JOINT, j, "joint"))
                             for j in self._joints]

        n, nb, nj = self.chunk_frames, len(self._moving), len(self._joints)
        self._t = np.empty(n)
        self._pos = np.empty((n, nb, 3))
        self._quat = np.empty((n, nb, 4))      # MuJoCo order w, x, y, z
        self._q = np.empty((n, nj))
        self._k = 0                            # frames in the buffers
        self._sent_pos = np.full((nb, 3), np.nan)   # the last pose sent per moving body
        self._sent_quat = np.full((nb, 4), np.nan)
        self._tcp_site: int | None = None      # set by log_cell: the tool tip's site
        self._tcp = np.empty((n, 3))
        self._scalars: dict[str, tuple[list[float], list[float]]] = {}
        self._texts: dict[str, tuple[list[float], list[str], list[str]]] = {}
        self._plans: list[tuple[float, np.ndarray, str]] = []
        self._scalar_count = 0

        if self.enabled:
            self._log_static()

    # ---- set-up -----------------------------------------------------------

    def _entity_names(self) -> list[str]:
        m = self.model
        used: set[str] = set()
        paths = ["world"]
        for b in range(1, m.nbody):
            name = entity_part(_name(m, mujoco.mjtObj.mjOBJ_BODY, b, "body"))
            while name in used:
                name = f"{name}_{b}"
            used.add(name)
            paths.append(f"world/{name}")
        # World-body geoms live at world/<geom>: keep them clear of body names.
        self._used_names = used
        return paths

    def _moving_mask(self) -> np.ndarray:
        m = self.model
        moving = np.zeros(m.nbody, bool)
        for b in range(1, m.nbody):   # parents come before children
            moving[b] = m.body_jntnum[b] > 0 or m.body_mocapid[b] >= 0 or moving[m.body_parentid[b]]
        return moving

    def _log_static(self) -> None:
        m = self.model
        rec = self.rec
        rec.log("world", rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
        # Poses at the model's reference configuration: exact for bodies that cannot move.
        d = mujoco.MjData(m)
        mujoco.mj_kinematics(m, d)
        moving = set(self._moving.tolist())
        for b in range(1, m.nbody):
            if b not in moving:
                rec.log(self._body_paths[b], rr.Transform3D(
                    translation=d.xpos[b], quaternion=d.xquat[b][[1, 2, 3, 0]]), static=True)
        used = set(self._used_names)
        shapes: dict[tuple, rr.Mesh3D] = {}   # the pool's parts share a few shapes: each built once
        for g in range(m.ngeom):
            invisible = m.geom_rgba[g][3] == 0 and m.geom_matid[g] < 0
            if m.geom_group[g] not in self._geom_groups or invisible:
                continue
            b = m.geom_bodyid[g]
            name = entity_part(_name(m, mujoco.mjtObj.mjOBJ_GEOM, g, "geom"))
            if b == 0:
                while name in used:
                    name = f"{name}_{g}"
                used.add(name)
            rgba = (_geom_rgba(m, g) * 255).round().astype(np.uint8)
            key = (int(m.geom_type[g]), m.geom_size[g].tobytes(), int(m.geom_dataid[g]), rgba.tobytes())
            if key not in shapes:
                shapes[key] = self._geom_shape(g, rgba)
            if shapes[key] is None:
                continue
            path = f"{self._body_paths[b]}/{name}"
            if m.geom_pos[g].any() or not np.array_equal(m.geom_quat[g], [1, 0, 0, 0]):
                rec.log(path, rr.Transform3D(translation=m.geom_pos[g], quaternion=m.geom_quat[g][[1, 2, 3, 0]]),
                        static=True)
            rec.log(path, shapes[key], static=True)

    def _geom_shape(self, g: int, rgba: np.ndarray) -> rr.Mesh3D | None:
        """Geom g's Mesh3D (shaded, coloured), or None when it is not drawn."""
        m = self.model
        mesh = geom_mesh(m, g)
        if mesh is None or len(mesh.faces) == 0:
            return None
        plane = m.geom_type[g] == mujoco.mjtGeom.mjGEOM_PLANE
        shaded = mesh if plane else mesh.smooth_shaded
        return rr.Mesh3D(vertex_positions=np.asarray(shaded.vertices, np.float32),
                         triangle_indices=np.asarray(shaded.faces, np.uint32),
                         vertex_normals=np.asarray(shaded.vertex_normals, np.float32),
                         albedo_factor=rgba, face_rendering="DoubleSided" if plane else None)

    # ---- per frame --------------------------------------------------------

    def wants_frame(self, sim_time: float) -> bool:
        """True when a frame is due: the first call, then every 1/fps of simulated time."""
        return self.enabled and not self._closed and sim_time >= self._next_frame - 1e-9

    def sample(self, sim_time: float, data: mujoco.MjData) -> None:
        """Record the moving bodies' world poses and the joint positions at `sim_time`."""
        if not self.enabled or self._closed:
            return
        k = self._k
        self._t[k] = sim_time
        idx = self._moving
        self._pos[k] = data.xpos[idx]
        self._quat[k] = data.xquat[idx]
        self._q[k] = data.qpos[self._joint_qadr]
        if self._tcp_site is not None:
            self._tcp[k] = data.site_xpos[self._tcp_site]
        self._k = k + 1
        self.frames += 1
        self._next_frame = (math.floor(sim_time * self.fps + 1e-6) + 1) / self.fps
        if self._k == self.chunk_frames:
            self._flush_frames()

    def log_text(self, sim_time: float, text: str, level: str = "INFO", path: str = "program/log") -> None:
        """A line of program output, an error or a cell event, at `sim_time`; buffered and
        sent with the frames (one send_columns per entity, not one log call per line)."""
        if not self.enabled or self._closed:
            return
        times, texts, levels = self._texts.setdefault(path, ([], [], []))
        times.append(sim_time)
        texts.append(text)
        levels.append(level)

    def log_image(self, path: str, sim_time: float, rgb: np.ndarray, strips: list[np.ndarray] | None = None,
                  points: np.ndarray | None = None, labels: list[str] | None = None) -> None:
        """A camera picture at `sim_time` (sent at once: pictures are taken rarely), with
        optional 2-D overlays in its pixel coordinates: outlines (closed line strips) under
        ``path/outlines``, points with labels under ``path/found``."""
        if not self.enabled or self._closed:
            return
        self.rec.set_time(TIMELINE, duration=sim_time)
        self.rec.log(path, rr.Image(rgb))
        if strips:
            self.rec.log(f"{path}/outlines", rr.LineStrips2D(strips, colors=[0, 255, 0]))
        if points is not None and len(points):
            self.rec.log(f"{path}/found", rr.Points2D(points, labels=labels, radii=3.0, colors=[255, 64, 0]))

    def log_cell(self, cell) -> None:
        """The cell's static annotations: regions as boxes, taught locations as frames (in the
        world, through the robot base's pose), and the tool tip whose path is recorded."""
        if not self.enabled or self._closed:
            return
        from .controller.location import Location

        regions = cell.regions
        self.rec.log("world/regions", rr.Boxes3D(
            mins=regions.lo, sizes=regions.hi - regions.lo, labels=list(regions.names),
            colors=[(80, 160, 255, 60)] * len(regions.names)), static=True)
        base = cell.robot_base_pose()
        for name, values in cell.locations().items():
            T = Location(*values).matrix()
            T[:3, 3] /= 1000.0
            W = base @ T
            self.rec.log(f"world/locations/{entity_part(name)}", rr.Transform3D(
                translation=W[:3, 3], mat3x3=W[:3, :3]), static=True)
            self.rec.log(f"world/locations/{entity_part(name)}", rr.TransformAxes3D(0.05), static=True)
        self._tcp_site = cell.gripper.tcp_site

    def log_plan(self, sim_time: float, points: np.ndarray, label: str) -> None:
        """A motion's planned tool-tip path (world, metres) from `sim_time` on; buffered and
        sent with the frames."""
        if not self.enabled or self._closed:
            return
        self._plans.append((sim_time, np.asarray(points, np.float32), label))

    def log_belt_window(self, name: str, sim_time: float, world_T: np.ndarray, upstream_m: float,
                        downstream_m: float, width_m: float) -> None:
        """A belt's tracking window from `sim_time` on: a flat box between the upstream and
        downstream limits along the belt frame's X (`world_T`, metres), across the belt."""
        if not self.enabled or self._closed:
            return
        self.rec.set_time(TIMELINE, duration=sim_time)
        path = f"world/belts/{entity_part(name)}"
        self.rec.log(path, rr.Transform3D(translation=world_T[:3, 3], mat3x3=world_T[:3, :3]))
        self.rec.log(f"{path}/window", rr.Boxes3D(
            centers=[[(upstream_m + downstream_m) / 2, 0.0, 0.002]],
            half_sizes=[[(downstream_m - upstream_m) / 2, width_m / 2, 0.002]],
            labels=[f"{name} window"], colors=[(255, 200, 0, 90)]))

    def log_scalar(self, name: str, sim_time: float, value: float) -> None:
        """One sample of a signal; buffered and sent with send_columns."""
        if not self.enabled or self._closed:
            return
        ts, vs = self._scalars.setdefault(name, ([], []))
        ts.append(sim_time)
        vs.append(value)
        self._scalar_count += 1
        if self._scalar_count >= 50 * self.chunk_frames:
            self._flush_scalars()

    # ---- output -----------------------------------------------------------

    def _flush_frames(self) -> None:
        k = self._k
        if k == 0:
            return
        times = [rr.TimeColumn(TIMELINE, duration=self._t[:k].copy())]
        pos, quat = self._pos[:k], self._quat[:k]
        # Only the frames where a body's pose changed: a parked or sleeping part costs nothing
        # (one comparison for all bodies; NaN, never sent, differs from everything).
        changed = (np.any(pos != np.concatenate([self._sent_pos[None], pos[:-1]]), axis=2)
                   | np.any(quat != np.concatenate([self._sent_quat[None], quat[:-1]]), axis=2))
        self._sent_pos[:], self._sent_quat[:] = pos[-1], quat[-1]
        for i in np.flatnonzero(changed.any(axis=0)):
            rows = changed[:, i]
            self.rec.send_columns(self._body_paths[self._moving[i]],
                                  indexes=[rr.TimeColumn(TIMELINE, duration=self._t[:k][rows])],
                                  columns=rr.Transform3D.columns(translation=pos[rows, i],
                                                                 quaternion=quat[rows, i][:, [1, 2, 3, 0]]))
        if self._tcp_site is not None:
            self.rec.send_columns("world/tcp", indexes=times,
                                  columns=rr.Points3D.columns(positions=self._tcp[:k]))
        q = self._q[:k] * self._joint_scale
        for i, path in enumerate(self._joint_paths):
            self.rec.send_columns(path, indexes=times, columns=rr.Scalars.columns(scalars=q[:, i]))
        self._k = 0
        self._flush_events()

    def _flush_events(self) -> None:
        """The text lines and planned paths buffered since the last flush."""
        for path, (ts, texts, levels) in self._texts.items():
            if ts:
                self.rec.send_columns(path, indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(ts, float))],
                                      columns=rr.TextLog.columns(text=texts, level=levels))
                ts.clear()
                texts.clear()
                levels.clear()
        if self._plans:
            ts, strips, labels = zip(*self._plans)
            n = len(ts)
            self.rec.send_columns("world/plan", indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(ts, float))],
                                  columns=rr.LineStrips3D.columns(strips=list(strips), labels=list(labels),
                                                                  colors=[PLAN_COLOUR] * n, radii=[-1.5] * n))
            self._plans.clear()

    def _flush_scalars(self) -> None:
        for name, (ts, vs) in self._scalars.items():
            if ts:
                self.rec.send_columns(name, indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(ts, float))],
                                      columns=rr.Scalars.columns(scalars=np.asarray(vs, float)))
                ts.clear()
                vs.clear()
        self._scalar_count = 0

    def send_buffered(self) -> None:
        """Send what is buffered now (a notebook's run stops: its live viewer is up to date)."""
        if not self.enabled or self._closed:
            return
        self._flush_frames()
        self._flush_events()   # also when no frame was taken since the last flush
        self._flush_scalars()

    def close(self) -> None:
        """Send what is buffered, flush, and finish the .rrd file. Safe to call twice."""
        if self._closed:
            return
        if self.enabled:
            self.send_buffered()
            self.rec.flush()
            self.rec.disconnect()   # closes the file sink: writes the footer
        self._closed = True

    def __enter__(self) -> "Recorder":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
