"""The served step's shorter paths (issue #38) give the numbers of the forms they stand in for, to
the bit: ``FootPieces.turned`` where every pitch is on one side of 0, ``leg_ik``'s stacked roots,
``pelvis_angles`` without the rates, ``step_table``'s one-step hip reference and the message's
dynamics columns rounded as one array."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.kinematics import pelvis
from klaw_ocp.kinematics.leg_geometry import foot_pieces, leg_ik
from klaw_ocp.serve import protocol

BODY = Body(1.8, 80)


@pytest.mark.parametrize("limit", (math.radians(35.0), 0.2, 0.0))
def test_a_foot_turned_one_way_is_the_mixed_pass(limit):
    """Each row of a one-signed batch equals the same pitch's row in a batch with both signs
    (np.where's general pass), for every set of the foot's points."""
    rng, pieces = np.random.default_rng(3), foot_pieces(BODY, limit)
    for _ in range(200):
        n = int(rng.integers(1, 30))
        p = np.abs(rng.normal(0.0, 0.6, n)) * (1.0 if rng.random() < 0.5 else -1.0)
        p[p == 0.0] = 1e-3
        other = np.array([-0.1 if p[0] > 0 else 0.1])
        for points in (slice(None), slice(1, 2)):
            alone = pieces.turned(0.3, p, points)
            mixed = pieces.turned(0.3, np.concatenate([p, other]), points)[:n]
            assert alone.shape == mixed.shape and alone.tobytes() == mixed.tobytes()


def test_leg_ik_is_the_cosine_law_by_half_angles():
    """The stacked roots give the half-angle formulas computed one by one."""
    rng = np.random.default_rng(4)
    l3, l4 = BODY.l3, BODY.l4
    for _ in range(100):
        n = int(rng.integers(1, 40))
        hip, ankle = rng.normal([0.0, 0.9], 0.3, (n, 2)), rng.normal([0.0, 0.1], 0.3, (n, 2))
        theta3, theta4, knee = leg_ik(BODY, hip, ankle)
        dx, dy = ankle[:, 0] - hip[:, 0], ankle[:, 1] - hip[:, 1]
        d = np.minimum(np.hypot(dx, dy), l3 + l4)
        s, short = (l3 + l4 + d) / 2, (l3 + l4 - d) / 2
        root = lambda v: np.sqrt(np.maximum(v, 0.0))
        delta = 2 * np.arctan2(root((s - l3) * short), root(s * (s - l4)))
        assert theta4.tobytes() == (2 * np.arctan2(root(s * short), root((s - l3) * (s - l4)))).tobytes()
        assert theta3.tobytes() == (np.arctan2(-dx, -dy) - delta).tobytes()
        assert knee.tobytes() == np.column_stack([hip[:, 0] - l3 * np.sin(theta3), hip[:, 1] - l3 * np.cos(theta3)]).tobytes()


def test_pelvis_angles_are_the_first_terms_of_the_rates():
    rng = np.random.default_rng(5)
    for _ in range(50):
        n = int(rng.integers(1, 50))
        args = (rng.uniform(0, 0.1, n), rng.uniform(0, 0.1, n), rng.uniform(0, 0.1, n), rng.uniform(0.3, 0.7, n))
        t = rng.uniform(0.0, 0.7, n)
        rotation, lowered = pelvis._angles_and_rates(*args, t, np)
        angles = pelvis.pelvis_angles(*args, t)
        assert angles[0].tobytes() == rotation[0].tobytes() and angles[1].tobytes() == lowered[0].tobytes()


def test_the_dynamics_columns_are_each_column_rounded():
    rng = np.random.default_rng(6)
    names = ("a", "b", "c")
    for n in (0, 1, 7, 40):
        table = {c: rng.normal(0, 100, n) for c in names}
        if n:
            table["b"][rng.integers(0, n)] = np.nan
            table["c"][:] = np.inf
        assert protocol._finite_columns(table, names, 4) == {c: protocol._finite(table[c], 4) for c in names}


def test_a_step_table_is_its_walks_rows():
    """step_table (its own hips and one-step hip reference) gives walk_table's rows of the step."""
    from klaw_ocp.config import ExperimentConfig
    from klaw_ocp.results import walk_table, step_table
    from klaw_ocp.stepwise import StepwiseWalk
    live = StepwiseWalk(ExperimentConfig.from_mapping({"name": "t", "body": {"height": 1.8, "mass": 80.0},
                                                       "walk": {"speed": 5.0, "steps": 1}}))
    for _ in range(3):
        live.next_step()
    whole = walk_table(live.walk)
    start = 0
    for step in live.walk.steps:
        table = step_table(step, live.body)
        rows = slice(start, start + len(table["t"]))
        for c, values in table.items():
            if c == "subphase":
                assert list(values) == list(whole[c][rows])
            else:
                assert np.ascontiguousarray(values).tobytes() == whole[c][rows].tobytes(), c
        start = rows.stop
    assert start == len(whole["t"])
