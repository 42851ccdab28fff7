"""``klaw-ocp reproduce`` (issue #20): results/paper/ regenerated from the shipped configs, with our
numbers beside the paper's."""
import json
from pathlib import Path

import pytest
from matplotlib.image import imread

from klaw_ocp.cli import main

ROOT = Path(__file__).resolve().parents[1]
FILES = {"README.md", "fig8.png", "figure9_pelvic_list.png", "fig10.png", "acceleration.png", "comparison.png", "comparison.csv",
         "numbers.json", "natural_hip_height.png", "natural_gait_diagram.png", ".klaw-ocp"}


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    assert main(["reproduce", "--configs", str(ROOT / "configs"), "--out", str(out), "--quiet"]) == 0
    return out


def test_reproduce_writes_every_figure_and_the_readme(paper):
    assert {p.name for p in paper.iterdir()} == FILES
    for png in paper.glob("*.png"):
        image = imread(png)
        assert image.shape[0] > 400 and image.shape[1] > 800
        assert (image[..., :3] < 0.9).mean() > 0.01             # not blank
    assert max(p.stat().st_size for p in paper.iterdir()) < 1_500_000
    assert not list(paper.parent.glob(f"{paper.name}.partial-*"))       # swapped in, nothing left beside


def test_fig10_numbers_are_the_papers(paper):
    numbers = json.loads((paper / "numbers.json").read_text())
    for key, (sl, sf) in {"natural": (0.77, 107.5), "short": (0.50, 166.7), "long": (1.05, 79.4)}.items():
        ours = numbers["fig10"][key]
        assert ours["sl_m"] == pytest.approx(sl, abs=0.006)
        assert ours["sf_spm"] == pytest.approx(sf, abs=0.1)
    timings = numbers["timings_natural"]
    assert timings["t_swing1_end_s"] == pytest.approx(0.5 * timings["t_swing_s"])
    assert timings["t_stance_s"] == pytest.approx(timings["t_step_s"] + timings["t_ds_s"])
    assert numbers["fig8"]["fig8_2kmh"]["steps"] == 9 and numbers["fig8"]["fig8_5kmh"]["steps"] == 7
    # one bump per step: the steady step's hip excursion is a few centimetres at 5 km/h
    assert 0.02 < numbers["hip_excursion_m"]["natural"]["steady"] < 0.08


def test_readme_sets_our_numbers_beside_the_papers(paper):
    text = (paper / "README.md").read_text()
    numbers = json.loads((paper / "numbers.json").read_text())
    for needle in ("107.5", "166.7", "79.4", "37.3", "between 6 and 10", "SUN3-50", "fig8.png", "fig10.png",
                   "acceleration.png", "comparison.png", f"{numbers['fig10']['natural']['sf_spm']:.1f}"):
        assert needle in text, needle


def test_reproduce_refuses_a_folder_without_the_configs(tmp_path, capsys):
    assert main(["reproduce", "--configs", str(tmp_path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--configs" in err[0] and "natural_walk.yaml" in err[0]
    assert not (tmp_path / "out").exists()
