"""Per-sample progress of a long spot check: the worker reports the samples done after each chunk."""

import numpy as np

from helpers import GRID, quiet

from screening.core.model import Block, Foundation
from screening.core.excitations.white import WhiteNoise
from screening.solvers.montecarlo import monte_carlo
from screening.sweep.study import parse_study
from screening.sweep.run import SampleCount, run_sweep


def test_monte_carlo_calls_a_progress_function_after_each_chunk():
    seen = []
    monte_carlo(Block(8.67, 0.035, 0.21), Foundation(2.89e7, lam=8.95e8), WhiteNoise(1e-4), n_samples=10,
                t_end=0.5, progress=seen.append, chunk_size=4)
    assert seen == [4, 8, 10]


class _Bar:
    def __init__(self):
        self.done = 0

    def update(self, n):
        self.done += n


def test_sample_count_only_counts_up_per_spot():
    bar = _Bar()
    count = SampleCount(bar, 2)
    for spot, done in [(0, 64), (1, 64), (0, 128), (0, 64), (0, 130), (1, 130), (1, 128)]:
        count.set(spot, done)              # a late event (64 after 128) never counts twice
    assert bar.done == 260 and count.done == [130, 130]


def test_a_sweep_s_spot_checks_send_sample_events(client, tmp_path, capsys):
    study = parse_study(GRID.replace("t_end = 4.0", "t_end = 1.0") + "[mcs]\npoints = \"auto\"\ncount = 1\n"
                        "samples = 130\nmodel = \"condensed\"\n", name="s", source="s.toml")
    run_sweep(study, tmp_path / "r.nc", client=client, progress=True, log=quiet)
    topics = {t: e for t, e in client.get_events().items() if t.startswith("screening-spot-samples-")}
    assert len(topics) == 1
    done = [msg["done"] for _, msg in next(iter(topics.values()))]
    assert done == [64, 128, 130]
    err = capsys.readouterr().err
    assert "spot checks (1 x condensed, samples)" in err and "(130/130)" in err
