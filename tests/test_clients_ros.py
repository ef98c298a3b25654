"""programs/vplus/ros_server.pg, the ROS-Industrial simple_message server, driven by a
client written from the protocol description (big-endian int32 / float32 fields:
length, message type, comm type, reply code, body).

The server runs in this process on the SCARA cell (as fast as it goes); the client
runs in a thread.  Measured joint positions are taken between major cycles, when
the client has had its reply and the robot is at rest; every cycle's joints are kept,
so that fed-back joints are compared with the joints of the cycle they were read in
(which cycle that is depends on the machine's load, the comparison does not).
"""

from __future__ import annotations

import math
import queue
import socket
import struct
import threading
import time

import numpy as np
import pytest

from twin.controller import network
from twin.runner import finish_run, start_program

MOTION_PORT, STATE_PORT = 11000, 11002
JOINT_POSITION, JOINT_TRAJ_PT, STATUS = 10, 11, 13
TOPIC, REQUEST, REPLY = 1, 2, 3
SUCCESS = 1
TARGETS = [  # rad, rad, m, rad (the Cobra's J3 is the quill, in metres for ROS)
    [0.3, 0.5, 0.015, 0.2],
    [-0.4, 1.0, 0.03, -1.0],
    [0.0, -0.8, 0.02, 3.0],
    [1.2, -1.5, 0.005, -2.5],
    [-1.0, 2.2, 0.0, 0.0],
]


def connect(port: int) -> socket.socket:
    """A client of the server's `port` (in-process runs: wherever the port was moved)."""
    for _ in range(1000):
        if port in network.port_map:
            real = network.listening_on(port)
            if real is None:
                time.sleep(0.01)
                continue
            port = real
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=30)
        except OSError:
            time.sleep(0.01)
    raise RuntimeError(f"nothing listens on {port}")


def receive(sock: socket.socket, count: int) -> bytes:
    data = b""
    while len(data) < count:
        chunk = sock.recv(count - len(data))
        if not chunk:
            raise ConnectionError("closed")
        data += chunk
    return data


def receive_message(sock: socket.socket) -> tuple[int, int, int, bytes]:
    (length,) = struct.unpack(">i", receive(sock, 4))
    data = receive(sock, length)
    kind, comm, code = struct.unpack(">iii", data[:12])
    return kind, comm, code, data[12:]


def trajectory_point(sequence: int, joints: list[float], velocity: float = 0.5) -> bytes:
    body = struct.pack(">i10fff", sequence, *(joints + [0.0] * (10 - len(joints))), velocity, 0.0)
    message = struct.pack(">iii", JOINT_TRAJ_PT, REQUEST, 0) + body
    return struct.pack(">i", len(message)) + message


class Feedback:
    """Reads the state port in its own thread: the latest joints and status, counted."""

    def __init__(self, sock: socket.socket):
        self.sock, self.count, self.joints, self.status = sock, 0, None, None
        self.lock = threading.Condition()
        threading.Thread(target=self._read, daemon=True).start()

    def _read(self) -> None:
        try:
            while True:
                kind, comm, _, body = receive_message(self.sock)
                assert comm == TOPIC
                with self.lock:
                    if kind == JOINT_POSITION:
                        self.joints = struct.unpack(">i10f", body)[1:]
                    elif kind == STATUS:
                        self.status = struct.unpack(">7i", body)
                        self.count += 1
                    self.lock.notify_all()
        except (ConnectionError, OSError):
            pass

    def after(self, count: int) -> tuple[tuple, tuple]:
        """The joints and status of a pair sent after `count` pairs had arrived."""
        with self.lock:
            assert self.lock.wait_for(lambda: self.count >= count + 2, timeout=30)
            return self.joints, self.status


class Run:
    """The server on the SCARA cell; `client(run)` in a thread; measured joints on request."""

    def __init__(self, client):
        # Free ports, so that test runs side by side never fight over 11000 and 11002.
        network.port_map.update({MOTION_PORT: 0, STATE_PORT: 0})
        try:
            self._run(client)
        finally:
            for port in (MOTION_PORT, STATE_PORT):
                network.port_map.pop(port, None)

    def _run(self, client):
        self.requests: queue.Queue = queue.Queue()
        self.history: list[np.ndarray] = []  # the robot's joints at each major cycle
        self.done = threading.Event()
        self.failure: BaseException | None = None
        self.started = start_program("programs/vplus/ros_server.pg")

        def body():
            try:
                client(self)
            except BaseException as err:  # reported by the test, not lost in the thread
                self.failure = err
            finally:
                self.done.set()

        thread = threading.Thread(target=body, daemon=True)
        thread.start()
        outcome = self.started.simulation.run(max_sim_time=600.0, on_cycle=self._between_cycles)
        thread.join(10)
        self.result = finish_run(self.started, outcome)
        if self.failure is not None:
            raise self.failure
        assert self.result.report.errors == []

    def _between_cycles(self) -> bool:
        self.history.append(self.started.simulation.cell.robot_qpos().copy())
        while not self.requests.empty():
            answer = self.requests.get()
            answer.put(self.started.simulation.cell.robot_qpos().copy())
        return self.done.is_set()

    def measured(self) -> np.ndarray:
        answer: queue.Queue = queue.Queue()
        self.requests.put(answer)
        return answer.get(timeout=30)


def float32_of_a_cycle(joints, history: list[np.ndarray]) -> float:
    """How far (in float32 steps) fed-back `joints` are from the float32 rounding of the
    nearest cycle's simulated joints: 0 or 1 when they are those joints as IEEE singles
    (the server converts degrees and mm back to rad and m in double before rounding)."""
    fed = np.array(joints[:4], dtype=np.float32).astype(float)
    steps = [np.max(np.abs(fed - q.astype(np.float32)) / np.spacing(np.abs(q).astype(np.float32)))
             for q in history]
    return float(min(steps))


def test_every_commanded_joint_target_is_reached_and_fed_back():
    log = []

    def client(run: Run):
        motion, state = connect(MOTION_PORT), connect(STATE_PORT)
        feedback = Feedback(state)
        for k, target in enumerate(TARGETS):
            motion.sendall(trajectory_point(k, target))
            kind, comm, code, body = receive_message(motion)
            measured = run.measured()
            joints, status = feedback.after(feedback.count)
            log.append((target, (kind, comm, code, struct.unpack(">i", body[:4])[0]), measured, joints, status))
        motion.close()
        state.close()

    run = Run(client)
    assert run.result.report.errors == []
    assert len(log) == len(TARGETS)
    for k, (target, reply, measured, joints, status) in enumerate(log):
        assert reply == (JOINT_TRAJ_PT, REPLY, SUCCESS, k)
        error = np.abs(measured - np.array(target))
        assert np.degrees(error[[0, 1, 3]]).max() < 0.01, (k, np.degrees(error))
        assert error[2] * 1000 < 0.01  # mm on the quill
        # The feedback is the simulated joints of one cycle, as float32 (bit for bit but
        # the last place), and it too is within the 0.01 degree bar of the target.
        assert float32_of_a_cycle(joints, run.history) <= 1.0, k
        fed_error = np.abs(np.array(joints[:4]) - np.array(target))
        assert np.degrees(fed_error[[0, 1, 3]]).max() < 0.01 and fed_error[2] * 1000 < 0.01, k
        assert joints[4:] == (0.0,) * 6
        drives, estop, code, in_error, in_motion, mode, possible = status
        assert (drives, estop, code, in_error, in_motion, mode, possible) == (1, 0, 0, 0, 0, 2, 1)
    worst = max(np.degrees(np.abs(m - np.array(t))[[0, 1, 3]]).max() for t, _, m, _, _ in log)
    print(f"worst joint-target error {worst:.5f} deg")


def test_a_client_that_leaves_mid_message_leaves_the_server_serving_the_next():
    target = [0.5, -0.5, 0.01, 1.0]
    replies = []

    def client(run: Run):
        first = connect(MOTION_PORT)
        first.sendall(trajectory_point(0, [1.0, 1.0, 0.1, 1.0])[:30])
        first.close()
        second = connect(MOTION_PORT)
        second.sendall(trajectory_point(7, target))
        replies.append(receive_message(second))
        replies.append(run.measured())
        second.close()

    run = Run(client)
    (kind, comm, code, body), measured = replies
    assert (kind, comm, code, struct.unpack(">i", body[:4])[0]) == (JOINT_TRAJ_PT, REPLY, SUCCESS, 7)
    assert np.degrees(np.abs(measured - target)[[0, 1, 3]]).max() < 0.01
    output = run.result.report.output
    assert "client left (30 bytes of a message dropped)" in output
    assert output.count("client connected") == 2
    assert run.result.report.errors == []


def test_a_state_client_that_leaves_leaves_the_feedback_serving_the_next():
    seen = []

    def client(run: Run):
        first = connect(STATE_PORT)
        seen.append(receive_message(first)[0])
        receive(first, 7)  # part of the next message, then gone
        first.close()
        second = connect(STATE_PORT)
        feedback = Feedback(second)
        joints, status = feedback.after(0)
        seen.append((joints, status, run.measured()))
        second.close()

    run = Run(client)
    first_kind, (joints, status, measured) = seen
    assert first_kind in (JOINT_POSITION, STATUS)
    assert float32_of_a_cycle(joints, run.history) <= 1.0  # the next client is fed the simulated joints
    assert np.abs(np.array(joints[:4]) - measured).max() < 1e-3  # at rest: the same pose
    assert status == (1, 0, 0, 0, 0, 2, 1)
    assert run.result.report.errors == []
