"""A run records the env its dataset was recorded from (issue 26: ``swm eval`` can then say when a run
is used on another env): ``World.record_dataset`` writes the env id into the file, ``train`` copies it
into ``protocol.json``, and ``HDF5Writer(attrs=...)`` keeps what a file was created with."""

from __future__ import annotations

import json

import numpy as np
import pytest

from stable_worldmodel.data import HDF5Dataset
from stable_worldmodel.data.writer import HDF5Writer
from stable_worldmodel.errors import ConfigError


def test_the_dataset_and_the_run_name_the_env(fit, toy, _stablewm_home):
    assert HDF5Dataset(toy).attrs["env_id"] == "swm/Toy-v0"
    result = fit("dummy", "r", steps=2)
    assert json.loads((result.folder / "protocol.json").read_text())["env"] == "swm/Toy-v0"


def test_writer_attrs_are_kept_and_checked(tmp_path):
    episode = {"action": np.zeros((3, 2), np.float32)}
    with HDF5Writer(tmp_path / "a.h5", attrs={"env_id": "swm/A-v0"}) as w:
        w.write_episodes([episode])
    with HDF5Writer(tmp_path / "a.h5", attrs={"env_id": "swm/B-v0", "note": "x"}) as w:  # resumed: kept, added
        w.write_episodes([episode])
    assert HDF5Dataset(tmp_path / "a.h5").attrs == {"env_id": "swm/A-v0", "note": "x"}
    with pytest.raises(ConfigError, match="attrs to map names to strings"):
        HDF5Writer(tmp_path / "b.h5", attrs={"env_id": 3})
