"""Shared fixtures."""
import pytest
import yaml

from klaw_ocp.errors import ConvergenceError


@pytest.fixture
def fail_at_step(monkeypatch):
    """Make step ``index`` of any walk raise ConvergenceError(index, subphase, residual): its
    first half fails (``solve_step`` of a whole walk and the step-wise walk's ``begin_next`` both
    start there)."""
    from klaw_ocp.control.step import StepController
    original = StepController.solve_stance_stage

    def arm(index: int, subphase: str, residual: float):
        def failing(self, plan, inp, k, at_rest=False):
            if k == index:
                raise ConvergenceError(index, subphase, residual, "forced for the test")
            return original(self, plan, inp, k, at_rest)
        monkeypatch.setattr(StepController, "solve_stance_stage", failing)
    return arm


@pytest.fixture(scope="session", autouse=True)
def fresh_kernel_cache(tmp_path_factory):
    """Every test session compiles the solver kernels it needs into a cache of its own: the
    compile path runs on every machine the suite runs on, and no test depends on a cache left by
    an earlier run (klaw_ocp.kernels)."""
    import os
    previous = os.environ.get("KLAW_OCP_CACHE_DIR")
    os.environ["KLAW_OCP_CACHE_DIR"] = str(tmp_path_factory.mktemp("kernel-cache"))
    yield
    if previous is None:
        os.environ.pop("KLAW_OCP_CACHE_DIR", None)
    else:
        os.environ["KLAW_OCP_CACHE_DIR"] = previous


@pytest.fixture
def short_config(tmp_path):
    """A two-step walk at 5 km/h (1.8 m, 80 kg): the quickest config a command can run."""
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump({"name": "short", "body": {"height": 1.8, "mass": 80},
                                    "walk": {"speed": 5.0, "steps": 2}}))
    return path


@pytest.fixture
def no_solving(monkeypatch):
    """Any walk or solver built from here on fails the test."""
    import klaw_ocp.walk

    def refuse(*args, **kwargs):
        raise AssertionError("solved a walk")
    monkeypatch.setattr(klaw_ocp.walk, "simulate_walk", refuse)
    monkeypatch.setattr(klaw_ocp.walk, "make_solver", refuse)
