"""Tests of stable_worldmodel.spaces.Dict: order, dotted names, partial update/set, constraints, display."""

from __future__ import annotations

import copy
import logging
import time

import numpy as np
import pytest

from stable_worldmodel.errors import SpaceError
from stable_worldmodel.spaces import Box, Dict, Discrete, MultiDiscrete, RGBBox


def make_nested() -> Dict:
    return Dict(
        {
            "z": Discrete(5, init_value=1),
            "agent": Dict(
                {"color": RGBBox(init_value=[10, 20, 30]), "size": Box(0.0, 1.0, shape=(), init_value=0.25)},
                sampling_order=["size", "color"],
            ),
            "a": MultiDiscrete([3, 4], init_value=[2, 3]),
        }
    )


def make_pusht_like() -> Dict:
    """About 16 leaves, like the PushT variation space."""

    def part() -> Dict:
        return Dict({"color": RGBBox(), "scale": Box(0.5, 1.5, shape=()), "angle": Box(-np.pi, np.pi, shape=())})

    space = Dict(
        {
            "agent": part(),
            "block": Dict({"color": RGBBox(), "scale": Box(0.5, 1.5, shape=()), "shape": Discrete(3)}),
            "goal": Dict(
                {
                    "color": RGBBox(),
                    "pos": Box(0.0, 512.0, shape=(2,)),
                    "angle": Box(-np.pi, np.pi, shape=()),
                    "scale": Box(0.5, 1.5),
                }
            ),
            "background": Dict({"color": RGBBox()}),
            "rendering": Dict({"render_goal": Discrete(2), "line_width": Discrete(4, start=1)}),
            "physics": Dict(
                {"friction": Box(0.0, 1.0, shape=()), "damping": MultiDiscrete([3, 3]), "mass": Box(0.1, 2.0)}
            ),
        }
    )
    space.seed(12345)
    space.set_init_value(space.sample())  # leaves built without init_value start unset
    space.reset()
    return space


def assert_tree_equal(a, b):
    assert a.keys() == b.keys()
    for k in a:
        if isinstance(a[k], dict):
            assert_tree_equal(a[k], b[k])
        else:
            np.testing.assert_array_equal(a[k], b[k])


def test_keys_keep_insertion_order_and_names_are_dotted():
    space = make_nested()
    assert list(space.spaces) == ["z", "agent", "a"]  # gymnasium would sort them
    assert space.names() == ["z", "agent.color", "agent.size", "a"]
    assert space["agent.size"] is space["agent"]["size"]


def test_value_and_init_value_are_nested_dicts():
    space = make_nested()
    v = space.value
    assert v["z"] == 1 and float(v["agent"]["size"]) == 0.25
    np.testing.assert_array_equal(v["agent"]["color"], [10, 20, 30])
    assert_tree_equal(space.init_value, v)
    space.sample()
    assert_tree_equal(space.init_value, v)
    space.reset()
    assert_tree_equal(space.value, v)


def test_sampling_follows_order_and_nested_order():
    calls = []

    def leaf(name):
        return Discrete(50, constrain_fn=lambda x, n=name: calls.append(n) or True)

    space = Dict(
        {"a": leaf("a"), "inner": Dict({"x": leaf("x"), "y": leaf("y")}, sampling_order=["y", "x"]), "b": leaf("b")},
        sampling_order=["b", "inner", "a"],
    )
    space.sample()
    assert calls == ["b", "y", "x", "a"]
    assert space.sampling_order == ["b", "inner", "inner.y", "inner.x", "a"]
    calls.clear()
    space.update(["a", "inner.x"])
    assert calls[:2] == ["x", "a"]  # the draws; update's final check() then calls every constraint again


def test_sampling_order_is_a_fresh_list_of_node_paths():
    space = make_nested()
    order = space.sampling_order
    assert order == ["z", "agent", "agent.size", "agent.color", "a"]
    order.clear()  # a copy: the space keeps its order
    assert space.sampling_order == ["z", "agent", "agent.size", "agent.color", "a"]


def test_sampling_order_missing_keys_appended_with_one_warning(caplog):
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        space = Dict({"a": Discrete(2), "b": Discrete(2), "c": Discrete(2)}, sampling_order=["c"])
    assert list(space.sampling_order) == ["c", "a", "b"]
    assert len(caplog.records) == 1 and "['a', 'b']" in caplog.records[0].getMessage()


@pytest.mark.parametrize(
    "order, match",
    [(["colour"], "Did you mean 'color'"), (["color", "color"], "repeated"), ("color", "list of keys")],
)
def test_bad_sampling_order_raises_value_error(order, match):
    with pytest.raises(ValueError, match=match):
        Dict({"color": RGBBox(), "size": Discrete(2)}, sampling_order=order)


def test_update_resamples_only_named_keys():
    space = make_pusht_like()
    space.seed(0)
    before = space.value
    space.update({"agent.color", "goal"})
    after = space.value
    for path in space.names():
        top, leaf = path.split(".")
        same = np.array_equal(before[top][leaf], after[top][leaf])
        if path == "agent.color" or top == "goal":
            assert not same, path  # continuous or RGB: equal by chance with probability ~0
        else:
            assert same, path


def test_update_all_and_string_key():
    space = make_nested()
    space.seed(1)
    space.update({"all"})
    first = space.value
    space.update(["all"])
    assert any(not np.array_equal(first["agent"][k], space.value["agent"][k]) for k in ("color", "size"))
    keep = space.value
    space.update("z")  # a single string is one key
    assert_tree_equal({k: v for k, v in space.value.items() if k != "z"}, {k: v for k, v in keep.items() if k != "z"})
    keep = space.value
    space.update([])
    assert_tree_equal(space.value, keep)


def test_update_parent_and_child_resamples_whole_subtree():
    calls = []
    space = Dict(
        {
            "p": Dict(
                {
                    "x": Discrete(9, constrain_fn=lambda v: calls.append("x") or True),
                    "y": Discrete(9, constrain_fn=lambda v: calls.append("y") or True),
                }
            )
        }
    )
    space.sample()
    calls.clear()
    space.update(["p.x", "p"])
    assert calls == ["x", "y", "x", "y"]  # both drawn, then both checked by update's final check()
    calls.clear()
    space.update(["p", "p.x"])
    assert calls == ["x", "y", "x", "y"]


def test_update_unknown_key_raises_with_suggestion():
    space = make_nested()
    before = space.value
    with pytest.raises(ValueError, match="Did you mean.*'agent.color'"):
        space.update({"agent.colour"})
    with pytest.raises(SpaceError, match="'nope'"):
        space.update(["z", "nope"])
    assert_tree_equal(space.value, before)


def test_nested_constraint_is_enforced_by_update():
    inner = Dict({"lo": Discrete(10), "hi": Discrete(10, init_value=5)}, constrain_fn=lambda v: v["lo"] < v["hi"])
    space = Dict({"inner": inner, "other": Discrete(3, init_value=0)})
    space.seed(0)
    for _ in range(30):
        space.update(["inner.lo"])
        v = space.value["inner"]
        assert v["lo"] < v["hi"]
    assert space.check()


def test_dict_constraint_receives_full_value_and_impossible_raises():
    received = []
    space = Dict(
        {"a": Discrete(4, init_value=0), "n": Dict({"b": Discrete(4, init_value=0)})},
        constrain_fn=lambda v: received.append(v) or v["a"] + v["n"]["b"] == 3,
    )
    space.seed(0)
    out = space.sample()
    assert out["a"] + out["n"]["b"] == 3 and received[-1] == out
    assert space.contains(out) and not space.contains({"a": 0, "n": {"b": 0}})
    space.set_value({"a": 1, "n.b": 2})
    space.constrain_fn = lambda v: False
    with pytest.raises(RuntimeError, match="7 rejections"):
        space.sample(max_tries=7)
    assert space.value == {"a": 1, "n": {"b": 2}}  # values restored after the failure
    with pytest.raises(RuntimeError):
        space.update(["n.b"])
    assert space.value == {"a": 1, "n": {"b": 2}}


def test_dict_slow_sampling_warns_once_per_call(caplog):
    space = Dict({"a": Discrete(3)}, constrain_fn=lambda v: False)
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        with pytest.raises(RuntimeError, match="Dict.sample"):
            space.sample(max_tries=200, warn_after_s=0.0)
    assert sum("rejected by constrain_fn" in r.getMessage() for r in caplog.records) == 1


def test_value_dict_is_a_copy():
    space = make_nested()
    v = space.value
    v["agent"]["color"][0] = 99
    v["z"] = 4
    assert space.value["z"] == 1 and space.value["agent"]["color"][0] == 10


def test_sample_without_set_value_restores_everything():
    space = make_pusht_like()
    before = space.value
    draw = space.sample(set_value=False)
    assert_tree_equal(space.value, before)
    assert space.contains(draw)


def test_set_value_nested_dotted_partial():
    space = make_nested()
    space.set_value({"agent": {"size": 0.5}})
    space.set_value({"agent.color": np.array([1, 2, 3])})
    space.set_value({"a": [0, 0], "agent": {"color": [4, 5, 6]}})
    v = space.value
    assert v["z"] == 1 and float(v["agent"]["size"]) == 0.5
    np.testing.assert_array_equal(v["agent"]["color"], [4, 5, 6])
    assert v["agent"]["color"].dtype == np.uint8
    np.testing.assert_array_equal(v["a"], [0, 0])
    space.set_init_value({"z": 3, "agent.size": 0.75})
    assert space.value["z"] == 1
    space.reset()
    assert space.value["z"] == 3 and float(space.value["agent"]["size"]) == 0.75
    np.testing.assert_array_equal(space.value["agent"]["color"], [10, 20, 30])


@pytest.mark.parametrize(
    "bad, error, match",
    [
        ({"agent.colour": [1, 2, 3]}, ValueError, "Did you mean.*'agent.color'"),
        ({"agent": 3}, SpaceError, "requires a dict for nested space 'agent'"),
        ({"z": {"x": 1}}, SpaceError, "got a dict"),
        ({"agent.size": 2.0}, SpaceError, "'agent.size' inside its bounds"),
        ([("z", 1)], SpaceError, "nested or dotted"),
    ],
)
def test_set_value_errors_are_atomic(bad, error, match):
    space = make_nested()
    before = space.value
    with pytest.raises(error, match=match):
        space.set_value({"z": 4, **bad} if isinstance(bad, dict) else bad)
    assert_tree_equal(space.value, before)  # "z" was not written either


def test_init_value_argument_overrides_leaf_defaults():
    space = Dict({"a": Discrete(5), "n": Dict({"b": Box(0.0, 1.0, shape=())})}, init_value={"n.b": 0.9})
    assert space.value["a"] is None and float(space.value["n"]["b"]) == pytest.approx(0.9)
    space.sample()
    space.reset()
    assert float(space.value["n"]["b"]) == pytest.approx(0.9)


def test_contains_and_check():
    space = make_nested()
    v = space.value
    assert space.contains(v)
    assert not space.contains({**v, "extra": 1})
    assert not space.contains({k: v[k] for k in ("z", "a")})
    assert not space.contains([1, 2])
    assert not space.contains({**v, "z": 7})
    assert space.check(debug=True)


def test_check_debug_logs_failures(caplog):
    flag = {"ok": True}
    space = Dict({"n": Dict({"b": Discrete(3, init_value=0)}, constrain_fn=lambda v: flag["ok"])})
    assert space.check()
    flag["ok"] = False
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        assert not space.check()
        assert not caplog.records
        assert not space.check(debug=True)
    assert "'n (constrain_fn)'" in caplog.text and "failed check()" in caplog.text


def test_empty_dict():
    space = Dict({})
    assert space.sample() == {} and space.value == {} and space.init_value == {}
    assert space.names() == [] and list(space.sampling_order) == []
    space.update(["all"])
    space.set_value({})
    space.reset()
    assert space.contains({}) and space.check()
    assert space.to_str() == "" and "Dict" in space.describe()


def test_seed_makes_nested_sampling_deterministic():
    a, b = make_pusht_like(), make_pusht_like()
    a.seed(7)
    b.seed(np.int64(7))
    for _ in range(3):
        assert_tree_equal(a.sample(), b.sample())
        a.update(["goal", "agent.color"])
        b.update(["goal", "agent.color"])
        assert_tree_equal(a.value, b.value)


def test_seed_keyword_at_construction():
    a = Dict({"x": Discrete(100), "y": Box(0.0, 1.0, shape=(2,), seed=5)}, seed=3)
    b = Dict({"x": Discrete(100), "y": Box(0.0, 1.0, shape=(2,))})
    b.seed(3)
    assert_tree_equal(a.sample(), b.sample())


def test_mask_mapping_is_routed_per_key():
    space = Dict({"d": Discrete(4), "n": Dict({"e": Discrete(3)})})
    out = space.sample(mask={"d": np.array([0, 0, 0, 1], np.int8), "n": {"e": np.array([0, 1, 0], np.int8)}})
    assert out == {"d": 3, "n": {"e": 1}}


def test_getitem_setitem_and_invalid_entries():
    space = make_nested()
    with pytest.raises(KeyError, match="agent.size"):
        space["agent.sise"]
    space["extra"] = Discrete(2)
    assert space.names()[-1] == "extra" and list(space.sampling_order)[-1] == "extra"
    import gymnasium as gym

    with pytest.raises(SpaceError, match="gymnasium.spaces.box.Box"):
        Dict({"a": gym.spaces.Box(0, 1)})
    with pytest.raises(SpaceError, match="without '.'"):
        Dict({"a.b": Discrete(2)})
    with pytest.raises(SpaceError, match="callable"):
        Dict({}, constrain_fn="yes")


def test_to_str_is_the_tree_0_0_3_prints():
    space = make_nested()
    lines = space.to_str().splitlines()
    assert "agent:" in lines and "    color: Box(0, 255, (3,), uint8)" in lines
    assert "    size: Box(0.0, 1.0, (), float32)" in space.to_str()


def test_describe_renders_tree_with_values():
    space = make_nested()
    text = space.describe()
    lines = text.splitlines()
    assert lines[0].startswith("Dict(sampling_order=['z', 'agent', 'a'])")
    assert any(line.startswith("    color: RGBBox((3,)) = [10, 20, 30]") for line in lines)
    assert "size: Box(0.0, 1.0, (), float32) = 0.25" in text
    assert "a: MultiDiscrete([3 4]) = [2, 3]" in text


def test_deepcopy_is_independent():
    space = make_nested()
    clone = copy.deepcopy(space)
    clone.set_value({"z": 4})
    assert space.value["z"] == 1 and clone.value["z"] == 4


def test_sampling_is_fast_and_silent(caplog):
    space = make_pusht_like()
    space.seed(0)
    assert len(space.names()) == 16
    best = float("inf")
    with caplog.at_level(logging.DEBUG, logger="stable_worldmodel.spaces"):
        for _ in range(5):  # best of 5 batches: robust to a loaded machine
            t0 = time.perf_counter()
            for _ in range(50):
                space.update({"all"})
            best = min(best, (time.perf_counter() - t0) / 50)
    assert not caplog.records
    assert best < 1e-3, f"update({{'all'}}) took {best * 1e6:.0f} us"
