"""The J2 benchmark module runs (speed is reported, never gated): its states are what they claim
(bench.states raises otherwise) and every case gives a positive, finite rate."""
import math

from workbench.materials import bench


def test_bench_runs_on_a_small_batch():
    res = bench.run(n=200, repeat=1)
    assert set(res) == set(bench.CASES)
    for row in res.values():
        assert math.isfinite(row["current"]) and row["current"] > 0
