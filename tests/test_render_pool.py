"""The plots and walk.gif drawn on several cores (klaw_ocp.figures.render_pool): the same files as drawn
one after the other in this process, written where they were, and a pool that cannot be used
only means drawing here."""
import pytest
import yaml
from PIL import Image

from klaw_ocp.figures import render_pool
from klaw_ocp.figures.animation import GIF_FILE, write_animation
from klaw_ocp.figures.plots import render_plots
from klaw_ocp.figures.registry import PLOTS
from klaw_ocp.result_files import RunData
from klaw_ocp.walk import simulate_walk


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A three-step walk: every plot and a GIF of a few dozen frames."""
    path = tmp_path_factory.mktemp("pool") / "short.yaml"
    path.write_text(yaml.safe_dump({"name": "short", "body": {"height": 1.8, "mass": 80},
                                    "walk": {"speed": 5.0, "steps": 3}}))
    return RunData.from_walk(simulate_walk(path))


def test_the_pool_draws_every_plot_of_the_registry_and_the_gif_the_longest_first():
    from klaw_ocp.figures.registry import GIF_TASK, cost_order
    order = cost_order()
    assert set(order) == set(PLOTS) | {GIF_TASK} and len(order) == len(PLOTS) + 1
    assert order[0] == GIF_TASK and order[1] == "body"          # walk.gif, then the skeleton, take longest


def test_drawn_in_parallel_or_here_the_files_are_the_same(run, tmp_path, monkeypatch):
    parallel, times = render_pool.render_outputs(run, tmp_path / "a" / "plots", tmp_path / "a" / GIF_FILE)
    assert list(parallel) == [*PLOTS, "animation"]                        # the plots in their order, then the GIF
    assert times["plots"] > 0 and times["animation"] > 0
    expected = render_plots(run)
    for name, (filename, data) in expected.items():
        assert parallel[name] == tmp_path / "a" / "plots" / filename
        assert parallel[name].read_bytes() == data
    write_animation(run, tmp_path / GIF_FILE)
    assert (tmp_path / "a" / GIF_FILE).read_bytes() == (tmp_path / GIF_FILE).read_bytes()
    monkeypatch.setattr(render_pool, "usable_cores", lambda: 1)           # one core: drawn here
    here, _ = render_pool.render_outputs(run, tmp_path / "b" / "plots", None)
    assert list(here) == list(PLOTS)
    assert all(here[n].read_bytes() == parallel[n].read_bytes() for n in PLOTS)


def test_a_pool_that_breaks_means_drawing_here(run, tmp_path, monkeypatch):
    from concurrent.futures.process import BrokenProcessPool

    class Broken:
        def __init__(self, *args, **kwargs):
            pass

        def submit(self, *args, **kwargs):
            raise BrokenProcessPool("no worker")

        def shutdown(self, *args, **kwargs):
            pass
    monkeypatch.setattr("concurrent.futures.ProcessPoolExecutor", Broken)
    paths, times = render_pool.render_outputs(run, tmp_path / "plots", tmp_path / GIF_FILE)
    assert set(paths) == {*PLOTS, "animation"} and times["animation"] is not None
    with Image.open(paths["animation"]) as gif:
        assert gif.n_frames > 1


def test_a_task_s_own_error_is_raised_here(run, tmp_path):
    with pytest.raises(OSError):       # walk.gif's folder is a file: writing it fails in the worker
        (tmp_path / "file").write_text("")
        render_pool.render_outputs(run, tmp_path / "plots", tmp_path / "file" / GIF_FILE)
