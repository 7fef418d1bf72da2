"""``swm convert`` (upstream 0.1.1's command: NAME [OUTPUT] --dest-format/-f, default video) and
``swm preview`` (upstream's main: one MP4 per episode, the image columns side by side)."""

from __future__ import annotations

import numpy as np
import pytest

from stable_worldmodel.data import get_cache_dir, load_dataset

TOY = "swm/Toy-v0"


@pytest.fixture
def toyset(swm):
    result = swm(
        "collect", TOY, "-n", "5", "--policy", "expert", "--name", "toyset", "--image-size", "16", "--seed", "1"
    )
    assert result.exit_code == 0, result.output
    return "toyset"


def test_convert_to_each_format_beside_the_source(swm, toyset):
    home = get_cache_dir()
    result = swm("convert", toyset)  # default: video, as upstream
    assert result.exit_code == 0, result.output
    assert result.stdout.splitlines()[0] == "Converting toyset.h5 -> video as toyset-video"
    assert (home / "toyset-video").is_dir() and result.stdout.strip().endswith(str(home / "toyset-video"))
    for fmt, written in (("lance", "copy.lance"), ("hdf5", "copy.h5"), ("folder", "copy")):
        out = swm("convert", toyset, "copy", "-f", fmt)
        assert out.exit_code == 0, out.output
        back = load_dataset(home / written)
        np.testing.assert_array_equal(back.lengths, load_dataset(toyset).lengths)
        np.testing.assert_allclose(back.get_col_data("action"), load_dataset(toyset).get_col_data("action"))


def test_convert_errors_are_one_line(swm, toyset, error_line):
    bad = swm("convert", toyset, "-f", "lanc")
    assert bad.exit_code == 1 and "Did you mean" in error_line(bad) and "'lance'" in error_line(bad)
    missing = swm("convert", "toysett")
    assert missing.exit_code == 1 and "Did you mean 'toyset'" in error_line(missing)


def test_preview_writes_one_video_per_episode(swm, toyset, tmp_path):
    import imageio.v3 as iio

    result = swm("preview", toyset, "-n", "2")
    assert result.exit_code == 0, result.output
    paths = result.stdout.split()
    assert len(paths) == 2 and all(p.startswith(str(get_cache_dir() / "previews" / "toyset")) for p in paths)
    assert swm("preview", toyset, "-n", "2").stdout.split() == paths  # the draw is seeded
    chosen = swm("preview", toyset, "--episodes", "0,4", "--out", str(tmp_path / "v"))
    assert chosen.stdout.split() == [str(tmp_path / "v" / "episode_0.mp4"), str(tmp_path / "v" / "episode_4.mp4")]
    frames = iio.imread(tmp_path / "v" / "episode_0.mp4")
    ds = load_dataset(toyset)
    assert len(frames) == ds.lengths[0] and frames.shape[1:] == (32, 16, 3)  # pixels above goal


def test_preview_errors(swm, toyset, error_line):
    assert "requires episodes in [0, 5)" in error_line(swm("preview", toyset, "--episodes", "9"))
    assert "comma-separated integers" in error_line(swm("preview", toyset, "--episodes", "a,b"))
