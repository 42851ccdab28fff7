"""Shared fixtures."""
import pytest

from klaw_ocp.errors import ConvergenceError


@pytest.fixture
def fail_at_step(monkeypatch):
    """Make step ``index`` of any walk raise ConvergenceError(index, subphase, residual)."""
    from klaw_ocp.control.step import StepController
    original = StepController.solve_step

    def arm(index: int, subphase: str, residual: float):
        def failing(self, plan, inp, k, at_rest=False):
            if k == index:
                raise ConvergenceError(index, subphase, residual, "forced for the test")
            return original(self, plan, inp, k, at_rest)
        monkeypatch.setattr(StepController, "solve_step", failing)
    return arm
