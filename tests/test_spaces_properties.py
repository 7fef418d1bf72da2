"""Property-based tests (hypothesis) of stable_worldmodel.spaces over random space trees."""

from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from stable_worldmodel.spaces import Box, Dict, Discrete, MultiDiscrete, RGBBox
from stable_worldmodel.utils import flatten_dict

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])

shapes = st.sampled_from([(), (1,), (3,), (2, 2)])
seeds = st.integers(0, 2**31 - 1)


@st.composite
def float_boxes(draw):
    dtype = draw(st.sampled_from([np.float32, np.float64]))
    shape = draw(shapes)
    low = draw(st.floats(-1e3, 1e3, width=32))
    width = draw(st.floats(0.0, 1e3, width=32))
    constrained = draw(st.booleans())
    mid = low + width / 2  # keeps the constraint satisfiable: half the box passes
    fn = (lambda x, m=mid: bool(np.all(np.asarray(x) <= m))) if constrained else None
    return Box(low, low + width, shape=shape, dtype=dtype, constrain_fn=fn)


@st.composite
def int_boxes(draw):
    dtype = draw(st.sampled_from([np.int32, np.int64, np.uint8]))
    low = draw(st.integers(0, 100))
    high = draw(st.integers(low, low + 100))
    return Box(low, high, shape=draw(shapes), dtype=dtype)


@st.composite
def discretes(draw):
    n = draw(st.integers(1, 20))
    start = draw(st.integers(-5, 5))
    parity = draw(st.sampled_from([None, 0]))
    fn = None if parity is None or n < 2 else (lambda x: int(x) % 2 == 0)
    return Discrete(n, start=start, constrain_fn=fn)


@st.composite
def multidiscretes(draw):
    nvec = draw(st.lists(st.integers(1, 6), min_size=1, max_size=4))
    return MultiDiscrete(nvec)


rgbs = st.sampled_from([(3,), (2, 3), (3, 2, 2)]).map(lambda shape: RGBBox(shape=shape))
leaves = st.one_of(float_boxes(), int_boxes(), discretes(), multidiscretes(), rgbs)
names = st.text("abcdefgh_", min_size=1, max_size=4)


def dicts(children) -> st.SearchStrategy[Dict]:
    return st.dictionaries(names, children, min_size=0, max_size=4).map(Dict)


trees = st.recursive(leaves, dicts, max_leaves=10).filter(lambda s: isinstance(s, Dict))


def same_tree(a, b) -> bool:
    fa, fb = flatten_dict(a), flatten_dict(b)
    return fa.keys() == fb.keys() and all(
        np.array_equal(fa[k], fb[k]) and np.asarray(fa[k]).dtype == np.asarray(fb[k]).dtype for k in fa
    )


@SETTINGS
@given(space=leaves, seed=seeds)
def test_leaf_sample_is_contained(space, seed):
    space.seed(seed)
    for _ in range(3):
        x = space.sample()
        assert space.contains(x)
        assert space.check()


@SETTINGS
@given(space=trees, seed=seeds)
def test_dict_sample_is_contained(space, seed):
    space.seed(seed)
    x = space.sample()
    assert space.contains(x)
    assert same_tree(x, space.value)
    assert space.check()


@SETTINGS
@given(space=trees, seed=seeds)
def test_reset_restores_init_value(space, seed):
    init = space.init_value
    space.seed(seed)
    space.sample()
    space.update(["all"])
    space.reset()
    assert same_tree(space.value, init)


@SETTINGS
@given(space=trees, seed=seeds, data=st.data())
def test_update_never_touches_other_keys(space, seed, data):
    space.seed(seed)
    space.sample()
    nodes = list(space._node_paths())
    chosen = data.draw(st.lists(st.sampled_from(nodes), max_size=3) if nodes else st.just([]))
    before = flatten_dict(space.value)
    space.update(chosen)
    after = flatten_dict(space.value)
    assert after.keys() == before.keys()
    for path in before:
        if not any(path == c or path.startswith(c + ".") for c in chosen):
            assert np.array_equal(before[path], after[path]), path
    assert space.contains(space.value)


@SETTINGS
@given(space=trees, seed=seeds)
def test_set_value_round_trips_nested_and_dotted(space, seed):
    space.seed(seed)
    drawn = space.sample(set_value=False)
    space.set_value(drawn)
    assert same_tree(space.value, drawn)
    space.reset()
    space.set_value(flatten_dict(drawn))
    assert same_tree(space.value, drawn)


@SETTINGS
@given(space=trees, seed=seeds)
def test_same_seed_same_samples(space, seed):
    space.seed(seed)
    first = [space.sample() for _ in range(2)]
    space.seed(seed)
    second = [space.sample() for _ in range(2)]
    assert all(same_tree(a, b) for a, b in zip(first, second, strict=False))
