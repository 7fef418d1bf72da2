"""``swm/Craftax*-v1``: craftax's games as Gymnasium envs with factors (extra ``craftax``).

Compiling a craftax game takes seconds to a minute per process, so every test that resets an env
is ``slow``; they use Craftax-Classic (the smaller game) with ``fast_compile=True``.
"""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from stable_worldmodel import keys
from stable_worldmodel._optional import is_available, missing_extra
from stable_worldmodel.envs import get_entry, list_envs
from stable_worldmodel.errors import ConfigError

IDS = ["swm/CraftaxPixels-v1", "swm/CraftaxSymbolic-v1", "swm/CraftaxClassicPixels-v1", "swm/CraftaxClassicSymbolic-v1"]
HAVE = is_available("craftax") and is_available("jax")
needs_craftax = pytest.mark.skipif(not HAVE, reason="extra 'craftax' not installed")


# -- fast: no game is compiled ----------------------------------------------------------------------
def test_registry_entries():
    assert set(IDS) <= set(list_envs(tag="craftax"))
    for env_id in IDS:
        entry = get_entry(env_id)
        assert entry.expert is None and "discrete" in entry.tags and entry.tool_steps == 1000
        assert entry.entry_point.startswith("stable_worldmodel.envs.craftax.craftax:Craftax")
    assert missing_extra(("craftax",)) == (None if HAVE else "craftax")


def test_missing_extra_names_it_and_the_package_imports_light():
    code = (
        "import sys; sys.modules['craftax'] = None\n"
        "import gymnasium as gym, stable_worldmodel, stable_worldmodel.envs.craftax as c\n"
        "print('jax' in sys.modules)\n"
        "sys.modules['jax'] = None  # the env module imports jax first: the error without its seconds of import\n"
        "from stable_worldmodel.errors import DependencyNotInstalled\n"
        "try:\n"
        "    gym.make('swm/CraftaxClassicSymbolic-v1')\n"
        "except DependencyNotInstalled as e:\n"
        "    print('typed:', e)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    lines = out.stdout.splitlines()
    assert lines[0] == "False", out.stderr
    assert "typed:" in out.stdout and 'pip install "stable-worldmodel[craftax]"' in out.stdout, out.stderr


# -- slow: these compile Craftax-Classic ------------------------------------------------------------
@pytest.fixture(scope="module")
def classic():
    from stable_worldmodel.envs.craftax import CraftaxClassicSymbolicWrapper

    return CraftaxClassicSymbolicWrapper(fast_compile=True)


def _offset(env, field: str) -> int:
    """Index of ``field``'s first number in the flat state."""
    from stable_worldmodel.envs.craftax.craftax import _flat_size

    i = 0
    for name, _, leaves in env._game.spec:
        if name == field:
            return i
        i += sum(_flat_size(shape, dtype) for shape, dtype in leaves)
    raise KeyError(field)


@needs_craftax
@pytest.mark.slow
def test_spaces_infos_and_upstreams_worlds(classic):
    import jax
    from craftax.craftax_env import make_craftax_env_from_name

    obs, info = classic.reset(seed=3)
    assert obs.shape == (1345,) and obs.dtype == np.float32 and classic.action_space.n == 17
    assert len(classic.variation_space.names()) == 10
    assert info[keys.STATE].shape == (8345,) and info[keys.PROPRIO].shape == (20,)
    assert info[keys.GOAL].shape == (63, 63, 3) and np.array_equal(info[keys.GOAL_STATE], info[keys.STATE])
    assert info["Achievements/collect_wood"] == 0
    # upstream's key use: split, reset with the second half
    craftax = make_craftax_env_from_name("Craftax-Classic-Symbolic-v1", auto_reset=False)
    _, sub = jax.random.split(jax.random.PRNGKey(3))
    ref, _ = craftax.reset(sub, craftax.default_params)
    np.testing.assert_array_equal(obs, np.asarray(ref))
    obs2, r, terminated, truncated, info2 = classic.step(5)
    assert isinstance(r, float) and not terminated and not truncated
    again, _ = classic.reset(seed=3)
    np.testing.assert_array_equal(again, obs)
    assert np.array_equal(classic.step(5)[0], obs2)


@needs_craftax
@pytest.mark.slow
def test_factors_change_the_game(classic):
    _, a = classic.reset(seed=0, options={keys.VARIATION_VALUES: {"world.always_diamond": 0}})
    _, b = classic.reset(seed=0, options={keys.VARIATION_VALUES: {"world.always_diamond": 1}})
    assert not np.array_equal(a[keys.STATE], b[keys.STATE])
    light = _offset(classic, "light_level")
    lights = []
    for day in (100, 600):
        classic.reset(seed=0, options={keys.VARIATION_VALUES: {"world.day_length": day}})
        for _ in range(40):
            *_, info = classic.step(0)
        lights.append(info[keys.STATE][light])
    assert lights[0] != lights[1]
    classic.reset(seed=0, options={keys.VARIATION: ["all"]})
    drawn = classic.variation_space.value
    assert drawn["mobs"]["zombie_health"] != 5 or drawn["world"]["day_length"] != 300


@needs_craftax
@pytest.mark.slow
def test_state_and_goal_options_and_eval_state(classic):
    obs, info = classic.reset(seed=1)
    for a in (1, 2, 3, 4, 5):
        obs, *_, info = classic.step(a)
    state = info[keys.STATE]
    restored, info2 = classic.reset(seed=9, options={keys.STATE: state})
    np.testing.assert_array_equal(restored, obs)
    np.testing.assert_array_equal(info2[keys.STATE], state)
    start, info3 = classic.reset(seed=1, options={keys.GOAL_STATE: state})
    np.testing.assert_array_equal(info3[keys.GOAL_STATE], state)
    assert classic.eval_state(state, state) == (True, 0.0)
    moved = state.copy()
    moved[0] += 2
    moved[1] -= 1
    assert classic.eval_state(state, moved) == (False, 3.0)
    with pytest.raises(ConfigError, match="8345"):
        classic.reset(options={keys.STATE: state[:10]})


@needs_craftax
@pytest.mark.slow
def test_death_terminates_and_the_time_limit_truncates(classic):
    _, info = classic.reset(seed=0)
    dying = info[keys.STATE].copy()
    dying[3] = 0.0  # player_health (position, direction, then health)
    classic.reset(seed=0, options={keys.STATE: dying})
    *_, terminated, truncated, _ = classic.step(0)
    assert terminated and not truncated
    late = info[keys.STATE].copy()
    late[_offset(classic, "timestep")] = 9999.0
    classic.reset(seed=0, options={keys.STATE: late})
    *_, terminated, truncated, _ = classic.step(0)
    assert truncated and not terminated


@needs_craftax
@pytest.mark.slow
def test_frames_at_any_size_and_pixels_observation():
    from env_checks import assert_render_size

    from stable_worldmodel.envs.craftax import CraftaxClassicPixelsWrapper, CraftaxClassicSymbolicWrapper

    env = CraftaxClassicPixelsWrapper(fast_compile=True, render_size=(40, 40))
    assert_render_size(env, (40, 40))
    env.set_render_size((63, 63))
    obs, info = env.reset(seed=2)
    assert obs.shape == (63, 63, 3)
    np.testing.assert_array_equal(env.render(), (np.clip(obs, 0, 1) * 255).astype(np.uint8))
    blind = CraftaxClassicSymbolicWrapper(fast_compile=True, render_mode=None)
    blind.reset(seed=2)
    blind.step(1)
    with pytest.raises(ConfigError, match="render_mode"):
        blind.render()
