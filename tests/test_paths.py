"""Reference paths of the simulated operator: boundary conditions, derivatives, geometry."""

import numpy as np
import pytest

from leadthrough.twin.errors import OperatorError
from leadthrough.twin.paths import Circle, JointMinimumJerk, Line, MinimumJerk, minimum_jerk_phase

RNG_SEED = 20240611


def random_minimum_jerk(rng: np.random.Generator) -> MinimumJerk:
    """A minimum-jerk reach between two random points, 0.5–3 s long."""
    return MinimumJerk(rng.normal(size=3), rng.normal(size=3), rng.uniform(0.5, 3.0))


def example_paths():
    """One path of each kind, with non-trivial geometry."""
    return [
        MinimumJerk([0.3, -0.2, 0.5], [0.6, 0.1, 0.2], 1.5),
        Line([0.0, 0.4, 0.3], [0.2, -0.1, 0.6], 2.0),
        Circle([0.4, 0.0, 0.3], 0.12, [0.2, 0.3, 1.0], [1.0, 0.0, 0.0], 3.0, turns=1.5),
        JointMinimumJerk(-0.4, 1.1, 2.5),
    ]


def test_minimum_jerk_boundary_conditions():
    """Minimum jerk starts at start, ends at goal, at rest at both ends and held outside."""
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(20):
        path = random_minimum_jerk(rng)
        for t in (-1.0, 0.0):
            np.testing.assert_allclose(path.position(t), path.start, atol=1e-12)
            np.testing.assert_allclose(path.velocity(t), 0.0, atol=1e-12)
        for t in (path.duration, path.duration + 1.0):
            np.testing.assert_allclose(path.position(t), path.goal, atol=1e-12)
            np.testing.assert_allclose(path.velocity(t), 0.0, atol=1e-12)


def test_minimum_jerk_acceleration_vanishes_at_both_ends():
    """The acceleration (central difference of velocity) is zero at t = 0 and t = duration."""
    phase_rate = lambda t: minimum_jerk_phase(t, 2.0)[1]  # noqa: E731
    h = 1e-5
    for t in (0.0, 2.0):
        assert abs(phase_rate(t + h) - phase_rate(t - h)) / (2 * h) < 1e-3


@pytest.mark.parametrize("path", example_paths(), ids=lambda p: type(p).__name__)
def test_velocity_is_central_difference_of_position(path):
    """velocity(t) equals the central finite difference of position(t) at many t."""
    h = 1e-6
    for t in np.linspace(-0.5, path.duration + 0.5, 97):
        difference = (np.asarray(path.position(t + h)) - path.position(t - h)) / (2 * h)
        np.testing.assert_allclose(path.velocity(t), difference, atol=1e-6)


@pytest.mark.parametrize("path", example_paths(), ids=lambda p: type(p).__name__)
def test_array_of_times_matches_scalar_calls(path):
    """Position and velocity at an array of t stack the results at each scalar t."""
    t = np.linspace(-0.2, path.duration + 0.2, 11)
    np.testing.assert_allclose(path.position(t), np.array([path.position(ti) for ti in t]))
    np.testing.assert_allclose(path.velocity(t), np.array([path.velocity(ti) for ti in t]))


def test_minimum_jerk_peak_speed():
    """The peak speed of minimum jerk is 1.875 · distance / duration, reached at duration / 2."""
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(10):
        path = random_minimum_jerk(rng)
        t = np.linspace(0.0, path.duration, 2001)
        speed = np.linalg.norm(path.velocity(t), axis=1)
        expected = 1.875 * np.linalg.norm(path.goal - path.start) / path.duration
        assert speed.max() == pytest.approx(expected, rel=1e-9)
        assert t[speed.argmax()] == pytest.approx(path.duration / 2)


def test_line_stays_on_the_segment_and_advances_monotonically():
    """Every point of a line lies on the segment, its parameter in [0, 1] and non-decreasing."""
    start, end = np.array([0.1, -0.3, 0.4]), np.array([-0.2, 0.5, 0.7])
    path = Line(start, end, 1.2)
    points = path.position(np.linspace(-0.1, 1.3, 301))
    direction = end - start
    along = (points - start) @ direction / (direction @ direction)
    off_line = points - start - np.outer(along, direction)
    np.testing.assert_allclose(off_line, 0.0, atol=1e-12)
    assert along.min() >= -1e-12 and along.max() <= 1.0 + 1e-12
    assert np.all(np.diff(along) >= -1e-12)


def test_line_and_minimum_jerk_agree():
    """A line and a minimum-jerk reach between the same points are the same motion."""
    line = Line([0.0, 0.0, 0.0], [1.0, 2.0, 3.0], 2.0)
    reach = MinimumJerk([0.0, 0.0, 0.0], [1.0, 2.0, 3.0], 2.0)
    t = np.linspace(0.0, 2.0, 21)
    np.testing.assert_array_equal(line.position(t), reach.position(t))
    np.testing.assert_array_equal(line.velocity(t), reach.velocity(t))


def test_circle_stays_at_radius_in_the_plane():
    """A circle stays at ``radius`` from the center, in the plane through it normal to normal."""
    rng = np.random.default_rng(RNG_SEED)
    for _ in range(10):
        center, normal, direction = rng.normal(size=(3, 3))
        radius, duration, turns = rng.uniform(0.05, 0.5), rng.uniform(1, 4), rng.uniform(-2, 2)
        circle = Circle(center, radius, normal, direction, duration, turns=turns)
        offsets = circle.position(np.linspace(0.0, circle.duration, 203)) - circle.center
        np.testing.assert_allclose(np.linalg.norm(offsets, axis=1), circle.radius, rtol=1e-12)
        np.testing.assert_allclose(offsets @ circle.normal, 0.0, atol=1e-12)


def test_circle_closes_after_one_turn_and_opposes_after_half():
    """One turn ends where it started, at rest; half a turn ends diametrically opposite."""
    kwargs = {"center": [0.4, 0.1, 0.3], "radius": 0.1, "normal": [0, 0, 1], "duration": 2.0}
    full = Circle(start_direction=[0, 1, 0], **kwargs)
    np.testing.assert_allclose(full.position(2.0), full.position(0.0), atol=1e-12)
    np.testing.assert_allclose(full.velocity(2.0), 0.0, atol=1e-12)
    half = Circle(start_direction=[0, 1, 0], turns=0.5, **kwargs)
    np.testing.assert_allclose(half.position(2.0), [0.4, 0.0, 0.3], atol=1e-12)


def test_circle_starts_at_orthogonalised_direction_and_turns_right_handed():
    """The start point uses start_direction made orthogonal to normal; motion is about +normal."""
    circle = Circle([0, 0, 0], 2.0, [0, 0, 5], [1.0, 0.0, 3.0], 1.0)
    np.testing.assert_allclose(circle.position(0.0), [2.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(circle.normal, [0, 0, 1])
    for t in (0.1, 0.5, 0.9):
        assert np.cross(circle.position(t), circle.velocity(t)) @ circle.normal > 0.0


def test_joint_minimum_jerk_returns_floats_with_boundary_conditions():
    """A joint reference returns floats, from start to goal, at rest at both ends."""
    path = JointMinimumJerk(0.2, -0.7, 1.0)
    assert isinstance(path.position(0.3), float) and isinstance(path.velocity(0.3), float)
    assert path.position(0.0) == pytest.approx(0.2) and path.position(1.0) == pytest.approx(-0.7)
    assert path.velocity(0.0) == 0.0 and path.velocity(5.0) == 0.0
    assert path.velocity(0.5) == pytest.approx(1.875 * -0.9)


@pytest.mark.parametrize(
    ("make", "parameter"),
    [
        (lambda: MinimumJerk([0, 0, 0], [1, 0, 0], 0.0), "duration"),
        (lambda: MinimumJerk([0, 0, 0], [1, 0, 0], -1.0), "duration"),
        (lambda: MinimumJerk([0, 0, np.nan], [1, 0, 0], 1.0), "start"),
        (lambda: MinimumJerk([0, 0, 0], [1, 0], 1.0), "goal"),
        (lambda: Line([0, 0, 0], [np.inf, 0, 0], 1.0), "end"),
        (lambda: Line([0, 0, 0], [1, 0, 0], np.nan), "duration"),
        (lambda: Circle([0, 0, 0], 0.0, [0, 0, 1], [1, 0, 0], 1.0), "radius"),
        (lambda: Circle([0, 0, 0], 0.1, [0, 0, 0], [1, 0, 0], 1.0), "normal"),
        (lambda: Circle([0, 0, 0], 0.1, [0, 0, 1], [0, 0, 2], 1.0), "start_direction"),
        (lambda: Circle([0, 0, 0], 0.1, [0, 0, 1], [1, 0, 0], 1.0, turns=np.inf), "turns"),
        (lambda: Circle([0, np.nan, 0], 0.1, [0, 0, 1], [1, 0, 0], 1.0), "center"),
        (lambda: JointMinimumJerk(0.0, 1.0, 0.0), "duration"),
        (lambda: JointMinimumJerk(np.nan, 1.0, 1.0), "start"),
        (lambda: JointMinimumJerk(0.0, "1", 1.0), "goal"),
    ],
)
def test_invalid_parameters_raise_one_line_error_naming_them(make, parameter):
    """Invalid path parameters raise a one-line OperatorError (a ValueError) naming them."""
    with pytest.raises(OperatorError) as caught:
        make()
    assert isinstance(caught.value, ValueError)
    assert caught.value.parameter == parameter
    assert str(caught.value).startswith(f"{parameter}: ") and "\n" not in str(caught.value)
