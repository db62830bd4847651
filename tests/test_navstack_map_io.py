"""navstack.map_io: the keyframe trajectory in TUM format."""

import math

import pytest

from navstack.map_io import MapError, read_trajectory_tum, write_trajectory_tum


def test_a_trajectory_round_trips_through_the_tum_format(tmp_path):
    poses = [(0.0, 1.0, 2.0, 0.0), (0.5, 1.2, 2.1, 1.0), (1.0, -3.0, 0.5, -2.9), (1.5, 0.0, 0.0, math.pi)]
    path = write_trajectory_tum(poses, tmp_path / "map.tum")
    lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
    assert len(lines) == 4 and all(len(ln.split()) == 8 for ln in lines)  # t x y z qx qy qz qw
    back = read_trajectory_tum(path)
    for (t, x, y, yaw), (t2, x2, y2, yaw2) in zip(poses, back):
        assert (t2, x2, y2) == pytest.approx((t, x, y), abs=1e-6)
        assert math.remainder(yaw2 - yaw, 2 * math.pi) == pytest.approx(0.0, abs=1e-6)


def test_a_malformed_trajectory_line_names_its_line(tmp_path):
    path = tmp_path / "bad.tum"
    path.write_text("# header\n0 1 2 0 0 0 0 1\n1 2 3\n")
    with pytest.raises(MapError, match=r"bad.tum:3: expected 't x y z qx qy qz qw', got 3 fields"):
        read_trajectory_tum(path)
