"""Tests of clik.trajectory: numbers of the case study, analytic velocities, validation."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clik.errors import InputError
from clik.trajectory import (
    Circle,
    Function,
    Hold,
    Line,
    PoseTrajectory,
    Reference,
    Slerp,
    Trajectory,
    TrapezoidalProfile,
    Waypoints,
    time_grid,
    trapezoidal_profile,
)

TIGHT = 1e-12  # [m] or [rad]: exact formulas
FD_RTOL = 1e-4  # analytic velocity vs central finite differences
FD_STEP = 1e-6  # [s]

P0 = np.array([0.5598, -0.15, 0.0])  # case study start (docs/method.md) [m]
P1 = np.array([0.8, -0.2, 0.0])  # case study goal [m]


def rotation_about(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    axis_array = np.asarray(axis, dtype=float)
    return pin.exp3(angle * axis_array / np.linalg.norm(axis_array))


def assert_velocity_is_derivative(trajectory: Trajectory, t: np.ndarray, atol: float) -> None:
    """Central finite differences of the position match the analytic linear velocity."""
    ahead = trajectory.sample(t + FD_STEP).position
    behind = trajectory.sample(t - FD_STEP).position
    numeric = (ahead - behind) / (2 * FD_STEP)
    np.testing.assert_allclose(
        trajectory.sample(t).linear_velocity, numeric, rtol=FD_RTOL, atol=atol
    )


# ---------------------------------------------------------------- profile


class TestProfile:
    def test_case_study_numbers(self):
        length = math.hypot(0.2402, 0.05)
        profile = TrapezoidalProfile.resolve(length, duration=3.0, cruise_speed=0.12)
        assert profile.accel_time == pytest.approx(3.0 - length / 0.12, abs=TIGHT)
        assert profile.accel_time == pytest.approx(0.955427, abs=1e-6)
        assert profile.acceleration == pytest.approx(0.12 / profile.accel_time)

    def test_phases_and_continuity(self):
        t = np.linspace(-1.0, 4.0, 5001)
        s, sdot = trapezoidal_profile(t, 2.0, 3.0, 1.0)  # t_a = 1 s, a = 1 m/s^2
        np.testing.assert_allclose(s[t <= 0], 0.0)
        np.testing.assert_allclose(s[t >= 3], 2.0)
        np.testing.assert_allclose(sdot[(t <= 0) | (t >= 3)], 0.0)
        np.testing.assert_allclose(trapezoidal_profile(0.5, 2.0, 3.0, 1.0)[0], 0.125)
        np.testing.assert_allclose(trapezoidal_profile(1.5, 2.0, 3.0, 1.0)[0], 1.0)
        np.testing.assert_allclose(trapezoidal_profile(2.5, 2.0, 3.0, 1.0)[0], 2.0 - 0.125)
        assert sdot.max() == pytest.approx(1.0)
        assert np.all(np.diff(s) >= 0) and np.max(np.abs(np.diff(s))) < 1.1e-3

    def test_default_speed_is_one_and_a_half_mean(self):
        profile = TrapezoidalProfile.resolve(3.0, duration=2.0)
        assert profile.cruise_speed == pytest.approx(2.25)
        assert profile.accel_time == pytest.approx(2.0 / 3.0)

    def test_only_speed_uses_default_accel_time(self):
        profile = TrapezoidalProfile.resolve(1.0, cruise_speed=0.5)
        assert profile.accel_time == pytest.approx(0.25)
        assert profile.duration == pytest.approx(2.25)

    def test_duration_and_accel_time(self):
        profile = TrapezoidalProfile.resolve(1.0, duration=2.0, accel_time=0.5)
        assert profile.cruise_speed == pytest.approx(1.0 / 1.5)

    def test_bounds_of_feasible_range(self):
        flat = TrapezoidalProfile(1.0, 2.0, 0.5)  # constant speed
        assert flat.accel_time == 0.0
        np.testing.assert_allclose(flat(np.array([0.0, 1.0, 2.0]))[0], [0.0, 0.5, 1.0])
        triangle = TrapezoidalProfile(1.0, 2.0, 1.0)
        assert triangle.accel_time == pytest.approx(1.0)
        assert triangle(1.0)[0] == pytest.approx(0.5)

    def test_zero_distance_stays_put(self):
        s, sdot = trapezoidal_profile(np.linspace(0, 1, 5), 0.0, 1.0)
        np.testing.assert_array_equal(s, 0.0)
        np.testing.assert_array_equal(sdot, 0.0)

    @pytest.mark.parametrize(
        ("kwargs", "field", "words"),
        [
            ({"duration": 3.0, "cruise_speed": 0.05}, "cruise_speed", "at least"),
            ({"duration": 3.0, "cruise_speed": 0.2}, "cruise_speed", "at most"),
            ({"duration": 3.0, "cruise_speed": 0.12, "accel_time": 1.0}, "accel_time", "two"),
            ({}, "duration", "a duration or a cruise_speed"),
            ({"accel_time": 0.5}, "duration", "a duration or a cruise_speed"),
            ({"duration": -1.0}, "duration", "positive"),
            ({"duration": 3.0, "cruise_speed": math.nan}, "cruise_speed", "finite"),
            ({"duration": 3.0, "accel_time": 2.0}, "accel_time", "half"),
            ({"cruise_speed": 2.0}, "accel_time", "too short"),
        ],
    )
    def test_infeasible_or_bad_arguments(self, kwargs, field, words):
        with pytest.raises(InputError, match=f"^{field}: expected .*{words}") as info:
            TrapezoidalProfile.resolve(0.2453, **kwargs)
        assert info.value.field == field

    def test_message_gives_feasible_range(self):
        with pytest.raises(InputError) as info:
            trapezoidal_profile(0.0, 0.3, 3.0, 0.05)
        assert "feasible range [0.1, 0.2] m/s" in str(info.value)

    @settings(max_examples=50, deadline=None)
    @given(
        distance=st.floats(1e-3, 10.0),
        duration=st.floats(0.1, 10.0),
        fraction=st.floats(0.0, 1.0),
    )
    def test_ends_and_peak_for_any_feasible_speed(self, distance, duration, fraction):
        speed = distance / duration * (1.0 + fraction)
        t = np.linspace(0.0, duration, 201)
        s, sdot = trapezoidal_profile(t, distance, duration, speed)
        assert s[0] == 0.0 and s[-1] == pytest.approx(distance, rel=1e-9)
        assert sdot.max() <= speed * (1 + 1e-9)
        assert np.all(np.diff(s) >= -1e-12)


# ---------------------------------------------------------------- time grid and reference


class TestTimeGrid:
    def test_case_study_grid(self):
        t = time_grid(3.0, 1e-3)
        assert t.shape == (3001,)
        assert t[0] == 0.0 and t[-1] == pytest.approx(3.0) and t[1] == pytest.approx(1e-3)

    def test_zero_duration_is_one_sample(self):
        np.testing.assert_array_equal(time_grid(0.0, 0.01), [0.0])

    @pytest.mark.parametrize(
        ("duration", "dt", "field"), [(1.0, 0.0, "dt"), (-1.0, 0.1, "duration")]
    )
    def test_rejects(self, duration, dt, field):
        with pytest.raises(InputError, match=f"^{field}: "):
            time_grid(duration, dt)


class TestReference:
    def test_rejects_nan_naming_array_and_time(self):
        t = np.array([0.0, 0.5, 1.0])
        position = np.zeros((3, 3))
        position[2, 1] = np.nan
        with pytest.raises(InputError) as info:
            Reference(t, position=position, linear_velocity=np.zeros((3, 3)))
        assert info.value.field == "trajectory"
        message = str(info.value)
        assert message.startswith("trajectory: expected finite values")
        assert "position[2]" in message and "t = 1 s" in message

    def test_rejects_inf_in_angular_velocity(self):
        omega = np.zeros((2, 3))
        omega[1, 0] = np.inf
        with pytest.raises(InputError, match=r"angular_velocity\[1\].*t = 0.1 s"):
            Reference([0.0, 0.1], rotation=np.tile(np.eye(3), (2, 1, 1)), angular_velocity=omega)

    def test_rejects_inconsistent_shapes(self):
        with pytest.raises(InputError, match=r"^trajectory.position: expected shape \(3, 3\)"):
            Reference(np.zeros(3), position=np.zeros((2, 3)), linear_velocity=np.zeros((3, 3)))

    def test_rejects_half_pairs_and_empty(self):
        with pytest.raises(InputError, match="both given or both None"):
            Reference(np.zeros(1), position=np.zeros((1, 3)))
        with pytest.raises(InputError, match="a position or a rotation"):
            Reference(np.zeros(1))

    def test_rejects_non_rotation(self):
        with pytest.raises(InputError, match=r"^trajectory.rotation: .*sample 0"):
            Reference(np.zeros(1), rotation=2 * np.eye(3)[None], angular_velocity=np.zeros((1, 3)))


# ---------------------------------------------------------------- line


class TestLine:
    line = Line(P0, P1, duration=3.0, cruise_speed=0.12)
    t = time_grid(3.0, 1e-3)

    def test_case_study_timing(self):
        length = math.hypot(0.2402, 0.05)
        assert self.line.duration == 3.0
        assert self.line.length == pytest.approx(length, abs=TIGHT)
        assert self.line.length == pytest.approx(0.245349, abs=1e-6)
        assert self.line.accel_time == pytest.approx(3.0 - length / 0.12, abs=TIGHT)

    def test_case_study_samples(self):
        reference = self.line.sample(self.t)
        assert reference.rotation is None and reference.angular_velocity is None
        np.testing.assert_allclose(reference.position[0], P0, atol=TIGHT)
        np.testing.assert_allclose(reference.position[-1], P1, atol=TIGHT)
        speed = np.linalg.norm(reference.linear_velocity, axis=1)
        assert speed.max() == pytest.approx(0.12, abs=TIGHT)
        assert speed[0] == 0.0 and speed[-1] == pytest.approx(0.0, abs=TIGHT)
        path = np.sum(np.linalg.norm(np.diff(reference.position, axis=0), axis=1))
        assert path == pytest.approx(self.line.length, rel=1e-9)

    def test_case_study_by_hand(self):
        length = math.hypot(0.2402, 0.05)
        ta = 3.0 - length / 0.12
        u = (P1 - P0) / length
        # t = 1.5 s cruises: s = v (t - ta / 2) = L / 2 by symmetry
        s_mid = 0.12 * (1.5 - ta / 2)
        assert s_mid == pytest.approx(length / 2)
        reference = self.line.sample(np.array([0.5, 1.5]))
        np.testing.assert_allclose(reference.position[1], P0 + s_mid * u, atol=TIGHT)
        np.testing.assert_allclose(reference.position[1], [0.6799, -0.175, 0.0], atol=TIGHT)
        # t = 0.5 s accelerates: s = a t^2 / 2 with a = v / ta
        s_accel = 0.5 * (0.12 / ta) * 0.5**2
        np.testing.assert_allclose(reference.position[0], P0 + s_accel * u, atol=TIGHT)
        np.testing.assert_allclose(reference.linear_velocity[0], 0.12 / ta * 0.5 * u, atol=TIGHT)

    def test_holds_outside_duration(self):
        reference = self.line.sample(np.array([-1.0, 5.0]))
        np.testing.assert_allclose(reference.position, [P0, P1], atol=TIGHT)
        np.testing.assert_array_equal(reference.linear_velocity, 0.0)
        np.testing.assert_array_equal(reference.t, [-1.0, 5.0])

    def test_velocity_is_derivative(self):
        assert_velocity_is_derivative(self.line, np.linspace(0.01, 2.99, 97), atol=1e-9)

    def test_only_duration_and_only_speed(self):
        assert Line(P0, P1, duration=3.0).cruise_speed == pytest.approx(
            1.5 * 0.245349 / 3, rel=1e-5
        )
        by_speed = Line(P0, P1, cruise_speed=0.12)
        assert by_speed.duration == pytest.approx(0.245349 / 0.12 + 0.25, rel=1e-5)

    @pytest.mark.parametrize(
        ("kwargs", "field"),
        [
            ({"start": (0, 0), "goal": P1, "duration": 1.0}, "start"),
            ({"start": P0, "goal": (0, np.nan, 0), "duration": 1.0}, "goal"),
            ({"start": P0, "goal": P1, "duration": 0.0}, "duration"),
            ({"start": P0, "goal": P1, "duration": 3.0, "cruise_speed": 0.01}, "cruise_speed"),
            ({"start": P0, "goal": P1, "duration": 3.0, "cruise_speed": 0.5}, "cruise_speed"),
            ({"start": P0, "goal": P1, "cruise_speed": -1.0}, "cruise_speed"),
            ({"start": P0, "goal": P1}, "duration"),
        ],
    )
    def test_rejects(self, kwargs, field):
        with pytest.raises(InputError, match=f"^{field}: expected") as info:
            Line(**kwargs)
        assert info.value.field == field


# ---------------------------------------------------------------- circle


class TestCircle:
    def test_radius_constant_and_arc_angle(self):
        circle = Circle((0.1, 0.2, 0.3), 0.05, start_angle=0.5, angle=1.5, duration=2.0)
        reference = circle.sample(time_grid(2.0, 1e-3))
        offsets = reference.position - circle.center
        np.testing.assert_allclose(np.linalg.norm(offsets, axis=1), 0.05, atol=TIGHT)
        np.testing.assert_allclose(offsets[:, 2], 0.0, atol=TIGHT)
        start = math.atan2(offsets[0, 1], offsets[0, 0])
        end = math.atan2(offsets[-1, 1], offsets[-1, 0])
        assert start == pytest.approx(0.5, abs=TIGHT) and end == pytest.approx(2.0, abs=TIGHT)
        np.testing.assert_allclose(
            np.einsum("ij,ij->i", offsets, reference.linear_velocity), 0.0, atol=TIGHT
        )
        assert circle.length == pytest.approx(0.075)

    def test_full_turn_returns_and_clockwise(self):
        circle = Circle(np.zeros(3), 1.0, angle=-2 * math.pi, duration=4.0)
        reference = circle.sample(np.array([0.0, 1.0, 2.0, 4.0]))
        np.testing.assert_allclose(reference.position[0], [1, 0, 0], atol=TIGHT)
        np.testing.assert_allclose(reference.position[2], [-1, 0, 0], atol=TIGHT)
        np.testing.assert_allclose(reference.position[3], [1, 0, 0], atol=1e-9)
        assert reference.linear_velocity[1, 1] < 0  # clockwise about +z

    def test_tilted_plane_velocity_is_derivative(self):
        circle = Circle((0.4, 0.0, 0.5), 0.1, normal=(1, 1, 1), angle=3.0, cruise_speed=0.2)
        t = np.linspace(0.01, circle.duration - 0.01, 89)
        reference = circle.sample(t)
        np.testing.assert_allclose(
            (reference.position - circle.center) @ circle.normal, 0.0, atol=TIGHT
        )
        assert_velocity_is_derivative(circle, t, atol=1e-8)

    def test_through_starts_at_point(self):
        start = np.array([0.5598, -0.15, 0.2])
        circle = Circle.through(start, center=(0.6, -0.15, 0.0), angle=math.pi, duration=2.0)
        reference = circle.sample(np.array([0.0, 2.0]))
        np.testing.assert_allclose(reference.position[0], start, atol=TIGHT)
        np.testing.assert_allclose(reference.position[1], [0.6402, -0.15, 0.2], atol=TIGHT)
        assert circle.radius == pytest.approx(0.0402)
        np.testing.assert_allclose(circle.center, [0.6, -0.15, 0.2])

    @pytest.mark.parametrize(
        ("kwargs", "field"),
        [
            ({"radius": 0.0}, "radius"),
            ({"radius": 1.0, "normal": (0, 0, 0)}, "normal"),
            ({"radius": 1.0, "angle": 0.0}, "angle"),
            ({"radius": 1.0, "center": (0, 0, math.inf)}, "center"),
        ],
    )
    def test_rejects(self, kwargs, field):
        kwargs = {"center": np.zeros(3), "duration": 1.0, **kwargs}
        with pytest.raises(InputError, match=f"^{field}: expected"):
            Circle(**kwargs)

    def test_through_rejects_point_on_axis(self):
        with pytest.raises(InputError, match=r"^start_point: expected"):
            Circle.through((0, 0, 1), (0, 0, 0), duration=1.0)


# ---------------------------------------------------------------- waypoints


SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5]], dtype=float)


class TestWaypoints:
    def test_sharp_corners_pass_through_points(self):
        path = Waypoints(SQUARE, duration=4.0)
        polyline = 2.0 + math.hypot(1.0, 0.5)
        assert path.length == pytest.approx(polyline)
        s_at = np.array([0.0, 1.0, 2.0, polyline])
        t_grid = np.linspace(0.0, 4.0, 400001)
        times = np.interp(s_at, path.profile(t_grid)[0], t_grid)
        np.testing.assert_allclose(path.sample(times).position, SQUARE, atol=1e-5)

    def test_sharp_velocity_is_derivative_away_from_corners(self):
        path = Waypoints(SQUARE, duration=4.0)
        t = np.linspace(0.01, 3.99, 101)
        s, _ = path.profile(t)
        away = np.min(np.abs(s[:, None] - path.breaks[None, 1:-1]), axis=1) > 1e-3
        assert_velocity_is_derivative(path, t[away], atol=1e-8)

    def test_blended_path_is_smooth_and_consistent(self):
        path = Waypoints(SQUARE, cruise_speed=0.5, blend_radius=0.2)
        t = time_grid(path.duration, 1e-3)
        reference = path.sample(t)
        np.testing.assert_allclose(reference.position[0], SQUARE[0], atol=TIGHT)
        np.testing.assert_allclose(reference.position[-1], SQUARE[-1], atol=TIGHT)
        speed = np.linalg.norm(reference.linear_velocity, axis=1)
        assert speed.max() == pytest.approx(0.5)
        jumps = np.linalg.norm(np.diff(reference.linear_velocity, axis=0), axis=1)
        # no velocity jump: |dv| <= |a| dt, |a| <= tangential 2 m/s^2 + normal 0.5^2 / 0.2
        assert jumps.max() < (2.0 + 1.25) * 1e-3
        assert_velocity_is_derivative(path, t[5:-5:37], atol=1e-7)
        # the first corner (90 deg, d = 0.2) is rounded with radius 0.2: misses (1, 0) by
        # 0.2 (sqrt 2 - 1)
        gap = np.min(np.linalg.norm(reference.position - SQUARE[1], axis=1))
        assert gap == pytest.approx(0.2 * (math.sqrt(2) - 1), abs=1e-6)
        chord = np.sum(np.linalg.norm(np.diff(reference.position, axis=0), axis=1))
        assert chord == pytest.approx(path.length, rel=1e-6)

    @pytest.mark.parametrize(
        ("points", "kwargs", "field"),
        [
            ([[0, 0, 0]], {}, "points"),
            ([[0, 0, 0], [0, 0, 0], [1, 0, 0]], {}, "points"),
            ([[0, 0, 0], [1, np.nan, 0]], {}, "points"),
            (SQUARE, {"blend_radius": -0.1}, "blend_radius"),
            (SQUARE, {"duration": None}, "duration"),
        ],
    )
    def test_rejects(self, points, kwargs, field):
        kwargs = {"duration": 1.0, **kwargs}
        with pytest.raises(InputError, match=f"^{field}: expected"):
            Waypoints(points, **kwargs)


# ---------------------------------------------------------------- hold and slerp


class TestHold:
    def test_constant_with_zero_velocity(self):
        rotation = rotation_about((0, 0, 1), 0.3)
        reference = Hold(P1, rotation, duration=1.0).sample(np.linspace(0, 2, 5))
        np.testing.assert_array_equal(reference.position, np.tile(P1, (5, 1)))
        np.testing.assert_array_equal(reference.rotation[3], rotation)
        np.testing.assert_array_equal(reference.linear_velocity, 0.0)
        np.testing.assert_array_equal(reference.angular_velocity, 0.0)

    def test_rejects(self):
        with pytest.raises(InputError, match=r"^position: expected"):
            Hold()
        with pytest.raises(InputError, match=r"^rotation: expected a rotation matrix"):
            Hold(rotation=np.ones((3, 3)))


class TestSlerp:
    start = rotation_about((1, 2, 3), 0.7)
    goal = rotation_about((-1, 0.5, 0.2), 1.9) @ start

    def test_endpoints_and_angle(self):
        slerp = Slerp(self.start, self.goal, duration=2.0)
        reference = slerp.sample(np.array([0.0, 2.0]))
        np.testing.assert_allclose(reference.rotation[0], self.start, atol=TIGHT)
        np.testing.assert_allclose(reference.rotation[1], self.goal, atol=1e-12)
        assert slerp.angle == pytest.approx(1.9)
        assert reference.position is None

    def test_angular_velocity_is_world_derivative(self):
        slerp = Slerp(self.start, self.goal, cruise_speed=1.0)
        t = np.linspace(0.01, slerp.duration - 0.01, 53)
        ahead, now = slerp.sample(t + FD_STEP).rotation, slerp.sample(t).rotation
        behind = slerp.sample(t - FD_STEP).rotation
        numeric = np.array([pin.log3(a @ b.T) for a, b in zip(ahead, behind, strict=True)]) / (
            2 * FD_STEP
        )
        np.testing.assert_allclose(
            slerp.sample(t).angular_velocity, numeric, rtol=FD_RTOL, atol=1e-8
        )
        one_sided = np.array([pin.log3(a @ b.T) for a, b in zip(ahead, now, strict=True)]) / FD_STEP
        np.testing.assert_allclose(
            slerp.sample(t).angular_velocity, one_sided, rtol=1e-3, atol=1e-5
        )
        peak = np.linalg.norm(slerp.sample(t).angular_velocity, axis=1).max()
        assert peak == pytest.approx(1.0)

    def test_stays_on_geodesic(self):
        slerp = Slerp(self.start, self.goal, duration=2.0)
        rotations = slerp.sample(np.linspace(0, 2, 11)).rotation
        vectors = np.array([pin.log3(self.start.T @ r) for r in rotations])
        np.testing.assert_allclose(np.cross(vectors, slerp.axis), 0.0, atol=1e-12)

    def test_identical_rotations_hold(self):
        reference = Slerp(self.start, self.start, duration=1.0).sample(np.linspace(0, 1, 3))
        np.testing.assert_allclose(reference.rotation, np.tile(self.start, (3, 1, 1)))
        np.testing.assert_array_equal(reference.angular_velocity, 0.0)

    def test_rejects(self):
        with pytest.raises(InputError, match=r"^goal_rotation: expected a rotation matrix"):
            Slerp(self.start, -self.goal, duration=1.0)  # det = -1
        with pytest.raises(InputError, match=r"^cruise_speed: expected .*rad/s"):
            Slerp(self.start, self.goal, duration=1.0, cruise_speed=0.5)


# ---------------------------------------------------------------- pose and function


class TestPose:
    def test_combines_and_holds_shorter_part(self):
        pose = PoseTrajectory(
            Line(P0, P1, duration=3.0, cruise_speed=0.12),
            Slerp(np.eye(3), rotation_about((0, 0, 1), 1.0), duration=1.0),
        )
        assert pose.duration == 3.0
        reference = pose.sample(np.array([0.0, 2.0, 3.0]))
        np.testing.assert_allclose(reference.rotation[1], rotation_about((0, 0, 1), 1.0))
        np.testing.assert_array_equal(reference.angular_velocity[1], 0.0)
        np.testing.assert_allclose(reference.position[2], P1, atol=TIGHT)

    def test_rejects_wrong_parts(self):
        line = Line(P0, P1, duration=1.0)
        with pytest.raises(InputError, match=r"^orientation: expected a trajectory that gives"):
            PoseTrajectory(line, line)
        with pytest.raises(InputError, match=r"^position: expected a Trajectory"):
            PoseTrajectory("line", line)  # type: ignore[arg-type]


def helix(t):
    return (
        np.array([math.cos(t), math.sin(t), 0.1 * t]),
        np.array([-math.sin(t), math.cos(t), 0.1]),
    )


class TestFunction:
    def test_per_sample_and_vectorized_agree(self):
        def vectorized(t):
            return (
                np.stack([np.cos(t), np.sin(t), 0.1 * t], axis=1),
                np.stack([-np.sin(t), np.cos(t), np.full_like(t, 0.1)], axis=1),
            )

        t = np.linspace(-0.5, 2.5, 31)
        loop = Function(helix, 2.0).sample(t)
        vector = Function(vectorized, 2.0, vectorized=True).sample(t)
        np.testing.assert_allclose(loop.position, vector.position, atol=TIGHT)
        np.testing.assert_allclose(loop.linear_velocity, vector.linear_velocity, atol=TIGHT)
        np.testing.assert_allclose(loop.position[-1], helix(2.0)[0])
        np.testing.assert_array_equal(loop.linear_velocity[[0, -1]], 0.0)  # held outside

    def test_names_time_of_nan(self):
        def broken(t):
            x, xdot = helix(t)
            return (x, xdot * math.nan) if t > 0.5 else (x, xdot)

        with pytest.raises(InputError) as info:
            Function(broken, 1.0).sample(np.array([0.0, 0.25, 0.75, 1.0]))
        assert info.value.field == "trajectory"
        assert "xdot_d" in str(info.value) and "t = 0.75 s" in str(info.value)

    def test_names_time_of_nan_vectorized(self):
        def broken(t):
            x = np.zeros((t.size, 3))
            x[t > 0.5, 0] = np.inf
            return x, np.zeros((t.size, 3))

        with pytest.raises(InputError, match=r"x_d\[2\].*t = 0.75 s"):
            Function(broken, 1.0, vectorized=True).sample(np.array([0.0, 0.25, 0.75]))

    def test_names_time_of_wrong_shape(self):
        with pytest.raises(InputError, match=r"x_d of shape \(2,\) at t = 0 s"):
            Function(lambda t: ((0.0, 0.0), (0.0, 0.0, 0.0)), 1.0).sample(np.zeros(1))
        with pytest.raises(InputError, match=r"^trajectory: expected a callable returning"):
            Function(lambda t: 1.0, 1.0).sample(np.zeros(1))

    def test_rejects_arguments(self):
        with pytest.raises(InputError, match=r"^f: expected a callable"):
            Function(3.0, 1.0)  # type: ignore[arg-type]
        with pytest.raises(InputError, match=r"^duration: expected a positive"):
            Function(helix, 0.0)

    def test_rejects_bad_times(self):
        with pytest.raises(InputError, match=r"^t: expected a finite 1-D array"):
            Function(helix, 1.0).sample(np.array([0.0, np.nan]))
