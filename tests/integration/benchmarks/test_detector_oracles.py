"""The oracle decomposition: every oracle at once gives back a rigid hand's truth."""

import numpy as np
import pytest

from handdb.lifting import kinematic
from tests.support import real_data
from tests.support.benchmarks import benchmark_module


@pytest.fixture(scope="module")
def bench():
    """``benchmarks/detector_oracles.py`` as a module."""
    with benchmark_module("detector_oracles") as module:
        yield module


@pytest.fixture(scope="module")
def synthetic_case(bench):
    """The quick plan's synthetic clip (a rigid hand: its truth is length-consistent)."""
    key, _, cases = bench.datasets(bench.QUICK)[-1]
    assert key == "synthetic"
    return next(iter(cases(np.random.default_rng(0))))


def mpjpe(case, xyz):
    errors = real_data.Errors(case.skeleton)
    errors.add(case.truth, xyz)
    return errors.summary()["all"]["mpjpe"]


def test_every_oracle_at_once_is_the_truth_and_none_is_not(bench, synthetic_case):
    ratios = bench.build_ratios()
    every = bench.lift_with(synthetic_case, frozenset(bench.FACTORS), ratios,
                            np.random.default_rng(1))
    none = bench.lift_with(synthetic_case, frozenset(), ratios, np.random.default_rng(1))
    assert mpjpe(synthetic_case, every) < 1.0
    assert mpjpe(synthetic_case, none) > 3.0 * mpjpe(synthetic_case, every)


def test_the_true_root_depth_is_given_only_while_lifting(bench, synthetic_case):
    estimate = kinematic.estimate_root_depth
    root = synthetic_case.skeleton.root
    with bench.true_root_depth(synthetic_case.truth, root):
        given = kinematic.estimate_root_depth(None, None, None, None, None)
        assert np.array_equal(given, synthetic_case.truth[:, root, 2])
    assert kinematic.estimate_root_depth is estimate


def test_the_labels_name_every_oracle_set_once(bench):
    labels = [bench.label(o) for o in bench.ORACLE_SETS]
    assert len(set(labels)) == len(labels)
    assert labels[0].startswith("none")
