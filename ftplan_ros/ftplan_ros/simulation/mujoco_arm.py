"""The MuJoCo arm: position actuators track the commands, a lock is a brake, gravity on.

The commanded path comes from a `KinematicArm` (the reference): it times the commands
as the kinematic backend does (speed limit, stamps, scheduled locks), and each MuJoCo
step the actuators are set to where it is. The arm's state is MuJoCo's. A lock engages
the joint's brake (a stiff joint equality) where the joint is at that moment, and its
actuator is set there too; the other joints keep their dynamics: with `brake_on_lock`
they are sent to the commanded point of the lock's moment and stop there under their
actuators. Obstacle updates rebuild the model (the state carried over) when the set
of obstacles changes. A step in which the arm settled (SETTLED_SPEED) reports no sweep:
it stands. Contacts come from MuJoCo's collision detection: a step reports
the pairs of bodies that came into contact during it, with their deepest penetration.
See arm.py for the interface and its units, mujoco_model.py for the model.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from ftplan_ros.core import Robot
from ftplan_ros.execution.options import Obstacles

from .arm import ArmOptions, Contact, Following, Locked, LockOutcome, Step
from .kinematic import KinematicArm
from .mujoco_model import PhysicsOptions, model_xml

SETTLED_SPEED = 0.01  # [rad/s] fastest joint speed of an arm that counts as standing


class MujocoArm:
    """An arm simulated by MuJoCo (see the module docstring and arm.py)."""

    def __init__(self, robot: Robot, q: np.ndarray, options: ArmOptions,
                 physics: PhysicsOptions, obstacles: Obstacles):
        self.robot = robot
        self.physics = physics
        self.obstacles = obstacles
        self.reference = KinematicArm(robot, q, options)
        self._checker = None
        self._build(np.array(q, dtype=float), np.zeros(robot.n_joints))
        self._clear_figures()

    options = property(lambda self: self.reference.options,
                       lambda self, value: setattr(self.reference, 'options', value))

    @property
    def q(self) -> np.ndarray:
        """The configuration now (n,) [rad]."""
        return self.data.qpos[self._qpos].copy()

    @property
    def velocity(self) -> np.ndarray:
        """The joint velocities now (n,) [rad/s]."""
        return self.data.qvel[self._dof].copy()

    @property
    def locked(self) -> dict[int, float]:
        """Locked joints and their angles [rad]."""
        return self.reference.locked

    @property
    def time(self) -> float:
        """[s] the arm's clock, advanced by `step`."""
        return self.reference.time

    @property
    def moving(self) -> bool:
        """Whether a command is under way or the arm has not settled yet."""
        return self.reference.moving or bool(np.max(np.abs(self.velocity)) > SETTLED_SPEED)

    def follow(self, positions: np.ndarray, times: np.ndarray, stamp_ns: int, now_ns: int,
               ) -> Following:
        """Follow positions (k, n) at times (k,) [s] from ROS time `stamp_ns`, from here."""
        self.reference.q = self.q
        return self.reference.follow(positions, times, stamp_ns, now_ns)

    def stop(self) -> None:
        """Stop: the actuators hold where the arm is (where it stops, after a brake)."""
        if self.reference.moving:
            self.reference.stop()
            self.reference.q = self.q

    def lock(self, joint: int, angle: float | None, stamp_ns: int, now_ns: int = 0,
             ) -> LockOutcome | None:
        """Brake `joint` now, or schedule it for ROS time `stamp_ns` (see KinematicArm.lock)."""
        if not self.reference.moving:
            self.reference.q = self.q
        return self._braked(self.reference.lock(joint, angle, stamp_ns, now_ns))

    def _braked(self, outcome: LockOutcome | None) -> LockOutcome | None:
        """Engage the brake of a joint the reference locked, where the joint is."""
        if not isinstance(outcome, Locked):
            return outcome
        angle = float(self.data.qpos[self._qpos[outcome.joint]])
        self.reference.locked[outcome.joint] = angle
        self.reference.q[outcome.joint] = angle
        self._engage(outcome.joint, angle)
        self._braked_at = self.time
        return Locked(outcome.joint, angle)

    def _engage(self, joint: int, angle: float) -> None:
        brake = self._brakes[joint]
        self.model.eq_data[brake, 0] = angle
        self.data.eq_active[brake] = 1

    def step(self, dt: float) -> Step:
        """Move on by `dt` [s] in MuJoCo steps, the actuators following the reference."""
        substeps = max(1, round(dt / self.physics.timestep))
        self._rebuild_if_obstacles_changed()
        swept, locks, contacts = [self.q], [], {}
        for _ in range(substeps):
            commanded = self.reference.q
            reference = self.reference.step(dt / substeps)
            locks += [self._braked(outcome) for outcome in reference.locks]
            self._command(self.reference.q, (self.reference.q - commanded) * substeps / dt)
            mujoco.mj_step(self.model, self.data)
            swept.append(self.q)
            self._collect_contacts(contacts)
            self._measure()
        here = self.robot.skeleton(np.stack([self.q, self.reference.q]))
        self.tracking_displacement = max(self.tracking_displacement, float(np.max(
            np.linalg.norm(here[0] - here[1], axis=-1))))
        began = [Contact(a, b, depth) for (a, b), depth in contacts.items()
                 if (a, b) not in self._touching]
        self._touching = set(contacts)
        # A settled arm creeps by less than SETTLED_SPEED: it counts as standing, or the
        # node would check and report every tick.
        return Step(np.array(swept) if self.moving else None, locks, velocity=self.velocity,
                    effort=self.effort(), contacts=began)

    def _measure(self) -> None:
        """Update the tracking error and, after a lock, the time until the arm stands."""
        self.tracking_error = max(self.tracking_error,
                                  float(np.max(np.abs(self.q - self.reference.q))))
        if self._braked_at is not None and np.max(np.abs(self.velocity)) <= SETTLED_SPEED:
            self.standstill_time = self.time - self._braked_at
            self._braked_at = None

    def effort(self) -> np.ndarray:
        """Return the joint torques (n,) [Nm]: the actuators', plus the brake's when locked."""
        effort = self.data.qfrc_actuator[self._dof].copy()
        for joint in self.locked:
            effort[joint] += self.data.qfrc_constraint[self._dof[joint]]
        return effort

    def reset(self, q: np.ndarray) -> None:
        """Stand at q (n,), every joint free, nothing commanded or scheduled."""
        self.reference.reset(q)
        self._build(np.array(q, dtype=float), np.zeros(self.robot.n_joints))
        self._clear_figures()

    def _clear_figures(self) -> None:
        self._touching: set[tuple[str, str]] = set()
        self.tracking_error = 0.0         # [rad] largest |q - commanded| of any joint so far
        self.tracking_displacement = 0.0  # [m] farthest a joint or the tool was from its
        #                                   commanded place, at the end of a step, so far
        self.standstill_time = math.nan   # [s] from the last lock until the arm stood
        self._braked_at: float | None = None

    def _collect_contacts(self, contacts: dict[tuple[str, str], float]) -> None:
        """Add this step's penetrating contacts: body pair -> deepest depth [m]."""
        for contact in self.data.contact[:self.data.ncon]:
            if contact.dist >= 0.0:
                continue
            bodies = tuple(sorted(self._body_name(g) for g in contact.geom))
            contacts[bodies] = max(contacts.get(bodies, 0.0), -float(contact.dist))

    def _command(self, position: np.ndarray, velocity: np.ndarray) -> None:
        """Set the actuators: positions (n,) [rad] and velocities (n,) [rad/s] to track."""
        n = self.robot.n_joints
        self.data.ctrl[:n] = position
        self.data.ctrl[n:] = velocity

    def _body_name(self, geom: int) -> str:
        """Return the link of a geom, or the obstacle it is ('obstacle<i>', scene order)."""
        body = int(self.model.geom_bodyid[geom])
        return self.model.body(body).name if body else self.model.geom(geom).name

    def _rebuild_if_obstacles_changed(self) -> None:
        if self.obstacles.checker is not self._checker:
            self._build(self.q, self.velocity)

    def _build(self, q: np.ndarray, velocity: np.ndarray) -> None:
        """Compile the model with the obstacles of the moment; stand at q, moving at velocity."""
        self._checker = self.obstacles.checker
        obstacles = self._checker.obstacles if self._checker is not None else ()
        self.model = mujoco.MjModel.from_xml_string(
            model_xml(self.robot, obstacles, self.physics))
        self.data = mujoco.MjData(self.model)
        names = self.robot.joint_names
        self._qpos = np.array([self.model.joint(name).qposadr[0] for name in names])
        self._dof = np.array([self.model.joint(name).dofadr[0] for name in names])
        self._brakes = [self.model.equality(f'brake_{name}').id for name in names]
        self.data.qpos[self._qpos] = q
        self.data.qvel[self._dof] = velocity
        self._command(self.reference.q, np.zeros(self.robot.n_joints))
        for joint, angle in self.locked.items():
            self._engage(joint, angle)
        mujoco.mj_forward(self.model, self.data)
