"""The fast solvers find the same walk as before: every subphase's torque parameters of the natural
walk, in each mode, against a stored reference solved by the solvers as they were before the
performance work (tests/data/natural_walk_reference.json: CasADi's rootfinder on the whole SX
transcription, IPOPT on the expanded NLP, plain shooting on SX Functions).

Each solve meets the final conditions to 1e-10; how far that leaves the parameters depends on the
conditioning (about 1e-8 relative here), so the comparison is relative, to 1e-6: a change of
formulation or discretisation moves them by far more, round-off by far less.
"""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from klaw_ocp.config import load_config
from klaw_ocp.walk import simulate_walk, walk_spec

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = json.loads((Path(__file__).parent / "data" / "natural_walk_reference.json").read_text())
RTOL = 1e-6


@pytest.mark.parametrize("mode", sorted(REFERENCE["modes"]))
def test_natural_walk_matches_the_reference(mode):
    method, stance = mode.split("/")
    spec = replace(walk_spec(load_config(ROOT / "configs" / "natural_walk.yaml"), method), stance=stance)
    walk = simulate_walk(spec)
    reference = REFERENCE["modes"][mode]
    assert len(walk.steps) == len(reference["steps"])
    np.testing.assert_allclose(walk.initial_state, reference["initial_state"], rtol=RTOL, atol=RTOL)
    for step, expected in zip(walk.steps, reference["steps"]):
        assert [s.name for s in step.subphases] == list(expected)
        for sub in step.subphases:
            for name, value in expected[sub.name].items():
                got = sub.parameters[name]
                assert abs(got - value) <= RTOL * max(1.0, abs(value)), (
                    f"step {step.index} {sub.name} {name}: {got!r} != reference {value!r}")
