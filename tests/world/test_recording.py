"""record_dataset / record_video / evaluate_from_dataset on swm/Toy-v0, and SIGKILL safety."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import h5py
import numpy as np
import pytest

from stable_worldmodel import World, keys
from stable_worldmodel.data import HDF5Dataset, _superblock
from stable_worldmodel.errors import ConfigError
from stable_worldmodel.policy import RandomPolicy

STEPS = 6


def make_world(n=3, steps=STEPS):
    world = World("swm/Toy-v0", num_envs=n, image_shape=(16, 16), max_episode_steps=steps, verbose=0)
    world.set_policy(RandomPolicy(seed=0))
    return world


def spy_episodes(world):
    """Collect the infos each env shows, episode by episode, in the order the recorder finishes them."""
    n = world.num_envs
    live = [[] for _ in range(n)]
    finished = []
    step, reset, reset_envs = world.step, world.reset, world.reset_envs

    def grab(ids):
        for i in ids:
            live[i].append({k: np.array(v[i, -1]) for k, v in world.infos.items()})

    def spy_reset(*a, **k):
        reset(*a, **k)
        for i in range(n):
            live[i] = []
        grab(range(n))

    def spy_step():
        step()
        grab(range(n))
        for i in np.flatnonzero(world.terminateds | world.truncateds):
            finished.append(live[i])
            live[i] = []

    def spy_reset_envs(ids, *a, **k):
        reset_envs(ids, *a, **k)
        grab(ids)

    world.reset, world.step, world.reset_envs = spy_reset, spy_step, spy_reset_envs
    return finished


@pytest.mark.parametrize("n, episodes, seed", [(1, 2, 0), (3, 4, 7), (2, 5, None)])
def test_round_trip(tmp_path, n, episodes, seed):
    world = make_world(n)
    seen = spy_episodes(world)
    path = world.record_dataset("toy", episodes=episodes, seed=seed, cache_dir=tmp_path)
    assert path == tmp_path / "toy.h5"
    with h5py.File(path, "r") as f:
        lengths = f[keys.EP_LEN][:]
        assert len(lengths) == episodes
        assert f[keys.EP_OFFSET][:].tolist() == np.concatenate([[0], np.cumsum(lengths)[:-1]]).tolist()
        assert f[keys.PIXELS].shape == (lengths.sum(), 16, 16, 3) and f[keys.PIXELS].dtype == np.uint8
        assert not any(k.startswith("_") for k in f)
        for ep, (off, length) in enumerate(zip(f[keys.EP_OFFSET][:], lengths, strict=False)):
            rows = seen[ep]
            assert len(rows) == length
            assert np.isnan(rows[0][keys.ACTION]).all()  # the reset row is kept
            for k in f:
                if k in (keys.EP_LEN, keys.EP_OFFSET) or k.startswith("checksum:"):  # row checksums: not info columns
                    continue
                got = f[k][off : off + length]
                if k == keys.EP_IDX:  # the episode's index in the file, on every row
                    assert got.tolist() == [ep] * length
                elif k == keys.ACTION:  # row t holds the action taken at step t
                    want = np.stack([r[k] for r in rows[1:]])
                    np.testing.assert_array_equal(got[:-1], want)
                    assert np.isnan(got[-1]).all()
                else:
                    np.testing.assert_array_equal(got, np.stack([r[k] for r in rows]), err_msg=k)
    # windows read back equal the recorded infos
    for num_steps, frameskip in [(1, 1), (2, 2), (3, 1)]:
        ds = HDF5Dataset(
            path, num_steps=num_steps, frameskip=frameskip, keys_to_load=[keys.PIXELS, keys.STATE, keys.ACTION]
        )
        item = ds[len(ds) - 1]
        ep, start = ds.locate(len(ds) - 1)
        rows = seen[ep][start : start + num_steps * frameskip : frameskip]
        np.testing.assert_array_equal(item[keys.STATE].numpy(), np.stack([r[keys.STATE] for r in rows]))
        np.testing.assert_array_equal(
            item[keys.PIXELS].numpy(), np.stack([r[keys.PIXELS] for r in rows]).transpose(0, 3, 1, 2)
        )
        assert item[keys.ACTION].shape == (num_steps, frameskip * 2)


def test_recording_again_resumes_to_the_asked_total(tmp_path):
    world = make_world(2)
    world.record_dataset("toy", episodes=3, seed=5, cache_dir=tmp_path)
    world.record_dataset("toy", episodes=5, seed=5, cache_dir=tmp_path)  # 0.0.3: 5 in all, not 3 + 5
    with h5py.File(tmp_path / "toy.h5", "r") as f:
        assert len(f[keys.EP_LEN]) == 5
        starts = f[keys.STATE][:][f[keys.EP_OFFSET][:]]
        assert len({tuple(s) for s in starts}) == 5  # no episode seed was used twice
        assert f.attrs["next_seed"] >= 5 + 5
        assert np.unique(f[keys.EP_IDX][:]).tolist() == [0, 1, 2, 3, 4]
    before = (tmp_path / "toy.h5").read_bytes()
    world.record_dataset("toy", episodes=4, seed=5, cache_dir=tmp_path)  # already more than asked: nothing
    assert (tmp_path / "toy.h5").read_bytes() == before


def test_keys_only_some_rows_have_are_skipped(tmp_path, monkeypatch):
    """An env whose reset info has a key its step info lacks (ALE's ``seeds``) still records."""
    world = make_world(2)
    reset_envs = world.reset_envs

    def with_extra(ids, *a, **k):
        reset_envs(ids, *a, **k)
        world.infos = {**world.infos, "seeds": np.zeros((world.num_envs, 1), np.int64)}

    world.reset_envs = with_extra
    path = world.record_dataset("toy", episodes=3, seed=0, cache_dir=tmp_path)
    with h5py.File(path, "r") as f:
        assert "seeds" not in f and len(f[keys.EP_LEN]) == 3


def test_record_dataset_rejects_bad_episodes(tmp_path):
    with pytest.raises(ConfigError, match="episodes"):
        make_world(1).record_dataset("toy", episodes=0, cache_dir=tmp_path)


def test_record_video_writes_one_playable_mp4_per_env(tmp_path):
    import imageio.v3 as iio

    paths = make_world(2).record_video(tmp_path / "vids", max_steps=4, fps=10, seed=1)
    assert [p.name for p in paths] == ["env_0.mp4", "env_1.mp4"]
    frames = iio.imread(paths[0], plugin="pyav")
    assert frames.shape[1:] == (32, 16, 3)  # observation above goal
    assert 2 <= len(frames) <= 5
    props = iio.improps(paths[0], plugin="pyav")
    assert props.shape[1:3] == (32, 16)


def test_record_video_from_dataset(tmp_path):
    world = make_world(1)
    world.record_dataset("toy", episodes=2, seed=0, cache_dir=tmp_path)
    paths = world.record_video_from_dataset(
        tmp_path / "v", "toy", [0, 1], cache_dir=tmp_path, viewname=[keys.PIXELS, keys.GOAL]
    )
    assert [p.name for p in paths] == ["episode_0.mp4", "episode_1.mp4"]
    import imageio.v3 as iio

    assert iio.imread(paths[0], plugin="pyav").shape == (STEPS + 1, 16, 32, 3)  # views side by side


def test_evaluate_from_dataset(tmp_path):
    from stable_worldmodel.envs.toy.env import ToyExpert

    world = make_world(2, steps=40)
    world.set_policy(ToyExpert())
    world.record_dataset("toy", episodes=2, seed=3, cache_dir=tmp_path)
    ds = HDF5Dataset("toy", cache_dir=tmp_path)
    out = world.evaluate_from_dataset(
        ds, [0, 1], [0, 1], goal_offset_steps=3, eval_budget=10, save_video=True, video_path=tmp_path / "ev"
    )
    assert out["success_rate"] == 100.0
    assert out["episode_successes"].tolist() == [True, True]
    assert (tmp_path / "ev" / "env_0.mp4").is_file()
    np.testing.assert_allclose(world.infos[keys.GOAL_STATE][0, -1], ds.get_row_data(3)[keys.STATE])
    with pytest.raises(ValueError, match="start_steps"):
        world.evaluate_from_dataset(ds, [0, 1], [0], 3, 10)
    with pytest.raises(ValueError, match="num_envs"):
        world.evaluate_from_dataset(ds, [0], [0], 3, 10)
    with pytest.raises(ValueError, match="goal_offset_steps"):
        world.evaluate_from_dataset(ds, [0, 1], [0, 0], 1000, 10)


KILL_SCRIPT = """
import sys, time
import numpy as np
from stable_worldmodel import World
from stable_worldmodel.data import _superblock
from stable_worldmodel.policy import RandomPolicy

mode, out, marker = sys.argv[1], sys.argv[2], sys.argv[3]

class Policy(RandomPolicy):
    calls = 0
    def get_action(self, infos, **kw):
        Policy.calls += 1
        if mode == "between" and Policy.calls == 40:
            open(marker, "w").close(); time.sleep(600)
        return super().get_action(infos, **kw)

if mode == "during":  # stop inside a commit: HDF5 wrote its metadata, not yet the superblock
    real = _superblock.SealedFile._write_head
    count = [0]
    def _write_head(self, pos, view):
        count[0] += 1
        if count[0] == 8:
            open(marker, "w").close(); time.sleep(600)
        return real(self, pos, view)
    _superblock.SealedFile._write_head = _write_head

world = World("swm/Toy-v0", num_envs=2, image_shape=(16, 16), max_episode_steps=5, verbose=0)
world.set_policy(Policy(seed=0))
world.record_dataset("k", episodes=10**6, seed=0, cache_dir=out)
"""


def _kill_while(tmp_path, mode):
    script = tmp_path / "rec.py"
    script.write_text(textwrap.dedent(KILL_SCRIPT))
    marker = tmp_path / "marker"
    proc = subprocess.Popen([sys.executable, str(script), mode, str(tmp_path), str(marker)])
    try:
        deadline = time.time() + 60
        while not marker.exists() and proc.poll() is None and time.time() < deadline:
            time.sleep(0.05)
        assert marker.exists(), "the recorder never reached the kill point"
    finally:
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
    return tmp_path / "k.h5"


def _check_episodes(f):
    lengths, offsets = f[keys.EP_LEN][:], f[keys.EP_OFFSET][:]
    assert len(lengths) >= 2
    steps = f[keys.STEP_IDX][: offsets[-1] + lengths[-1]]
    actions = f[keys.ACTION][: offsets[-1] + lengths[-1]]
    pixels = f[keys.PIXELS][: offsets[-1] + lengths[-1]]
    assert pixels.any()
    for off, n in zip(offsets, lengths, strict=False):
        assert steps[off : off + n].tolist() == list(range(n))
        assert np.isnan(actions[off + n - 1]).all() and not np.isnan(actions[off : off + n - 1]).any()


def test_sigkill_between_commits_leaves_a_plain_h5py_file(tmp_path):
    path = _kill_while(tmp_path, "between")
    with h5py.File(path, "r") as f:  # plain h5py, no repair
        _check_episodes(f)
    ds = HDF5Dataset(path)
    assert len(ds) > 0
    ds.close()


def test_sigkill_during_a_commit_keeps_every_committed_episode(tmp_path):
    path = _kill_while(tmp_path, "during")
    assert not _superblock.needs_repair(path)
    with h5py.File(path, "r") as f:  # plain h5py, no repair
        _check_episodes(f)
    ds = HDF5Dataset(path)
    assert ds.num_episodes >= 2
    ds.close()


def test_same_seed_gives_byte_identical_datasets(tmp_path):
    paths = [make_world(2).record_dataset(name, episodes=3, seed=11, cache_dir=tmp_path) for name in ("a", "b")]
    with h5py.File(paths[0]) as f:
        assert keys.RENDER_TIME not in f  # a wall-clock timing: never recorded
    assert paths[0].read_bytes() == paths[1].read_bytes()


def test_evaluate_from_dataset_callables_read_their_arguments_from_the_start_row(tmp_path, caplog):
    world = World("swm/PushT-v1", num_envs=2, image_shape=(16, 16), max_episode_steps=6, verbose=0)
    world.set_policy(RandomPolicy(seed=0))
    world.record_dataset("pt", episodes=2, seed=1, cache_dir=tmp_path)
    ds = HDF5Dataset("pt", cache_dir=tmp_path)
    callables = [
        {"method": "_set_goal_state", "args": {"goal_state": {"value": keys.STATE}}},  # after the reset
        {"method": "no_such_method", "args": {}},
    ]
    with caplog.at_level("WARNING"):
        world.evaluate_from_dataset(
            ds, [0, 1], [1, 2], goal_offset_steps=3, eval_budget=1, callables=callables, save_video=False
        )
    goals = world.envs.call("_goal_state")
    for i, (ep, step) in enumerate([(0, 1), (1, 2)]):
        np.testing.assert_allclose(goals[i], ds.get_row_data(int(ds.offsets[ep]) + step)[keys.STATE])
    assert "no method 'no_such_method'" in caplog.text
    literal = [0.0, 0.0, 100.0, 100.0, 0.5, 0.0, 0.0]
    callables = [{"method": "_set_goal_state", "args": {"goal_state": {"value": literal, "in_dataset": False}}}]
    world.evaluate_from_dataset(
        ds, [0, 1], [1, 2], goal_offset_steps=3, eval_budget=1, callables=callables, save_video=False
    )
    np.testing.assert_allclose(world.envs.call("_goal_state")[1], literal)


def test_collect_writes_any_registered_format_and_appends(tmp_path):
    from stable_worldmodel.data import load_dataset

    world = make_world(2)
    world.collect(tmp_path / "runs" / "toy", episodes=3, seed=0)  # no suffix: HDF5, parents created
    assert (tmp_path / "runs" / "toy.h5").is_file()
    world.collect(tmp_path / "runs" / "toy.h5", episodes=2, seed=0)  # appends 2 more
    ds = load_dataset(str(tmp_path / "runs" / "toy.h5"))
    assert ds.num_episodes == 5 and len({tuple(r) for r in ds.get_col_data(keys.STATE)[ds.offsets]}) == 5
    world.collect(tmp_path / "folder", episodes=2, seed=0, format="folder", progress=False)
    assert load_dataset(str(tmp_path / "folder")).num_episodes == 2
    with pytest.raises(ConfigError, match="exactly one of path= or writer="):
        world.collect(episodes=1)
    world.collect(tmp_path / "x.lance", episodes=2, seed=0)  # .lance: upstream's default format
    lance = load_dataset(str(tmp_path / "x.lance"))
    assert type(lance).__name__ == "LanceDataset" and lance.num_episodes == 2 and not (tmp_path / "x.lance.h5").exists()


def test_collect_into_a_writer_object(tmp_path):
    class Sink:
        def __init__(self):
            self.episodes = []

        def write_episode(self, episode):
            self.episodes.append(episode)

    sink = Sink()
    make_world(2).collect(writer=sink, episodes=3, seed=1)
    assert len(sink.episodes) == 3 and all(keys.PIXELS in ep for ep in sink.episodes)
