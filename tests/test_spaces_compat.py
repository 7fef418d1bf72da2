"""Release-0.0.3 behaviours of stable_worldmodel.spaces (observed on 0.0.3; reset_variation_space on 0.1.1).

Each test states what the old release did and what we do where we deliberately differ.
"""

from __future__ import annotations

import logging
from unittest import mock

import numpy as np
import pytest

import stable_worldmodel as swm
from stable_worldmodel import spaces
from stable_worldmodel.errors import SpaceError
from stable_worldmodel.spaces import Box, Dict, Discrete, MultiDiscrete, RGBBox, SpaceCheckError, reset_variation_space


def game_space(**leaf_kwargs) -> Dict:
    """A three-level tree with an explicit order at every level (0.0.3 sorts keys, so orders are given)."""

    def leaf(**kw):
        return Discrete(10, **{**leaf_kwargs, **kw})

    world = Dict({"w": leaf(init_value=1), "h": leaf(init_value=2)}, sampling_order=["h", "w"])
    game = Dict(
        {"level": leaf(init_value=3), "world": world, "speed": leaf(init_value=4)},
        sampling_order=["world", "speed", "level"],
    )
    return Dict({"z": leaf(init_value=5), "game": game, "a": leaf(init_value=6)}, sampling_order=["game", "a", "z"])


class Recorder:
    """Stands in for ``spaces.logging.warning`` and keeps each message."""

    def __init__(self):
        self.messages: list[str] = []

    def __call__(self, message, *args, **kwargs):
        self.messages.append(message % args if args else message)


@pytest.fixture
def warnings_seen(monkeypatch) -> Recorder:
    recorder = Recorder()
    monkeypatch.setattr(spaces.logging, "warning", recorder)
    return recorder


# -- 1. no init_value: None until set ---------------------------------------------------------


def test_dict_with_unset_leaves_reports_none_and_fails_check():
    space = Dict({"a": Discrete(3), "b": Box(0.0, 1.0, shape=()), "c": Discrete(3, init_value=1)})
    assert space.init_value == {"a": None, "b": None, "c": 1}
    assert space.value == {"a": None, "b": None, "c": 1}
    assert not space.check()
    out = space.sample()  # sampling fills every leaf, as in 0.0.3
    assert space.check() and out["a"] is not None and out["b"] is not None
    space.reset()
    assert space.value == {"a": None, "b": None, "c": 1}


def test_update_with_other_leaves_unset_raises_an_assertion_error_and_changes_nothing(warnings_seen):
    space = Dict({"a": Discrete(3), "b": Discrete(3, init_value=0)})
    with pytest.raises(AssertionError) as info:  # 0.0.3: AssertionError("Values must be within space!")
        space.update(["b"])
    assert isinstance(info.value, SpaceCheckError) and isinstance(info.value, SpaceError)
    assert "a (unset)" in str(info.value)
    assert space.value == {"a": None, "b": 0}  # we undo the draw (0.0.3 kept it)
    assert any("failed check()" in m for m in warnings_seen.messages)  # 0.0.3 logs like check(debug=True)
    space.update(["all"])  # resampling everything fills the gap
    assert space.check()


# -- 2. out-of-bounds init_value: kept, reported by check() --------------------------------------


@pytest.mark.parametrize(
    "make, bad",
    [
        (lambda v: Box(0.0, 1.0, shape=(2,), init_value=v), [2.0, 0.5]),
        (lambda v: Discrete(5, init_value=v), 7),
        (lambda v: MultiDiscrete([3, 4], init_value=v), [5, 0]),
        (lambda v: RGBBox(shape=(3,), init_value=v, constrain_fn=lambda x: x[0] < 10), [200, 0, 0]),
    ],
    ids=["box", "discrete", "multidiscrete", "rgb-constraint"],
)
def test_bad_init_value_is_accepted_and_check_warns(make, bad, warnings_seen):
    space = make(bad)
    np.testing.assert_array_equal(space.init_value, bad)
    np.testing.assert_array_equal(space.value, bad)
    assert space.check() is False
    assert len(warnings_seen.messages) == 1
    assert repr(space) in warnings_seen.messages[0]


def test_dict_init_value_out_of_bounds_is_accepted_and_reported(warnings_seen):
    space = Dict({"a": Discrete(3), "b": Discrete(3, init_value=0)}, init_value={"a": 9})
    assert space.init_value == {"a": 9, "b": 0} and space.value == {"a": 9, "b": 0}
    assert not space.check()
    assert space.check(debug=True) is False
    assert warnings_seen.messages == ["Dict: spaces ['a (out of bounds)'] failed check()"]
    with pytest.raises(SpaceError, match="inside its bounds"):
        space.set_value({"a": 9})  # 0.0.3's setters refuse it too


# -- 3. sampling_order: node paths, settable ----------------------------------------------------


def test_sampling_order_lists_nested_dict_nodes_like_0_0_3():
    assert game_space().sampling_order == [
        "game",
        "game.world",
        "game.world.h",
        "game.world.w",
        "game.speed",
        "game.level",
        "a",
        "z",
    ]
    assert game_space()["game"].sampling_order == ["world", "world.h", "world.w", "speed", "level"]


def draw_order(space: Dict, action) -> list[str]:
    """Leaf names in the order ``action(space)`` draws them (each leaf's constrain_fn logs its name)."""
    calls: list[str] = []
    for path in space.names():
        space[path].constrain_fn = lambda x, p=path: calls.append(p) or True
    action(space)
    return calls


def test_setting_sampling_order_changes_sample_and_update_order():
    space = game_space()
    space.sampling_order = ["a", "game.speed", "game.world.w"]
    assert space.sampling_order == [
        "a",
        "game",
        "game.speed",
        "game.world",
        "game.world.w",
        "game.world.h",
        "game.level",
        "z",
    ]
    assert draw_order(space, Dict.sample) == ["a", "game.speed", "game.world.w", "game.world.h", "game.level", "z"]
    drawn = draw_order(space, lambda s: s.update(["z", "game.level", "game.world"]))
    assert drawn[:4] == ["game.world.w", "game.world.h", "game.level", "z"]  # then check() revisits all
    space.sampling_order = space.sampling_order  # a round trip changes nothing
    assert space.sampling_order[0] == "a"


def test_setting_sampling_order_warns_about_unnamed_children(warnings_seen):
    space = game_space()
    space.sampling_order = ["game.world.w"]
    assert space.sampling_order[:4] == ["game", "game.world", "game.world.w", "game.world.h"]
    assert len(warnings_seen.messages) == 1
    assert "['a', 'z', 'game.speed', 'game.level', 'game.world.h']" in warnings_seen.messages[0]


@pytest.mark.parametrize(
    "order, fragments",
    [
        (["nope", "game.wrld", "a"], ["unknown ['nope', 'game.wrld']", "Did you mean"]),
        (["a", "game", "a"], ["repeated", "['a']"]),
        (["game.speed", "a", "game.level"], ["together", "game.speed"]),
        ("game", ["list of keys"]),
        (3, ["list of keys"]),
    ],
    ids=["unknown", "repeated", "interleaved", "string", "not-iterable"],
)
def test_bad_sampling_order_raises_space_error_and_changes_nothing(order, fragments):
    space = game_space()
    before = space.sampling_order
    with pytest.raises(SpaceError) as info:
        space.sampling_order = order
    for fragment in fragments:
        assert fragment in str(info.value)
    assert space.sampling_order == before


def test_constructor_accepts_dotted_paths_and_top_level_keys():
    inner = Dict({"x": Discrete(2, init_value=0), "y": Discrete(2, init_value=0)})
    space = Dict({"p": inner, "q": Discrete(2, init_value=0)}, sampling_order=["q", "p.y", "p.x"])
    assert space.sampling_order == ["q", "p", "p.y", "p.x"]
    with pytest.raises(ValueError, match="'r'"):  # 0.0.3: ValueError for keys not in spaces
        Dict({"q": Discrete(2)}, sampling_order=["r"])


# -- 4. spaces.logging -----------------------------------------------------------------------


def test_spaces_logging_is_the_logger_the_package_warns_through(caplog):
    assert swm.spaces.logging is spaces.logging
    assert isinstance(spaces.logging, logging.Logger) and spaces.logging.name == "stable_worldmodel.spaces"
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        Discrete(3, init_value=1, constrain_fn=lambda x: False).check()
    assert "does not satisfy constrain_fn" in caplog.text


def test_patching_spaces_logging_warning_captures_every_warning(warnings_seen):
    Discrete(3, init_value=1, constrain_fn=lambda x: False).check()
    Dict({"a": Discrete(2)}).check(debug=True)
    Dict({"a": Discrete(2), "b": Discrete(2)}, sampling_order=["b"])
    with pytest.raises(RuntimeError):
        Box(0.0, 1.0, shape=(), constrain_fn=lambda x: False).sample(max_tries=50, warn_after_s=0.0)
    assert len(warnings_seen.messages) == 4
    assert "does not satisfy constrain_fn" in warnings_seen.messages[0]
    assert "failed check()" in warnings_seen.messages[1]
    assert "sampling_order" in warnings_seen.messages[2]
    assert "rejected by constrain_fn" in warnings_seen.messages[3]


def test_replacing_spaces_logging_object_captures_warnings():
    with mock.patch("stable_worldmodel.spaces.logging") as fake:
        Box(0.0, 1.0, shape=(), init_value=0.5, constrain_fn=lambda x: False).check()
    fake.warning.assert_called_once()
    assert "does not satisfy constrain_fn" in fake.warning.call_args.args[0]


# -- 5. reset_variation_space -----------------------------------------------------------------


def tree() -> Dict:
    return Dict(
        {
            "a": Discrete(10, init_value=0),
            "b": Dict({"c": Discrete(10, init_value=1), "d": Box(0.0, 1.0, shape=(), init_value=0.5)}),
        }
    )


def test_reset_variation_space_without_options_resets_to_init_values():
    space = tree()
    space.sample()
    assert reset_variation_space(space, seed=3) is None
    assert space.value == {"a": 0, "b": {"c": 1, "d": np.float32(0.5)}}


def test_reset_variation_space_resamples_named_variations_deterministically():
    space = tree()
    reset_variation_space(space, seed=3, options={"variation": ["b"]})
    first = space.value
    assert first["a"] == 0  # not named: back to its init value
    reset_variation_space(space, seed=3, options={"variation": ("b",)})
    assert space.value["b"]["c"] == first["b"]["c"] and space.value["b"]["d"] == first["b"]["d"]
    reset_variation_space(space, seed=3, options={"variation": "b.c"})  # one name as a string
    assert space.value["b"]["d"] == np.float32(0.5)


def test_reset_variation_space_default_variations_and_values():
    space = tree()
    reset_variation_space(space, seed=1, default_variations=["all"])
    assert space.value != tree().value
    reset_variation_space(space, seed=1, options={"variation": []}, default_variations=["a"])  # explicit: none
    assert space.value["a"] == 0
    reset_variation_space(space, seed=1, default_variations={"a"})  # a set works (0.1.1 raised ValueError)
    reset_variation_space(space, options={"variation": ["a"], "variation_values": {"a": 5, "b": {"c": 7}}})
    assert space.value["a"] == 5 and space.value["b"]["c"] == 7  # values are applied after the draws
    reset_variation_space(space, options={"variation_values": {"b.c": 2}})
    assert space.value == {"a": 0, "b": {"c": 2, "d": np.float32(0.5)}}


def test_reset_variation_space_errors():
    unset = Dict({"a": Discrete(10)})
    with pytest.raises(AssertionError):  # 0.1.1: AssertionError when the result fails check()
        reset_variation_space(unset)
    reset_variation_space(unset, options={"variation": ["a"]})  # drawing the unset factor fixes it
    reset_variation_space(unset, options={"variation_values": {"a": 4}})
    assert unset.value == {"a": 4}
    with pytest.raises(SpaceError, match="inside its bounds"):
        reset_variation_space(tree(), options={"variation_values": {"a": 50}})
    with pytest.raises(SpaceError, match="'zz'"):  # 0.1.1 ignored unknown names silently
        reset_variation_space(tree(), options={"variation": ["zz"]})
    with pytest.raises(ValueError, match="list of variation names"):
        reset_variation_space(tree(), options={"variation": 3})
    with pytest.raises(SpaceError, match="Dict"):
        reset_variation_space(Discrete(4, init_value=1))


# -- 6. "constrain_fn not satisfied" -----------------------------------------------------------


def test_failed_rejection_sampling_keeps_the_0_0_3_phrase():
    space = Dict({"a": Discrete(3), "b": Discrete(3)}, constrain_fn=lambda v: False)
    with pytest.raises(RuntimeError, match="constrain_fn not satisfied after 3 draws"):
        space.sample(max_tries=3)
    with pytest.raises(RuntimeError, match="constrain_fn not satisfied after 4 draws"):
        Discrete(3, constrain_fn=lambda x: False).sample(max_tries=4)


def test_dict_sampling_order_private_names_of_the_releases():
    """0.0.3 / 0.1.1 research code reads ``_sampling_order`` (top-level keys) and walks
    ``_get_sampling_order(parts)`` (dotted paths); setting ``_sampling_order`` reorders sampling."""
    from stable_worldmodel import spaces as swm_spaces
    from stable_worldmodel.errors import SpaceError

    d = swm_spaces.Dict(
        {
            "a": swm_spaces.Discrete(3),
            "g": swm_spaces.Dict({"w": swm_spaces.Discrete(4), "h": swm_spaces.Discrete(5)}),
            "b": swm_spaces.Discrete(2),
        }
    )
    assert d._sampling_order == ["a", "g", "b"]
    assert list(d._get_sampling_order()) == ["a", "g", "g.w", "g.h", "b"] == d.sampling_order
    assert list(d._get_sampling_order(("env",)))[:2] == ["env.a", "env.g"]
    d._sampling_order = ["g"]  # missing keys appended, in their order
    assert d._sampling_order == ["g", "a", "b"] and d.sampling_order[0] == "g"
    with pytest.raises(SpaceError, match="'zz'"):
        d._sampling_order = ["zz"]
