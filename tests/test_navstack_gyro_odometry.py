"""navstack.gyro_odometry: the wheels' distance along the gyro's heading, as the localiser
and the mapper run on it, and map -> odom back in the wheels' frame for /tf."""

from __future__ import annotations

import math

import pytest

from navstack.amcl import compose
from navstack.gyro_odometry import IMU_STALE, GyroOdometry

DT = 1 / 30  # the simulator's /odom and IMU rate


def turn_in_place(
    odo: GyroOdometry, seconds: float, rate: float, wheel_scale: float, imu_first: bool, imu: bool = True
) -> None:
    """The robot turns at ``rate`` [rad/s]; the wheels report the turn ``wheel_scale``
    times too much (both radii off), the IMU the true heading. ``imu_first``: the IMU's
    message of a stamp arrives before the odometry's."""
    for k in range(1, round(seconds / DT) + 1):
        t = k * DT
        truth = rate * t
        wheel = (0.0, 0.0, math.remainder(truth * wheel_scale, 2 * math.pi))
        if imu and imu_first:
            odo.on_imu(t, math.remainder(truth, 2 * math.pi))
        odo.fuse(t, wheel)
        if imu and not imu_first:
            odo.on_imu(t, math.remainder(truth, 2 * math.pi))


@pytest.mark.parametrize("imu_first", [True, False])
def test_a_turn_takes_the_gyros_heading_not_the_wheels(imu_first):
    odo = GyroOdometry()
    odo.on_imu(0.0, 0.0)
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    turn_in_place(odo, 2 * math.pi, 1.0, wheel_scale=1.03, imu_first=imu_first)
    truth = round(2 * math.pi / DT) * DT  # where the last message has it
    # the wheels are 3 % (10 degrees) off; the fused heading lags the IMU by at most one
    # message's worth of the wheels' own turn when the IMU comes second
    assert abs(math.remainder(odo.wheel[2] - truth, 2 * math.pi)) > math.radians(9)
    assert abs(math.remainder(odo.fused[2] - truth, 2 * math.pi)) < 0.03 * DT * 1.0 + 1e-9
    assert odo.imu_used > 0


def test_without_the_imu_it_is_the_wheel_odometry():
    odo = GyroOdometry()
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    turn_in_place(odo, 3.0, 0.5, wheel_scale=1.03, imu_first=True, imu=False)
    assert odo.fused == pytest.approx(odo.wheel)
    assert odo.imu_used == 0


def test_a_stale_imu_hands_over_to_the_wheels_without_a_jump():
    odo = GyroOdometry()
    odo.on_imu(0.0, 0.0)
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    turn_in_place(odo, 1.0, 1.0, wheel_scale=1.0, imu_first=True)
    yaw = odo.fused[2]
    # the IMU stops: the heading goes on with the wheels from where it was
    odo.fuse(1.0 + IMU_STALE + 0.05, (0.0, 0.0, 1.0 + 0.15))
    assert odo.fused[2] == pytest.approx(yaw + 0.15, abs=1e-6)


def test_a_straight_drive_keeps_the_wheels_distance():
    odo = GyroOdometry()
    for k in range(31):
        t = k * 0.1
        odo.on_imu(t, 0.0)
        odo.fuse(t, (0.1 * k, 0.0, 0.0))
    assert odo.fused == pytest.approx((3.0, 0.0, 0.0), abs=1e-9)


def test_map_to_odom_for_tf_is_in_the_wheels_frame():
    """What the localiser publishes: map -> (wheel) odom such that composed with the
    wheels' pose (odom -> base_footprint on /tf) it gives the fused estimate."""
    odo = GyroOdometry()
    odo.on_imu(0.0, 0.0)
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    turn_in_place(odo, 2.0, 0.8, wheel_scale=0.97, imu_first=True)
    odo.fuse(2.0 + DT, (0.3, 0.1, odo.wheel[2]))
    map_to_fused = (1.0, 2.0, 0.3)
    on_tf = compose(odo.map_to_wheel_odom(map_to_fused), odo.wheel)
    assert on_tf == pytest.approx(compose(map_to_fused, odo.fused), abs=1e-9)


def test_standing_still_the_gyros_bias_turns_nothing():
    odo = GyroOdometry()
    bias = math.radians(0.05)  # [rad/s]: after start-up calibration
    for k in range(301):  # 10 s still
        t = k * DT
        odo.on_imu(t, bias * t)
        odo.fuse(t, (1.0, 2.0, 0.5))
    assert odo.fused == pytest.approx((1.0, 2.0, 0.5))
    for k in range(1, 31):  # then 1 s turning at 0.5 rad/s: by the gyro
        t = 10.0 + k * DT
        odo.on_imu(t, bias * t + 0.5 * k * DT)
        odo.fuse(t, (1.0, 2.0, 0.5 + 1.03 * 0.5 * k * DT))
    assert odo.fused[2] == pytest.approx(0.5 + 0.5 + bias, abs=1e-3)  # the first step: the wheels


def drive(odo: GyroOdometry, t0: float, seconds: float, speed: float, rate: float, bias: float) -> float:
    """The robot drives from ``t0`` at ``speed`` [m/s] turning at ``rate`` [rad/s] (0, 0:
    it stands still); the gyro reads the turn plus ``bias`` [rad/s] all the time (its
    heading integrates from 0 at t = 0), the wheels the truth. Returns the end time."""
    t = t0
    for _ in range(round(seconds / DT)):
        t += DT
        x0, y0, w0 = odo.wheel
        truth_yaw = w0 + rate * DT
        odo.on_imu(t, math.remainder(truth_yaw + bias * t, 2 * math.pi))
        odo.fuse(t, (x0 + speed * DT * math.cos(truth_yaw), y0 + speed * DT * math.sin(truth_yaw), truth_yaw))
    return t


def test_a_stop_measures_the_gyros_bias_and_the_heading_after_it_is_free_of_it():
    bias = math.radians(0.1)
    odo = GyroOdometry()
    odo.on_imu(0.0, 0.0)
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    t = drive(odo, 0.0, 5.0, 0.2, 0.0, bias)
    before = odo.fused[2] - odo.wheel[2]  # the bias turned the heading while it drove
    assert before == pytest.approx(5.0 * bias, rel=0.1)
    t = drive(odo, t, 3.0, 0.0, 0.0, bias)  # a stop: the wheels stand still
    assert odo.fused[2] - odo.wheel[2] == pytest.approx(before)  # no turn while still
    t = drive(odo, t, 20.0, 0.2, 0.0, bias)
    assert odo.bias == pytest.approx(bias, rel=0.05)
    # after the stop, 20 s of driving add under 2 % of what the bias alone would turn
    assert abs(odo.fused[2] - odo.wheel[2] - before) < 0.02 * 20.0 * bias
    assert odo.gyro_heading


def test_a_short_stop_leaves_the_bias_as_it_was():
    odo = GyroOdometry()
    odo.on_imu(0.0, 0.0)
    odo.fuse(0.0, (0.0, 0.0, 0.0))
    t = drive(odo, 0.0, 2.0, 0.2, 0.0, math.radians(0.1))
    t = drive(odo, t, 0.5, 0.0, 0.0, math.radians(0.1))
    drive(odo, t, 1.0, 0.2, 0.0, math.radians(0.1))
    assert odo.bias == 0.0
