"""Tests of stable_worldmodel.spaces: the seed's examples verbatim, then each documented behaviour."""

from __future__ import annotations

import copy
import logging

import gymnasium as gym
import numpy as np
import pytest

from stable_worldmodel import spaces
from stable_worldmodel.errors import SpaceError
from stable_worldmodel.spaces import Box, Dict, Discrete, MultiDiscrete, RGBBox

# ----------------------------------------------------------------------------------------------
# seed 000 examples, copied verbatim
# ----------------------------------------------------------------------------------------------


def test_seed_box_example():
    import numpy as np

    def in_circle(pos):
        return np.linalg.norm(pos) <= 1.0

    space = Box(
        low=np.array([-1.0, -1.0]),
        high=np.array([1.0, 1.0]),
        init_value=np.array([0.0, 0.0]),
        constrain_fn=in_circle,
    )
    position = space.sample()  # Only samples within unit circle

    assert in_circle(position) and space.contains(position)
    np.testing.assert_array_equal(space.value, position)
    space.seed(0)
    assert all(in_circle(space.sample()) for _ in range(200))
    assert space.check()


def test_seed_dict_example():
    import numpy as np

    from stable_worldmodel import spaces

    config = spaces.Dict(
        {
            "difficulty": spaces.Discrete(n=3, init_value=0),
            "world": spaces.Dict(
                {
                    "width": spaces.Discrete(n=100, init_value=50),
                    "height": spaces.Discrete(n=100, init_value=50),
                }
            ),
            "player_pos": spaces.Box(
                low=np.array([0, 0]),
                high=np.array([99, 99]),
                init_value=np.array([25, 25]),
            ),
        },
        sampling_order=["difficulty", "world", "player_pos"],
    )
    # Sample respects order
    state = config.sample()

    assert config.contains(state)
    assert list(state) == ["difficulty", "world", "player_pos"]
    assert config.sampling_order == ["difficulty", "world", "world.width", "world.height", "player_pos"]
    config.reset()
    assert config.check()  # the int init_value of the float Box was cast, not rejected
    assert config.value["player_pos"].dtype == np.float32
    np.testing.assert_array_equal(config.value["player_pos"], [25.0, 25.0])
    assert config.value["world"] == {"width": 50, "height": 50}


def test_seed_dict_constraint_note_reads_top_level_value():
    """The seed's Environment pattern: the constraint reads ``self.config_space.value`` at the top level."""

    class Environment:
        def __init__(self):
            self.config_space = spaces.Dict(
                {
                    "world": spaces.Dict({"width": spaces.Discrete(n=100, init_value=50)}),
                    "player_pos": spaces.Box(
                        low=np.array([0, 0]), high=np.array([99, 99]), init_value=np.array([25, 25])
                    ),
                },
                constrain_fn=lambda _: self.validate_config(),
            )

        def validate_config(self):
            # ✓ CORRECT: Access via .value at top level
            values = self.config_space.value
            return values["player_pos"][0] < values["world"]["width"]

    env = Environment()
    env.config_space.seed(0)
    for _ in range(50):
        state = env.config_space.sample()
        assert state["player_pos"][0] < state["world"]["width"]
        assert env.validate_config()


def test_seed_discrete_example():
    space = Discrete(n=10, init_value=0, constrain_fn=lambda x: x % 2 == 0)
    value = space.sample()  # Samples even number and updates space.value
    space.reset()  # Resets space.value back to 0 (init_value)

    assert value % 2 == 0
    assert space.value == 0
    space.seed(1)
    draws = [space.sample() for _ in range(100)]
    assert all(d % 2 == 0 for d in draws) and len(set(draws)) > 1
    assert space.value == draws[-1]


def test_seed_multidiscrete_example():
    import numpy as np

    space = MultiDiscrete(
        nvec=[5, 3, 10],  # [enemy_count, speed_level, spawn_rate]
        init_value=np.array([2, 1, 5]),
    )
    settings = space.sample()  # Random difficulty configuration
    space.reset()  # Resets to [2, 1, 5] (medium difficulty)

    assert space.contains(settings)
    np.testing.assert_array_equal(space.value, [2, 1, 5])


def test_seed_rgbbox_example():
    import numpy as np

    space = RGBBox(shape=(64, 64, 3), init_value=np.zeros((64, 64, 3), dtype=np.uint8))
    image = space.sample()  # Random RGB image
    space.reset()  # Returns to black image

    assert image.shape == (64, 64, 3) and image.dtype == np.uint8 and image.any()
    assert not space.value.any()


# ----------------------------------------------------------------------------------------------
# leaf spaces
# ----------------------------------------------------------------------------------------------

LEAVES = [
    pytest.param(lambda **kw: Box(0.0, 1.0, shape=(2,), **kw), id="box"),
    pytest.param(lambda **kw: Box(-2.0, 3.0, shape=(), **kw), id="box-scalar"),
    pytest.param(lambda **kw: Box(0, 10, shape=(3,), dtype=np.int64, **kw), id="box-int"),
    pytest.param(lambda **kw: Discrete(7, start=2, **kw), id="discrete"),
    pytest.param(lambda **kw: MultiDiscrete([4, 5], **kw), id="multidiscrete"),
    pytest.param(lambda **kw: RGBBox(**kw), id="rgb"),
]


def test_leaves_extend_gymnasium_classes():
    assert isinstance(Box(0, 1), gym.spaces.Box)
    assert isinstance(Discrete(3), gym.spaces.Discrete)
    assert isinstance(MultiDiscrete([2, 3]), gym.spaces.MultiDiscrete)
    assert isinstance(RGBBox(), gym.spaces.Box) and isinstance(RGBBox(), Box)
    assert isinstance(Dict({}), gym.spaces.Dict)


@pytest.mark.parametrize("make", LEAVES)
def test_leaf_sample_sets_value_and_keeps_type(make):
    space = make()
    space.seed(3)
    assert space.value is None  # no init_value: nothing until the first draw
    x = space.sample()
    assert space.contains(x) and space.check()
    assert type(x) is (np.int64 if isinstance(space, Discrete) else np.ndarray) and np.shape(x) == space.shape
    assert np.asarray(x).dtype == space.dtype
    np.testing.assert_array_equal(space.value, x)


@pytest.mark.parametrize("make", LEAVES)
def test_leaf_seed_makes_sampling_deterministic(make):
    a, b = make(), make()
    a.seed(42)
    b.seed(np.int64(42))  # numpy ints are accepted
    for _ in range(5):
        np.testing.assert_array_equal(a.sample(), b.sample())


@pytest.mark.parametrize("make", LEAVES)
def test_leaf_sample_without_set_value_keeps_value(make):
    space = make()
    space.sample()
    before = space.value
    space.seed(0)
    draws = [space.sample(set_value=False) for _ in range(20)]
    np.testing.assert_array_equal(space.value, before)
    assert any(not np.array_equal(d, before) for d in draws)


@pytest.mark.parametrize("make", LEAVES)
def test_no_init_value_means_none_until_set(make, caplog):
    space = make(constrain_fn=lambda x: True)
    assert space.init_value is None and space.value is None
    assert not space.contains(None)
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        assert not space.check()
    assert "None" in caplog.text
    space.sample(set_value=False)
    assert space.value is None  # a draw that is not kept leaves it unset
    x = space.sample()
    assert space.check() and space.init_value is None
    np.testing.assert_array_equal(space.value, x)
    space.reset()
    assert space.value is None and not space.check()
    space.set_value(x)
    assert space.check()
    space.reset()
    assert space.value is None


def test_init_value_of_other_dtype_is_cast():
    box = Box(0.0, 1.0, shape=(2,), init_value=np.array([0, 1]))
    assert box.value.dtype == np.float32 and box.check()
    md = MultiDiscrete([3, 3], dtype=np.int32, init_value=np.array([1, 2], dtype=np.int64))
    assert md.value.dtype == np.int32 and md.check()
    assert Discrete(4, init_value=np.int32(3)).value == 3
    assert Discrete(4, init_value=2.0).value == 2
    rgb = RGBBox(init_value=[255, 0, 10])
    assert rgb.value.dtype == np.uint8


@pytest.mark.parametrize(
    "make, bad, match",
    [
        (lambda v: Box(0.0, 1.0, shape=(2,), init_value=v), np.zeros(3), "shape"),
        (lambda v: Box(0.0, 1.0, shape=(), init_value=v), "abc", "numeric"),
        (lambda v: Discrete(4, init_value=v), 2.5, "integer"),
        (lambda v: RGBBox(init_value=v), [256, 0, 0], "integer"),
        (lambda v: RGBBox(init_value=v), [1.5, 0, 0], "integer"),
    ],
)
def test_bad_init_value_raises_space_error(make, bad, match):
    """A value that cannot be an element of the space (shape, type, lossy cast) is refused."""
    with pytest.raises(SpaceError, match=match) as info:
        make(bad)
    assert isinstance(info.value, ValueError)
    assert "requires" in str(info.value)


@pytest.mark.parametrize(
    "make, bad",
    [
        (lambda v: Box(0.0, 1.0, shape=(2,), init_value=v), np.array([0.5, 2.0])),
        (lambda v: Discrete(4, init_value=v), 4),
        (lambda v: MultiDiscrete([2, 2], init_value=v), [1, 2]),
    ],
    ids=["box", "discrete", "multidiscrete"],
)
def test_out_of_bounds_init_value_is_kept_and_reported_by_check(make, bad, caplog):
    space = make(bad)  # accepted, as release 0.0.3 documents
    np.testing.assert_array_equal(space.init_value, bad)
    np.testing.assert_array_equal(space.value, bad)
    assert not space.contains(space.value)
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        assert space.check() is False  # reported, not raised
    assert "outside the space bounds" in caplog.text
    space.sample()
    space.reset()
    np.testing.assert_array_equal(space.value, bad)  # reset brings the out-of-bounds value back
    with pytest.raises(SpaceError, match="inside its bounds"):
        space.set_init_value(np.full(space.shape, 9, dtype=space.dtype))  # the setters still validate


def test_set_value_and_set_init_value():
    box = Box(0.0, 10.0, shape=(2,), init_value=np.array([1.0, 1.0]))
    box.set_value(np.array([2, 3]))  # int -> cast
    np.testing.assert_array_equal(box.value, [2.0, 3.0])
    box.set_init_value([4.0, 4.0])
    np.testing.assert_array_equal(box.value, [2.0, 3.0])  # current value untouched
    box.reset()
    np.testing.assert_array_equal(box.value, [4.0, 4.0])
    box.value = [5.0, 6.0]  # attribute assignment goes through set_value
    np.testing.assert_array_equal(box.value, [5.0, 6.0])
    with pytest.raises(SpaceError, match=r"Box\(0.0, 10.0, \(2,\), float32\).*shape \(2,\)"):
        box.set_value([1.0])
    with pytest.raises(SpaceError, match="11"):
        box.value = [11.0, 0.0]
    np.testing.assert_array_equal(box.value, [5.0, 6.0])


def test_value_is_a_copy_and_input_is_copied():
    src = np.array([0.1, 0.2], dtype=np.float32)
    box = Box(0.0, 1.0, shape=(2,), init_value=src)
    src[0] = 0.9
    box.value[1] = 0.7
    np.testing.assert_allclose(box.value, [0.1, 0.2])
    drawn = box.sample()
    drawn[0] = 0.99
    assert box.value[0] != np.float32(0.99)


def test_contains_applies_constraint_and_bounds():
    space = Discrete(10, constrain_fn=lambda x: x % 2 == 0)
    assert space.contains(4) and not space.contains(3) and not space.contains(12)
    box = Box(-1.0, 1.0, shape=(2,), constrain_fn=lambda p: p[0] > 0)
    assert box.contains(np.array([0.5, 0.0], np.float32))
    assert not box.contains(np.array([-0.5, 0.0], np.float32))
    assert box.contains([0.5, 0.0])  # lists are converted without gymnasium's warning
    assert not box.contains(np.zeros(3, np.float32))


def test_check_logs_when_constraint_breaks(caplog):
    flag = {"ok": True}
    box = Box(0.0, 1.0, shape=(), init_value=0.5, constrain_fn=lambda _: flag["ok"])
    assert box.check()
    flag["ok"] = False
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        assert not box.check()
    assert "does not satisfy constrain_fn" in caplog.text


def test_impossible_constraint_raises_runtime_error_and_keeps_value():
    space = Discrete(5, init_value=1, constrain_fn=lambda x: x > 10)
    with pytest.raises(RuntimeError, match="5 rejections") as info:
        space.sample(max_tries=5)
    assert "constrain_fn not satisfied after 5 draws" in str(info.value)
    assert space.value == 1
    with pytest.raises(SpaceError, match="max_tries"):
        space.sample(max_tries=0)


def test_slow_sampling_warns_once_per_call(caplog):
    space = Box(0.0, 1.0, shape=(), constrain_fn=lambda x: False)
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        with pytest.raises(RuntimeError):
            space.sample(max_tries=300, warn_after_s=0.0)
    assert sum("rejected by constrain_fn" in r.getMessage() for r in caplog.records) == 1
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="stable_worldmodel.spaces"):
        with pytest.raises(RuntimeError):
            space.sample(max_tries=300, warn_after_s=None)
    assert not caplog.records


def test_constraint_sees_candidate_as_current_value():
    seen = []
    box = Box(0.0, 1.0, shape=(), init_value=0.5)
    box.constrain_fn = lambda x: seen.append(float(box.value) == float(x)) or True
    box.sample()
    assert seen == [True]


def test_gymnasium_kwargs_pass_through():
    space = Discrete(4, init_value=0)
    mask = np.array([0, 0, 1, 0], dtype=np.int8)
    assert all(space.sample(mask=mask) == 2 for _ in range(10))
    assert space.sample(probability=np.array([0, 1.0, 0, 0])) == 1
    md = MultiDiscrete([3, 3])
    out = md.sample(mask=(np.array([0, 1, 0], np.int8), np.array([0, 0, 1], np.int8)))
    np.testing.assert_array_equal(out, [1, 2])
    box = Box(0.0, 1.0, shape=(2,))
    with pytest.raises(gym.error.Error, match="cannot be provided a mask"):  # the kwarg reached gymnasium
        box.sample(mask=np.ones(2))


def test_box_fast_sampler_matches_bounds_and_dtype():
    for dtype, low, high in [(np.float32, -3.0, 2.0), (np.float64, 0.0, 1e-3), (np.int32, -5, 5), (np.uint8, 0, 255)]:
        box = Box(low, high, shape=(500,), dtype=dtype)
        box.seed(0)
        x = box.sample()
        assert x.dtype == dtype and box.contains(x)
        if np.issubdtype(dtype, np.integer):
            assert x.min() == low and x.max() == high  # both ends reachable
    unbounded = Box(-np.inf, np.inf, shape=(3,))
    assert unbounded.contains(unbounded.sample())


def test_rgbbox_shapes_and_fixed_bounds():
    assert RGBBox().shape == (3,)
    assert RGBBox(shape=(3, 8, 8)).shape == (3, 8, 8)
    assert RGBBox(shape=3).shape == (3,)
    space = RGBBox()
    assert space.dtype == np.uint8 and space.low.min() == 0 and space.high.max() == 255
    for bad in [(4, 4), (1,), (64, 64, 4)]:
        with pytest.raises(SpaceError, match="size 3"):
            RGBBox(shape=bad)
    with pytest.raises(ValueError, match="fixed"):
        RGBBox((3,), low=10)
    with pytest.raises(ValueError, match="fixed"):
        RGBBox((3,), 0, 255)
    with pytest.raises(SpaceError, match="shape tuple"):
        RGBBox(shape="rgb")
    assert repr(space) == "RGBBox((3,))"


def test_non_callable_constraint_is_rejected():
    with pytest.raises(SpaceError, match="callable"):
        Box(0.0, 1.0, constrain_fn=3)


def test_leaf_deepcopy_is_independent():
    space = Box(0.0, 1.0, shape=(2,), init_value=[0.5, 0.5])
    clone = copy.deepcopy(space)
    clone.set_value([0.1, 0.1])
    np.testing.assert_array_equal(space.value, [0.5, 0.5])
