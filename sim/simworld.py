"""SimWorld: one pybullet world (own DIRECT client), stepped by a periodic timer on the
runtime clock, speaking ROS topics on the runtime's bus (see sim/topics.py)."""

from __future__ import annotations

import functools
import logging
import math
import os
import time
from typing import TYPE_CHECKING, Literal

import numpy as np

from common.quiet_pybullet import pybullet as p

from .actuators import TrajectoryError, trajectory_from_msg
from .appearance import noisy_depth
from .description import load_world
from .gridmap import RESOLUTION, build_grid
from .objects import CATEGORIES
from .renderer import GLThread, Renderer
from .lidar import SCAN_FRAME, Lidar, LidarModel
from .lidar import episode_rng as lidar_rng
from .imu import Gyro
from .imu import episode_rng as gyro_rng
from .odometry import OdomNoise, WheelOdometry
from .odometry import episode_rng as odometry_rng
from .robot import ARM, ROBOT_COLLISION_GROUP, Robot
from .scene import Scene
from .sensors import CameraModel
from .world_spec import PlacedObject, WorldSpec

if TYPE_CHECKING:
    from .topics import SimTopics

log = logging.getLogger("sim")

#: Whether /ground_truth/pose goes on the bus when SimWorld(debug_ground_truth=...) is not
#: given. The robot's own senses are /scan, /odom, /joint_states and the camera; the exact
#: pose is a debugging aid (scoring and pictures read SimWorld.robot_pose() instead), and
#: the actors localise from /scan and /odom without it (tests/test_ground_truth_guard.py).
DEBUG_GROUND_TRUTH = False
#: [s] diff_drive_controller brakes when no command came this long (ROBOTIS' Jazzy
#: hardware_controller_manager.yaml: cmd_vel_timeout 0.5)
CMD_VEL_TIMEOUT = 0.5
#: the contact solver: at most this many iterations a substep, fewer once the residual is
#: below the threshold (None: pybullet's own, which is not 0; bench/bench_physics.py)
SOLVER_ITERATIONS = 50
SOLVER_RESIDUAL = None
#: the contact solver's iterations while the fingers hold something (the servo's setpoint
#: has reached its goal and a finger stands short of it; a grasp still closing is solved
#: with the usual ones). Friction alone keeps a held body, and a solver stopped short of
#: converging lets it creep about the line between the pads. A held body is solved at the
#: full physics rate while the arm moves and at the still hand's rate while it is carried
#: with the arm still. Over a 21 s carry (tests/test_sim_grip_hold.py), 9 grasps of
#: bottles, cans and cartons turned in the hand, in degrees (median / worst), with the
#: fingers coupled as on the real gripper: 1.2 / 7.2 at 100 iterations, 1.0 / 3.5 at 150,
#: 0.8 / 3.0 at 200; 9 grasps 5 mm higher, 1.5 / 3.4, 0.9 / 3.0 and 0.9 / 7.2. Held at the
#: full rate throughout, 100 iterations gave 2.1 / 4.4 and 1.7 / 5.8, for about the cost
#: of 150 at the still hand's rate. Bullet's friction anchors on the pads held
#: better but kept stale contacts after the fingers opened: a tilted can stayed wedged
#: between open-commanded pads.
HOLDING_SOLVER_ITERATIONS = 150
#: [Hz] physics substeps while the arm or the gripper moves: grasps, lifts and placements
#: are solved at this rate
PHYSICS_HZ = 240
#: [Hz] physics substeps while the arm and the fingers are still (driving, looking,
#: standing, carrying); None: always PHYSICS_HZ. Resting objects and the wheel odometry
#: behave as at 240 Hz (bench/bench_physics.py) for 0.4 of the cost; a held body is solved
#: with HOLDING_SOLVER_ITERATIONS.
#: ``ACTORBT_SIM_STILL_HAND_HZ=240`` (or none) sets one rate for every world of a run, also
#: in an evaluation's worker processes.
STILL_HAND_PHYSICS_HZ: int | None = 120
#: [s] the hand counts as moving this long after it stopped (what it touched settles)
HAND_SETTLE = 0.5
#: joint speeds below which the hand is still: [rad/s] the arm's, [m/s] a finger's
ARM_STILL, FINGER_STILL = 0.05, 0.01


def _still_hand_hz() -> int | None:
    """STILL_HAND_PHYSICS_HZ, or what ACTORBT_SIM_STILL_HAND_HZ asks for."""
    value = os.environ.get("ACTORBT_SIM_STILL_HAND_HZ", "").strip().lower()
    if not value:
        return STILL_HAND_PHYSICS_HZ
    if value == "none":
        return None
    if not value.isdigit():
        raise ValueError(f"ACTORBT_SIM_STILL_HAND_HZ={value!r}: a rate in Hz or none")
    return int(value)


def _on_hub(fn):
    """With a runtime, only the hub thread touches this world's pybullet client (and its EGL
    context, which is bound to the thread that made it): calls from other threads (tests,
    the CLI) are handed to the hub and wait for the result."""

    @functools.wraps(fn)
    def wrapper(self, *args, **kwargs):
        return self._on_hub_call(fn, self, *args, **kwargs)

    return wrapper


class SimWorld:
    """A simulated house (or other world) with the mobile manipulator in it.

    SimWorld(runtime, world="house", seed=0, gui=False) builds the world at once; ``start()``
    puts it on the runtime (physics timer + bus topics), ``close()`` takes it off and frees
    the pybullet client. Without a runtime (``runtime=None``) the world can still be stepped
    with ``advance(seconds)``: the CLI helpers and tests use that.

    Timing: physics runs at ``physics_hz`` in ``control_hz`` timer ticks (each tick applies
    the controllers, then steps ``physics_hz/control_hz`` substeps, then integrates the wheel
    odometry); at ``still_hand_physics_hz`` while the arm and the gripper are still and
    hold nothing (None: always ``physics_hz``; by default :data:`STILL_HAND_PHYSICS_HZ` or
    ``ACTORBT_SIM_STILL_HAND_HZ``). Robot state topics go out at ``publish_hz``, the lidar at
    ``lidar.rate_hz`` and the camera at ``camera_hz``, each only while someone subscribes.

    Senses: ``odom_noise`` (an :class:`~sim.odometry.OdomNoise`; ``OdomNoise.exact()`` for
    none) and ``lidar`` (a :class:`~sim.lidar.LidarModel`; ``lidar_noise=False`` for exact
    ranges) draw their errors from the world seed. ``debug_ground_truth`` puts the exact
    pose on ``/ground_truth/pose`` (default: :data:`DEBUG_GROUND_TRUTH`).
    ``locations``: a locations YAML for a world built from a map_server map (see
    :mod:`sim.map_world`).

    The base stops when no velocity command came for ``cmd_vel_timeout`` seconds, as
    ``diff_drive_controller`` does (0: never). ``initial_pose``: tell the localiser where
    the robot starts, as a user does with RViz's "2D Pose Estimate" (sim/topics.py);
    False leaves it to find out by itself. On ROS 2 every stamp is ROS time (the wall
    clock's epoch time, as on a real robot); on the local bus, the runtime clock.
    """

    #: publish the world's own map on /map (map_server's job); False while the robot maps
    serve_map = True
    #: the bus endpoints while started (set on the hub by start()), else None
    topics: SimTopics | None

    def __init__(
        self,
        runtime=None,
        world: str | WorldSpec = "house",
        seed: int = 0,
        gui: bool = False,
        *,
        physics_hz: int = PHYSICS_HZ,
        still_hand_physics_hz: int | None | Literal["env"] = "env",
        control_hz: int = 60,
        publish_hz: float = 30.0,
        camera_hz: float = 5.0,
        camera_size=(320, 240),
        odom_noise: OdomNoise | None = None,
        prefer_egl: bool = True,
        camera: bool = True,
        cmd_vel_timeout: float = CMD_VEL_TIMEOUT,
        map_resolution: float = RESOLUTION,
        lidar: LidarModel | None = None,
        lidar_noise: bool = True,
        debug_ground_truth: bool | None = None,
        locations=None,
        initial_pose: bool = True,
        faults=None,
        solver_iterations: int = SOLVER_ITERATIONS,
        solver_residual: float | None = SOLVER_RESIDUAL,
        holding_solver_iterations: int = HOLDING_SOLVER_ITERATIONS,
    ):
        if still_hand_physics_hz == "env":
            still_hand_physics_hz = _still_hand_hz()
        still_hz = physics_hz if still_hand_physics_hz is None else still_hand_physics_hz
        for name, hz in (("physics_hz", physics_hz), ("still_hand_physics_hz", still_hz)):
            if hz % control_hz:
                raise ValueError(f"{name} ({hz}) must be a multiple of control_hz ({control_hz})")
        self.runtime = runtime
        self.seed = int(seed)
        self.spec = load_world(world, self.seed, locations)
        self.dt = 1.0 / control_hz
        self.substeps = physics_hz // control_hz
        self.still_hand_substeps = still_hz // control_hz
        self.solver_iterations, self.solver_residual = int(solver_iterations), solver_residual
        self.holding_solver_iterations = int(holding_solver_iterations)
        self.publish_every = max(1, round(control_hz / publish_hz))
        self.lidar_model = lidar or LidarModel()
        self.scan_every = max(1, round(control_hz / self.lidar_model.rate_hz))
        self._lidar_noise = lidar_noise
        self.debug_ground_truth = bool(DEBUG_GROUND_TRUTH if debug_ground_truth is None else debug_ground_truth)
        self.camera_hz = camera_hz
        self.cmd_vel_timeout = cmd_vel_timeout
        self.give_initial_pose = initial_pose
        self.faults = faults  # a sim.faults.Faults: what the robot side breaks
        self.prefer_egl = prefer_egl
        self.gui = False
        self.cid: int | None = None  # the pybullet client; None once closed
        self._gui_requested = gui
        self._camera_enabled = camera
        self._camera_size = camera_size
        self._odom_noise = odom_noise
        self._map_resolution = map_resolution
        # the OpenGL context lives on its own thread (see GLThread): build the world there
        self._gl = GLThread() if camera else None
        try:
            self._gl_call(self._build)
        except BaseException:
            if self._gl is not None:
                self._gl.stop()
            raise

    def _gl_call(self, fn, *args, **kwargs):
        if self._gl is None:
            return fn(*args, **kwargs)
        return self._gl.call(fn, *args, **kwargs)

    def _on_hub_call(self, fn, *args, **kwargs):
        rt = self.runtime
        if rt is None:
            return fn(*args, **kwargs)
        from bt_engine.errors import RuntimeClosedError

        try:
            return rt.run_on_hub(fn, *args, **kwargs)
        except RuntimeClosedError:
            return fn(*args, **kwargs)  # the hub is gone: nothing else touches the client

    def _build(self):
        if self._gui_requested:
            if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"):
                self.cid = p.connect(p.GUI)
                self.gui = self.cid >= 0
            else:
                log.warning("--gui: no display found; running headless")
        if not self.gui:
            self.cid = p.connect(p.DIRECT)
        cid = self.cid
        assert cid is not None  # connected above: GUI when it came up, DIRECT otherwise
        if cid < 0:
            raise RuntimeError("pybullet: could not connect a physics client")
        p.resetSimulation(physicsClientId=cid)
        p.setGravity(0, 0, -9.81, physicsClientId=cid)
        residual = {} if self.solver_residual is None else {"solverResidualThreshold": self.solver_residual}
        p.setPhysicsEngineParameter(
            fixedTimeStep=self.dt,
            numSubSteps=self.substeps,
            numSolverIterations=self.solver_iterations,
            deterministicOverlappingPairs=1,
            **residual,
            physicsClientId=cid,
        )
        if self.gui:
            p.configureDebugVisualizer(p.COV_ENABLE_GUI, 0, physicsClientId=cid)
        # the EGL plugin only sees visual shapes created after it loads: load it first
        self._renderer: Renderer | None = (
            Renderer(cid, prefer_egl=self.prefer_egl and not self.gui) if self._camera_enabled else None
        )
        self.scene = Scene(cid, self.spec)
        # varied poses: the objects come to rest before the robot is there and time starts
        self.settle_steps = self.scene.settle(self.spec.settle_steps) if self.spec.settle_steps else 0
        self.robot = Robot(cid, self.spec.robot_start)
        self.odometry = WheelOdometry(self._odom_noise or OdomNoise(), odometry_rng(self.seed))
        self.gyro = Gyro(self._odom_noise or OdomNoise(), gyro_rng(self.seed))
        self.lidar = Lidar(
            cid, self.lidar_model, lidar_rng(self.seed), ray_mask=~ROBOT_COLLISION_GROUP, noise=self._lidar_noise
        )
        self.camera = CameraModel(*self._camera_size)
        # the depth camera's noise: a stream of its own from the world seed
        self._depth_rng = np.random.default_rng([self.seed, 43])
        self.grid = build_grid(self.spec, self._map_resolution)
        self.t = 0.0  # simulated seconds since construction
        self._t_offset = 0.0  # runtime clock - self.t (set by start())
        self.stamp_offset = 0.0  # ROS time - runtime clock (set by start() on ROS 2)
        self.ticks = 0
        self._traj = None
        self._hand_moved_at = 0.0  # self.t when the arm or a finger last moved
        self._substeps_now = self.substeps
        self._iterations_now = self.solver_iterations
        self._last_cmd_vel = -math.inf
        self.topics = None
        self._timers = []
        self.frames_rendered = 0
        self.render_seconds = 0.0
        js = self.robot.joint_states()[0]
        self.odometry.reset(js[0], js[1], self.robot.base_pose()[0][2])

    # ------------------------------------------------------------------ runtime glue
    def start(self):
        """Register the physics timer, the camera timer and the bus endpoints on the runtime."""
        if self.runtime is None:
            raise RuntimeError("SimWorld.start() needs a runtime (SimWorld(runtime, ...))")
        if not self._timers:
            self.runtime.run_on_hub(self._start_on_hub)
        return self

    def _start_on_hub(self):
        from .topics import SimTopics

        rt = self.runtime
        self._t_offset = rt.now() - self.t
        if rt.bus.name == "ros":  # stamps in ROS time: the wall clock's epoch time
            self.stamp_offset = time.time() - rt.now()
        self.topics = SimTopics(self, rt)
        self._timers = [rt.call_every(self.dt, self._tick), rt.call_every(1.0 / self.camera_hz, self._camera_tick)]

    def drivers_down(self):
        """Hub code: the robot's drivers stop (a robot-side process that died): its topics,
        controllers and actions go away; the physics goes on, the base brakes."""
        if self.topics is not None:
            self.topics.close()
            self.topics = None
        self.robot.set_base_velocity(0.0, 0.0)

    def drivers_up(self):
        """Hub code: the drivers start again, with no memory of goals or subscribers."""
        from .topics import SimTopics

        if self.topics is None:
            self.topics = SimTopics(self, self.runtime)

    def _camera_tick(self):
        if self.topics is not None:
            self.topics.camera_tick()

    def _stop_on_hub(self):
        for h in self._timers:
            h.cancel()
        self._timers = []
        if self.topics is not None:
            self.topics.close()
            self.topics = None

    def close(self):
        """Take the world off the runtime and free its pybullet client."""
        if self.cid is not None:
            self._on_hub_call(self._close_on_hub)

    def _close_on_hub(self):
        self._stop_on_hub()
        self._gl_call(self._disconnect)
        if self._gl is not None:
            self._gl.stop()
            self._gl = None

    def _disconnect(self):
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        if self.cid is not None and self.cid >= 0:
            try:
                p.disconnect(physicsClientId=self.cid)
            except p.error:
                pass
        self.cid = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def now(self) -> float:
        """Time on the runtime clock that corresponds to the simulated state."""
        return self.t + self._t_offset

    def ros_time(self, t: float | None = None) -> float:
        """A runtime clock time (now when None) as the stamps carry it [s]."""
        return (self.now() if t is None else t) + self.stamp_offset

    def _tick(self):
        self.step()
        if self.topics is not None:
            self.topics.after_step()

    # ------------------------------------------------------------------ physics
    def step(self):
        """One control period: controllers, then physics substeps, then odometry."""
        t_next = (self.ticks + 1) * self.dt
        if self.cmd_vel_timeout > 0 and self.now() - self._last_cmd_vel > self.cmd_vel_timeout:
            self.robot.set_base_velocity(0.0, 0.0)
        if self._traj is not None:
            pos, vel = self._traj.sample(t_next + self._t_offset)
            self.robot.set_arm(pos, vel)
        self.robot.apply(self.dt)
        follows_hand = self.still_hand_substeps != self.substeps  # else one rate: no watching
        if follows_hand:
            self._choose_substeps()
        p.stepSimulation(physicsClientId=self.cid)
        self.t = t_next
        self.ticks += 1
        q, v, _ = self.robot.joint_states()
        holding = self.robot.holding(q[6:8])
        self._choose_iterations(holding)
        # fingers pressed on a held body jitter with its contacts; the servo's setpoint says
        # whether they open or close
        fingers_moving = self.robot.gripper_moving() or (not holding and max(map(abs, v[6:8])) > FINGER_STILL)
        if follows_hand and (max(map(abs, v[2:6])) > ARM_STILL or fingers_moving):
            self._hand_moved_at = self.t
        yaw = self.robot.base_pose()[0][2]
        # the encoders see the wheel joints; the gyro the body's true rotation
        self.odometry.update(q[0], q[1], self.dt, yaw)
        self.gyro.update(yaw, self.odometry.v, self.dt)

    def _choose_iterations(self, holding: bool) -> None:
        """More solver iterations for the next control period while the fingers hold
        something (friction alone keeps it), the usual ones otherwise."""
        n = self.holding_solver_iterations if holding else self.solver_iterations
        if n != self._iterations_now:
            p.setPhysicsEngineParameter(numSolverIterations=n, physicsClientId=self.cid)
            self._iterations_now = n

    @property
    def solver_iterations_now(self) -> int:
        """The contact solver's iterations in the last control period."""
        return self._iterations_now

    def _choose_substeps(self):
        """Contact-rich work (the arm or the gripper moving or holding, or what they touched
        settling) at the full physics rate; the rest at the still hand's rate."""
        traj = self._traj
        moving = self.t - self._hand_moved_at < HAND_SETTLE or (
            traj is not None and self.t + self._t_offset < traj.end_time + HAND_SETTLE
        )
        n = self.substeps if moving else self.still_hand_substeps
        if n != self._substeps_now:
            p.setPhysicsEngineParameter(numSubSteps=n, physicsClientId=self.cid)
            self._substeps_now = n

    @property
    def physics_hz(self) -> int:
        """The physics rate of the last control period [Hz]."""
        return round(self._substeps_now / self.dt)

    @_on_hub
    def advance(self, seconds: float):
        """Step the world for ``seconds`` without a runtime (tests, CLI helpers)."""
        if self._timers:
            raise RuntimeError("advance() steps the world by hand; this world runs on a runtime timer")
        for _ in range(max(0, round(seconds / self.dt))):
            self.step()

    # ------------------------------------------------------------------ commands
    @_on_hub
    def apply_cmd_vel(self, v: float, w: float):
        self._last_cmd_vel = self.now()
        self.robot.set_base_velocity(v, w)

    @property
    def arm_trajectory(self):
        """The arm's running :class:`~sim.actuators.ArmTrajectory` (None before the first)."""
        return self._traj

    def set_arm_trajectory(self, traj):
        """Hub code (the arm controller): make ``traj`` the arm's trajectory now."""
        self._traj = traj

    @_on_hub
    def apply_joint_trajectory(self, msg):
        """trajectory_msgs/JointTrajectory for joint1..joint4, as if it came on
        /arm_controller/joint_trajectory; False (and a warning) when refused."""
        if self.topics is not None:
            return self.topics.arm.on_trajectory(msg)
        try:
            self._traj = trajectory_from_msg(msg, ARM, self.now(), self.robot.arm_positions())
        except TrajectoryError as e:
            log.warning("ignored /arm_controller/joint_trajectory: %s", e)
            return False
        return True

    @_on_hub
    def set_arm_positions(self, positions, duration: float = 2.0):
        """Convenience: a straight-line (joint space) move over ``duration`` seconds."""
        from builtin_interfaces.msg import Duration
        from trajectory_msgs.msg import JointTrajectory, JointTrajectoryPoint

        msg = JointTrajectory()
        msg.joint_names = list(ARM)
        pt = JointTrajectoryPoint()
        pt.positions = [float(x) for x in positions]
        pt.time_from_start = Duration(sec=int(duration), nanosec=int((duration % 1) * 1e9))
        msg.points = [pt]
        return self.apply_joint_trajectory(msg)

    @_on_hub
    def set_gripper(self, width: float):
        """Finger opening in metres (0 closed .. 0.09 open); fingers push with 10 N each.
        (The robot's interface is the gripper action on the controller's position scale,
        sim/controllers.py; this sets the simulated fingers directly.)"""
        self.robot.set_gripper(width)

    # ------------------------------------------------------------------ ground truth
    @_on_hub
    def robot_pose(self):
        """(x, y, yaw) of base_footprint in the map (world) frame."""
        return self.robot.base_pose()[0]

    @_on_hub
    def odom_pose(self):
        """(x, y, yaw) from wheel odometry, in the odom frame (= the start pose)."""
        o = self.odometry
        return (o.x, o.y, o.yaw)

    def object_names(self):
        return list(self.scene.objects)

    def object_category(self, name):
        return self.scene.categories[name]

    @_on_hub
    def object_pose(self, name):
        """(x, y, z, qx, qy, qz, qw): frame at the centre of the object's bounding box."""
        return self.scene.object_pose(name)

    @_on_hub
    def object_bottom(self, name) -> float:
        """[m] the height of the lowest point of an object's body (its bounding box's)."""
        return p.getAABB(self.scene.objects[name], physicsClientId=self.cid)[0][2]

    @_on_hub
    def object_poses(self):
        return {n: self.scene.object_pose(n) for n in self.scene.objects}

    @property
    def place_location(self):
        return self.spec.place

    @_on_hub
    def add_object(self, category: str, x: float, y: float, yaw: float = 0.0, name: str | None = None):
        if category not in CATEGORIES:
            raise ValueError(f"unknown category '{category}' (one of: {', '.join(CATEGORIES)})")
        if name is None:
            k = 1
            while f"{category}_{k}" in self.scene.objects:
                k += 1
            name = f"{category}_{k}"
        self._gl_call(self.scene.add_object, PlacedObject(name, category, x, y, yaw))
        return name

    @_on_hub
    def set_object_pose(self, name, x, y, yaw=0.0, z=None):
        self.scene.set_object_pose(name, x, y, yaw, z)

    @_on_hub
    def link_pose(self, link: str):
        """World pose (pos, quat) of a robot link (names as in the URDF)."""
        return self.robot.link_pose(link)

    @_on_hub
    def in_gripper(self, name) -> bool:
        """True if the object touches both fingers (a grasp, as physics sees it)."""
        b, body = self.robot.body, self.scene.objects[name]
        touching = set()
        for c in p.getContactPoints(bodyA=b, bodyB=body, physicsClientId=self.cid):
            touching.add(c[3])
        return all(self.robot.joint[j] in touching for j in ("gripper_left_joint", "gripper_right_joint"))

    @_on_hub
    def state_vector(self) -> np.ndarray:
        """Every body's pose and velocity and every joint's state: for determinism checks."""
        out = []
        bodies = [self.robot.body] + list(self.scene.objects.values())
        for body in bodies:
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=self.cid)
            lin, ang = p.getBaseVelocity(body, physicsClientId=self.cid)
            out += list(pos) + list(orn) + list(lin) + list(ang)
        q, v, _ = self.robot.joint_states()
        out += list(q) + list(v) + list(self.odom_pose())
        return np.array(out)

    # ------------------------------------------------------------------ lidar
    @_on_hub
    def scan(self):
        """One lidar scan now: ranges [m] (float32, beam i at i * angle_increment in
        base_scan; +inf no return, -inf closer than range_min). Draws from the noise stream."""
        return self.scan_now()

    def scan_now(self):
        """scan() for hub code (the topics): no hand-over."""
        return self.lidar.scan(*self.robot.link_pose(SCAN_FRAME))

    # ------------------------------------------------------------------ camera
    @property
    def renderer(self) -> Renderer:
        if self._renderer is None:
            if self.cid is None:
                raise RuntimeError("SimWorld is closed: no renderer")
            # built without camera=True: the EGL plugin would miss the existing shapes
            self._renderer = Renderer(self.cid, prefer_egl=False)
        return self._renderer

    @property
    def renderer_name(self) -> str:
        """ "egl" or "tiny"."""
        return self.renderer.name

    @_on_hub
    def render_camera(self):
        """(rgb uint8 [h, w, 3], depth float32 [h, w] metres, NaN = no return)."""
        return self._gl_call(self._render_camera)

    def _render_camera(self):
        t0 = time.perf_counter()
        pos, orn = self.robot.link_pose("camera_optical_frame")
        cam = self.camera
        look = self.spec.lighting
        rgb, buf = self.renderer.render(
            cam.width,
            cam.height,
            cam.view(pos, orn),
            cam.projection(),
            light_direction=None if look is None else look.direction,
        )
        depth = cam.linearize(buf)
        if look is not None:
            rgb = look.apply(rgb)
        if self.spec.appearance.depth_noise is not None:
            depth = noisy_depth(depth, self._depth_rng, self.spec.appearance.depth_noise, cam.fx)
        self.frames_rendered += 1
        self.render_seconds += time.perf_counter() - t0
        return rgb, depth
